"""A 45 m/s jet into the Hoomans 1996 Table 2 box runs stably at DT = 1e-4 s for 1 s.

Grid 15 × 25 cells of 0.01 × 0.02 m (0.15 m × 0.5 m); bottom: influx cells of voidage 0.4,
45 m/s interstitial (18 m/s superficial) through the centre cell, 4.5 m/s elsewhere
(Hoomans 1996 §5.3.1); no-slip side walls; 101325 Pa at the top; a fixed bed of voidage
0.4 in the lower 0.2 m with Ergun's β (eq. 45, d_p = 4 mm) from the gas velocity of each
step; ideal gas (eq. 44).
"""
import numpy as np

from fluidem.gas import GasProperties, GasSolver, Inflow, PressureOutlet, Segment, StaggeredGrid, Wall

GRID = StaggeredGrid(cells=(15, 25), size=(0.15, 0.5), depth=0.004)
D_P, MU, DT = 4e-3, 1.8e-5, 1e-4
BED = 0.2  # bed height [m]


def make(convection):
    bcs = {"left": Wall(), "right": Wall(), "top": PressureOutlet(pressure=101325.0),
           "bottom": Inflow(segments=[Segment(interstitial=4.5), Segment(interstitial=45.0, start=0.07, end=0.08)],
                            voidage=0.4)}
    solver = GasSolver(GRID, GasProperties(viscosity=MU), bcs, convection=convection)
    _, Y = GRID.centres()
    return solver, solver.initial_state(voidage=np.where(Y < BED, 0.4, 1.0))


def beta(state):
    uc = 0.5 * (state.u[1:] + state.u[:-1])
    vc = 0.5 * (state.v[:, 1:] + state.v[:, :-1])
    e = state.voidage
    b = 150 * (1 - e) ** 2 / e * MU / D_P**2 + 1.75 * (1 - e) * state.rho / D_P * np.hypot(uc, vc)  # eq. 45
    return np.where(e < 0.8, b, 0.0)


def run(convection, seconds):
    solver, state = make(convection)
    steps = int(round(seconds / DT))
    worst_courant, worst_balance, speeds = 0.0, 0.0, []
    for n in range(steps):
        info = solver.advance(state, DT, n * DT, beta=beta(state), solids_u=0.0, solids_v=0.0)
        assert info.converged, (n, info)
        worst_courant = max(worst_courant, info.courant)
        worst_balance = max(worst_balance, info.mass_balance_error)
        if n % 100 == 99:
            speeds.append(max(np.abs(state.u).max(), np.abs(state.v).max()))
    return solver, state, worst_courant, worst_balance, np.array(speeds)


def test_jet_runs_stably_for_one_second_upwind():
    solver, state, courant, balance, speeds = run("upwind", 1.0)
    assert np.all(np.isfinite(state.p)) and np.all(np.isfinite(state.v))
    assert courant < 1.0  # explicit convection inside its stability limit all along
    assert balance < 1e-8
    assert speeds.max() <= 45.0 * (1 + 1e-9)  # no velocity beyond the jet's: no growing oscillation
    # settled: the last 0.2 s change the fields by less than 0.1 % of the jet speed
    assert np.ptp(speeds[-20:]) < 1e-3 * 45.0
    # the bed's pressure drop is Ergun's at the mean superficial velocity, 2.88 m/s, or a little
    # more (where the jet spreads, the quadratic term weighs more): measured 1.004 times
    p_mean = state.p.mean(axis=0)
    j_bed = int(round(BED / GRID.dy))
    superficial = (1.8 * 0.14 + 18.0 * 0.01) / 0.15
    rho = state.rho[:, :j_bed].mean()
    ergun = (150 * 0.6**2 / 0.4**3 * MU * superficial / D_P**2 + 1.75 * 0.6 / 0.4**3 * rho * superficial**2 / D_P)
    ratio = (p_mean[0] - p_mean[j_bed]) / (ergun * j_bed * GRID.dy)
    assert 1.0 < ratio < 1.05, ratio


def test_jet_runs_stably_tvd():
    _, state, courant, balance, speeds = run("tvd", 0.2)
    assert np.all(np.isfinite(state.v))
    assert courant < 0.5  # TVD with explicit Euler: stable below 0.5
    assert balance < 1e-8
    assert speeds.max() <= 45.0 * (1 + 1e-9)
