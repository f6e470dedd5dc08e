"""Mitsuba 3 side by side for the environment map: scenes/envmap.ron (diffuse, glossy and glass
spheres on a ground quad, lit only by scenes/textures/sky.hdr, a sky with a 2.5-degree sun of
2000x its radiance) rebuilt for Mitsuba, rendered by both at equal time, each compared with one
converged Mitsuba reference: RMSE, the lamp-out RMSE (both clamped to [0, 1], pixels above 1 in
the reference left out: the sun's highlight), the same over the pixels that show surfaces
(not the map seen directly, where the texel lookups differ) and the relative difference of
the image means.

Run through `benches/mitsuba/envmap.sh`, which sets up the virtual environment; never run by
the tests. `--mitsuba-only` skips rondo (to check the Mitsuba half alone).

The match, item by item:
  - environment: Mitsuba's `envmap` at an identity to_world has rondo's convention (y up,
    u = atan2(d.x, -d.z) / 2pi, v = acos(d.y) / pi, row 0 up); `scale` = `strength`. Both
    importance-sample it; Mitsuba looks texels up bilinearly.
  - ground: the same 200x200 quad, written as an OBJ of rondo's two triangles (a b c, a c d);
    diffuse BSDFs are `twosided` because rondo shades both sides.
  - `Diffuse` = `diffuse`; `Dielectric(ior: 1.5)` = `dielectric` with int_ior 1.5 and
    ext_ior 1.0 (Mitsuba's default exterior is air, 1.000277). Difference left: rondo uses
    Schlick's Fresnel, Mitsuba the exact one (equal at normal incidence; at 60 degrees Schlick
    reflects 0.070, the exact 0.089).
  - `Glossy(albedo: 1, roughness: r)` = `roughconductor`, `distribution: ggx`,
    alpha = r^2, `material: none` (Fresnel 1), specular_reflectance 1: with albedo 1 rondo's
    Schlick Fresnel is 1 at every angle too. Difference left: rondo's shadowing-masking is
    Smith's height-correlated G2 = 1 / (1 + L(wi) + L(wo)), Mitsuba's the separable
    G1(wi) G1(wo), which is smaller, so rondo's sphere is a little brighter at grazing angles.
  - camera: rondo's fov is vertical (fov_axis "y"); Mitsuba's look_at gives rondo's image
    orientation (checked: the red sphere must be on the left). Box pixel filter, `path`
    integrator with rondo's max_depth (both count the camera ray).

Equal time: rondo renders at each --spp-list value (method mis, its default sampler; its time
is the render time from its log, without loading the scene and building the map's
distribution, which the process time column includes). Mitsuba gets the spp its timed rate
says fits in the same wall time (the rate measured first, after a warm-up that fills Dr.Jit's
kernel cache), renders once untimed at that spp (the kernels) and once timed; when that time
is off by more than 15 %, the spp is scaled by the ratio and it renders again (at most twice).
--mean-spp renders both once more at that spp for the mean difference with less noise (the
image means are dominated by rare bright paths, sun caustics, so they are noisy at low spp).
"""

import argparse
import math
import os
import re
import subprocess
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "common"))
from image_metrics import metrics  # noqa: E402 - the shared error metrics

# The scene of scenes/envmap.ron (checked against the file by check_scene before anything runs).
CAMERA = {"position": (0.0, 1.6, 7.5), "look_at": (0.0, 0.7, 0.0), "fov": 35.0}
SIZE = (480, 320)
MAX_DEPTH = 8
ENV_PATH = "textures/sky.hdr"
ENV_STRENGTH = 1.0
GROUND = [(-100.0, 0.0, 100.0), (100.0, 0.0, 100.0), (100.0, 0.0, -100.0), (-100.0, 0.0, -100.0)]
GROUND_ALBEDO = (0.5, 0.5, 0.5)
DIFFUSE_ALBEDO = (0.7, 0.2, 0.15)
GLOSSY_ROUGHNESS = 0.4
GLASS_IOR = 1.5
SPHERES = [("diffuse", (-2.2, 0.75, 0.0), 0.75), ("glossy", (0.0, 0.75, 0.0), 0.75),
           ("glass", (2.2, 0.75, 0.0), 0.75)]


def numbers(text):
    return tuple(float(x) for x in re.findall(r"-?[0-9]+(?:\.[0-9]*)?(?:[eE]-?[0-9]+)?", text))


def check_scene(path):
    """Exits unless the RON file still has the numbers this script builds for Mitsuba."""
    text = re.sub(r"//[^\n]*", "", open(path).read())

    def field(pattern, what):
        m = re.search(pattern, text, re.S)
        if not m:
            sys.exit("%s: cannot find %s; update benches/mitsuba/envmap.py" % (path, what))
        return m.group(1)

    found = {
        "camera position": numbers(field(r"position:\s*(\([^)]*\))", "the camera position")),
        "camera look_at": numbers(field(r"look_at:\s*(\([^)]*\))", "look_at")),
        "fov": numbers(field(r"fov:\s*([0-9.]+)", "fov")),
        "size": numbers(field(r"width:\s*([0-9]+)", "width") + " "
                        + field(r"height:\s*([0-9]+)", "height")),
        "max_depth": numbers(field(r"max_depth:\s*([0-9]+)", "max_depth")),
        "environment": (field(r'Environment\(\s*path:\s*"([^"]*)"', "the environment path"),
                        numbers(field(r"strength:\s*([0-9.]+)", "strength")),
                        numbers(field(r"Environment\([^)]*rotate:\s*(\([^)]*\))", "rotate"))),
        "ground": numbers(field(r"Quad\((.*?\))\)", "the ground quad")),
        "albedos": [numbers(a) for a in re.findall(r"albedo:\s*Constant\((\([^)]*\))\)", text)],
        "roughness": numbers(field(r"roughness:\s*([0-9.]+)", "roughness")),
        "ior": numbers(field(r"ior:\s*([0-9.]+)", "ior")),
        "spheres": [numbers(c + " " + r) for c, r in re.findall(
            r"Sphere\(\s*center:\s*(\([^)]*\)),\s*radius:\s*([0-9.]+)\s*\)", text)],
        "aperture": re.findall(r"aperture|focus|\bsun\b|Sun\(|background", text),
    }
    want = {
        "camera position": CAMERA["position"], "camera look_at": CAMERA["look_at"],
        "fov": (CAMERA["fov"],), "size": SIZE, "max_depth": (MAX_DEPTH,),
        "environment": (ENV_PATH, (ENV_STRENGTH,), (0.0, 0.0, 0.0)),
        "ground": tuple(c for v in GROUND for c in v),
        "albedos": [GROUND_ALBEDO, DIFFUSE_ALBEDO, (1.0, 1.0, 1.0)],
        "roughness": (GLOSSY_ROUGHNESS,), "ior": (GLASS_IOR,),
        "spheres": [c + (r,) for _, c, r in SPHERES], "aperture": [],
    }
    for key, value in want.items():
        if found[key] != value:
            sys.exit("%s: %s is %r, this script builds %r; update benches/mitsuba/envmap.py"
                     % (path, key, found[key], value))


def write_obj(path, quad):
    a, b, c, d = quad
    with open(path, "w") as f:
        for v in (a, b, c, d):
            f.write("v %r %r %r\n" % v)
        f.write("f 1 2 3\nf 1 3 4\n")


def scene_dict(mi, tmp, env_file, sampler):
    ground = os.path.join(tmp, "ground.obj")
    write_obj(ground, GROUND)

    def rgb(v):
        return {"type": "rgb", "value": list(v)}

    bsdfs = {
        "diffuse": {"type": "twosided", "bsdf": {"type": "diffuse",
                                                 "reflectance": rgb(DIFFUSE_ALBEDO)}},
        "glossy": {"type": "roughconductor", "distribution": "ggx", "material": "none",
                   "alpha": GLOSSY_ROUGHNESS ** 2, "specular_reflectance": rgb((1, 1, 1))},
        "glass": {"type": "dielectric", "int_ior": GLASS_IOR, "ext_ior": 1.0},
    }
    T = mi.ScalarTransform4f
    look = T().look_at if hasattr(T(), "look_at") else T.look_at
    d = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": MAX_DEPTH},
        "sensor": {
            "type": "perspective", "fov": CAMERA["fov"], "fov_axis": "y",
            "to_world": look(origin=list(CAMERA["position"]), target=list(CAMERA["look_at"]),
                             up=[0, 1, 0]),
            "sampler": {"type": sampler, "sample_count": 1},
            "film": {"type": "hdrfilm", "width": SIZE[0], "height": SIZE[1],
                     "rfilter": {"type": "box"}, "pixel_format": "rgb"},
        },
        "sky": {"type": "envmap", "filename": env_file, "scale": ENV_STRENGTH},
        "ground": {"type": "obj", "filename": ground, "face_normals": True,
                   "bsdf": {"type": "twosided", "bsdf": {"type": "diffuse",
                                                         "reflectance": rgb(GROUND_ALBEDO)}}},
    }
    for name, centre, radius in SPHERES:
        d[name] = {"type": "sphere", "center": list(centre), "radius": radius, "bsdf": bsdfs[name]}
    return d


def read_exr(mi, path):
    return np.array(mi.Bitmap(path).convert(mi.Bitmap.PixelFormat.RGB,
                                            mi.Struct.Type.Float32, srgb_gamma=False))


def red_on_left(img):
    """The red diffuse sphere is in the left third: more red-dominant pixels there than in
    the right third."""
    third = img.shape[1] // 3

    def reds(part):
        return int(np.sum((part[..., 0] > 2 * part[..., 1]) & (part[..., 0] > 0.05)))

    return reds(img[:, :third]) > 10 * reds(img[:, -third:]) + 100


def rondo_render(rondo, scene, spp, seed, out):
    """rondo's own render wall time (from its log: scene loading and the map's distribution
    excluded) and the process's wall time (everything)."""
    cmd = [rondo, "render", scene, "-o", out, "--spp", str(spp), "--seed", str(seed),
           "--method", "mis"]
    t = time.perf_counter()
    p = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - t
    if p.returncode != 0:
        sys.exit("rondo failed: %s\n%s" % (" ".join(cmd), p.stderr))
    m = re.search(r"spp, ([0-9.]+) s,", p.stderr)
    if not m:
        sys.exit("cannot read rondo's time from: %s" % p.stderr)
    return float(m.group(1)), wall


def surface_mask():
    """True where the camera ray through the pixel centre hits the ground or a sphere and so
    do its 8 neighbours' rays: the pixels that do not show the map directly. There the two
    renderers' texel lookups (Mitsuba's bilinear, rondo's nearest) make a systematic
    difference of up to a texel's height, largest across the horizon's sky-to-ground step."""
    w, h = SIZE
    eye, target = np.array(CAMERA["position"]), np.array(CAMERA["look_at"])
    fwd = (target - eye) / np.linalg.norm(target - eye)
    right = np.cross(fwd, [0.0, 1.0, 0.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, fwd)
    t = math.tan(math.radians(CAMERA["fov"]) / 2)
    x = (2 * (np.arange(w) + 0.5) / w - 1) * t * w / h
    y = (1 - 2 * (np.arange(h) + 0.5) / h) * t
    d = fwd + x[None, :, None] * right + y[:, None, None] * up
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    hit = np.zeros((h, w), bool)
    with np.errstate(divide="ignore", invalid="ignore"):
        s = -eye[1] / d[..., 1]  # the ground's plane y = 0
        p = eye + s[..., None] * d
        lo, hi = np.min(GROUND, axis=0), np.max(GROUND, axis=0)
        hit |= (s > 0) & (p[..., 0] >= lo[0]) & (p[..., 0] <= hi[0]) & (p[..., 2] >= lo[2]) \
            & (p[..., 2] <= hi[2])
    for _, centre, radius in SPHERES:
        oc = eye - np.array(centre)
        b = np.sum(d * oc, axis=-1)
        hit |= b * b - (oc @ oc - radius * radius) > 0
    padded = np.pad(hit, 1, mode="edge")
    keep = hit.copy()
    for dj in range(3):
        for di in range(3):
            keep &= padded[dj:dj + h, di:di + w]
    return keep


def mean_diff(img, ref):
    """Relative difference of the image means (all channels), and the largest per channel."""
    total = (img.mean() - ref.mean()) / ref.mean()
    per = [(img[..., c].mean() - ref[..., c].mean()) / ref[..., c].mean() for c in range(3)]
    return total, max(per, key=abs)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--scene", default="scenes/envmap.ron")
    ap.add_argument("--reference", default="bench/mitsuba/envmap_reference.exr")
    ap.add_argument("--reference-spp", type=int, default=4096)
    ap.add_argument("--reference-sampler", default="ldsampler")
    ap.add_argument("--rondo", default=os.environ.get("RONDO_BIN", "target/release/rondo"),
                    help="the rondo binary (default: $RONDO_BIN, which envmap.sh sets to a "
                         "private copy of target/release/rondo)")
    ap.add_argument("--spp-list", default="4,16,64")
    ap.add_argument("--mean-spp", type=int, default=1024,
                    help="spp of one more render by each for the mean difference (0: none)")
    ap.add_argument("--mitsuba-sampler", default="independent")
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("--mitsuba-only", action="store_true", help="no rondo renders")
    ap.add_argument("--out", default="bench/mitsuba")
    args = ap.parse_args()
    check_scene(args.scene)
    env_file = os.path.join(os.path.dirname(os.path.abspath(args.scene)), ENV_PATH)
    if not os.path.isfile(env_file):
        sys.exit("%s: missing; run python3 scripts/make-sky.py" % env_file)

    import mitsuba as mi
    import drjit as dr
    try:
        mi.set_variant(args.variant)
        variant = args.variant
    except Exception as e:  # noqa: BLE001 - report why and fall back
        print("variant %s unavailable (%s); falling back to scalar_rgb" % (args.variant, e))
        mi.set_variant("scalar_rgb")
        variant = "scalar_rgb"
    print("mitsuba %s, variant %s" % (mi.__version__, variant), flush=True)
    os.makedirs(args.out, exist_ok=True)
    tmp = tempfile.mkdtemp(prefix="rondo-mitsuba-envmap-")

    def render(scene, spp, seed):
        t = time.perf_counter()
        img = mi.render(scene, spp=spp, seed=seed)
        dr.eval(img)
        arr = np.array(img)
        return time.perf_counter() - t, arr

    if not os.path.isfile(args.reference):
        # In passes of 256 spp (bounded memory), averaged.
        scene = mi.load_dict(scene_dict(mi, tmp, env_file, args.reference_sampler))
        acc, done, total = None, 0, 0.0
        while done < args.reference_spp:
            n = min(256, args.reference_spp - done)
            dt, arr = render(scene, n, 10_000 + done)
            acc = arr * n if acc is None else acc + arr * n
            done += n
            total += dt
            print("reference: %d/%d spp, %.1f s" % (done, args.reference_spp, total), flush=True)
        mi.util.write_bitmap(args.reference, acc / done, write_async=False)
    ref = read_exr(mi, args.reference)
    if ref.shape[:2] != (SIZE[1], SIZE[0]):
        sys.exit("%s: reference is %dx%d, expected %dx%d" % (
            args.reference, ref.shape[1], ref.shape[0], SIZE[0], SIZE[1]))
    print("reference: %s (%s, %d spp), mean %.5f" % (
        args.reference, args.reference_sampler, args.reference_spp, ref.mean()), flush=True)

    scene = mi.load_dict(scene_dict(mi, tmp, env_file, args.mitsuba_sampler))
    # Warm-up (kernels), orientation check, then Mitsuba's rate in seconds per spp.
    render(scene, 16, 1)
    t16, probe = render(scene, 16, 2)
    for name, img in (("mitsuba", probe), ("reference", ref)):
        if not red_on_left(img):
            sys.exit("%s: the red sphere is not on the left: camera conventions differ" % name)
    rate = t16 / 16
    print("mitsuba: %.4f s per spp (16 spp in %.3f s)" % (rate, t16), flush=True)

    rows = []

    surfaces = surface_mask()

    def surface_error(img):
        """The lamp-out RMSE over the pixels of surface_mask only."""
        keep = surfaces & np.all(ref <= 1.0, axis=-1)
        d = (np.clip(img, 0, 1) - np.clip(ref, 0, 1))[keep]
        return math.sqrt(np.mean(d.astype(np.float64) ** 2))

    def mitsuba_row(label, spp, seed, target=None):
        for attempt in range(3):
            render(scene, spp, seed)  # untimed: Dr.Jit compiles the kernels of this spp
            t, img = render(scene, spp, seed + 1)
            if target is None or abs(t - target) <= 0.15 * target or attempt == 2:
                break
            spp = max(1, round(spp * target / t))
        m, md, se = metrics(img, ref), mean_diff(img, ref), surface_error(img)
        rows.append((label, "mitsuba", spp, t, None, m[0], m[3], se) + md)
        print("%-8s mitsuba %5d spp %8.3f s  rmse %.4e  lamp-out %.4e  surfaces %.4e  "
              "mean %+.3f %% (worst channel %+.3f %%)" % (
                  label, spp, t, m[0], m[3], se, 100 * md[0], 100 * md[1]), flush=True)
        return img

    def rondo_row(label, spp, seed):
        out = os.path.join(tmp, "rondo.exr")
        t, wall = rondo_render(args.rondo, args.scene, spp, seed, out)
        img = read_exr(mi, out)
        if label == "equal-t" and not red_on_left(img):
            sys.exit("rondo: the red sphere is not on the left: camera conventions differ")
        m, md, se = metrics(img, ref), mean_diff(img, ref), surface_error(img)
        rows.append((label, "rondo", spp, t, wall, m[0], m[3], se) + md)
        print("%-8s rondo   %5d spp %8.3f s  rmse %.4e  lamp-out %.4e  surfaces %.4e  "
              "mean %+.3f %% (worst channel %+.3f %%)  (process %.3f s)" % (
                  label, spp, t, m[0], m[3], se, 100 * md[0], 100 * md[1], wall), flush=True)
        return t, img

    spps = [int(s) for s in args.spp_list.split(",")]
    for k, spp in enumerate(spps):
        if args.mitsuba_only:
            mitsuba_row("equal-n", spp, 100 + 10 * k)
            continue
        t, _ = rondo_row("equal-t", spp, 300 + k)
        mitsuba_row("equal-t", max(1, round(t / rate)), 100 + 10 * k, target=t)
    if args.mean_spp:
        if not args.mitsuba_only:
            t, img = rondo_row("mean", args.mean_spp, 900)
            mi.util.write_bitmap(os.path.join(args.out, "envmap_rondo.exr"), img,
                                 write_async=False)
        img = mitsuba_row("mean", args.mean_spp, 910)
        mi.util.write_bitmap(os.path.join(args.out, "envmap_mitsuba.exr"), img,
                             write_async=False)

    print()
    print("```sh\nbenches/mitsuba/envmap.sh %s\n```" % " ".join(sys.argv[1:]))
    print()
    print("Reference: Mitsuba %s, `%s`, %s, %d spp, %dx%d, max depth %d; mean %.5f."
          % (mi.__version__, variant, args.reference_sampler, args.reference_spp,
             SIZE[0], SIZE[1], MAX_DEPTH, ref.mean()))
    print()
    print("| run | renderer | spp | wall s | process s | RMSE | lamp-out RMSE "
          "| lamp-out, surfaces | mean vs reference | worst channel |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for label, who, spp, t, wall, rmse, lamp_out, se, md, worst in rows:
        print("| %s | %s | %d | %.3f | %s | %.4f | %.4f | %.4f | %+.2f %% | %+.2f %% |"
              % (label, who, spp, t, "%.3f" % wall if wall is not None else "", rmse,
                 lamp_out, se, 100 * md, 100 * worst))
    print()
    print("(wall s: rondo's render time from its log, Mitsuba's wall time of `mi.render` after "
          "a warm-up at the same spp; process s: rondo's whole process, loading included. "
          "Mitsuba's sampler: `%s`.)" % args.mitsuba_sampler)
    if not all(math.isfinite(r[5]) for r in rows):
        sys.exit("non-finite error: an image holds NaN or infinity")


if __name__ == "__main__":
    main()
