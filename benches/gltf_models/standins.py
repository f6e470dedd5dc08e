"""Stand-ins for the Khronos glTF sample models this machine cannot download: small glTF 2.0
files (JSON + .bin + PNG) written with numpy alone, each exercising what its namesake tests.
Never used by the tests. What each one is, and how it differs from the real model: README.md.

    write(name, folder) -> path of the .gltf written in folder"""

import json
import math
import os
import struct
import zlib

import numpy as np

FLOAT, USHORT, SHORT, BYTE, UINT = 5126, 5123, 5122, 5120, 5125


def write_png(path, pixels):
    """An 8-bit RGB or RGBA PNG from an H x W x C uint8 array."""
    h, w, c = pixels.shape
    raw = b"".join(b"\0" + pixels[y].tobytes() for y in range(h))

    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))

    color_type = {3: 2, 4: 6}[c]
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n")
        f.write(chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, color_type, 0, 0, 0)))
        f.write(chunk(b"IDAT", zlib.compress(raw, 9)))
        f.write(chunk(b"IEND", b""))


class Gltf:
    """Accumulates buffer views, accessors and the JSON of one glTF file."""

    def __init__(self):
        self.bin = bytearray()
        self.j = {"asset": {"version": "2.0", "generator": "rondo benches/gltf_models"},
                  "scene": 0, "scenes": [{"nodes": []}], "nodes": [], "meshes": [],
                  "accessors": [], "bufferViews": [], "materials": [], "textures": [],
                  "images": [], "samplers": []}

    def accessor(self, array, component, kind, normalized=False, minmax=False, target=None):
        data = np.ascontiguousarray(array).tobytes()
        while len(self.bin) % 4:
            self.bin.append(0)
        view = {"buffer": 0, "byteOffset": len(self.bin), "byteLength": len(data)}
        if target:
            view["target"] = target
        self.bin += data
        self.j["bufferViews"].append(view)
        a = {"bufferView": len(self.j["bufferViews"]) - 1, "componentType": component,
             "count": len(array), "type": kind}
        if normalized:
            a["normalized"] = True
        if minmax:
            flat = np.asarray(array).reshape(len(array), -1)
            a["min"] = [float(x) for x in flat.min(0)]
            a["max"] = [float(x) for x in flat.max(0)]
        self.j["accessors"].append(a)
        return len(self.j["accessors"]) - 1

    def mesh(self, pos, nrm, idx, material, uvs=(), extra=None):
        attrs = {"POSITION": self.accessor(pos.astype(np.float32), FLOAT, "VEC3", minmax=True,
                                           target=34962),
                 "NORMAL": self.accessor(nrm.astype(np.float32), FLOAT, "VEC3", target=34962)}
        for k, uv in enumerate(uvs):
            attrs["TEXCOORD_%d" % k] = self.accessor(uv.astype(np.float32), FLOAT, "VEC2",
                                                     target=34962)
        attrs.update(extra or {})
        prim = {"attributes": attrs, "material": material,
                "indices": self.accessor(idx.astype(np.uint32).ravel(), UINT, "SCALAR",
                                         target=34963)}
        self.j["meshes"].append({"primitives": [prim]})
        return len(self.j["meshes"]) - 1

    def node(self, **kw):
        self.j["nodes"].append(kw)
        n = len(self.j["nodes"]) - 1
        self.j["scenes"][0]["nodes"].append(n)
        return n

    def texture(self, folder, name, pixels, sampler=None):
        write_png(os.path.join(folder, name), pixels)
        self.j["images"].append({"uri": name})
        s = sampler or {}
        if s not in self.j["samplers"]:
            self.j["samplers"].append(s)
        self.j["textures"].append({"source": len(self.j["images"]) - 1,
                                   "sampler": self.j["samplers"].index(s)})
        return len(self.j["textures"]) - 1

    def material(self, **m):
        self.j["materials"].append(m)
        return len(self.j["materials"]) - 1

    def save(self, folder, name):
        self.j["buffers"] = [{"byteLength": len(self.bin), "uri": name + ".bin"}]
        for k in [k for k, v in self.j.items() if v == []]:
            del self.j[k]
        with open(os.path.join(folder, name + ".bin"), "wb") as f:
            f.write(self.bin)
        path = os.path.join(folder, name + ".gltf")
        with open(path, "w") as f:
            json.dump(self.j, f, indent=1)
        return path


def uv_sphere(radius, center=(0, 0, 0), seg=64, rings=32):
    """Positions, normals, uv (u around, v from the top) and triangles of a UV sphere."""
    th = np.linspace(0, math.pi, rings + 1)
    ph = np.linspace(0, 2 * math.pi, seg + 1)
    t, p = np.meshgrid(th, ph, indexing="ij")
    n = np.stack([np.sin(t) * np.sin(p), np.cos(t), np.sin(t) * np.cos(p)], -1).reshape(-1, 3)
    uv = np.stack([p / (2 * math.pi), t / math.pi], -1).reshape(-1, 2)
    tris = []
    for r in range(rings):
        for s in range(seg):
            a, b = r * (seg + 1) + s, (r + 1) * (seg + 1) + s
            if r > 0:
                tris.append((a, b, a + 1))
            if r < rings - 1:
                tris.append((a + 1, b, b + 1))
    return n * radius + np.asarray(center), n, uv, np.array(tris)


def cube(half=1.0):
    """24 vertices (4 per face), normals, per-face uv (0..1) and 12 triangles."""
    pos, nrm, uv, tris = [], [], [], []
    for axis in range(3):
        for sign in (1, -1):
            n = np.zeros(3)
            n[axis] = sign
            u = np.zeros(3)
            u[(axis + 1) % 3] = 1
            v = np.cross(n, u)
            base = len(pos)
            for du, dv in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
                pos.append(half * (n + du * u + dv * v))
                nrm.append(n)
                uv.append(((du + 1) / 2, (1 - dv) / 2))
            tris += [(base, base + 1, base + 2), (base, base + 2, base + 3)]
    return np.array(pos), np.array(nrm), np.array(uv), np.array(tris)


def metal_rough_spheres(folder):
    """5 x 5 spheres: metallic 0..1 bottom to top, roughness 0..1 left to right, read from a
    5 x 5 metallicRoughness texture (nearest), each sphere's uv at its texel's centre."""
    g = Gltf()
    mr = np.zeros((5, 5, 3), np.uint8)
    for row in range(5):
        for col in range(5):
            mr[row, col] = (0, round(255 * col / 4), round(255 * (4 - row) / 4))
    tex = g.texture(folder, "Spheres_MetalRough.png", mr, {"magFilter": 9728, "minFilter": 9728})
    mat = g.material(pbrMetallicRoughness={"baseColorFactor": [0.9, 0.9, 0.9, 1],
                                           "metallicRoughnessTexture": {"index": tex}})
    P, N, U, T = [], [], [], []
    for row in range(5):
        for col in range(5):
            p, n, _, t = uv_sphere(0.4, ((col - 2) * 1.0, (2 - row) * 1.0, 0))
            T.append(t + sum(len(x) for x in P))
            P.append(p)
            N.append(n)
            U.append(np.tile([(col + 0.5) / 5, (row + 0.5) / 5], (len(p), 1)))
    g.node(mesh=g.mesh(np.vstack(P), np.vstack(N), np.vstack(T), mat, [np.vstack(U)]))
    return g.save(folder, "MetalRoughSpheres")


def normal_tangent_test(folder):
    """3 x 3 spheres with a tangent-space normal map of hemispherical dimples and bumps (no
    TANGENT attribute: readers make MikkTSpace-like tangents), a blue-grey base colour."""
    g = Gltf()
    n = 256
    y, x = (np.mgrid[0:n, 0:n] + 0.5) / n * 8 % 1 - 0.5
    r2 = (x * x + y * y) / 0.16
    inside = r2 < 1
    h = np.sqrt(np.clip(1 - r2, 0, 1))
    sgn = np.where((np.floor(np.mgrid[0:n, 0:n] / n * 8).sum(0) % 2) == 0, 1, -1)
    nx = np.where(inside, sgn * x / 0.4, 0)
    ny = np.where(inside, -sgn * y / 0.4, 0)
    nz = np.where(inside, h, 1)
    v = np.stack([nx, ny, nz], -1)
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    tex = g.texture(folder, "NormalTangentTest_Normal.png",
                    np.round((v * 0.5 + 0.5) * 255).astype(np.uint8))
    mat = g.material(pbrMetallicRoughness={"baseColorFactor": [0.55, 0.6, 0.75, 1],
                                           "metallicFactor": 0.0, "roughnessFactor": 0.45},
                     normalTexture={"index": tex})
    for row in range(3):
        for col in range(3):
            p, nn, uv, t = uv_sphere(0.45, ((col - 1) * 1.1, (1 - row) * 1.1, 0))
            g.node(mesh=g.mesh(p, nn, t, mat, [uv]))
    return g.save(folder, "NormalTangentTest")


def uv_grid_image(n=256, border=(128, 128, 128)):
    """A colour ramp (u red, v green) with a checker and a grey border, as the test's UV.png."""
    y, x = (np.mgrid[0:n, 0:n] + 0.5) / n
    check = ((np.floor(x * 8) + np.floor(y * 8)) % 2) * 0.25 + 0.75
    img = np.stack([x * check, (1 - y) * check, 0.35 * check], -1)
    img = np.round(img * 255).astype(np.uint8)
    b = n // 32
    img[:b], img[-b:], img[:, :b], img[:, -b:] = border, border, border, border
    return img


def texture_transform_test(folder):
    """Six quads, each textured through KHR_texture_transform as in the real test: offsets
    (0.5, 0), (0, 0.5), (0.5, 0.5) on uv 0..0.5; rotation 22.5°; scale 1.5; all three. The
    texture's quadrant [0, 0.5]² is yellow (what a reader that ignores the offset shows), and
    the sampler clamps."""
    g = Gltf()
    img = uv_grid_image()
    img[128:, :128] = (230, 220, 40)  # uv [0, .5]² (v down): "offset not applied"
    tex = g.texture(folder, "UV.png", img, {"magFilter": 9729, "minFilter": 9729,
                                            "wrapS": 33071, "wrapT": 33071})
    cases = [(0.5, {"offset": [0.5, 0.0]}), (0.5, {"offset": [0.0, 0.5]}),
             (0.5, {"offset": [0.5, 0.5]}), (1.0, {"rotation": 0.392699}),
             (1.0, {"scale": [1.5, 1.5]}),
             (1.0, {"offset": [-0.2, -0.1], "rotation": 0.3, "scale": [1.5, 1.5]})]
    for k, (span, tt) in enumerate(cases):
        mat = g.material(pbrMetallicRoughness={
            "baseColorTexture": {"index": tex, "extensions": {"KHR_texture_transform": tt}},
            "metallicFactor": 0.0, "roughnessFactor": 0.8})
        cx, cy = (k % 3 - 1) * 1.2, (0.6 if k < 3 else -0.6)
        p = np.array([(-0.5, -0.5, 0), (0.5, -0.5, 0), (0.5, 0.5, 0), (-0.5, 0.5, 0)]) + (cx, cy, 0)
        uv = np.array([(0, span), (span, span), (span, 0), (0, 0)])
        g.node(mesh=g.mesh(p, np.tile((0, 0, 1.0), (4, 1)), np.array([(0, 1, 2), (0, 2, 3)]),
                           mat, [uv]))
    g.j["extensionsUsed"] = ["KHR_texture_transform"]
    return g.save(folder, "TextureTransformTest")


def simple_instancing(folder):
    """One unit cube placed 125 times by EXT_mesh_gpu_instancing as the real sample
    describes: translations 0..10, rotations 0..90° about (1, 1, 1), scales 1..2 along the
    5 x 5 x 5 grid; the node itself is not drawn apart from its instances."""
    g = Gltf()
    p, n, _, t = cube(0.5)
    mat = g.material(pbrMetallicRoughness={"baseColorFactor": [0.8, 0.5, 0.3, 1],
                                           "metallicFactor": 0.0, "roughnessFactor": 0.5})
    mesh = g.mesh(p, n, t, mat)
    tr, rot, sc = [], [], []
    axis = np.ones(3) / math.sqrt(3)
    for i in range(5):
        for j in range(5):
            for k in range(5):
                f = (i * 25 + j * 5 + k) / 124
                tr.append((i * 2.5, j * 2.5, k * 2.5))
                a = math.radians(90 * f) / 2
                rot.append((*(axis * math.sin(a)), math.cos(a)))
                sc.append((1 + f,) * 3)
    attrs = {"TRANSLATION": g.accessor(np.array(tr, np.float32), FLOAT, "VEC3"),
             "ROTATION": g.accessor(np.array(rot, np.float32), FLOAT, "VEC4"),
             "SCALE": g.accessor(np.array(sc, np.float32), FLOAT, "VEC3")}
    g.node(mesh=mesh, extensions={"EXT_mesh_gpu_instancing": {"attributes": attrs}})
    g.j["extensionsUsed"] = ["EXT_mesh_gpu_instancing"]
    return g.save(folder, "SimpleInstancing")


def multi_uv_test(folder):
    """A cube as the real MultiUVTest: base colour from texture 0 on TEXCOORD_0 (each face the
    whole image), emission (factor 1) from texture 1 on TEXCOORD_1 (each face a quarter of
    it)."""
    g = Gltf()
    p, n, uv0, t = cube(1.0)
    uv1 = np.vstack([uv0[4 * f:4 * f + 4] * 0.25 + ((f % 2) * 0.5, (f // 2) * 0.25)
                     for f in range(6)])
    base = g.texture(folder, "uv0.png", uv_grid_image())
    m = 256
    y, x = np.mgrid[0:m, 0:m]
    emit = np.zeros((m, m, 3), np.uint8)
    emit[..., 2] = np.where(((x // 16 + y // 16) % 2) == 0, 200, 0)
    emit[..., 0] = np.where(x < m // 2, 60, 0)
    glow = g.texture(folder, "uv1.png", emit)
    mat = g.material(pbrMetallicRoughness={"baseColorTexture": {"index": base}},
                     emissiveTexture={"index": glow, "texCoord": 1},
                     emissiveFactor=[1.0, 1.0, 1.0])
    g.node(mesh=g.mesh(p, n, t, mat, [uv0, uv1]))
    return g.save(folder, "MultiUVTest")


def avocado_quantized(folder):
    """An avocado-sized (6 cm) egg as the quantized Avocado is stored: KHR_mesh_quantization
    positions as SHORT (dequantized by the node's scale and translation), normals as
    normalized BYTE, uv as normalized UNSIGNED_SHORT spanning the whole range, which every
    texture's KHR_texture_transform (offset, scale) maps back onto the part of the atlas in use."""
    g = Gltf()
    p, n, uv, t = uv_sphere(1.0, seg=96, rings=48)
    p = p * (0.021, 0.031, 0.021)
    n = n / np.array((0.021, 0.031, 0.021))
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    lo, hi = p.min(0), p.max(0)
    scale = (hi - lo) / 65534
    q = np.round((p - lo) / scale - 32767).astype(np.int16)
    qn = np.round(n * 127).astype(np.int8)
    qn = np.hstack([qn, np.zeros((len(qn), 1), np.int8)])  # 4-byte stride for BYTE VEC3
    uv_lo, uv_span = np.array((0.1, 0.05)), np.array((0.8, 0.9))
    quv = np.round(uv * 65535).astype(np.uint16)
    size = 256
    yy, xx = (np.mgrid[0:size, 0:size] + 0.5) / size
    used = (xx >= uv_lo[0]) & (xx <= uv_lo[0] + uv_span[0]) & (yy >= uv_lo[1]) & \
        (yy <= uv_lo[1] + uv_span[1])
    vv = np.clip((yy - uv_lo[1]) / uv_span[1], 0, 1)
    skin = np.stack([0.12 + 0.2 * vv, 0.22 + 0.25 * vv, 0.05 + 0.03 * vv], -1)
    base = np.where(used[..., None], skin, (0.5, 0.1, 0.4))
    mr = np.zeros((size, size, 3))
    mr[..., 1] = np.where(used, 0.35 + 0.4 * vv, 1.0)
    tt = {"offset": [float(uv_lo[0]), float(uv_lo[1])], "scale": [float(x) for x in uv_span]}
    tb = g.texture(folder, "Avocado_baseColor.png", np.round(base * 255).astype(np.uint8))
    tm = g.texture(folder, "Avocado_roughnessMetallic.png", np.round(mr * 255).astype(np.uint8))
    mat = g.material(pbrMetallicRoughness={
        "baseColorTexture": {"index": tb, "extensions": {"KHR_texture_transform": tt}},
        "metallicRoughnessTexture": {"index": tm, "extensions": {"KHR_texture_transform": tt}}})
    pos = g.accessor(np.hstack([q, np.zeros((len(q), 1), np.int16)]), SHORT, "VEC4")
    # Positions are VEC3: the fourth short pads each to 8 bytes (a byteStride of 8).
    g.j["accessors"][pos]["type"] = "VEC3"
    g.j["bufferViews"][g.j["accessors"][pos]["bufferView"]]["byteStride"] = 8
    g.j["accessors"][pos]["min"] = [int(x) for x in q.min(0)]
    g.j["accessors"][pos]["max"] = [int(x) for x in q.max(0)]
    nrm = g.accessor(qn, BYTE, "VEC4", normalized=True)
    g.j["accessors"][nrm]["type"] = "VEC3"
    g.j["bufferViews"][g.j["accessors"][nrm]["bufferView"]]["byteStride"] = 4
    tex = g.accessor(quv, USHORT, "VEC2", normalized=True)
    idx = g.accessor(t.astype(np.uint16).ravel(), USHORT, "SCALAR")
    g.j["meshes"].append({"primitives": [{"attributes": {"POSITION": pos, "NORMAL": nrm,
                                                         "TEXCOORD_0": tex},
                                          "indices": idx, "material": mat}]})
    centre = lo + 32767 * scale
    g.node(mesh=0, translation=[float(x) for x in centre + (0, 0.031, 0)],
           scale=[float(x) for x in scale])
    g.j["extensionsUsed"] = ["KHR_mesh_quantization", "KHR_texture_transform"]
    g.j["extensionsRequired"] = ["KHR_mesh_quantization"]
    return g.save(folder, "Avocado")


WRITERS = {"MetalRoughSpheres": metal_rough_spheres, "NormalTangentTest": normal_tangent_test,
           "TextureTransformTest": texture_transform_test,
           "SimpleInstancing": simple_instancing, "MultiUVTest": multi_uv_test,
           "AvocadoQuantized": avocado_quantized}


def write(name, folder):
    os.makedirs(folder, exist_ok=True)
    return WRITERS[name](folder)
