"""scene.json (from `rondo export`) rendered by Blender Cycles (PyPI `bpy`, CPU), at equal time
with given targets, raw and with its Open Image Denoise denoiser. Run by suite.py with the Cycles
virtual environment's Python; never by the tests. The mapping is in README.md beside this file.

    cycles_render.py EXPORT_DIR OUT_DIR --size W H --targets 1.5,6 [--denoise-targets 1,10]
                     [--spp-list 4,16]

Prints one JSON line per render: {"spp", "seconds", "wall", "file", "denoised"}. seconds is
Cycles' own render time from the EXR's metadata (path tracing, and denoising when on; no scene
synchronisation: the scene is synchronised once and kept, `use_persistent_data`); wall is
bpy.ops.render.render's whole call."""

import argparse
import json
import math
import os
import sys
import time

import bpy
import numpy as np
from mathutils import Matrix, Vector

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))


def read_ply(path):
    """The vertices (N x k float32, the header's properties) and triangles (M x 3) of a PLY
    file as `rondo export` writes it."""
    data = open(path, "rb").read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    props, counts = [], {}
    for line in data[:end].decode().splitlines():
        w = line.split()
        if w[:1] == ["element"]:
            counts[w[1]] = int(w[2])
        elif w[:2] == ["property", "float"]:
            props.append(w[2])
    nv, nf = counts["vertex"], counts["face"]
    verts = np.frombuffer(data, np.float32, nv * len(props), end).reshape(nv, len(props))
    faces = np.frombuffer(data, np.dtype([("n", "u1"), ("i", "<u4", 3)]), nf,
                          end + 4 * nv * len(props))
    return props, verts, faces["i"]


def mesh_object(path, name):
    """A mesh object from an exported PLY: positions, flat or smooth (custom normals when the
    file has them), texture coordinates as the active UV map (rondo's v up is Blender's)."""
    props, verts, tris = read_ply(path)
    me = bpy.data.meshes.new(name)
    me.vertices.add(len(verts))
    me.vertices.foreach_set("co", np.ascontiguousarray(verts[:, :3]).ravel())
    n = len(tris)
    me.loops.add(3 * n)
    me.loops.foreach_set("vertex_index", tris.astype(np.int32).ravel())
    me.polygons.add(n)
    me.polygons.foreach_set("loop_start", np.arange(0, 3 * n, 3, dtype=np.int32))
    me.polygons.foreach_set("loop_total", np.full(n, 3, dtype=np.int32))
    if "u" in props:
        uv = me.uv_layers.new(name="UVMap")
        cols = [props.index("u"), props.index("v")]
        uv.data.foreach_set("uv", verts[:, cols][tris.ravel()].ravel())
    me.update()
    if "nx" in props:
        cols = [props.index("nx"), props.index("ny"), props.index("nz")]
        me.polygons.foreach_set("use_smooth", np.ones(n, dtype=bool))
        me.normals_split_custom_set_from_vertices(verts[:, cols].astype(np.float64))
    else:
        me.polygons.foreach_set("use_smooth", np.zeros(n, dtype=bool))
    return bpy.data.objects.new(name, me)


def node(tree, kind, **inputs):
    n = tree.nodes.new(kind)
    for k, v in inputs.items():
        n.inputs[k].default_value = v
    return n


class Builder:
    def __init__(self, export_dir):
        self.dir = export_dir
        self.j = json.load(open(os.path.join(export_dir, "scene.json")))
        self.materials = {}
        self.notes = set()

    def image_node(self, tree, t, colorspace=None):
        n = tree.nodes.new("ShaderNodeTexImage")
        img = bpy.data.images.load(t["path"], check_existing=True)
        img.colorspace_settings.name = colorspace or (
            "sRGB" if t["encoding"] == "srgb" else "Non-Color")
        n.image = img
        n.interpolation = "Closest" if t["filter"] == "nearest" else "Linear"
        n.extension = {"clamp": "EXTEND", "repeat": "REPEAT",
                       "mirrored_repeat": "MIRROR"}[t["wrap"][0]]
        return n

    def color(self, tree, t):
        """(socket or None, constant RGBA) for a texture."""
        k = t["kind"]
        if k == "constant":
            return None, tuple(t["value"]) + (1.0,)
        if k == "image":
            return self.image_node(tree, t).outputs["Color"], None
        if k == "scaled":
            sock, const = self.color(tree, t["texture"])
            f = t["factor"]
            if sock is None:
                return None, tuple(c * s for c, s in zip(const[:3], f)) + (1.0,)
            mix = tree.nodes.new("ShaderNodeMix")
            mix.data_type = "RGBA"
            mix.blend_type = "MULTIPLY"
            mix.inputs["Factor"].default_value = 1.0
            tree.links.new(sock, mix.inputs[6])
            mix.inputs[7].default_value = tuple(f) + (1.0,)
            return mix.outputs[2], None
        if k == "checker":
            e, o = t["even"], t["odd"]
            if e["kind"] == "constant" and o["kind"] == "constant":
                # even where sin(k u) sin(k v) > 0
                uv = tree.nodes.new("ShaderNodeUVMap")
                sep = tree.nodes.new("ShaderNodeSeparateXYZ")
                tree.links.new(uv.outputs["UV"], sep.inputs[0])
                prods = []
                for axis in ("X", "Y"):
                    m = node(tree, "ShaderNodeMath")
                    m.operation = "MULTIPLY"
                    m.inputs[1].default_value = t["scale"]
                    tree.links.new(sep.outputs[axis], m.inputs[0])
                    s = tree.nodes.new("ShaderNodeMath")
                    s.operation = "SINE"
                    tree.links.new(m.outputs[0], s.inputs[0])
                    prods.append(s)
                p = tree.nodes.new("ShaderNodeMath")
                p.operation = "MULTIPLY"
                tree.links.new(prods[0].outputs[0], p.inputs[0])
                tree.links.new(prods[1].outputs[0], p.inputs[1])
                g = tree.nodes.new("ShaderNodeMath")
                g.operation = "GREATER_THAN"
                g.inputs[1].default_value = 0.0
                tree.links.new(p.outputs[0], g.inputs[0])
                mix = tree.nodes.new("ShaderNodeMix")
                mix.data_type = "RGBA"
                tree.links.new(g.outputs[0], mix.inputs["Factor"])
                mix.inputs[6].default_value = tuple(o["value"]) + (1.0,)
                mix.inputs[7].default_value = tuple(e["value"]) + (1.0,)
                return mix.outputs[2], None
        self.notes.add("texture %s approximated by its mean" % k)
        return None, (0.5, 0.5, 0.5, 1.0)

    def set_input(self, tree, target, t):
        sock, const = self.color(tree, t)
        if sock is None:
            target.default_value = const
        else:
            tree.links.new(sock, target)

    def material(self, key):
        if key in self.materials:
            return self.materials[key]
        m = self.j["materials"][key]
        mat = bpy.data.materials.new(key[-60:])
        mat.use_nodes = True
        tree = mat.node_tree
        tree.nodes.clear()
        out = tree.nodes.new("ShaderNodeOutputMaterial")
        tree.links.new(self.shader(tree, out, m), out.inputs["Surface"])
        self.materials[key] = mat
        return mat

    def shader(self, tree, out, m):
        """The surface shader socket of material m (a glass's absorption linked to out)."""
        k = m["kind"]
        if k == "diffuse":
            b = tree.nodes.new("ShaderNodeBsdfDiffuse")
            self.set_input(tree, b.inputs["Color"], m["albedo"])
            shader = b.outputs[0]
        elif k in ("glossy", "metal"):
            b = tree.nodes.new("ShaderNodeBsdfPrincipled")
            # rondo's Glossy puts back GGX's multiple scattering; its Metal (fuzz) has none.
            b.distribution = "MULTI_GGX" if k == "glossy" else "GGX"
            b.inputs["Metallic"].default_value = 1.0
            r = m["roughness"] if k == "glossy" else m["fuzz"]
            b.inputs["Roughness"].default_value = max(r, 0.01) if k == "glossy" else r
            self.set_input(tree, b.inputs["Base Color"], m["albedo"])
            shader = b.outputs[0]
        elif k == "dielectric":
            b = tree.nodes.new("ShaderNodeBsdfGlass")
            # Energy-conserving rough glass, as rondo's compensated lobe.
            b.distribution = "MULTI_GGX"
            # Cycles squares its roughness into GGX's alpha, as rondo does.
            b.inputs["Roughness"].default_value = m["roughness"]
            b.inputs["IOR"].default_value = m["ior"]
            b.inputs["Color"].default_value = (1, 1, 1, 1)
            shader = b.outputs[0]
            self.absorption(tree, out, m["absorption"])
        elif k == "light":
            e = tree.nodes.new("ShaderNodeEmission")
            self.set_input(tree, e.inputs["Color"], m["emit"])
            e.inputs["Strength"].default_value = m["intensity"]
            shader = e.outputs[0]
            if not m["two_sided"]:
                # rondo's lamps emit on the front side only; the back is black.
                geo = tree.nodes.new("ShaderNodeNewGeometry")
                black = tree.nodes.new("ShaderNodeBsdfDiffuse")
                black.inputs["Color"].default_value = (0, 0, 0, 1)
                mix = tree.nodes.new("ShaderNodeMixShader")
                tree.links.new(geo.outputs["Backfacing"], mix.inputs[0])
                tree.links.new(e.outputs[0], mix.inputs[1])
                tree.links.new(black.outputs[0], mix.inputs[2])
                shader = mix.outputs[0]
        elif k == "pbr":
            shader = self.pbr(tree, m)
        elif k == "transmissive":
            shader = self.transmissive(tree, out, m)
        else:
            raise SystemExit("unknown material kind %r" % k)
        return shader

    def transmissive(self, tree, out, m):
        """rondo's mix weight * glass + (1 - weight) * base as a Mix Shader (its Fac the
        second shader's share); a transmission texture mixes the glass part again, by the
        texture's red channel, with the opaque material it hands the rest to."""
        glass = self.shader(tree, out, m["glass"])
        tt = m.get("transmission_texture")
        if tt is not None:
            inner = tree.nodes.new("ShaderNodeMixShader")
            t = tt["texture"]
            if t["kind"] == "mapped" and t["set"] == 0 and t["transform"] is None:
                t = t["texture"]
            if t["kind"] == "image":
                # The colour space the export found the file read in (rondo reads it linear;
                # the two agree on its texels).
                img = self.image_node(tree, t)
                sep = tree.nodes.new("ShaderNodeSeparateColor")
                tree.links.new(img.outputs["Color"], sep.inputs[0])
                tree.links.new(sep.outputs["Red"], inner.inputs["Fac"])
            else:
                sock, const = self.color(tree, t)
                if sock is None:
                    inner.inputs["Fac"].default_value = const[0]
                else:
                    sep = tree.nodes.new("ShaderNodeSeparateColor")
                    tree.links.new(sock, sep.inputs[0])
                    tree.links.new(sep.outputs["Red"], inner.inputs["Fac"])
            tree.links.new(self.shader(tree, out, tt["opaque"]), inner.inputs[1])
            tree.links.new(glass, inner.inputs[2])
            glass = inner.outputs[0]
        e = m["base"].get("emissive")
        if e is not None and not (e["kind"] == "constant" and max(e["value"]) == 0):
            self.notes.add("transmissive emission mixed by the weights (rondo's is in full)")
        mix = tree.nodes.new("ShaderNodeMixShader")
        mix.inputs["Fac"].default_value = m["weight"]
        tree.links.new(self.shader(tree, out, m["base"]), mix.inputs[1])
        tree.links.new(glass, mix.inputs[2])
        return mix.outputs[0]

    def absorption(self, tree, out, absorption):
        """Beer–Lambert absorption inside glass: a Volume Absorption node, whose coefficient
        is density × (1 − colour) per channel."""
        # rondo writes an opaque (infinite) channel as null.
        sigma = [1e6 if a is None else a for a in absorption]
        density = max(sigma)
        if density <= 0:
            return
        v = tree.nodes.new("ShaderNodeVolumeAbsorption")
        v.inputs["Color"].default_value = tuple(1 - a / density for a in sigma) + (1,)
        v.inputs["Density"].default_value = density
        tree.links.new(v.outputs[0], out.inputs["Volume"])

    def pbr(self, tree, m):
        b = tree.nodes.new("ShaderNodeBsdfPrincipled")
        # Cycles' default, energy-conserving like rondo's Pbr.
        b.distribution = "MULTI_GGX"
        b.inputs["IOR"].default_value = 1.5
        self.set_input(tree, b.inputs["Base Color"], m["base_color"])
        b.inputs["Metallic"].default_value = m["metallic"]
        b.inputs["Roughness"].default_value = max(m["roughness"], 0.01)
        mr = m["metallic_roughness"]
        if mr is not None and mr["kind"] == "image":
            img = self.image_node(tree, mr, "Non-Color")
            sep = tree.nodes.new("ShaderNodeSeparateColor")
            tree.links.new(img.outputs["Color"], sep.inputs[0])
            for channel, name, factor in (("Green", "Roughness", m["roughness"]),
                                          ("Blue", "Metallic", m["metallic"])):
                mul = tree.nodes.new("ShaderNodeMath")
                mul.operation = "MULTIPLY"
                mul.inputs[1].default_value = factor
                tree.links.new(sep.outputs[channel], mul.inputs[0])
                tree.links.new(mul.outputs[0], b.inputs[name])
        nm = m["normal_map"]
        if nm is not None:
            img = self.image_node(tree, nm["texture"], "Non-Color")
            n = tree.nodes.new("ShaderNodeNormalMap")
            n.space = "TANGENT"
            n.inputs["Strength"].default_value = nm["scale"]
            tree.links.new(img.outputs["Color"], n.inputs["Color"])
            tree.links.new(n.outputs["Normal"], b.inputs["Normal"])
        e = m["emissive"]
        if not (e["kind"] == "constant" and max(e["value"]) == 0):
            self.set_input(tree, b.inputs["Emission Color"], e)
            b.inputs["Emission Strength"].default_value = m["emissive_strength"]
        am = m["alpha_mask"]
        if am is not None and am["image"] is not None:
            img = self.image_node(tree, am["image"])
            mul = tree.nodes.new("ShaderNodeMath")
            mul.operation = "MULTIPLY"
            mul.inputs[1].default_value = am["factor"]
            tree.links.new(img.outputs["Alpha"], mul.inputs[0])
            ge = tree.nodes.new("ShaderNodeMath")
            ge.operation = "GREATER_THAN"
            # alpha >= cutoff, as a strict comparison just below the cutoff
            ge.inputs[1].default_value = am["cutoff"] - 1e-6
            tree.links.new(mul.outputs[0], ge.inputs[0])
            tree.links.new(ge.outputs[0], b.inputs["Alpha"])
        return b.outputs[0]

    def build(self, size, max_depth=None):
        bpy.ops.wm.read_factory_settings(use_empty=True)
        j = self.j
        scene = bpy.context.scene
        scene.render.engine = "CYCLES"
        c = scene.cycles
        c.device = "CPU"
        c.use_denoising = False
        c.use_adaptive_sampling = False
        depth = (max_depth or j["settings"]["max_depth"]) - 1
        c.max_bounces = depth
        for name in ("diffuse_bounces", "glossy_bounces", "transmission_bounces",
                     "volume_bounces", "transparent_max_bounces"):
            setattr(c, name, depth)
        c.sample_clamp_direct = 0.0
        c.sample_clamp_indirect = 0.0
        c.blur_glossy = 0.0
        c.caustics_reflective = True
        c.caustics_refractive = True
        c.pixel_filter_type = "BOX"
        c.filter_width = 1.0
        scene.render.resolution_x, scene.render.resolution_y = size
        scene.render.resolution_percentage = 100
        scene.view_settings.view_transform = "Standard"
        scene.render.image_settings.file_format = "OPEN_EXR"
        scene.render.image_settings.color_depth = "32"
        scene.render.threads_mode = "AUTO"
        # Camera, in rondo's own (y-up) coordinates: the scene is not turned to z-up.
        cam = j["camera"]
        cd = bpy.data.cameras.new("camera")
        cd.sensor_fit = "VERTICAL"
        cd.angle_y = math.radians(cam["fov_y_degrees"])
        cd.clip_start = 1e-3
        cd.clip_end = 1e7
        co = bpy.data.objects.new("camera", cd)
        scene.collection.objects.link(co)
        fwd = Vector(cam["direction"]).normalized()
        right = fwd.cross(Vector(cam["up"])).normalized()
        up = right.cross(fwd)
        m = Matrix.Identity(4)
        for r in range(3):
            m[r][0], m[r][1], m[r][2], m[r][3] = right[r], up[r], -fwd[r], cam["position"][r]
        co.matrix_world = m
        if cam["aperture_radius"] > 0:
            cd.dof.use_dof = True
            cd.dof.focus_distance = cam["focus_distance"]
            # Cycles' lens radius is (focal length / f-stop) / 2, the focal length in metres.
            cd.dof.aperture_fstop = 0.5 * cd.lens * 1e-3 / cam["aperture_radius"]
        scene.camera = co
        self.world(scene)
        for i, sp in enumerate(j["spheres"]):
            bpy.ops.mesh.primitive_uv_sphere_add(segments=128, ring_count=64,
                                                 radius=sp["radius"], location=sp["center"])
            o = bpy.context.active_object
            o.data.materials.append(self.material(sp["material"]))
            bpy.ops.object.shade_smooth()
        self.notes.add("spheres as 128x64 UV spheres, smooth-shaded")
        for mesh in j["meshes"]:
            o = mesh_object(os.path.join(self.dir, mesh["file"]), mesh["file"])
            scene.collection.objects.link(o)
            o.data.materials.append(self.material(mesh["material"]))
        return scene

    def world(self, scene):
        j = self.j
        w = bpy.data.worlds.new("world")
        scene.world = w
        w.use_nodes = True
        tree = w.node_tree
        tree.nodes.clear()
        out = tree.nodes.new("ShaderNodeOutputWorld")
        bg = tree.nodes.new("ShaderNodeBackground")
        tree.links.new(bg.outputs[0], out.inputs[0])
        if j["environment"] is not None:
            env = j["environment"]
            tex = tree.nodes.new("ShaderNodeTexEnvironment")
            tex.image = bpy.data.images.load(env["path"])
            tex.interpolation = "Closest"
            coord = tree.nodes.new("ShaderNodeTexCoord")
            mapping = tree.nodes.new("ShaderNodeMapping")
            mapping.vector_type = "VECTOR"
            # Blender reads u = 1/2 - atan2(y, x) / 2pi, v = 1/2 - acos(z) / pi (z up); rondo
            # u = atan2(x, -z) / 2pi, v = acos(y) / pi: the direction (z, x, y) of rondo's map
            # space reads the same texel.
            r = Matrix(((0, 0, 1), (1, 0, 0), (0, 1, 0)))
            world_from_map = Matrix(env["world_from_map"])
            mapping.inputs["Rotation"].default_value = (r @ world_from_map.inverted()).to_euler("XYZ")
            tree.links.new(coord.outputs["Generated"], mapping.inputs["Vector"])
            tree.links.new(mapping.outputs[0], tex.inputs["Vector"])
            tree.links.new(tex.outputs["Color"], bg.inputs["Color"])
            bg.inputs["Strength"].default_value = env["strength"]
        else:
            b = j["background"] or [0, 0, 0]
            bg.inputs["Color"].default_value = tuple(b) + (1.0,)
            bg.inputs["Strength"].default_value = 1.0
        if j["sun"] is not None:
            s = j["sun"]
            half = math.radians(s["angular_diameter_degrees"]) / 2
            irradiance = [x * math.pi * math.sin(half) ** 2 for x in s["radiance"]]
            strength = max(irradiance)
            ld = bpy.data.lights.new("sun", "SUN")
            ld.angle = 2 * half
            ld.energy = strength
            ld.color = [x / strength for x in irradiance]
            lo = bpy.data.objects.new("sun", ld)
            scene.collection.objects.link(lo)
            d = Vector(s["direction"]).normalized()
            lo.rotation_euler = d.to_track_quat("Z", "Y").to_euler()


def exr_render_seconds(path):
    """Cycles' own render time, from the metadata it stamps into the EXR header
    (`cycles.<view layer>.render_time`, "[HH:]MM:SS.cc", 10 ms resolution): path tracing and
    denoising, without the scene's synchronisation (`synchronization_time`)."""
    with open(path, "rb") as f:
        data = f.read(1 << 16)
    if data[:4] != b"\x76\x2f\x31\x01":
        raise SystemExit("%s: not an OpenEXR file" % path)
    i, found = 8, None
    while i < len(data) and data[i] != 0:
        n = data.index(b"\0", i)
        name = data[i:n].decode(errors="replace")
        n2 = data.index(b"\0", n + 1)
        size = int.from_bytes(data[n2 + 1:n2 + 5], "little")
        value = data[n2 + 5:n2 + 5 + size]
        i = n2 + 5 + size
        if name.startswith("cycles.") and name.endswith(".render_time"):
            found = value.decode()
    if found is None:
        raise SystemExit("%s: no cycles.*.render_time in the header" % path)
    seconds = 0.0
    for part in found.split(":"):
        seconds = 60 * seconds + float(part)
    # Rounded to 10 ms: a render read as 0.00 s took under 5 ms.
    return max(seconds, 0.005)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("export")
    ap.add_argument("out")
    ap.add_argument("--size", nargs=2, type=int, required=True)
    ap.add_argument("--targets", default="", help="seconds to match (equal time)")
    ap.add_argument("--denoise-targets", default="",
                    help="seconds to match with the OIDN denoiser on (render + denoise)")
    ap.add_argument("--spp-list", default="", help="fixed spp renders")
    ap.add_argument("--threads", type=int, default=0)
    ap.add_argument("--guiding", action="store_true",
                    help="path guiding on (Open PGL; surface guiding, Cycles' defaults)")
    args = ap.parse_args()
    b = Builder(args.export)
    scene = b.build(tuple(args.size))
    if args.threads:
        scene.render.threads_mode = "FIXED"
        scene.render.threads = args.threads
    # The synchronised scene (BVH, images, the environment's importance map) is kept between
    # renders: only the first one pays for it.
    scene.render.use_persistent_data = True
    c = scene.cycles
    c.denoiser = "OPENIMAGEDENOISE"
    c.denoising_use_gpu = False
    c.denoising_input_passes = "RGB_ALBEDO_NORMAL"
    c.denoising_prefilter = "ACCURATE"
    c.denoising_quality = "HIGH"
    if args.guiding:
        c.use_guiding = True
        c.use_surface_guiding = True
    print(json.dumps({"notes": sorted(b.notes)}), flush=True)
    os.makedirs(args.out, exist_ok=True)

    def render(spp, seed, name, denoise=False):
        c.samples = spp
        c.seed = seed
        c.use_denoising = denoise
        scene.render.filepath = os.path.join(args.out, name)
        t = time.perf_counter()
        bpy.ops.render.render(write_still=True)
        wall = time.perf_counter() - t
        return exr_render_seconds(scene.render.filepath), wall, scene.render.filepath

    def equal_time(targets, denoise, seed, prefix):
        t4, _, _ = render(4, 1, "probe.exr", denoise)
        rate = max(t4, 0.01) / 4
        for k, target in enumerate(float(x) for x in targets.split(",") if x):
            spp = max(1, round(target / rate))
            for _attempt in range(3):
                t, wall, f = render(spp, seed + k, "%s%d.exr" % (prefix, k), denoise)
                if abs(t - target) <= 0.15 * target:
                    break
                spp = max(1, round(spp * target / max(t, 0.01)))
            print(json.dumps({"spp": spp, "seconds": t, "wall": wall, "file": f,
                              "target": target, "denoised": denoise}), flush=True)

    # Untimed: the first render synchronises the scene; the first denoised one loads OIDN.
    render(1, 0, "warmup.exr")
    for s in [int(x) for x in args.spp_list.split(",") if x]:
        t, wall, f = render(s, 100 + s, "cycles_n%d.exr" % s)
        print(json.dumps({"spp": s, "seconds": t, "wall": wall, "file": f}), flush=True)
    equal_time(args.targets, False, 200, "cycles_t")
    if args.denoise_targets:
        render(1, 0, "warmup.exr", True)
        equal_time(args.denoise_targets, True, 300, "cycles_denoised_t")


if __name__ == "__main__":
    main()
