"""A textured partial transmission against Mitsuba 3 (issue 35; a bench, never in the tests).

Writes a 2 x 1 glTF panel (KHR_materials_transmission factor 0.8, a transmissionTexture whose red
is 0 on the left half and 1 on the right, base colour (0.8, 0.3, 0.2), metallic 0.3, roughness
0.2) and a scene placing it over a ground under the sky of scenes/envmap.ron, renders it with
rondo (`mis`) and, from `rondo export`, with Mitsuba 3 through the suite's converter, and prints
rondo / Mitsuba means over the image and over each half of the panel.

    source benches/mitsuba/venv.sh && cargo build --release
    "$VENV/bin/python" benches/mitsuba/transmission_panel.py OUT [SPP]

(the Mitsuba virtual environment of benches/mitsuba/venv.sh, with pillow: the suite's
run.sh installs it).
"""
import base64
import io
import json
import shutil
import struct
import subprocess
import sys
from pathlib import Path

import mitsuba as mi
import numpy as np
from PIL import Image

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "benches" / "suite"))
import mitsuba_scene  # noqa: E402

SIZE = (160, 120)


def write_panel(path):
    """The panel's glTF file, buffers and texture embedded."""
    pos = [(-1, -0.5, 0), (1, -0.5, 0), (1, 0.5, 0), (-1, 0.5, 0)]
    uv = [(0, 1), (1, 1), (1, 0), (0, 0)]
    buf = (b"".join(struct.pack("<3f", *p) for p in pos)
           + b"".join(struct.pack("<3f", 0, 0, 1) for _ in pos)
           + b"".join(struct.pack("<2f", *t) for t in uv)
           + struct.pack("<6H", 0, 1, 2, 0, 2, 3))
    img = Image.new("RGB", (2, 1))
    img.putpixel((1, 0), (255, 0, 0))
    png = io.BytesIO()
    img.save(png, "PNG")
    uri = lambda kind, data: "data:%s;base64,%s" % (kind, base64.b64encode(data).decode())
    gltf = {
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_materials_transmission"],
        "buffers": [{"byteLength": len(buf), "uri": uri("application/octet-stream", buf)}],
        "bufferViews": [{"buffer": 0, "byteOffset": o, "byteLength": n}
                        for o, n in [(0, 48), (48, 48), (96, 32), (128, 12)]],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
             "min": [-1, -0.5, 0], "max": [1, 0.5, 0]},
            {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3"},
            {"bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC2"},
            {"bufferView": 3, "componentType": 5123, "count": 6, "type": "SCALAR"}],
        "images": [{"uri": uri("image/png", png.getvalue())}],
        "samplers": [{"magFilter": 9728, "minFilter": 9728}],
        "textures": [{"source": 0, "sampler": 0}],
        "materials": [{
            "name": "panel", "doubleSided": True,
            "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.3, 0.2, 1],
                                     "metallicFactor": 0.3, "roughnessFactor": 0.2},
            "extensions": {"KHR_materials_transmission": {
                "transmissionFactor": 0.8, "transmissionTexture": {"index": 0}}}}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2},
                                    "indices": 3, "material": 0}]}],
        "nodes": [{"mesh": 0, "name": "panel"}],
        "scenes": [{"nodes": [0]}],
        "scene": 0,
    }
    path.write_text(json.dumps(gltf))


SCENE = """Scene(
    camera: Camera(position: (0, 1.2, 4.5), look_at: (0, 0.6, 0), fov: 35),
    settings: Settings(width: %d, height: %d, spp: 64, max_depth: 8,
        environment: Environment(path: "sky.hdr", strength: 1.0, rotate: (0, 0, 0))),
    materials: { "ground": Diffuse(albedo: Constant((0.5, 0.5, 0.5))) },
    entities: [
        Entity(name: "ground", material: "ground", shape: Quad(a: (-20, 0, 20), b: (20, 0, 20), c: (20, 0, -20), d: (-20, 0, -20))),
        Entity(name: "panel", gltf: "panel.gltf", transform: Transform(translate: (0, 0.7, 0), rotate: (0, 20, 0))),
    ],
)
""" % SIZE


def main():
    out = Path(sys.argv[1])
    spp = int(sys.argv[2]) if len(sys.argv) > 2 else 1024
    out.mkdir(parents=True, exist_ok=True)
    write_panel(out / "panel.gltf")
    shutil.copy(ROOT / "scenes" / "textures" / "sky.hdr", out / "sky.hdr")
    (out / "scene.ron").write_text(SCENE)
    rondo = str(ROOT / "target" / "release" / "rondo")
    subprocess.run([rondo, "export", "scene.ron", "--output", "export"], cwd=out, check=True)
    subprocess.run([rondo, "render", "scene.ron", "--spp", str(spp), "--method", "mis",
                    "-o", "rondo.exr"], cwd=out, check=True)
    mi.set_variant("llvm_ad_rgb")
    scene, notes = mitsuba_scene.load(mi, str(out / "export"), "independent", str(out), SIZE)
    peer = np.array(mi.render(scene, spp=spp, seed=1))
    mi.Bitmap(peer).write(str(out / "mitsuba.exr"))
    ours = np.array(mi.Bitmap(str(out / "rondo.exr")).convert(
        mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32, False))
    print("converter notes:", notes)
    print("whole image: rondo / Mitsuba %.4f" % (ours.mean() / peer.mean()))
    # Rows 35-74 and these columns lie inside the panel's halves at 160 x 120.
    for name, cols in [("left half (no glass)", slice(45, 78)),
                       ("right half (glass share 0.56)", slice(82, 115))]:
        a, b = ours[35:75, cols], peer[35:75, cols]
        print("%s: rondo / Mitsuba %.4f" % (name, a.mean() / b.mean()))


if __name__ == "__main__":
    main()
