"""Error metrics of the peer-renderer bench scripts (Mitsuba, Cycles, FLIP), so every script
measures alike. Never used by the tests."""

import math

import numpy as np


def metrics(a, r):
    """RMSE, relative MSE, MAE over all pixels, and the lamp-out clamped RMSE: pixels whose
    reference exceeds 1 in some channel (the lamp and its antialiased edge) are left out, and
    both images are clamped to [0, 1]. `a` and `r` are H x W x 3 arrays."""
    a, r = a.astype(np.float64), r.astype(np.float64)
    d = a - r
    keep = np.all(r <= 1.0, axis=-1)
    dc = (np.clip(a, 0, 1) - np.clip(r, 0, 1))[keep]
    return (math.sqrt(np.mean(d * d)),
            float(np.mean(d * d / (r ** 2 + 0.01))),
            float(np.mean(np.abs(d))),
            math.sqrt(np.mean(dc * dc)))
