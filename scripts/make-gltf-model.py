#!/usr/bin/env python3
"""Writes scenes/models/crates.glb: a small glTF 2.0 model that uses what rondo imports.

    python3 scripts/make-gltf-model.py                       # scenes/models/crates.glb
    python3 scripts/make-gltf-model.py -o /tmp/crates.glb

What is in it (no randomness: the same script gives the same bytes):
  - mesh "crate": a unit cube (24 vertices, per-face normals and texture coordinates) with
    material "Crate": a base colour texture of wooden planks in a metal frame (sRGB), a
    metallic-roughness texture (the frame metallic 1, roughness 0.35; the wood metallic 0,
    roughness 0.75) and a tangent-space normal map of grooves between the planks, the frame
    raised;
  - mesh "fence": a quad with material "Fence": a lattice whose holes are cut out by the base
    colour texture's alpha (alphaMode MASK, cutoff 0.5), double-sided;
  - mesh "orb": a smooth UV sphere (32 x 16) with material "Gold" (metallic 1, roughness 0.2,
    no textures);
  - nodes: "stack" (translated) holding two crates, the upper one turned 30 degrees about y and
    scaled 0.7 (the same mesh twice: one BVH, two instances), "orb" on top, and "fence" beside
    them, rotated about y by a quaternion. The model stands on y = 0 and spans about
    x in [-1.6, 0.6], z in [-0.6, 0.6], y in [0, 2].

Textures are 128 x 128 PNGs inside the .glb (buffer views with a mimeType), written with zlib
and struct from the Python 3 standard library, so the script runs on a fresh machine.
"""

import argparse
import json
import math
import os
import struct
import zlib

SIZE = 128


def png(width, height, channels, pixel):
    """An 8-bit PNG (RGB or RGBA) whose pixel (x, y) from the top-left is `pixel(x, y)`."""
    raw = bytearray()
    for y in range(height):
        raw.append(0)
        for x in range(width):
            raw.extend(pixel(x, y))

    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))

    colour_type = 6 if channels == 4 else 2
    header = struct.pack(">IIBBBBB", width, height, 8, colour_type, 0, 0, 0)
    return (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", header)
        + chunk(b"IDAT", zlib.compress(bytes(raw), 9))
        + chunk(b"IEND", b"")
    )


def crate_texel(x, y):
    """(frame?, groove depth 0..1, plank index) of the crate texture at texel (x, y)."""
    border = 12
    frame = x < border or y < border or x >= SIZE - border or y >= SIZE - border
    plank = (y - border) * 4 // (SIZE - 2 * border)
    within = (y - border) % ((SIZE - 2 * border) // 4)
    groove = 1.0 if within < 2 else 0.0
    return frame, groove, plank


def crate_colour(x, y):
    frame, groove, plank = crate_texel(x, y)
    if frame:
        return (150, 150, 160)
    shade = (0.85, 1.0, 0.92, 0.78)[plank % 4]
    grain = 0.9 + 0.1 * math.sin(x * 0.35 + plank * 2.0 + math.sin(x * 0.05) * 3.0)
    k = shade * grain * (0.45 if groove else 1.0)
    return (int(170 * k), int(110 * k), int(60 * k))


def crate_metallic_roughness(x, y):
    frame, _, _ = crate_texel(x, y)
    # glTF: roughness in G, metallic in B (linear).
    return (0, int(0.35 * 255), 255) if frame else (0, int(0.75 * 255), 0)


def crate_normal(x, y):
    """Tangent-space normal: grooves slope in v at their edges; the frame's inner edge slopes
    outwards in u and v."""
    frame, groove, _ = crate_texel(x, y)
    nx, ny = 0.0, 0.0
    border = 12
    if not frame:
        period = (SIZE - 2 * border) // 4
        within = (y - border) % period
        if within == 0:
            ny = -0.6
        elif within == 1:
            ny = 0.6
    else:
        if x == border - 1:
            nx = -0.5
        if x == SIZE - border:
            nx = 0.5
        if y == border - 1:
            ny = 0.5
        if y == SIZE - border:
            ny = -0.5
    nz = math.sqrt(max(0.0, 1.0 - nx * nx - ny * ny))
    return tuple(int(round((c * 0.5 + 0.5) * 255)) for c in (nx, ny, nz))


def fence_colour(x, y):
    bar = 10
    cell = SIZE // 4
    solid = (x % cell) < bar or (y % cell) < bar
    return (60, 110, 40, 255) if solid else (0, 0, 0, 0)


def cube():
    """A unit cube centred on (0, 0.5, 0): positions, normals, uvs, indices (24 vertices)."""
    faces = [
        ((1, 0, 0), (0, 0, -1), (0, 1, 0)),
        ((-1, 0, 0), (0, 0, 1), (0, 1, 0)),
        ((0, 1, 0), (1, 0, 0), (0, 0, -1)),
        ((0, -1, 0), (1, 0, 0), (0, 0, 1)),
        ((0, 0, 1), (1, 0, 0), (0, 1, 0)),
        ((0, 0, -1), (-1, 0, 0), (0, 1, 0)),
    ]
    pos, nrm, uv, idx = [], [], [], []
    for n, u, v in faces:
        base = len(pos)
        for su, sv in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
            p = [0.5 * (n[k] + su * u[k] + sv * v[k]) for k in range(3)]
            p[1] += 0.5
            pos.append(p)
            nrm.append(list(n))
            # glTF: v runs down the image.
            uv.append([0.5 * (su + 1), 0.5 * (1 - sv)])
        idx += [base, base + 1, base + 2, base, base + 2, base + 3]
    return pos, nrm, uv, idx


def quad():
    """A 1.2 x 1.2 quad in the xy plane standing on y = 0, facing +z."""
    pos = [[-0.6, 0, 0], [0.6, 0, 0], [0.6, 1.2, 0], [-0.6, 1.2, 0]]
    nrm = [[0, 0, 1]] * 4
    uv = [[0, 1], [1, 1], [1, 0], [0, 0]]
    return pos, nrm, uv, [0, 1, 2, 0, 2, 3]


def sphere(nu=32, nv=16, radius=0.3):
    pos, nrm, uv, idx = [], [], [], []
    for j in range(nv + 1):
        theta = math.pi * j / nv
        for i in range(nu + 1):
            phi = 2 * math.pi * i / nu
            n = [math.sin(theta) * math.cos(phi), math.cos(theta), -math.sin(theta) * math.sin(phi)]
            pos.append([radius * c for c in n])
            nrm.append(n)
            uv.append([i / nu, j / nv])
    for j in range(nv):
        for i in range(nu):
            a = j * (nu + 1) + i
            b = a + nu + 1
            if j > 0:
                idx += [a, b, a + 1]
            if j < nv - 1:
                idx += [a + 1, b, b + 1]
    return pos, nrm, uv, idx


class Builder:
    """Buffer views and accessors of one binary chunk."""

    def __init__(self):
        self.bin = bytearray()
        self.views = []
        self.accessors = []

    def view(self, data):
        while len(self.bin) % 4:
            self.bin.append(0)
        self.views.append({"buffer": 0, "byteOffset": len(self.bin), "byteLength": len(data)})
        self.bin.extend(data)
        return len(self.views) - 1

    def floats(self, rows, kind):
        flat = [c for r in rows for c in r]
        acc = {
            "bufferView": self.view(struct.pack("<%df" % len(flat), *flat)),
            "componentType": 5126,
            "count": len(rows),
            "type": kind,
        }
        if kind == "VEC3":
            acc["min"] = [min(r[k] for r in rows) for k in range(3)]
            acc["max"] = [max(r[k] for r in rows) for k in range(3)]
        self.accessors.append(acc)
        return len(self.accessors) - 1

    def indices(self, idx):
        self.accessors.append(
            {
                "bufferView": self.view(struct.pack("<%dH" % len(idx), *idx)),
                "componentType": 5123,
                "count": len(idx),
                "type": "SCALAR",
            }
        )
        return len(self.accessors) - 1

    def mesh(self, name, geometry, material):
        pos, nrm, uv, idx = geometry
        attributes = {
            "POSITION": self.floats(pos, "VEC3"),
            "NORMAL": self.floats(nrm, "VEC3"),
            "TEXCOORD_0": self.floats(uv, "VEC2"),
        }
        return {
            "name": name,
            "primitives": [{"attributes": attributes, "indices": self.indices(idx), "material": material}],
        }


def build():
    b = Builder()
    images = []
    for name, channels, pixel in (
        ("crate_base", 3, crate_colour),
        ("crate_mr", 3, crate_metallic_roughness),
        ("crate_normal", 3, crate_normal),
        ("fence_base", 4, fence_colour),
    ):
        images.append(
            {"name": name, "mimeType": "image/png", "bufferView": b.view(png(SIZE, SIZE, channels, pixel))}
        )
    meshes = [
        b.mesh("crate", cube(), 0),
        b.mesh("fence", quad(), 1),
        b.mesh("orb", sphere(), 2),
    ]
    s = math.sin(math.radians(15))
    c = math.cos(math.radians(15))
    doc = {
        "asset": {"version": "2.0", "generator": "rondo scripts/make-gltf-model.py"},
        "scene": 0,
        "scenes": [{"nodes": [0, 4]}],
        "nodes": [
            {"name": "stack", "translation": [0.0, 0.0, 0.0], "children": [1, 2, 3]},
            {"name": "crate_low", "mesh": 0},
            {"name": "crate_high", "mesh": 0, "translation": [0.05, 1.0, 0.0],
             "rotation": [0.0, s, 0.0, c], "scale": [0.7, 0.7, 0.7]},
            {"name": "orb", "mesh": 2, "translation": [0.05, 1.7 + 0.3, 0.0]},
            {"name": "fence", "mesh": 1, "translation": [-1.1, 0.0, 0.2],
             "rotation": [0.0, math.sin(math.radians(-20)), 0.0, math.cos(math.radians(-20))]},
        ],
        "meshes": meshes,
        "materials": [
            {
                "name": "Crate",
                "pbrMetallicRoughness": {
                    "baseColorTexture": {"index": 0},
                    "metallicRoughnessTexture": {"index": 1},
                },
                "normalTexture": {"index": 2, "scale": 1.0},
            },
            {
                "name": "Fence",
                "pbrMetallicRoughness": {"baseColorTexture": {"index": 3}, "metallicFactor": 0.0, "roughnessFactor": 0.8},
                "alphaMode": "MASK",
                "alphaCutoff": 0.5,
                "doubleSided": True,
            },
            {
                "name": "Gold",
                "pbrMetallicRoughness": {"baseColorFactor": [1.0, 0.78, 0.34, 1.0], "metallicFactor": 1.0, "roughnessFactor": 0.2},
            },
        ],
        "samplers": [{"magFilter": 9729, "minFilter": 9729, "wrapS": 10497, "wrapT": 10497},
                     {"magFilter": 9728, "minFilter": 9728, "wrapS": 33071, "wrapT": 33071}],
        "textures": [
            {"source": 0, "sampler": 0},
            {"source": 1, "sampler": 1},
            {"source": 2, "sampler": 0},
            {"source": 3, "sampler": 1},
        ],
        "images": images,
        "accessors": b.accessors,
        "bufferViews": b.views,
        "buffers": [{"byteLength": len(b.bin)}],
    }
    while len(b.bin) % 4:
        b.bin.append(0)
    text = json.dumps(doc, separators=(",", ":"), sort_keys=True).encode()
    while len(text) % 4:
        text += b" "
    total = 12 + 8 + len(text) + 8 + len(b.bin)
    return (
        b"glTF"
        + struct.pack("<II", 2, total)
        + struct.pack("<I", len(text))
        + b"JSON"
        + text
        + struct.pack("<I", len(b.bin))
        + b"BIN\x00"
        + bytes(b.bin)
    )


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-o", "--output", default=os.path.join(here, "..", "scenes", "models", "crates.glb"))
    args = parser.parse_args()
    os.makedirs(os.path.dirname(os.path.abspath(args.output)), exist_ok=True)
    data = build()
    with open(args.output, "wb") as f:
        f.write(data)
    print(f"wrote {args.output} ({len(data)} bytes)")


if __name__ == "__main__":
    main()
