"""Compiled random sequential addition of non-overlapping spheres in a box."""
import numpy as np
from numba import njit


@njit(cache=True)
def random_fill(radius, lo, hi, dim2, z0, seed, max_tries):
    """Place spheres (largest first as given) at random without overlap; returns (pos, n_placed)."""
    np.random.seed(seed)
    n = radius.shape[0]
    pos = np.zeros((n, 3))
    rmax = radius.max() if n > 0 else 1.0
    size = 2.0 * rmax
    nc = np.ones(3, dtype=np.int64)
    for d in range(3):
        if not (dim2 and d == 2):
            nc[d] = max(1, int((hi[d] - lo[d]) / size))
    ntot = nc[0] * nc[1] * nc[2]
    head = -np.ones(ntot, dtype=np.int64)
    nxt = -np.ones(n, dtype=np.int64)
    for i in range(n):
        r = radius[i]
        placed = False
        for _ in range(max_tries):
            p = np.empty(3)
            for d in range(3):
                if dim2 and d == 2:
                    p[d] = z0
                else:
                    a = lo[d] + r
                    b = hi[d] - r
                    if b < a:
                        return pos, i
                    p[d] = a + (b - a) * np.random.random()
            c = np.empty(3, dtype=np.int64)
            for d in range(3):
                k = int((p[d] - lo[d]) / (hi[d] - lo[d]) * nc[d]) if hi[d] > lo[d] else 0
                c[d] = min(max(k, 0), nc[d] - 1)
            ok = True
            for dx in range(-1, 2):
                x = c[0] + dx
                if x < 0 or x >= nc[0]:
                    continue
                for dy in range(-1, 2):
                    y = c[1] + dy
                    if y < 0 or y >= nc[1]:
                        continue
                    for dz in range(-1, 2):
                        z = c[2] + dz
                        if z < 0 or z >= nc[2]:
                            continue
                        j = head[(x * nc[1] + y) * nc[2] + z]
                        while j >= 0:
                            s = 0.0
                            for d in range(3):
                                s += (p[d] - pos[j, d]) ** 2
                            if s < (r + radius[j]) ** 2:
                                ok = False
                                break
                            j = nxt[j]
                        if not ok:
                            break
                    if not ok:
                        break
                if not ok:
                    break
            if ok:
                pos[i, :] = p
                cell = (c[0] * nc[1] + c[1]) * nc[2] + c[2]
                nxt[i] = head[cell]
                head[cell] = i
                placed = True
                break
        if not placed:
            return pos, i
    return pos, n
