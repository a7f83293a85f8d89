"""Compiled conversions between the GPU engine's full neighbour list and the CPU engine's half list.

The CPU engine lists each pair once (CSR ``row_start``, ``partner`` by owner, the spring ``hist`` (P, 3)
relative to the owner); the GPU engine lists it from both ends (``nbr`` (K, N) int32, rows sorted by
partner, ``count`` (N,), springs ``fhist`` (3, K, N) relative to the row's particle: minus the owner's in
the partner's row). Checkpoints hold the half list, so that either engine resumes the other's run; these
run on the host when a GPU engine writes or reads one.
"""
import numpy as np
from numba import njit


@njit(cache=True, error_model="numpy")
def full_rows(n, row_start, partner, hist, kmin):
    """(count (N,) int32, nbr (K, N) int32, fhist (3, K, N)) of the half list (row_start, partner, hist):
    each pair in the rows of both its particles, the partner's spring negated, rows sorted by partner;
    K = max(kmin, the longest row)."""
    count = np.zeros(n, dtype=np.int32)
    for i in range(n):
        for p in range(row_start[i], row_start[i + 1]):
            count[i] += 1
            count[partner[p]] += 1
    k = kmin
    for i in range(n):
        k = max(k, count[i])
    nbr = np.zeros((k, n), dtype=np.int32)
    fhist = np.zeros((3, k, n))
    fill = np.zeros(n, dtype=np.int32)
    for i in range(n):
        for p in range(row_start[i], row_start[i + 1]):
            j = partner[p]
            q = fill[i]
            nbr[q, i] = j
            fhist[0, q, i] = hist[p, 0]
            fhist[1, q, i] = hist[p, 1]
            fhist[2, q, i] = hist[p, 2]
            fill[i] = q + 1
            q = fill[j]
            nbr[q, j] = i
            fhist[0, q, j] = -hist[p, 0]
            fhist[1, q, j] = -hist[p, 1]
            fhist[2, q, j] = -hist[p, 2]
            fill[j] = q + 1
    for i in range(n):  # insertion sort of each row by partner, springs alongside
        for a in range(1, count[i]):
            v = nbr[a, i]
            h0 = fhist[0, a, i]
            h1 = fhist[1, a, i]
            h2 = fhist[2, a, i]
            b = a - 1
            while b >= 0 and nbr[b, i] > v:
                nbr[b + 1, i] = nbr[b, i]
                fhist[0, b + 1, i] = fhist[0, b, i]
                fhist[1, b + 1, i] = fhist[1, b, i]
                fhist[2, b + 1, i] = fhist[2, b, i]
                b -= 1
            nbr[b + 1, i] = v
            fhist[0, b + 1, i] = h0
            fhist[1, b + 1, i] = h1
            fhist[2, b + 1, i] = h2
    return count, nbr, fhist


@njit(cache=True, error_model="numpy")
def half_history(row_start, partner, count, nbr, fhist):
    """(P, 3) springs of the half list (row_start, partner), relative to each pair's owner, from the full
    list: the owner's row's slot of the partner (bisection: rows are sorted); zero where the full list does
    not hold the pair."""
    n = row_start.shape[0] - 1
    hist = np.zeros((partner.shape[0], 3))
    for i in range(n):
        for p in range(row_start[i], row_start[i + 1]):
            j = partner[p]
            lo = 0
            hi = count[i]
            while lo < hi:
                mid = (lo + hi) // 2
                if nbr[mid, i] < j:
                    lo = mid + 1
                else:
                    hi = mid
            if lo < count[i] and nbr[lo, i] == j:
                hist[p, 0] = fhist[0, lo, i]
                hist[p, 1] = fhist[1, lo, i]
                hist[p, 2] = fhist[2, lo, i]
    return hist


@njit(cache=True, error_model="numpy")
def upper_rows(count, nbr):
    """(row_start (N+1,), partner (P,) int32): the full list's pairs once each, in the row of the smaller
    index (a half list for the analyses that count contacts)."""
    n = count.shape[0]
    row_start = np.zeros(n + 1, dtype=np.int64)
    for i in range(n):
        c = 0
        for k in range(count[i]):
            c += nbr[k, i] > i
        row_start[i + 1] = row_start[i] + c
    partner = np.empty(row_start[n], dtype=np.int32)
    for i in range(n):
        q = row_start[i]
        for k in range(count[i]):
            if nbr[k, i] > i:
                partner[q] = nbr[k, i]
                q += 1
    return row_start, partner
