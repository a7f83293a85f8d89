"""Compiled contact statistics over the Verlet list (read-only)."""
import numpy as np
from numba import njit


@njit(cache=True, error_model="numpy")
def contact_counts(pos, radius, row_start, partner):
    """(contacts per particle (N,) int64, number of contacts, largest overlap / diameter [-])."""
    n = pos.shape[0]
    per = np.zeros(n, dtype=np.int64)
    total = 0
    worst = 0.0
    for i in range(n):
        for p in range(row_start[i], row_start[i + 1]):
            j = partner[p]
            r2 = 0.0
            for d in range(3):
                r2 += (pos[i, d] - pos[j, d]) ** 2
            cut = radius[i] + radius[j]
            if r2 < cut * cut:
                per[i] += 1
                per[j] += 1
                total += 1
                ov = (cut - np.sqrt(r2)) / (2.0 * min(radius[i], radius[j]))
                if ov > worst:
                    worst = ov
    return per, total, worst
