"""Blender Cycles anchor for rondo's denoiser (issue 21): the Cornell box at 512x512 rendered by
Cycles (the PyPI `bpy` module, CPU, 2 threads) at a sweep of spp, raw and denoised with
OpenImageDenoise (albedo + normal, prefiltered), each timed; error against the converged
Mitsuba reference of benches/mitsuba/ (plain RMSE and the lamp-out clamped RMSE of
benches/common/image_metrics.py). Optionally rondo renders in the same run, interleaved.

Run through `benches/cycles/run.sh`, which installs bpy into a virtual environment.
Never run by the tests.

The scene is benches/common/cornell_geometry.py, the very data the Mitsuba script uses:
- the quads as triangles a b c, a c d (rondo's split), flat shaded; diffuse reflectances as
  linear RGB (Blender's scene-linear space is Rec.709, the same primaries as rondo's sRGB);
  Cycles shades both sides of a surface, as rondo does;
- the lamp one-sided along its normal (down), radiance 15: an Emission of strength 15 on the
  front face, a black diffuse on the back face (Backfacing mix), emission sampling 'FRONT'. The
  script checks the radiance: the pixels inside the lamp must read 15;
- camera: look-at from (278, 278, -800) to (278, 278, 0), up +y, vertical fov 40 degrees
  (sensor_fit VERTICAL). Blender's camera looks along its local -z with local +y up, so its
  local x (image right) is forward x up = -x world, as rondo's (image right = direction x up):
  the red x = 555 wall is on the image's left. Checked, as in the Mitsuba script, by the
  means of the left and right image columns;
- max bounces: rondo's max_depth counts rays per path, camera ray included (max_depth 8: up to
  7 scattering vertices, the 8th ray reaching the lamp); Cycles' max_bounces counts the
  indirect bounces after the first hit (0 = direct light only, 1 scattering vertex), so
  max_bounces = max_depth - 2 = 6, diffuse_bounces too. `--bounce-check` verifies this by
  image means (see BENCHMARKS.md);
- box pixel filter of width 1 pixel, clamping off (direct and indirect), adaptive sampling off,
  light tree and MIS at their defaults, sampling pattern default, seed fixed (not the
  reference's), CPU device, 2 threads;
- view transform 'Standard', look 'None', and the EXR is scene-linear (float32): the linear
  radiance is compared, no tone curve.

Timing: `seconds` is the wall time of the render call (bpy.ops.render.render: Cycles' scene
sync and BVH build, the path tracing, and the denoiser when on); building the scene in Blender
and writing the EXR are left out. Each configuration renders `--repeats` times in a row with
the same seed (identical images); `seconds` is the fastest, `cpu_seconds` its user + system
CPU time (all of Cycles' threads; less inflated than the wall time when other processes share
the cores), `first_seconds` the first wall time. For rondo, `seconds` is the render time it
logs (scene loading and the EXR write left out), `cpu_seconds` its whole process's.
`process_seconds` (with --process-wall) is the wall time of a fresh Python process that
imports bpy, builds the scene, renders once and writes the EXR: what a user waits for from
the command line.
"""

import argparse
import csv
import json
import math
import os
import re
import resource
import subprocess
import sys
import tempfile
import time

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "common"))
from cornell_geometry import (  # noqa: E402 - the shared scene data
    ALBEDO, CAMERA_FOV_Y, CAMERA_ORIGIN, CAMERA_TARGET, CAMERA_UP, LAMP_RADIANCE, QUADS,
    triangles)
from image_metrics import metrics  # noqa: E402 - the shared error metrics


def normalize(v):
    n = math.sqrt(sum(c * c for c in v))
    return tuple(c / n for c in v)


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def camera_matrix(mathutils):
    """Blender camera-to-world: local -z along the view direction, local +y up, local x =
    forward x up (image right)."""
    forward = normalize(tuple(t - o for t, o in zip(CAMERA_TARGET, CAMERA_ORIGIN)))
    right = normalize(cross(forward, CAMERA_UP))
    up = cross(right, forward)
    back = tuple(-c for c in forward)
    m = mathutils.Matrix.Identity(4)
    for row in range(3):
        m[row][0], m[row][1], m[row][2], m[row][3] = (
            right[row], up[row], back[row], CAMERA_ORIGIN[row])
    return m


def diffuse_material(bpy, name, rgb):
    mat = bpy.data.materials.new(name)
    nodes = mat.node_tree.nodes
    nodes.clear()
    out = nodes.new("ShaderNodeOutputMaterial")
    bsdf = nodes.new("ShaderNodeBsdfDiffuse")
    bsdf.inputs["Color"].default_value = (*rgb, 1.0)
    bsdf.inputs["Roughness"].default_value = 0.0  # Lambert, not Oren-Nayar
    mat.node_tree.links.new(bsdf.outputs["BSDF"], out.inputs["Surface"])
    return mat


def lamp_material(bpy):
    """Emission of radiance LAMP_RADIANCE on the front face (along the normal), a black
    absorber on the back face, as rondo's one-sided Light."""
    mat = bpy.data.materials.new("light")
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    nodes.clear()
    out = nodes.new("ShaderNodeOutputMaterial")
    emission = nodes.new("ShaderNodeEmission")
    emission.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    emission.inputs["Strength"].default_value = LAMP_RADIANCE
    black = nodes.new("ShaderNodeBsdfDiffuse")
    black.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
    geometry = nodes.new("ShaderNodeNewGeometry")
    mix = nodes.new("ShaderNodeMixShader")
    links.new(geometry.outputs["Backfacing"], mix.inputs["Fac"])
    links.new(emission.outputs["Emission"], mix.inputs[1])
    links.new(black.outputs["BSDF"], mix.inputs[2])
    links.new(mix.outputs["Shader"], out.inputs["Surface"])
    mat.cycles.emission_sampling = "FRONT"
    return mat


def build_scene(bpy, mathutils, size, max_bounces, threads):
    """The Cornell box in a fresh Blender scene, with Cycles' settings (see the module doc)."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    materials = {name: diffuse_material(bpy, name, rgb) for name, rgb in ALBEDO.items()}
    materials["light"] = lamp_material(bpy)
    for name, material, quads in QUADS:
        verts = [tuple(float(c) for c in v) for q in quads for v in q]
        mesh = bpy.data.meshes.new(name)
        mesh.from_pydata(verts, [], triangles(quads))
        mesh.update()
        mesh.materials.append(materials[material])
        obj = bpy.data.objects.new(name, mesh)
        scene.collection.objects.link(obj)

    cam_data = bpy.data.cameras.new("camera")
    cam_data.sensor_fit = "VERTICAL"
    cam_data.angle_y = math.radians(CAMERA_FOV_Y)
    cam_data.clip_start = 1.0
    cam_data.clip_end = 1.0e5
    cam = bpy.data.objects.new("camera", cam_data)
    cam.matrix_world = camera_matrix(mathutils)
    scene.collection.objects.link(cam)
    scene.camera = cam

    # A black world (Blender 5 gives new materials and worlds a node tree, no `use_nodes`).
    world = bpy.data.worlds.new("black")
    nodes = world.node_tree.nodes
    nodes.clear()
    background = nodes.new("ShaderNodeBackground")
    background.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
    background.inputs["Strength"].default_value = 0.0
    world.node_tree.links.new(background.outputs["Background"],
                              nodes.new("ShaderNodeOutputWorld").inputs["Surface"])
    scene.world = world

    r = scene.render
    r.engine = "CYCLES"
    r.resolution_x = r.resolution_y = size
    r.resolution_percentage = 100
    r.pixel_aspect_x = r.pixel_aspect_y = 1.0
    r.film_transparent = False
    r.threads_mode = "FIXED"
    r.threads = threads
    r.use_persistent_data = False
    r.image_settings.file_format = "OPEN_EXR"
    r.image_settings.color_mode = "RGB"
    r.image_settings.color_depth = "32"
    r.image_settings.exr_codec = "ZIP"
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0

    c = scene.cycles
    c.device = "CPU"
    c.use_adaptive_sampling = False
    c.time_limit = 0.0
    c.pixel_filter_type = "BOX"
    c.filter_width = 1.0
    c.sample_clamp_direct = 0.0
    c.sample_clamp_indirect = 0.0
    c.max_bounces = max_bounces
    c.diffuse_bounces = max_bounces
    c.use_animated_seed = False
    c.use_denoising = False
    c.denoiser = "OPENIMAGEDENOISE"
    c.denoising_input_passes = "RGB_ALBEDO_NORMAL"
    c.denoising_prefilter = "ACCURATE"
    c.denoising_use_gpu = False
    return scene


def cpu_seconds(who):
    """User + system CPU time of this process (Cycles' threads) or of its waited-for children."""
    r = resource.getrusage(who)
    return r.ru_utime + r.ru_stime


def render(bpy, scene, spp, seed, denoise, out):
    """Renders once; returns the wall and CPU seconds of the render call. Writes the EXR to
    `out`."""
    c = scene.cycles
    c.samples = spp
    c.seed = seed
    c.use_denoising = denoise
    scene.view_layers[0].cycles.use_denoising = denoise
    cpu = cpu_seconds(resource.RUSAGE_SELF)
    t = time.perf_counter()
    bpy.ops.render.render(write_still=False)
    dt = time.perf_counter() - t
    cpu = cpu_seconds(resource.RUSAGE_SELF) - cpu
    bpy.data.images["Render Result"].save_render(out, scene=scene)
    return dt, cpu


def read_exr(bpy, path):
    """An EXR's RGB as an H x W x 3 float32 array, top row first, values untouched."""
    img = bpy.data.images.load(path, check_existing=False)
    try:
        img.colorspace_settings.name = "Non-Color"
        w, h = img.size
        if w == 0 or h == 0:
            sys.exit("%s: cannot read the image" % path)
        px = np.empty(w * h * img.channels, dtype=np.float32)
        img.pixels.foreach_get(px)
        return px.reshape(h, w, img.channels)[::-1, :, :3].copy()
    finally:
        bpy.data.images.remove(img)


def read_rgb_channels(path):
    """The R, G, B channels of an EXR by name, with the `OpenEXR` bindings: rondo's denoised
    EXRs carry more channels (`raw.R`, …) beside them, which Blender's image loader does not
    read."""
    import OpenEXR

    with OpenEXR.File(path, separate_channels=True) as f:
        channels = f.channels()
        return np.stack([channels[c].pixels.astype(np.float32) for c in "RGB"], axis=-1)


def red_on_left(img):
    """The orientation check of the Mitsuba script: the red wall (more red than green) on the
    left, the green one on the right."""
    n = img.shape[1] // 8
    left, right = img[:, :n], img[:, -n:]
    return left[..., 0].mean() > left[..., 1].mean() and right[..., 1].mean() > right[..., 0].mean()


def rondo_render(rondo, scene_path, spp, seed, out, size, max_depth, denoise=False):
    """rondo, method mis and its default sampler (with `denoise`, `--denoise`: Open Image
    Denoise guided by albedo and normal); returns its own time (render, plus the denoise when
    denoised, from its log), the process wall time and the process CPU time."""
    cmd = [rondo, "render", scene_path, "-o", out, "--spp", str(spp), "--seed", str(seed),
           "--width", str(size), "--height", str(size), "--max-depth", str(max_depth),
           "--method", "mis"] + (["--denoise"] if denoise else [])
    cpu = cpu_seconds(resource.RUSAGE_CHILDREN)
    t = time.perf_counter()
    p = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - t
    cpu = cpu_seconds(resource.RUSAGE_CHILDREN) - cpu
    if p.returncode != 0:
        sys.exit("rondo failed: %s\n%s" % (" ".join(cmd), p.stderr))
    m = re.search(r"spp, ([0-9.]+) s,", p.stderr)
    if not m:
        sys.exit("cannot read rondo's time from: %s" % p.stderr)
    own = float(m.group(1))
    if denoise:
        d = re.search(r"denoised in ([0-9.]+) s", p.stderr)
        if not d:
            sys.exit("cannot read rondo's denoise time from: %s" % p.stderr)
        own += float(d.group(1))
    return own, wall, cpu


def child_main(args, bpy, mathutils):
    """--child: one render in this fresh process (for --process-wall); prints its render-call
    time as JSON on the last line."""
    spp, mode = args.child.split(":")
    scene = build_scene(bpy, mathutils, args.size, args.max_depth - 2, args.threads)
    dt, cpu = render(bpy, scene, int(spp), args.seed, mode == "denoised", args.child_out)
    print(json.dumps({"render_seconds": dt, "render_cpu_seconds": cpu}))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0].replace("\n", " "))
    ap.add_argument("--reference", default="bench/mitsuba/reference.exr",
                    help="converged reference .exr (size x size)")
    ap.add_argument("--also-reference", action="append", metavar="PATH",
                    help="a further reference (repeatable): its lamp-out RMSE in extra columns")
    ap.add_argument("--spp-list", default="4,16,64")
    ap.add_argument("--modes", default="raw,denoised", help="raw, denoised or both")
    ap.add_argument("--size", type=int, default=512)
    ap.add_argument("--max-depth", type=int, default=8,
                    help="rondo's max_depth (rays per path); Cycles gets max_bounces = this - 2")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--seed", type=int, default=21,
                    help="Cycles' seed (the Mitsuba reference used 10000 and up)")
    ap.add_argument("--seeds", type=int, default=1,
                    help="render every configuration with this many seeds (--seed, --seed + 1, "
                         "...): the error of a denoised 4-spp image varies by seed")
    ap.add_argument("--repeats", type=int, default=2,
                    help="renders of each configuration's first seed in this process (timing)")
    ap.add_argument("--process-wall", action="store_true",
                    help="also time each configuration as a fresh process (import bpy, build, "
                         "render, write)")
    ap.add_argument("--rondo", metavar="PATH",
                    help="also render with this rondo binary (interleaved), --method mis")
    ap.add_argument("--scene", default="scenes/cornell.ron")
    ap.add_argument("--out", default="bench/cycles")
    ap.add_argument("--keep-images", action="store_true",
                    help="keep every image as OUT/images/<renderer>_<spp>_<mode>_s<seed>.exr")
    ap.add_argument("--bounce-check", action="store_true",
                    help="only print image means at max_bounces depth-3 .. depth-1 against the "
                         "reference's, at the largest spp of --spp-list, then stop")
    ap.add_argument("--child", help=argparse.SUPPRESS)
    ap.add_argument("--child-out", help=argparse.SUPPRESS)
    args = ap.parse_args()

    import bpy
    import mathutils

    if args.child:
        child_main(args, bpy, mathutils)
        return

    print("Blender %s (bpy), Cycles CPU, %d threads" % (bpy.app.version_string, args.threads))
    ref = read_exr(bpy, args.reference)
    if ref.shape[:2] != (args.size, args.size):
        sys.exit("%s: reference is %dx%d, expected %dx%d" % (
            args.reference, ref.shape[1], ref.shape[0], args.size, args.size))
    os.makedirs(args.out, exist_ok=True)
    images = os.path.join(args.out, "images")
    if args.keep_images:
        os.makedirs(images, exist_ok=True)
    tmp = tempfile.mkdtemp(prefix="rondo-cycles-")
    spps = [int(s) for s in args.spp_list.split(",")]
    modes = args.modes.split(",")
    max_bounces = args.max_depth - 2
    scene = build_scene(bpy, mathutils, args.size, max_bounces, args.threads)

    if args.bounce_check:
        print("reference mean %.5f" % ref.mean())
        for b in (max_bounces - 1, max_bounces, max_bounces + 1):
            scene.cycles.max_bounces = scene.cycles.diffuse_bounces = b
            out = os.path.join(tmp, "bounces.exr")
            render(bpy, scene, spps[-1], args.seed, False, out)
            img = read_exr(bpy, out)
            keep = np.all(ref <= 1.0, axis=-1)
            print("max_bounces %d: mean %.5f (lamp-out mean %.5f, reference %.5f)"
                  % (b, img.mean(), img[keep].mean(), ref[keep].mean()), flush=True)
        return

    # Checks before measuring: orientation and the lamp's radiance.
    probe = os.path.join(tmp, "probe.exr")
    render(bpy, scene, 16, args.seed + 1, False, probe)
    img = read_exr(bpy, probe)
    for name, im in (("cycles", img), ("reference", ref)):
        if not red_on_left(im):
            sys.exit("%s: red wall not on the left: camera conventions differ" % name)
    inside = np.all(np.abs(ref - LAMP_RADIANCE) < 1e-3, axis=-1)
    if inside.sum() < 16:
        sys.exit("%s: fewer than 16 pixels read the lamp's radiance %g" % (
            args.reference, LAMP_RADIANCE))
    lamp = img[inside]
    print("lamp check: %d pixels fully inside the lamp read %.4f .. %.4f (radiance %g); "
          "orientation check passed" % (inside.sum(), lamp.min(), lamp.max(), LAMP_RADIANCE))
    if np.max(np.abs(lamp - LAMP_RADIANCE)) > 1e-3 * LAMP_RADIANCE:
        sys.exit("the lamp's pixels differ from its radiance: emission units differ")

    extra = [(path, read_exr(bpy, path)) for path in args.also_reference or []]
    for path, r in extra:
        if r.shape != ref.shape:
            sys.exit("%s: %dx%d, the reference is %dx%d" % (
                path, r.shape[1], r.shape[0], ref.shape[1], ref.shape[0]))
    git = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True)
    rondo_rev = git.stdout.strip() if git.returncode == 0 else "?"
    seeds = [args.seed + i for i in range(max(1, args.seeds))]
    # One row per render: renderer, spp, mode, seed, wall s, CPU s, process wall s (or None),
    # RMSE, lamp-out RMSE, then the lamp-out RMSE against each --also-reference.
    rows = []

    def record(renderer, spp, mode, seed, seconds, cpu, process, path):
        img = read_rgb_channels(path) if renderer == "rondo" else read_exr(bpy, path)
        m = metrics(img, ref)
        others = [metrics(img, r)[3] for _, r in extra]
        rows.append((renderer, spp, mode, seed, seconds, cpu, process, m[0], m[3], others))
        print("%-7s %4d spp %-9s seed %4d %8.3f s cpu %8.3f s process %s  rmse %.4e  "
              "lamp-out %.4e%s" % (renderer, spp, mode, seed, seconds, cpu,
                 "%7.3f s" % process if process is not None else "      -",
                 m[0], m[3], "".join("  (%.4e)" % o for o in others)), flush=True)
        if args.keep_images:
            os.replace(path, os.path.join(images, "%s_%d_%s_s%d.exr" % (renderer, spp, mode, seed)))

    for spp in spps:
        for mode in modes:
            for k, seed in enumerate(seeds):
                out = os.path.join(tmp, "cycles.exr")
                # (wall, cpu) of each repeat of the first seed (one render for the others); the
                # fastest wall is recorded, with its CPU time.
                times = [render(bpy, scene, spp, seed, mode == "denoised", out)
                         for _ in range(max(1, args.repeats) if k == 0 else 1)]
                process = None
                if args.process_wall and k == 0:
                    child_out = os.path.join(tmp, "child.exr")
                    cmd = [sys.executable, os.path.abspath(__file__), "--child",
                           "%d:%s" % (spp, mode), "--child-out", child_out,
                           "--size", str(args.size), "--max-depth", str(args.max_depth),
                           "--threads", str(args.threads), "--seed", str(seed)]
                    t = time.perf_counter()
                    p = subprocess.run(cmd, capture_output=True, text=True)
                    process = time.perf_counter() - t
                    if p.returncode != 0:
                        sys.exit("child render failed: %s\n%s" % (" ".join(cmd), p.stderr[-2000:]))
                best = min(times)
                record("cycles", spp, mode, seed, best[0], best[1], process, out)
        if args.rondo:
            for mode in modes:
                for seed in seeds:
                    out = os.path.join(tmp, "rondo.exr")
                    t, wall, cpu = rondo_render(args.rondo, args.scene, spp, seed, out,
                                                args.size, args.max_depth,
                                                denoise=mode == "denoised")
                    record("rondo", spp, mode, seed, t, cpu, wall, out)

    path = os.path.join(args.out, "cycles.csv")
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["renderer", "spp", "mode", "seed", "seconds", "cpu_seconds",
                    "process_seconds", "rmse", "lamp_out_rmse"]
                   + ["lamp_out_rmse_vs_" + os.path.splitext(os.path.basename(p))[0]
                      for p, _ in extra])
        for r in rows:
            w.writerow(list(r[:4]) + ["%.4f" % r[4], "%.4f" % r[5],
                                      "" if r[6] is None else "%.4f" % r[6],
                                      "%.6g" % r[7], "%.6g" % r[8]] + ["%.6g" % o for o in r[9]])
    print()
    print("Blender %s, rondo %s (%s), reference %s%s; %d seed(s) from %d: errors are means "
          "(min-max), times the fastest render" % (
              bpy.app.version_string, rondo_rev, args.rondo or "not run", args.reference,
              "".join(", also " + p for p, _ in extra), len(seeds), args.seed))
    print("| renderer | spp | mode | wall s (render call) | CPU s | process wall s "
          "| lamp-out RMSE | RMSE |" + "".join(" lamp-out vs %s |" % os.path.basename(p)
                                               for p, _ in extra))
    print("|---|---:|---|---:|---:|---:|---:|---:|" + "---:|" * len(extra))
    groups = {}
    for r in rows:
        groups.setdefault(r[:3], []).append(r)
    for (renderer, spp, mode), g in groups.items():
        fastest = min(g, key=lambda r: r[4])
        process = [r[6] for r in g if r[6] is not None]
        spread = lambda xs: ("%.4f" % np.mean(xs)) + (
            " (%.4f–%.4f)" % (min(xs), max(xs)) if len(xs) > 1 else "")
        print("| %s | %d | %s | %.2f | %.2f | %s | %s | %s |%s" % (
            renderer, spp, mode, fastest[4], fastest[5],
            "%.2f" % min(process) if process else "–", spread([r[8] for r in g]),
            spread([r[7] for r in g]),
            "".join(" %s |" % spread([r[9][i] for r in g]) for i in range(len(extra)))))
    print("wrote", path)


if __name__ == "__main__":
    main()
