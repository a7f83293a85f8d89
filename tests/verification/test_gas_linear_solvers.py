"""The linear solvers of the pressure correction give the same converged gas steps.

``GasSolver(linear_solver=...)``: "band" (compiled block-tridiagonal LU, refactorised only from
the first block whose matrix rows changed), "multigrid" (compiled GMRES with an aggregation
multigrid V-cycle, for large grids) and "superlu" (SciPy) all stop the Newton iterations at the
same mass-residual tolerance, so their steps agree to what that tolerance leaves open.
"""
import numpy as np
import pytest

from fluidem.gas import (
    GasProperties,
    GasSolver,
    Inflow,
    Periodic,
    PressureOutlet,
    Segment,
    StaggeredGrid,
    Wall,
)
from fluidem.errors import CaseError
from fluidem.gas import _layout as lay
from fluidem.bench import gas_bench_problem as _bench_problem


def bed_steps(nx, ny, linear_solver, steps, **kw):
    """``steps`` steps of the benchmark jet bed (moving voidage, Ergun β) with one linear solver."""
    solver, state, beta_of, voidage_at = _bench_problem(nx, ny)
    solver = GasSolver(solver.grid, solver.props, solver.boundaries, linear_solver=linear_solver, **kw)
    state = solver.initial_state(voidage=state.voidage)
    dt = min(1e-4, 0.5 * min(solver.grid.dx, solver.grid.dy) / 45.0)
    infos = []
    for k in range(steps):
        t = k * dt
        infos.append(solver.advance(state, dt, t, voidage=voidage_at(t + dt), beta=beta_of(state),
                                    solids_u=0.0, solids_v=0.0))
    return solver, state, infos


def assert_same_steps(a, b):
    """Two states after steps converged to the mass-residual tolerance 1e-10: pressures (1e5 Pa,
    differences of a few kPa) to 1e-10 relative, velocities (up to 45 m/s) to 1e-7 m/s."""
    np.testing.assert_allclose(a.p, b.p, rtol=1e-10, atol=0)
    for k in ("u", "v"):
        np.testing.assert_allclose(getattr(a, k), getattr(b, k), rtol=0, atol=1e-7)


def test_auto_choice_by_grid_size():
    assert _bench_problem(15, 25)[0].linear_solver == "band"
    assert _bench_problem(64, 100)[0].linear_solver == "band"
    assert _bench_problem(65, 100)[0].linear_solver == "multigrid"
    assert _bench_problem(150, 300)[0].linear_solver == "multigrid"
    periodic = {s: Periodic() for s in ("left", "right", "bottom", "top")}
    solver = GasSolver(StaggeredGrid(cells=(8, 6), size=(0.08, 0.06)), GasProperties(), periodic)
    assert solver.linear_solver == "multigrid"


def test_multigrid_equals_the_direct_solve_on_150_by_300():
    mg, s_mg, i_mg = bed_steps(150, 300, "multigrid", 2)
    lu, s_lu, i_lu = bed_steps(150, 300, "superlu", 2)
    assert mg.linear_solver == "multigrid" and lu.linear_solver == "superlu"
    assert all(i.converged for i in i_mg + i_lu)
    assert mg.krylov_iterations > 0
    assert_same_steps(s_mg, s_lu)
    for a, b in zip(i_mg, i_lu):
        assert a.mass == pytest.approx(b.mass, rel=1e-12)
        assert a.mass_balance_error < 1e-8 and b.mass_balance_error < 1e-8


def test_band_refactorises_only_the_blocks_that_changed_and_equals_superlu():
    band, s_band, i_band = bed_steps(15, 45, "band", 30)
    _, s_lu, _ = bed_steps(15, 45, "superlu", 30)
    assert band.linear_solver == "band" and all(i.converged for i in i_band)
    assert_same_steps(s_band, s_lu)
    # the blocks are numbered from the pressure outlet at the top; the bed (moving voidage) is below
    # 0.2 m of 0.5 m, so the blocks above it keep their factors
    blocks = band._ipar[lay.I_BLOCKS]
    assert band.factorisations > 1 and blocks < 0.8 * band.factorisations * band._band.shape[0]


@pytest.mark.parametrize("nx, ny", [(1, 3), (1, 4), (2, 3), (3, 2), (5, 9), (13, 20), (17, 6)])
def test_band_equals_superlu_on_small_and_padded_grids(nx, ny):
    """The band blocks are padded with zero columns to a multiple of 4 where the work rows hold them
    (``GasSolver``: 15 → 16, 13 → 16; not for a grid of fewer cells than that): the same steps as SuperLU."""
    band, s_band, i_band = bed_steps(nx, ny, "band", 5)
    lu, s_lu, i_lu = bed_steps(nx, ny, "superlu", 5)
    assert band.linear_solver == "band" and all(i.converged for i in i_band + i_lu)
    bw = band._band.shape[1]
    assert band._band.shape[2] == (-(-bw // 4) * 4 if -(-bw // 4) * 4 <= nx * ny else bw)
    assert_same_steps(s_band, s_lu)


def test_multigrid_constant_density_and_periodic_sides():
    """Constant density (the matrix is a pure diffusion operator) in a box periodic along x, and
    a box periodic both ways: the multigrid path against SuperLU."""
    grid = StaggeredGrid(cells=(40, 30), size=(0.08, 0.06), depth=0.01)
    rng = np.random.default_rng(3)
    beta = rng.uniform(100.0, 2000.0, grid.shape)
    for bcs, props in (({"left": Periodic(), "right": Periodic(), "bottom": Inflow(superficial=0.5, voidage=0.4),
                         "top": PressureOutlet()}, GasProperties(density=1.2)),
                       ({s: Periodic() for s in ("left", "right", "bottom", "top")}, GasProperties())):
        states = []
        for linear_solver in ("multigrid", "superlu"):
            solver = GasSolver(grid, props, bcs, gravity=(0.3, -9.81), linear_solver=linear_solver)
            state = solver.initial_state(voidage=0.6, velocity=(0.2, 0.1))
            for k in range(5):
                info = solver.advance(state, 1e-4, k * 1e-4, beta=beta, solids_u=0.05,
                                      voidage=0.6 + 0.05 * np.sin(k + np.arange(grid.nx))[:, None] * np.ones(grid.shape))
                assert info.converged
            assert solver.linear_solver == linear_solver
            states.append(state)
        assert_same_steps(*states)


def test_multigrid_gives_way_to_superlu_when_gmres_stalls():
    solver, state, beta_of, voidage_at = _bench_problem(70, 100)
    assert solver.linear_solver == "multigrid"
    solver._ipar[lay.I_KRYLOV_MAX] = 1  # one GMRES iteration cannot reach the target
    info = solver.advance(state, 1e-5, 0.0, voidage=voidage_at(1e-5), beta=beta_of(state), solids_u=0.0,
                          solids_v=0.0)
    assert info.converged and solver.linear_solver == "superlu"


def test_jet_steps_agree_for_all_three_solvers():
    """A small ideal-gas jet through a bed: band, multigrid (forced) and SuperLU, 10 steps."""
    grid = StaggeredGrid(cells=(12, 20), size=(0.06, 0.1), depth=0.004)
    bcs = {"left": Wall(), "right": Wall(), "top": PressureOutlet(),
           "bottom": Inflow(segments=[Segment(interstitial=3.0), Segment(interstitial=30.0, start=0.025, end=0.035)],
                            voidage=0.4)}
    _, Y = grid.centres()
    states = []
    for linear_solver in ("band", "multigrid", "superlu"):
        solver = GasSolver(grid, GasProperties(), bcs, linear_solver=linear_solver)
        state = solver.initial_state(voidage=np.where(Y < 0.05, 0.45, 1.0))
        for k in range(10):
            eps = np.where(Y < 0.05 + 0.001 * k, 0.45, 1.0)
            info = solver.advance(state, 5e-5, k * 5e-5, voidage=eps, beta=np.where(eps < 0.8, 3000.0, 0.0))
            assert info.converged
        states.append(state)
    assert_same_steps(states[0], states[2])
    assert_same_steps(states[1], states[2])


def test_pyamg_is_refused_with_the_solvers_allowed():
    grid = StaggeredGrid(cells=(12, 20), size=(0.06, 0.1), depth=0.004)
    bcs = {"left": Wall(), "right": Wall(), "top": PressureOutlet(), "bottom": Inflow(superficial=1.0, voidage=0.4)}
    with pytest.raises(CaseError, match=r"gas.linear_solver = 'pyamg': not offered: 'multigrid' .* faster .*; "
                                        r"allowed are 'auto', 'band', 'multigrid', 'superlu'$"):
        GasSolver(grid, GasProperties(), bcs, linear_solver="pyamg")


def test_pyamg_in_a_case_is_refused_with_the_reason():
    from fluidem.case import load_case

    with pytest.raises(CaseError, match=r"gas.linear_solver = 'pyamg': not offered: 'multigrid' .* faster"):
        load_case("tsuji-jet-background", {"gas.linear_solver": "pyamg"})
