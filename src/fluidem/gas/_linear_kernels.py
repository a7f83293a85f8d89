"""Compiled direct solvers of sparse linear systems A x = b, independent of the equations behind A.

Two of them: the triangular solves of given sparse LU factors (``lu_solve``, with the factors of
SciPy's SuperLU), and a block-tridiagonal LU for matrices that are block tridiagonal in a given
numbering of the unknowns (``band_factor``, ``band_solve``): a 5-point matrix on a grid numbered
along one direction first. Matrices come as CSC arrays (data, indices, indptr); the caller owns
every array, work arrays included.

Speed: on the small grids of coupled runs the cost follows the chains of dependent operations more
than the operation count; hence the band solve works on blocks of unknowns (dense mat-vecs, one
dependent step per block) and indexes with unsigned integers (no wrap-around code).
"""
import numpy as np
from numba import njit

UI = np.uintp  # unsigned array index: no wrap-around code for negative indices

# LUI (4, n + 1) int64, the index arrays of SuperLU factors Pr A Pc = L U (``lu_solve``):
#   L_LP      column pointers of L (strictly lower, unit diagonal), CSC
#   L_UP      column pointers of U (strictly upper; its diagonal apart), CSC
#   L_PERM_R  the row permutation Pr (first n entries)
#   L_PERM_C  the column permutation Pc (first n entries)
L_LP, L_UP, L_PERM_R, L_PERM_C = 0, 1, 2, 3


@njit(cache=True, error_model="numpy")
def lu_solve(LUI, Li, Lx, Ui, Ux, Ud, b, x, w):
    """x = A^-1 b from SuperLU factors Pr A Pc = L U: L strictly lower (unit diagonal), U strictly
    upper plus its diagonal Ud, both CSC; w[perm_r] = b, then x = (U^-1 L^-1 w)[perm_c]."""
    n = b.size
    Lp, Up, perm_r, perm_c = LUI[L_LP], LUI[L_UP], LUI[L_PERM_R], LUI[L_PERM_C]
    for i in range(n):
        w[perm_r[i]] = b[i]
    for j in range(n):
        wj = w[j]
        if wj != 0.0:
            for k in range(Lp[j], Lp[j + 1]):
                w[Li[k]] -= Lx[k] * wj
    for j in range(n - 1, -1, -1):
        wj = w[j] / Ud[j]
        w[j] = wj
        if wj != 0.0:
            for k in range(Up[j], Up[j + 1]):
                w[Ui[k]] -= Ux[k] * wj
    for i in range(n):
        x[i] = w[perm_c[i]]


# ---------------------------------------------------------------------------- block-tridiagonal LU ("band")
# With the unknowns numbered along one grid direction first (m = its number of cells, the band
# half-width), the 5-point matrix is block tridiagonal: nb = n / m dense diagonal blocks D_j (m × m,
# tridiagonal, plus corners for a periodic direction) and diagonal couplings lo_j, up_j to the
# blocks before and after. Block LU: S_0 = D_0, S_j = D_j - diag(lo_j) S_{j-1}^-1 diag(up_{j-1});
# the inverses S_j^-1 are kept, so that a solve is 2 nb dense mat-vecs (one dependent step per
# block instead of one per unknown):
#     y_j = S_j^-1 (b_j - lo_j ∘ y_{j-1}),   x_j = y_j - S_j^-1 (up_j ∘ x_{j+1})
# BINV (nb, m, m) holds S_j^-1 transposed (BINV[j, c, r] = (S_j^-1)[r, c]); BLU (2, nb, m) lo and up.
@njit(cache=True, error_model="numpy")
def _invert_in_place(A, rows):
    """A^-1 in place by Gauss-Jordan elimination without pivoting (A diagonally dominant), the
    pivots taken two at a time so that every other row is updated in one pass; ``rows`` (2, ≥ m)
    is work. Returns the smallest |pivot|, 0 if one vanished.

    A may have more columns than rows (m × mp, mp ≥ m), the extra ones zero: they stay zero, and the
    row operations run over mp columns, a multiple of the vector width (``GasSolver`` pads the band
    blocks so): 45 blocks of 15 × 15 take 108 µs, of 16 × 16 97 µs, the real entries the same bits.
    Written with two-index subscripts only: a row view ``A[r]`` in the loops cost an atomic
    reference-count increment and decrement each (120 per 15 × 15 block), a fifth of the time
    (137 → 108 µs, the same bits); unsigned indices spare the wrap-around code."""
    m = A.shape[0]
    mp = A.shape[1]
    pmin = np.inf
    k = 0
    while k < m:
        two = k + 1 < m
        for q in range(2 if two else 1):  # eliminate inside the pair of rows k, k + 1
            kk = UI(k + q)
            piv = A[kk, kk]
            pmin = min(pmin, abs(piv))
            if piv == 0.0:
                return 0.0
            inv = 1.0 / piv
            A[kk, kk] = 1.0
            for c in range(mp):
                A[kk, UI(c)] *= inv
            if two:
                ko = UI(k + 1 - q)
                f = A[ko, kk]
                A[ko, kk] = 0.0
                for c in range(mp):
                    A[ko, UI(c)] -= f * A[kk, UI(c)]
        uk = UI(k)
        if not two:  # the last pivot alone, on the rows above it
            for c in range(mp):
                rows[UI(0), UI(c)] = A[uk, UI(c)]
            for r in range(k):
                ur = UI(r)
                f = A[ur, uk]
                if f != 0.0:
                    A[ur, uk] = 0.0
                    for c in range(mp):
                        A[ur, UI(c)] -= f * rows[UI(0), UI(c)]
            break
        uk1 = UI(k + 1)
        for c in range(mp):
            rows[UI(0), UI(c)] = A[uk, UI(c)]
            rows[UI(1), UI(c)] = A[uk1, UI(c)]
        for r in range(m):
            if r == k or r == k + 1:
                continue
            ur = UI(r)
            f0 = A[ur, uk]
            f1 = A[ur, uk1]
            A[ur, uk] = 0.0
            A[ur, uk1] = 0.0
            for c in range(mp):
                A[ur, UI(c)] -= f0 * rows[UI(0), UI(c)] + f1 * rows[UI(1), UI(c)]
        k += 2
    return pmin


@njit(cache=True, error_model="numpy")
def band_factor(data, indices, indptr, place, BINV, BLU, rows, j0):
    """Block-tridiagonal LU (see above) of the CSC matrix (data, indices, indptr) with rows and
    columns renumbered by the band numbering ``order`` of ``band_solve``, given as ``place`` (2, n) int64:
    order // m and order % m (the block of each unknown and its place in it, made once by ``GasSolver``),
    from block ``j0`` on (the blocks before it keep their
    factors: the recursion runs in block order); ``row`` is work (≥ m). Without pivoting, as the
    pressure matrix is diagonally dominant; returns the smallest |pivot| relative to the largest
    |diagonal| so that the caller can check (0 when the matrix is not block tridiagonal in this
    numbering)."""
    nb, m = BINV.shape[0], BINV.shape[1]
    n = nb * m
    lo, up = BLU[0], BLU[1]
    for jb in range(j0, nb):
        for a in range(m):
            lo[jb, a] = 0.0
            up[jb, a] = 0.0
            for b in range(BINV.shape[2]):  # with the padding columns (``_invert_in_place``)
                BINV[jb, a, b] = 0.0
    blk, at = place[0], place[1]  # block of each unknown and its place in it (a division per matrix entry
    # here took 33 µs of a tsuji-jet-background factorisation)
    for col in range(n):
        jc = blk[col]
        ic = at[col]
        for q in range(indptr[col], indptr[col + 1]):
            rk = indices[q]
            jr = blk[rk]
            if jr < j0:
                continue
            ir = at[rk]
            if jr == jc:
                BINV[jr, ic, ir] += data[q]  # the transposed block: inv(Sᵀ) = inv(S)ᵀ
            elif jc == jr - 1 and ic == ir:
                lo[jr, ir] += data[q]
            elif jc == jr + 1 and ic == ir:
                up[jr, ir] += data[q]
            else:
                return 0.0
    dmax = 0.0
    for jb in range(j0, nb):
        for a in range(m):
            dmax = max(dmax, abs(BINV[jb, a, a]))
    pmin = np.inf
    for jb in range(j0, nb):
        St = BINV[jb]
        if jb > 0:  # Sᵀ[b, a] -= up_{j-1}[b] (S_{j-1}^-1)ᵀ[b, a] lo_j[a]
            Pt = BINV[jb - 1]
            for b in range(m):
                ub = up[jb - 1, b]
                if ub != 0.0:
                    for a in range(m):
                        St[b, a] -= ub * Pt[b, a] * lo[jb, a]
        pmin = min(pmin, _invert_in_place(St, rows))
        if pmin == 0.0:
            return 0.0
    return pmin / dmax if dmax > 0.0 else 0.0


@njit(cache=True, error_model="numpy")
def _block_matvec(T, v, y):
    """y = Tᵀ v (T an inverse block stored transposed, m × mp with zero padding columns: y has mp
    entries, the last mp − m zero), two columns per pass."""
    m = T.shape[0]
    mp = T.shape[1]
    for a in range(mp):
        y[a] = 0.0
    c = 0
    while c + 1 < m:  # two-index subscripts: no row views (``_invert_in_place``)
        v0, v1 = v[c], v[c + 1]
        uc, uc1 = UI(c), UI(c + 1)
        for a in range(mp):
            y[UI(a)] += T[uc, UI(a)] * v0 + T[uc1, UI(a)] * v1
        c += 2
    if c < m:
        vc = v[c]
        uc = UI(c)
        for a in range(mp):
            y[UI(a)] += T[uc, UI(a)] * vc


@njit(cache=True, error_model="numpy")
def band_solve(BINV, BLU, order, b, x, w, v, y):
    """x = A^-1 b with the factors of ``band_factor``; w (n), v (≥ m) and y (≥ mp, the padded block
    width) are work."""
    nb, m = BINV.shape[0], BINV.shape[1]
    n = nb * m
    lo, up = BLU[0], BLU[1]
    for k in range(n):  # unsigned indices: no wrap-around code
        w[UI(order[UI(k)])] = b[UI(k)]
    for jb in range(nb):
        base = UI(jb * m)
        if jb > 0:
            for a in range(m):
                v[UI(a)] = w[base + UI(a)] - lo[UI(jb), UI(a)] * w[base - UI(m) + UI(a)]
        else:
            for a in range(m):
                v[UI(a)] = w[base + UI(a)]
        _block_matvec(BINV[jb], v, y)
        for a in range(m):
            w[base + UI(a)] = y[UI(a)]
    for jb in range(nb - 2, -1, -1):
        base = UI(jb * m)
        for c in range(m):
            v[UI(c)] = up[UI(jb), UI(c)] * w[base + UI(m) + UI(c)]
        _block_matvec(BINV[jb], v, y)
        for a in range(m):
            w[base + UI(a)] -= y[UI(a)]
    for k in range(n):
        x[UI(k)] = w[UI(order[UI(k)])]
