"""Gas through a fixed packed bed: the pressure drop is Ergun's.

Uniform voidage ε = 0.4, solids at rest, β of Hoomans 1996 eq. 45 evaluated from the
gas velocity each step. In steady plug flow eq. 43 reduces to −ε dp/dy = β u + ε ρ |g|
with u = U/ε (U superficial), and β u/ε = 150 (1−ε)²/ε³ μ U/d² + 1.75 (1−ε)/ε³ ρ U²/d,
which is Ergun's equation. Particle Reynolds numbers Re_p = ε ρ |u| d / μ (eq. 47) from
1 to 500.
"""
import numpy as np
import pytest

from fluidem.gas import FreeSlip, GasProperties, GasSolver, Inflow, PressureOutlet, StaggeredGrid

D_P = 4e-3  # particle diameter [m]
EPS = 0.4
MU = 1.8e-5
G = 9.81


def ergun_beta(eps, rho, slip):
    """Hoomans 1996 eq. 45 [kg m^-3 s^-1]."""
    return 150.0 * (1 - eps) ** 2 / eps * MU / D_P**2 + 1.75 * (1 - eps) * rho / D_P * slip


def ergun_gradient(superficial, rho):
    """Ergun's frictional pressure gradient [Pa/m]."""
    return (150.0 * (1 - EPS) ** 2 / EPS**3 * MU * superficial / D_P**2
            + 1.75 * (1 - EPS) / EPS**3 * rho * superficial**2 / D_P)


def packed_bed(re_p: float, density):
    grid = StaggeredGrid(cells=(3, 20), size=(0.03, 0.2), depth=0.01)
    props = GasProperties(viscosity=MU, density=density)
    rho0 = props.density_at(101325.0)
    superficial = re_p * MU / (rho0 * D_P)  # inlet superficial velocity for Re_p at the outlet density
    bcs = {"left": FreeSlip(), "right": FreeSlip(), "bottom": Inflow(superficial=superficial, voidage=EPS),
           "top": PressureOutlet(pressure=101325.0)}
    solver = GasSolver(grid, props, bcs, gravity=(0.0, -G))
    state = solver.initial_state(voidage=EPS, velocity=(0.0, superficial / EPS))
    dt = min(1e-3, 0.4 * grid.dy * EPS / superficial)
    t = 0.0
    for _ in range(400):
        vc = 0.5 * (state.v[:, 1:] + state.v[:, :-1])
        beta = ergun_beta(state.voidage, state.rho, np.abs(vc))
        info = solver.advance(state, dt, t, beta=beta, solids_u=0.0, solids_v=0.0)
        t += dt
    assert info.converged
    return grid, state, superficial


@pytest.mark.parametrize("re_p", [1.0, 10.0, 100.0, 500.0])
def test_ergun_pressure_drop_constant_density(re_p):
    grid, state, superficial = packed_bed(re_p, density=1.2)
    j0, j1 = 2, grid.ny - 3
    dp = state.p[:, j0] - state.p[:, j1]
    length = (j1 - j0) * grid.dy
    frictional = dp / length - 1.2 * G  # minus the weight of the gas
    expected = ergun_gradient(superficial, 1.2)
    # required tolerance 0.5 %; plug flow is an exact discrete solution, so the error is round-off
    assert np.abs(frictional / expected - 1.0).max() < 5e-3
    assert np.abs(frictional / expected - 1.0).max() < 1e-8
    assert np.abs(state.v[:, 1:-1] - superficial / EPS).max() < 1e-9 * superficial / EPS


@pytest.mark.parametrize("re_p", [1.0, 500.0])
def test_ergun_pressure_drop_ideal_gas_locally(re_p):
    """With the ideal gas (eq. 44) the density falls along the bed and the velocity rises, with the
    mass flux ρU constant; Ergun holds locally with the local ρ and U."""
    grid, state, _ = packed_bed(re_p, density=None)
    rho_f = 0.5 * (state.rho[1, :-1] + state.rho[1, 1:])
    mass_flux = EPS * rho_f * state.v[1, 1:-1]  # ε ρ_f v through the interior y-faces
    assert np.ptp(mass_flux) < 1e-9 * mass_flux.mean()  # steady: the same through every face
    j = np.arange(2, grid.ny - 3)
    grad = (state.p[1, j] - state.p[1, j + 1]) / grid.dy  # at the face between j and j + 1
    rho_f = 0.5 * (state.rho[1, j] + state.rho[1, j + 1])
    superficial_f = EPS * state.v[1, j + 1]
    expected = ergun_gradient(superficial_f, rho_f) + rho_f * G
    assert np.abs(grad / expected - 1.0).max() < 5e-3
