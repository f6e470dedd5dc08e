"""FLIP (NVIDIA's perceptual image-difference metric, PyPI `flip-evaluator`) next to the
lamp-out RMSE of the bench scripts, for a set of EXR images against one reference.

    flip.py REFERENCE.exr IMAGE_OR_DIRECTORY... [--csv OUT.csv] [--mode ldr|hdr] [--layer NAME]

Every *.exr in a directory is measured (the reference itself is skipped). The CSV has one row
per image: file, flip, lamp_out_rmse, rmse. If a directory holds `accuracy.csv` (from
`rondo bench accuracy`) with a column `image` (or `file`) naming each EXR relative to the
directory, the script also writes `accuracy_flip.csv` there: accuracy.csv with `flip_ldr` (or
`flip_hdr`) and `lamp_out_rmse` columns added, rows matched by file name (`rondo bench accuracy
--keep-images DIR` names them `<method>_<sampler>_<spp>spp[_denoised].exr`; a denoised one holds
the denoised colour as R, G, B, which is what is measured, and the raw one as the layer `raw`).
With the images in another directory than accuracy.csv, name it with `--accuracy PATH`.

FLIP mode. The default is LDR-FLIP on what the user looks at: each image clamped to [0, 1]
and encoded with the sRGB transfer function, as rondo writes its PNGs and shows the viewer and
watch images; the same clamp as the lamp-out RMSE, so the two metrics judge the same pixels
(the lamp, above 1 in both images, counts as equal). HDR-FLIP (`--mode hdr`) instead tone-maps
the linear radiance at a range of exposures chosen from the reference and keeps the worst; with
a lamp of radiance 15 beside walls below 1 its exposures span the lamp too, and its tone
mapper (ACES by default) is not the display rondo uses, so it answers another question.

EXRs are read with the `OpenEXR` bindings: flip-evaluator's own loader (tinyexr) misreads
PIZ-compressed float EXRs such as Mitsuba's (it gave a reference with values of 3e12 and
-inf). An EXR with several layers needs `--layer` (channels LAYER.R, LAYER.G, LAYER.B) unless
it has plain R, G, B channels.

Run through `benches/flip/run.sh` (installs flip-evaluator, OpenEXR and numpy into a virtual
environment). Never run by the tests.
"""

import argparse
import csv
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "common"))
from image_metrics import metrics  # noqa: E402 - the shared error metrics

# Images larger than this (pixels) are refused before they are decoded.
MAX_PIXELS = 64 * 1024 * 1024


def read_exr(path, layer=None):
    """An EXR's RGB (or LAYER.R/G/B) as an H x W x 3 float32 array, top row first. The header
    is read and checked (size, channels) before any pixel is decoded."""
    import OpenEXR

    prefix = layer + "." if layer else ""
    names = [prefix + c for c in "RGB"]
    try:
        with OpenEXR.File(path, header_only=True) as f:
            # (The header is emptied when the file closes: read what is needed inside.)
            header = f.header()
            lo, hi = header["dataWindow"]
            present = [c.name for c in header["channels"]]
        w, h = int(hi[0] - lo[0] + 1), int(hi[1] - lo[1] + 1)
        if w <= 0 or h <= 0 or w * h > MAX_PIXELS:
            sys.exit("%s: image size %dx%d out of range" % (path, w, h))
        missing = [n for n in names if n not in present]
        if missing:
            sys.exit("%s: no channel %s (channels: %s)%s" % (
                path, ", ".join(missing), ", ".join(sorted(present)),
                "" if layer else "; choose a layer with --layer"))
        with OpenEXR.File(path, separate_channels=True) as f:
            channels = f.channels()
            return np.stack([channels[n].pixels.astype(np.float32) for n in names], axis=-1)
    except (OSError, RuntimeError, KeyError, ValueError, AttributeError) as e:
        sys.exit("%s: cannot read the EXR: %s" % (path, e))


def srgb_encode(linear):
    """Clamps to [0, 1] and applies the sRGB transfer function (as rondo's PNG output)."""
    c = np.clip(linear, 0.0, 1.0)
    return np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1.0 / 2.4) - 0.055)


def flip_error(ref, img, mode, ppd):
    """Mean FLIP of `img` against `ref` (both linear H x W x 3)."""
    import flip_evaluator

    params = {"ppd": ppd}
    if mode == "ldr":
        r = np.ascontiguousarray(srgb_encode(ref), dtype=np.float32)
        t = np.ascontiguousarray(srgb_encode(img), dtype=np.float32)
        _, mean, _ = flip_evaluator.evaluate(r, t, "LDR", inputsRGB=True, applyMagma=False,
                                             parameters=params)
    else:
        r = np.ascontiguousarray(np.maximum(ref, 0.0), dtype=np.float32)
        t = np.ascontiguousarray(np.maximum(img, 0.0), dtype=np.float32)
        _, mean, _ = flip_evaluator.evaluate(r, t, "HDR", applyMagma=False, parameters=params)
    return float(mean)


def collect(paths, reference):
    """(directory or None, file) pairs: every *.exr of a directory, sorted, and plain files."""
    ref = os.path.realpath(reference)
    out = []
    for p in paths:
        if os.path.isdir(p):
            for name in sorted(os.listdir(p)):
                full = os.path.join(p, name)
                if name.lower().endswith(".exr") and os.path.realpath(full) != ref:
                    out.append((p, full))
        elif os.path.isfile(p):
            out.append((None, p))
        else:
            sys.exit("%s: no such file or directory" % p)
    if not out:
        sys.exit("no EXR images in %s" % ", ".join(paths))
    return out


def annotate_accuracy(directory, results, mode, src=None):
    """Writes DIRECTORY/accuracy_flip.csv: accuracy.csv (or `src`, then beside it) with flip and
    lamp_out_rmse added, matched by the `image` (or `file`) column's file name. A lamp_out_rmse
    column already there (rondo writes one) is kept. Returns its path, or None with the reason."""
    if src is None:
        src = os.path.join(directory, "accuracy.csv")
    else:
        directory = os.path.dirname(src) or "."
    if not os.path.isfile(src):
        return None, "no %s" % src
    with open(src, newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        return None, "accuracy.csv is empty"
    key = next((k for k in ("image", "file") if k in rows[0]), None)
    if key is None:
        return None, "accuracy.csv has no `image` column naming the EXRs"
    by_name = {os.path.basename(path): r for path, r in results.items()}
    ours = "lamp_out_rmse" not in rows[0]
    fields = list(rows[0].keys()) + ["flip_" + mode] + (["lamp_out_rmse"] if ours else [])
    out = os.path.join(directory, "accuracy_flip.csv")
    matched = 0
    with open(out, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields)
        w.writeheader()
        for r in rows:
            m = by_name.get(os.path.basename(r[key] or ""))
            matched += m is not None
            r["flip_" + mode] = "%.6g" % m[0] if m else ""
            if ours:
                r["lamp_out_rmse"] = "%.6g" % m[1] if m else ""
            w.writerow(r)
    return out, "%d of %d rows matched" % (matched, len(rows))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0].replace("\n", " "))
    ap.add_argument("reference", help="converged reference .exr")
    ap.add_argument("images", nargs="+", help="EXR files or directories of them")
    ap.add_argument("--csv", help="output CSV (default: flip.csv in the first directory given, "
                                  "else in the current one)")
    ap.add_argument("--mode", choices=["ldr", "hdr"], default="ldr",
                    help="ldr: LDR-FLIP of the clamped sRGB images (default); hdr: HDR-FLIP")
    ap.add_argument("--ppd", type=float, default=67.0,
                    help="pixels per degree of visual angle (FLIP's default 67: a 0.7 m "
                         "viewing distance from a 24-inch 4K display)")
    ap.add_argument("--layer", help="EXR layer holding the colour (channels LAYER.R, .G, .B)")
    ap.add_argument("--accuracy", help="accuracy.csv to annotate with every image measured "
                                       "(default: accuracy.csv in each directory given), for "
                                       "`rondo bench accuracy --keep-images DIR` with DIR "
                                       "other than --out")
    args = ap.parse_args()

    ref = read_exr(args.reference)
    images = collect(args.images, args.reference)
    results = {}
    print("%-48s %10s %14s %10s" % ("image", "FLIP-" + args.mode.upper(), "lamp-out RMSE",
                                    "RMSE"))
    for _, path in images:
        img = read_exr(path, args.layer)
        if img.shape != ref.shape:
            sys.exit("%s: %dx%d, the reference is %dx%d" % (
                path, img.shape[1], img.shape[0], ref.shape[1], ref.shape[0]))
        m = metrics(img, ref)
        results[path] = (flip_error(ref, img, args.mode, args.ppd), m[3], m[0])
        print("%-48s %10.5f %14.5f %10.5f" % ((os.path.relpath(path),) + results[path]),
              flush=True)

    dirs = [d for d, _ in images if d is not None]
    out = args.csv or os.path.join(dirs[0] if dirs else ".", "flip.csv")
    with open(out, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["file", "flip_" + args.mode, "lamp_out_rmse", "rmse"])
        for path, (fl, lo, rm) in results.items():
            w.writerow([os.path.relpath(path), "%.6g" % fl, "%.6g" % lo, "%.6g" % rm])
    print("wrote", out)
    if args.accuracy:
        path, why = annotate_accuracy(None, results, args.mode, args.accuracy)
        print("%s: %s" % (path, why) if path else "%s: not annotated (%s)" % (args.accuracy, why))
        return
    for d in dict.fromkeys(dirs):
        path, why = annotate_accuracy(d, {p: v for p, v in results.items()
                                          if os.path.dirname(p) == d.rstrip("/")}, args.mode)
        print("%s: %s" % (path, why) if path else "%s: not annotated (%s)" % (d, why))


if __name__ == "__main__":
    main()
