"""The Cornell box of scenes/cornell.ron as plain data, shared by the peer-renderer bench scripts
(benches/mitsuba/cornell.py, benches/cycles/cornell.py): the quads (rondo's winding, so the
lamp's normal a-b-c points down, -y), the boxes (rotated about y, then translated, as rondo's
Transform does), the diffuse reflectances (linear RGB), the lamp's radiance and the camera.
Never used by the tests.
"""

import math

# Camera (rondo's Camera in scenes/cornell.ron): vertical field of view in degrees.
CAMERA_ORIGIN = (278.0, 278.0, -800.0)
CAMERA_TARGET = (278.0, 278.0, 0.0)
CAMERA_UP = (0.0, 1.0, 0.0)
CAMERA_FOV_Y = 40.0

# The lamp's radiance (Light(emit: (1, 1, 1), intensity: 15)), one-sided along its normal.
LAMP_RADIANCE = 15.0


def rot_y_then_translate(p, degrees, t):
    """rondo's Transform(rotate: (0, degrees, 0), translate: t) applied to point p."""
    a = math.radians(degrees)
    c, s = math.cos(a), math.sin(a)
    x, y, z = p
    return (c * x + s * z + t[0], y + t[1], -s * x + c * z + t[2])


def box_quads(lo, hi, degrees, t):
    """The six faces of an axis-aligned box as quads with outward normals, transformed."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    corner = lambda i, j, k: rot_y_then_translate(
        (x1 if i else x0, y1 if j else y0, z1 if k else z0), degrees, t)
    faces = [
        [(0, 0, 0), (0, 0, 1), (0, 1, 1), (0, 1, 0)],  # -x
        [(1, 0, 0), (1, 1, 0), (1, 1, 1), (1, 0, 1)],  # +x
        [(0, 0, 0), (1, 0, 0), (1, 0, 1), (0, 0, 1)],  # -y
        [(0, 1, 0), (0, 1, 1), (1, 1, 1), (1, 1, 0)],  # +y
        [(0, 0, 0), (0, 1, 0), (1, 1, 0), (1, 0, 0)],  # -z
        [(0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)],  # +z
    ]
    return [[corner(*v) for v in f] for f in faces]


# (name, material, quads) exactly as in scenes/cornell.ron.
QUADS = [
    ("left", "red", [[(555, 0, 0), (555, 0, 555), (555, 555, 555), (555, 555, 0)]]),
    ("right", "green", [[(0, 0, 0), (0, 555, 0), (0, 555, 555), (0, 0, 555)]]),
    ("lamp", "light", [[(343, 554, 332), (213, 554, 332), (213, 554, 227), (343, 554, 227)]]),
    ("floor", "white", [[(0, 0, 0), (0, 0, 555), (555, 0, 555), (555, 0, 0)]]),
    ("ceiling", "white", [[(555, 555, 555), (0, 555, 555), (0, 555, 0), (555, 555, 0)]]),
    ("back", "white", [[(0, 0, 555), (0, 555, 555), (555, 555, 555), (555, 0, 555)]]),
    ("tall", "white", box_quads((0, 0, 0), (165, 330, 165), 15, (265, 0, 295))),
    ("short", "white", box_quads((0, 0, 0), (165, 165, 165), -18, (130, 0, 65))),
]
ALBEDO = {"red": (0.65, 0.05, 0.05), "white": (0.73, 0.73, 0.73), "green": (0.12, 0.45, 0.15)}


def triangles(quads):
    """Quad a b c d as triangles a b c and a c d (as rondo splits it), as index triples into
    the flattened vertex list (four vertices per quad, in order)."""
    return [t for i in range(len(quads))
            for t in ((4 * i, 4 * i + 1, 4 * i + 2), (4 * i, 4 * i + 2, 4 * i + 3))]
