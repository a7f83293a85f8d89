"""Convection schemes: a transverse velocity wave carried by a uniform stream.

Periodic box, inviscid constant-density gas, u = U, v = sin(2πx/L): divergence-free, and
the exact solution is the wave moving at U with no pressure gradient. After one period,
first-order upwind has smeared it (error ∝ h); the TVD scheme (van Leer limiter) is second
order in space, in L1 (in the max norm the limiter clips the extrema and the order drops
towards 1, as for any TVD scheme). The small Courant number (0.02) keeps the first-order
time error of the explicit Euler step below the spatial error being measured.
"""
import numpy as np
import pytest

from fluidem.gas import GasProperties, GasSolver, Periodic, StaggeredGrid

U = 1.0
COURANT = 0.02


def l1_error_after_one_period(n, scheme):
    grid = StaggeredGrid(cells=(n, 2), size=(1.0, 2.0 / n))
    bcs = {side: Periodic() for side in ("left", "right", "bottom", "top")}
    solver = GasSolver(grid, GasProperties(viscosity=0.0, density=1.0), bcs, gravity=(0.0, 0.0), convection=scheme)
    x = grid.x_centres
    state = solver.initial_state(velocity=(U, np.tile(np.sin(2 * np.pi * x)[:, None], (1, 3))))
    dt = COURANT * grid.dx / U
    steps = int(round(1.0 / dt))
    for k in range(steps):
        solver.advance(state, dt, k * dt)
    assert np.abs(state.u - U).max() < 1e-12  # the stream itself is untouched
    return np.abs(state.v[:, 1] - np.sin(2 * np.pi * (x - U * steps * dt))).mean()


@pytest.fixture(scope="module")
def errors():
    return {s: np.array([l1_error_after_one_period(n, s) for n in (16, 32, 64)]) for s in ("upwind", "tvd")}


def test_upwind_is_first_order(errors):
    order = np.log2(errors["upwind"][:-1] / errors["upwind"][1:])
    assert np.all(order > 0.5) and np.all(order < 1.2), order  # measured 0.64, 0.80: tending to 1


def test_tvd_is_second_order_and_far_more_accurate(errors):
    order = np.log2(errors["tvd"][1] / errors["tvd"][2])
    assert order > 1.6, errors["tvd"]  # measured 1.78 from 32 to 64 cells
    assert np.all(errors["tvd"] < errors["upwind"] / 5.0)
