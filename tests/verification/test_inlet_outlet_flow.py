"""Inlets and outlets against free fall: inserted particles reach an outlet plane at the analytic time, and
the outlet's mass flow rate equals the inlet's."""
from __future__ import annotations

import math

import pytest

from fluidem import Simulation
from fluidem.case import validate_case
from fluidem.particles.population import OUTLET_INTERVAL

D, RHO, G, H, V0 = 1e-3, 2500.0, 9.81, 0.05, 0.3  # [m], [kg/m^3], [m/s^2], drop height [m], initial speed down [m/s]


def stream(**inlet):
    return validate_case({
        "name": "stream", "gravity": [0.0, -G, 0.0],
        "particles": {"dimensions": 3, "species": [{"name": "s", "diameter": D, "density": RHO, "count": 0}],
                      "contact": {"model": "hertz_mindlin", "youngs_modulus": 1e7, "poisson_ratio": 0.3,
                                  "restitution": 0.5, "friction": 0.3}},
        "inlets": [{"name": "feed", "lower": [0.0, H - D / 2, 0.0], "upper": [0.02, H + D / 2, 0.02],
                    "velocity": [0.0, -V0, 0.0], **inlet}],
        "outlets": [{"name": "floor", "kind": "plane", "point": [0.0, 0.0, 0.0], "normal": [0.0, 1.0, 0.0]}],
        "time": {"end": 0.2},
    })


def test_first_removal_at_the_free_fall_time():
    sim = Simulation(stream(rate=500.0, stop=0.005, interval=0.005))
    sim.run(until=0.15)
    t_fall = (-V0 + math.sqrt(V0**2 + 2 * G * H)) / G  # centre from y = H to y = 0, starting at V0 downwards
    t_first = sim.population.out_first["floor"][0]
    # removals are checked every OUTLET_INTERVAL: the first is the first check after the crossing
    assert t_fall <= t_first <= t_fall + OUTLET_INTERVAL + 2 * sim.dt
    assert sim.population.out_count["floor"] == 2 and sim.state.n == 0


def test_outlet_mass_rate_equals_inlet_mass_rate():
    q = 2e-3  # [kg/s]
    s = Simulation(stream(mass_rate=q, stop=0.1, interval=0.005)).run(until=0.25)
    m_p = RHO * math.pi / 6 * D**3
    batches = 0.1 / 0.005
    assert s["outlet_floor_mass_kg"] == pytest.approx(s["inlet_feed_mass_kg"], rel=1e-12)
    assert abs(s["inlet_feed_mass_kg"] - q * 0.1) <= m_p
    # between the first and the last batch's removal: (batches − 1) batches over (batches − 1) intervals, each
    # batch within half a particle of q × interval
    assert s["outlet_floor_mass_rate_kg_s"] == pytest.approx(q, abs=m_p / 0.005 / math.sqrt(batches))
