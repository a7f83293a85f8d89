"""JKR adhesion (``hertz_mindlin_jkr``) against the analytic JKR solution (Johnson, Kendall & Roberts 1971).

The law's two equations, in the contact radius a (γ the surface energy, E*, R* the effective modulus and
radius):

    F(a) = 4 E* a³/(3 R*) − sqrt(8 π γ E* a³),     δ(a) = a²/R* − sqrt(2 π γ a/E*)

give, by dF/da = 0, dF = 0, δ = 0 and dδ/da = 0 in turn:

    pull-off force     F_c = (3/2) π γ R*            at a³ = a0³/4
    zero load          a0³ = 9 π γ R*²/(2 E*)
    touch (δ = 0)      a³ = 2 π γ R*²/E*,             F = −(8/9) F_c
    pull-off distance  δ_c = −(3/4) (π² γ² R*/E*²)^(1/3)   at a³ = a0³/36,  F = −(5/9) F_c

The kernel solves δ(a) for a in closed form; a slow approach-and-retract cycle of two spheres (and of a
sphere and a wall) driven at constant speed must follow F(δ) from the snap-in at touch to the break at δ_c.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from fluidem.errors import CaseError
from fluidem.particles.contact import hertz_mindlin_jkr as jkr
from fluidem.particles.contact.hertz_mindlin_jkr import HertzMindlinJKR

GAMMA = 1.09e-3  # [J/m²] the cohesive powder of the 2012 DEM-book chapter (Wu & Guo)
E, NU = 1.0e8, 0.3  # [Pa], [-]
E_STAR = E / (2.0 * (1.0 - NU**2))  # two like bodies
D = 4e-3  # [m]
R_EFF = 0.25 * D  # two equal spheres

# Tolerances:
# KERNEL_TOL = 1e-6 (the brief): the closed-form root is exact to round-off (relative residual of the quartic
#   ~1e-15) except at δ_c, where da/dδ is infinite and a is only good to sqrt(eps) ~ 1e-8.
# CURVE_TOL = 1e-8 of F_c: with restitution 1 the law has no damping, and a pair moved at constant speed feels
#   exactly F(δ) at each step; what is left is the round-off of δ = a_i + a_j − r (r ~ 4e-3 m, δ ~ 1e-8 m:
#   ~1e-19 m in δ, ~1e-9 in F/F_c near δ_c where dF/dδ is steep).
KERNEL_TOL = 1e-6
CURVE_TOL = 1e-8


def row():
    return HertzMindlinJKR(youngs_modulus=E, poisson_ratio=NU, surface_energy=GAMMA, restitution=1.0).pack(None, None)


def force(overlap, r_eff=R_EFF):
    return jkr.coefficients(row(), overlap, 1e-5, r_eff)[0]


def overlap_at(a, r_eff=R_EFF):
    return a * a / r_eff - math.sqrt(2.0 * math.pi * GAMMA * a / E_STAR)


def analytic_force(overlap, r_eff=R_EFF):
    """F(δ) on the stable branch a ≥ a_c, by root finding on δ(a) (independent of the kernel's closed form)."""
    a_c = (math.pi * GAMMA * r_eff**2 / (8.0 * E_STAR)) ** (1.0 / 3.0)
    hi = max(2.0 * a_c, 2.0 * math.sqrt(r_eff * max(overlap, 0.0)))
    while overlap_at(hi, r_eff) < overlap:
        hi *= 2.0
    if overlap_at(a_c, r_eff) >= overlap:  # at δ_c (to round-off): the end of the branch
        a = a_c
    else:
        a = brentq(lambda x: overlap_at(x, r_eff) - overlap, a_c, hi, xtol=1e-30, rtol=1e-15)
    return 4.0 * E_STAR * a**3 / (3.0 * r_eff) - math.sqrt(8.0 * math.pi * GAMMA * E_STAR * a**3)


def test_jkr_pull_off_force_and_zero_load_radius():
    f_c = 1.5 * math.pi * GAMMA * R_EFF
    a0 = (9.0 * math.pi * GAMMA * R_EFF**2 / (2.0 * E_STAR)) ** (1.0 / 3.0)
    # the largest attraction, at a = a0/4^(1/3), is the pull-off force, and it is a minimum of F(δ)
    d1 = overlap_at(a0 / 4.0 ** (1.0 / 3.0))
    assert force(d1) == pytest.approx(-f_c, rel=KERNEL_TOL)
    assert force(d1 - 1e-3 * abs(d1)) > force(d1) and force(d1 + 1e-3 * abs(d1)) > force(d1)
    # zero load at the contact radius a0
    d0 = overlap_at(a0)
    assert d0 > 0.0
    assert abs(force(d0)) < KERNEL_TOL * f_c
    assert jkr.contact_radius(E_STAR, GAMMA, d0, R_EFF) == pytest.approx(a0, rel=KERNEL_TOL)
    # touch: a³ = 2πγR*²/E*, F = −(8/9) F_c
    assert jkr.contact_radius(E_STAR, GAMMA, 0.0, R_EFF) ** 3 == pytest.approx(
        2.0 * math.pi * GAMMA * R_EFF**2 / E_STAR, rel=KERNEL_TOL)
    assert force(0.0) == pytest.approx(-8.0 / 9.0 * f_c, rel=KERNEL_TOL)
    # pull-off distance: δ_c = −(3/4)(π²γ²R*/E*²)^(1/3) at a = a0/36^(1/3), where F = −(5/9) F_c
    d_c = 0.75 * (math.pi**2 * GAMMA**2 * R_EFF / E_STAR**2) ** (1.0 / 3.0)
    assert overlap_at(a0 / 36.0 ** (1.0 / 3.0)) == pytest.approx(-d_c, rel=1e-12)
    assert force(-d_c) == pytest.approx(-5.0 / 9.0 * f_c, rel=KERNEL_TOL)
    assert jkr.pull_off(row(), R_EFF) == pytest.approx((f_c, d_c), rel=1e-14)
    law = HertzMindlinJKR(youngs_modulus=E, poisson_ratio=NU, surface_energy=GAMMA)
    assert law.pull_off_distance(R_EFF) == pytest.approx(d_c, rel=1e-14)


@pytest.mark.parametrize("scale", [-1.0, -0.5, 0.0, 1e-3, 1.0, 30.0, 1e4])
def test_closed_form_contact_radius_solves_the_jkr_relation(scale):
    """a(δ) from δ_c up to overlaps far above the adhesive scale (Hertz: a → sqrt(R* δ))."""
    d_c = 0.75 * (math.pi**2 * GAMMA**2 * R_EFF / E_STAR**2) ** (1.0 / 3.0)
    d = scale * d_c
    a = jkr.contact_radius(E_STAR, GAMMA, d, R_EFF)
    tol = 1e-7 if scale == -1.0 else 1e-12  # sqrt(eps) at δ_c (see KERNEL_TOL)
    assert overlap_at(a) == pytest.approx(d, rel=tol, abs=tol * d_c)
    assert force(d) == pytest.approx(analytic_force(d), rel=1e-7 if scale == -1.0 else 1e-10, abs=1e-12)


def test_no_surface_energy_is_hertz():
    p = HertzMindlinJKR(youngs_modulus=E, poisson_ratio=NU, surface_energy=0.0).pack(None, None)
    d = 1e-6
    assert jkr.coefficients(p, d, 1e-5, R_EFF)[0] == pytest.approx(4.0 / 3.0 * E_STAR * math.sqrt(R_EFF) * d**1.5,
                                                                 rel=1e-13)


def driven_cycle(eng, move, gap0, depth, speed):
    """Move body 1 (a particle, or the particle against a wall) towards body 0 at constant speed from a gap gap0
    to an overlap depth and back out to a gap gap0; record (overlap, normal force on the moving body).

    Each step the moving particle gets the prescribed velocity and no stored force, so that the drift moves it
    by exactly speed dt; the force is then evaluated at the new position (restitution 1: no damping)."""
    st = eng.state
    n_in = int(round((gap0 + depth) / (speed * eng.dt)))
    record = []
    for direction in (-1.0, 1.0):
        for _ in range(n_in):
            st.velocity[:] = 0.0
            st.force[:] = 0.0
            st.velocity[move[0], move[1]] = direction * speed * move[2]
            eng.advance(1)
            record.append((move[3](st), move[2] * st.force[move[0], move[1]]))
    return np.array(record)


@pytest.mark.parametrize("body", ["pair", "wall"])
def test_approach_and_retract_follow_the_jkr_curve(make_engine, contact_law, body):
    law = contact_law("hertz_mindlin_jkr", youngs_modulus=E, poisson_ratio=NU, surface_energy=GAMMA,
                      restitution=1.0, friction=0.3)
    a = 0.5 * D
    r_eff = R_EFF if body == "pair" else a  # a wall of the particles' material: the same E*, R* = a
    f_c = 1.5 * math.pi * GAMMA * r_eff
    d_c = 0.75 * (math.pi**2 * GAMMA**2 * r_eff / E_STAR**2) ** (1.0 / 3.0)
    a0 = (9.0 * math.pi * GAMMA * r_eff**2 / (2.0 * E_STAR)) ** (1.0 / 3.0)
    depth = 3.0 * overlap_at(a0, r_eff)  # three times the zero-load overlap
    gap0 = 2.0 * d_c
    if body == "pair":
        pos = [[0.0, 0.0, 0.0], [D + gap0, 0.0, 0.0]]
        eng = make_engine(pos, D, contact=law)
        # body 1 moves along −x towards body 0; the normal force on it is +x for repulsion
        move = (1, 0, 1.0, lambda st: D - (st.position[1, 0] - st.position[0, 0]))
    else:
        wall = {"name": "floor", "kind": "plane", "point": [0.0, 0.0, 0.0], "normal": [0.0, 0.0, 1.0]}
        eng = make_engine([[0.0, 0.0, a + gap0]], D, contact=law, walls=[wall])
        move = (0, 2, 1.0, lambda st: a - st.position[0, 2])
    speed = 0.02 * d_c / eng.dt  # 50 steps over the pull-off distance
    rec = driven_cycle(eng, move, gap0, depth, speed)
    n = rec.shape[0] // 2
    approach, retract = rec[:n], rec[n:]
    # approach: nothing before touch (δ ≤ 0), then the JKR curve, starting with the snap-in near −(8/9) F_c
    assert np.all(approach[approach[:, 0] <= 0.0, 1] == 0.0)
    touching = approach[approach[:, 0] > 0.0]
    assert touching[0, 1] == pytest.approx(-8.0 / 9.0 * f_c, rel=0.02)  # the first step lands at δ < 0.02 δ_c
    # retraction: attraction persists into negative overlap down to δ_c, then the contact breaks
    held = retract[retract[:, 1] != 0.0]
    assert held[:, 0].min() < -0.9 * d_c
    assert held[:, 0].min() > -d_c
    assert np.all(retract[retract[:, 0] <= -d_c, 1] == 0.0)
    free = retract[retract[:, 0] < 0.0]
    assert free[free[:, 1] == 0.0, 0].max() <= -d_c + 1e-3 * d_c, "the contact broke before δ_c"
    # hysteresis: at the same negative overlap the approach felt nothing and the retraction feels attraction
    assert np.all(held[held[:, 0] < 0.0, 1] < 0.0) and (held[:, 0] < 0.0).sum() > 20
    # and every step in contact is on the analytic curve
    on = np.concatenate([touching, held])
    expected = np.array([analytic_force(d, r_eff) for d in on[:, 0]])
    np.testing.assert_allclose(on[:, 1], expected, rtol=0.0, atol=CURVE_TOL * f_c)
    # the attraction reached during retraction is the pull-off force (sampled at 50 steps per δ_c)
    assert held[:, 1].min() == pytest.approx(-f_c, rel=1e-3)


def test_a_skin_below_the_pull_off_distance_is_refused(make_engine, contact_law):
    law = contact_law("hertz_mindlin_jkr", youngs_modulus=1e5, surface_energy=1.0)
    d_c = HertzMindlinJKR(**{k: v for k, v in law.items()}).pull_off_distance(R_EFF)
    with pytest.raises(CaseError, match="pull-off distance"):
        make_engine([[0.0, 0.0, 0.0], [D, 0.0, 0.0]], D, contact=law, skin=0.5 * d_c)


def test_adhesive_bed_resumes_bit_for_bit(tmp_path):
    """A cohesive bed's checkpoint holds the fourth history column (each contact's pull-off distance), for pairs
    and walls: a run stopped and resumed ends where the uninterrupted run ends, every array equal."""
    import h5py

    from fluidem import Simulation
    from fluidem.case import validate_case

    case = validate_case({
        "name": "cohesive-pour", "gravity": [0.0, 0.0, -9.81],
        "particles": {"dimensions": 3, "species": [{"diameter": 1e-3, "density": 2500.0, "count": 120}],
                      "contact": {"model": "hertz_mindlin_jkr", "youngs_modulus": 1e7, "poisson_ratio": 0.3,
                                  "surface_energy": 0.05, "restitution": 0.5, "friction": 0.3},
                      "placement": {"seed": 4}},
        "walls": [{"name": "box", "kind": "box", "lower": [0, 0, 0], "upper": [0.006, 0.006, 0.012]}],
        "time": {"end": 0.06},
    })
    whole = Simulation(case, out_dir=tmp_path / "whole")
    whole.run()
    part = Simulation(case, out_dir=tmp_path / "part")
    part.run(until=0.03)
    Simulation.resume(tmp_path / "part").run()
    with h5py.File(tmp_path / "whole" / "restart.h5") as f1, h5py.File(tmp_path / "part" / "restart.h5") as f2:
        assert f1["engine/hist"].shape[1] == 4 and f1["engine/wall_hist"].shape[2] == 4
        held = f1["engine/hist"][:, 3]
        assert np.count_nonzero(held) > 50  # contacts that formed and carry a pull-off distance
        for name in f1["engine"]:
            assert np.array_equal(f1["engine"][name][...], f2["engine"][name][...]), name
        for name in f1["state"]:
            assert np.array_equal(f1["state"][name][...], f2["state"][name][...]), name
