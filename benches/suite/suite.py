"""The benchmark suite: each scene exported by `rondo export`, converted to Mitsuba 3 and
Blender Cycles, a converged Mitsuba reference, then rondo at several spp and each peer at equal
time; per scene the error-vs-time curve (SVG), E = t_peer err_peer^2 / (t_rondo err_rondo^2),
samples/s (rays/s for rondo, which counts them) and each renderer's mean against the reference.
Run through run.sh (which builds rondo and makes the virtual environments); never by the tests.

err is the clamped ("lamp-out") RMSE of benches/common/image_metrics.py: both images clamped
to [0, 1], pixels whose reference exceeds 1 left out. On a scene of OWN_REFERENCE, whose
materials the renderers model differently, each renderer's err is taken against its own
converged image (noise only, what E compares) and its mean against Mitsuba's (the bias the
models' difference costs).

With --repeat N the timed renders are timed N times in all: after the first round (which picks
each peer's spp for equal time and gives every image), N - 1 more rounds time rondo, Mitsuba and
Cycles again in turn at the same spp and seed (the same images), and each point's time is the
median of its N. The rounds interleave the renderers, so a slow phase of a shared host reaches
each of them rather than one; the denoised budgets are rendered once.
"""

import argparse
import json
import os
import re
import shlex
import statistics
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
# Scenes whose materials differ between the renderers by more than noise: glTF's
# metallic-roughness material is rondo's `Pbr` (Lambertian base), Mitsuba's and Cycles'
# `principled` (Disney/Burley diffuse base, each its own specular); rondo's `Glossy` (and rough
# glass) put back the light single-scattering GGX loses, as Cycles' multiscatter GGX does and
# Mitsuba's GGX does not (up to 3 % brighter at the roughness 0.25-0.4 of these scenes).
# `sunlit` (not one of the suite's own, for issue 36): its gold ball is a `Glossy`, and its
# infinite ground plane meets the sky at a horizon the peers' large ground quad does not draw
# the same (0.0084 between rondo's and Mitsuba's 16,384-spp images, 99 % of it in 1,000 pixels
# along the horizon's row).
OWN_REFERENCE = {"gltf", "veach_mis", "envmap", "dof", "bigmesh", "sunlit"}


def scene_path(name, out):
    """The scene file of a suite scene, or scenes/NAME.ron for a name outside ALL."""
    gen = os.path.join(out, "generated")
    if name == "bigmesh":
        path = os.path.join(gen, "bigmesh.ron")
        if not os.path.isfile(path):
            subprocess.run([sys.executable, os.path.join(HERE, "make_bigmesh.py"), gen],
                           check=True)
        return path
    if name == "bunnies":
        # 1,000 placements of the bunny (scenes/bunnies.ron places 5); written on every run,
        # the same bytes each time (a seeded generator).
        subprocess.run([sys.executable, os.path.join(HERE, "make_bunnies.py"), gen], check=True)
        return os.path.join(gen, "bunnies1000.ron")
    return os.path.join(ROOT, "scenes", name + ".ron")


def check_bunnies(scene, j):
    """The export of the generated bunnies holds every placement: its triangles are the
    placements times the triangles of bunny.obj (counted from the files here) and the lamp's
    quad (2)."""
    gen = os.path.dirname(scene)
    with open(os.path.join(gen, "bunny.obj")) as f:
        per_bunny = sum(len(line.split()) - 3 for line in f if line.startswith("f "))
    with open(scene) as f:
        placements = f.read().count('Mesh(path: "bunny.obj")')
    want = placements * per_bunny + 2
    if placements != 1000 or j["counts"]["triangles"] != want:
        sys.exit("%s: the export holds %d triangles, %d placements x %d + 2 = %d expected" % (
            scene, j["counts"]["triangles"], placements, per_bunny, want))


def read_exr(mi, path):
    """The colour of an EXR as H x W x 3: its R, G, B channels (a denoised rondo image also
    holds the raw colour as the layer `raw`, whose channels are `raw.R`, ...)."""
    bmp = mi.Bitmap(path)
    names = [bmp.struct_()[i].name for i in range(bmp.channel_count())]
    arr = np.asarray(bmp)
    if names[:3] != ["R", "G", "B"]:
        sys.exit("%s: channels %s, not R, G, B first" % (path, names))
    return np.array(arr[..., :3], dtype=np.float32)


def err(img, ref):
    return metrics(img, ref)[3]


def means(img, ref):
    """Relative difference of the image mean, raw and clamped to [0, 1]."""
    raw = img.mean() / ref.mean() - 1
    clamped = np.clip(img, 0, 1).mean() / np.clip(ref, 0, 1).mean() - 1
    return float(raw), float(clamped)


def rondo_render(rondo, scene, spp, size, seed, out, threads, denoise=False, method=None):
    """Renders and reads rondo's log: t is the render time without the BVH build (Mitsuba
    builds its BVH when the scene loads, Cycles when it synchronises it: neither is timed),
    samples/s and rays/s over that time, the BVH build and the denoiser's time. `method`
    overrides the scene's light-transport method (`--method`)."""
    cmd = [rondo, "render", scene, "-o", out, "--spp", str(spp), "--seed", str(seed),
           "--width", str(size[0]), "--height", str(size[1])]
    if method:
        cmd += ["--method", method]
    if threads:
        cmd += ["--threads", str(threads)]
    if denoise:
        cmd += ["--denoise"]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit("rondo failed: %s\n%s" % (" ".join(cmd), p.stderr))
    m = re.search(r"spp, ([0-9.]+) s, ([0-9.]+) M samples/s, ([0-9.]+) M rays/s, "
                  r"BVH ([0-9.]+) ms", p.stderr)
    if not m:
        sys.exit("cannot read rondo's time from: %s" % p.stderr)
    wall, bvh = float(m.group(1)), float(m.group(4)) / 1000
    # The log gives 2 decimals: keep at least 5 ms of sampling.
    t = max(wall - bvh, 0.005)
    mrays = float(m.group(3)) * wall
    d = re.search(r"denoised in ([0-9.]+) s", p.stderr)
    if denoise and not d:
        sys.exit("cannot read rondo's denoising time from: %s" % p.stderr)
    return {"t": t, "wall": wall, "bvh": bvh, "msps": spp * size[0] * size[1] / t / 1e6,
            "mrps": mrays / t, "denoise": float(d.group(1)) if d else 0.0}


def own_references(args, name, scene, export, work, size, mi):
    """Converged images of rondo and Cycles at the reference's spp, for a scene of
    OWN_REFERENCE. Cycles' is kept like Mitsuba's; rondo's is made on every run, by the rondo
    under test (a kept one would be stale after a change of its materials)."""
    refs = {}
    tag = "%dx%d_%d.exr" % (size + (args.reference_spp,))
    path = os.path.join(work, "rondo_reference_" + tag)
    r = rondo_render(args.rondo, scene, args.reference_spp, size, 20_000, path, args.threads)
    print("  rondo reference %d spp, %.1f s" % (args.reference_spp, r["t"]), flush=True)
    refs["rondo"] = read_exr(mi, path)
    if not args.no_cycles:
        path = os.path.join(work, "cycles_reference_" + tag)
        if not os.path.isfile(path):
            cmd = [args.cycles_python, os.path.join(HERE, "cycles_render.py"), export,
                   os.path.join(work, "cycles"), "--size", str(size[0]), str(size[1]),
                   "--spp-list", str(args.reference_spp)]
            if args.threads:
                cmd += ["--threads", str(args.threads)]
            p = subprocess.run(cmd, capture_output=True, text=True)
            if p.returncode != 0:
                sys.exit("cycles failed:\n%s" % p.stderr[-3000:])
            lines = [json.loads(x) for x in p.stdout.splitlines() if x.startswith("{")]
            d = [x for x in lines if "file" in x][0]
            os.replace(d["file"], path)
            print("  cycles reference %d spp, %.1f s" % (args.reference_spp, d["seconds"]),
                  flush=True)
        refs["cycles"] = read_exr(mi, path)
    print("  %s: each renderer's err against its own reference" % name, flush=True)
    return refs


def rondo_denoised(args, scene, size, budgets, raw, ref, own_ref, mi, out_img):
    """rondo with its OIDN denoiser at each time budget (render + denoise): spp from the
    samples/s of the raw renders, then scaled again while the time is off by more than 15 %
    (at most twice); err against `own_ref`, the mean against `ref`."""
    rate = raw["t"] / raw["spp"]
    t_denoise = 0.0
    pts = []
    for k, budget in enumerate(budgets):
        spp = max(1, round((budget - t_denoise) / rate))
        for attempt in range(3):
            r = rondo_render(args.rondo, scene, spp, size, 500 + k, out_img, args.threads,
                             denoise=True)
            t = r["t"] + r["denoise"]
            rate, t_denoise = r["t"] / spp, r["denoise"]
            if abs(t - budget) <= 0.15 * budget or attempt == 2:
                break
            new = max(1, round((budget - t_denoise) / rate))
            if new == spp:
                break
            spp = new
        img = read_exr(mi, out_img)
        pts.append({"budget": budget, "spp": spp, "t": t, "t_denoise": r["denoise"],
                    "err": err(img, own_ref), "mean": means(img, ref)})
        print("  rondo+OIDN  %5d spp %8.3f s (denoise %.3f s) err %.4e" % (
            spp, t, r["denoise"], pts[-1]["err"]), flush=True)
    return pts


def run_cycles(args, export, work, size, guiding, extra):
    """cycles_render.py on the export with `extra` arguments; its standard output."""
    cmd = [args.cycles_python, os.path.join(HERE, "cycles_render.py"), export,
           os.path.join(work, "cycles_guiding" if guiding else "cycles"),
           "--size", str(size[0]), str(size[1])] + extra
    if args.threads:
        cmd += ["--threads", str(args.threads)]
    if guiding:
        cmd += ["--guiding"]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit("cycles failed:\n%s" % p.stderr[-3000:])
    return p.stdout


def cycles_curve(args, export, work, size, rondo_pts, budgets, own_ref, ref, mi, guiding):
    """Cycles at equal time with rondo's raw renders (and at the denoised budgets): the raw
    points, the denoised points and Cycles' notes. `guiding` turns on Cycles' path guiding
    (Open PGL, surface guiding; it trains on its first samples)."""
    out = run_cycles(args, export, work, size, guiding,
                     ["--targets", ",".join("%.4f" % p["t"] for p in rondo_pts),
                      "--denoise-targets", ",".join("%g" % b for b in budgets)])
    pts, dpts, notes = [], [], []
    for line in out.splitlines():
        if not line.startswith("{"):
            continue
        d = json.loads(line)
        if "notes" in d:
            notes = d["notes"]
            continue
        img = read_exr(mi, d["file"])
        pix = img.shape[0] * img.shape[1]
        pt = {"spp": d["spp"], "t": d["seconds"], "wall": d["wall"], "err": err(img, own_ref),
              "msps": d["spp"] * pix / d["seconds"] / 1e6, "mean": means(img, ref)}
        if d.get("denoised"):
            pt["budget"] = d["target"]
            dpts.append(pt)
        else:
            pts.append(pt)
        print("  cycles%s%s %5d spp %8.3f s (call %.3f s) err %.4e" % (
            " guiding" if guiding else "", "+OIDN" if d.get("denoised") else "     ", d["spp"],
            d["seconds"], d["wall"], pt["err"]), flush=True)
    return pts, dpts, notes


def cycles_retime(args, export, work, size, pts, guiding):
    """Cycles' render times at the spp of `pts` again (fixed-spp renders, `--spp-list`), in
    their order."""
    out = run_cycles(args, export, work, size, guiding,
                     ["--spp-list", ",".join(str(p["spp"]) for p in pts)])
    records = [json.loads(line) for line in out.splitlines() if line.startswith("{")]
    times = [r["seconds"] for r in records if "seconds" in r and not r.get("denoised")]
    if len(times) != len(pts):
        sys.exit("cycles gave %d times for %d renders" % (len(times), len(pts)))
    return times


def settle_times(curves):
    """Each repeated point's time becomes the median of its times; its rates follow."""
    for key, pts in curves.items():
        if key.endswith("notes"):
            continue
        for p in pts:
            if len(p.get("times", [])) < 2:
                continue
            t = statistics.median(p["times"])
            if "mrps" in p:
                p["mrps"] *= p["t"] / t
            p["msps"] *= p["t"] / t
            p["t"] = t


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--scenes", default=",".join(ALL),
                    help="comma-separated; besides the suite's own, any scenes/NAME.ron "
                    "(e.g. caustic, sun_caustics)")
    ap.add_argument("--quick", action="store_true",
                    help="smoke test: images at most 96 wide, 2 and 8 spp, 64-spp reference, "
                    "denoised at 0.2 and 1 s")
    ap.add_argument("--scale", type=float, default=1.0, help="image size factor")
    ap.add_argument("--spp-list", default="4,16,64")
    ap.add_argument("--denoise-times", default="1,10",
                    help="time budgets (s) of the denoised renders, rondo's and Cycles'")
    ap.add_argument("--reference-spp", type=int, default=1024)
    ap.add_argument("--reference-sampler", default="ldsampler")
    ap.add_argument("--rondo-reference", default="", metavar="METHOD:SPP",
                    help="measure every renderer's err against rondo's render with METHOD at SPP "
                    "(e.g. caustics:4096, for caustics a path tracer's reference leaves noisy); "
                    "the means stay against Mitsuba's reference")
    ap.add_argument("--rondo", default=os.path.join(ROOT, "target", "release", "rondo"))
    ap.add_argument("--cycles-python", default=None, help="Python of the Cycles venv")
    ap.add_argument("--no-cycles", action="store_true")
    ap.add_argument("--cycles-guiding", action="store_true",
                    help="also Cycles with path guiding on (a second Cycles column)")
    ap.add_argument("--threads", type=int, default=0, help="render threads (0: all)")
    ap.add_argument("--rondo-methods", default="",
                    help="rondo's light-transport methods, comma-separated (default: the "
                    "scene's own): the first is the curve the peers are matched to in time; "
                    "each other one (e.g. caustics) gets its own curve and the table's column "
                    "`E <method>` = t_first err_first^2 / (t err^2)")
    ap.add_argument("--repeat", type=int, default=1,
                    help="time every raw render this many times, in rounds that interleave "
                    "the renderers, and keep the median (the images are rendered once)")
    ap.add_argument("--out", default=os.path.join(ROOT, "bench", "suite"))
    args = ap.parse_args()
    if args.repeat < 1:
        sys.exit("--repeat takes 1 or more")
    if args.quick:
        args.spp_list, args.reference_spp, args.denoise_times = "2,8", 64, "0.2,1"

    import drjit as dr
    import mitsuba as mi
    mi.set_variant("llvm_ad_rgb")
    import mitsuba_scene

    spps = [int(s) for s in args.spp_list.split(",")]
    # None: the scene's own method (no --method).
    methods = [m for m in args.rondo_methods.split(",") if m] or [None]
    budgets = [float(s) for s in args.denoise_times.split(",") if s]
    rows = []
    for name in args.scenes.split(","):
        if name not in ALL and not os.path.isfile(scene_path(name, args.out)):
            sys.exit("unknown scene %r (%s, or a scenes/NAME.ron)" % (name, ", ".join(ALL)))
        work = os.path.join(args.out, name)
        export = os.path.join(work, "export")
        os.makedirs(work, exist_ok=True)
        scene = scene_path(name, args.out)
        subprocess.run([args.rondo, "export", scene, "--output", export], check=True)
        j = json.load(open(os.path.join(export, "scene.json")))
        if name == "bunnies":
            check_bunnies(scene, j)
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
        refs = own_references(args, name, scene, export, work, size, mi) \
            if name in OWN_REFERENCE else {}
        if args.rondo_reference:
            method, spp = args.rondo_reference.split(":")
            path = os.path.join(work, "rondo_%s_reference_%dx%d_%s.exr" % ((method,) + size
                                                                            + (spp,)))
            r = rondo_render(args.rondo, scene, int(spp), size, 30_000, path, args.threads,
                             method=method)
            print("  rondo %s reference %s spp, %.1f s: every renderer's err against it" % (
                method, spp, r["t"]), flush=True)
            common = read_exr(mi, path)
            refs = {"rondo": common, "cycles": common, "mitsuba": common}

        curves = {}
        out_img = os.path.join(work, "rondo.exr")
        rondo_pts = []
        for k, spp in enumerate(spps):
            r = rondo_render(args.rondo, scene, spp, size, 300 + k, out_img, args.threads,
                             method=methods[0])
            img = read_exr(mi, out_img)
            rondo_pts.append({"spp": spp, "t": r["t"], "times": [r["t"]], "bvh": r["bvh"],
                              "err": err(img, refs.get("rondo", ref)),
                              "msps": r["msps"], "mrps": r["mrps"], "mean": means(img, ref)})
            print("  rondo   %5d spp %8.3f s err %.4e  %.2f M samples/s %.2f M rays/s"
                  "  (BVH %.3f s, not timed)" % (spp, r["t"], rondo_pts[-1]["err"], r["msps"],
                                                 r["mrps"], r["bvh"]), flush=True)
        curves["rondo"] = rondo_pts
        for method in methods[1:]:
            pts = []
            for k, spp in enumerate(spps):
                r = rondo_render(args.rondo, scene, spp, size, 300 + k, out_img, args.threads,
                                 method=method)
                img = read_exr(mi, out_img)
                pts.append({"spp": spp, "t": r["t"], "times": [r["t"]],
                            "err": err(img, refs.get("rondo", ref)),
                            "msps": r["msps"], "mrps": r["mrps"], "mean": means(img, ref)})
                print("  rondo/%-9s %5d spp %8.3f s err %.4e" % (method, spp, r["t"],
                                                                 pts[-1]["err"]), flush=True)
            curves["rondo " + method] = pts
        denoised = {}
        if budgets:
            denoised["rondo"] = rondo_denoised(args, scene, size, budgets, rondo_pts[-1], ref,
                                               refs.get("rondo", ref), mi,
                                               os.path.join(work, "rondo_denoised.exr"))

        mitsuba_timers = {}
        for sampler in dict.fromkeys(["independent", BEST.get(name, "multijitter")]):
            sc, notes = mitsuba_scene.load(mi, export, sampler, work, size)

            def render(n, seed, sc=sc):
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
                pts.append({"spp": n, "t": t, "times": [t], "seed": 101 + k,
                            "err": err(img, refs.get("mitsuba", ref)),
                            "msps": n * pix / t / 1e6, "mean": means(img, ref)})
                print("  mitsuba/%-11s %5d spp %8.3f s err %.4e" % (sampler, n, t,
                                                                     pts[-1]["err"]),
                      flush=True)
            curves["mitsuba " + sampler] = pts
            curves["mitsuba " + sampler + " notes"] = notes
            mitsuba_timers[sampler] = render

        if not args.no_cycles:
            pts, dpts, notes = cycles_curve(args, export, work, size, rondo_pts, budgets,
                                            refs.get("cycles", ref), ref, mi, guiding=False)
            curves["cycles"] = pts
            if budgets:
                denoised["cycles"] = dpts
            curves["cycles notes"] = notes
            if args.cycles_guiding:
                pts, _, notes = cycles_curve(args, export, work, size, rondo_pts, [],
                                             refs.get("cycles", ref), ref, mi, guiding=True)
                curves["cycles guiding"] = pts
                curves["cycles guiding notes"] = notes

        for round_ in range(1, args.repeat):
            for key, method in [("rondo", methods[0])] + [("rondo " + m, m)
                                                            for m in methods[1:]]:
                for k, p in enumerate(curves[key]):
                    p["times"].append(rondo_render(args.rondo, scene, p["spp"], size, 300 + k,
                                                   out_img, args.threads, method=method)["t"])
            for sampler, render in mitsuba_timers.items():
                for p in curves["mitsuba " + sampler]:
                    # Untimed first, as in the first round: after the other sampler's renders,
                    # Dr.Jit compiles this one's kernels again.
                    render(p["spp"], p["seed"] - 1)
                    p["times"].append(render(p["spp"], p["seed"])[0])
            for key, guiding in (("cycles", False), ("cycles guiding", True)):
                if key in curves:
                    for p, t in zip(curves[key], cycles_retime(args, export, work, size,
                                                               curves[key], guiding)):
                        p.setdefault("times", [p["t"]]).append(t)
            print("  round %d of %d: %s" % (round_ + 1, args.repeat, "; ".join(
                "%s %s s" % (key, "/".join("%.3f" % p["times"][-1] for p in pts))
                for key, pts in curves.items() if not key.endswith("notes"))), flush=True)
        settle_times(curves)

        row = summarise(name, size, args, curves, denoised)
        row["own_reference"] = name in OWN_REFERENCE
        rows.append(row)
        json.dump({"size": size, "curves": curves, "denoised": denoised, "row": row},
                  open(os.path.join(work, "result.json"), "w"), indent=1)
        chart(os.path.join(work, "%s.svg" % name), name, size, curves, denoised)
    table(rows, args)


def summarise(name, size, args, curves, denoised):
    r = curves["rondo"][-1]
    row = {"scene": name, "size": "%dx%d" % size, "rondo_spp": r["spp"], "rondo_t": r["t"],
           "rondo_err": r["err"], "msps": r["msps"], "mrps": r["mrps"],
           "means": {"rondo": r["mean"]}, "E": {}, "peer_msps": {}, "denoised": denoised}
    row["methods"] = {}
    for who in [k for k in curves if k.startswith("rondo ")]:
        p = curves[who][-1]
        row["methods"][who[len("rondo "):]] = {
            "spp": p["spp"], "t": p["t"], "err": p["err"],
            "E": r["t"] * r["err"] ** 2 / (p["t"] * p["err"] ** 2)}
    for peer in [k for k in curves if k != "rondo" and not k.startswith("rondo ")
                 and not k.endswith("notes")]:
        p = curves[peer][-1]
        row["E"][peer] = p["t"] * p["err"] ** 2 / (r["t"] * r["err"] ** 2)
        row["peer_msps"][peer] = p["msps"]
        row["means"][peer] = p["mean"]
    return row


def chart(path, name, size, curves, denoised):
    import matplotlib
    matplotlib.use("svg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6, 4))
    for who, pts in curves.items():
        if who.endswith("notes") or not pts:
            continue
        ax.plot([p["t"] for p in pts], [p["err"] for p in pts], "o-", label=who)
    for who, pts in denoised.items():
        if pts:
            ax.plot([p["t"] for p in pts], [p["err"] for p in pts], "s--", mfc="none",
                    label=who + " + OIDN")
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
    peers, extra = [], []
    for r in rows:
        for p in r["E"]:
            if p not in peers:
                peers.append(p)
        for m in r["methods"]:
            if m not in extra:
                extra.append(m)
    argv = sys.argv[1:]
    if "--cycles-python" in argv:
        k = argv.index("--cycles-python")
        argv = argv[:k] + argv[k + 2:]
    lines = ["```sh", "benches/suite/run.sh " + shlex.join(argv), "```", "",
             "Reference: Mitsuba 3 `%s`, %d spp. E = t_peer err_peer^2 / (t_rondo err_rondo^2) "
             "at rondo's largest spp (peers at equal time); err = clamped RMSE; mean = relative "
             "difference of the image mean from the reference's, clamped to [0, 1] (raw in "
             "brackets); E <method> = t err^2 of rondo's first method over that of the method "
             "named (above 1: the named one wins at equal time). Times: rondo's render without its BVH build, Mitsuba's `mi.render` (its BVH "
             "is built at load), Cycles' own `render_time` (no scene synchronisation; see "
             "benches/suite/README.md). On %s each renderer's err is against its own converged "
             "image at the same spp (their materials differ; the mean column gives what that "
             "costs against Mitsuba's).%s" % (args.reference_sampler, args.reference_spp,
                                             ", ".join(sorted(OWN_REFERENCE)),
                                             " Each time is the median of %d, timed in rounds "
                                             "that interleave the renderers (--repeat)."
                                             % args.repeat if args.repeat > 1 else ""), "",
             "| scene | size | rondo spp, s, err | rondo M samples/s, M rays/s | "
             + "".join("rondo %s spp, s, err | E %s | " % (m, m) for m in extra)
             + " | ".join("E vs %s" % p for p in peers) + " | "
             + " | ".join("%s M samples/s" % p for p in peers) + " | mean: rondo | "
             + " | ".join("mean: %s" % p for p in peers) + " |",
             "|" + "---|" * (5 + 2 * len(extra) + 2 * len(peers) + len(peers))]
    for r in rows:
        def m(who):
            v = r["means"].get(who)
            return "%+.1f %% (%+.1f %%)" % (100 * v[1], 100 * v[0]) if v else ""
        def x(m):
            v = r["methods"].get(m)
            return "%d, %.2f, %.4f | %.2f | " % (v["spp"], v["t"], v["err"], v["E"]) if v \
                else " | | "
        lines.append("| %s | %s | %d, %.2f, %.4f | %.2f, %.2f | %s%s | %s | %s | %s |" % (
            r["scene"], r["size"], r["rondo_spp"], r["rondo_t"], r["rondo_err"], r["msps"],
            r["mrps"], "".join(x(m) for m in extra),
            " | ".join("%.2f" % r["E"][p] if p in r["E"] else "" for p in peers),
            " | ".join("%.2f" % r["peer_msps"][p] if p in r["peer_msps"] else "" for p in peers),
            m("rondo"), " | ".join(m(p) for p in peers)))
    lines += denoised_table(rows, args.reference_spp)
    text = "\n".join(lines) + "\n"
    print()
    print(text)
    open(os.path.join(args.out, "summary.md"), "w").write(text)


def denoised_table(rows, reference_spp):
    """Denoised error at each time budget, rondo's beside Cycles + OIDN's. On a scene measured
    against each renderer's own reference, a render of more than a quarter of the reference's
    samples is marked: its error is then mostly the reference's own noise, not the render's."""
    budgets = []
    for r in rows:
        for pts in r["denoised"].values():
            for p in pts:
                if p["budget"] not in budgets:
                    budgets.append(p["budget"])
    if not budgets:
        return []
    who = ["rondo", "cycles"]
    lines = ["", "Denoised (Open Image Denoise, albedo and normal guides, quality high): clamped "
             "RMSE against the same reference at each time budget (render + denoise; Cycles' "
             "own render time, its denoiser included), spp and measured time in brackets. "
             "† a render of more than a quarter of its own reference's %d samples: the error "
             "measures mostly the reference's noise (compare only unmarked cells)." % reference_spp,
             "",
             "| scene | size | " + " | ".join("%s + OIDN, %g s" % (w, b) for b in budgets
                                               for w in who) + " |",
             "|" + "---|" * (2 + len(budgets) * len(who))]
    for r in rows:
        cells = []
        for b in budgets:
            for w in who:
                p = [q for q in r["denoised"].get(w, []) if q["budget"] == b]
                mark = "†" if p and r.get("own_reference") and 4 * p[0]["spp"] > reference_spp \
                    else ""
                cells.append("%.4f%s (%d spp, %.2f s)" % (p[0]["err"], mark, p[0]["spp"],
                                                         p[0]["t"]) if p else "")
        lines.append("| %s | %s | %s |" % (r["scene"], r["size"], " | ".join(cells)))
    return lines


if __name__ == "__main__":
    main()
