"""The Hertzian variant of the linear spring–dashpot: Sun 2007 eq. 21 with f(δ/d) = sqrt(δ/d), d = 4R*.

Two spheres at rest overlapping by δ push with F = k_n δ sqrt(δ/d); approaching at speed v with
F = sqrt(δ/d)(k_n δ + η_n v), η_n = 2 ζ sqrt(k_n m_eff) as for the linear law (Sun 2007 eqs 21, 25–26).
For equal spheres d = 4R* is their diameter.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from fluidem.particles.contact.spring_dashpot import damping_ratio

K = 1e4  # [N/m]
D = (4e-3, 3e-3)  # [m]
DENSITY = 2500.0


@pytest.mark.parametrize("diameters", [(4e-3, 4e-3), D], ids=["equal", "unequal"])
@pytest.mark.parametrize("depth", [1e-5, 1e-4])
def test_hertzian_force_overlap_relation(two_particles, diameters, depth):
    r_eff = 0.25 * diameters[0] * diameters[1] / (0.5 * (diameters[0] + diameters[1]))
    overlap = depth * min(diameters)
    eng = two_particles(overlap=overlap, diameters=diameters, stiffness=K, nonlinearity="hertzian", restitution=0.8)
    f = eng.state.force[0, 0]  # along −x on particle 0 (particle 1 at +x)
    expected = K * overlap * math.sqrt(overlap / (4.0 * r_eff))
    # 1e-9: δ = a_0 + a_1 − r carries the round-off of r (~1e-19 m) against δ ≥ 3e-8 m
    assert -f == pytest.approx(expected, rel=1e-9)
    if diameters[0] == diameters[1]:
        assert expected == pytest.approx(K * overlap * math.sqrt(overlap / diameters[0]), rel=1e-14)
    # the linear law at the same overlap: f = 1
    lin = two_particles(overlap=overlap, diameters=diameters, stiffness=K, restitution=0.8)
    assert -lin.state.force[0, 0] == pytest.approx(K * overlap, rel=1e-9)
    # approaching: the dashpot carries the same factor
    v = 0.05
    moving = two_particles(overlap=overlap, diameters=diameters, stiffness=K, nonlinearity="hertzian",
                           restitution=0.8, vel=[[0.0, 0.0, 0.0], [-v, 0.0, 0.0]])
    m = [DENSITY * math.pi * d**3 / 6.0 for d in diameters]
    m_eff = m[0] * m[1] / (m[0] + m[1])
    eta = 2.0 * damping_ratio(0.8) * math.sqrt(K * m_eff)
    assert -moving.state.force[0, 0] == pytest.approx(math.sqrt(overlap / (4.0 * r_eff)) * (K * overlap + eta * v),
                                                     rel=1e-9)


def test_hertzian_variant_has_its_own_code():
    from fluidem.particles.contact import LinearSpringDashpot
    from fluidem.particles.contact import spring_dashpot as sd

    assert LinearSpringDashpot(stiffness=K).pack(None, None)[0] == sd.CODE
    assert LinearSpringDashpot(stiffness=K, nonlinearity="hertzian").pack(None, None)[0] == sd.HERTZIAN
    assert np.isfinite(LinearSpringDashpot(stiffness=K, nonlinearity="hertzian").contact_time(1e-5, 1e-3, 1.0))
