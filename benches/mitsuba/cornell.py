"""Mitsuba 3 anchor for rondo: the Cornell box at 512x512, max depth 8, `path` integrator,
box pixel filter, rendered by Mitsuba and by rondo at a sweep of spp, interleaved, each
timed; error of both against one converged reference.

Several Mitsuba samplers (--mitsuba-samplers) and several rondo binaries or samplers
(--rondo LABEL=PATH[:SAMPLER], repeatable) can be compared in one run: for each spp every
configuration renders in turn. Errors are reported as RMSE over all pixels and as the
"lamp-out" RMSE: pixels whose reference value exceeds 1 in some channel (the lamp and its
antialiased edge, whose error is pixel-footprint noise only) are left out, and both images
are clamped to [0, 1]. The efficiency E = (t_M e_M^2) / (t_R e_R^2) at each spp, against
Mitsuba's default (independent) sampler and its best, uses the lamp-out error.

Run through `benches/mitsuba/run.sh`, which installs mitsuba into a virtual environment.
Never run by the tests.

The scene mirrors scenes/cornell.ron: the same quads, boxes (rotated about y, then
translated) and lamp, diffuse reflectances used as linear RGB (variant *_rgb), the lamp
one-sided facing down with radiance 15. rondo shades both sides of every surface, so the
Mitsuba BSDFs are wrapped in `twosided`. Camera: rondo's fov is vertical (fov_axis="y");
rondo's image right is direction x up, which is also what Mitsuba's look_at gives (its
camera space is +x = left, and its sample-to-camera map flips x), so no mirror is needed:
the red x = 555 wall is on the image's left in both. The script checks this by comparing
the mean of the left and right image columns before it measures anything.
"""

import argparse
import csv
import os
import re
import resource
import subprocess
import sys
import tempfile
import time

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "common"))
from cornell_geometry import QUADS, ALBEDO  # noqa: E402 - the shared scene data
from image_metrics import metrics  # noqa: E402 - the shared error metrics


def write_obj(path, quads):
    """One OBJ file; quad a b c d becomes triangles a b c and a c d (as rondo splits it)."""
    with open(path, "w") as f:
        for q in quads:
            for v in q:
                f.write("v %r %r %r\n" % tuple(float(c) for c in v))
        for i in range(len(quads)):
            b = 4 * i + 1
            f.write("f %d %d %d\nf %d %d %d\n" % (b, b + 1, b + 2, b, b + 2, b + 3))


def scene_dict(mi, tmp, size, max_depth, sampler="independent"):
    shapes = {}
    for name, material, quads in QUADS:
        path = os.path.join(tmp, name + ".obj")
        write_obj(path, quads)
        shape = {"type": "obj", "filename": path, "face_normals": True}
        if material == "light":
            shape["bsdf"] = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0, 0, 0]}}
            shape["emitter"] = {"type": "area", "radiance": {"type": "rgb", "value": [15, 15, 15]}}
        else:
            shape["bsdf"] = {"type": "twosided", "bsdf": {
                "type": "diffuse", "reflectance": {"type": "rgb", "value": list(ALBEDO[material])}}}
        shapes[name] = shape
    T = mi.ScalarTransform4f
    look = T().look_at if hasattr(T(), "look_at") else T.look_at
    return {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": max_depth},
        "sensor": {
            "type": "perspective",
            "fov": 40.0,
            "fov_axis": "y",
            "to_world": look(origin=[278, 278, -800], target=[278, 278, 0], up=[0, 1, 0]),
            "sampler": {"type": sampler, "sample_count": 1},
            "film": {"type": "hdrfilm", "width": size, "height": size,
                     "rfilter": {"type": "box"}, "pixel_format": "rgb"},
        },
        **shapes,
    }


def read_exr(mi, path):
    return np.array(mi.Bitmap(path).convert(mi.Bitmap.PixelFormat.RGB,
                                            mi.Struct.Type.Float32, srgb_gamma=False))


def cpu_seconds(who):
    """User + system CPU time of this process (Mitsuba's threads) or of its waited-for children."""
    r = resource.getrusage(who)
    return r.ru_utime + r.ru_stime


def rondo_render(rondo, scene, spp, seed, out, size, max_depth, sampler=None):
    """Renders with rondo (method mis, the default; `sampler` if given, else the binary's
    default); returns rondo's own render wall time and the process's CPU time (scene loading
    included, a few ms)."""
    cmd = [rondo, "render", scene, "-o", out, "--spp", str(spp), "--seed", str(seed),
           "--width", str(size), "--height", str(size), "--max-depth", str(max_depth),
           "--method", "mis"] + (["--sampler", sampler] if sampler else [])
    c = cpu_seconds(resource.RUSAGE_CHILDREN)
    p = subprocess.run(cmd, capture_output=True, text=True)
    cpu = cpu_seconds(resource.RUSAGE_CHILDREN) - c
    if p.returncode != 0:
        sys.exit("rondo failed: %s\n%s" % (" ".join(cmd), p.stderr))
    m = re.search(r"spp, ([0-9.]+) s,", p.stderr)
    if not m:
        sys.exit("cannot read rondo's time from: %s" % p.stderr)
    return float(m.group(1)), cpu


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--reference", required=True, help="converged reference .exr (512x512)")
    ap.add_argument("--rondo", action="append", metavar="LABEL=PATH[:SAMPLER]",
                    help="a rondo configuration (repeatable); default rondo=target/release/rondo")
    ap.add_argument("--mitsuba-samplers", default="independent",
                    help="Mitsuba samplers, comma-separated (independent, stratified, "
                         "multijitter, orthogonal, ldsampler)")
    ap.add_argument("--reference-sampler", default="independent",
                    help="Mitsuba sampler of --make-reference")
    ap.add_argument("--scene", default="scenes/cornell.ron")
    ap.add_argument("--spp-list", default="4,16,64,256")
    ap.add_argument("--size", type=int, default=512)
    ap.add_argument("--max-depth", type=int, default=8)
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("--out", default="bench/mitsuba")
    ap.add_argument("--make-reference", type=int, default=0, metavar="SPP",
                    help="only render a Mitsuba reference at SPP to --reference, then stop")
    args = ap.parse_args()

    import mitsuba as mi
    import drjit as dr
    try:
        mi.set_variant(args.variant)
        variant = args.variant
    except Exception as e:  # noqa: BLE001 - report why and fall back
        print("variant %s unavailable (%s); falling back to scalar_rgb" % (args.variant, e))
        mi.set_variant("scalar_rgb")
        variant = "scalar_rgb"
    print("mitsuba %s, variant %s" % (mi.__version__, variant))
    os.makedirs(args.out, exist_ok=True)
    tmp = tempfile.mkdtemp(prefix="rondo-mitsuba-")
    samplers = args.mitsuba_samplers.split(",")
    if args.make_reference:
        samplers = [args.reference_sampler]
    scenes = {s: mi.load_dict(scene_dict(mi, tmp, args.size, args.max_depth, s)) for s in samplers}
    scene = scenes[samplers[0]]

    def render(spp, seed, with_cpu=False, scene=scene):
        c = cpu_seconds(resource.RUSAGE_SELF)
        t = time.perf_counter()
        img = mi.render(scene, spp=spp, seed=seed)
        dr.eval(img)
        arr = np.array(img)
        wall = time.perf_counter() - t
        if with_cpu:
            return wall, cpu_seconds(resource.RUSAGE_SELF) - c, arr
        return wall, arr

    if args.make_reference:
        # In passes of 256 spp (bounded memory), averaged.
        acc, done, total = None, 0, 0.0
        while done < args.make_reference:
            n = min(256, args.make_reference - done)
            dt, arr = render(n, 10_000 + done)
            acc = arr * n if acc is None else acc + arr * n
            done += n
            total += dt
            print("reference: %d/%d spp, %.1f s" % (done, args.make_reference, total), flush=True)
        mi.util.write_bitmap(args.reference, acc / done)
        return

    ref = read_exr(mi, args.reference)
    if ref.shape[:2] != (args.size, args.size):
        sys.exit("%s: reference is %dx%d, expected %dx%d" % (
            args.reference, ref.shape[1], ref.shape[0], args.size, args.size))

    # Orientation check: the red wall (more red than green) must be on the left in both.
    _, probe = render(16, 1)
    for name, img in (("mitsuba", probe), ("reference", ref)):
        left, right = img[:, : args.size // 8], img[:, -args.size // 8:]
        if not (left[..., 0].mean() > left[..., 1].mean() and right[..., 1].mean() > right[..., 0].mean()):
            sys.exit("%s: red wall not on the left: camera conventions differ" % name)

    configs = []
    for spec in args.rondo or ["rondo=target/release/rondo"]:
        # A bare PATH (as run.sh passes the fresh build) is labelled "rondo".
        label, _, rest = spec.partition("=") if "=" in spec else ("rondo", "=", spec)
        path, _, sampler = rest.partition(":")
        configs.append((label, path, sampler or None))

    rows = []
    spps = [int(s) for s in args.spp_list.split(",")]
    for k, spp in enumerate(spps):
        for sampler in samplers:
            # Mitsuba JIT-compiles its kernels; a first render at this spp (untimed) fills the
            # kernel cache, so the timed one measures rendering only, as rondo's time does.
            cold, _ = render(spp, 100 + k, scene=scenes[sampler])
            warm, cpu, img = render(spp, 200 + k, with_cpu=True, scene=scenes[sampler])
            m = metrics(img, ref)
            rows.append(("mitsuba-" + sampler, spp, warm, cpu, cold) + m)
            print("%-22s %5d spp  %8.3f s  cpu %8.3f s (cold %.3f s)  rmse %.4e  lamp-out %.4e"
                  % ("mitsuba-" + sampler, spp, warm, cpu, cold, m[0], m[3]), flush=True)
        for label, path, sampler in configs:
            out = os.path.join(tmp, "rondo.exr")
            t, cpu = rondo_render(path, args.scene, spp, 300 + k, out, args.size,
                                  args.max_depth, sampler)
            m = metrics(read_exr(mi, out), ref)
            rows.append((label, spp, t, cpu, t) + m)
            print("%-22s %5d spp  %8.3f s  cpu %8.3f s                 rmse %.4e  lamp-out %.4e"
                  % (label, spp, t, cpu, m[0], m[3]), flush=True)

    path = os.path.join(args.out, "mitsuba.csv")
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["renderer", "spp", "seconds", "cpu_seconds", "cold_seconds", "rmse",
                    "rel_mse", "mae", "lamp_out_rmse"])
        w.writerows(rows)
    by = {(r[0], r[1]): r for r in rows}
    mitsubas = ["mitsuba-" + s for s in samplers]
    for spp in spps:
        # Mitsuba's best sampler at this spp: the lowest time x error^2.
        cost = lambda who, col: by[(who, spp)][col] * by[(who, spp)][8] ** 2
        best = min(mitsubas, key=lambda m: cost(m, 2))
        for label, _, _ in configs:
            print("%4d spp %-14s E vs %s: wall %.2f cpu %.2f | E vs best (%s): wall %.2f cpu %.2f"
                  % (spp, label, mitsubas[0], cost(mitsubas[0], 2) / cost(label, 2),
                     cost(mitsubas[0], 3) / cost(label, 3), best,
                     cost(best, 2) / cost(label, 2), cost(best, 3) / cost(label, 3)))
    print("wrote", path)


if __name__ == "__main__":
    main()
