"""Equal and opposite pair forces, and no force out of contact, for every registered contact model.

Two spheres of different sizes overlap on the x axis while sliding past each other and
spinning; with no gravity and no walls, ``state.force`` right after construction holds
only the pair force. Parametrised over the registry, so a new model is tested without
new code (it only needs default parameters in tests/conftest.py).
"""
from __future__ import annotations

import numpy as np
import pytest

from fluidem.particles.contact import contact_models, soft_contact_models

DIAMETERS = (4e-3, 3e-3)  # [m] unequal, so that m_eff, R* and lever arms differ between the bodies
# relative sliding (y, z) plus approach (x), and spins about every axis
VELOCITY = np.array([[0.3, 0.2, -0.1], [-0.2, -0.3, 0.25]])  # [m/s]
OMEGA = np.array([[40.0, -25.0, 60.0], [-30.0, 55.0, 20.0]])  # [rad/s]


@pytest.mark.parametrize("model", soft_contact_models())
def test_pair_forces_are_equal_and_opposite(two_particles, model):
    # e < 1 so that the tangential dashpot acts at once (the tangential spring starts unstretched)
    eng = two_particles(overlap=0.01 * DIAMETERS[1], model=model, diameters=DIAMETERS, vel=VELOCITY,
                        omega=OMEGA, restitution=0.5, friction=0.3)
    f, t = eng.state.force, eng.state.torque
    # Exact: the engine adds one pair force to i and subtracts the same number from j (no round-off)
    np.testing.assert_array_equal(f[0], -f[1])
    n = np.array([-1.0, 0.0, 0.0])  # unit normal from particle 1 to particle 0
    fn = f[0] @ n
    ft = f[0] - fn * n
    assert fn > 0.0, "the normal force must push the particles apart"
    assert np.linalg.norm(ft) > 1e-3 * fn, "the test needs a tangential force (sliding + spin)"
    # Coulomb limit |F_t| ≤ μ |F_n|; an adhesive law's is μ (F_n + 2 F_c), F_c = (3/2) π γ R* (Thornton & Yin 1991)
    r_eff = 0.25 * DIAMETERS[0] * DIAMETERS[1] / (0.5 * sum(DIAMETERS))
    shift = 3.0 * np.pi * contact_models.get(model).example.get("surface_energy", 0.0) * r_eff
    assert np.linalg.norm(ft) <= 0.3 * (abs(fn) + shift) * (1 + 1e-12), "Coulomb limit |F_t| ≤ μ |F_n|"
    # torques come from the tangential force only: perpendicular to n and F_t, same direction on both
    # bodies (each is r_c × F with r_c towards the contact point and the force reversed)
    for k in range(2):
        assert abs(t[k] @ n) < 1e-12 * np.linalg.norm(t[k])
        assert abs(t[k] @ ft) < 1e-12 * np.linalg.norm(t[k]) * np.linalg.norm(ft)
    assert np.linalg.norm(np.cross(t[0], t[1])) < 1e-12 * np.linalg.norm(t[0]) * np.linalg.norm(t[1])
    assert t[0] @ t[1] > 0.0


@pytest.mark.parametrize("model", soft_contact_models())
@pytest.mark.parametrize("gap", [0.0, 1e-9, 1e-4], ids=["touching", "1nm", "0.1mm"])
def test_no_force_without_overlap(two_particles, model, gap):
    """At zero overlap the force is exactly zero — the dashpot must not act on approaching bodies."""
    eng = two_particles(overlap=-gap, model=model, diameters=DIAMETERS, vel=VELOCITY, omega=OMEGA,
                        restitution=0.5, friction=0.3)
    assert np.all(eng.state.force == 0.0) and np.all(eng.state.torque == 0.0)


@pytest.mark.parametrize("model", [m for m in soft_contact_models() if not contact_models.get(m).adhesive])
def test_elastic_force_vanishes_continuously(two_particles, model):
    """Bodies at rest: F(δ) → 0 as δ → 0 (no jump at first touch).

    At δ = 1e-9 d the force must be below 1e-5 of the force at δ = 1e-3 d: linear springs
    give 1e-6, Hertz 1e-9; a constant offset (e.g. an adhesive term) would give ~1. Adhesive laws jump to
    −(8/9) F_c at touch by design (test_jkr.py).
    """
    small = two_particles(overlap=1e-9 * DIAMETERS[1], model=model, diameters=DIAMETERS)
    ref = two_particles(overlap=1e-3 * DIAMETERS[1], model=model, diameters=DIAMETERS)
    f_small, f_ref = np.linalg.norm(small.state.force[0]), np.linalg.norm(ref.state.force[0])
    assert f_ref > 0.0
    assert f_small < 1e-5 * f_ref
