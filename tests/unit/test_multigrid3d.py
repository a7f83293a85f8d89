"""GMRES with the aggregation V-cycle of ``_multigrid3d_kernels`` on 3D 7-point Poisson-type matrices.

A multigrid cycle reduces the error by a factor bounded away from 1 independently of the grid spacing
(the textbook property: Trottenberg, Oosterlee & Schüller 2001, Multigrid, ch. 2; for plain aggregation
with the coarse couplings scaled, Braess 1995 and Notay 2010), so the preconditioned GMRES needs a number of
iterations to a given reduction that does not grow with the grid. The bound below is that property with
a contraction of 0.1 per iteration (a V-cycle with two Gauss-Seidel sweeps on each side is a factor 5 to
20 on the Poisson equation): reducing the residual by 1e8 takes at most log(1e-8)/log(0.1) = 8 iterations,
on a grid and on one 64 times larger, and the larger grid needs at most one iteration more. The matrices
are anisotropic (cells twice as tall as wide, couplings 4:1), the case that the semi-coarsening is for.
"""
import numpy as np
import pytest
import scipy.sparse as sp

from fluidem.gas import _multigrid3d_kernels as MK
from fluidem.gas._multigrid3d import multigrid_arrays
from fluidem.gas.solver import COARSEST, KRYLOV_MAX, KRYLOV_RESTART

REDUCTION = 1e-8
BOUND = 8  # log(REDUCTION) / log(0.1)


def poisson(dims, spacing, periodic=(False, False, False), shift=0.0):
    """CSC matrix of -div grad (flux area / distance per face) on a box of ``dims`` cells of ``spacing``,
    a fixed value on the faces of the non-periodic axes (one half-cell away), plus ``shift`` times the
    cell volume on the diagonal; unknown (i ny + j) nz + k is cell (i, j, k). The matrix the gas solver
    assembles has this pattern, with voidage-weighted couplings and a compressibility on the diagonal."""
    nx, ny, nz = dims
    n = nx * ny * nz
    h = np.asarray(spacing, float)
    couple = [h[(q + 1) % 3] * h[(q + 2) % 3] / h[q] for q in range(3)]
    idx = np.arange(n).reshape(dims)
    rows, cols, vals = [], [], []
    diag = np.full(dims, shift * h.prod())
    for q in range(3):
        for step in (-1, 1):
            nb = np.roll(idx, -step, axis=q)
            inside = np.ones(dims, bool)
            if not periodic[q]:
                edge = [slice(None)] * 3
                edge[q] = 0 if step == -1 else -1
                inside[tuple(edge)] = False
                outside = ~inside
                diag[outside] += 2.0 * couple[q]  # the boundary value half a cell away
            diag[inside] += couple[q]
            rows.append(idx[inside])
            cols.append(nb[inside])
            vals.append(np.full(int(inside.sum()), -couple[q]))
    rows.append(idx.ravel())
    cols.append(idx.ravel())
    vals.append(diag.ravel())
    A = sp.csc_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n))
    A.sum_duplicates()
    A.sort_indices()
    return A


def solve(A, dims, spacing, periodic, b):
    h = np.asarray(spacing, float)
    weights = tuple(h[(q + 1) % 3] * h[(q + 2) % 3] / h[q] for q in range(3))
    mg = multigrid_arrays(dims, periodic, A.indices, A.indptr, COARSEST, KRYLOV_RESTART, weights)
    assert mg is not None
    assert MK.mg_setup(A.data, mg.ell, mg.MGL, mg.MGI, mg.MGA, mg.MGS, mg.MGW, mg.DLU, mg.PIV)
    x = np.zeros(b.size)
    its = MK.gmres(mg.MGL, mg.MGI, mg.MGA, mg.MGS, mg.MGW, mg.DLU, mg.PIV, mg.KRY, mg.HES, b, x,
                   REDUCTION * np.linalg.norm(b), KRYLOV_MAX)
    return its, x, mg


@pytest.mark.parametrize("periodic, shift", [((False, False, False), 0.0), ((True, False, False), 1.0)])
def test_vcycle_gmres_reaches_the_tolerance_in_a_bounded_number_of_iterations_on_two_grids(periodic, shift):
    iterations = []
    for m in (12, 48):  # m x m/2 x m cells of 1/m x 2/m x 1/m: 864 and 55,296 cells
        dims, spacing = (m, m // 2, m), (1.0 / m, 2.0 / m, 1.0 / m)
        A = poisson(dims, spacing, periodic, shift)
        rng = np.random.default_rng(m)
        exact = rng.standard_normal(A.shape[0])  # all wavelengths, the smooth ones included
        b = A @ exact
        its, x, _ = solve(A, dims, spacing, periodic, b)
        assert 0 < its <= BOUND
        assert np.linalg.norm(b - A @ x) <= REDUCTION * np.linalg.norm(b)
        # error ≤ condition number × residual; κ of this Laplacian is below 4 m²
        assert np.linalg.norm(x - exact) <= 4 * m**2 * REDUCTION * np.linalg.norm(exact)
        iterations.append(its)
    assert iterations[1] <= iterations[0] + 1


def test_the_weak_axis_is_not_coarsened_until_the_couplings_are_even():
    # cells twice as tall (y) as wide: the y couplings are 4 times weaker; aggregating 2 x 1 x 2 evens them
    dims, spacing = (16, 8, 16), (1.0 / 16, 1.0 / 8, 1.0 / 16)
    A = poisson(dims, spacing)
    h = np.asarray(spacing)
    weights = tuple(h[(q + 1) % 3] * h[(q + 2) % 3] / h[q] for q in range(3))
    mg = multigrid_arrays(dims, (False,) * 3, A.indices, A.indptr, COARSEST, KRYLOV_RESTART, weights)
    assert tuple(mg.MGL[4:7, 0]) == (2, 1, 2)
    assert tuple(mg.MGL[1:4, 1]) == (8, 8, 8)
    assert tuple(mg.MGL[4:7, 1]) == (2, 2, 2)
    # without weights (isotropic): 2 x 2 x 2 from the start
    mg = multigrid_arrays(dims, (False,) * 3, A.indices, A.indptr, COARSEST, KRYLOV_RESTART)
    assert tuple(mg.MGL[4:7, 0]) == (2, 2, 2)


def test_the_vcycle_is_a_fixed_linear_operator():
    # GMRES needs the preconditioner to be the same linear map at every iteration
    dims, spacing = (10, 6, 8), (0.1, 0.2, 0.125)
    A = poisson(dims, spacing, (False, False, True), 0.5)
    _, _, mg = solve(A, dims, spacing, (False, False, True), np.ones(A.shape[0]))
    rng = np.random.default_rng(1)
    u, v = rng.standard_normal((2, A.shape[0]))
    mu, mv, muv = (np.zeros(A.shape[0]) for _ in range(3))
    for rhs, out in ((u, mu), (v, mv), (2.0 * u - 3.0 * v, muv)):
        MK.mg_cycle(mg.MGL, mg.MGI, mg.MGA, mg.MGS, mg.MGW, mg.DLU, mg.PIV, rhs.copy(), out)
    assert np.allclose(muv, 2.0 * mu - 3.0 * mv, rtol=0.0, atol=1e-12 * np.abs(muv).max())


def test_a_grid_as_small_as_the_coarsest_level_is_solved_exactly():
    # 4 x 4 x 4 = 64 cells: one level, the dense LU; GMRES converges in one iteration
    dims, spacing = (4, 4, 4), (0.25, 0.25, 0.25)
    A = poisson(dims, spacing, shift=0.1)
    exact = np.random.default_rng(4).standard_normal(A.shape[0])
    b = A @ exact
    its, x, mg = solve(A, dims, spacing, (False, False, False), b)
    assert mg.MGL.shape[1] - 1 == 1
    assert its == 1
    assert np.abs(x - exact).max() < 1e-10 * np.abs(exact).max()


@pytest.mark.parametrize("periodic", [(False, False, False), (True, False, True)])
def test_the_coarse_matrix_is_the_galerkin_product_with_the_couplings_divided_by_the_aggregation_factors(periodic):
    # level 1 of an 8 x 6 x 8 grid (2 x 1 x 2 aggregation): Pᵀ A P with P the piecewise-constant
    # prolongation, each coupling along axis q divided by that axis's factor and the row sums kept;
    # the set-up starts from an MGA of NaN (the slots no entry of A fills must be set to 0)
    from fluidem.gas._multigrid3d import grid_neighbours

    dims, spacing = (8, 6, 8), (1.0 / 8, 2.0 / 6, 1.0 / 8)
    A = poisson(dims, spacing, periodic, shift=0.7)
    A = A + sp.diags(np.linspace(0.0, 0.3, A.shape[0])) @ abs(A)  # rows of unequal weight, not symmetric
    A = sp.csc_matrix(A)
    A.sort_indices()
    h = np.asarray(spacing)
    weights = tuple(h[(q + 1) % 3] * h[(q + 2) % 3] / h[q] for q in range(3))
    mg = multigrid_arrays(dims, periodic, A.indices, A.indptr, COARSEST, KRYLOV_RESTART, weights)
    assert mg.ell.dtype == np.int32 and mg.MGS.dtype == np.float32
    mg.MGA[:] = np.nan
    assert MK.mg_setup(A.data, mg.ell, mg.MGL, mg.MGI, mg.MGA, mg.MGS, mg.MGW, mg.DLU, mg.PIV)
    r = mg.MGL[4:7, 0]
    coarse = tuple(int(v) for v in mg.MGL[1:4, 1])
    assert tuple(r) == (2, 1, 2) and coarse == (4, 6, 4)
    I, J, K = np.meshgrid(*(np.arange(n) for n in dims), indexing="ij")
    agg = (((I // r[0]) * coarse[1] + J // r[1]) * coarse[2] + K // r[2]).ravel()
    P = sp.csr_matrix((np.ones(agg.size), (np.arange(agg.size), agg)), shape=(agg.size, int(np.prod(coarse))))
    C = (P.T @ A @ P).toarray()
    nb = grid_neighbours(coarse, periodic)
    o1, o2 = mg.MGL[0, 1], mg.MGL[0, 2]
    rows = mg.MGA[o1:o2]
    for t in range(C.shape[0]):
        expected = [C[t, nb[t, d]] / r[d // 2] if nb[t, d] >= 0 else 0.0 for d in range(6)]
        assert np.allclose(rows[t, 1:], expected, rtol=1e-13, atol=0.0)
        assert np.isclose(rows[t, 0], C[t].sum() - sum(expected), rtol=1e-13, atol=0.0)
    n0 = A.shape[0]
    fine = np.zeros((n0, 7))
    fine.reshape(-1)[mg.ell[:A.nnz]] = A.data
    assert np.array_equal(mg.MGA[:n0], fine)  # the finest level: A's entries, 0 in the slots it leaves empty
    assert np.array_equal(mg.MGS[:, :7], mg.MGA.astype(np.float32))
    assert np.allclose(mg.MGS[:, 7], 1.0 / mg.MGA[:, 0], rtol=1e-7)


def _arrays(dims, periodic, seed):
    """A 7-point matrix on ``dims`` (``poisson`` with its entries scaled at random: not symmetric) and its
    hierarchy."""
    A = poisson(dims, (0.1, 0.2, 0.15), periodic, 0.3)
    A.data *= np.random.default_rng(seed).uniform(0.5, 1.5, A.data.size)
    mg = multigrid_arrays(dims, periodic, A.indices, A.indptr, COARSEST, KRYLOV_RESTART)
    assert mg is not None
    assert MK.mg_setup(A.data, mg.ell, mg.MGL, mg.MGI, mg.MGA, mg.MGS, mg.MGW, mg.DLU, mg.PIV)
    return A, mg


@pytest.mark.parametrize("dims", [(3, 2, 1), (2, 3, 3), (1, 4, 2), (5, 1, 3), (4, 3, 5)])
@pytest.mark.parametrize("periodic", [(False, False, False), (True, True, True), (True, False, True),
                                      (False, True, False)])
def test_the_matrix_product_is_scipys_on_every_face_and_wrap_around(dims, periodic):
    # the neighbours of the cells on the box's faces are the wrap-around of a periodic axis (one or two cells
    # thick included: the neighbour is the cell itself or both neighbours are one cell) or none
    A, mg = _arrays(dims, periodic, 5)
    x = np.random.default_rng(6).standard_normal(A.shape[0])
    y = np.zeros_like(x)
    MK.mg_matvec(mg.MGL, mg.MGI, mg.MGA, x, y)
    assert np.allclose(y, A @ x, rtol=0.0, atol=1e-13 * np.abs(A @ x).max())


@pytest.mark.parametrize("dims, periodic", [((12, 5, 3), (False, False, False)), ((10, 4, 3), (True, True, True)),
                                            ((8, 6, 2), (True, False, True)), ((9, 2, 6), (False, True, False))])
def test_the_presmoothing_is_lexicographic_gauss_seidel_with_the_single_precision_rows(dims, periodic):
    # SWEEPS forward sweeps from x = 0 over the cells in the order (i, j, k), done plane by plane as a wave
    # (step t: sweep s on plane t − s), with the rows and 1 / diagonal rounded to float32 as the smoother reads
    # them; then the restricted residual Pᵀ (b − A x). Without a wrap-around along x the wave makes the same
    # updates as whole sweeps one after the other; along a periodic x the last planes' first sweep reads
    # plane 0 after its second
    A, mg = _arrays(dims, periodic, 7)
    assert mg.MGL.shape[1] - 1 >= 2
    n = A.shape[0]
    b = np.random.default_rng(8).standard_normal(n)
    x = np.random.default_rng(9).standard_normal(n)  # overwritten: the sweeps start from 0
    BC = mg.MGW[MK.MG_B]
    wrap = bool(periodic[0]) and dims[0] > 1
    MK._mg_presmooth_restrict(mg.MGL, mg.MGI, mg.MGS, x, b, BC, 0, wrap, True)
    A32 = sp.csr_matrix(A.astype(np.float32).astype(np.float64))
    inv = (1.0 / A.diagonal()).astype(np.float32).astype(np.float64)
    ref = np.zeros(n)
    plane = n // dims[0]
    for t in range(dims[0] + MK.SWEEPS - 1):
        for s in range(MK.SWEEPS):
            if 0 <= t - s < dims[0]:
                for g in range((t - s) * plane, (t - s + 1) * plane):
                    row = slice(A32.indptr[g], A32.indptr[g + 1])
                    cols, vals = A32.indices[row], A32.data[row]
                    off = cols != g
                    ref[g] = (b[g] - vals[off] @ ref[cols[off]]) * inv[g]
    if not periodic[0]:
        whole = np.zeros(n)
        for _ in range(MK.SWEEPS):
            for g in range(n):
                row = slice(A32.indptr[g], A32.indptr[g + 1])
                cols, vals = A32.indices[row], A32.data[row]
                off = cols != g
                whole[g] = (b[g] - vals[off] @ whole[cols[off]]) * inv[g]
        assert np.allclose(ref, whole, rtol=0.0, atol=1e-13 * np.abs(whole).max())
    assert np.allclose(x, ref, rtol=0.0, atol=1e-12 * np.abs(ref).max())
    agg = mg.MGI[:n, MK.MGI_AGG]
    coarse = np.bincount(agg, weights=b - A32 @ ref, minlength=mg.MGL[0, 2] - mg.MGL[0, 1])
    assert np.allclose(BC[mg.MGL[0, 1]:mg.MGL[0, 2]], coarse, rtol=0.0, atol=1e-12 * np.abs(coarse).max())
