"""Per-step mass balance of the 3D gas: inflow − outflow = accumulation, to the solver tolerance.

A 3D bed (10 × 14 × 8 cells, 0.1 × 0.14 × 0.08 m): inflow at the bottom through influx cells of voidage
0.4 (a 0.3 m/s superficial background and a pulsed circular jet), a pressure outlet on top, no-slip walls;
ideal gas, a voidage field that changes every step (a bed whose surface waves and a bubble that rises), β
from Ergun's law with it. Each step's mass balance closes to the mass-residual tolerance: |in − out −
d(mass)/dt| ≤ tolerance × reference flow (the residual is the sum of the cells' imbalances, which the
domain's balance telescopes). Also with continuous outflow on top instead of the pressure outlet, and
with the multigrid-preconditioned GMRES in place of SuperLU.
"""
import numpy as np
import pytest

from fluidem.gas import (
    Circle,
    GasProperties,
    GasSolver,
    Inflow,
    Outflow,
    PressureOutlet,
    Pulse,
    StaggeredGrid,
    Wall,
)

TOL = 1e-10


def voidage_at(grid, t):
    X, Y, Z = grid.centres()
    surface = 0.06 + 0.005 * np.sin(2 * np.pi * (X / 0.1 + Z / 0.08 - t / 0.01))
    eps = 0.45 + 0.55 / (1.0 + np.exp(-(Y - surface) / 0.005))
    r = np.sqrt((X - 0.05) ** 2 + (Y - (0.02 + 2.0 * t)) ** 2 + (Z - 0.04) ** 2)
    return np.clip(eps + 0.5 / (1.0 + np.exp((r - 0.012) / 0.003)), 0.45, 1.0)


@pytest.mark.parametrize("top, linear_solver", [(PressureOutlet(), "superlu"), (Outflow(), "superlu"),
                                                (PressureOutlet(), "multigrid")])
def test_inflow_minus_outflow_is_the_accumulation_every_step(top, linear_solver):
    grid = StaggeredGrid(cells=(10, 14, 8), size=(0.1, 0.14, 0.08))
    jet = Circle(centre=(0.05, 0.04), radius=0.012, interstitial=Pulse(6.0, start=2e-4, duration=3e-4, otherwise=2.0))
    bcs = {s: Wall() for s in grid.sides}
    bcs.update(bottom=Inflow(superficial=0.3, voidage=0.4, patches=[jet]), top=top)
    props = GasProperties()
    solver = GasSolver(grid, props, bcs, linear_solver=linear_solver, tolerance=TOL)
    assert solver.linear_solver == linear_solver
    state = solver.initial_state(voidage=voidage_at(grid, 0.0))
    dt, d_p = 1e-4, 1e-3
    t = 0.0
    for _ in range(8):
        eps = voidage_at(grid, t + dt)
        beta = 150.0 * (1 - eps) ** 2 / eps * props.viscosity / d_p**2  # Ergun's viscous term (Hoomans eq. 45)
        info = solver.advance(state, dt, t, voidage=eps, beta=beta, solids_u=0.0, solids_v=0.0, solids_w=0.0)
        t += dt
        assert info.converged
        reference = info.inflow_rate + info.outflow_rate + abs(info.mass_change_rate)
        assert abs(info.inflow_rate - info.outflow_rate - info.mass_change_rate) <= TOL * reference
        assert info.inflow_rate > 0.0 and info.outflow_rate > 0.0
    # the patch and background flows; the gas enters at the pressure under the bed, 0.14 % above the outlet's
    rho = props.density_at(props.reference_pressure)
    assert info.inflow_rate == pytest.approx(rho * 0.4 * (0.3 / 0.4 * (0.1 * 0.08 - jet.area()) + 2.0 * jet.area()),
                                             rel=3e-3)
