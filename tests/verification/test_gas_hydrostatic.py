"""Gas at rest under gravity: hydrostatic pressure within round-off.

Ideal gas (Hoomans 1996 eq. 44): dp/dy = −ρ g = −p M g/(RT), so p = p_a exp(−M g (y − y_a)/(RT)).
The staggered balance (p_j+1 − p_j)/dy = −g (ρ_j + ρ_j+1)/2 has the exact solution
p_j+1/p_j = (1 − a)/(1 + a), a = M g dy/(2RT), whose rate differs from the exponential's
by a²/3 ≈ 4e-13 relative: invisible in double precision. Constant density: p linear.
"""
import numpy as np
import pytest

from fluidem.gas import FreeSlip, GasProperties, GasSolver, PressureOutlet, StaggeredGrid, Wall
from fluidem.gas.solver import GAS_CONSTANT

GRID = StaggeredGrid(cells=(15, 25), size=(0.15, 0.5), depth=0.004)  # Hoomans 1996 Table 2
G = 9.81
P_OUT = 101325.0
# round-off: pressures carry ~1e-16 relative; a few hundred operations in the balance
PRESSURE_TOL = 1e-13  # relative
VELOCITY_TOL = 1e-10  # [m/s]; the pressure's round-off (~1e-11 Pa over 2 cm) drives ~1e-13 m/s per step


def closed_box():
    return {"left": Wall(), "right": Wall(), "bottom": Wall(), "top": Wall()}


def outlet_on_top():
    return {"left": Wall(), "right": FreeSlip(), "bottom": Wall(), "top": PressureOutlet(pressure=P_OUT)}


def run_at_rest(bcs, props, voidage, steps=100, dt=1e-4, pressure=None):
    solver = GasSolver(GRID, props, bcs, gravity=(0.0, -G))
    state = solver.initial_state(voidage=voidage, pressure=pressure)
    for n in range(steps):
        info = solver.advance(state, dt, n * dt)
        assert info.converged
    return solver, state


def voidages():
    rng = np.random.default_rng(3)
    return {"uniform": 1.0, "random bed": rng.uniform(0.35, 1.0, GRID.shape)}


@pytest.mark.parametrize("voidage", ["uniform", "random bed"])
@pytest.mark.parametrize("box", ["closed", "outlet"])
def test_ideal_gas_at_rest_is_exponential(box, voidage):
    props = GasProperties()
    bcs = closed_box() if box == "closed" else outlet_on_top()
    _, state = run_at_rest(bcs, props, voidages()[voidage])
    _, Y = GRID.centres()
    k = props.molar_mass * G / (GAS_CONSTANT * props.temperature)
    if box == "outlet":  # prescribed pressure at the centre of the boundary cells above the top
        expected = P_OUT * np.exp(-k * (Y - (GRID.size[1] + 0.5 * GRID.dy)))
    else:  # closed: the level is what the initial state had (reference pressure at mid-height)
        expected = props.reference_pressure * np.exp(-k * (Y - 0.5 * GRID.size[1]))
    assert np.abs(state.p / expected - 1.0).max() < PRESSURE_TOL
    assert np.abs(state.u).max() < VELOCITY_TOL
    assert np.abs(state.v).max() < VELOCITY_TOL
    # it is the exponential, not a straight line: the curvature is resolved far above round-off
    linear = expected[:, 0:1] + (expected[:, -1:] - expected[:, 0:1]) * (Y - Y[:, :1]) / (Y[:, -1:] - Y[:, :1])
    assert np.abs(linear / expected - 1.0).max() > 1e3 * PRESSURE_TOL


@pytest.mark.parametrize("voidage", ["uniform", "random bed"])
def test_constant_density_gas_at_rest_is_linear(voidage):
    props = GasProperties(density=1.2)
    _, state = run_at_rest(outlet_on_top(), props, voidages()[voidage])
    _, Y = GRID.centres()
    expected = P_OUT - 1.2 * G * (Y - (GRID.size[1] + 0.5 * GRID.dy))
    assert np.abs(state.p / expected - 1.0).max() < PRESSURE_TOL
    assert np.abs(state.v).max() < VELOCITY_TOL


def test_constant_density_gas_becomes_hydrostatic_in_one_step():
    """Started from a uniform pressure, the incompressible gas finds the hydrostatic pressure at
    once (the pressure correction is exact) and never moves."""
    props = GasProperties(density=1.2)
    solver, state = run_at_rest(outlet_on_top(), props, 1.0, steps=1, pressure=P_OUT)
    assert np.abs(state.p / solver.hydrostatic_pressure() - 1.0).max() < PRESSURE_TOL
    assert np.abs(state.v).max() < VELOCITY_TOL
