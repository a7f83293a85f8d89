"""Compiled cell-list + Verlet-list construction with tangential-history carry-over.

Pairs closer than a_i + a_j + skin are stored once (a half list, CSR by owner).
The domain is cut into slabs at least one cut-off wide along its longest axis;
a pair belongs to the particle in the lower slab (the lower index within a
slab), so the pairs of slab s touch only particles of slabs s and s + 1. Force
loops then run the even slabs in parallel, then the odd ones, adding straight
into per-particle sums without races. The slab partition depends on geometry
only, so sums have the same order for any thread count: results are bitwise
independent of the number of threads.
"""
import numpy as np
from numba import njit, prange


@njit(cache=True, error_model="numpy")
def _cell_grid(pos, radius, skin, dim2):
    n = pos.shape[0]
    lo = np.empty(3)
    hi = np.empty(3)
    for d in range(3):
        lo[d] = np.inf
        hi[d] = -np.inf
    rmax = 0.0
    for i in range(n):
        for d in range(3):
            x = pos[i, d]
            if x < lo[d]:
                lo[d] = x
            if x > hi[d]:
                hi[d] = x
        if radius[i] > rmax:
            rmax = radius[i]
    size = 2.0 * rmax + skin
    ncell = np.ones(3, dtype=np.int64)
    # grow cells if a stray particle would make the grid too large
    while True:
        total = 1
        for d in range(3):
            if dim2 and d == 2:
                ncell[d] = 1
            else:
                ncell[d] = max(1, int((hi[d] - lo[d]) / size))
            total *= ncell[d]
        if total <= 4 * n + 64:
            break
        size *= 1.5
    inv = np.empty(3)
    for d in range(3):
        ext = hi[d] - lo[d]
        inv[d] = ncell[d] / ext if ext > 0 else 0.0
    return lo, inv, ncell


@njit(cache=True, error_model="numpy")
def _bin(pos, lo, inv, ncell):
    n = pos.shape[0]
    cell = np.empty(n, dtype=np.int64)
    for i in range(n):
        c = 0
        for d in range(3):
            k = int((pos[i, d] - lo[d]) * inv[d])
            if k >= ncell[d]:
                k = ncell[d] - 1
            if k < 0:
                k = 0
            c = c * ncell[d] + k
        cell[i] = c
    start, members = _counting_sort(cell, ncell[0] * ncell[1] * ncell[2])
    return cell, start, members


@njit(cache=True, error_model="numpy")
def _counting_sort(key, nkeys):
    """CSR of the indices grouped by key: (start (nkeys+1,), members (N,)), stable within a key."""
    n = key.shape[0]
    start = np.zeros(nkeys + 1, dtype=np.int64)
    for i in range(n):
        start[key[i] + 1] += 1
    for c in range(nkeys):
        start[c + 1] += start[c]
    fill = start[:-1].copy()
    members = np.empty(n, dtype=np.int64)
    for i in range(n):
        members[fill[key[i]]] = i
        fill[key[i]] += 1
    return start, members


@njit(cache=True, error_model="numpy", inline="always")
def _fill_row(i, pos, radius, skin, cell, start, members, ncell, slab, buf, w):
    """Append the partners j owned by particle i to ``buf`` from slot w, sorted; returns the new end.

    The append is branch-free (write j, advance by the 0/1 of "owned and within the cut-off"):
    whether a candidate is kept is a coin toss for the branch predictor, and mispredicted
    branches were most of the cost of the list build (3.5x slower in 2D, 2.5x in 3D).
    ``buf`` must have room for every candidate of the row plus one.
    """
    c = cell[i]
    cz = c % ncell[2]
    cy = (c // ncell[2]) % ncell[1]
    cx = c // (ncell[2] * ncell[1])
    xi = pos[i, 0]
    yi = pos[i, 1]
    zi = pos[i, 2]
    ai = radius[i]
    si = slab[i]
    w0 = w
    for x in range(max(cx - 1, 0), min(cx + 2, ncell[0])):
        for y in range(max(cy - 1, 0), min(cy + 2, ncell[1])):
            base = (x * ncell[1] + y) * ncell[2]
            for z in range(max(cz - 1, 0), min(cz + 2, ncell[2])):
                cc = base + z
                for m in range(start[cc], start[cc + 1]):
                    j = members[m]
                    sj = slab[j]
                    rx = xi - pos[j, 0]
                    ry = yi - pos[j, 1]
                    rz = zi - pos[j, 2]
                    cut = ai + radius[j] + skin  # as brute_force_pairs: the same rounding
                    own = (sj > si) | ((sj == si) & (j > i))
                    close = rx * rx + ry * ry + rz * rz < cut * cut
                    buf[w] = j
                    w += np.int64(own & close)
    # insertion sort of the (short) row: deterministic, cache-friendly lookups by partner
    for k in range(w0 + 1, w):
        v = buf[k]
        q = k - 1
        while q >= w0 and buf[q] > v:
            buf[q + 1] = buf[q]
            q -= 1
        buf[q + 1] = v
    return w


@njit(cache=True, error_model="numpy")
def _fill_rows(lo, hi, pos, radius, skin, cell, start, members, ncell, slab, buf, counts, room):
    """Rows lo..hi−1 one after the other into ``buf`` (from slot 0), their lengths into ``counts``.

    Returns the slots used, or −1 when fewer than ``room`` (the most candidates one row can
    have) slots were left before a row: the caller retries with a larger buffer."""
    w = 0
    cap = buf.shape[0]
    for i in range(lo, hi):
        if cap - w < room:
            return -1
        w2 = _fill_row(i, pos, radius, skin, cell, start, members, ncell, slab, buf, w)
        counts[i] = w2 - w
        w = w2
    return w


@njit(cache=True, error_model="numpy")
def _slabs(pos, radius, skin, dim2, max_slabs):
    """Slab index of each particle and CSR of slab members (slabs >= one cut-off wide)."""
    n = pos.shape[0]
    axis = 0
    best = -1.0
    for d in range(2 if dim2 else 3):
        lo = np.inf
        hi = -np.inf
        for i in range(n):
            lo = min(lo, pos[i, d])
            hi = max(hi, pos[i, d])
        if hi - lo > best:
            best = hi - lo
            axis = d
    lo = np.inf
    rmax = 0.0
    for i in range(n):
        lo = min(lo, pos[i, axis])
        rmax = max(rmax, radius[i])
    cut = 2.0 * rmax + skin
    nslab = max(1, min(max_slabs, int(best / cut))) if n > 0 else 1
    width = best / nslab if best > 0 else 1.0
    slab = np.empty(n, dtype=np.int64)
    for i in range(n):
        slab[i] = min(nslab - 1, int((pos[i, axis] - lo) / width))
    start, members = _counting_sort(slab, nslab)
    return slab, start, members


BUILD_CHUNKS = 16  # work items of the list build (rows lo..hi each, filled into a buffer of their own)


@njit(cache=True, error_model="numpy", parallel=True)
def build_pairs(pos, radius, skin, dim2, expected=0):
    """Half neighbour list (CSR by owner) of all pairs closer than a_i + a_j + skin.

    Returns (row_start (N+1,), partner (P,), slab_start (S+1,), slab_members (N,)).
    Each chunk of rows is filled in one pass into a buffer of its own, then the buffers
    are joined; ``expected`` (e.g. the previous list's length) sizes the buffers, which
    grow if too small. The result does not depend on the chunking or the thread count.
    """
    n = pos.shape[0]
    slab, slab_start, slab_members = _slabs(pos, radius, skin, dim2, 64)
    lo, inv, ncell = _cell_grid(pos, radius, skin, dim2)
    cell, start, members = _bin(pos, lo, inv, ncell)
    # the most candidates one row can have: the members of its 3 x 3 (x 3) cells
    room = 1
    for c in range(ncell[0] * ncell[1] * ncell[2]):
        room = max(room, start[c + 1] - start[c])
    room = room * (9 if ncell[2] == 1 else 27) + 1
    nchunk = max(1, min(BUILD_CHUNKS, n // 256))
    per = (n + nchunk - 1) // nchunk
    cap = max(expected, 6 * n) // nchunk + room
    counts = np.zeros(n, dtype=np.int64)
    used = np.zeros(nchunk, dtype=np.int64)
    while True:
        bufs = np.empty((nchunk, cap), dtype=np.int32)
        for c in prange(nchunk):
            used[c] = _fill_rows(min(n, c * per), min(n, (c + 1) * per), pos, radius, skin, cell, start, members,
                                 ncell, slab, bufs[c], counts, room)
        if used.min() >= 0:
            break
        cap *= 2
    row_start = np.zeros(n + 1, dtype=np.int64)
    for i in range(n):
        row_start[i + 1] = row_start[i] + counts[i]
    partner = np.empty(row_start[n], dtype=np.int32)  # 4-byte partners: less memory traffic per step
    for c in prange(nchunk):
        b = row_start[min(n, c * per)]
        for k in range(used[c]):
            partner[b + k] = bufs[c, k]
    return row_start, partner, slab_start, slab_members


@njit(cache=True, error_model="numpy", inline="always")
def _find(start, partner, i, j):
    """Slot of partner j in the sorted row i, or −1."""
    lo = start[i]
    b = start[i + 1]
    hi = b
    while lo < hi:
        mid = (lo + hi) // 2
        if partner[mid] < j:
            lo = mid + 1
        else:
            hi = mid
    if lo < b and partner[lo] == j:
        return lo
    return -1


@njit(cache=True, error_model="numpy", parallel=True)
def carry_history(old_start, old_partner, old_hist, new_start, new_partner):
    """Tangential history of the new list, copied from the old list where a pair persists.

    A pair whose owner changed (a particle crossed a slab boundary) is found in the
    old row of its partner; its history, kept relative to the owner, changes sign.
    """
    n = new_start.shape[0] - 1
    hist = np.zeros((new_partner.shape[0], 3))
    for i in prange(n):
        for p in range(new_start[i], new_start[i + 1]):
            j = new_partner[p]
            q = _find(old_start, old_partner, i, j)
            sign = 1.0
            if q < 0:
                q = _find(old_start, old_partner, j, i)
                sign = -1.0
            if q >= 0:
                hist[p, 0] = sign * old_hist[q, 0]
                hist[p, 1] = sign * old_hist[q, 1]
                hist[p, 2] = sign * old_hist[q, 2]
    return hist


@njit(cache=True, error_model="numpy")
def brute_force_pairs(pos, radius, cutoff_extra):
    """All pairs i < j with |r_ij| < a_i + a_j + cutoff_extra, O(N²) (for tests)."""
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
