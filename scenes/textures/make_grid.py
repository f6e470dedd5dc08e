#!/usr/bin/env python3
"""Writes grid.png, the test image texture of scenes/textures.ron.

Run from anywhere (Python 3, standard library only):

    python3 scenes/textures/make_grid.py

It writes grid.png beside this script: a 64x64 8-bit RGB PNG whose four quadrants are
coloured differently (top-left red, top-right green, bottom-left blue, bottom-right yellow),
crossed by a dark grid line every 8 pixels, with a white letter "F" in the top-left quadrant.
No two quadrants match and the "F" reads wrongly under any mirror, so a rendered image shows at
once whether u or v is flipped. The output is deterministic (byte-identical on every run).
"""

import struct
import zlib
from pathlib import Path

SIZE = 64
CELL = 8

QUADRANTS = {
    (0, 0): (220, 50, 40),  # top-left: red
    (1, 0): (60, 170, 70),  # top-right: green
    (0, 1): (50, 90, 200),  # bottom-left: blue
    (1, 1): (235, 200, 40),  # bottom-right: yellow
}
GRID = (30, 30, 30)
LETTER = (255, 255, 255)


def letter_f(x, y):
    """Whether pixel (x, y) belongs to the "F" drawn in the top-left quadrant."""
    stem = 9 <= x <= 12 and 6 <= y <= 26
    top = 9 <= x <= 24 and 6 <= y <= 9
    middle = 9 <= x <= 20 and 15 <= y <= 18
    return stem or top or middle


def pixel(x, y):
    """Colour of pixel (x, y); y = 0 is the top row."""
    if letter_f(x, y):
        return LETTER
    if x % CELL == 0 or y % CELL == 0 or x == SIZE - 1 or y == SIZE - 1:
        return GRID
    return QUADRANTS[(x * 2 // SIZE, y * 2 // SIZE)]


def chunk(kind, data):
    """One PNG chunk: length, type, data, CRC of type and data."""
    return (
        struct.pack(">I", len(data))
        + kind
        + data
        + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)
    )


def png(width, height, rows):
    """An 8-bit RGB PNG from rows of (r, g, b) tuples, top row first."""
    raw = b"".join(b"\x00" + bytes(c for p in row for c in p) for row in rows)
    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)  # 8-bit, RGB
    return (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", header)
        + chunk(b"IDAT", zlib.compress(raw, 9))
        + chunk(b"IEND", b"")
    )


def main():
    rows = [[pixel(x, y) for x in range(SIZE)] for y in range(SIZE)]
    out = Path(__file__).resolve().with_name("grid.png")
    out.write_bytes(png(SIZE, SIZE, rows))
    print(f"wrote {out} ({out.stat().st_size} bytes)")


if __name__ == "__main__":
    main()
