"""scene.json (from `rondo export`) as a Mitsuba 3 scene dictionary. The mapping of each
material and light, and what it leaves different, is in README.md beside this file.
Never used by the tests."""

import json
import math
import os

import numpy as np

from textures import checker_image, load_rgba


def _rgb(v):
    return {"type": "rgb", "value": [float(x) for x in v]}


class Converter:
    def __init__(self, mi, export_dir, cache_dir):
        self.mi = mi
        self.dir = export_dir
        self.cache = cache_dir
        self.json = json.load(open(os.path.join(export_dir, "scene.json")))
        self.notes = set()
        self.volumetric = False

    def T(self):
        return self.mi.ScalarTransform4f()

    # Textures -----------------------------------------------------------------------------
    def bitmap(self, t, raw=None):
        wrap = {"clamp": "clamp", "repeat": "repeat", "mirrored_repeat": "mirror"}[t["wrap"][0]]
        if t["wrap"][0] != t["wrap"][1]:
            self.notes.add("wrap modes differing between u and v: u's used")
        # rondo's v points up the image (v = 0 its bottom row); Mitsuba's bitmap reads row 0 at
        # v = 0, and its PLY reader keeps the file's v: so v is flipped here.
        return {
            "type": "bitmap", "filename": t["path"],
            "raw": (t["encoding"] == "linear") if raw is None else raw,
            "filter_type": "nearest" if t["filter"] == "nearest" else "bilinear",
            "wrap_mode": wrap,
            "to_uv": self.T().translate([0, 1, 0]).scale([1, -1, 1]),
        }

    def texture(self, t):
        """A colour texture: rgb, bitmap, or a bitmap made for a checker."""
        k = t["kind"]
        if k == "constant":
            return _rgb(t["value"])
        if k == "image":
            return self.bitmap(t)
        if k == "scaled":
            inner = t["texture"]
            if inner["kind"] == "constant":
                return _rgb(np.multiply(inner["value"], t["factor"]))
            if np.allclose(t["factor"], 1.0):
                return self.texture(inner)
            # A bitmap times a factor: baked into a float image.
            if inner["kind"] == "image":
                rgba = load_rgba(inner["path"], inner["encoding"])
                rgb = rgba[..., :3] * np.asarray(t["factor"], dtype=np.float32)
                return self.array_bitmap(rgb, inner)
        if k == "checker":
            even, odd = t["even"], t["odd"]
            if even["kind"] == "constant" and odd["kind"] == "constant":
                img = checker_image(even["value"], odd["value"])
                # even where sin(k u) sin(k v) > 0: a 2x2 tile of period 2 pi / k, nearest.
                s = t["scale"] / (2 * math.pi)
                return {"type": "bitmap", "data": self.mi.TensorXf(img), "raw": True, "filter_type": "nearest",
                        "wrap_mode": "repeat", "to_uv": self.T().scale([s, s, 1])}
        self.notes.add("texture %s approximated by its mean colour" % k)
        return _rgb(self.mean(t))

    def mean(self, t):
        k = t["kind"]
        if k == "constant":
            return np.asarray(t["value"])
        if k == "checker":
            return 0.5 * (self.mean(t["even"]) + self.mean(t["odd"]))
        if k == "scaled":
            return self.mean(t["texture"]) * np.asarray(t["factor"])
        if k == "mapped":
            return self.mean(t["texture"])
        return load_rgba(t["path"], t["encoding"])[..., :3].reshape(-1, 3).mean(axis=0)

    def array_bitmap(self, arr, like):
        filt = "nearest" if like.get("filter", "nearest") == "nearest" else "bilinear"
        wrap = {"clamp": "clamp", "repeat": "repeat", "mirrored_repeat": "mirror"}[
            like.get("wrap", ["clamp"])[0]]
        # Arrays are stored top row first, as files are: the same v flip.
        return {"type": "bitmap",
                "data": self.mi.TensorXf(np.ascontiguousarray(arr, dtype=np.float32)),
                "raw": True, "filter_type": filt, "wrap_mode": wrap,
                "to_uv": self.T().translate([0, 1, 0]).scale([1, -1, 1])}

    # Materials ----------------------------------------------------------------------------
    def bsdf(self, key):
        return self.material_bsdf(self.json["materials"][key])

    def material_bsdf(self, m):
        k = m["kind"]
        if k == "diffuse":
            return {"type": "twosided", "bsdf": {"type": "diffuse",
                                                 "reflectance": self.texture(m["albedo"])}}
        if k == "metal":
            if m["fuzz"] == 0:
                inner = {"type": "conductor", "material": "none",
                         "specular_reflectance": self.texture(m["albedo"])}
            else:
                self.notes.add("Metal fuzz approximated by GGX alpha = fuzz")
                inner = {"type": "roughconductor", "material": "none", "distribution": "ggx",
                         "alpha": max(m["fuzz"], 1e-3),
                         "specular_reflectance": self.texture(m["albedo"])}
            return {"type": "twosided", "bsdf": inner}
        if k == "glossy":
            self.notes.add("Glossy: single-scattering GGX (rondo's puts multiple scattering back)")
            # Schlick's Fresnel with F0 = albedo: the principled BSDF's metallic lobe.
            return {"type": "twosided", "bsdf": {
                "type": "principled", "base_color": self.texture(m["albedo"]),
                "metallic": 1.0, "roughness": max(m["roughness"], 0.01)}}
        if k == "dielectric":
            if m["alpha"] > 0:
                self.notes.add("rough glass: single-scattering GGX (rondo's is compensated)")
                return {"type": "roughdielectric", "distribution": "ggx",
                        "alpha": max(m["alpha"], 1e-3), "int_ior": m["ior"], "ext_ior": 1.0}
            return {"type": "dielectric", "int_ior": m["ior"], "ext_ior": 1.0}
        if k == "light":
            return {"type": "diffuse", "reflectance": _rgb((0, 0, 0))}
        if k == "pbr":
            return self.pbr(m)
        if k == "transmissive":
            return self.transmissive(m)
        raise SystemExit("unknown material kind %r" % k)

    def transmissive(self, m):
        """rondo's mix weight * glass + (1 - weight) * base as blendbsdf (its weight the
        probability of bsdf_1); a transmission texture mixes the glass part again, by the
        texture's red channel, with the opaque material it hands the rest to."""
        glass = self.material_bsdf(m["glass"])
        tt = m.get("transmission_texture")
        if tt is not None:
            glass = {"type": "blendbsdf", "weight": self.red(tt["texture"]),
                     "bsdf_0": self.material_bsdf(tt["opaque"]), "bsdf_1": glass}
        return {"type": "blendbsdf", "weight": float(m["weight"]),
                "bsdf_0": self.material_bsdf(m["base"]), "bsdf_1": glass}

    def red(self, t):
        """The red channel of colour texture t as a float texture (a blend weight)."""
        k = t["kind"]
        if k == "mapped" and t["set"] == 0 and t["transform"] is None:
            return self.red(t["texture"])
        if k == "constant":
            return float(t["value"][0])
        if k == "image":
            return self.array_bitmap(load_rgba(t["path"], t["encoding"])[..., 0:1], t)
        self.notes.add("transmission texture %s approximated by its mean red" % k)
        return float(self.mean(t)[0])

    def pbr(self, m):
        p = {"type": "principled", "base_color": self.texture(m["base_color"]),
             "metallic": m["metallic"], "roughness": max(m["roughness"], 0.01),
             "specular": 0.5}
        mr = m["metallic_roughness"]
        if mr is not None:
            img = mr if mr["kind"] == "image" else mr.get("texture")
            if img is None or img["kind"] != "image":
                self.notes.add("metallic-roughness texture not an image: factors only")
            else:
                arr = load_rgba(img["path"], "linear")
                p["roughness"] = self.array_bitmap(
                    np.maximum(arr[..., 1:2] * m["roughness"], 0.01), img)
                p["metallic"] = self.array_bitmap(arr[..., 2:3] * m["metallic"], img)
        bsdf = {"type": "twosided", "bsdf": p}
        nm = m["normal_map"]
        if nm is not None:
            t = nm["texture"]
            arr = load_rgba(t["path"], "linear")[..., :3]
            if nm["scale"] != 1.0:
                n = 2 * arr - 1
                n[..., :2] *= nm["scale"]
                n /= np.linalg.norm(n, axis=-1, keepdims=True) + 1e-12
                arr = 0.5 * (n + 1)
            bsdf = {"type": "normalmap", "normalmap": self.array_bitmap(arr, t), "bsdf": bsdf}
        am = m["alpha_mask"]
        if am is not None:
            if am["image"] is None:
                opacity = _rgb([1.0 if am["factor"] >= am["cutoff"] else 0.0] * 3)
            else:
                t = am["image"]
                alpha = load_rgba(t["path"], "linear")[..., 3:4]
                present = (am["factor"] * alpha >= am["cutoff"]).astype(np.float32)
                opacity = self.array_bitmap(np.repeat(present, 3, axis=-1), t)
            bsdf = {"type": "mask", "opacity": opacity, "bsdf": bsdf}
        return bsdf

    def emitter(self, key):
        """The area emitter of a material, if it emits, and whether it emits on both sides."""
        m = self.json["materials"][key]
        if m["kind"] == "transmissive":
            # A mix emits as its base, whichever part shades.
            m = m["base"]
        if m["kind"] == "light":
            return self.scaled_emission(m["emit"], m["intensity"]), m["two_sided"]
        if m["kind"] == "pbr":
            e = m["emissive"]
            if e["kind"] == "constant" and max(e["value"]) == 0:
                return None, False
            self.notes.add("Pbr emission (two-sided in rondo)")
            return self.scaled_emission(e, m["emissive_strength"]), True
        return None, False

    def scaled_emission(self, t, s):
        if t["kind"] == "constant":
            return {"type": "area", "radiance": _rgb(np.asarray(t["value"]) * s)}
        return {"type": "area", "radiance": self.texture(
            {"kind": "scaled", "factor": [s] * 3, "texture": t})}

    def interior(self, key):
        """The absorbing medium inside a dielectric with Beer–Lambert absorption, if any."""
        m = self.json["materials"][key]
        if m["kind"] == "transmissive":
            # Only paths that refract through the glass part get inside.
            m = m["glass"]
        if m["kind"] != "dielectric":
            return None
        # σa per unit length and channel; rondo writes an opaque (infinite) channel as null.
        sigma = [1e6 if a is None else a for a in m["absorption"]]
        if max(sigma) <= 0:
            return None
        self.volumetric = True
        self.notes.add("absorbing glass as a purely absorbing homogeneous interior (volpath)")
        # Mitsuba reads an RGB σt as a reflectance (each channel in [0, 1]) times `scale`.
        scale = max(sigma)
        return {"type": "homogeneous", "albedo": _rgb((0, 0, 0)),
                "sigma_t": _rgb([a / scale for a in sigma]), "scale": scale}

    # Scene --------------------------------------------------------------------------------
    def scene(self, sampler, size=None, max_depth=None):
        j, mi = self.json, self.mi
        cam = j["camera"]
        w, h = size or (cam["width"], cam["height"])
        to_world = self.T().look_at(origin=cam["position"],
                                    target=list(np.add(cam["position"], cam["direction"])),
                                    up=cam["up"])
        sensor = {
            "type": "thinlens" if cam["aperture_radius"] > 0 else "perspective",
            "fov": cam["fov_y_degrees"], "fov_axis": "y", "to_world": to_world,
            "sampler": {"type": sampler, "sample_count": 1},
            "film": {"type": "hdrfilm", "width": w, "height": h,
                     "rfilter": {"type": "box"}, "pixel_format": "rgb"},
        }
        if cam["aperture_radius"] > 0:
            sensor["aperture_radius"] = cam["aperture_radius"]
            sensor["focus_distance"] = cam["focus_distance"]
        d = {"type": "scene",
             "integrator": {"type": "path",
                            "max_depth": max_depth or j["settings"]["max_depth"]},
             "sensor": sensor}
        if j["environment"] is not None:
            env = j["environment"]
            m = np.eye(4)
            m[:3, :3] = np.asarray(env["world_from_map"])
            d["environment"] = {"type": "envmap", "filename": env["path"],
                                "scale": env["strength"],
                                "to_world": mi.ScalarTransform4f(m.tolist())}
        elif j["background"] is not None and max(j["background"]) > 0:
            d["background"] = {"type": "constant", "radiance": _rgb(j["background"])}
        if j["sun"] is not None:
            s = j["sun"]
            half = math.radians(s["angular_diameter_degrees"]) / 2
            # A delta light of the disk's irradiance on a plane facing it.
            irradiance = np.asarray(s["radiance"]) * math.pi * math.sin(half) ** 2
            d["sun"] = {"type": "directional", "direction": [-x for x in s["direction"]],
                        "irradiance": _rgb(irradiance)}
            self.notes.add("sun as a directional (delta) light of equal irradiance")
        for i, sp in enumerate(j["spheres"]):
            e, two = self.emitter(sp["material"])
            shape = {"type": "sphere", "center": sp["center"], "radius": sp["radius"],
                     "bsdf": self.bsdf(sp["material"])}
            if e is not None:
                shape["emitter"] = e
            medium = self.interior(sp["material"])
            if medium is not None:
                shape["interior"] = medium
            d["sphere%d" % i] = shape
        for i, mesh in enumerate(j["meshes"]):
            e, two = self.emitter(mesh["material"])
            shape = {"type": "ply", "filename": os.path.join(self.dir, mesh["file"]),
                     "face_normals": not mesh["normals"], "bsdf": self.bsdf(mesh["material"])}
            if e is not None:
                shape["emitter"] = e
            medium = self.interior(mesh["material"])
            if medium is not None:
                shape["interior"] = medium
            d["mesh%d" % i] = shape
            if e is not None and two:
                back = dict(shape, flip_normals=True, emitter=dict(e))
                d["mesh%d_back" % i] = back
        if self.volumetric:
            # Only the volumetric path tracer attenuates along rays inside a medium.
            d["integrator"]["type"] = "volpath"
        return d


def load(mi, export_dir, sampler, cache_dir, size=None):
    c = Converter(mi, export_dir, cache_dir)
    d = c.scene(sampler, size)
    return mi.load_dict(d), sorted(c.notes)
