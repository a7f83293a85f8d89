"""Validation: Hoomans et al. 1996 §5.1 with the hard-sphere engine, the settled bed of the pour.

The hard-sphere pour of tests/verification/test_hardsphere_pour.py (the built-in ``pour`` case with
e = e_w = 0.9, μ = μ_w = 0.3, collapse remedy off, DT = 1e-4 s) run on to t = 0.35 s, when the bed rests:
about 3.7e8 collisions, 7 minutes on one core. Published area fraction of the settled bed:
0.832 ± 0.010 (Hoomans), 0.80 (Hogue & Newland), 0.805 (Rosato et al.).
"""
from __future__ import annotations

import numpy as np
import pytest

from fluidem.analysis import probes as P
from fluidem.particles.hardsphere import HardSphereEngine

from _helpers.hardsphere import max_overlap, pour_case, relative_energy_error

pytestmark = pytest.mark.validation

HEXAGONAL = np.pi / (2 * np.sqrt(3))  # 0.9069, densest packing of equal discs


@pytest.fixture(scope="module")
def settled():
    """The pour run to t = 0.35 s (the bed rests by ~0.3 s): about 3.7e8 collisions, 7 minutes on one core."""
    eng = HardSphereEngine(pour_case(1e-4))
    e0 = eng.energies()["total_J"]
    eng.advance(3500)
    return eng, e0


def test_settled_hard_sphere_pour_rests_without_overlap(settled):
    """Measured at t = 0.35 s: kinetic energy 2.3e-8 E_0, energy error +8.3e-4 (growing by ~4.6e-4 per
    0.1 s at rest, the O(m g² DT²) per step of tests/verification/test_hardsphere_pour.py), area
    fraction 0.8437."""
    eng, e0 = settled
    e = eng.energies()
    assert e["kinetic_J"] < 1e-6 * e0, "the bed must rest"
    assert abs(relative_energy_error(eng, e0)) < 2e-3
    assert max_overlap(eng) < 1e-12
    assert P.surface_packing_fraction(eng) < HEXAGONAL


@pytest.mark.xfail(strict=True, reason="hard-sphere pour packs 0.8437 (seed 1996) vs Hoomans 0.832 ± 0.010")
def test_settled_hard_sphere_pour_packs_like_hoomans(settled):
    """Hoomans 1996 §5.1: area fraction 0.832 ± 0.010 (0.80 Hogue & Newland, 0.805 Rosato et al.), span
    0.79–0.842 as for the soft-sphere pour (tests/validation/test_pour.py). We settle denser, 0.8437:
    just above the span. The box fits 24 equal spheres exactly, and our bed crystallises into
    rows near the floor. A strict xfail: the day this passes, the note must be revisited."""
    eng, _ = settled
    phi = P.surface_packing_fraction(eng)
    assert 0.79 <= phi <= 0.842, f"packing fraction {phi:.4f}"
