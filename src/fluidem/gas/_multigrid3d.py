"""Set-up of the grid multigrid of ``_multigrid3d_kernels`` for the pressure matrix of an nx × ny × nz grid.

``multigrid_arrays`` makes, once per solver, the levels of the aggregation hierarchy (2 cells per coarse
cell along the axes aggregated, down to ``coarsest`` cells), the neighbours and Galerkin targets of every
cell of every level, the map of the matrix's CSC entries to grid rows, and the work arrays of GMRES; the
kernels fill in the matrices (``mg_setup``) every time they solve. Semi-coarsening: given the coupling of
the matrix along each axis (``weights``, face area / distance of the grid's cells), a level aggregates only
the axes coupled at least SEMI_COARSENING times as strongly as the strongest (an axis one cell thick is
never aggregated); a step of factors (r_x, r_y, r_z) scales the coupling along axis q by
r_q+1 r_q+2 / r_q (face area over distance), so a grid of cells twice as tall as wide (y couplings 4 times
weaker) coarsens 2 × 1 × 2 once, which evens the couplings, and 2 × 2 × 2 after. Pointwise Gauss-Seidel
and aggregation both lose their grip on the weakly coupled axis of an anisotropic grid: on the benchmark
bed of 100³ cells (couplings 4:1) full coarsening took 14 GMRES iterations to 1e-8, semi-coarsening 6. Array layout: the module docstring of ``_multigrid3d_kernels.py``.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ._multigrid3d_kernels import MGI_AGG, MGI_GAL, MGI_NB, NS

SEMI_COARSENING = 0.6  # aggregate the axes coupled at least this fraction as strongly as the strongest


class Multigrid3D(NamedTuple):
    """The arrays of ``_multigrid3d_kernels.gmres`` and ``mg_setup`` (layout there) and ``ell``, the row and
    slot of each matrix entry in MGA (flat index row * 7 + slot), then the slots of the finest level that no
    entry fills (int32 where the indices fit)."""

    MGL: np.ndarray
    MGI: np.ndarray
    MGA: np.ndarray
    MGS: np.ndarray
    MGW: np.ndarray
    DLU: np.ndarray
    PIV: np.ndarray
    KRY: np.ndarray
    HES: np.ndarray
    ell: np.ndarray


def grid_neighbours(dims: tuple[int, int, int], periodic: tuple[bool, bool, bool]) -> np.ndarray:
    """(a b c, 6) neighbours -x, +x, -y, +y, -z, +z of the cells (i b + j) c + k of an a × b × c grid (-1: none
    or itself); ``periodic``: whether the grid wraps around along each axis."""
    a, b, c = dims
    I, J, K = np.meshgrid(np.arange(a), np.arange(b), np.arange(c), indexing="ij")
    me = ((I * b + J) * c + K).ravel()
    out = np.empty((a * b * c, 6), np.int64)
    for d in range(6):
        axis, step = d // 2, (-1, 1)[d % 2]
        idx = [I, J, K]
        idx[axis] = idx[axis] + step
        if periodic[axis]:
            idx[axis] = idx[axis] % dims[axis]
        ok = np.ones(I.shape, bool)
        for q in range(3):
            ok &= (idx[q] >= 0) & (idx[q] < dims[q])
        k = ((idx[0] * b + idx[1]) * c + idx[2]).ravel()
        out[:, d] = np.where(ok.ravel() & (k != me), k, -1)
    return out


def multigrid_arrays(dims: tuple[int, int, int], periodic: tuple[bool, bool, bool], indices: np.ndarray,
                     indptr: np.ndarray, coarsest: int, restart: int,
                     weights: tuple[float, float, float] | None = None) -> Multigrid3D | None:
    """The ``Multigrid3D`` arrays of the 7-point matrix (CSC ``indices``, ``indptr``; unknown (i ny + j) nz + k
    is cell (i, j, k)) of an nx × ny × nz grid, periodic along the axes flagged in ``periodic``: levels down
    to at most ``coarsest`` cells, GMRES restarted every ``restart`` iterations; ``weights``: the coupling
    along each axis (area / distance of a cell; None: all equal, 2 × 2 × 2 aggregation). None if the matrix
    pattern is not the grid's 7-point one."""
    levels = [tuple(int(n) for n in dims)]
    steps = []
    w = [1.0, 1.0, 1.0] if weights is None else [float(v) for v in weights]
    while np.prod(levels[-1]) > coarsest and max(levels[-1]) > 1:
        d = levels[-1]
        strong = max(w[q] for q in range(3) if d[q] > 1)
        r = [2 if d[q] > 1 and w[q] >= SEMI_COARSENING * strong else 1 for q in range(3)]
        w = [w[q] * r[(q + 1) % 3] * r[(q + 2) % 3] / r[q] for q in range(3)]
        steps.append(r)
        levels.append(tuple((n + r[q] - 1) // r[q] for q, n in enumerate(d)))
    sizes = [int(np.prod(d)) for d in levels]
    offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    MGI = np.full((int(offsets[-1]), 13), -1, np.int64)
    nbs = [grid_neighbours(d, periodic) for d in levels]
    MGL = np.zeros((7, len(levels) + 1), np.int64)
    MGL[0] = offsets
    for q in range(3):
        MGL[1 + q, :-1] = [d[q] for d in levels]
    for l, d in enumerate(levels):
        rows = slice(offsets[l], offsets[l + 1])
        MGI[rows, MGI_NB:MGI_NB + 6] = nbs[l]
        if l + 1 == len(levels):
            break
        coarse = levels[l + 1]
        factors = steps[l]
        MGL[4:7, l] = factors
        I, J, K = np.meshgrid(*(np.arange(n) for n in d), indexing="ij")
        agg = (((I // factors[0]) * coarse[1] + J // factors[1]) * coarse[2] + K // factors[2]).ravel()
        MGI[rows, MGI_AGG] = agg
        for s in range(6):
            c = nbs[l][:, s]
            has = c >= 0
            ic, jc = agg, agg[np.where(has, c, 0)]
            same = ic == jc
            if np.any(has & ~same & (nbs[l + 1][ic, s] != jc)):
                return None  # a wrap-around that the coarse level does not have
            MGI[rows, MGI_GAL + s] = np.where(has, (offsets[l + 1] + ic) * NS + np.where(same, 0, s + 1), -1)
    n = int(np.prod(dims))
    rows = indices.astype(np.int64)
    cols = np.repeat(np.arange(n, dtype=np.int64), np.diff(indptr))
    slot = np.full(rows.size, -1, np.int64)
    slot[rows == cols] = 0
    for s in range(5, -1, -1):  # the first matching direction wins
        slot = np.where((rows != cols) & (nbs[0][rows, s] == cols), s + 1, slot)
    if np.any(slot < 0):
        return None
    ell = rows * NS + slot
    filled = np.zeros(n * NS, bool)
    filled[ell] = True
    if np.count_nonzero(filled) != ell.size:
        return None  # two entries in one slot
    ell = np.concatenate([ell, np.flatnonzero(~filled)])  # then the slots that stay 0
    m = sizes[-1]
    N = int(offsets[-1])
    return Multigrid3D(MGL, MGI, np.zeros((N, NS)), np.zeros((N, NS + 1), np.float32), np.zeros((3, N)), np.zeros((m, m)),
                       np.zeros(m, np.int64), np.zeros((2 * (restart + 1), n)), np.zeros((restart + 4, restart + 1)),
                       ell.astype(np.int32 if n * NS < 2**31 else np.int64))
