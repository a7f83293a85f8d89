"""Behaviour of each boundary condition / cell flag (Hoomans 1996 Table 1, plus periodic sides).

Each test isolates what one flag does and checks it against an exact answer:
free-slip (2) and no-slip (3) walls by the decay of shear modes, inflow (4) by the
velocities and mass flow it imposes, prescribed pressure (5) by a pressure that follows
a time-dependent outlet, continuous outflow (6) by zero gradient and the mass balance,
corners (7) by the mirror symmetry of a symmetric box, periodic sides (8) by invariance
under shifting the domain.
"""
import numpy as np
import pytest

from fluidem.gas import (CORNER, INFLOW, INTERIOR, NO_SLIP, PRESSURE, FreeSlip, GasProperties, GasSolver,
                         Inflow, Outflow, Periodic, PressureOutlet, Pulse, Segment, StaggeredGrid, Wall)

P0 = 101325.0


# ------------------------------------------------------------------ walls (flags 2 and 3)
def shear_mode_decay(wall, profile, n=20, decay_time=0.1):
    """Amplitude ratio after ``decay_time`` of a shear mode u(y) in a periodic channel of height 1
    with ``wall`` top and bottom (ρ = 1, μ = 1, no forcing), and the analytic ratio."""
    grid = StaggeredGrid(cells=(2, n), size=(1.0, 1.0))
    solver = GasSolver(grid, GasProperties(viscosity=1.0, density=1.0),
                       {"left": Periodic(), "right": Periodic(), "bottom": wall, "top": wall}, gravity=(0.0, 0.0))
    y = grid.y_centres
    u0 = profile(y)
    state = solver.initial_state(velocity=(np.tile(u0, (3, 1)), 0.0))
    dt = 0.05 * grid.dy**2
    steps = int(round(decay_time / dt))
    for k in range(steps):
        solver.advance(state, dt, k * dt)
    ratio = state.u[0] @ u0 / (u0 @ u0)
    return ratio, state


def test_no_slip_walls_damp_the_half_sine_at_the_analytic_rate():
    """u = sin(πy) vanishes on no-slip walls and decays as exp(−π² ν t)."""
    ratio, state = shear_mode_decay(Wall(), lambda y: np.sin(np.pi * y))
    expected = np.exp(-np.pi**2 * 0.1)
    # tolerance: the discrete eigenvalue differs by (πh)²/12 = 0.2 % on 20 cells (h = 1/20)
    assert ratio == pytest.approx(expected, rel=5e-3)
    assert np.abs(state.v).max() < 1e-12


def test_free_slip_walls_damp_the_half_cosine_and_leave_uniform_flow():
    """u = cos(πy) has zero shear on free-slip walls and decays as exp(−π² ν t); a uniform
    stream does not decay at all, whereas no-slip walls slow it."""
    ratio, _ = shear_mode_decay(FreeSlip(), lambda y: np.cos(np.pi * y))
    assert ratio == pytest.approx(np.exp(-np.pi**2 * 0.1), rel=5e-3)
    ratio_free, state = shear_mode_decay(FreeSlip(), lambda y: np.ones_like(y))
    assert abs(ratio_free - 1.0) < 1e-12 and np.ptp(state.u) < 1e-12
    ratio_wall, _ = shear_mode_decay(Wall(), lambda y: np.ones_like(y))
    assert ratio_wall < 0.9


# ------------------------------------------------------------------ inflow (flag 4)
def inflow_box(inflow, density=1.2, cells=(15, 5)):
    grid = StaggeredGrid(cells=cells, size=(0.15, 0.1), depth=0.004)
    bcs = {"left": Wall(), "right": Wall(), "bottom": inflow, "top": PressureOutlet(pressure=P0)}
    return grid, GasSolver(grid, GasProperties(density=density), bcs, gravity=(0.0, 0.0))


def test_inflow_segments_set_interstitial_face_velocities_and_the_mass_flow():
    """Hoomans 1996 §5.3.1: 45 m/s through the centre cell, 4.5 m/s elsewhere, influx voidage 0.4;
    the same given as superficial velocities (18 and 1.8 m/s)."""
    inter = Inflow(segments=[Segment(interstitial=4.5), Segment(interstitial=45.0, start=0.07, end=0.08)],
                   voidage=0.4)
    sup = Inflow(segments=[Segment(superficial=1.8), Segment(superficial=18.0, start=0.07, end=0.08)], voidage=0.4)
    results = []
    for bc in (inter, sup):
        grid, solver = inflow_box(bc)
        state = solver.initial_state()
        info = solver.advance(state, 1e-4, 0.0)
        expected_v = np.full(grid.nx, 4.5)
        expected_v[7] = 45.0
        np.testing.assert_allclose(state.v[:, 0], expected_v, rtol=1e-14)
        # mass inflow: ε_in ρ u_interstitial = ρ u_superficial over the face areas
        expected_rate = 1.2 * (1.8 * 0.14 + 18.0 * 0.01) * grid.depth
        assert info.inflow_rate == pytest.approx(expected_rate, rel=1e-12)
        results.append(state)
    np.testing.assert_allclose(results[0].v, results[1].v, rtol=1e-12, atol=1e-12)


def test_inflow_segment_partly_covering_faces_keeps_its_mass_flow():
    """A jet 0.065-0.085 m covers faces 6 and 8 by half: they get the covered share of each velocity,
    and the mass flow is the segment's width times its velocity."""
    bc = Inflow(segments=[Segment(interstitial=1.0), Segment(interstitial=11.0, start=0.065, end=0.085)])
    grid, solver = inflow_box(bc)
    state = solver.initial_state()
    info = solver.advance(state, 1e-4, 0.0)
    assert state.v[6, 0] == pytest.approx(6.0) and state.v[8, 0] == pytest.approx(6.0)
    assert state.v[7, 0] == pytest.approx(11.0) and state.v[0, 0] == pytest.approx(1.0)
    assert info.inflow_rate == pytest.approx(1.2 * (1.0 * 0.13 + 11.0 * 0.02) * grid.depth, rel=1e-12)


def test_inflow_pulse_switches_at_the_end_of_the_step():
    """Hoomans 1996 §5.4 style: a 200 ms pulse of 2.5 m/s superficial through the orifice over a
    background of 0.5 m/s; velocities are taken at t + dt."""
    pulse = Pulse(2.5, start=0.0, duration=0.2, otherwise=0.5)
    bc = Inflow(segments=[Segment(superficial=0.5), Segment(superficial=pulse, start=0.07, end=0.08)], voidage=0.4)
    _, solver = inflow_box(bc)
    state = solver.initial_state()
    solver.advance(state, 1e-3, 0.198)  # ends at 0.199 s: inside the pulse
    assert state.v[7, 0] == pytest.approx(2.5 / 0.4) and state.v[0, 0] == pytest.approx(0.5 / 0.4)
    solver.advance(state, 1e-3, 0.199)  # ends at 0.2 s: the pulse is over
    assert state.v[7, 0] == pytest.approx(0.5 / 0.4)


def test_inflow_cells_hold_their_voidage_and_zero_tangential_velocity():
    """Hoomans 1996 §3.5: the influx cells keep voidage 0.4 whatever the bed above them does; the
    gas in them has no velocity along the side."""
    grid, solver = inflow_box(Inflow(superficial=1.0, voidage=0.4))
    rng = np.random.default_rng(1)
    state = solver.initial_state(voidage=rng.uniform(0.4, 1.0, grid.shape), velocity=(0.3, 0.0))
    solver.advance(state, 1e-4, 0.0, voidage=rng.uniform(0.4, 1.0, grid.shape))
    assert np.all(solver.E[1:-1, 0] == 0.4)  # boundary cells of the bottom side
    assert np.all(solver.U[2:grid.nx + 3, 1] == 0.0)  # x velocity in the influx cells


# ------------------------------------------------------------------ prescribed pressure (flag 5)
def test_prescribed_pressure_follows_a_time_dependent_outlet():
    """A closed box with one pressure side: the incompressible gas at rest takes the outlet's
    pressure at t + dt plus its weight, step by step."""
    grid = StaggeredGrid(cells=(6, 10), size=(0.06, 0.1))

    def p_out(t):
        return P0 + 500.0 * np.sin(2 * np.pi * 10.0 * t)

    solver = GasSolver(grid, GasProperties(density=1.2), {"left": Wall(), "right": Wall(), "bottom": Wall(),
                                                            "top": PressureOutlet(pressure=p_out)})
    state = solver.initial_state()
    _, Y = grid.centres()
    for k in range(20):
        t = k * 1e-3
        solver.advance(state, 1e-3, t)
        expected = p_out(t + 1e-3) + 1.2 * 9.81 * (grid.size[1] + 0.5 * grid.dy - Y)
        assert np.abs(state.p - expected).max() < 1e-9
        assert np.abs(state.v).max() < 1e-10


# ------------------------------------------------------------------ continuous outflow (flag 6)
@pytest.mark.parametrize("density", [1.2, None], ids=["constant density", "ideal gas"])
def test_continuous_outflow_has_zero_gradient_and_closes_the_mass_balance(density):
    grid = StaggeredGrid(cells=(20, 10), size=(0.2, 0.05), depth=0.01)
    bcs = {"left": Inflow(interstitial=1.0), "right": Outflow(), "bottom": Wall(), "top": Wall()}
    solver = GasSolver(grid, GasProperties(density=density), bcs, gravity=(0.0, 0.0))
    state = solver.initial_state()
    p_first = state.p[0, 0]
    for k in range(1500):
        info = solver.advance(state, 2e-3, k * 2e-3)
        assert info.mass_balance_error < 1e-8
    # developed: the outflow faces copy the adjacent interior faces, and carry the inflow out
    np.testing.assert_allclose(state.u[-1], state.u[-2], rtol=1e-6)
    assert info.outflow_rate == pytest.approx(info.inflow_rate, rel=1e-8)
    assert np.abs(state.v[:, [0, -1]]).max() == 0.0
    if density is not None:  # no pressure side: the level stays where it was at the first cell
        assert state.p[0, 0] == pytest.approx(p_first, abs=1e-9)


# ------------------------------------------------------------------ corners (flag 7)
def test_corner_cells_carry_flag_7_and_a_symmetric_box_stays_symmetric():
    grid = StaggeredGrid(cells=(15, 25), size=(0.15, 0.5), depth=0.004)
    bcs = {"left": Wall(), "right": Wall(), "top": PressureOutlet(pressure=P0),
           "bottom": Inflow(segments=[Segment(interstitial=4.5), Segment(interstitial=45.0, start=0.07, end=0.08)],
                            voidage=0.4)}
    solver = GasSolver(grid, GasProperties(), bcs)
    fl = solver.flags
    assert fl[0, 0] == fl[0, -1] == fl[-1, 0] == fl[-1, -1] == CORNER
    assert np.all(fl[1:-1, 1:-1] == INTERIOR) and np.all(fl[0, 1:-1] == NO_SLIP) and np.all(fl[1:-1, 0] == INFLOW)
    assert np.all(fl[1:-1, -1] == PRESSURE)
    # a corner cell is no equation and no pressure unknown
    for i, j in ((0, 0), (0, -1), (-1, 0), (-1, -1)):
        assert solver.row_of[i, j] == -1 and solver.col_of[i, j] == -1
    state = solver.initial_state()
    for k in range(200):
        solver.advance(state, 1e-4, k * 1e-4)
    # mirror symmetry about x = 0.075: the left and right corners (and walls) act alike
    np.testing.assert_allclose(state.v, state.v[::-1], rtol=0, atol=1e-9 * 45.0)
    np.testing.assert_allclose(state.u, -state.u[::-1], rtol=0, atol=1e-9 * 45.0)
    np.testing.assert_allclose(state.p, state.p[::-1], rtol=1e-13)


# ------------------------------------------------------------------ periodic sides (flag 8)
@pytest.mark.parametrize("walls", [False, True], ids=["periodic box", "periodic channel"])
@pytest.mark.parametrize("convection", ["upwind", "tvd"])
def test_periodic_sides_make_the_solution_invariant_under_shifts(walls, convection):
    """Stepping a shifted initial field gives the shifted result: no place is special."""
    grid = StaggeredGrid(cells=(12, 8), size=(0.12, 0.08))
    bcs = {"left": Periodic(), "right": Periodic(), "bottom": Periodic(), "top": Periodic()}
    if walls:
        bcs.update(bottom=Wall(), top=FreeSlip())
    solver = GasSolver(grid, GasProperties(viscosity=1e-3), bcs, gravity=(0.3, -9.81), convection=convection)
    rng = np.random.default_rng(5)
    eps = rng.uniform(0.5, 1.0, grid.shape)
    u = rng.normal(0.0, 1.0, grid.u_shape)
    u[-1] = u[0]
    v = rng.normal(0.0, 1.0, grid.v_shape)
    if not walls:
        v[:, -1] = v[:, 0]
    shift_x, shift_y = 5, 0 if walls else 3

    def run(eps, u, v):
        state = solver.initial_state(voidage=eps, velocity=(u, v), pressure=P0)
        for k in range(10):
            info = solver.advance(state, 1e-4, k * 1e-4)
            assert info.converged
        return state

    a = run(eps, u, v)
    b = run(np.roll(eps, (shift_x, shift_y), (0, 1)),
            np.concatenate([np.roll(u[:-1], (shift_x, shift_y), (0, 1)), np.roll(u[:-1], (shift_x, shift_y), (0, 1))[:1]]),
            np.roll(v, (shift_x, 0), (0, 1)) if walls else
            np.concatenate([np.roll(v[:, :-1], (shift_x, shift_y), (0, 1)),
                            np.roll(v[:, :-1], (shift_x, shift_y), (0, 1))[:, :1]], axis=1))
    np.testing.assert_allclose(np.roll(a.u[:-1], (shift_x, shift_y), (0, 1)), b.u[:-1], rtol=0, atol=1e-10)
    np.testing.assert_allclose(np.roll(a.p, (shift_x, shift_y), (0, 1)), b.p, rtol=1e-13)
    assert np.all(b.u[-1] == b.u[0])  # the duplicate face is the same face
