#!/usr/bin/env python3
"""Side-by-side watch-mode latencies of two rondo binaries (issue 24's table).

Drives `rondo watch SCENE -o out.png` of each binary, alternating them round by round, and reads
its log lines: `loaded: … parse X, … BVH X, … first image X since start` for a cold start and
`reload N: … parse X, … BVH X, … first image X since save` after each edit. Works with any
binary that prints those lines (no bench flags needed), so a build from before a change can be
compared with the current one.

Scenes (generated into a private temporary directory, removed at the end):
  mesh   4 entities (floor, wall, lamp, small sphere) + a 1M-triangle OBJ (~77 MB, normals):
         edits: the wall's material colour, move the small sphere, move the mesh;
         its cold start gives the BVH of the 1M-triangle mesh;
  tiny   the same without the mesh (the reference for "untouched assets cost nothing");
  flat   10^5 named spheres (~10 MB of RON): one entity's material.
Every edit is a plain in-place write (open, truncate, write, close), alternating the edited text
and the original, each after the previous render finished.

Usage: python3 scripts/watch-compare.py BEFORE AFTER [--rounds 3] [--edits 5] [--triangles N]
                                        [--entities N] [--only mesh,tiny,flat]
Prints a Markdown table (median and minimum over every round) and the raw figures as JSON.
"""

import argparse
import json
import math
import os
import queue
import re
import shutil
import signal
import statistics
import subprocess
import sys
import tempfile
import threading
import time

WAIT = 300.0  # seconds: longest wait for a log line
GAP = 0.3  # seconds between a render's last line and the next save
SETTINGS = "settings: Settings(width: 64, height: 64, spp: 4, max_depth: 4)"


def write_obj(path, triangles):
    """An OBJ height field of at least `triangles` triangles with vertex normals."""
    side = math.isqrt(max(1, (triangles + 1) // 2) - 1) + 2
    step = 2.0 / (side - 1)
    with open(path, "w") as f:
        for j in range(side):
            z = j * step
            f.write("".join(
                f"v {i * step:.6f} {0.1 * math.sin(3 * i * step) * math.cos(2 * z):.6f} {z:.6f}\n"
                for i in range(side)))
        for j in range(side):
            z = j * step
            lines = []
            for i in range(side):
                x = i * step
                dx = 0.3 * math.cos(3 * x) * math.cos(2 * z)
                dz = -0.2 * math.sin(3 * x) * math.sin(2 * z)
                n = math.sqrt(dx * dx + 1 + dz * dz)
                lines.append(f"vn {-dx / n:.6f} {1 / n:.6f} {-dz / n:.6f}\n")
            f.write("".join(lines))
        for j in range(side - 1):
            lines = []
            for i in range(side - 1):
                a = j * side + i + 1
                b, c, d = a + 1, a + side + 1, a + side
                lines.append(f"f {a}//{a} {b}//{b} {c}//{c}\nf {a}//{a} {c}//{c} {d}//{d}\n")
            f.write("".join(lines))
    return 2 * (side - 1) ** 2


def small_scene(with_mesh):
    mesh = ('        Entity(name: "big", material: "white", shape: Mesh(path: "big.obj"),\n'
            '               transform: Transform(translate: (0, 0, 1))),\n') if with_mesh else ""
    return f"""Scene(
    camera: Camera(position: (1, 2, -4), look_at: (1, 0, 1), fov: 50),
    {SETTINGS},
    materials: {{
        "white": Diffuse(albedo: Constant((0.7, 0.7, 0.7))),
        "wall": Diffuse(albedo: Constant((0.65, 0.05, 0.05))),
        "lamp": Light(emit: Constant((1, 1, 1)), intensity: 6),
    }},
    entities: [
        Entity(name: "floor", material: "white", shape: Quad(a: (-3, 0, -3), b: (-3, 0, 5), c: (5, 0, 5), d: (5, 0, -3))),
        Entity(name: "back", material: "wall", shape: Quad(a: (-3, 0, 4), b: (-3, 4, 4), c: (5, 4, 4), d: (5, 0, 4))),
        Entity(name: "light", material: "lamp", shape: Quad(a: (0, 3.9, 0), b: (2, 3.9, 0), c: (2, 3.9, 2), d: (0, 3.9, 2))),
        Entity(name: "ball", material: "white", shape: Sphere(center: (0, 0.3, 0), radius: 0.3)),
{mesh}    ],
)
"""


def flat_scene(n):
    side = max(1, math.ceil(math.sqrt(n)))
    c = 0.5 * side
    lines = []
    for k in range(n):
        material = "glaze" if k == 0 else "clay"
        lines.append(f'        Entity(name: "e{k}", material: "{material}", shape: Sphere(center: '
                     f'({k % side}, 0.4, {k // side}), radius: 0.4)),\n')
    return (f"Scene(\n    camera: Camera(position: ({c}, {side + 5}, {-side - 5}), look_at: ({c}, 0, {c}), fov: 50),\n"
            f"    {SETTINGS},\n"
            '    materials: {\n        "clay": Diffuse(albedo: Constant((0.7, 0.6, 0.5))),\n'
            '        "glaze": Diffuse(albedo: Constant((0.2, 0.3, 0.6))),\n    },\n'
            f"    entities: [\n{''.join(lines)}    ],\n)\n")


def replace_once(text, old, new):
    if text.count(old) != 1:
        sys.exit(f"internal error: {old!r} occurs {text.count(old)} times")
    return text.replace(old, new)


def scenarios(entities):
    """(name, file, text, [(edit, edited text)])."""
    mesh = small_scene(True)
    tiny = small_scene(False)
    edits = lambda text: [  # noqa: E731
        ("material colour", replace_once(text, "(0.65, 0.05, 0.05)", "(0.05, 0.05, 0.65)")),
        ("move small sphere", replace_once(text, "center: (0, 0.3, 0)", "center: (0.2, 0.3, 0)")),
    ]
    flat = flat_scene(entities)
    middle = f'name: "e{entities // 2}", material: "clay"'
    return [
        ("mesh", "mesh.ron", mesh, edits(mesh) + [
            ("move mesh", replace_once(mesh, "translate: (0, 0, 1)", "translate: (0.1, 0, 1)"))]),
        ("tiny", "tiny.ron", tiny, edits(tiny)),
        ("flat", "flat.ron", flat, [
            ("one entity's material", replace_once(flat, middle, middle.replace('"clay"', '"glaze"')))]),
    ]


def seconds(value, unit):
    return float(value) * (1.0 if unit == "s" else 1e-3)


FIELDS = {
    "parse": re.compile(r"parse ([\d.]+) (ms|s)\b"),
    # `BVH refit X` (a moved entity's refit, after issue 24) counts as the BVH's time too.
    "bvh": re.compile(r"BVH (?:refit )?([\d.]+) (ms|s)\b"),
    "first_image": re.compile(r"first image ([\d.]+) (ms|s) since (?:save|start)"),
}


def figures(line):
    out = {}
    for name, pattern in FIELDS.items():
        m = pattern.search(line)
        if m:
            out[name] = seconds(m.group(1), m.group(2))
    return out


class Watch:
    """A running `rondo watch` and its stderr lines."""

    def __init__(self, binary, scene, out):
        self.proc = subprocess.Popen([binary, "watch", scene, "-o", out], stdin=subprocess.DEVNULL,
                                     stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        self.lines = queue.Queue()
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self):
        for line in self.proc.stderr:
            self.lines.put(line.rstrip("\n"))
        self.lines.put(None)

    def wait_line(self, prefix):
        deadline = time.monotonic() + WAIT
        while True:
            try:
                line = self.lines.get(timeout=max(0.0, deadline - time.monotonic()))
            except queue.Empty:
                raise RuntimeError(f"no line starting {prefix!r} within {WAIT} s")
            if line is None:
                raise RuntimeError("rondo exited")
            if line.startswith("error") or " failed" in line:
                raise RuntimeError(line)
            if line.startswith(prefix):
                return line

    def stop(self):
        self.proc.send_signal(signal.SIGINT)
        try:
            self.proc.wait(timeout=60)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()


def save(path, text):
    """A plain in-place write: open (truncating), write, close."""
    with open(path, "w") as f:
        f.write(text)


def run_scenario(binary, directory, scenario, n_edits, results, label):
    name, file, text, edits = scenario
    path = os.path.join(directory, file)
    save(path, text)
    watch = Watch(binary, path, os.path.join(directory, "out.png"))
    try:
        line = watch.wait_line("loaded:")
        results.setdefault((name, "cold start"), {}).setdefault(label, []).append(figures(line))
        print(f"{label} {name} cold: {line}", file=sys.stderr)
        reload = 0
        for edit, edited in edits:
            for k in range(n_edits):
                time.sleep(GAP)
                save(path, edited if k % 2 == 0 else text)
                reload += 1
                line = watch.wait_line(f"reload {reload}:")
                results.setdefault((name, edit), {}).setdefault(label, []).append(figures(line))
                print(f"{label} {name} {edit}: {line}", file=sys.stderr)
            if n_edits % 2 == 1:
                time.sleep(GAP)
                save(path, text)
                reload += 1
                watch.wait_line(f"reload {reload}:")
    finally:
        watch.stop()


def ms(values):
    if not values:
        return "–"
    median, low = statistics.median(values) * 1e3, min(values) * 1e3
    digits = 2 if median < 10 else 1
    return f"{median:.{digits}f} ({low:.{digits}f})"


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("before")
    p.add_argument("after")
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--edits", type=int, default=5)
    p.add_argument("--triangles", type=int, default=1_000_000)
    p.add_argument("--entities", type=int, default=100_000)
    p.add_argument("--only", default="mesh,tiny,flat")
    a = p.parse_args()
    binaries = [("before", a.before), ("after", a.after)]
    for _, b in binaries:
        if not os.access(b, os.X_OK):
            sys.exit(f"{b}: not an executable")
    only = set(a.only.split(","))
    directory = tempfile.mkdtemp(prefix="rondo-watch-compare-")
    try:
        triangles = write_obj(os.path.join(directory, "big.obj"), a.triangles)
        size = os.path.getsize(os.path.join(directory, "big.obj"))
        print(f"big.obj: {triangles} triangles, {size / 1e6:.1f} MB", file=sys.stderr)
        chosen = [s for s in scenarios(a.entities) if s[0] in only]
        results = {}
        for r in range(a.rounds):
            order = binaries if r % 2 == 0 else binaries[::-1]
            for scenario in chosen:
                for label, binary in order:
                    run_scenario(binary, directory, scenario, a.edits, results, label)
        print(f"big.obj: {triangles} triangles, {size / 1e6:.1f} MB; {a.entities} flat entities; "
              f"{a.rounds} rounds × {a.edits} edits, binaries alternating\n")
        print("| scene | edit | n | first image ms, before | after | parse ms, before | after | BVH ms, before | after |")
        print("|---|---|---:|---:|---:|---:|---:|---:|---:|")
        for (scene, edit), by in results.items():
            col = lambda label, field: ms([f[field] for f in by.get(label, []) if field in f])  # noqa: E731
            n = len(by.get("after", []))
            print(f"| {scene} | {edit} | {n} | {col('before', 'first_image')} | {col('after', 'first_image')} "
                  f"| {col('before', 'parse')} | {col('after', 'parse')} | {col('before', 'bvh')} | {col('after', 'bvh')} |")
        print("\n" + json.dumps({f"{s} / {e}": by for (s, e), by in results.items()}))
    finally:
        shutil.rmtree(directory, ignore_errors=True)


if __name__ == "__main__":
    main()
