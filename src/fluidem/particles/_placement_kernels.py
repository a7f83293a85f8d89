"""Compiled random sequential addition of non-overlapping spheres in a box."""
import numpy as np
from numba import njit


@njit(cache=True)
def random_fill(radius, lo, hi, dim2, z0, seed, max_tries, period):
    """Place spheres (largest first as given) at random without overlap; returns (pos, n_placed).

    ``period`` (3,): hi − lo along each periodic axis of the box (0 elsewhere). Along such an axis a centre
    may lie anywhere in [lo, hi) and spheres must not overlap their neighbours' nearest images across the
    seam (r − L round(r / L), Allen & Tildesley 1987 eq. 1.9); along the others a sphere stays inside."""
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
                    if period[d] > 0.0:
                        a = lo[d]
                        b = hi[d]
                    if b < a:
                        return pos, i
                    p[d] = a + (b - a) * np.random.random()
            c = np.empty(3, dtype=np.int64)
            for d in range(3):
                k = int((p[d] - lo[d]) / (hi[d] - lo[d]) * nc[d]) if hi[d] > lo[d] else 0
                c[d] = min(max(k, 0), nc[d] - 1)
            ok = True
            k_lo = np.empty(3, dtype=np.int64)
            k_hi = np.empty(3, dtype=np.int64)
            for d in range(3):  # the 3 x 3 x 3 cells round c; round a periodic axis modulo nc (all its cells if < 3)
                k_lo[d] = c[d] - 1
                k_hi[d] = c[d] + 1
                if period[d] > 0.0 and nc[d] < 3:
                    k_lo[d] = 0
                    k_hi[d] = nc[d] - 1
            for dx in range(k_lo[0], k_hi[0] + 1):
                x = dx % nc[0] if period[0] > 0.0 else dx
                if x < 0 or x >= nc[0]:
                    continue
                for dy in range(k_lo[1], k_hi[1] + 1):
                    y = dy % nc[1] if period[1] > 0.0 else dy
                    if y < 0 or y >= nc[1]:
                        continue
                    for dz in range(k_lo[2], k_hi[2] + 1):
                        z = dz % nc[2] if period[2] > 0.0 else dz
                        if z < 0 or z >= nc[2]:
                            continue
                        j = head[(x * nc[1] + y) * nc[2] + z]
                        while j >= 0:
                            s = 0.0
                            for d in range(3):
                                rd = p[d] - pos[j, d]
                                if period[d] > 0.0:
                                    if rd > 0.5 * period[d]:
                                        rd -= period[d]
                                    elif rd < -0.5 * period[d]:
                                        rd += period[d]
                                s += rd ** 2
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
