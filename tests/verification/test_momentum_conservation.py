"""A free cloud of colliding spheres conserves linear and angular momentum.

No gravity and no walls: the only forces are pair contacts, equal and opposite, so
P = Σ m v is conserved to round-off. Angular momentum about the origin including spin,
L = Σ r × m v + I ω, is conserved when the pair torques balance the moment of the pair
forces: (r_i − r_j) × F_t + T_i + T_j = 0. Sun 2007 eq. 24, T_i = −½ Σ_j r_ij × F_t,
satisfies this exactly; velocity Verlet then conserves L to round-off too (a kick at fixed
positions adds Σ r × F + T = 0, a drift adds Σ v dt × m v = 0).
"""
from __future__ import annotations

import numpy as np
import pytest

DIAMETER = 4e-3  # [m] mean
N = 60
STEPS = 10_000  # the cloud expands; nearly all collisions happen in the first 5000 steps
# Tolerances:
# P_TOL = 1e-12 of Σ m|v| (the brief): pair forces enter the two bodies as +F and −F of the same number, so
#   only the (m · (F/m)) round-off of the kicks accumulates: measured 6e-17.
# L_TOL = 1e-10 of Σ |r × m v| + I |ω| (the brief): round-off of cross products over 1e4 steps, measured
#   1e-13 without friction; a torque lever that does not match the pair's moment loses O(δ/d) of each
#   tangential impulse, ~1e-4 here.
P_TOL = 1e-12
L_TOL = 1e-10


def random_cloud(seed, n, solid_fraction=0.25):
    """Non-overlapping polydisperse spheres (d ∈ [0.7, 1.3] × DIAMETER) in a cube around the origin."""
    rng = np.random.default_rng(seed)
    d = DIAMETER * rng.uniform(0.7, 1.3, n)
    side = np.cbrt(np.sum(np.pi / 6 * d**3) / solid_fraction)
    pos = np.empty((n, 3))
    k = 0
    while k < n:
        p = rng.uniform(-0.5 * side, 0.5 * side, 3)
        if np.all(np.linalg.norm(pos[:k] - p, axis=1) > 0.505 * (d[:k] + d[k])):
            pos[k] = p
            k += 1
    vel = rng.normal(0.0, 1.0, (n, 3))  # [m/s]
    omega = rng.normal(0.0, 300.0, (n, 3))  # [rad/s]: spins of the order of v / a
    return pos, d, vel, omega


def momenta(st):
    m = st.mass[:, None]
    orbital = np.cross(st.position, m * st.velocity)
    p = np.sum(m * st.velocity, axis=0)
    l = np.sum(orbital, axis=0) + np.sum(st.inertia[:, None] * st.omega, axis=0)
    p_scale = float(np.sum(m * np.abs(st.velocity)))
    l_scale = float(np.sum(np.linalg.norm(orbital, axis=1)) + np.sum(st.inertia * np.linalg.norm(st.omega, axis=1)))
    return p, l, p_scale, l_scale


def run_cloud(make_engine, contact_law, model, friction, seed=5):
    pos, d, vel, omega = random_cloud(seed, N)
    eng = make_engine(pos, d, vel, omega=omega, contact=contact_law(model, restitution=0.7, friction=friction))
    st = eng.state
    p0, l0, p_scale, l_scale = momenta(st)
    ke0 = 0.5 * np.sum(st.mass * np.sum(st.velocity**2, axis=1))
    p_err = l_err = 0.0
    for _ in range(10):
        eng.advance(STEPS // 10)
        p, l, _, _ = momenta(st)
        p_err = max(p_err, float(np.max(np.abs(p - p0))) / p_scale)
        l_err = max(l_err, float(np.max(np.abs(l - l0))) / l_scale)
    ke = 0.5 * np.sum(st.mass * np.sum(st.velocity**2, axis=1))
    # many inelastic collisions happened: they took away more than 10 % of the kinetic energy
    assert ke < 0.9 * ke0, f"too few collisions (KE kept {ke / ke0:.3f})"
    return p_err, l_err


@pytest.mark.parametrize("model", ["linear_spring_dashpot", "hertz_mindlin"])
@pytest.mark.parametrize("friction", [0.0, 0.5], ids=["frictionless", "friction"])
def test_linear_momentum_is_conserved(make_engine, contact_law, model, friction):
    p_err, _ = run_cloud(make_engine, contact_law, model, friction)
    assert p_err < P_TOL, f"linear momentum changed by {p_err:.2e} of Σ m|v|"


@pytest.mark.parametrize("model", ["linear_spring_dashpot", "hertz_mindlin"])
def test_angular_momentum_is_conserved_without_friction(make_engine, contact_law, model):
    """Central forces only: orbital angular momentum conserved, spins untouched."""
    _, l_err = run_cloud(make_engine, contact_law, model, 0.0)
    assert l_err < L_TOL, f"angular momentum changed by {l_err:.2e}"


@pytest.mark.parametrize("model", ["linear_spring_dashpot", "hertz_mindlin"])
def test_angular_momentum_is_conserved_with_friction(make_engine, contact_law, model):
    """Σ r × m v + I ω about the origin, spins included, with frictional (tangential) contacts."""
    _, l_err = run_cloud(make_engine, contact_law, model, 0.5)
    assert l_err < L_TOL, f"angular momentum changed by {l_err:.2e}"


@pytest.mark.parametrize("model", ["linear_spring_dashpot", "hertz_mindlin"])
def test_pair_contact_exerts_no_net_moment(two_particles, model):
    """One frictional contact, one instant: Σ_k (r_k × F_k + T_k) = 0 about any point.

    Tolerance 1e-12 of |r × F| + |T|: the two bodies' terms cancel up to round-off.
    """
    d = (4e-3, 3e-3)
    vel = np.array([[0.3, 0.2, -0.1], [-0.2, -0.3, 0.25]])
    omega = np.array([[40.0, -25.0, 60.0], [-30.0, 55.0, 20.0]])
    eng = two_particles(overlap=0.01 * d[1], model=model, diameters=d, vel=vel, omega=omega, restitution=0.5,
                        friction=0.3)
    st = eng.state
    origin = np.array([1e-3, -2e-3, 0.5e-3])  # any point; not on the line of centres
    moments = np.cross(st.position - origin, st.force) + st.torque
    scale = np.sum(np.linalg.norm(np.cross(st.position - origin, st.force), axis=1)) + np.sum(
        np.linalg.norm(st.torque, axis=1))
    assert np.linalg.norm(st.torque) > 0.0
    net = np.linalg.norm(moments.sum(axis=0))
    assert net < 1e-12 * scale, f"net moment {net:.3g} N m of {scale:.3g}"
