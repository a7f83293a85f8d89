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
def _scan_row(i, pos, radius, skin, cell, start, members, ncell, slab, out, write_from):
    # out: int32 partner slots (empty array: count only)
    """Count (and, if out is not empty, write) the partners j owned by particle i."""
    c = cell[i]
    cz = c % ncell[2]
    cy = (c // ncell[2]) % ncell[1]
    cx = c // (ncell[2] * ncell[1])
    count = 0
    for dx in range(-1, 2):
        x = cx + dx
        if x < 0 or x >= ncell[0]:
            continue
        for dy in range(-1, 2):
            y = cy + dy
            if y < 0 or y >= ncell[1]:
                continue
            for dz in range(-1, 2):
                z = cz + dz
                if z < 0 or z >= ncell[2]:
                    continue
                cc = (x * ncell[1] + y) * ncell[2] + z
                for m in range(start[cc], start[cc + 1]):
                    j = members[m]
                    if slab[j] < slab[i] or (slab[j] == slab[i] and j <= i):
                        continue
                    rx = pos[i, 0] - pos[j, 0]
                    ry = pos[i, 1] - pos[j, 1]
                    rz = pos[i, 2] - pos[j, 2]
                    cut = radius[i] + radius[j] + skin
                    if rx * rx + ry * ry + rz * rz < cut * cut:
                        if out.shape[0] > 0:
                            out[write_from + count] = j
                        count += 1
    return count


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


@njit(cache=True, error_model="numpy", parallel=True)
def build_pairs(pos, radius, skin, dim2):
    """Half neighbour list (CSR by owner) of all pairs closer than a_i + a_j + skin.

    Returns (row_start (N+1,), partner (P,), slab_start (S+1,), slab_members (N,)).
    """
    n = pos.shape[0]
    slab, slab_start, slab_members = _slabs(pos, radius, skin, dim2, 64)
    lo, inv, ncell = _cell_grid(pos, radius, skin, dim2)
    cell, start, members = _bin(pos, lo, inv, ncell)
    counts = np.zeros(n + 1, dtype=np.int64)
    empty = np.empty(0, dtype=np.int32)
    for i in prange(n):
        counts[i + 1] = _scan_row(i, pos, radius, skin, cell, start, members, ncell, slab, empty, 0)
    for i in range(n):
        counts[i + 1] += counts[i]
    row_start = counts
    partner = np.empty(row_start[n], dtype=np.int32)  # 4-byte partners: less memory traffic per step
    for i in prange(n):
        _scan_row(i, pos, radius, skin, cell, start, members, ncell, slab, partner, row_start[i])
    # sort each row so that lookups are deterministic and cache-friendly
    for i in prange(n):
        partner[row_start[i]:row_start[i + 1]].sort()
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
