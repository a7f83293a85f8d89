"""A closed 3D box of gas under gravity stays at rest with the hydrostatic pressure.

Constant density: started from a uniform pressure, the first pressure correction makes
p = p0 + ρ g (H − z) (z along gravity, exact on the grid: the discrete balance of a linear profile is
exact) with velocities at the level of the solver tolerance, and the box stays so. Ideal gas: the
barometric profile p = p0 exp(−M g z/(RT)), which ``hydrostatic_pressure`` makes in exact discrete balance
(its rate differs from M g/(RT) by O((M g h/(RT))²), 1e-13 here), is kept at rest step after step. Along
y (the 2D convention: bottom and top are the y sides) and along z.
"""
import numpy as np
import pytest

from fluidem.gas import GasProperties, GasSolver, StaggeredGrid, Wall
from fluidem.gas.solver import GAS_CONSTANT

G = 9.81


def closed_box(props, axis):
    grid = StaggeredGrid(cells=(5, 6, 7), size=(0.5, 0.6, 0.7))
    gravity = [0.0, 0.0, 0.0]
    gravity[axis] = -G
    solver = GasSolver(grid, props, {s: Wall() for s in grid.sides}, gravity=tuple(gravity))
    return grid, solver


@pytest.mark.parametrize("axis", [1, 2])
def test_constant_density_box_settles_to_the_hydrostatic_pressure_in_one_step(axis):
    rho = 1.2
    grid, solver = closed_box(GasProperties(density=rho, viscosity=1.8e-5), axis)
    state = solver.initial_state(pressure=1e5)  # uniform: out of balance
    z = grid.centres()[axis]
    height = grid.size[axis]
    for k in range(5):
        info = solver.advance(state, 1e-3, k * 1e-3)
        assert info.converged
        # p0 + ρ g (H − z), with the level of cell 0 held (a closed constant-density box has no other)
        expected = state.p[0, 0, 0] + rho * G * ((height - z) - (height - z[0, 0, 0]))
        assert np.abs(state.p - expected).max() < 1e-9  # [Pa], round-off of 1e5 Pa
        for w in (state.u, state.v, state.w):
            # the tolerance 1e-10 of the mass residual, relative to 1e-4 mass/dt, is a velocity of about
            # 1e-14 L/dt = 1e-11 m/s; measured 3e-13 m/s
            assert np.abs(w).max() < 1e-11


@pytest.mark.parametrize("axis", [1, 2])
def test_ideal_gas_box_keeps_the_barometric_profile_at_rest(axis):
    props = GasProperties()
    grid, solver = closed_box(props, axis)
    p = solver.hydrostatic_pressure()
    z = grid.centres()[axis]
    k = props.molar_mass * G / (GAS_CONSTANT * props.temperature)
    # anchored at the reference pressure in the box's centre
    barometric = props.reference_pressure * np.exp(-k * (z - 0.5 * grid.size[axis]))
    assert np.abs(p / barometric - 1.0).max() < 1e-12
    state = solver.initial_state()
    p0 = state.p.copy()
    mass = None
    for step in range(10):
        info = solver.advance(state, 1e-3, step * 1e-3)
        assert info.converged
        mass = mass or info.mass
        assert info.mass == pytest.approx(mass, rel=1e-13)
    assert np.abs(state.p - p0).max() < 1e-8  # [Pa] of 1e5
    for w in (state.u, state.v, state.w):
        assert np.abs(w).max() < 1e-11  # measured 2e-12 m/s
