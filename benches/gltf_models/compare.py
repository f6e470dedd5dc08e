"""rondo against Blender Cycles' default Principled BSDF (multiple-scattering GGX) on the
Khronos glTF sample models, each placed alone under the sky of scenes/gltf.ron. Run by run.sh
with the Cycles virtual environment's Python; never by the tests. See README.md.

For each model: a RON scene placing the .gltf (camera, size, spp, sky), rendered by rondo to
EXR; `rondo export` of the same scene gives Cycles the camera and the sky (as
benches/suite/cycles_render.py maps them); Cycles imports the same .gltf with Blender's own glTF
importer (turned back to y up), every Principled BSDF left at (and set to) multiple-scattering
GGX. The mean of each channel over the pixels the model covers fully (alpha >= 0.999 in a
16-spp transparent-film Cycles render), rondo / Cycles, and over the whole frame (sky
included)."""

import argparse
import json
import math
import os
import shutil
import subprocess
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(REPO, "benches", "suite"))

import standins  # noqa: E402

# name: (path under --models of the real file, camera position, look_at, fov_y degrees)
MODELS = {
    "MetalRoughSpheres": ("MetalRoughSpheres/glTF/MetalRoughSpheres.gltf",
                          (0, 0, 7.5), (0, 0, 0), 45),
    "DamagedHelmet": ("DamagedHelmet/glTF/DamagedHelmet.gltf", (0, 0, 3.2), (0, 0, 0), 40),
    "NormalTangentTest": ("NormalTangentTest/glTF/NormalTangentTest.gltf",
                          (0, 0, 4.5), (0, 0, 0), 45),
    "TextureTransformTest": ("TextureTransformTest/glTF/TextureTransformTest.gltf",
                             (0, 0, 4.0), (0, 0, 0), 40),
    "SimpleInstancing": ("SimpleInstancing/glTF/SimpleInstancing.gltf",
                         (-14, 18, 30), (5, 5, 5), 40),
    "MultiUVTest": ("MultiUVTest/glTF/MultiUVTest.gltf", (3.5, 2.8, 4.5), (0, 0, 0), 40),
    "AvocadoQuantized": ("Avocado/glTF-Quantized/Avocado.gltf",
                         (0, 0.035, 0.16), (0, 0.031, 0), 30),
}

SCENE = """// {name}: the glTF alone under the sky of gltf.ron (benches/gltf_models/compare.py).
Scene(
    camera: Camera(position: {pos}, look_at: {look}, fov: {fov}),
    settings: Settings(
        width: {w}, height: {h},
        spp: {spp},
        max_depth: {depth},
        environment: Environment(path: "{sky}", strength: 1.0, rotate: (0, 0, 0)),
    ),
    materials: {{}},
    entities: [
        Entity(name: "model", gltf: "{gltf}"),
    ],
)
"""


def read_exr(path, alpha=False):
    """An EXR's RGB (and A) as an H x W x C float32 array, top row first."""
    import OpenEXR

    with OpenEXR.File(path, separate_channels=True) as f:
        ch = f.channels()
        names = list("RGBA" if alpha else "RGB")
        return np.stack([ch[n].pixels.astype(np.float32) for n in names], -1)


def srgb8(x):
    x = np.clip(x, 0, 1)
    return np.round(255 * np.where(x <= 0.0031308, 12.92 * x,
                                   1.055 * x ** (1 / 2.4) - 0.055)).astype(np.uint8)


def cycles_render(gltf, export_dir, out, mask_out, size, spp, depth):
    """Cycles' image of the glTF with the camera and sky of rondo's export (EXR at `out`), and
    the model's coverage as the alpha of a transparent-film render (`mask_out`)."""
    import bpy
    from mathutils import Matrix

    import cycles_render as cr

    b = cr.Builder(export_dir)
    b.j["meshes"], b.j["spheres"] = [], []
    scene = b.build(size, depth)
    scene.cycles.seed = 1
    scene.render.image_settings.color_mode = "RGBA"
    before = set(bpy.data.objects)
    bpy.ops.import_scene.gltf(filepath=gltf)
    new = [o for o in bpy.data.objects if o not in before]
    # The importer turns glTF's y up into Blender's z up; rondo's export is y up: turn back.
    back = Matrix(((1, 0, 0, 0), (0, 0, 1, 0), (0, -1, 0, 0), (0, 0, 0, 1)))
    for o in new:
        if o.parent is None:
            o.matrix_world = back @ o.matrix_world
    principled = 0
    for m in bpy.data.materials:
        if m.node_tree is None:
            continue
        for n in m.node_tree.nodes:
            if n.type == "BSDF_PRINCIPLED":
                n.distribution = "MULTI_GGX"
                principled += 1
    scene.cycles.samples = spp
    scene.render.filepath = out
    bpy.ops.render.render(write_still=True)
    # The model's coverage: the alpha of a transparent-film render (few samples suffice).
    scene.render.film_transparent = True
    scene.cycles.samples = 16
    scene.render.filepath = mask_out
    bpy.ops.render.render(write_still=True)
    return {"objects": len(new), "principled": principled,
            "mesh_objects": sum(o.type == "MESH" for o in new)}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default="bench/gltf_models")
    ap.add_argument("--rondo", default=os.path.join(REPO, "target/release/rondo"))
    ap.add_argument("--label", default="rondo", help="name of this rondo's images and column")
    ap.add_argument("--models", default="", help="folder of the real sample models "
                    "(NAME/glTF/NAME.gltf ...); a model missing there is made as a stand-in")
    ap.add_argument("--only", default="", help="comma-separated model names")
    ap.add_argument("--size", nargs=2, type=int, default=(320, 240))
    ap.add_argument("--spp", type=int, default=256)
    ap.add_argument("--cycles-spp", type=int, default=0, help="default: --spp")
    ap.add_argument("--max-depth", type=int, default=8)
    args = ap.parse_args()
    names = [n for n in args.only.split(",") if n] or list(MODELS)
    w, h = args.size
    cspp = args.cycles_spp or args.spp
    sky = os.path.join(REPO, "scenes/textures/sky.hdr")
    rows = []
    for name in names:
        rel, pos, look, fov = MODELS[name]
        d = os.path.abspath(os.path.join(args.out, name))
        os.makedirs(d, exist_ok=True)
        real = os.path.join(args.models, rel) if args.models else ""
        if real and os.path.isfile(real):
            gltf, kind = os.path.abspath(real), "real"
        else:
            gltf, kind = standins.write(name, os.path.join(d, "model")), "stand-in"
        scene = os.path.join(d, "scene.ron")
        with open(scene, "w") as f:
            f.write(SCENE.format(name=name, pos=tuple(pos), look=tuple(look), fov=fov, w=w, h=h,
                                 spp=args.spp, depth=args.max_depth, sky=sky, gltf=gltf))
        rimg = os.path.join(d, "%s.exr" % args.label)
        log = subprocess.run([args.rondo, "render", scene, "--output", rimg],
                             capture_output=True, text=True)
        warnings = [x for x in log.stderr.splitlines() if "warn" in x.lower()]
        if log.returncode != 0:
            print("%s: rondo failed: %s" % (name, log.stderr.strip()[-400:]), flush=True)
            rows.append({"model": name, "kind": kind, "error": log.stderr.strip()[-400:]})
            continue
        cimg = os.path.join(d, "cycles_%dx%d_%d.exr" % (w, h, cspp))
        info = {}
        cmask = os.path.join(d, "cycles_%dx%d_alpha.exr" % (w, h))
        if not (os.path.isfile(cimg) and os.path.isfile(cmask)):
            export = os.path.join(d, "export")
            shutil.rmtree(export, ignore_errors=True)
            subprocess.run([args.rondo, "export", scene, "--output", export], check=True,
                           capture_output=True)
            info = cycles_render(gltf, export, cimg, cmask, (w, h), cspp, args.max_depth)
        r = read_exr(rimg)
        c = read_exr(cimg)
        mask = read_exr(cmask, alpha=True)[..., 3] >= 0.999
        rm, cm = r[mask].mean(0), c[mask].mean(0)
        row = {"model": name, "kind": kind, "pixels": int(mask.sum()),
               "rondo_rgb": [float(x) for x in rm], "cycles_rgb": [float(x) for x in cm],
               "ratio_rgb": [float(x) for x in rm / cm],
               "ratio": float(rm.mean() / cm.mean()),
               "frame_ratio": float(r.mean() / c.mean()), "warnings": warnings, **info}
        rows.append(row)
        pair = np.concatenate([srgb8(r), np.full((h, 4, 3), 255, np.uint8), srgb8(c)], 1)
        standins.write_png(os.path.join(d, "pair_%s.png" % args.label), pair)
        print(json.dumps(row), flush=True)
    with open(os.path.join(args.out, "result_%s.json" % args.label), "w") as f:
        json.dump(rows, f, indent=1)
    lines = ["| model | file | rondo/Cycles model pixels (R, G, B) | mean | frame | warnings |",
             "|---|---|---|---|---|---|"]
    for r in rows:
        if "error" in r:
            lines.append("| %s | %s | failed: %s | | | |" % (r["model"], r["kind"],
                                                           r["error"].replace("\n", " ")[:120]))
            continue
        lines.append("| %s | %s | %s | %.3f | %.3f | %d |" % (
            r["model"], r["kind"], ", ".join("%.3f" % x for x in r["ratio_rgb"]), r["ratio"],
            r["frame_ratio"], len(r["warnings"])))
    table = "\n".join(lines)
    with open(os.path.join(args.out, "summary_%s.md" % args.label), "w") as f:
        f.write(table + "\n")
    print(table)


if __name__ == "__main__":
    main()
