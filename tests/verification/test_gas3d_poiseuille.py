"""Fully developed laminar flow in a duct of square section (3D gas, ε = 1, no-slip walls) against the
Fourier series.

A duct of side h, periodic along its axis, driven by a uniform body force G [N/m^3] (the momentum source of
``GasSolver.advance``, equivalent to a pressure gradient −dp/dx = G). With y, z measured from the duct's
centre line (White, Viscous Fluid Flow, §3.3.3)::

    u(y, z) = 4 G h² / (μ π³) Σ_{n odd} (−1)^((n−1)/2) / n³ [1 − cosh(nπ z/h) / cosh(nπ/2)] cos(nπ y/h)
    Q = G h⁴ / (12 μ) [1 − 192/π⁵ Σ_{n odd} tanh(nπ/2) / n⁵]

On the staggered grid (face velocities at cell centres of the cross-section, mirrored ghosts on the walls)
the steady discrete profile differs from the series by O((h/N)²): the largest error of the face
velocities, relative to the centre-line velocity, is 2.34 % on 8 × 8 cells and 0.63 % on 16 × 16 (order
1.9), that of the flow rate 5.9 % and 1.5 % (order 2.0); the same along x, y and z. (Plane Poiseuille
flow on the same grid is off by exactly (1/N)², ``test_gas_poiseuille.py``; the duct has walls in both
directions.) The tolerances are those of second order, C/N² with C fitted at N = 8 and a margin of 1.2.
"""
import numpy as np
import pytest

from fluidem.gas import GasProperties, GasSolver, Periodic, StaggeredGrid, Wall

H = 1.0  # side of the duct [m]
MU = 1.0  # [Pa s]
RHO = 1.0  # [kg/m^3]
G = 10.0  # body force [N/m^3]


def series_velocity(y, z, terms=101):
    """Axial velocity [m/s] at (y, z) measured from the centre line (the series above)."""
    u = np.zeros(np.broadcast(y, z).shape)
    for n in range(1, 2 * terms, 2):
        u += (-1) ** ((n - 1) // 2) / n**3 * (1.0 - np.cosh(n * np.pi * z / H) / np.cosh(n * np.pi / 2)) \
            * np.cos(n * np.pi * y / H)
    return 4.0 * G * H**2 / (MU * np.pi**3) * u


def series_flow_rate(terms=101):
    n = np.arange(1, 2 * terms, 2)
    return G * H**4 / (12.0 * MU) * (1.0 - 192.0 / np.pi**5 * np.sum(np.tanh(n * np.pi / 2) / n**5))


def steady_duct(n: int, axis: int):
    """Steady axial velocity on the (n × n) faces of a cross-section of a duct along ``axis`` (0: x, 1: y, 2: z),
    started from the series (the discrete steady state differs from it by O(h²), which decays in ~0.3 s);
    returns (velocity (n, n), cross-section coordinates (y, z) from the centre line, cell area, solver)."""
    cells, size = [n, n, n], [H, H, H]
    cells[axis], size[axis] = 2, 0.5
    grid = StaggeredGrid(cells=tuple(cells), size=tuple(size))
    sides = {0: ("left", "right"), 1: ("bottom", "top"), 2: ("front", "back")}[axis]
    bcs = {s: (Periodic() if s in sides else Wall()) for s in grid.sides}
    solver = GasSolver(grid, GasProperties(viscosity=MU, density=RHO), bcs, gravity=(0.0, 0.0, 0.0))
    across = [a for a in range(3) if a != axis]
    c = [(np.arange(n) + 0.5) * H / n - 0.5 * H for _ in across]
    Y, Z = np.meshgrid(*c, indexing="ij")
    profile = np.expand_dims(series_velocity(Y, Z), axis)  # broadcast along the duct's axis
    velocity = [0.0, 0.0, 0.0]
    velocity[axis] = np.broadcast_to(profile, grid.face_shape(axis)).copy()
    state = solver.initial_state(velocity=tuple(velocity), pressure=1e5)
    h = H / n
    dt = 0.1 * h**2 * RHO / MU  # viscous number ν dt Σ 2/h² = 0.4 + a little
    source = {("source_u", "source_v", "source_w")[axis]: G}
    t = 0.0
    for _ in range(int(0.35 / dt)):  # 7 time constants h²/(2 π² ν) of the slowest mode
        info = solver.advance(state, dt, t, **source)
        t += dt
    assert info.converged
    w = (state.u, state.v, state.w)[axis]
    section = np.take(w, 0, axis=axis)
    assert np.ptp(w, axis=axis).max() < 1e-12  # fully developed: the same on every face along the axis
    return section, Y, Z, h * h, solver


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_square_duct_profile_and_flow_rate_to_second_order(axis):
    errors, flows = [], []
    for n in (8, 16):
        u, Y, Z, area, _ = steady_duct(n, axis)
        exact = series_velocity(Y, Z)
        errors.append(np.abs(u - exact).max() / series_velocity(0.0, 0.0))
        flows.append(abs(u.sum() * area - series_flow_rate()) / series_flow_rate())
    # the discretisation error of a second-order scheme, C / N², C = 1.50 (profile), 3.76 (flow rate)
    assert errors[0] < 1.2 * 1.50 / 8**2 and errors[1] < 1.2 * 1.50 / 16**2
    assert flows[0] < 1.2 * 3.76 / 8**2 and flows[1] < 1.2 * 3.76 / 16**2
    for e in (errors, flows):
        order = np.log2(e[0] / e[1])
        assert 1.8 < order < 2.2
