"""GasSolver and GasProperties: input checks, initial states, operators and kernels against NumPy."""
import numpy as np
import pytest
import scipy.sparse as sp

from fluidem.errors import CaseError
from fluidem.gas import (GasConvergenceError, GasProperties, GasSolver, GasState, Inflow, PressureOutlet, Segment,
                         StaggeredGrid, StepInfo, Wall)
from fluidem.bench import gas_step_benchmark
from fluidem.gas import _linear_kernels as K
from fluidem.gas._operators import TVD, UPWIND, centre_to_x_faces, centre_to_y_faces, face_value
from fluidem.gas.solver import GAS_CONSTANT

GRID = StaggeredGrid(cells=(5, 4), size=(0.05, 0.08), depth=0.01)


def box(props=None, **kw):
    bcs = {"left": Wall(), "right": Wall(), "bottom": Inflow(superficial=0.5, voidage=0.4),
           "top": PressureOutlet(pressure=101325.0)}
    return GasSolver(GRID, props or GasProperties(), bcs, **kw)


# ------------------------------------------------------------------ properties
def test_ideal_gas_density_is_eq_44():
    props = GasProperties()
    assert props.ideal and props.compressibility == pytest.approx(28.8e-3 / (GAS_CONSTANT * 293.0))
    assert props.density_at(101325.0) == pytest.approx(1.198, abs=1e-3)  # air at 293 K
    const = GasProperties(density=1.2)
    assert not const.ideal and const.compressibility == 0.0 and const.density_at(5e4) == 1.2


@pytest.mark.parametrize("key, value", [("viscosity", -1.8e-5), ("molar_mass", 0.0), ("temperature", -10.0),
                                        ("density", 0.0), ("reference_pressure", float("inf")),
                                        ("viscosity", "thin")])
def test_bad_gas_properties_are_case_errors(key, value):
    with pytest.raises(CaseError, match=f"gas.{key} = "):
        GasProperties(**{key: value})


# ------------------------------------------------------------------ solver arguments
@pytest.mark.parametrize("kw, message", [
    ({"convection": "quick"}, "gas.convection = 'quick': allowed are"),
    ({"gravity": (0.0, -9.81, 1.0)}, "gravity = "),
    ({"gravity": (1.0,)}, "gravity = "),
    ({"tolerance": 0.0}, "gas.tolerance"),
    ({"max_iterations": 0}, "gas.max_iterations"),
])
def test_bad_solver_arguments_are_case_errors(kw, message):
    with pytest.raises(CaseError, match=message):
        box(**kw)


def test_an_inflow_segment_off_its_side_is_a_case_error():
    bcs = {"left": Wall(), "right": Wall(), "top": PressureOutlet(),
           "bottom": Inflow(segments=[Segment(interstitial=1.0), Segment(interstitial=5.0, start=0.2, end=0.3)])}
    with pytest.raises(CaseError, match=r"gas.boundaries.bottom: inflow segment 1 \(start = 0.2, end = 0.3\)"):
        GasSolver(GRID, GasProperties(), bcs)


def test_gravity_may_have_a_zero_third_component():
    assert box(gravity=(0.0, -9.81, 0.0)).gravity == (0.0, -9.81)


def test_initial_state_meets_the_boundary_conditions():
    solver = box()
    state = solver.initial_state(voidage=0.6, velocity=(0.3, 0.2))
    assert isinstance(state, GasState)
    assert state.p.shape == GRID.shape and state.u.shape == GRID.u_shape and state.v.shape == GRID.v_shape
    assert np.all(state.u[[0, -1]] == 0.0)  # walls
    np.testing.assert_allclose(state.v[:, 0], 0.5 / 0.4)  # interstitial inflow
    assert np.all(state.v[:, 1:] == 0.2) and np.all(state.u[1:-1] == 0.3)
    np.testing.assert_allclose(state.rho, state.p * GasProperties().compressibility)
    assert state.p[0, 0] > state.p[0, -1]  # hydrostatic by default


@pytest.mark.parametrize("kw, message", [
    ({"voidage": np.ones((4, 5))}, r"gas voidage: shape \(4, 5\) does not match"),
    ({"voidage": 1.2}, "gas voidage: value 1.2 outside"),
    ({"beta": np.ones((3, 3))}, "gas beta: shape"),
    ({"beta": -1.0}, "gas beta: must be finite and >= 0"),
    ({"beta": (np.ones((6, 4)), np.ones((6, 4)))}, r"gas beta\[1\]: shape \(6, 4\) does not match \(5, 5\)"),
    ({"beta": 1.0, "solids_u": np.ones((5, 5))}, "gas solids_u: shape"),
    ({"source_v": np.ones((6, 4))}, "gas source_v: shape"),
    ({"dt": 0.0}, "dt = 0.0: must be > 0"),
    ({"pressure_voidage": np.ones((6, 4))}, r"pressure_voidage: give a pair"),
    ({"pressure_voidage": (np.ones((6, 4)), np.ones((6, 4)))}, r"pressure_voidage\[1\]: shape \(6, 4\), expected \(5, 5\)"),
    ({"pressure_voidage": (np.ones((6, 4)), np.zeros((5, 5)))}, r"pressure_voidage: 25 face values outside \(0, 1\]"),
    ({"pressure_voidage": (np.full((6, 4), np.nan), np.ones((5, 5)))}, r"24 face values outside \(0, 1\], e.g. nan"),
])
def test_bad_step_input_is_a_case_error(kw, message):
    solver = box()
    state = solver.initial_state()
    kw = {"dt": 1e-4, **kw}
    with pytest.raises(CaseError, match=message):
        solver.advance(state, kw.pop("dt"), 0.0, **kw)


def test_a_state_of_another_grid_is_a_case_error():
    state = box().initial_state()
    state.u = np.zeros((3, 3))
    with pytest.raises(CaseError, match=r"gas state.u: shape \(3, 3\) does not match \(6, 4\)"):
        box().advance(state, 1e-4)


def test_an_array_replaced_after_a_good_step_is_checked_again():
    """The solver skips the state check while the state holds the arrays it found right; a replaced one is
    checked (and refused) at the next step."""
    solver = box()
    state = solver.initial_state()
    solver.advance(state, 1e-4)
    state.v = np.zeros((5, 4))
    with pytest.raises(CaseError, match=r"gas state.v: shape \(5, 4\) does not match \(5, 5\)"):
        solver.advance(state, 1e-4)
    state.v = np.zeros((5, 5), dtype=np.float32)
    with pytest.raises(CaseError, match=r"gas state.v: must be a C-contiguous float64"):
        solver.advance(state, 1e-4)


def test_a_step_far_beyond_the_stability_limit_raises():
    solver = box(GasProperties(density=1.2))
    state = solver.initial_state(velocity=(0.0, 1.0))
    state.u[2, 1] = 1e300  # a wrecked field: the next step cannot be finite
    with pytest.raises(GasConvergenceError, match="Courant number"):
        solver.advance(state, 1e-3)


def test_max_time_step_keeps_courant_and_viscous_numbers():
    solver = box()
    state = solver.initial_state(velocity=(2.0, 0.0))
    dt = solver.max_time_step(state, courant=0.5)
    assert dt == pytest.approx(min(0.5 / (2.0 / GRID.dx + 1.25 / GRID.dy),
                                   0.5 / (1.8e-5 / state.rho.min() * (2 / GRID.dx**2 + 2 / GRID.dy**2))))


# ------------------------------------------------------------------ Newton iterations
def test_pressure_matrix_is_the_exact_jacobian_for_constant_density():
    """With the matrix refactorised every step, the constant-density gas needs one correction."""
    bcs = {"left": Wall(), "right": Wall(), "top": PressureOutlet(pressure=101325.0),
           "bottom": Inflow(segments=[Segment(interstitial=4.5), Segment(interstitial=45.0, start=0.02, end=0.03)],
                            voidage=0.4)}
    solver = GasSolver(GRID, GasProperties(density=1.2), bcs, jacobian_reuse=0.0)
    state = solver.initial_state(voidage=0.5)
    rng = np.random.default_rng(0)
    for k in range(10):
        info = solver.advance(state, 1e-4, k * 1e-4, beta=rng.uniform(100, 1000, GRID.shape),
                              voidage=rng.uniform(0.4, 0.6, GRID.shape))
        assert info.iterations == 1 and info.converged


@pytest.mark.parametrize("ideal", [False, True])
def test_pressure_matrix_stays_the_exact_jacobian_with_a_pressure_voidage(ideal):
    """A pressure term −ε_p ∇p with ε_p ≠ ε_f: the matrix's D = ε_p / a, so the constant-density gas still
    needs one correction, and the ideal gas as many as with ε_p = ε_f (4-6 on these random steps)."""
    counts = []
    for given in (False, True):
        bcs = {"left": Wall(), "right": Wall(), "top": PressureOutlet(pressure=101325.0),
               "bottom": Inflow(superficial=0.5, voidage=0.4)}
        solver = GasSolver(GRID, GasProperties() if ideal else GasProperties(density=1.2), bcs, jacobian_reuse=0.0)
        state = solver.initial_state(voidage=0.5)
        rng = np.random.default_rng(1)
        counts.append([])
        for k in range(10):
            pv = (rng.uniform(0.3, 1.0, GRID.u_shape), rng.uniform(0.3, 1.0, GRID.v_shape))
            info = solver.advance(state, 1e-4, k * 1e-4, beta=rng.uniform(100, 1000, GRID.shape),
                                  voidage=rng.uniform(0.4, 0.6, GRID.shape), pressure_voidage=pv if given else None)
            assert info.converged
            counts[-1].append(info.iterations)
    if not ideal:
        assert counts[1] == [1] * 10
    assert counts[1] == counts[0]


@pytest.mark.parametrize("eps_p", [0.5, 1.0])
def test_gas_at_rest_balances_its_weight_with_the_pressure_voidage(eps_p):
    """Closed box, gas at rest of voidage ε = 0.5: ε_p ∂p/∂y = ε ρ g on every face, so the pressure rises
    downwards by (ε / ε_p) ρ g per metre: ρ g with ε_p = ε (the default), ρ g / 2 with ε_p = 1."""
    rho, g = 1.2, 9.81
    bcs = {s: Wall() for s in ("left", "right", "bottom", "top")}
    solver = GasSolver(GRID, GasProperties(density=rho), bcs, gravity=(0.0, -g))
    state = solver.initial_state(voidage=0.5, pressure=101325.0)
    pv = (np.full(GRID.u_shape, eps_p), np.full(GRID.v_shape, eps_p))
    for k in range(30):
        solver.advance(state, 1e-3, k * 1e-3, pressure_voidage=pv)
    slope = -np.diff(state.p, axis=1) / GRID.dy
    np.testing.assert_allclose(slope, 0.5 / eps_p * rho * g, rtol=1e-8)
    assert np.abs(state.v).max() < 1e-9


def test_step_info_mass_balance_error():
    info = StepInfo(iterations=1, mass_residual=0.0, converged=True, inflow_rate=2.0, outflow_rate=1.0, mass=1.0,
                    mass_change_rate=0.5, courant=0.1)
    assert info.mass_balance_error == pytest.approx(0.25)


# ------------------------------------------------------------------ operators and kernels against NumPy
def test_face_value_upwind_and_tvd():
    # monotone data: upwind takes the donor, TVD adds the limited slope
    assert face_value(1.0, 0.0, 1.0, 2.0, 3.0, UPWIND) == 1.0
    assert face_value(-1.0, 0.0, 1.0, 2.0, 3.0, UPWIND) == 2.0
    assert face_value(1.0, 0.0, 1.0, 2.0, 3.0, TVD) == pytest.approx(1.5)  # smooth: linear interpolation
    assert face_value(-1.0, 0.0, 1.0, 2.0, 3.0, TVD) == pytest.approx(1.5)
    # at an extremum the limiter falls back to the donor value
    assert face_value(1.0, 0.0, 1.0, 0.0, 1.0, TVD) == 1.0


def test_centre_to_face_interpolation():
    rng = np.random.default_rng(4)
    q = rng.normal(size=(4, 3))
    ux, vy = np.empty((5, 3)), np.empty((4, 4))
    centre_to_x_faces(q, False, ux)
    centre_to_y_faces(q, True, vy)
    np.testing.assert_allclose(ux[1:-1], 0.5 * (q[1:] + q[:-1]))
    np.testing.assert_allclose(ux[[0, -1]], q[[0, -1]])
    np.testing.assert_allclose(vy[:, 1:-1], 0.5 * (q[:, 1:] + q[:, :-1]))
    np.testing.assert_allclose(vy[:, 0], 0.5 * (q[:, 0] + q[:, -1]))
    np.testing.assert_allclose(vy[:, -1], vy[:, 0])


def test_lu_solve_kernel_matches_scipy():
    import scipy.sparse.linalg as spla

    rng = np.random.default_rng(7)
    n = 40
    A = (sp.random(n, n, density=0.1, random_state=3) + 4.0 * sp.eye(n)).tocsc()
    lu = spla.splu(A, permc_spec="MMD_AT_PLUS_A")
    L = sp.tril(lu.L, k=-1, format="csc")
    U = lu.U.tocsc()
    Us = sp.triu(U, k=1, format="csc")
    lui = np.zeros((4, n + 1), np.int64)
    lui[K.L_LP], lui[K.L_UP] = L.indptr, Us.indptr
    lui[K.L_PERM_R, :n], lui[K.L_PERM_C, :n] = lu.perm_r, lu.perm_c
    b = rng.normal(size=n)
    x, w = np.empty(n), np.empty(n)
    K.lu_solve(lui, L.indices.astype(np.int64), L.data, Us.indices.astype(np.int64), Us.data, U.diagonal(), b, x, w)
    np.testing.assert_allclose(A @ x, b, atol=1e-12)


def test_band_and_superlu_give_the_same_steps():
    bcs = {"left": Wall(), "right": Wall(), "top": PressureOutlet(pressure=101325.0),
           "bottom": Inflow(segments=[Segment(interstitial=4.5), Segment(interstitial=45.0, start=0.02, end=0.03)],
                            voidage=0.4)}
    states = []
    for linear_solver in ("band", "superlu"):
        solver = GasSolver(GRID, GasProperties(), bcs, linear_solver=linear_solver)
        assert solver.linear_solver == linear_solver
        state = solver.initial_state(voidage=0.5)
        for k in range(20):
            solver.advance(state, 1e-4, k * 1e-4, beta=300.0)
        states.append(state)
    np.testing.assert_allclose(states[0].v, states[1].v, rtol=0, atol=1e-9)
    np.testing.assert_allclose(states[0].p, states[1].p, rtol=1e-13)


def test_band_solver_is_refused_with_periodic_sides_both_ways():
    from fluidem.gas import Periodic

    with pytest.raises(CaseError, match="gas.linear_solver = 'band'"):
        GasSolver(GRID, GasProperties(), {s: Periodic() for s in ("left", "right", "bottom", "top")},
                  linear_solver="band")


def test_benchmark_rows():
    rows = gas_step_benchmark(grids=((6, 10),), seconds=0.05)
    assert [r["problem"].split(",")[2].strip().split()[0] for r in rows] == ["fixed", "moving"]
    for row in rows:
        assert row["grid"] == "6x10" and row["cells"] == 60 and row["steps"] >= 3 and row["ms_per_step"] > 0.0
        assert {"problem", "iterations_per_step", "factorisations_per_step", "dt_s", "linear_solver"} <= set(row)


@pytest.mark.parametrize("linear_solver", ["band", "superlu"])
def test_restored_factors_continue_the_steps_bit_for_bit(linear_solver):
    """A solver restored from another's ``checkpoint_arrays`` (and the gas state) takes the same next steps to
    the last bit; without the factors it factorises afresh and differs at the tolerance's level (the
    uninterrupted solver reuses factors of an earlier matrix, ``jacobian_reuse``)."""
    bcs = {"left": Wall(), "right": Wall(), "top": PressureOutlet(pressure=101325.0),
           "bottom": Inflow(segments=[Segment(interstitial=4.5), Segment(interstitial=45.0, start=0.02, end=0.03)],
                            voidage=0.4)}
    rng = np.random.default_rng(3)
    # a fixed bed and a slow change of voidage: the matrix changes little from step to step, so factors are reused
    bed = np.clip(0.6 + 0.1 * rng.standard_normal(GRID.shape), 0.4, 0.95)
    voidages = [bed + 0.002 * k for k in range(16)]

    def steps(solver, state, ks):
        for k in ks:
            solver.advance(state, 1e-4, k * 1e-4, voidage=voidages[k], beta=300.0)

    whole = GasSolver(GRID, GasProperties(), bcs, linear_solver=linear_solver)
    state = whole.initial_state(voidage=voidages[0])
    steps(whole, state, range(8))
    saved = {k: v.copy() for k, v in whole.checkpoint_arrays().items()}
    kept = GasState(*(a.copy() for a in (state.p, state.rho, state.u, state.v, state.voidage)))
    steps(whole, state, range(8, 16))
    again = GasSolver(GRID, GasProperties(), bcs, linear_solver=linear_solver)
    again.restore_factors(saved)
    fresh = GasSolver(GRID, GasProperties(), bcs, linear_solver=linear_solver)
    resumed = GasState(*(a.copy() for a in (kept.p, kept.rho, kept.u, kept.v, kept.voidage)))
    afresh = GasState(*(a.copy() for a in (kept.p, kept.rho, kept.u, kept.v, kept.voidage)))
    steps(again, resumed, range(8, 16))
    steps(fresh, afresh, range(8, 16))
    assert again.linear_solver == linear_solver
    for k in ("p", "rho", "u", "v"):
        assert np.array_equal(getattr(resumed, k), getattr(state, k)), k
    assert not np.array_equal(afresh.p, state.p), "the factors matter (else this test shows nothing)"
    np.testing.assert_allclose(afresh.p, state.p, rtol=1e-9)


def test_factors_of_another_grid_are_a_case_error():
    saved = box().checkpoint_arrays()
    other = GasSolver(StaggeredGrid(cells=(6, 4), size=(0.06, 0.08), depth=0.01), GasProperties(),
                      {"left": Wall(), "right": Wall(), "bottom": Inflow(superficial=0.5, voidage=0.4),
                       "top": PressureOutlet(pressure=101325.0)})
    with pytest.raises(CaseError, match="checkpoint gas solver matrix: shape"):
        other.restore_factors(saved)
