"""The implicit interphase term −β(u − u_s) of the 3D gas against the analytic relaxation.

A periodic box of constant-density, inviscid gas (ε = 0.6) with a uniform β and a solids velocity field
u_s that varies across its own direction only (u_s = U sin(2π z/Lz) x̂, or its cyclic siblings along y
and z): the gas flow stays parallel and divergence-free, so convection and pressure do nothing and each
face relaxes on its own, ε ρ du/dt = −β (u − u_s)::

    u(t) = u_s + (u0 − u_s) exp(−β t/(ε ρ))

The implicit step makes u_{n+1} − u_s = (u_n − u_s) / (1 + β dt/(ε ρ)) exactly (to round-off, asserted at
1e-13 m/s); that approaches the exponential to first order in dt (asserted: the error halves with dt).
"""
import numpy as np
import pytest

from fluidem.gas import GasProperties, GasSolver, Periodic, StaggeredGrid

BETA, EPS, RHO, U = 2000.0, 0.6, 1.2, 0.3


def relax(axis: int, dt: float, t_end: float):
    grid = StaggeredGrid(cells=(6, 5, 4), size=(0.06, 0.05, 0.04))
    solver = GasSolver(grid, GasProperties(density=RHO, viscosity=0.0), {s: Periodic() for s in grid.sides},
                       gravity=(0.0, 0.0, 0.0))
    across = (axis + 2) % 3  # u_s along ``axis`` varies along ``across``
    shape = grid.face_shape(axis)
    coord = (np.arange(shape[across]) + 0.5) * grid.spacing[across]
    profile = np.expand_dims(U * np.sin(2 * np.pi * coord / grid.size[across]), [a for a in range(3) if a != across])
    solids = np.ascontiguousarray(np.broadcast_to(profile, shape))
    start = [0.0, 0.0, 0.0]
    start[axis] = 0.1  # u0: a uniform stream along the axis
    state = solver.initial_state(voidage=EPS, velocity=tuple(start), pressure=1e5)
    names = ("solids_u", "solids_v", "solids_w")
    kwargs = {n: (solids if a == axis else 0.0) for a, n in enumerate(names)}
    steps = round(t_end / dt)
    discrete = (0.1 - solids) / (1.0 + BETA * dt / (EPS * RHO)) ** steps + solids
    for k in range(steps):
        info = solver.advance(state, dt, k * dt, beta=BETA, **kwargs)
        assert info.converged
    w = (state.u, state.v, state.w)
    exact = solids + (0.1 - solids) * np.exp(-BETA * steps * dt / (EPS * RHO))
    return w[axis], discrete, exact, [w[a] for a in range(3) if a != axis]


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_uniform_beta_relaxes_the_gas_to_the_solids_velocity(axis):
    t_end = 5e-4  # β t/(ε ρ) = 1.4
    errors = []
    for dt in (5e-5, 2.5e-5):
        w, discrete, exact, others = relax(axis, dt, t_end)
        assert np.abs(w - discrete).max() < 1e-13
        for o in others:
            assert np.abs(o).max() < 1e-14
        errors.append(np.abs(w - exact).max())
    assert errors[1] < 0.06 * U  # first order: 3.7 % of U at dt = 2.5e-5 s
    assert errors[0] / errors[1] == pytest.approx(2.0, rel=0.1)
