"""Compiled pieces of adding and removing particles during a run (``particles/population.py``).

``insert_fill``: random sequential addition of new spheres in a box region, without overlap with each other
and with the particles already there. ``drop_pairs``: the half contact list with removed particles left out
and the others renumbered, histories kept, for ``carry_history`` to carry into the rebuilt list.
"""
import numpy as np
from numba import njit


@njit(cache=True)
def insert_fill(old_pos, old_radius, radius, lo, hi, dim2, z0, seed, max_tries):
    """Place the spheres of ``radius`` (in the given order) at random in the box lo–hi, each wholly inside it
    and overlapping neither a sphere already placed nor any of (``old_pos``, ``old_radius``); returns
    (pos (n, 3), n_placed): the first n_placed rows are placed, the rest could not be within ``max_tries``
    random tries each and are left for a later insertion."""
    np.random.seed(seed)
    n = radius.shape[0]
    pos = np.zeros((n, 3))
    if n == 0:
        return pos, 0
    rmax = radius.max()
    for i in range(old_radius.shape[0]):
        rmax = max(rmax, old_radius[i])
    size = 2.0 * rmax
    # the cell grid covers the region grown by one largest diameter: old spheres there can touch new ones
    glo = np.empty(3)
    nc = np.ones(3, dtype=np.int64)
    for d in range(3):
        glo[d] = lo[d] - size
        if not (dim2 and d == 2):
            nc[d] = max(1, int((hi[d] - lo[d] + 2.0 * size) / size))
    ntot = nc[0] * nc[1] * nc[2]
    nold = old_pos.shape[0]
    head = -np.ones(ntot, dtype=np.int64)
    nxt = -np.ones(nold + n, dtype=np.int64)
    # entries 0 … nold−1 are old spheres, nold + k the k-th new one
    cx = np.empty(3, dtype=np.int64)
    for j in range(nold):
        inside = True
        for d in range(3):
            if dim2 and d == 2:
                cx[d] = 0
                continue
            k = int(np.floor((old_pos[j, d] - glo[d]) / size))
            if k < 0 or k >= nc[d]:
                inside = False
                break
            cx[d] = k
        if inside:
            c = (cx[0] * nc[1] + cx[1]) * nc[2] + cx[2]
            nxt[j] = head[c]
            head[c] = j
    for i in range(n):
        r = radius[i]
        placed = False
        p = np.empty(3)
        for _ in range(max_tries):
            for d in range(3):
                if dim2 and d == 2:
                    p[d] = z0
                else:
                    a = lo[d] + r
                    b = hi[d] - r
                    if b < a:
                        return pos, i
                    p[d] = a + (b - a) * np.random.random()
            for d in range(3):
                if dim2 and d == 2:
                    cx[d] = 0
                else:
                    cx[d] = min(max(int(np.floor((p[d] - glo[d]) / size)), 0), nc[d] - 1)
            ok = True
            for ddx in range(-1, 2):
                x = cx[0] + ddx
                if x < 0 or x >= nc[0] or not ok:
                    continue
                for ddy in range(-1, 2):
                    y = cx[1] + ddy
                    if y < 0 or y >= nc[1] or not ok:
                        continue
                    for ddz in range(-1, 2):
                        z = cx[2] + ddz
                        if z < 0 or z >= nc[2] or not ok:
                            continue
                        j = head[(x * nc[1] + y) * nc[2] + z]
                        while j >= 0:
                            s = 0.0
                            if j < nold:
                                for d in range(3):
                                    s += (p[d] - old_pos[j, d]) ** 2
                                rj = old_radius[j]
                            else:
                                for d in range(3):
                                    s += (p[d] - pos[j - nold, d]) ** 2
                                rj = radius[j - nold]
                            if s < (r + rj) ** 2:
                                ok = False
                                break
                            j = nxt[j]
            if ok:
                placed = True
                break
        if not placed:
            return pos, i
        for d in range(3):
            pos[i, d] = p[d]
        c = (cx[0] * nc[1] + cx[1]) * nc[2] + cx[2]
        nxt[nold + i] = head[c]
        head[c] = nold + i
    return pos, n


@njit(cache=True)
def drop_pairs(row_start, partner, hist, new_index, n_rows):
    """The half list (row_start, partner, hist) without the pairs of removed particles (``new_index`` −1) and
    with particle i renamed new_index[i] (order kept, so rows stay in owner order); ``n_rows`` rows (the kept
    particles and, empty, any added after them)."""
    n = row_start.shape[0] - 1
    count = 0
    for i in range(n):
        if new_index[i] < 0:
            continue
        for p in range(row_start[i], row_start[i + 1]):
            if new_index[partner[p]] >= 0:
                count += 1
    new_start = np.zeros(n_rows + 1, dtype=np.int64)
    new_partner = np.empty(count, dtype=partner.dtype)
    new_hist = np.empty((count, hist.shape[1]))
    q = 0
    for i in range(n):
        a = new_index[i]
        if a < 0:
            continue
        for p in range(row_start[i], row_start[i + 1]):
            b = new_index[partner[p]]
            if b < 0:
                continue
            new_partner[q] = b
            for e in range(hist.shape[1]):
                new_hist[q, e] = hist[p, e]
            q += 1
        new_start[a + 1] = q
    for i in range(n_rows):  # rows of removed or added particles end where the row before them does
        if new_start[i + 1] < new_start[i]:
            new_start[i + 1] = new_start[i]
    return new_start, new_partner, new_hist
