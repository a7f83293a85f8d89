"""A settled bed: the walls carry its weight.

In static equilibrium every particle's acceleration is zero, the pair forces cancel
in pairs (Newton's third law), and so the forces of the particles on all the box planes
sum, along gravity, to the bed weight N ρ (π/6) d³ g — friction on the side walls
included. The wall forces come from ``analysis.probes.wall_forces``, which recomputes
the wall contacts independently of the engine's force sums.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from fluidem.analysis.probes import energies, wall_forces
from fluidem.particles.softsphere import SoftSphereEngine

G = 9.81
N = 150
# Tolerance 0.5 % of the weight (the brief). "Settled" below means KE < 1e-5 W d and every particle's net
# force under 1 % of its own weight; at that point the measured residual Σ m a was ≤ 1e-4 W (linear and
# Hertz). A bed whose pair forces did not cancel, or a probe that dropped wall friction (the side walls
# carry ≈ 2 % of the weight here) or a wall's sign, misses by more than 0.5 %.
WEIGHT_TOL = 5e-3
SETTLE_KE = 1e-5  # [W d]
SETTLE_FORCE = 1e-2  # [m g] per particle
CHUNK = 0.02  # [s] simulated between checks
MAX_TIME = 1.5  # [s] simulated; the beds settle in 0.3–0.5 s


@pytest.mark.parametrize("model", ["linear_spring_dashpot", "hertz_mindlin"])
def test_wall_forces_carry_the_settled_bed(tiny_bed_case, model):
    case = tiny_bed_case(n=N, model=model, restitution=0.3, friction=0.3)
    assert tuple(case.gravity) == (0.0, 0.0, -G)
    sp = case.particles.species[0]
    weight = N * sp.density * math.pi / 6.0 * sp.diameter**3 * G  # analytic, not the engine's masses
    down = np.array([0.0, 0.0, -1.0])

    eng = SoftSphereEngine(case)
    st = eng.state
    chunk = max(1, round(CHUNK / eng.dt))
    while True:
        eng.advance(chunk)
        ke = energies(eng)["kinetic_J"]
        worst = np.max(np.linalg.norm(st.force, axis=1) / (st.mass * G))
        if ke < SETTLE_KE * weight * sp.diameter and worst < SETTLE_FORCE:
            break
        assert eng.time < MAX_TIME, f"bed not settled after {eng.time:.2f} s (KE {ke:.3g} J, max |F|/mg {worst:.3g})"

    forces = wall_forces(eng)
    assert len(forces) == 6  # all box planes
    carried = sum(float(f @ down) for f in forces.values())
    assert abs(carried - weight) < WEIGHT_TOL * weight, f"walls carry {carried / weight:.5f} of the weight"
    # the bed has settled into the lower part of the box (from a lattice 10 layers high)
    assert np.all((st.position[:, 2] > 0.0) & (st.position[:, 2] < 10 * sp.diameter))
