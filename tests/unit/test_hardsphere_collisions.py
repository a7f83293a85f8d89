"""Single collisions of the hard-sphere engine against Hoomans et al. 1996, eqs 10–29, written out here.

Each test places two spheres (or a sphere and a wall) exactly at contact and
approaching, with no gravity. The engine then collides them at the start of its first
step, and after the collision they fly apart at constant velocity. The velocities and
spins at the end of the step are therefore the post-collision ones. The expected
values are computed in this file in two independent ways:

* 2D: the paper's own equations in collision coordinates (x along the tangent, y
  along the normal from b to a, z out of the plane), eqs 1–6, 11–12, 14–15, 22–29.
  Eqs 3 and 6 use the lever arms y_a = R_a and y_b = −R_b, the centres' y-coordinates
  with the origin at the contact point. This is what makes eq. 10, with B1 of eq. 12,
  follow from eqs 1–6 and 11. The tests check that eq. 10 holds too.
* 3D: plain rigid-body mechanics with vectors, where the contact-point velocities
  are v + ω × (x_cp − x) and the torques are (x_cp − x) × J (numpy.cross). The slip is a
  vector: sliding gives J_t = −μ P_n ŝ, sticking ends with zero tangential
  contact-point velocity.

Tolerance 1e-12 relative: the engine and the reference do the same arithmetic in a
different order, and the contact normal is fixed only up to round-off (|r| = R_a + R_b
to the last bit), so they agree to a few ulps. A wrong sign or a missing term in any
equation is of order one.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from fluidem.errors import CaseError
from fluidem.particles.contact.hard_sphere import HardSphere
from fluidem.particles.hardsphere import CollisionCascadeError, HardSphereEngine
from fluidem.state import ParticleState

DENSITY = 2700.0  # [kg/m^3] aluminium, Hoomans Table 2
DIAMETER = 4e-3  # [m]
RTOL = 1e-12


# ---------------------------------------------------------------- set-up helpers
def hard(e=0.9, mu=0.3, **kw):
    return {"model": "hard_sphere", "restitution": e, "friction": mu, **kw}


def make(make_case, pos, diam, vel, omega, *, dimensions, contact, walls=(), wall_contact=None, species=None,
         species_index=None, densities=None, pairs=None, dt=1e-4):
    """Hard-sphere engine with the given particles (spins included) and no gravity."""
    pos = np.asarray(pos, float)
    n = pos.shape[0]
    kw = {}
    if species is not None:
        kw["species"] = species
    case = make_case(pos, diam, vel, contact=contact, walls=walls, gravity=(0.0, 0.0, 0.0), dimensions=dimensions,
                     dt=dt, wall_contact=wall_contact, species_index=species_index, **kw)
    if pairs:
        data = case.model_dump(mode="json", exclude_none=True)
        data["particles"]["pairs"] = pairs
        from fluidem.case import validate_case

        case = validate_case(data)
    dens = np.array([s.density for s in case.particles.species])
    spec = np.zeros(n, np.int64) if species_index is None else np.asarray(species_index, np.int64)
    state = ParticleState.create(pos.copy(), np.asarray(vel, float).copy(), np.broadcast_to(diam, (n,)).copy(),
                                 spec, dens)
    state.omega[...] = np.asarray(omega, float)
    eng = HardSphereEngine(case, state=state)
    eng.check_initial_overlaps()
    return eng


def kinetic(eng):
    st = eng.state
    return (0.5 * np.sum(st.mass * np.sum(st.velocity**2, axis=1))
            + 0.5 * np.sum(st.inertia * np.sum(st.omega**2, axis=1)))


# ---------------------------------------------------------------- references
def paper_2d(va, vb, wa, wb, n, Ra, Rb, ma, mb, e, mu):
    """Hoomans 1996 eqs 1–29 in collision coordinates. b = None side: wall (mb = inf).

    Returns (va', vb', ωa', ωb', E_y, E_x, sliding, checks) with the 2D vectors in
    system coordinates and ω about z.
    """
    n = np.asarray(n, float)
    ex = np.array([n[1], -n[0]])  # tangent x such that (x, y = n, z) is right-handed
    Ia = 0.4 * ma * Ra**2
    inv_mb = 0.0 if math.isinf(mb) else 1.0 / mb
    Rb2_Ib = 0.0 if math.isinf(mb) else Rb**2 / (0.4 * mb * Rb**2)
    vxa0, vya0 = va @ ex, va @ n
    vxb0, vyb0 = vb @ ex, vb @ n
    S0 = (vxa0 + wa * Ra) - (vxb0 - wb * Rb)  # eq. 11
    C0 = vya0 - vyb0  # eq. 14
    B1 = 1 / ma + inv_mb + Ra**2 / Ia + Rb2_Ib  # eq. 12
    B2 = 1 / ma + inv_mb  # eq. 15
    assert C0 < 0
    Py = -(1 + e) * C0 / B2  # eq. 22
    Ey = C0**2 / (2 * B2) * (1 - e**2)  # eq. 23
    sliding = abs(S0) >= mu * B1 * Py  # eq. 24
    if sliding:
        Px = -mu * math.copysign(1.0, S0) * Py  # eq. 26
        Ex = -mu * (1 + e) * C0 / B2 * (abs(S0) + mu * B1 * (1 + e) * C0 / (2 * B2))  # eq. 27
    else:
        Px = -S0 / B1  # eq. 28
        Ex = S0**2 / (2 * B1)  # eq. 29
    ya, yb = Ra, -Rb
    vxa, vya = vxa0 + Px / ma, vya0 + Py / ma  # eqs 1, 2
    wa1 = wa + Px * ya / Ia  # eq. 3
    vxb, vyb = vxb0 - Px * inv_mb, vyb0 - Py * inv_mb  # eqs 4, 5
    wb1 = wb - Px * yb * (Rb2_Ib / Rb**2 if Rb2_Ib else 0.0)  # eq. 6 (I_b = ∞ for a wall)
    checks = {
        "S_end": (vxa + wa1 * Ra) - (vxb - wb1 * Rb), "S_eq10": S0 + B1 * Px,  # eqs 8, 10
        "C_end": vya - vyb, "C_newton": -e * C0,  # eqs 9, 16
    }
    return vxa * ex + vya * n, vxb * ex + vyb * n, wa1, wb1, Ey, Ex, sliding, checks


def vector_3d(xa, xb, va, vb, wa, wb, Ra, Rb, ma, mb, e, mu):
    """Rigid-body impulse of a frictional inelastic collision, in vectors (b = wall if mb = inf)."""
    wall = math.isinf(mb)
    n = (xa - xb) / np.linalg.norm(xa - xb)
    cp = xa - Ra * n
    Ia = 0.4 * ma * Ra**2
    Ib = np.inf if wall else 0.4 * mb * Rb**2
    u = (va + np.cross(wa, cp - xa)) - (vb + (0 if wall else np.cross(wb, cp - xb)))
    C0 = u @ n
    S0 = u - C0 * n
    inv_mb = 0.0 if wall else 1 / mb
    B2 = 1 / ma + inv_mb
    B1 = B2 + Ra**2 / Ia + (0.0 if wall else Rb**2 / Ib)
    Pn = -(1 + e) * C0 / B2
    s = np.linalg.norm(S0)
    sliding = s >= mu * B1 * Pn
    Pt = -mu * Pn * S0 / s if sliding else -S0 / B1
    J = Pn * n + Pt
    va1 = va + J / ma
    wa1 = wa + np.cross(cp - xa, J) / Ia
    vb1 = vb - J * inv_mb
    wb1 = wb if wall else wb + np.cross(cp - xb, -J) / Ib
    Ey = C0**2 / (2 * B2) * (1 - e**2)
    Ex = mu * Pn * (s - 0.5 * mu * B1 * Pn) if sliding else s**2 / (2 * B1)
    u1 = (va1 + np.cross(wa1, cp - xa)) - (vb1 + (0 if wall else np.cross(wb1, cp - xb)))
    return va1, vb1, wa1, wb1, Ey, Ex, sliding, u1 - (u1 @ n) * n, S0, B1, Pn


def close(a, b, scale):
    np.testing.assert_allclose(a, b, rtol=RTOL, atol=RTOL * scale)


# ---------------------------------------------------------------- 2D pair collisions
PAIR_2D = [
    # (label, angle of n, v_a, v_b, ω_a, ω_b, R_a, R_b, e, μ, expected class)
    ("sticking, equal", 0.3, (-0.4, 0.1), (0.2, -0.05), 5.0, -3.0, 2e-3, 2e-3, 0.9, 0.3, False),
    ("sliding, equal", 1.1, (-0.2, -0.3), (0.1, 0.05), 0.0, 300.0, 2e-3, 2e-3, 0.9, 0.1, True),
    ("sliding, polydisperse", 2.0, (0.5, -0.7), (-0.1, 0.2), -600.0, 200.0, 2e-3, 3.1e-3, 0.7, 0.05, True),
    ("sticking, polydisperse", -0.7, (-0.3, 0.25), (0.05, -0.1), 10.0, 12.0, 1.5e-3, 2.5e-3, 0.5, 0.5, False),
]


@pytest.mark.parametrize("label, ang, va, vb, wa, wb, Ra, Rb, e, mu, slides", PAIR_2D, ids=[p[0] for p in PAIR_2D])
def test_2d_pair_collision_follows_hoomans_eqs(make_case, label, ang, va, vb, wa, wb, Ra, Rb, e, mu, slides):
    n = np.array([math.cos(ang), math.sin(ang)])
    xb = np.array([0.05, 0.05, 0.002])
    xa = xb + np.array([*((Ra + Rb) * n), 0.0])
    va, vb = np.array(va), np.array(vb)
    assert (va - vb) @ n < 0, "the test set-up must approach"
    eng = make(make_case, [xa, xb], np.array([2 * Ra, 2 * Rb]),
               [[*va, 0.0], [*vb, 0.0]], [[0, 0, wa], [0, 0, wb]], dimensions=2, contact=hard(e, mu))
    e0 = kinetic(eng)
    eng.advance(1)
    ma, mb = eng.state.mass
    va1, vb1, wa1, wb1, Ey, Ex, sliding, chk = paper_2d(va, vb, wa, wb, n, Ra, Rb, ma, mb, e, mu)
    assert sliding == slides
    assert eng.collisions == 1 and eng.wall_collisions == 0
    assert eng.sticking_collisions == (0 if slides else 1)
    st = eng.state
    vscale = np.abs(np.r_[va, vb]).max()
    close(st.velocity[0, :2], va1, vscale)
    close(st.velocity[1, :2], vb1, vscale)
    close(st.omega[:, 2], [wa1, wb1], vscale / min(Ra, Rb))
    assert np.all(st.velocity[:, 2] == 0) and np.all(st.omega[:, :2] == 0), "2D: planar motion, spin about z only"
    # eq. 10 and Newton's law (eq. 16) hold for the reference itself
    assert chk["S_end"] == pytest.approx(chk["S_eq10"], rel=RTOL, abs=RTOL * vscale)
    assert chk["C_end"] == pytest.approx(chk["C_newton"], rel=RTOL, abs=RTOL * vscale)
    if not sliding:
        assert abs(chk["S_end"]) < RTOL * vscale  # sticking ends with zero slip (eq. 28)
    # dissipated energy: eq. 23 and eq. 27/29, and equal to the loss of kinetic + rotational energy
    assert eng.dissipated_normal_J == pytest.approx(Ey, rel=RTOL, abs=RTOL * e0)
    assert eng.dissipated_tangential_J == pytest.approx(Ex, rel=1e-10, abs=RTOL * e0)
    assert e0 - kinetic(eng) == pytest.approx(Ey + Ex, rel=1e-10, abs=1e-12 * e0)


# ---------------------------------------------------------------- 3D pair collisions
PAIR_3D = [
    ("sticking", (0.3, -0.5, 0.8), (-0.3, 0.2, -0.1), (0.2, 0.1, 0.3), (5.0, -8.0, 3.0), (-2.0, 4.0, 9.0),
     2e-3, 2e-3, 0.9, 0.4, False),
    ("sliding", (-0.6, 0.1, 0.4), (0.5, 0.9, -0.6), (-0.2, -0.3, 0.1), (100.0, 30.0, -50.0), (0.0, -20.0, 10.0),
     2e-3, 1.3e-3, 0.8, 0.2, True),
]


@pytest.mark.parametrize("label, nd, va, vb, wa, wb, Ra, Rb, e, mu, slides", PAIR_3D, ids=[p[0] for p in PAIR_3D])
def test_3d_pair_collision_is_the_vector_impulse(make_case, label, nd, va, vb, wa, wb, Ra, Rb, e, mu, slides):
    n = np.array(nd) / np.linalg.norm(nd)
    xb = np.array([0.05, 0.05, 0.05])
    xa = xb + (Ra + Rb) * n
    va, vb, wa, wb = map(np.array, (va, vb, wa, wb))
    eng = make(make_case, [xa, xb], np.array([2 * Ra, 2 * Rb]), [va, vb], [wa, wb], dimensions=3,
               contact=hard(e, mu))
    e0 = kinetic(eng)
    eng.advance(1)
    ma, mb = eng.state.mass
    va1, vb1, wa1, wb1, Ey, Ex, sliding, slip_end, S0, B1, Pn = vector_3d(xa, xb, va, vb, wa, wb, Ra, Rb, ma, mb, e, mu)
    assert sliding == slides and eng.collisions == 1
    st = eng.state
    vscale = max(np.abs(np.r_[va, vb]).max(), Ra * np.abs(np.r_[wa, wb]).max())
    close(st.velocity, [va1, vb1], vscale)
    close(st.omega, [wa1, wb1], vscale / min(Ra, Rb))
    if sliding:  # the slip keeps its direction and shrinks by μ B1 P_n (eqs 10, 26 as vectors)
        close(slip_end, S0 * (1 - mu * B1 * Pn / np.linalg.norm(S0)), vscale)
    else:
        assert np.linalg.norm(slip_end) < 10 * RTOL * vscale
    assert eng.dissipated_normal_J == pytest.approx(Ey, rel=RTOL, abs=RTOL * e0)
    assert eng.dissipated_tangential_J == pytest.approx(Ex, rel=1e-10, abs=RTOL * e0)
    assert e0 - kinetic(eng) == pytest.approx(Ey + Ex, rel=1e-10, abs=1e-12 * e0)


def test_3d_planar_collision_equals_the_2d_paper_equations(make_case):
    """In the x-y plane the vector law reduces to the paper's scalar one (same engine, dimensions = 3)."""
    ang, Ra, Rb, e, mu = 0.8, 2e-3, 2.6e-3, 0.85, 0.25
    n = np.array([math.cos(ang), math.sin(ang)])
    xb = np.array([0.05, 0.05, 0.05])
    xa = xb + np.array([*((Ra + Rb) * n), 0.0])
    va, vb, wa, wb = np.array([-0.3, 0.4]), np.array([0.2, 0.1]), 30.0, -12.0
    eng = make(make_case, [xa, xb], np.array([2 * Ra, 2 * Rb]), [[*va, 0], [*vb, 0]], [[0, 0, wa], [0, 0, wb]],
               dimensions=3, contact=hard(e, mu))
    eng.advance(1)
    va1, vb1, wa1, wb1, *_ = paper_2d(va, vb, wa, wb, n, Ra, Rb, *eng.state.mass, e, mu)
    close(eng.state.velocity[:, :2], [va1, vb1], 1.0)
    close(eng.state.omega[:, 2], [wa1, wb1], 1.0 / Ra)


def test_equal_spheres_have_b1_over_b2_of_seven_halves(make_case):
    """B1 = 1/m_a + 1/m_b + R_a²/I_a + R_b²/I_b = 7/m for equal solid spheres (I = 2/5 m R²), B2 = 2/m.

    Measured from a sticking collision: P_t = −S0/B1 and P_n = −(1+e) C0/B2, so the
    tangential and normal velocity changes of a are −S0/(m B1) and −(1+e)C0/(m B2).
    """
    R, e = 2e-3, 0.9
    xb = np.array([0.05, 0.05, 0.05])
    xa = xb + np.array([2 * R, 0.0, 0.0])
    S0, C0 = 0.1, -1.0  # slip along y from translation only, head-on approach along x
    eng = make(make_case, [xa, xb], 2 * R, [[C0 / 2, S0 / 2, 0], [-C0 / 2, -S0 / 2, 0]], np.zeros((2, 3)),
               dimensions=3, contact=hard(e, 1.0))
    eng.advance(1)
    m = eng.state.mass[0]
    dvt = eng.state.velocity[0, 1] - S0 / 2
    dvn = eng.state.velocity[0, 0] - C0 / 2
    b1 = -S0 / (m * dvt)
    b2 = -(1 + e) * C0 / (m * dvn)
    assert b1 * m == pytest.approx(7.0, rel=1e-12)
    assert b1 / b2 == pytest.approx(3.5, rel=1e-12)


# ---------------------------------------------------------------- walls
BOX = {"name": "box", "kind": "box", "lower": [0.0, 0.0, 0.0], "upper": [0.1, 0.1, 0.1]}


@pytest.mark.parametrize("dimensions", [2, 3])
@pytest.mark.parametrize("vx, w, slides", [(0.05, 20.0, False), (2.0, -40.0, True)])
def test_wall_collision_is_a_pair_with_an_infinite_mass(make_case, dimensions, vx, w, slides):
    """A sphere on the floor of a box (normal +y): the wall is particle b with v = 0, m = ∞ (Hoomans §2.3).

    The wall law comes from wall_contact (e_w, μ_w differ from the particle law on purpose).
    """
    R, ew, muw = 2e-3, 0.6, 0.35
    x = np.array([0.05, R, 0.05 if dimensions == 3 else 0.002])
    v = np.array([vx, -0.5, 0.0])
    wvec = np.array([0.0, 0.0, w])
    eng = make(make_case, [x], 2 * R, [v], [wvec], dimensions=dimensions, contact=hard(0.95, 0.05), walls=[BOX],
               wall_contact=hard(ew, muw))
    e0 = kinetic(eng)
    eng.advance(1)
    m = eng.state.mass[0]
    va1, _, wa1, _, Ey, Ex, sliding, _ = paper_2d(v[:2], np.zeros(2), w, 0.0, np.array([0.0, 1.0]), R, R, m,
                                                  math.inf, ew, muw)
    assert sliding == slides
    assert eng.collisions == 1 and eng.wall_collisions == 1
    close(eng.state.velocity[0, :2], va1, 1.0)
    close(eng.state.omega[0, 2], wa1, 1.0 / R)
    assert eng.dissipated_normal_J == pytest.approx(Ey, rel=RTOL)
    assert eng.dissipated_tangential_J == pytest.approx(Ex, rel=1e-10)
    assert e0 - kinetic(eng) == pytest.approx(Ey + Ex, rel=1e-10)
    # 3D vector reference agrees too
    va3, _, wa3, *_ = vector_3d(x, x - np.array([0, R, 0]), v, np.zeros(3), wvec, np.zeros(3), R, 0.0, m, math.inf,
                                ew, muw)
    close(eng.state.velocity[0], va3, 1.0)
    close(eng.state.omega[0], wa3, 1.0 / R)


def test_sticking_on_a_wall_leaves_five_sevenths_of_the_tangential_speed(make_case):
    """Classic result of B1 = 7/(2m): a sphere hitting a wall without spin leaves rolling at 5/7 v_t."""
    R, vt = 2e-3, 0.3
    eng = make(make_case, [[0.05, R, 0.002]], 2 * R, [[vt, -1.0, 0.0]], [[0, 0, 0]], dimensions=2,
               contact=hard(0.9, 1.0), walls=[BOX])
    eng.advance(1)
    v = eng.state.velocity[0]
    assert v[0] == pytest.approx(5 / 7 * vt, rel=1e-13)
    assert v[1] == pytest.approx(0.9, rel=1e-13)
    assert eng.state.omega[0, 2] == pytest.approx(-5 / 7 * vt / R, rel=1e-13)  # rolls: v_x + ω_z R = 0


def test_species_pair_and_wall_overrides_reach_the_collision(make_case):
    """pairs and wall_pairs overrides of e (as for soft spheres) set the restitution of that collision."""
    species = [{"name": "a", "diameter": DIAMETER, "density": DENSITY, "count": 1},
               {"name": "b", "diameter": DIAMETER, "density": 2 * DENSITY, "count": 1}]
    R = DIAMETER / 2
    xb = np.array([0.05, 0.05, 0.002])
    eng = make(make_case, [xb + [2 * R, 0, 0], xb], DIAMETER, [[-1.0, 0, 0], [0.0, 0, 0]], np.zeros((2, 3)),
               dimensions=2, contact=hard(0.9, 0.0), species=species, species_index=[0, 1],
               pairs=[{"species": ["b", "a"], "restitution": 0.4}])
    eng.advance(1)
    v = eng.state.velocity[:, 0]
    assert v[0] - v[1] == pytest.approx(0.4 * 1.0, rel=1e-13)  # Newton's law with the pair's e
    assert eng.pp[0, 1, 1] == eng.pp[1, 0, 1] == 0.4 and eng.pp[0, 0, 1] == 0.9


# ---------------------------------------------------------------- collapse remedy, guards
def test_tc_model_makes_a_collision_within_tc_elastic_and_frictionless(make_case):
    """Floor, a, b stacked and touching, moving down together: a hits the floor (inelastic, its
    first collision), rebounds into b at once (a collided 0 s ago < t_c): e = 1, μ = 0 there."""
    R, e, v = 2e-3, 0.5, -0.2
    eng = make(make_case, [[0.05, R, 0.002], [0.05, 3 * R, 0.002]], 2 * R, [[0.1, v, 0], [-0.1, v, 0]],
               np.zeros((2, 3)), dimensions=2, contact=hard(e, 0.4, collapse_time=1e-5), walls=[BOX])
    eng.record_collisions(10)
    e0 = kinetic(eng)
    eng.advance(1)
    log = eng.logged
    assert [tuple(r[1:3].astype(int)) for r in log[:2]] == [(0, -3 - 2), (0, 1)]  # floor = plane 2 (ymin)
    assert eng.remedy_count >= 1
    assert log[1, 3] == 0.0 and log[1, 4] == 0.0  # the remedied collision dissipates nothing
    # only the floor collision dissipated: eq. 23 with e, plus its tangential part
    assert e0 - kinetic(eng) == pytest.approx(eng.dissipated_normal_J + eng.dissipated_tangential_J, rel=1e-10)


def test_remedy_defaults_to_a_contact_time_and_can_be_switched_off():
    assert HardSphere().collapse_time == 1e-5
    assert HardSphere().pack(None, None)[2] == 1e-5
    assert HardSphere(collapse_time=0.0).pack(None, None)[2] == 0.0
    with pytest.raises(ValueError):
        HardSphere(collapse_time=-1.0)


def test_without_the_remedy_every_collision_uses_e_and_mu(make_case):
    """collapse_time = 0 (Hoomans 1996): the rebound into b right after the floor collision is inelastic."""
    R, e, v = 2e-3, 0.5, -0.2
    eng = make(make_case, [[0.05, R, 0.002], [0.05, 3 * R, 0.002]], 2 * R, [[0.0, v, 0], [0.0, v, 0]],
               np.zeros((2, 3)), dimensions=2, contact=hard(e, 0.4, collapse_time=0.0), walls=[BOX])
    eng.record_collisions(10)
    eng.advance(1)
    assert eng.remedy_count == 0
    assert eng.logged[1, 3] > 0.0  # the second collision dissipates (eq. 23 with e = 0.5)


def test_event_limit_stops_with_a_clear_error_and_keeps_the_state(make_case):
    R = 2e-3
    eng = make(make_case, [[0.05, R, 0.002], [0.05, 3 * R, 0.002]], 2 * R, [[0, -0.2, 0], [0, -0.2, 0]],
               np.zeros((2, 3)), dimensions=2, contact=hard(0.5, 0.0), walls=[BOX])
    eng.max_events_per_step = 1
    before = eng.state.position.copy(), eng.state.velocity.copy()
    with pytest.raises(CollisionCascadeError, match="more than 1 events in step 0"):
        eng.advance(3)
    assert eng.steps == 0 and eng.collisions == 0
    np.testing.assert_array_equal(eng.state.position, before[0])
    np.testing.assert_array_equal(eng.state.velocity, before[1])


def test_moving_wall_is_refused_by_name(make_case):
    wall = dict(BOX, motion={"kind": "constant_velocity", "velocity": [0.0, 0.1, 0.0]})
    with pytest.raises(CaseError, match="'box' moves"):
        make(make_case, [[0.05, 0.05, 0.002]], DIAMETER, [[0, 0, 0]], [[0, 0, 0]], dimensions=2, contact=hard(),
             walls=[wall])


def test_initial_overlap_is_reported(make_case):
    with pytest.raises(CaseError, match="overlap"):
        make(make_case, [[0.05, 0.05, 0.002], [0.053, 0.05, 0.002]], DIAMETER, np.zeros((2, 3)), np.zeros((2, 3)),
             dimensions=2, contact=hard())


@pytest.mark.parametrize("dim2", [True, False])
def test_upper_half_lists_each_pair_once_in_row_order(dim2):
    """``upper_half`` (what the all-particle prediction walks): row i holds exactly the neighbours j > i of
    the full list's row i, in that row's order (the order in which the prediction offers equal times)."""
    from fluidem.particles import _hardsphere_kernels as K

    rng = np.random.default_rng(3)
    n = 700
    pos = rng.uniform(0.0, 0.05 if dim2 else 0.02, (n, 3))  # a few neighbours each (overlaps do not matter)
    if dim2:
        pos[:, 2] = 0.002
    radius = rng.uniform(0.5e-3, 1.5e-3, n)
    start, nbr = K.build_neighbours(pos, radius, 1e-3, dim2)
    up_start, up = K.upper_half(start, nbr)
    assert up_start.dtype == np.uint64 and up.dtype == np.uint32
    assert up.size == nbr.size // 2 > n  # the full list is symmetric: each pair twice there, once here
    for i in range(n):
        row = nbr[start[i]:start[i + 1]]
        assert np.array_equal(up[up_start[i]:up_start[i + 1]], row[row > i])
