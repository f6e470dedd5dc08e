"""Should `--method caustics` be the default? (issue 36, BENCHMARKS.md "Caustics as the
default?"). Renders every scene of the suite plus the caustic ones with `mis` and `caustics`
at a small size, one thread, and compares them at equal time against a converged image.
A bench, never run by the tests.

    benches/caustics_default.py [--rondo target/release/rondo] [--out bench/caustics_default]
                                [--scenes cornell,...] [--width 120] [--spp 64] [--seeds 1,2,3]
                                [--repeat 3] [--reference-spp 4096] [--pilot-rondo BIN]

Needs numpy and the OpenEXR module (`pip install numpy OpenEXR`) in the Python running it.

- Reference per scene: `--method caustics`, `--reference-spp` spp, seed 99, all threads. Its
  image mean is checked against `mis` at the same spp (four renders of a quarter each, seeds
  101-104; the standard error of the mean from each pixel's variance over the four, taken as
  the reference's too): the `z` column.
- Timed renders: `--width` wide (the scene's aspect kept), `--spp`, each seed of `--seeds`,
  `--threads 1`, methods alternated, each timed `--repeat` times (same seed, same image). The
  time is the process's CPU time (user + system, from `wait4`, as `/usr/bin/time -f %U+%S`
  but in microseconds) less the loading and the BVH build: a `mis` render of 1 spp, timed the
  same way, less one 64th of a `mis` sample's time, is the scene's set-up (the big mesh's
  OBJ and BVH take seconds, alike for both methods).
- err: the suite's clamped RMSE (benches/common/image_metrics.py: pixels whose reference
  exceeds 1 left out, both images clamped to [0, 1]), mean of err^2 over the seeds.
- E = t_mis err_mis^2 / (t_caustics err_caustics^2): above 1, `caustics` wins at equal time.
- Fireflies: pixels whose luminance is above 4x the reference's and above it by 0.1, mean
  over the seeds.
- The pilot's light paths per pixel, when `--pilot-rondo` names a build that prints them (a
  line `PILOT share S paths N per_pixel P` from `budget::light_paths`; not in rondo itself).
"""

import argparse
import json
import os
import re
import subprocess
import sys

import numpy as np
import OpenEXR

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, ".."))
sys.path.insert(0, os.path.join(HERE, "common"))
from image_metrics import metrics  # noqa: E402

SUITE = ["cornell", "veach_mis", "envmap", "gltf", "dof", "bunnies", "bigmesh"]
CAUSTIC = ["caustic", "sunlit", "sun_caustics"]
# Beyond the suite: scenes/bunnies.ron itself (the suite's `bunnies` is 1,000 of them).
EXTRA = ["bunnies5"]
LUMA = np.array([0.2126, 0.7152, 0.0722])


def scene_path(name, out):
    """The suite's generated scenes (as benches/suite/suite.py makes them), else scenes/."""
    gen = os.path.join(out, "generated")
    if name == "bigmesh":
        path = os.path.join(gen, "bigmesh.ron")
        if not os.path.isfile(path):
            subprocess.run([sys.executable, os.path.join(HERE, "suite", "make_bigmesh.py"),
                            gen], check=True)
        return path
    if name == "bunnies":
        path = os.path.join(gen, "bunnies1000.ron")
        if not os.path.isfile(path):
            subprocess.run([sys.executable, os.path.join(HERE, "suite", "make_bunnies.py"),
                            gen], check=True)
        return path
    if name == "bunnies5":
        # scenes/bunnies.ron itself (5 placements); the suite's `bunnies` is the 1,000.
        return os.path.join(ROOT, "scenes", "bunnies.ron")
    return os.path.join(ROOT, "scenes", name + ".ron")


def scene_size(path, width):
    """`width` and the height that keeps the scene's aspect."""
    text = open(path).read()
    w = int(re.search(r"width:\s*(\d+)", text).group(1))
    h = int(re.search(r"height:\s*(\d+)", text).group(1))
    return width, max(8, round(width * h / w))


def read_exr(path):
    with OpenEXR.File(path) as f:
        return np.array(f.channels()["RGB"].pixels[..., :3], dtype=np.float64)


def render(rondo, scene, out, size, spp, seed, method, threads):
    """Runs one render; returns (CPU seconds of the process, its log)."""
    cmd = [rondo, "render", scene, "-o", out, "--spp", str(spp), "--seed", str(seed),
           "--width", str(size[0]), "--height", str(size[1]), "--method", method]
    if threads:
        cmd += ["--threads", str(threads)]
    p = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    log = p.stderr.read()
    _, status, usage = os.wait4(p.pid, 0)
    p.returncode = os.waitstatus_to_exitcode(status)
    if p.returncode != 0:
        sys.exit("rondo failed: %s\n%s" % (" ".join(cmd), log))
    return usage.ru_utime + usage.ru_stime, log


def fireflies(img, ref):
    a, r = img @ LUMA, ref @ LUMA
    return int(np.count_nonzero((a > 4 * r) & (a > r + 0.1)))


def references(args, name, scene, size, work):
    """The converged `caustics` image and the z of its mean against `mis`'s."""
    tag = "%dx%d_%d" % (size + (args.reference_spp,))
    ref_path = os.path.join(work, "reference_caustics_%s.exr" % tag)
    if not os.path.isfile(ref_path):
        render(args.rondo, scene, ref_path, size, args.reference_spp, 99, "caustics", 0)
    ref = read_exr(ref_path)
    quarter = args.reference_spp // 4
    parts = []
    for k in range(4):
        path = os.path.join(work, "check_mis_%dx%d_%d_seed%d.exr" % (size + (quarter, 101 + k)))
        if not os.path.isfile(path):
            render(args.rondo, scene, path, size, quarter, 101 + k, "mis", 0)
        parts.append(read_exr(path).mean(axis=-1))
    parts = np.array(parts)
    mis_mean = float(parts.mean())
    # The standard error of the image mean from each pixel's variance over the four parts
    # (pixels are independent under `mis`): steadier than the spread of four image means.
    se = float(np.sqrt(parts.var(axis=0, ddof=1).sum() / 4) / parts[0].size)
    # The reference's own mean is taken as noisy as `mis`'s at as many samples: sqrt(2).
    z = (ref.mean() - mis_mean) / (se * np.sqrt(2)) if se > 0 else float("inf")
    return ref, {"mean_caustics": float(ref.mean()), "mean_mis": mis_mean, "se_mis": se,
                 "z": float(z)}


def pilot(args, scene, size, seeds, work):
    """The pilot's light paths per pixel per seed, from a build that prints them."""
    if not args.pilot_rondo:
        return None
    got = []
    for seed in seeds:
        _, log = render(args.pilot_rondo, scene, os.path.join(work, "pilot.exr"), size, 1, seed,
                        "caustics", 1)
        m = re.search(r"PILOT share ([0-9.e-]+) paths (\d+) per_pixel ([0-9.e-]+)", log)
        got.append({"share": float(m.group(1)), "paths": int(m.group(2)),
                    "per_pixel": float(m.group(3))} if m else None)
    return got


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rondo", default=os.path.join(ROOT, "target", "release", "rondo"))
    ap.add_argument("--pilot-rondo", default="")
    ap.add_argument("--out", default=os.path.join(ROOT, "bench", "caustics_default"))
    ap.add_argument("--scenes", default=",".join(SUITE + EXTRA + CAUSTIC))
    ap.add_argument("--width", type=int, default=120)
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--seeds", default="1,2,3")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--reference-spp", type=int, default=4096)
    ap.add_argument("--references-only", action="store_true",
                    help="make the references (and check them) only, nothing timed")
    args = ap.parse_args()
    seeds = [int(s) for s in args.seeds.split(",")]
    methods = ["mis", "caustics"]
    rows = []
    for name in args.scenes.split(","):
        scene = scene_path(name, args.out)
        if not os.path.isfile(scene):
            print("== %s: no such scene, skipped" % name, flush=True)
            continue
        work = os.path.join(args.out, name)
        os.makedirs(work, exist_ok=True)
        size = scene_size(scene, args.width)
        ref, check = references(args, name, scene, size, work)
        print("== %s %dx%d: reference mean %.5f, mis %.5f +- %.5f (z %.2f)" % (
            name, size[0], size[1], check["mean_caustics"], check["mean_mis"], check["se_mis"],
            check["z"]), flush=True)
        if args.references_only:
            continue
        cpu = {m: [] for m in methods + ["setup"]}
        errs = {m: [] for m in methods}
        flies = {m: [] for m in methods}
        for seed in seeds:
            order = methods if seed % 2 else methods[::-1]
            for rep in range(args.repeat):
                t, _ = render(args.rondo, scene, os.path.join(work, "setup.exr"), size, 1, seed,
                              "mis", 1)
                cpu["setup"].append(t)
                for m in order:
                    out = os.path.join(work, "%s_seed%d.exr" % (m, seed))
                    t, _ = render(args.rondo, scene, out, size, args.spp, seed, m, 1)
                    cpu[m].append(t)
            for m in methods:
                img = read_exr(os.path.join(work, "%s_seed%d.exr" % (m, seed)))
                errs[m].append(metrics(img, ref)[3])
                flies[m].append(fireflies(img, ref))
        cpu_mean = {m: float(np.mean(v)) for m, v in cpu.items()}
        per_spp = (cpu_mean["mis"] - cpu_mean["setup"]) / (args.spp - 1)
        setup = cpu_mean["setup"] - per_spp
        row = {"scene": name, "size": "%dx%d" % size, "check": check, "setup": setup,
               "pilot": pilot(args, scene, size, seeds, work)}
        for m in methods:
            row[m] = {"cpu": cpu_mean[m], "cpu_all": cpu[m], "t": cpu_mean[m] - setup,
                      "err": float(np.sqrt(np.mean(np.square(errs[m])))), "errs": errs[m],
                      "fireflies": float(np.mean(flies[m]))}
        mis, ca = row["mis"], row["caustics"]
        row["E"] = mis["t"] * mis["err"] ** 2 / (ca["t"] * ca["err"] ** 2)
        row["E_process"] = mis["cpu"] * mis["err"] ** 2 / (ca["cpu"] * ca["err"] ** 2)
        rows.append(row)
        print("   mis      %.3f s (process %.3f) err %.5f fireflies %.1f" % (
            mis["t"], mis["cpu"], mis["err"], mis["fireflies"]), flush=True)
        print("   caustics %.3f s (process %.3f) err %.5f fireflies %.1f  E %.2f (process %.2f)"
              % (ca["t"], ca["cpu"], ca["err"], ca["fireflies"], row["E"], row["E_process"]),
              flush=True)
    with open(os.path.join(args.out, "result.json"), "w") as f:
        json.dump(rows, f, indent=1)
    print()
    print("| scene | size | mis CPU s | caustics CPU s | t ratio | mis err | caustics err "
          "| E | mis fireflies | caustics fireflies | light paths per pixel | ref. mean z |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        mis, ca = r["mis"], r["caustics"]
        p = r["pilot"]
        if p and all(p):
            lo, hi = min(x["per_pixel"] for x in p), max(x["per_pixel"] for x in p)
            paths = "1/%.0f" % (1 / hi) + ("" if lo == hi else "–1/%.0f" % (1 / lo))
        else:
            paths = "-"
        print("| %s | %s | %.3f | %.3f | %.3f | %.4f | %.4f | **%.2f** | %.1f | %.1f | %s | %+.1f |"
              % (r["scene"], r["size"], mis["t"], ca["t"], ca["t"] / mis["t"], mis["err"],
                 ca["err"], r["E"], mis["fireflies"], ca["fireflies"], paths,
                 r["check"]["z"]))


if __name__ == "__main__":
    main()
