"""The benchmark suite: each scene exported by `rondo export`, converted to Mitsuba 3 and
Blender Cycles, a converged Mitsuba reference, then rondo at several spp and each peer at equal
time; per scene the error-vs-time curve (SVG), E = t_peer err_peer^2 / (t_rondo err_rondo^2),
samples/s (rays/s for rondo, which counts them) and each renderer's mean against the reference.
Run through run.sh (which builds rondo and makes the virtual environments); never by the tests.

err is the clamped ("lamp-out") RMSE of benches/common/image_metrics.py: both images clamped
to [0, 1], pixels whose reference exceeds 1 left out.
"""

import argparse
import json
import math
import os
import re
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, os.path.join(HERE, "..", "common"))
sys.path.insert(0, HERE)
from image_metrics import metrics  # noqa: E402

ALL = ["cornell", "veach_mis", "envmap", "gltf", "dof", "bunnies", "bigmesh"]
# Mitsuba's best sampler per scene (its default is `independent`).
BEST = {name: "multijitter" for name in ALL}


def scene_path(name, out):
    if name == "bigmesh":
        gen = os.path.join(out, "generated")
        path = os.path.join(gen, "bigmesh.ron")
        if not os.path.isfile(path):
            subprocess.run([sys.executable, os.path.join(HERE, "make_bigmesh.py"), gen],
                           check=True)
        return path
    return os.path.join(ROOT, "scenes", name + ".ron")


def read_exr(mi, path):
    return np.array(mi.Bitmap(path).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32,
                                            srgb_gamma=False))


def err(img, ref):
    return metrics(img, ref)[3]


def means(img, ref):
    """Relative difference of the image mean, raw and clamped to [0, 1]."""
    raw = img.mean() / ref.mean() - 1
    clamped = np.clip(img, 0, 1).mean() / np.clip(ref, 0, 1).mean() - 1
    return float(raw), float(clamped)


def rondo_render(rondo, scene, spp, size, seed, out, threads):
    cmd = [rondo, "render", scene, "-o", out, "--spp", str(spp), "--seed", str(seed),
           "--width", str(size[0]), "--height", str(size[1])]
    if threads:
        cmd += ["--threads", str(threads)]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit("rondo failed: %s\n%s" % (" ".join(cmd), p.stderr))
    m = re.search(r"spp, ([0-9.]+) s, ([0-9.]+) M samples/s, ([0-9.]+) M rays/s", p.stderr)
    if not m:
        sys.exit("cannot read rondo's time from: %s" % p.stderr)
    return float(m.group(1)), float(m.group(2)), float(m.group(3))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--scenes", default=",".join(ALL))
    ap.add_argument("--quick", action="store_true",
                    help="smoke test: images at most 96 wide, 2 and 8 spp, 64-spp reference")
    ap.add_argument("--scale", type=float, default=1.0, help="image size factor")
    ap.add_argument("--spp-list", default="4,16,64")
    ap.add_argument("--reference-spp", type=int, default=1024)
    ap.add_argument("--reference-sampler", default="ldsampler")
    ap.add_argument("--rondo", default=os.path.join(ROOT, "target", "release", "rondo"))
    ap.add_argument("--cycles-python", default=None, help="Python of the Cycles venv")
    ap.add_argument("--no-cycles", action="store_true")
    ap.add_argument("--threads", type=int, default=0, help="render threads (0: all)")
    ap.add_argument("--out", default=os.path.join(ROOT, "bench", "suite"))
    args = ap.parse_args()
    if args.quick:
        args.spp_list, args.reference_spp = "2,8", 64

    import drjit as dr
    import mitsuba as mi
    mi.set_variant("llvm_ad_rgb")
    import mitsuba_scene

    spps = [int(s) for s in args.spp_list.split(",")]
    rows = []
    for name in args.scenes.split(","):
        if name not in ALL:
            sys.exit("unknown scene %r (%s)" % (name, ", ".join(ALL)))
        work = os.path.join(args.out, name)
        export = os.path.join(work, "export")
        os.makedirs(work, exist_ok=True)
        scene = scene_path(name, args.out)
        subprocess.run([args.rondo, "export", scene, "--output", export], check=True)
        j = json.load(open(os.path.join(export, "scene.json")))
        w, h = j["camera"]["width"], j["camera"]["height"]
        f = min(1.0, 96 / w) if args.quick else args.scale
        size = (max(8, round(w * f)), max(8, round(h * f)))
        print("== %s: %dx%d, %d triangles, %d spheres" % (
            name, size[0], size[1], j["counts"]["triangles"], j["counts"]["spheres"]),
            flush=True)

        ref_path = os.path.join(work, "reference_%dx%d_%d.exr" % (size + (args.reference_spp,)))
        if not os.path.isfile(ref_path):
            sc, _ = mitsuba_scene.load(mi, export, args.reference_sampler, work, size)
            acc, done, total = None, 0, 0.0
            while done < args.reference_spp:
                n = min(256, args.reference_spp - done)
                t = time.perf_counter()
                arr = np.array(mi.render(sc, spp=n, seed=10_000 + done))
                total += time.perf_counter() - t
                acc = arr * n if acc is None else acc + arr * n
                done += n
                print("  reference %d/%d spp, %.1f s" % (done, args.reference_spp, total),
                      flush=True)
            mi.util.write_bitmap(ref_path, acc / done, write_async=False)
        ref = read_exr(mi, ref_path)

        curves = {}
        out_img = os.path.join(work, "rondo.exr")
        rondo_pts = []
        for k, spp in enumerate(spps):
            t, msps, mrps = rondo_render(args.rondo, scene, spp, size, 300 + k, out_img,
                                         args.threads)
            img = read_exr(mi, out_img)
            rondo_pts.append({"spp": spp, "t": t, "err": err(img, ref), "msps": msps,
                              "mrps": mrps, "mean": means(img, ref)})
            print("  rondo   %5d spp %8.3f s err %.4e  %.2f M samples/s %.2f M rays/s" % (
                spp, t, rondo_pts[-1]["err"], msps, mrps), flush=True)
        curves["rondo"] = rondo_pts

        for sampler in dict.fromkeys(["independent", BEST[name]]):
            sc, notes = mitsuba_scene.load(mi, export, sampler, work, size)

            def render(n, seed):
                t0 = time.perf_counter()
                img = mi.render(sc, spp=n, seed=seed)
                dr.eval(img)
                arr = np.array(img)
                return time.perf_counter() - t0, arr

            render(4, 1)
            t4, _ = render(4, 2)
            rate = t4 / 4
            pts = []
            for k, rp in enumerate(rondo_pts):
                n = max(1, round(rp["t"] / rate))
                for attempt in range(3):
                    render(n, 100 + k)  # untimed: kernels of this spp
                    t, img = render(n, 101 + k)
                    if abs(t - rp["t"]) <= 0.15 * rp["t"] or attempt == 2:
                        break
                    n = max(1, round(n * rp["t"] / t))
                pix = img.shape[0] * img.shape[1]
                pts.append({"spp": n, "t": t, "err": err(img, ref),
                            "msps": n * pix / t / 1e6, "mean": means(img, ref)})
                print("  mitsuba/%-11s %5d spp %8.3f s err %.4e" % (sampler, n, t,
                                                                     pts[-1]["err"]),
                      flush=True)
            curves["mitsuba " + sampler] = pts
            curves["mitsuba " + sampler + " notes"] = notes

        if not args.no_cycles:
            cy_out = os.path.join(work, "cycles")
            cmd = [args.cycles_python, os.path.join(HERE, "cycles_render.py"), export, cy_out,
                   "--size", str(size[0]), str(size[1]),
                   "--targets", ",".join("%.4f" % p["t"] for p in rondo_pts)]
            if args.threads:
                cmd += ["--threads", str(args.threads)]
            p = subprocess.run(cmd, capture_output=True, text=True)
            if p.returncode != 0:
                sys.exit("cycles failed:\n%s" % p.stderr[-3000:])
            pts, notes = [], []
            for line in p.stdout.splitlines():
                if not line.startswith("{"):
                    continue
                d = json.loads(line)
                if "notes" in d:
                    notes = d["notes"]
                    continue
                img = read_exr(mi, d["file"])
                pix = img.shape[0] * img.shape[1]
                pts.append({"spp": d["spp"], "t": d["seconds"], "err": err(img, ref),
                            "msps": d["spp"] * pix / d["seconds"] / 1e6,
                            "mean": means(img, ref)})
                print("  cycles  %5d spp %8.3f s err %.4e" % (d["spp"], d["seconds"],
                                                             pts[-1]["err"]), flush=True)
            curves["cycles"] = pts
            curves["cycles notes"] = notes

        row = summarise(name, size, args, curves)
        rows.append(row)
        json.dump({"size": size, "curves": curves, "row": row},
                  open(os.path.join(work, "result.json"), "w"), indent=1)
        chart(os.path.join(work, "%s.svg" % name), name, size, curves)
    table(rows, args)


def summarise(name, size, args, curves):
    r = curves["rondo"][-1]
    row = {"scene": name, "size": "%dx%d" % size, "rondo_spp": r["spp"], "rondo_t": r["t"],
           "rondo_err": r["err"], "msps": r["msps"], "mrps": r["mrps"],
           "means": {"rondo": r["mean"]}, "E": {}, "peer_msps": {}}
    for peer in [k for k in curves if k != "rondo" and not k.endswith("notes")]:
        p = curves[peer][-1]
        row["E"][peer] = p["t"] * p["err"] ** 2 / (r["t"] * r["err"] ** 2)
        row["peer_msps"][peer] = p["msps"]
        row["means"][peer] = p["mean"]
    return row


def chart(path, name, size, curves):
    import matplotlib
    matplotlib.use("svg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6, 4))
    for who, pts in curves.items():
        if who.endswith("notes") or not pts:
            continue
        ax.plot([p["t"] for p in pts], [p["err"] for p in pts], "o-", label=who)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("render time (s)")
    ax.set_ylabel("clamped RMSE vs reference")
    ax.set_title("%s, %dx%d" % (name, size[0], size[1]))
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def table(rows, args):
    peers = []
    for r in rows:
        for p in r["E"]:
            if p not in peers:
                peers.append(p)
    argv = sys.argv[1:]
    if "--cycles-python" in argv:
        k = argv.index("--cycles-python")
        argv = argv[:k] + argv[k + 2:]
    lines = ["```sh", "benches/suite/run.sh " + " ".join(argv), "```", "",
             "Reference: Mitsuba 3 `%s`, %d spp. E = t_peer err_peer^2 / (t_rondo err_rondo^2) "
             "at rondo's largest spp (peers at equal time); err = clamped RMSE; mean = relative "
             "difference of the image mean from the reference's, clamped to [0, 1] (raw in "
             "brackets)." % (args.reference_sampler, args.reference_spp), "",
             "| scene | size | rondo spp, s, err | rondo M samples/s, M rays/s | "
             + " | ".join("E vs %s" % p for p in peers) + " | "
             + " | ".join("%s M samples/s" % p for p in peers) + " | mean: rondo | "
             + " | ".join("mean: %s" % p for p in peers) + " |",
             "|" + "---|" * (5 + 2 * len(peers) + len(peers))]
    for r in rows:
        def m(who):
            v = r["means"].get(who)
            return "%+.1f %% (%+.1f %%)" % (100 * v[1], 100 * v[0]) if v else ""
        lines.append("| %s | %s | %d, %.2f, %.4f | %.2f, %.2f | %s | %s | %s | %s |" % (
            r["scene"], r["size"], r["rondo_spp"], r["rondo_t"], r["rondo_err"], r["msps"],
            r["mrps"], " | ".join("%.2f" % r["E"][p] if p in r["E"] else "" for p in peers),
            " | ".join("%.2f" % r["peer_msps"][p] if p in r["peer_msps"] else "" for p in peers),
            m("rondo"), " | ".join(m(p) for p in peers)))
    text = "\n".join(lines) + "\n"
    print()
    print(text)
    open(os.path.join(args.out, "summary.md"), "w").write(text)


if __name__ == "__main__":
    main()
