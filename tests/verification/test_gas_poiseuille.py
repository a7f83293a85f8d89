"""Plane Poiseuille flow of the gas (ε = 1, no-slip walls) against the analytic profile.

u(y) = G y (H − y) / (2 μ) between walls at y = 0 and y = H, driven by a pressure
gradient −dp/dx = G. On the staggered grid with mirrored ghost velocities the steady
discrete profile is the analytic one shifted by G h² / (8 μ) everywhere (h = H/N),
so the relative error is exactly (1/N)²: 0.25 % on 20 cells, order 2.
"""
import numpy as np
import pytest

from fluidem.gas import GasProperties, GasSolver, Periodic, PressureOutlet, StaggeredGrid, Wall

H = 1.0  # channel height [m]
MU = 1.0  # [Pa s]
RHO = 1.0  # [kg/m^3]
G = 8.0  # driving gradient [Pa/m]: u_max = G H^2 / (8 μ) = 1 m/s


def analytic(y):
    return G * y * (H - y) / (2.0 * MU)


def steady_profile(n: int, *, driven_by: str = "source") -> tuple[np.ndarray, np.ndarray, GasSolver]:
    """Steady u on the x-faces (interior rows) of an n-cell-high channel, started from the analytic
    profile (the discrete steady state differs from it by O(h^2), which decays in ~0.7 s)."""
    if driven_by == "source":  # periodic channel, uniform body force G [N/m^3]
        grid = StaggeredGrid(cells=(2, n), size=(1.0, H))
        bcs = {"left": Periodic(), "right": Periodic(), "bottom": Wall(), "top": Wall()}
        kw = {"source_u": G}
    else:  # pressure boundaries at both ends; prescribed pressures sit at the boundary-cell centres
        grid = StaggeredGrid(cells=(4, n), size=(1.0, H))
        dp = G * (grid.size[0] + grid.dx)  # the centres are L + dx apart
        bcs = {"left": PressureOutlet(pressure=1e5 + dp), "right": PressureOutlet(pressure=1e5), "bottom": Wall(),
               "top": Wall()}
        kw = {}
    solver = GasSolver(grid, GasProperties(viscosity=MU, density=RHO), bcs, gravity=(0.0, 0.0))
    y = grid.y_centres
    X, _ = grid.centres()
    state = solver.initial_state(velocity=(np.tile(analytic(y), (grid.nx + 1, 1)), 0.0),
                                 pressure=1e5 + (G * (grid.size[0] + 0.5 * grid.dx - X) if kw == {} else 0.0))
    dt = 0.2 * grid.dy**2 * RHO / MU  # explicit viscous term: ν dt (2/dx² + 2/dy²) < 1
    t = 0.0
    for _ in range(int(0.8 / dt)):  # 8 time constants H²/(π² ν) of the slowest mode
        info = solver.advance(state, dt, t, **kw)
        t += dt
    assert info.converged
    return y, state.u, solver


def test_poiseuille_profile_within_half_percent_on_20_cells():
    y, u, _ = steady_profile(20)
    err = np.abs(u - analytic(y)).max() / analytic(0.5 * H)
    # required tolerance 0.5 %; the discretisation error is exactly (1/20)^2 = 0.25 %
    assert err < 5e-3
    assert err == pytest.approx(1.0 / 20**2, rel=1e-3)
    assert np.ptp(u, axis=0).max() < 1e-12  # fully developed: the same at every x-face


def test_poiseuille_order_of_accuracy():
    errors = []
    for n in (10, 20, 40):
        y, u, _ = steady_profile(n)
        errors.append(np.abs(u[0] - analytic(y)).max() / analytic(0.5 * H))
    order = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(order >= 1.8), (errors, order)  # required: observed order >= 1.8 (second-order scheme: 2.0)


def test_pressure_driven_poiseuille_between_pressure_boundaries():
    """Flag 5: the pressure difference of two prescribed-pressure sides drives the flow, with the
    prescribed pressures at the boundary-cell centres (gradient Δp / (L + dx))."""
    y, u, solver = steady_profile(20, driven_by="pressure")
    err = np.abs(u - analytic(y)).max() / analytic(0.5 * H)
    assert err == pytest.approx(1.0 / 20**2, rel=1e-3)
