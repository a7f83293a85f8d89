"""Elastic, frictionless spheres in a closed box conserve their total energy.

With e = 1 and μ = 0 every force is conservative: the total energy
kinetic + rotational + gravitational + elastic (½ k δ² for linear springs,
(2/5) k_h δ^(5/2) for Hertz, k_h = (4/3) E* sqrt(R*)) must stay constant.
Velocity Verlet is symplectic, so the sampled energy only oscillates by
O((ω dt)²) of the energy held in contacts and does not drift.
The elastic energy is computed here independently of the engine, by brute force.
"""
from __future__ import annotations


import numpy as np
import pytest

from fluidem.analysis.probes import energies

DIAMETER = 4e-3  # [m]
DENSITY = 2500.0  # [kg/m^3]
N_SIDE = 4  # particles per lattice row
N = 40
BOX = 6 * DIAMETER  # cube side [m]: solid fraction 0.19, many collisions
STEPS = 100_000
SAMPLE_EVERY = 1_000
STEPS_PER_CONTACT = 100  # dt = t_c/100
# Tolerance 0.1 % of the mechanical energy (the brief; JAX-MD uses 1 %): at dt = t_c/100 the velocity-Verlet
# energy error during a contact is ≈ (π/100)²/8 ≈ 1.2e-4 of the energy in that contact (measured max
# 6.5e-5 of the total); a first-order or wrongly ordered integrator, or a dashpot left on at e = 1, drifts
# by more than 1 % over these 1e5 steps.
DRIFT_TOL = 1e-3


def elastic_energy(eng, law) -> float:
    """Σ over touching pairs and particle–wall contacts of the spring energy [J]."""
    st = eng.state
    pos, r = st.position, st.radius
    i, j = np.triu_indices(st.n, 1)
    ov = r[i] + r[j] - np.linalg.norm(pos[i] - pos[j], axis=1)
    touch = ov > 0
    gap = np.einsum("nwk,wk->nw", pos[:, None, :] - eng.wall_point0[None], eng.wall_normal) - r[:, None]
    wall_ov = np.clip(-gap, 0.0, None)
    if law["model"] == "linear_spring_dashpot":
        return 0.5 * law["stiffness"] * (np.sum(ov[touch] ** 2) + np.sum(wall_ov**2))
    # Hertz; walls of the particle material: 1/E* = 2 (1 − ν²)/E for both pairs and walls
    e_star = law["youngs_modulus"] / (2.0 * (1.0 - law["poisson_ratio"] ** 2))
    r_pair = r[i] * r[j] / (r[i] + r[j])
    pair = np.sum(0.4 * 4.0 / 3.0 * e_star * np.sqrt(r_pair[touch]) * ov[touch] ** 2.5)
    wall = np.sum(0.4 * 4.0 / 3.0 * e_star * np.sqrt(r[:, None]) * wall_ov**2.5)
    return float(pair + wall)


def total_energy(eng, law) -> float:
    e = energies(eng)
    return e["kinetic_J"] + e["rotational_J"] + e["potential_J"] + elastic_energy(eng, law)


@pytest.mark.parametrize("model, g", [("linear_spring_dashpot", 0.0), ("hertz_mindlin", 9.81)],
                         ids=["linear-no-gravity", "hertz-gravity"])
def test_elastic_spheres_in_a_box_conserve_energy(make_engine, contact_law, model, g):
    law = contact_law(model, restitution=1.0, friction=0.0)
    rng = np.random.default_rng(3)
    cell = np.stack(np.meshgrid(*[np.arange(N_SIDE)] * 3, indexing="ij"), axis=-1).reshape(-1, 3)[:N]
    pos = (cell + 0.5) * (BOX / N_SIDE) + rng.uniform(-0.1, 0.1, (N, 3)) * DIAMETER
    vel = rng.normal(0.0, 0.5, (N, 3))
    box = {"name": "box", "kind": "box", "lower": [0.0, 0.0, 0.0], "upper": [BOX, BOX, BOX]}
    kw = dict(contact=law, walls=[box], gravity=(0.0, 0.0, -g), density=DENSITY)
    tc = make_engine(pos, DIAMETER, vel, **kw).contact_time  # shortest contact of the case
    eng = make_engine(pos, DIAMETER, vel, dt=tc / STEPS_PER_CONTACT, **kw)

    e0 = total_energy(eng, law)
    # energy that can be exchanged: the potential energy is measured from all spheres resting on the floor
    scale = e0 - float(np.sum(eng.state.mass)) * g * 0.5 * DIAMETER
    worst = 0.0
    for _ in range(STEPS // SAMPLE_EVERY):
        eng.advance(SAMPLE_EVERY)
        worst = max(worst, abs(total_energy(eng, law) - e0) / scale)
    assert worst < DRIFT_TOL, f"energy changed by {worst:.2e} of {scale:.3g} J"
    # the run must have had collisions and free flight: particles exchanged kinetic energy
    assert eng.rebuilds > 100
    assert np.all(np.abs(eng.state.omega) == 0.0)  # frictionless: no spin
