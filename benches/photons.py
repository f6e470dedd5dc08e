"""`--method photons` against `caustics` and `mis` where the camera sees caustics in mirrors and
through glass (issue 36; BENCHMARKS.md "Photons for the caustics seen in mirrors and glass").
A bench, never run by the tests.

    benches/photons.py [--rondo target/release/rondo] [--out bench/photons]
                       [--scenes sun_caustics,envmap] [--width 240] [--spp 64] [--seeds 16]
                       [--reference-spp 16384] [--box X0,Y0,X1,Y1]

Needs numpy and the OpenEXR module (`pip install numpy OpenEXR`) in the Python running it.

- Reference per scene: `--method caustics` (unbiased), `--reference-spp` spp, seed 77.
- Renders: `--width` wide (the scene's aspect kept), `--spp`, seeds 1..`--seeds`, each method.
- err: clamped RMSE (pixels whose reference exceeds 1 left out, both images clamped to [0, 1])
  over the whole image, and over the pixels seen through mirrors and glass: those where a
  `photons` and a `caustics` render of the same seed differ (seeds 1-4), the only pixels
  whose camera paths gather.
- `--box`: also the err over that box of pixels (at `--width`; X1, Y1 excluded), e.g. a
  glossy caustic on `sunlit.ron`: `--scenes sunlit --box 90,100,185,150`, the ground around
  and in front of the gold ball.
- Fireflies: pixels whose luminance is above 4x the reference's and above it by 0.1, mean
  per image; "sky seen through glass" are those also in a `mis` render of the same seed with
  every non-specular material black: light seen only through mirrors and glass (camera ->
  specular -> sky), which no method here samples but the pixel's own.
- Time: wall seconds of each render, median per method (for ratios use farm-bench).
"""

import argparse
import os
import re
import subprocess
import sys
import time

import numpy as np
import OpenEXR

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, ".."))
LUMA = np.array([0.2126, 0.7152, 0.0722])
METHODS = ["mis", "caustics", "photons"]


def read_exr(path):
    with OpenEXR.File(path) as f:
        return np.array(f.channels()["RGB"].pixels[..., :3], dtype=np.float64)


def render(rondo, scene, out, size, spp, seed, method):
    cmd = [rondo, "render", scene, "-o", out, "--spp", str(spp), "--seed", str(seed),
           "--width", str(size[0]), "--height", str(size[1]), "--method", method]
    start = time.monotonic()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.monotonic() - start


def blackened(scene, out):
    """The scene with every `Diffuse` and `Glossy` material black, its paths absolute."""
    text = open(scene).read()
    text = re.sub(r"(Diffuse|Glossy)\(albedo: Constant\(\([^)]*\)\)(, roughness: [0-9.]+)?\)",
                  "Diffuse(albedo: Constant((0, 0, 0)))", text)
    text = text.replace('"textures/', '"%s/' % os.path.join(ROOT, "scenes", "textures"))
    path = os.path.join(out, "black_" + os.path.basename(scene))
    with open(path, "w") as f:
        f.write(text)
    return path


def fireflies(img, ref):
    a, r = img @ LUMA, ref @ LUMA
    return (a > 4 * r) & (a > r + 0.1)


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--rondo", default=os.path.join(ROOT, "target", "release", "rondo"))
    p.add_argument("--out", default="bench/photons")
    p.add_argument("--scenes", default="sun_caustics,envmap")
    p.add_argument("--width", type=int, default=240)
    p.add_argument("--spp", type=int, default=64)
    p.add_argument("--seeds", type=int, default=16)
    p.add_argument("--reference-spp", type=int, default=16384)
    p.add_argument("--box", default=None, help="X0,Y0,X1,Y1: also the err over these pixels")
    args = p.parse_args()
    box = [int(v) for v in args.box.split(",")] if args.box else None
    os.makedirs(args.out, exist_ok=True)
    seeds = range(1, args.seeds + 1)
    print("| scene | method | s (median) | err | err seen through specular | fireflies "
          "| of which sky seen through glass | image mean / reference's |"
          + (" err in the box |" if box else ""))
    print("|---|---|---|---|---|---|---|---|" + ("---|" if box else ""))
    for name in args.scenes.split(","):
        scene = os.path.join(ROOT, "scenes", name + ".ron")
        text = open(scene).read()
        w = int(re.search(r"width:\s*(\d+)", text).group(1))
        h = int(re.search(r"height:\s*(\d+)", text).group(1))
        size = (args.width, max(8, round(args.width * h / w)))
        ref_path = os.path.join(args.out, "reference_%s_%d.exr" % (name, args.reference_spp))
        if not os.path.isfile(ref_path):
            render(args.rondo, scene, ref_path, size, args.reference_spp, 77, "caustics")
        ref = read_exr(ref_path)
        valid = (ref <= 1).all(-1)
        black = blackened(scene, args.out)
        images, times = {}, {}
        for m in METHODS:
            images[m], times[m] = [], []
            for s in seeds:
                path = os.path.join(args.out, "%s_%s_%d.exr" % (name, m, s))
                times[m].append(render(args.rondo, scene, path, size, args.spp, s, m))
                images[m].append(read_exr(path))
        sky = []
        for s in seeds:
            path = os.path.join(args.out, "black_%s_%d.exr" % (name, s))
            render(args.rondo, black, path, size, args.spp, s, "mis")
            sky.append(fireflies(read_exr(path), ref))
        seen = np.zeros(valid.shape, bool)
        for k in range(min(4, len(images["photons"]))):
            seen |= (images["photons"][k] != images["caustics"][k]).any(-1)
        inside = np.zeros(valid.shape, bool)
        if box:
            inside[box[1]:box[3], box[0]:box[2]] = True
        for m in METHODS:
            sq = np.array([(np.clip(a, 0, 1) - np.clip(ref, 0, 1)) ** 2 for a in images[m]])
            extra = " %.5f (%d px) |" % (np.sqrt(sq[:, inside & valid].mean()),
                                         (inside & valid).sum()) if box else ""
            flies = [fireflies(a, ref) for a in images[m]]
            print("| %s | %s | %.2f | %.5f | %.5f (%d px) | %.2f | %.2f | %.4f |%s" % (
                name, m, np.median(times[m]), np.sqrt(sq[:, valid].mean()),
                np.sqrt(sq[:, seen & valid].mean()), (seen & valid).sum(),
                np.mean([f.sum() for f in flies]),
                np.mean([(f & b).sum() for f, b in zip(flies, sky)]),
                np.mean([a.mean() for a in images[m]]) / ref.mean(), extra), flush=True)


if __name__ == "__main__":
    sys.exit(main())
