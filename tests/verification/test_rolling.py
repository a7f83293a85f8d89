"""A sphere launched sliding without spin on a plane ends rolling at 5/7 of its launch speed.

Friction at the contact acts until the contact point stops slipping. It changes m v
and (I/a) ω by equal and opposite amounts, so m v + (I/a) ω = m v0 is conserved;
with rolling v = a ω and I = (2/5) m a² this gives v = v0 / (1 + 2/5) = 5/7 v0,
independent of the friction coefficient, the normal force and the tangential spring.
The slip lasts t_s = 2 v0 / (7 μ g).
"""
from __future__ import annotations

import math

import numpy as np
import pytest

DIAMETER = 4e-3  # [m]
DENSITY = 2500.0  # [kg/m^3]
G = 9.81  # [m/s^2]
V0 = 0.5  # launch speed [m/s]
FRICTION = 0.3

# Tolerances:
# SPEED_TOL = 1 % (the brief): the scheme conserves m v + (I/a) ω exactly (both half kicks apply the same
#   tangential force with lever arm a), so the only error is the left-over stick oscillation of the
#   tangential spring, well under 0.1 % after the damping time; a wrong torque sign or lever arm, or a
#   slip velocity missing the a ω term, moves the end speed by > 10 %.
# SLIP_TOL = 1 % of v0: halfway through the slip, the slip speed follows v0 − 3.5 μ g t (the tangential
#   spring loads in ~1e-7 s, so the only error is round-off); at the end the contact point is at rest.
SPEED_TOL = 0.01
SLIP_TOL = 0.01


def equilibrium_overlap(law, mass, radius):
    """Static overlap under the sphere's weight on the wall (so that it starts without bouncing)."""
    if law["model"] == "linear_spring_dashpot":
        return mass * G / law["stiffness"]
    # wall of the same material: 1/E* = 2 (1 − ν²)/E; F = (4/3) E* sqrt(R) δ^(3/2)
    e_star = law["youngs_modulus"] / (2.0 * (1.0 - law["poisson_ratio"] ** 2))
    return (mass * G / (4.0 / 3.0 * e_star * math.sqrt(radius))) ** (2.0 / 3.0)


@pytest.mark.parametrize("model", ["linear_spring_dashpot", "hertz_mindlin"])
def test_sliding_sphere_ends_rolling_at_five_sevenths(make_engine, contact_law, model):
    # e = 0.5 gives the tangential dashpot enough damping to quench the stick oscillation quickly
    law = contact_law(model, restitution=0.5, friction=FRICTION)
    a = 0.5 * DIAMETER
    mass = DENSITY * math.pi * DIAMETER**3 / 6.0
    z0 = a - equilibrium_overlap(law, mass, a)
    floor = {"name": "floor", "kind": "plane", "point": [0.0, 0.0, 0.0], "normal": [0.0, 0.0, 1.0]}
    eng = make_engine([[0.0, 0.0, z0]], DIAMETER, [[V0, 0.0, 0.0]], contact=law, walls=[floor],
                      gravity=(0.0, 0.0, -G), density=DENSITY, impact_velocity=V0)
    assert eng.state.omega[0] == pytest.approx([0.0, 0.0, 0.0], abs=0.0)

    t_slip = 2.0 * V0 / (7.0 * FRICTION * G)
    # while sliding, Coulomb friction μ m g slows the slip v − a ω_y at the rate μ g (1 + m a²/I) = 3.5 μ g
    eng.advance(int(0.5 * t_slip / eng.dt))
    v, w = eng.state.velocity[0], eng.state.omega[0]
    expected_slip = V0 - 3.5 * FRICTION * G * eng.time
    assert abs(v[0] - a * w[1] - expected_slip) < SLIP_TOL * V0, "sliding friction is not μ m g"
    # run to twice the slip time: rolling since t_slip, the stick oscillation damped out
    eng.advance(int(1.5 * t_slip / eng.dt))
    v, w = eng.state.velocity[0], eng.state.omega[0]
    assert abs(v[0] - 5.0 / 7.0 * V0) < SPEED_TOL * 5.0 / 7.0 * V0, f"end speed {v[0] / V0:.5f} v0, expected 5/7"
    # contact point at rest: v + ω × (−a ẑ) = (v_x − a ω_y) x̂ + (v_y + a ω_x) ŷ
    slip = np.hypot(v[0] - a * w[1], v[1] + a * w[0])
    assert slip < SLIP_TOL * V0, f"still slipping at {slip:.3g} m/s"
    # it stays on the plane and moves in x only
    assert abs(v[1]) < 1e-12 and abs(v[2]) < 1e-3 * V0
