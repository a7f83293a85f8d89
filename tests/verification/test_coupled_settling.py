"""A lone sphere settling in still gas reaches the terminal velocity of its drag law.

The gas box is a 2D grid of large depth, so that the particle's drag hardly moves the
gas (its solids fraction is ~1e-9); the gas starts hydrostatic. The terminal velocity
solves the force balance of the closure's own ``particle_force`` (ε → 1, gas at rest):

    m g = F_drag(v_t) + ρ_g V_p g        (buoyancy from −V_p ∇p when that force is on)

with scipy's brentq. Particle: 100 µm glass-like (2500 kg/m^3) in air, Re_t ≈ 3, response
time ≈ 0.05 s; 0.4 s of settling is ~8 response times.
"""
import math

import numpy as np
import pytest
from scipy.optimize import brentq

from fluidem.case import validate_case
from fluidem.coupling import drag_laws
from fluidem.errors import CaseError
from fluidem.simulation import Simulation

from _helpers.settling import D, G, MU, RHO_P, settling_case


def terminal_velocity(drag, rho_g, buoyancy):
    law = drag_laws.get(drag)()
    vp = math.pi / 6.0 * D**3
    weight = (RHO_P - (rho_g if buoyancy else 0.0)) * vp * G

    def balance(v):
        f = law.particle_force(1.0, np.zeros((1, 3)), np.array([[0.0, -v, 0.0]]), D, rho_g, MU)
        return f[0, 1] - weight

    return brentq(balance, 1e-6, 10.0, xtol=1e-12)


@pytest.mark.parametrize("drag,density,pgf,update,exchange", [
    ("hoomans1996", 1.2, True, "frozen", "particle"),
    ("hoomans1996", 1.2, False, "frozen", "particle"),
    ("di_felice", None, True, "frozen", "particle"),
    ("di_felice", 1.2, True, "substep", "particle"),
    # Hoomans' own model: total force of eqs 35-39, no buoyancy (eq. 34), the gas on β of eqs 45-47
    ("hoomans1996_total", 1.2, False, "substep", "cell_beta"),
])
def test_lone_particle_reaches_the_terminal_velocity_of_its_drag_law(drag, density, pgf, update, exchange):
    end = 0.4 if update == "frozen" else 0.3
    case = validate_case(settling_case(drag, density, pgf, end=end, drag_update=update, momentum_exchange=exchange))
    sim = Simulation(case)
    sim.advance(int(round(end / sim.dt)))
    rho_g = float(sim.gas.state.rho.mean())
    vt = terminal_velocity(drag, rho_g, pgf)
    v = -sim.state.velocity[0, 1]
    assert abs(v - vt) < 0.005 * vt, (v, vt)  # measured: 0.01-0.03 %
    assert abs(sim.state.velocity[0, 0]) < 1e-3 * vt
    assert sim.gas.gas_steps == round(end / case.gas.dt)
    # the DEM step divides the gas step
    assert sim.gas.substeps * sim.dt == pytest.approx(case.gas.dt, rel=1e-12)


def test_gas_case_errors_name_the_allowed_values():
    bad = settling_case()
    bad["coupling"]["drag"] = "stokes"
    with pytest.raises(CaseError, match="allowed: .*hoomans1996"):
        validate_case(bad)
    bad = settling_case()
    bad["gas"]["boundaries"]["top"] = {"kind": "outlet"}
    with pytest.raises(CaseError, match="allowed: .*pressure_outlet"):
        validate_case(bad)
    bad = settling_case()
    del bad["gas"]["boundaries"]["left"]
    with pytest.raises(CaseError, match="missing side"):
        validate_case(bad)
    bad = settling_case()
    bad["gas"]["boundaries"]["left"] = {"kind": "wall", "pressure": 1e5}
    with pytest.raises(CaseError, match="does not take pressure"):
        validate_case(bad)
    bad = settling_case()
    bad["coupling"]["drag_update"] = "sometimes"
    with pytest.raises(CaseError, match="drag_update"):
        validate_case(bad)
    bad = settling_case()
    del bad["gas"]
    with pytest.raises(CaseError, match=r"\[coupling\] needs a \[gas\]"):
        validate_case(bad)


def test_gas_case_round_trips_through_toml():
    import tomllib

    case = validate_case(settling_case())
    again = validate_case(tomllib.loads(case.to_toml()))
    assert again == case
