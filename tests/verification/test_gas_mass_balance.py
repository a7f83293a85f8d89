"""Gas mass balance of every step: |inflow − outflow − d(mass)/dt| / inflow < 1e-8.

The set-up is the Hoomans 1996 single-orifice bed (Table 2 grid, 45 m/s jet through influx
cells of voidage 0.4, Ergun drag in a bed of voidage 0.4), started from rest so that the
first steps carry the largest pressure transient, for the ideal and the constant-density
gas; and the same with a voidage field that changes every step, as particles would make
it (the accumulation term ∂(ερ)/∂t then moves gas even where the velocity is steady).
d(mass)/dt is the change of Σ ε ρ V over the step divided by dt, computed independently
of the solver from the states before and after.
"""
import numpy as np
import pytest

from fluidem.gas import GasProperties, GasSolver, Inflow, PressureOutlet, Segment, StaggeredGrid, Wall

GRID = StaggeredGrid(cells=(15, 25), size=(0.15, 0.5), depth=0.004)
D_P, MU = 4e-3, 1.8e-5
BALANCE_TOL = 1e-8  # the required tolerance; the solver's mass residual (1e-10) bounds it


def jet_bed(density):
    bcs = {"left": Wall(), "right": Wall(), "top": PressureOutlet(pressure=101325.0),
           "bottom": Inflow(segments=[Segment(interstitial=4.5), Segment(interstitial=45.0, start=0.07, end=0.08)],
                            voidage=0.4)}
    solver = GasSolver(GRID, GasProperties(viscosity=MU, density=density), bcs)
    _, Y = GRID.centres()
    return solver, solver.initial_state(voidage=np.where(Y < 0.2, 0.4, 1.0))


def beta(state):
    uc = 0.5 * (state.u[1:] + state.u[:-1])
    vc = 0.5 * (state.v[:, 1:] + state.v[:, :-1])
    e = state.voidage
    b = 150 * (1 - e) ** 2 / e * MU / D_P**2 + 1.75 * (1 - e) * state.rho / D_P * np.hypot(uc, vc)  # eq. 45
    return np.where(e < 0.8, b, 0.0)


def mass(state):
    return float(np.sum(state.voidage * state.rho)) * GRID.cell_volume


@pytest.mark.parametrize("density", [None, 1.2], ids=["ideal gas", "constant density"])
@pytest.mark.parametrize("moving_voidage", [False, True], ids=["fixed bed", "moving voidage"])
def test_mass_balance_every_step(density, moving_voidage):
    solver, state = jet_bed(density)
    X, Y = GRID.centres()
    dt, t = 1e-4, 0.0
    worst = 0.0
    for n in range(150):
        new_voidage = None
        if moving_voidage:  # a bed surface that waves and a bubble that rises through the bed
            surface = 0.2 + 0.02 * np.sin(2 * np.pi * (X / 0.15 + (t + dt) / 0.05))
            bubble = np.hypot(X - 0.075, Y - (0.05 + 2.0 * (t + dt))) < 0.03
            new_voidage = np.where((Y < surface) & ~bubble, 0.4, 1.0)
        m0 = mass(state)
        info = solver.advance(state, dt, t, voidage=new_voidage, beta=beta(state), solids_u=0.0, solids_v=0.0)
        t += dt
        assert info.converged
        dm_dt = (mass(state) - m0) / dt
        err = abs(info.inflow_rate - info.outflow_rate - dm_dt) / info.inflow_rate
        worst = max(worst, err, info.mass_balance_error)
    assert worst < BALANCE_TOL, worst
    # the inflow is what the boundary condition prescribes: Σ ε_in ρ u A over the bottom faces
    expected_in = 0.4 * np.sum(state.rho[:, 0] * solver.vfix[:, 0]) * GRID.area_y
    assert info.inflow_rate == pytest.approx(expected_in, rel=1e-12)
