"""Compiled GMRES preconditioned by a geometric aggregation multigrid, for the 7-point matrices of a
box grid (optionally periodic along any axis): the 3D sibling of ``_multigrid_kernels.py``.

``mg_setup`` makes the hierarchy of a matrix given in CSC form (its entries mapped to grid rows by the
caller, once per pattern: ``_multigrid3d.py``) in one pass over the rows of each level (the smoother's
copy, 1 / diagonal and the sums of the next level's matrix, whose targets follow from (i, j, k) inside
the level's box; MGI is read on its faces only), ``gmres`` solves A x = b with one cycle (``mg_cycle``) as
right preconditioner (the preconditioned vectors are kept, as flexible GMRES does). Nothing here knows the
equations behind the matrix; the caller owns every array.

Hierarchy: 2 cells per coarse cell along each axis that is aggregated (the caller picks them: the
strongly coupled axes, semi-coarsening when the couplings differ; an axis one cell thick stays so),
piecewise-constant prolongation P, coarse matrices Pᵀ A P, which stay 7-point, with the coupling along
each axis divided by that axis's aggregation factor and the row sums kept (see ``_mg_level_matrix``: the
over-correction that plain aggregation needs, Braess 1995; Notay 2010 §2); SWEEPS forward Gauss-Seidel
sweeps before the coarse correction and SWEEPS backward ones after it, so that the cycle is symmetric;
CYCLES (2: a W-cycle) visits of a coarse level per visit of its fine level where that costs at most half
the fine level's work (the coarse level has at most a quarter of the cells), one elsewhere; dense LU on
the coarsest level. The smoother reads single-precision copies of the rows (MGS: half the memory traffic
of the float64 rows; the cycle is a preconditioner, GMRES works with A itself), and does its sweeps and the
residual's restriction in one pass over the x-planes of a level (``_mg_presmooth_restrict``), so that
each row is read from memory once per pass, not once per sweep. Layout, all levels concatenated (level l
holds cells MGL[0, l] .. MGL[0, l + 1] - 1):

  MGL (7, levels + 1) int64: cell offsets; the grid size (a, b, c) of each level (cell (i b + j) c + k);
      the aggregation factors (rx, ry, rz) from level l to level l + 1
  MGI (N, 13) int64: per cell its 6 neighbours (-x, +x, -y, +y, -z, +z; local index, -1 none), the
      Galerkin target of each of those 6 entries in MGA (flat index row * 7 + slot, slot 0 the diagonal;
      -1 none), and the coarse cell (local index) of this cell
  MGA (N, 7): matrix rows (diagonal, then the 6 neighbour coefficients)
  MGS (N, 8) float32: the rows of MGA, then 1 / diagonal (32 bytes a row)
  MGW (3, N): x, b (coarse levels; the finest level works in GMRES's vectors), the cycle's visit count of
      each level (first entries)
  DLU (m, m) + PIV (m): dense LU of the coarsest level, partial pivoting
  KRY (2 (restart + 1), n): GMRES basis V and preconditioned vectors Z
  HES (restart + 4, restart + 1): Hessenberg matrix, then rows of Givens cosines, sines, rhs
"""
import numpy as np
from numba import njit

MG_X, MG_B, MG_R = 0, 1, 2
MGI_NB, MGI_GAL, MGI_AGG = 0, 6, 12
NS = 7  # slots of a matrix row
SWEEPS = 2  # Gauss-Seidel sweeps before and after the coarse correction
CYCLES = 2  # cycles of the next coarser level per visit of a level: 1 a V-cycle, 2 a W-cycle


@njit(cache=True, error_model="numpy")
def _mg_level_pass(MGL, MGI, MGA, MGS, l):
    """One pass over the rows of level l: their single-precision copies and 1 / diagonal (MGS) and, but
    on the coarsest level, the sums of Pᵀ A P into the rows of level l + 1 (``_mg_coarse_rows`` scales
    them). The Galerkin target of an entry (row g, neighbour d) is the diagonal of g's coarse cell where
    the neighbour shares it, else that cell's entry d; inside the level's box it follows from (i, j, k)
    and the aggregation factors, on the box's faces (wrap-arounds) from MGI. Returns False where a
    diagonal is 0 (level 0) or its inverse is not finite (coarse levels)."""
    levels = MGL.shape[1] - 1
    o0, o1 = MGL[0, l], MGL[0, l + 1]
    a, b, c = MGL[1, l], MGL[2, l], MGL[3, l]
    last = l == levels - 1
    flat = MGA.reshape(MGA.size)
    rx, ry, rz, bc, cc = 1, 1, 1, 1, 1
    if not last:
        rx, ry, rz = MGL[4, l], MGL[5, l], MGL[6, l]
        bc, cc = MGL[2, l + 1], MGL[3, l + 1]
        for g in range(o1, MGL[0, l + 2]):
            for s in range(NS):
                MGA[g, s] = 0.0
    for i in range(a):
        edge_i = i == 0 or i == a - 1
        mx, px = i % rx != 0, i % rx != rx - 1  # the -x / +x neighbour in the same coarse cell
        for j in range(b):
            edge_ij = edge_i or j == 0 or j == b - 1
            my, py = j % ry != 0, j % ry != ry - 1
            g0 = o0 + (i * b + j) * c
            t0 = o1 + ((i // rx) * bc + j // ry) * cc
            for k in range(c):
                g = g0 + k
                d = MGA[g, 0]
                inv = 1.0 / d
                if (d == 0.0) if l == 0 else not np.isfinite(inv):
                    return False
                for s in range(NS):
                    MGS[g, s] = MGA[g, s]
                MGS[g, NS] = inv
                if last:
                    continue
                T = (t0 + k // rz) * NS
                flat[T] += d
                if edge_ij or k == 0 or k == c - 1:
                    for e in range(6):
                        t = MGI[g, MGI_GAL + e]
                        if t >= 0:
                            flat[t] += MGA[g, 1 + e]
                else:
                    mz, pz = k % rz != 0, k % rz != rz - 1
                    flat[T if mx else T + 1] += MGA[g, 1]
                    flat[T if px else T + 2] += MGA[g, 2]
                    flat[T if my else T + 3] += MGA[g, 3]
                    flat[T if py else T + 4] += MGA[g, 4]
                    flat[T if mz else T + 5] += MGA[g, 5]
                    flat[T if pz else T + 6] += MGA[g, 6]
    return True


@njit(cache=True, error_model="numpy")
def _mg_coarse_rows(MGL, MGA, l):
    """The rows of level l + 1 from their sums of Pᵀ A P (``_mg_level_pass`` of level l)."""
    # Pᵀ A P multiplies the coupling along an axis of a diffusion operator by that axis's aggregation
    # factor against its discretisation on the coarse grid (r_b r_c fine faces per coarse face, the ratio
    # area / distance r_b r_c / r_a); its row sums (the compressibility, the boundaries) are right:
    # divide the couplings, keep the row sums
    for g in range(MGL[0, l + 1], MGL[0, l + 2]):
        rs = 0.0
        for s in range(NS):
            rs += MGA[g, s]
        off = 0.0
        for d in range(6):
            MGA[g, 1 + d] /= MGL[4 + d // 2, l]
            off += MGA[g, 1 + d]
        MGA[g, 0] = rs - off


@njit(cache=True, error_model="numpy")
def mg_setup(data, csc_ell, MGL, MGI, MGA, MGS, MGW, DLU, PIV):
    """The multigrid hierarchy of the CSC matrix ``data`` (its entries go to MGA rows by ``csc_ell``: flat
    index cell * 7 + slot, each slot at most once; then the slots of level 0 that no entry fills, set to
    0), with the smoother's single-precision copy MGS, one pass over the rows of each level; returns False
    if a diagonal or the coarsest LU is singular."""
    levels = MGL.shape[1] - 1
    flat = MGA.reshape(MGA.size)
    for q in range(data.size):
        flat[csc_ell[q]] = data[q]
    for q in range(data.size, csc_ell.size):
        flat[csc_ell[q]] = 0.0
    for l in range(levels):
        if not _mg_level_pass(MGL, MGI, MGA, MGS, l):
            return False
        if l < levels - 1:
            _mg_coarse_rows(MGL, MGA, l)
    oc = MGL[0, levels - 1]
    m = MGL[0, levels] - oc
    for i in range(m):
        for j in range(m):
            DLU[i, j] = 0.0
    for i in range(m):
        g = oc + i
        DLU[i, i] += MGA[g, 0]
        for d in range(6):
            c = MGI[g, MGI_NB + d]
            if c >= 0:
                DLU[i, c] += MGA[g, 1 + d]
    for k in range(m):
        p = k
        big = abs(DLU[k, k])
        for i in range(k + 1, m):
            if abs(DLU[i, k]) > big:
                big = abs(DLU[i, k])
                p = i
        PIV[k] = p
        if big == 0.0:
            return False
        if p != k:
            for j in range(m):
                tmp = DLU[k, j]
                DLU[k, j] = DLU[p, j]
                DLU[p, j] = tmp
        inv = 1.0 / DLU[k, k]
        for i in range(k + 1, m):
            lik = DLU[i, k] * inv
            DLU[i, k] = lik
            if lik != 0.0:
                for j in range(k + 1, m):
                    DLU[i, j] -= lik * DLU[k, j]
    return True


@njit(cache=True, error_model="numpy", inline="always")
def _mg_wraps(MGL, MGI, l):
    """The offsets (local index of the neighbour − the cell's) of the −x, +x, −y, +y, −z, +z neighbours of the
    cells on the faces of level l's box: the wrap-around of a periodic axis, 0 where the face has no neighbour
    (that matrix entry is 0: ``mg_setup``). The same on the whole face of a box grid, read from MGI at
    the cells (0, 0, 0), (a − 1, 0, 0), (0, b − 1, 0) and (0, 0, c − 1)."""
    o0, a, b, c = MGL[0, l], MGL[1, l], MGL[2, l], MGL[3, l]
    last = ((a - 1) * b * c, (b - 1) * c, c - 1)
    return (_mg_wrap(MGI, o0, 0, 0), _mg_wrap(MGI, o0, last[0], 1), _mg_wrap(MGI, o0, 0, 2),
            _mg_wrap(MGI, o0, last[1], 3), _mg_wrap(MGI, o0, 0, 4), _mg_wrap(MGI, o0, last[2], 5))


@njit(cache=True, error_model="numpy", inline="always")
def _mg_wrap(MGI, o0, q, d):
    """Offset of the neighbour d of the cell of local index q (0: none)."""
    n = MGI[o0 + q, MGI_NB + d]
    return n - q if n >= 0 else 0


@njit(cache=True, error_model="numpy", inline="always")
def _mg_row(MGA, X, g, oxm, oxp, oym, oyp, ozm, ozp):
    """Σ_d A[g, d] x[neighbour d] of cell g, its neighbours at g + the offsets (``_mg_wraps`` on the box's
    faces: a face without a neighbour reads x[g] with its entry 0, which adds nothing); MGA: the float64
    rows or the float32 MGS."""
    return (MGA[g, 1] * X[g + oxm] + MGA[g, 2] * X[g + oxp] + MGA[g, 3] * X[g + oym] + MGA[g, 4] * X[g + oyp]
            + MGA[g, 5] * X[g + ozm] + MGA[g, 6] * X[g + ozp])


@njit(cache=True, error_model="numpy", inline="always")
def _mg_axis(i, n, step, wm, wp):
    """(−, +) neighbour offsets of index i along an axis of n cells, ``step`` apart, wrap offsets wm, wp."""
    return (-step if i > 0 else wm), (step if i < n - 1 else wp)


@njit(cache=True, error_model="numpy", inline="always")
def _mg_line_gauss_seidel(MGS, X, B, g0, c, oxm, oxp, oym, oyp, forward, W):
    """Gauss-Seidel update of the c cells g0 … g0 + c − 1 of one z line, in increasing (``forward``) or
    decreasing order: x_g = (b_g - Σ_d A[g, d] x[neighbour d]) / A[g, g]; neighbour offsets along x and y
    given, W: ``_mg_wraps``."""
    if c == 1:
        X[g0] = (B[g0] - _mg_row(MGS, X, g0, oxm, oxp, oym, oyp, W[4], W[5])) * MGS[g0, 7]
        return
    fm, fp = (W[4], 1) if forward else (-1, W[5])  # −z, +z offsets of the line's first cell in this order
    lm, lp = (-1, W[5]) if forward else (W[4], 1)  # and of its last
    g = g0 if forward else g0 + c - 1
    X[g] = (B[g] - _mg_row(MGS, X, g, oxm, oxp, oym, oyp, fm, fp)) * MGS[g, 7]
    for kk in range(1, c - 1):
        g = g0 + (kk if forward else c - 1 - kk)
        X[g] = (B[g] - _mg_row(MGS, X, g, oxm, oxp, oym, oyp, -1, 1)) * MGS[g, 7]
    g = g0 + c - 1 if forward else g0
    X[g] = (B[g] - _mg_row(MGS, X, g, oxm, oxp, oym, oyp, lm, lp)) * MGS[g, 7]


@njit(cache=True, error_model="numpy", inline="always")
def _mg_plane_gauss_seidel(MGL, MGS, X, B, l, i, forward, W):
    """Gauss-Seidel update of the cells of plane i (x index) of level l, rows j then cells k in increasing
    (``forward``) or decreasing order (``_mg_line_gauss_seidel``). W: ``_mg_wraps``."""
    o0, a, b, c = MGL[0, l], MGL[1, l], MGL[2, l], MGL[3, l]
    oxm, oxp = _mg_axis(i, a, b * c, W[0], W[1])
    for jj in range(b):
        j = jj if forward else b - 1 - jj
        oym, oyp = _mg_axis(j, b, c, W[2], W[3])
        _mg_line_gauss_seidel(MGS, X, B, o0 + (i * b + j) * c, c, oxm, oxp, oym, oyp, forward, W)


@njit(cache=True, error_model="numpy", inline="always")
def _mg_plane_restrict(MGL, MGS, X, B, BC, l, i, W):
    """Adds Pᵀ (b - A x) of plane i of level l (x, b in X, B) to b of level l + 1 (in BC; the coarse cell of
    (i, j, k) is ((i // rx) b' + j // ry) c' + k // rz). W: ``_mg_wraps``."""
    o0, a, b, c = MGL[0, l], MGL[1, l], MGL[2, l], MGL[3, l]
    rx, ry, rz = MGL[4, l], MGL[5, l], MGL[6, l]
    o1, bc, cc = MGL[0, l + 1], MGL[2, l + 1], MGL[3, l + 1]
    oxm, oxp = _mg_axis(i, a, b * c, W[0], W[1])
    for j in range(b):
        oym, oyp = _mg_axis(j, b, c, W[2], W[3])
        g0 = o0 + (i * b + j) * c
        t0 = o1 + ((i // rx) * bc + j // ry) * cc
        for k in range(c):
            g = g0 + k
            ozm, ozp = _mg_axis(k, c, 1, W[4], W[5])
            r = B[g] - MGS[g, 0] * X[g] - _mg_row(MGS, X, g, oxm, oxp, oym, oyp, ozm, ozp)
            BC[t0 + k // rz] += r


@njit(cache=True, error_model="numpy", inline="always")
def _mg_plane_prolong(MGL, X, XC, l, i):
    """x of plane i of level l (in X) += x of its coarse cells on level l + 1 (in XC; P: piecewise
    constant)."""
    o0, b, c = MGL[0, l], MGL[2, l], MGL[3, l]
    rx, ry, rz = MGL[4, l], MGL[5, l], MGL[6, l]
    o1, bc, cc = MGL[0, l + 1], MGL[2, l + 1], MGL[3, l + 1]
    for j in range(b):
        g0 = o0 + (i * b + j) * c
        t0 = o1 + ((i // rx) * bc + j // ry) * cc
        for k in range(c):
            X[g0 + k] += XC[t0 + k // rz]


@njit(cache=True, error_model="numpy", inline="always")
def _mg_plane_zero(MGL, X, l, i):
    o0, b, c = MGL[0, l], MGL[2, l], MGL[3, l]
    for g in range(o0 + i * b * c, o0 + (i + 1) * b * c):
        X[g] = 0.0


@njit(cache=True, error_model="numpy")
def _mg_presmooth_restrict(MGL, MGI, MGS, X, B, BC, l, wrap, zero):
    """SWEEPS forward Gauss-Seidel sweeps of level l (x, b in X, B; from x = 0 if ``zero``), then b of
    level l + 1 (in BC) = Pᵀ (b - A x), in one pass over the planes: sweep s updates plane t - s at step t
    (its lower neighbour plane has had sweep s, its upper one sweep s - 1: the same updates as SWEEPS whole
    sweeps one after the other, but along a periodic x, where the last planes' first sweep reads plane 0
    after its second), and the residual of plane t - SWEEPS, final by then, is restricted at
    once, while the planes are still in the cache; x = 0 is set a plane ahead of the first sweep.
    ``wrap``: the level is periodic along x (plane 0's residual waits for the last plane)."""
    o1, o2, a = MGL[0, l + 1], MGL[0, l + 2], MGL[1, l]
    W = _mg_wraps(MGL, MGI, l)
    for g in range(o1, o2):
        BC[g] = 0.0
    if zero:
        _mg_plane_zero(MGL, X, l, 0)
        if wrap:
            _mg_plane_zero(MGL, X, l, a - 1)
    for t in range(a + SWEEPS):
        if zero and t + 1 < a:
            _mg_plane_zero(MGL, X, l, t + 1)
        for s in range(SWEEPS):
            i = t - s
            if 0 <= i < a:
                _mg_plane_gauss_seidel(MGL, MGS, X, B, l, i, True, W)
        i = t - SWEEPS
        if i >= (1 if wrap else 0):
            _mg_plane_restrict(MGL, MGS, X, B, BC, l, i, W)
    if wrap:
        _mg_plane_restrict(MGL, MGS, X, B, BC, l, 0, W)


@njit(cache=True, error_model="numpy")
def _mg_prolong_postsmooth(MGL, MGI, MGS, X, B, XC, l, wrap):
    """x of level l (in X) += P x of level l + 1 (in XC), then SWEEPS backward Gauss-Seidel sweeps, in one
    pass over the planes from the last (each plane corrected just before the first sweep reads it;
    ``wrap``: periodic along x, plane 0 corrected first as the last plane reads it)."""
    a = MGL[1, l]
    W = _mg_wraps(MGL, MGI, l)
    _mg_plane_prolong(MGL, X, XC, l, a - 1)
    if wrap and a > 1:
        _mg_plane_prolong(MGL, X, XC, l, 0)
    for t in range(a + SWEEPS - 1):
        i = a - 2 - t
        if i >= (1 if wrap else 0):
            _mg_plane_prolong(MGL, X, XC, l, i)
        for s in range(SWEEPS):
            i = a - 1 - t + s
            if 0 <= i < a:
                _mg_plane_gauss_seidel(MGL, MGS, X, B, l, i, False, W)


@njit(cache=True, error_model="numpy")
def _mg_coarsest(MGL, DLU, PIV, X, B):
    """x = A^-1 b on the coarsest level: forward / back substitution with the pivots of DLU."""
    levels = MGL.shape[1] - 1
    oc = MGL[0, levels - 1]
    m = MGL[0, levels] - oc
    for i in range(m):
        X[oc + i] = B[oc + i]
    for k in range(m):
        p = PIV[k]
        if p != k:
            tmp = X[oc + k]
            X[oc + k] = X[oc + p]
            X[oc + p] = tmp
        xk = X[oc + k]
        for i in range(k + 1, m):
            X[oc + i] -= DLU[i, k] * xk
    for k in range(m - 1, -1, -1):
        s = X[oc + k]
        for j in range(k + 1, m):
            s -= DLU[k, j] * X[oc + j]
        X[oc + k] = s / DLU[k, k]


@njit(cache=True, error_model="numpy")
def mg_cycle(MGL, MGI, MGA, MGS, MGW, DLU, PIV, b, x):
    """x ≈ A^-1 b by one W-cycle (a fixed linear operator: the preconditioner of ``gmres``): on each level
    SWEEPS forward Gauss-Seidel sweeps, CYCLES cycles of the next level on the restricted residual (one if
    that level has more than a quarter of this one's cells, which keeps the work per cycle within twice
    the finest level's; one on the coarsest, solved exactly), then SWEEPS backward sweeps. The finest level
    works in b and x themselves, the others in MGW. Driven by a loop over the visit counts of the levels
    (MGW[MG_R, :levels]), not by recursion."""
    levels = MGL.shape[1] - 1
    X, B, VISITS = MGW[MG_X], MGW[MG_B], MGW[MG_R]
    top = levels - 1
    if top == 0:  # one level: the grid is the coarsest, solved exactly
        for g in range(b.size):
            B[g] = b[g]
        _mg_coarsest(MGL, DLU, PIV, X, B)
        for g in range(b.size):
            x[g] = X[g]
        return
    l = np.int64(0)  # a run-time integer: with a literal 0 the level-0 calls would compile once more for it
    VISITS[0] = 0.0
    down = True
    while True:
        if down:
            if l == top:
                _mg_coarsest(MGL, DLU, PIV, X, B)
                down = False
                continue
            wrap = MGL[1, l] > 1 and MGI[MGL[0, l], MGI_NB] >= 0
            if l == 0:
                _mg_presmooth_restrict(MGL, MGI, MGS, x, b, B, l, wrap, np.bool_(True))
            else:
                _mg_presmooth_restrict(MGL, MGI, MGS, X, B, B, l, wrap, VISITS[l] == 0.0)
            l += 1
            VISITS[l] = 0.0  # its first cycle starts from x = 0
        else:
            if l == 0:
                break
            VISITS[l] += 1.0
            if l < top and VISITS[l] < CYCLES and 4 * (MGL[0, l + 1] - MGL[0, l]) <= MGL[0, l] - MGL[0, l - 1]:
                down = True  # again on level l, from where the last cycle left x
                continue
            l -= 1
            wrap = MGL[1, l] > 1 and MGI[MGL[0, l], MGI_NB] >= 0
            if l == 0:
                _mg_prolong_postsmooth(MGL, MGI, MGS, x, b, X, l, wrap)
            else:
                _mg_prolong_postsmooth(MGL, MGI, MGS, X, B, X, l, wrap)


@njit(cache=True, error_model="numpy")
def mg_matvec(MGL, MGI, MGA, x, y):
    """y = A x with the finest level of the hierarchy."""
    a, b, c = MGL[1, 0], MGL[2, 0], MGL[3, 0]
    W = _mg_wraps(MGL, MGI, 0)
    for i in range(a):
        oxm, oxp = _mg_axis(i, a, b * c, W[0], W[1])
        for j in range(b):
            oym, oyp = _mg_axis(j, b, c, W[2], W[3])
            for k in range(c):
                g = (i * b + j) * c + k
                ozm, ozp = _mg_axis(k, c, 1, W[4], W[5])
                y[g] = MGA[g, 0] * x[g] + _mg_row(MGA, x, g, oxm, oxp, oym, oyp, ozm, ozp)


@njit(cache=True, error_model="numpy")
def gmres(MGL, MGI, MGA, MGS, MGW, DLU, PIV, KRY, HES, b, x, target, max_iter):
    """x ≈ A^-1 b by restarted GMRES with the multigrid cycle (``mg_cycle``) as right preconditioner, from x = 0,
    until ||b - A x||_2 <= target. Returns the iterations made, or -1 when ``max_iter`` were not enough."""
    n = b.size
    m = HES.shape[1] - 1
    Vb = KRY[: m + 1]
    Zb = KRY[m + 1:]
    Hh = HES[: m + 1]
    cs, sn, gv = HES[m + 1], HES[m + 2], HES[m + 3]
    for i in range(n):
        x[i] = 0.0
    r = Vb[0]
    for i in range(n):
        r[i] = b[i]
    its = 0
    while True:
        beta = 0.0
        for i in range(n):
            beta += r[i] * r[i]
        beta = np.sqrt(beta)
        if beta <= target:
            return its
        if its >= max_iter:
            return -1
        v0 = Vb[0]
        for i in range(n):
            v0[i] = r[i] / beta
        for k in range(m + 1):
            gv[k] = 0.0
        gv[0] = beta
        k_used = 0
        for k in range(m):
            mg_cycle(MGL, MGI, MGA, MGS, MGW, DLU, PIV, Vb[k], Zb[k])
            w = Vb[k + 1]
            mg_matvec(MGL, MGI, MGA, Zb[k], w)
            for jj in range(k + 1):  # modified Gram-Schmidt
                vj = Vb[jj]
                hsum = 0.0
                for i in range(n):
                    hsum += w[i] * vj[i]
                Hh[jj, k] = hsum
                for i in range(n):
                    w[i] -= hsum * vj[i]
            hn = 0.0
            for i in range(n):
                hn += w[i] * w[i]
            hn = np.sqrt(hn)
            Hh[k + 1, k] = hn
            if hn > 0.0:
                for i in range(n):
                    w[i] /= hn
            for jj in range(k):  # earlier rotations
                h0, h1 = Hh[jj, k], Hh[jj + 1, k]
                Hh[jj, k] = cs[jj] * h0 + sn[jj] * h1
                Hh[jj + 1, k] = -sn[jj] * h0 + cs[jj] * h1
            h0, h1 = Hh[k, k], Hh[k + 1, k]
            den = np.sqrt(h0 * h0 + h1 * h1)
            if den == 0.0:
                cs[k], sn[k] = 1.0, 0.0
            else:
                cs[k], sn[k] = h0 / den, h1 / den
            Hh[k, k] = den
            Hh[k + 1, k] = 0.0
            gv[k + 1] = -sn[k] * gv[k]
            gv[k] = cs[k] * gv[k]
            its += 1
            k_used = k + 1
            if abs(gv[k + 1]) <= target or its >= max_iter or hn == 0.0:
                break
        for jj in range(k_used - 1, -1, -1):  # y = H^-1 g, x += Z y
            s = gv[jj]
            for q in range(jj + 1, k_used):
                s -= Hh[jj, q] * gv[q]
            gv[jj] = s / Hh[jj, jj]
        for jj in range(k_used):
            z = Zb[jj]
            y = gv[jj]
            for i in range(n):
                x[i] += y * z[i]
        mg_matvec(MGL, MGI, MGA, x, r)  # true residual for the restart test
        for i in range(n):
            r[i] = b[i] - r[i]
