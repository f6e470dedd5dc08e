#!/usr/bin/env python3
"""Writes a procedural sky as an equirectangular Radiance RGBE (.hdr) environment map.

    python3 scripts/make-sky.py                                  # scenes/textures/sky.hdr, 1024x512
    python3 scripts/make-sky.py -o /tmp/sky4k.hdr --width 4096   # the load benchmark's map

What it makes (linear radiance, no randomness: the same arguments give the same bytes):
  - sky (upper hemisphere): deep blue at the zenith blending to a brighter, whiter horizon,
    plus a faint warm glow around the sun (components 0.12-1.0);
  - ground (lower hemisphere): a constant dark brown-grey (0.14, 0.12, 0.10), the horizon
    edge antialiased by the pixel's coverage;
  - the sun: a disk of --sun-diameter degrees (default 2.5) of radiance --sun-radiance x
    (1.0, 0.95, 0.88) (default 2000, some 2000-8000x the sky), centred on the direction
    --sun-direction (from the scene towards the sun, any length), its edge pixels weighted by
    their covered fraction (8x8 subsamples). With the defaults the disk covers ~0.0015 sr and
    gives an irradiance of 2.99 (red) on a plane facing it, 1.96 on the ground at the default
    elevation of 41 degrees; the sky without the sun gives ~1.0 on the ground.

Convention (rondo's `Environment` and Mitsuba 3's `envmap` at an identity to_world): y is up; a
direction d pointing away from the scene maps to u = atan2(d.x, -d.z) / 2pi wrapped into
[0, 1), v = acos(d.y) / pi. Pixel (column i, row j) covers u in [i/W, (i+1)/W) and v in
[j/H, (j+1)/H); row 0 is v = 0 (straight up, +y), the last row straight down; column 0 starts
at u = 0 (direction -z), u = 1/4 is +x, u = 1/2 is +z, u = 3/4 is -x. Each pixel's value is
the radiance at its centre direction (the sun's edge and the horizon are area-averaged).

File format: `#?RADIANCE`, `FORMAT=32-bit_rle_rgbe`, resolution line `-Y H +X W` (rows top to
bottom, columns left to right), then one scanline per row in the standard ("new") run-length
encoding, channel by channel (widths 8..32767; other widths are written flat, which is also
valid). Pure Python 3 standard library, so it runs on a fresh machine.
"""

import argparse
import math
import os
import sys

SUN_COLOUR = (1.0, 0.95, 0.88)
GROUND = (0.14, 0.12, 0.10)
ZENITH = (0.12, 0.26, 0.70)
HORIZON = (0.80, 0.88, 1.00)
GLOW = (0.30, 0.22, 0.12)
SUBSAMPLES = 8


def normalize(v):
    n = math.sqrt(sum(c * c for c in v))
    if not n > 0.0:
        sys.exit("make-sky: the sun direction must be non-zero")
    return tuple(c / n for c in v)


def direction(u, v):
    """The unit direction of texture coordinates (u, v) (inverse of the convention above)."""
    theta, phi = v * math.pi, u * 2.0 * math.pi
    s = math.sin(theta)
    return (s * math.sin(phi), math.cos(theta), -s * math.cos(phi))


def uv_of(d):
    """The texture coordinates of unit direction d (the convention above)."""
    u = math.atan2(d[0], -d[2]) / (2.0 * math.pi)
    u -= math.floor(u)
    return u, math.acos(max(-1.0, min(1.0, d[1]))) / math.pi


def sky(d, sun, pixel_height):
    """Radiance of the sky and ground (no sun disk) at unit direction d; the horizon is
    area-averaged over a pixel pixel_height radians tall."""
    up = max(d[1], 0.0)
    t = (1.0 - up) ** 4  # 0 at the zenith, 1 at the horizon: brighter, whiter towards it
    cos_sun = max(-1.0, min(1.0, sum(a * b for a, b in zip(d, sun))))
    glow = math.exp(-math.acos(cos_sun) / 0.25)
    upper = [z + (h - z) * t + g * glow for z, h, g in zip(ZENITH, HORIZON, GLOW)]
    # Fraction of the pixel above the horizon (the elevation is asin(d.y)).
    above = max(0.0, min(1.0, 0.5 + math.asin(max(-1.0, min(1.0, d[1]))) / pixel_height))
    return [above * a + (1.0 - above) * g for a, g in zip(upper, GROUND)]


def sun_coverage(i, j, width, height, sun, cos_radius):
    """Fraction of pixel (i, j) inside the sun's disk, by SUBSAMPLES^2 stratified points."""
    inside = 0
    for a in range(SUBSAMPLES):
        for b in range(SUBSAMPLES):
            d = direction((i + (a + 0.5) / SUBSAMPLES) / width,
                          (j + (b + 0.5) / SUBSAMPLES) / height)
            if sum(x * y for x, y in zip(d, sun)) >= cos_radius:
                inside += 1
    return inside / (SUBSAMPLES * SUBSAMPLES)


def rgbe(r, g, b):
    """Ward's RGBE encoding of one linear RGB value (components >= 0)."""
    m = max(r, g, b)
    if m < 1e-32:
        return (0, 0, 0, 0)
    mantissa, exponent = math.frexp(m)
    scale = mantissa * 256.0 / m
    return (int(r * scale), int(g * scale), int(b * scale), exponent + 128)


def rle_channel(data):
    """The standard RLE of one channel of a scanline: runs of 3..127 equal bytes as
    (128 + n, byte), everything else as literals (n <= 128, then n bytes)."""
    out = bytearray()
    n, i, literal = len(data), 0, 0  # data[literal:i] is pending as a literal
    while i < n:
        run = 1
        while i + run < n and run < 127 and data[i + run] == data[i]:
            run += 1
        if run >= 3:
            while literal < i:
                k = min(128, i - literal)
                out.append(k)
                out += data[literal:literal + k]
                literal += k
            out += bytes((128 + run, data[i]))
            i += run
            literal = i
        else:
            i += run
    while literal < n:
        k = min(128, n - literal)
        out.append(k)
        out += data[literal:literal + k]
        literal += k
    return out


def scanline(pixels, width):
    """One encoded scanline from a list of RGBE 4-tuples."""
    if not 8 <= width <= 32767:
        return bytes(c for p in pixels for c in p)
    out = bytearray((2, 2, width >> 8, width & 255))
    for channel in range(4):
        out += rle_channel(bytes(p[channel] for p in pixels))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    ap.add_argument("-o", "--output", default=os.path.join(root, "scenes", "textures", "sky.hdr"))
    ap.add_argument("--width", type=int, default=1024, help="pixels (height = width / 2)")
    ap.add_argument("--sun-direction", default="-0.6,0.65,-0.45",
                    help="x,y,z from the scene towards the sun (any length)")
    ap.add_argument("--sun-diameter", type=float, default=2.5, help="degrees")
    ap.add_argument("--sun-radiance", type=float, default=2000.0)
    args = ap.parse_args()
    width = args.width
    if not 8 <= width <= 32766 or width % 2:
        sys.exit("make-sky: --width must be even, 8..32766")
    height = width // 2
    try:
        sun = normalize(tuple(float(c) for c in args.sun_direction.split(",")))
    except ValueError:
        sys.exit("make-sky: --sun-direction must be three numbers x,y,z")
    if len(sun) != 3 or not 0.0 < args.sun_diameter < 90.0 or not args.sun_radiance >= 0.0:
        sys.exit("make-sky: bad sun (need x,y,z; 0 < diameter < 90; radiance >= 0)")
    radius = math.radians(args.sun_diameter) / 2.0
    cos_radius = math.cos(radius)
    pixel_height = math.pi / height
    # A pixel may touch the disk when its centre is within the radius plus its half-diagonal.
    margin = radius + math.sqrt(2.0) * 2.0 * math.pi / width
    sun_u, sun_v = uv_of(sun)
    # The solid angle of a cone of half-angle r: 2pi (1 - cos r).
    solid_angle = 2.0 * math.pi * (1.0 - cos_radius)

    out = bytearray(b"#?RADIANCE\n# procedural sky by scripts/make-sky.py\n"
                    b"FORMAT=32-bit_rle_rgbe\n\n")
    out += b"-Y %d +X %d\n" % (height, width)
    sun_pixels = 0
    for j in range(height):
        v = (j + 0.5) / height
        near_sun_row = abs(v * math.pi - sun_v * math.pi) <= margin
        row = []
        for i in range(width):
            d = direction((i + 0.5) / width, v)
            value = sky(d, sun, pixel_height)
            if near_sun_row and sum(a * b for a, b in zip(d, sun)) >= math.cos(margin):
                f = sun_coverage(i, j, width, height, sun, cos_radius)
                if f > 0.0:
                    sun_pixels += 1
                    value = [c + f * args.sun_radiance * s for c, s in zip(value, SUN_COLOUR)]
            row.append(rgbe(*value))
        out += scanline(row, width)
    os.makedirs(os.path.dirname(os.path.abspath(args.output)), exist_ok=True)
    with open(args.output, "wb") as f:
        f.write(out)
    print("%s: %dx%d, %d bytes; sun towards (%.4f, %.4f, %.4f) at u = %.4f, v = %.4f "
          "(column %d, row %d), %d pixels touched, disk %.3g sr, irradiance %.3g facing it"
          % (args.output, width, height, len(out), sun[0], sun[1], sun[2], sun_u, sun_v,
             int(sun_u * width), int(sun_v * height), sun_pixels, solid_angle,
             args.sun_radiance * solid_angle))


if __name__ == "__main__":
    main()
