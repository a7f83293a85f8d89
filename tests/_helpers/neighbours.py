"""Random polydisperse packings and the brute-force pair search for the neighbour-list and renumbering tests."""
from __future__ import annotations

import numpy as np
from numba import njit


def random_packing(seed, n, dim2, solid_fraction=0.3, spread=(0.5, 1.5)):
    """Random (overlapping allowed) polydisperse positions at a given nominal solid fraction.

    Radii are uniform in spread × 1 mm; the box side is chosen for the solid fraction.
    """
    rng = np.random.default_rng(seed)
    radius = 1e-3 * rng.uniform(*spread, n)
    if dim2:
        side = np.sqrt(np.sum(np.pi * radius**2) / solid_fraction)
        pos = np.column_stack([rng.uniform(0, side, (n, 2)), np.full(n, 0.25e-3)])  # one z, as 2D cases have
    else:
        side = np.cbrt(np.sum(4 / 3 * np.pi * radius**3) / solid_fraction)
        pos = rng.uniform(0, side, (n, 3)) - 0.3 * side  # a box not at the origin
    return pos, radius


@njit(error_model="numpy")
def brute_force_pairs(pos, radius, cutoff_extra):
    """All pairs i < j with |r_ij| < a_i + a_j + cutoff_extra, O(N²): the reference the cell-list search is checked against."""
    n = pos.shape[0]
    out = []
    for i in range(n):
        for j in range(i + 1, n):
            r2 = 0.0
            for d in range(3):
                r2 += (pos[i, d] - pos[j, d]) ** 2
            cut = radius[i] + radius[j] + cutoff_extra
            if r2 < cut * cut:
                out.append((i, j))
    return out

