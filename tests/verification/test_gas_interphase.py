"""The particle side as arrays: interphase drag β(u − v) implicit, explicit momentum sources.

In a periodic box with uniform fields there is no pressure gradient, and the momentum
balance of Hoomans 1996 eq. 43 per unit volume reduces to the implicit Euler step
ερ (u' − u)/dt = −β (u' − v) + s, whose exact discrete solution the solver must reproduce
to round-off, for any β dt / (ερ): the drag never limits the time step.
"""
import numpy as np
import pytest

from fluidem.gas import GasProperties, GasSolver, Periodic, StaggeredGrid

GRID = StaggeredGrid(cells=(6, 4), size=(0.06, 0.04))
PERIODIC = {side: Periodic() for side in ("left", "right", "bottom", "top")}


@pytest.mark.parametrize("density", [1.2, None], ids=["constant density", "ideal gas"])
@pytest.mark.parametrize("beta", [10.0, 1e4, 1e9])
def test_implicit_drag_relaxes_the_gas_to_the_solids_velocity(beta, density):
    solver = GasSolver(GRID, GasProperties(density=density), PERIODIC, gravity=(0.0, 0.0))
    eps = 0.45
    state = solver.initial_state(voidage=eps)
    er = eps * state.rho[0, 0]
    solids = (1.5, -0.5)
    dt = 1e-3  # β dt / (ερ) from 0.02 to 2e6
    u, v = 0.0, 0.0
    for k in range(20):
        info = solver.advance(state, dt, k * dt, beta=beta, solids_u=solids[0], solids_v=solids[1])
        assert info.converged
        u = (er * u / dt + beta * solids[0]) / (er / dt + beta)  # the exact implicit-Euler step
        v = (er * v / dt + beta * solids[1]) / (er / dt + beta)
    assert np.abs(state.u - u).max() < 1e-12 * max(abs(u), 1.0)
    assert np.abs(state.v - v).max() < 1e-12 * max(abs(v), 1.0)


def test_drag_given_on_faces_equals_drag_given_at_centres():
    """β and the solids velocity as face arrays or as cell-centre arrays (averaged onto faces)."""
    rng = np.random.default_rng(2)
    beta_c = rng.uniform(0.0, 5e3, GRID.shape)
    vs_c = rng.normal(0.0, 1.0, GRID.shape)
    solver = GasSolver(GRID, GasProperties(density=1.2), PERIODIC, gravity=(0.0, -9.81))
    a = solver.initial_state(voidage=0.6)
    b = a.copy()
    solver.advance(a, 1e-3, 0.0, beta=beta_c, solids_u=vs_c, solids_v=-vs_c)
    # the same on faces: periodic, so every face is the mean of the two cells it joins
    bu = 0.5 * (beta_c + np.roll(beta_c, 1, axis=0))
    bv = 0.5 * (beta_c + np.roll(beta_c, 1, axis=1))
    su = 0.5 * (vs_c + np.roll(vs_c, 1, axis=0))
    sv = -0.5 * (vs_c + np.roll(vs_c, 1, axis=1))
    solver.advance(b, 1e-3, 0.0, beta=(np.vstack([bu, bu[:1]]), np.hstack([bv, bv[:, :1]])),
                   solids_u=np.vstack([su, su[:1]]), solids_v=np.hstack([sv, sv[:, :1]]))
    np.testing.assert_allclose(a.u, b.u, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(a.v, b.v, rtol=1e-12, atol=1e-14)


@pytest.mark.parametrize("density", [1.2, None], ids=["constant density", "ideal gas"])
def test_momentum_source_accelerates_the_gas(density):
    """A uniform source s [N/m^3] in a periodic box: ερ du/dt = s, so u = s t / (ερ), and the
    gas mass stays what it was."""
    solver = GasSolver(GRID, GasProperties(density=density), PERIODIC, gravity=(0.0, 0.0))
    state = solver.initial_state(voidage=0.8)
    er = 0.8 * state.rho[0, 0]
    m0 = np.sum(state.voidage * state.rho)
    for k in range(10):
        solver.advance(state, 1e-3, k * 1e-3, source_u=2.0, source_v=np.full(GRID.shape, -1.0))
    assert np.abs(state.u - 2.0 * 0.01 / er).max() < 1e-12
    assert np.abs(state.v + 1.0 * 0.01 / er).max() < 1e-12
    assert np.sum(state.voidage * state.rho) == pytest.approx(m0, rel=1e-14)
