"""Compiled cell-list + Verlet-list construction with tangential-history carry-over.

Pairs are stored as a half list in CSR form: row i holds the j > i with
|r_i − r_j| < a_i + a_j + skin. A transposed index (rows by j) lets forces be
gathered per particle without write conflicts, so every particle's sum has a
fixed order: results do not depend on the number of threads.
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
    ntot = ncell[0] * ncell[1] * ncell[2]
    start = np.zeros(ntot + 1, dtype=np.int64)
    for i in range(n):
        start[cell[i] + 1] += 1
    for c in range(ntot):
        start[c + 1] += start[c]
    fill = start[:-1].copy()
    members = np.empty(n, dtype=np.int64)
    for i in range(n):
        members[fill[cell[i]]] = i
        fill[cell[i]] += 1
    return cell, start, members


@njit(cache=True, error_model="numpy", inline="always")
def _scan_row(i, pos, radius, skin, cell, start, members, ncell, out, write_from):
    """Count (and, if out is not empty, write) the partners j > i of particle i."""
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
                    if j <= i:
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


@njit(cache=True, error_model="numpy", parallel=True)
def build_pairs(pos, radius, skin, dim2):
    """Half neighbour list (CSR) of all pairs closer than a_i + a_j + skin.

    Returns (row_start (N+1,), partner (P,), trans_start (N+1,), trans_pair (P,)),
    where trans_pair lists, for each particle k, the pair indices whose partner is k.
    """
    n = pos.shape[0]
    lo, inv, ncell = _cell_grid(pos, radius, skin, dim2)
    cell, start, members = _bin(pos, lo, inv, ncell)
    counts = np.zeros(n + 1, dtype=np.int64)
    empty = np.empty(0, dtype=np.int64)
    for i in prange(n):
        counts[i + 1] = _scan_row(i, pos, radius, skin, cell, start, members, ncell, empty, 0)
    for i in range(n):
        counts[i + 1] += counts[i]
    row_start = counts
    partner = np.empty(row_start[n], dtype=np.int64)
    for i in prange(n):
        _scan_row(i, pos, radius, skin, cell, start, members, ncell, partner, row_start[i])
    # sort each row so that lookups are deterministic and cache-friendly
    for i in prange(n):
        partner[row_start[i]:row_start[i + 1]].sort()
    trans_start = np.zeros(n + 1, dtype=np.int64)
    for p in range(partner.shape[0]):
        trans_start[partner[p] + 1] += 1
    for i in range(n):
        trans_start[i + 1] += trans_start[i]
    trans_pair = np.empty(partner.shape[0], dtype=np.int64)
    fill = trans_start[:-1].copy()
    for i in range(n):
        for p in range(row_start[i], row_start[i + 1]):
            j = partner[p]
            trans_pair[fill[j]] = p
            fill[j] += 1
    return row_start, partner, trans_start, trans_pair


@njit(cache=True, error_model="numpy", parallel=True)
def carry_history(old_start, old_partner, old_hist, new_start, new_partner):
    """Tangential history of the new list, copied from the old list where a pair persists."""
    n = new_start.shape[0] - 1
    hist = np.zeros((new_partner.shape[0], 3))
    for i in prange(n):
        a = old_start[i]
        b = old_start[i + 1]
        if a == b:
            continue
        for p in range(new_start[i], new_start[i + 1]):
            j = new_partner[p]
            # rows are sorted: binary search
            lo = a
            hi = b
            while lo < hi:
                mid = (lo + hi) // 2
                if old_partner[mid] < j:
                    lo = mid + 1
                else:
                    hi = mid
            if lo < b and old_partner[lo] == j:
                hist[p, 0] = old_hist[lo, 0]
                hist[p, 1] = old_hist[lo, 1]
                hist[p, 2] = old_hist[lo, 2]
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
