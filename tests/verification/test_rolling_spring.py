"""The ``epsd`` rolling model: a rolling spring k_r = k_t R*² with its torque capped at μ_r R* F_n.

Ai, Chen, Rotter & Ooi (2011) model C (eqs 13-18) with the stiffness of Iwashita & Oda (1998):

    M_k ← M_k − k_r ω_r,t Δt,   |M_k| ≤ μ_r R* F_n,   M_d = −η_r 2 sqrt(I_r k_r) ω_r,t below the limit.

Kernel checks drive ``contact_force_full`` for one contact with a prescribed load (a sphere pressed on a
plane, its spin integrated here): below the limit the spring holds a static rotation θ = T/k_r under a
torque T, and without damping it oscillates with the period 2π sqrt(I/k_r). Engine checks: a sphere at rest
on a floor under gravity tilted by α (tan α < μ_r, μ) stays put, held by its tangential and rolling springs:
the friction force F = m g sin α stretches the tangential spring by F/k_t and the rolling spring turns the
sphere by θ = F a/k_r = F/(k_t a), so the centre moves by u_t + a θ = 2 F/k_t down the slope — on a plane
wall and on a wall shape alike; a checkpoint taken midway continues bit for bit.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from fluidem.particles.contact._dispatch import contact_force_full
from fluidem.particles.contact.base import ROLLING_HISTORY, SLOT_ROLLING_MODEL, ROLLING_EPSD
from fluidem.particles.contact.spring_dashpot import LinearSpringDashpot

DIAMETER = 4e-3  # [m]
DENSITY = 2500.0  # [kg/m^3]
G = 9.81  # [m/s^2]
K_N = 1e4  # [N/m]
K_T = 2.0 / 7.0 * K_N  # the linear law's default tangential stiffness [N/m]
ROLLING = 0.2  # μ_r


def _row(rolling_damping=0.0):
    law = LinearSpringDashpot(stiffness=K_N, restitution=0.5, friction=0.5, rolling_friction=ROLLING,
                              rolling_model="epsd", rolling_damping=rolling_damping)
    row = law.pack(None, None)
    assert row[SLOT_ROLLING_MODEL] == ROLLING_EPSD
    return tuple(float(v) for v in row)


def _spin_up(row, torque, omega0, steps, dt, inertia, mass, a, overlap):
    """Integrate I dω_y/dt = T + M_y of a sphere pressed on the plane z = 0 (normal +z) by k_n δ, its contact
    point held (no tangential motion): the rolling torque alone. Returns (angles, spins, last spring)."""
    w = omega0
    theta = 0.0
    g = (0.0, 0.0, 0.0)
    i_r = 1.4 * mass * a * a
    angles, spins = np.empty(steps), np.empty(steps)
    for k in range(steps):
        out = contact_force_full(row, overlap, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, w, 0.0,
                                 mass, a, i_r, dt, 0.0, 0.0, 0.0, g[0], g[1], g[2], True)
        g = out[11:14]
        w += (torque + out[9]) / inertia * dt
        theta += w * dt
        angles[k], spins[k] = theta, w
    return angles, spins, g


def _sphere():
    a = 0.5 * DIAMETER
    mass = DENSITY * math.pi * DIAMETER**3 / 6.0
    return a, mass, 0.4 * mass * a * a


def test_rolling_spring_holds_torque_over_stiffness():
    """Under a torque T below μ_r a F_n the damped spring settles at θ = T/k_r, k_r = k_t a² (R* = a at a wall).

    Tolerance 1e-6: the damping (η_r = 1) decays the oscillation by e^-40 over the run; what is left is
    round-off. Stiffness 2.25 k_n μ_r² a² (Ai model C's own) would be off by 40 %."""
    a, mass, inertia = _sphere()
    overlap = 1e-6
    limit = ROLLING * a * K_N * overlap
    torque = 0.5 * limit
    k_r = K_T * a * a
    period = 2.0 * math.pi * math.sqrt(inertia / k_r)
    dt = period / 200.0
    angles, spins, g = _spin_up(_row(rolling_damping=1.0), torque, 0.0, 4000, dt, inertia, mass, a, overlap)
    assert angles[-1] == pytest.approx(torque / k_r, rel=1e-6)
    assert g[1] == pytest.approx(-torque, rel=1e-6), "the spring torque balances the applied one"
    assert abs(spins[-1]) < 1e-6 * torque / k_r / dt


def test_rolling_spring_slips_at_full_mobilisation():
    """Above the limit the spring torque stays at μ_r a F_n and the sphere spins up at (T − μ_r a F_n)/I."""
    a, mass, inertia = _sphere()
    overlap = 1e-6
    limit = ROLLING * a * K_N * overlap
    torque = 3.0 * limit
    k_r = K_T * a * a
    dt = 2.0 * math.pi * math.sqrt(inertia / k_r) / 200.0
    steps = 2000
    angles, spins, g = _spin_up(_row(), torque, 0.0, steps, dt, inertia, mass, a, overlap)
    assert g[1] == pytest.approx(-limit, rel=1e-12)
    # after the wind-up (a rotation limit/k_r), the spin grows at (T − limit)/I
    rate = (spins[-1] - spins[steps // 2]) / ((steps - 1 - steps // 2) * dt)
    assert rate == pytest.approx((torque - limit) / inertia, rel=1e-9)


def test_rolling_spring_oscillation_period():
    """Undamped, below the limit: ω(t) = ω0 cos(Ω t), Ω = sqrt(k_r/I); zero crossings of ω half a period apart.

    Tolerance 1e-3: the symplectic-Euler loop here has a phase error of order (Ω dt)² = 1e-3 at 200 steps a
    period; a spring k_n a² or k_t R*² with R* = a/2 would be off by a factor 1.9 or 2."""
    a, mass, inertia = _sphere()
    overlap = 1e-6
    limit = ROLLING * a * K_N * overlap
    k_r = K_T * a * a
    period = 2.0 * math.pi * math.sqrt(inertia / k_r)
    omega0 = 0.3 * limit / math.sqrt(k_r * inertia)  # amplitude 0.3 of the limit torque
    dt = period / 200.0
    _, spins, g = _spin_up(_row(), 0.0, omega0, 2000, dt, inertia, mass, a, overlap)
    sign = np.signbit(spins)
    crossings = np.flatnonzero(sign[1:] != sign[:-1])
    # linear interpolation of each crossing time
    t = (crossings + spins[crossings] / (spins[crossings] - spins[crossings + 1])) * dt
    measured = 2.0 * float(np.mean(np.diff(t)))
    assert measured == pytest.approx(period, rel=1e-3)
    assert np.abs(spins).max() <= omega0 * (1.0 + 1e-3), "an undamped elastic spring keeps its amplitude"


def _tilted(make_engine, contact_law, walls, height, alpha, **kw):
    law = contact_law("linear_spring_dashpot", stiffness=K_N, restitution=0.3, friction=0.5,
                      rolling_friction=ROLLING, rolling_model="epsd", rolling_damping=0.5)
    gravity = (G * math.sin(alpha), 0.0, -G * math.cos(alpha))
    return make_engine([[0.0, 0.0, height]], DIAMETER, contact=law, walls=walls, gravity=gravity,
                       density=DENSITY, impact_velocity=0.1, **kw)


FLOOR = {"name": "floor", "kind": "plane", "point": [0.0, 0.0, 0.0], "normal": [0.0, 0.0, 1.0]}
SQUARE = {"name": "floor", "kind": "polygon",
          "points": [[-0.02, -0.02, 0.0], [0.02, -0.02, 0.0], [0.02, 0.02, 0.0], [-0.02, 0.02, 0.0]]}


@pytest.mark.parametrize("wall", [FLOOR, SQUARE], ids=["plane", "shape"])
def test_sphere_held_on_a_slope_by_its_rolling_spring(make_engine, contact_law, wall):
    """tan α = 0.05 < μ_r, μ: the sphere comes to rest 2 m g sin α / k_t down the slope (2.9e-8 m here).

    Tolerance 1e-3: the dashpots (e = 0.3, η_r = 0.5) damp the start-up over 0.05 s, 100 periods of the
    slowest (rolling) mode; without the rolling spring (θ = 0) the shift would be half, with cdt the sphere
    creeps (its torque chatters), and a stiffness of 2.25 k_n μ_r² a² would give 2.3 times the shift."""
    alpha = math.atan(0.05)  # half the limit tan α = μ_r: the start-up overshoot stays below it
    a, mass, _ = _sphere()
    f_n = mass * G * math.cos(alpha)
    eng = _tilted(make_engine, contact_law, [wall], a - f_n / K_N, alpha)
    eng.advance(int(0.05 / eng.dt))
    shift = eng.state.position[0, 0]
    f_t = mass * G * math.sin(alpha)
    assert shift == pytest.approx(2.0 * f_t / K_T, rel=1e-3)
    assert abs(eng.state.velocity[0, 0]) < 1e-9
    if wall["kind"] == "plane":
        spring = eng.wall_hist[0, 0, ROLLING_HISTORY:ROLLING_HISTORY + 3]
    else:
        spring = eng.shapes.slot_hist[0, :, 3:6].sum(axis=0)
    # the rolling spring holds the friction's moment F a (about +y the friction turns the sphere down the slope)
    assert spring[1] == pytest.approx(-f_t * a, rel=1e-3)


def test_rolling_spring_between_spheres_and_checkpoint(two_particles):
    """A pair: after one step of relative spin ω_r (tangential to the contact) the spring torque on 0 is
    −k_r ω_r Δt (k_r = k_t R*²), −(it) on 1; stored in the pair's history columns 4-6. A checkpoint taken
    then continues bit for bit."""
    d = DIAMETER
    omega = np.array([[0.0, 3.0, -2.0], [0.0, -1.0, 1.0]])
    eng = two_particles(overlap=0.01 * d, model="linear_spring_dashpot", omega=omega, friction=0.0,
                        rolling_friction=ROLLING, rolling_model="epsd", stiffness=K_N)
    assert eng.hist.shape[1] == ROLLING_HISTORY + 3
    w = eng.state.omega[0] - eng.state.omega[1]  # after the first half kick the spins are as given: no torque
    eng.advance(1)
    r_eff = 0.25 * d
    k_r = K_T * r_eff**2
    spring = eng.hist[0, ROLLING_HISTORY:ROLLING_HISTORY + 3]
    owner = 0 if eng.row_start[1] == 1 else 1  # the history is kept relative to the pair's owner
    sign = 1.0 if owner == 0 else -1.0
    np.testing.assert_allclose(spring, -sign * k_r * w * eng.dt * np.array([0.0, 1.0, 1.0]), rtol=1e-12)
    arrays = {k: v.copy() for k, v in eng.checkpoint_arrays().items()}
    scalars = dict(eng.checkpoint_scalars())
    eng.advance(50)
    after = eng.state.omega.copy(), eng.hist.copy()
    eng.restore(arrays, scalars)
    eng.advance(50)
    np.testing.assert_array_equal(eng.state.omega, after[0])
    np.testing.assert_array_equal(eng.hist, after[1])
