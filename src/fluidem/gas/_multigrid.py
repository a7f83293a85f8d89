"""Set-up of the grid multigrid of ``_multigrid_kernels`` for the pressure matrix of an nx × ny grid.

``multigrid_arrays`` makes, once per solver, the levels of the aggregation hierarchy (2 × 2 cells per
coarse cell down to ``coarsest`` cells), the neighbours and Galerkin targets of every cell of every
level, the map of the matrix's CSC entries to grid rows, and the work arrays of GMRES; the kernels fill
in the matrices (``mg_setup``) every time they solve. Array layout: the comment table in
``_multigrid_kernels.py``.
"""
from __future__ import annotations

import numpy as np

from ._layout import Multigrid
from ._multigrid_kernels import MGI_AGG, MGI_GAL, MGI_NB


def grid_neighbours(a: int, b: int, px: bool, py: bool) -> np.ndarray:
    """(a b, 4) neighbours -x, +x, -y, +y of the cells i b + j of an a × b grid (-1: none or itself);
    ``px``, ``py``: whether the grid wraps around along x, y."""
    I, J = np.meshgrid(np.arange(a), np.arange(b), indexing="ij")
    me = (I * b + J).ravel()
    out = np.empty((a * b, 4), np.int64)
    for d, (di, dj) in enumerate(((-1, 0), (1, 0), (0, -1), (0, 1))):
        i2, j2 = I + di, J + dj
        if px:
            i2 = i2 % a
        if py:
            j2 = j2 % b
        ok = ((i2 >= 0) & (i2 < a) & (j2 >= 0) & (j2 < b)).ravel()
        k = (i2 * b + j2).ravel()
        out[:, d] = np.where(ok & (k != me), k, -1)
    return out


def multigrid_arrays(nx: int, ny: int, px: bool, py: bool, indices: np.ndarray, indptr: np.ndarray, coarsest: int,
                     restart: int) -> Multigrid | None:
    """The ``Multigrid`` arrays of the 5-point matrix (CSC ``indices``, ``indptr``; unknown i ny + j is
    cell (i, j)) of an nx × ny grid, periodic along x (``px``) and/or y (``py``): levels down to at most
    ``coarsest`` cells, GMRES restarted every ``restart`` iterations. None if the matrix pattern is not
    the grid's 5-point one."""
    dims = [(nx, ny)]
    while dims[-1][0] * dims[-1][1] > coarsest:
        a, b = dims[-1]
        dims.append(((a + 1) // 2, (b + 1) // 2))
    sizes = [a * b for a, b in dims]
    offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    MGI = np.full((int(offsets[-1]), 9), -1, np.int64)
    nbs = [grid_neighbours(a, b, px, py) for a, b in dims]
    for l, (a, b) in enumerate(dims):
        rows = slice(offsets[l], offsets[l + 1])
        MGI[rows, MGI_NB:MGI_NB + 4] = nbs[l]
        if l + 1 == len(dims):
            break
        bc = dims[l + 1][1]
        I, J = np.meshgrid(np.arange(a), np.arange(b), indexing="ij")
        agg = ((I // 2) * bc + J // 2).ravel()
        MGI[rows, MGI_AGG] = agg
        for d in range(4):
            c = nbs[l][:, d]
            has = c >= 0
            ic, jc = agg, agg[np.where(has, c, 0)]
            same = ic == jc
            if np.any(has & ~same & (nbs[l + 1][ic, d] != jc)):
                return None  # cannot happen on a rectangular grid
            MGI[rows, MGI_GAL + d] = np.where(has, (offsets[l + 1] + ic) * 5 + np.where(same, 0, d + 1), -1)
    # CSC entries of the finest level -> (row, slot)
    n = nx * ny
    rows = indices.astype(np.int64)
    cols = np.repeat(np.arange(n, dtype=np.int64), np.diff(indptr))
    slot = np.full(rows.size, -1, np.int64)
    slot[rows == cols] = 0
    for d in range(3, -1, -1):  # the first matching direction wins
        slot = np.where((rows != cols) & (nbs[0][rows, d] == cols), d + 1, slot)
    if np.any(slot < 0):
        return None
    ell = rows * 5 + slot
    m = sizes[-1]
    MGL = np.zeros((3, len(dims) + 1), np.int64)
    MGL[0] = offsets
    MGL[1, :-1] = [a for a, _ in dims]
    MGL[2, :-1] = [b for _, b in dims]
    N = int(offsets[-1])
    return Multigrid(MGL, MGI, np.zeros((N, 5)), np.zeros((4, N)), np.zeros((m, m)), np.zeros(m, np.int64),
                     np.zeros((2 * (restart + 1), n)), np.zeros((restart + 4, restart + 1)), ell)


def no_multigrid() -> Multigrid:
    """Placeholder ``Multigrid`` arrays (of the right types) for a solver that does not use the multigrid."""
    return Multigrid(np.zeros((3, 2), np.int64), np.zeros((1, 9), np.int64), np.zeros((1, 5)), np.zeros((4, 1)),
                     np.zeros((1, 1)), np.zeros(1, np.int64), np.zeros((2, 1)), np.zeros((4, 1)), np.zeros(1, np.int64))
