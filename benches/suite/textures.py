"""Image helpers shared by the converters: textures read as rondo reads them."""

import numpy as np
from PIL import Image


def srgb_to_linear(c):
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def load_rgba(path, encoding):
    """H x W x 4 float32, top row first: 8-bit values / 255, through the sRGB curve for
    encoding "srgb" (alpha always linear)."""
    img = np.asarray(Image.open(path).convert("RGBA"), dtype=np.float32) / 255.0
    if encoding == "srgb":
        img[..., :3] = srgb_to_linear(img[..., :3])
    return img


def checker_image(even, odd):
    """2 x 2 texels: even where both halves agree (sin(k u) sin(k v) > 0)."""
    e, o = np.asarray(even, np.float32), np.asarray(odd, np.float32)
    return np.ascontiguousarray(np.array([[e, o], [o, e]], dtype=np.float32))
