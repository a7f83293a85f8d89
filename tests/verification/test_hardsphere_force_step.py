"""The force step of the hard-sphere engine against closed forms: free flight and a bouncing sphere.

Hoomans 1996 adds the whole impulse (g + F/m) DT to every velocity before the step's collision
sequence (eqs 33–34) and then flies straight (eq. 32): after n steps from rest, v_n = v_0 + a n DT and

    x_n = x_0 + Σ_{k=1..n} v_k DT = x_0 + v_0 t + a DT² n(n+1)/2 = x_0 + v_0 t + ½ a t² + ½ a DT t,

a position error ½ a DT t, first order in DT, and an energy error E_n − E_0 = −½ m |g|² DT t in free
fall (a = g): each step changes E = ½ m v² − m g·x by ½ m g·(v_{n+1} − v_n) DT = −½ m |g|² DT².
The split step (``particles.force_step = "split"``) gives half the impulse before the sequence and
half after: x_n = x_0 + Σ (v_{k-1} + ½ a DT) DT = x_0 + v_0 t + ½ a t², v_n = v_0 + a t, the parabola
itself, and no energy error in flight.

A bounce inside a step is straight flight at the step's velocity, so each bounce of an elastic
sphere on a floor changes the energy: by −(1 + e) m |g| y_mid (derived in the test) with y_mid the
height above contact at mid-step on the straight path, |y_mid| ≤ |v| DT/2. Under the split step
the steps are time-reversible: the next bounce meets the floor at the mirror phase and gives the
change back, so the energy takes two values forever, without drift. Hoomans' step is the split step
seen half a kick later (``test_hardsphere_dynamics``): it does not drift either, and adds the
first-order offset ½ m g·DT (v_0 − v) of its half-step-apart positions and velocities.
"""
from __future__ import annotations

import numpy as np
import pytest

from fluidem.case import validate_case
from fluidem.particles.hardsphere import HardSphereEngine

D = 4e-3  # [m]
R = D / 2
G = 9.81  # [m/s²]
DT = 1e-4  # [s] Hoomans' DT


def one_sphere(tmp_path, force_step, pos, vel=(0.0, 0.0, 0.0), e=1.0, dt=DT, height=1.0):
    """One aluminium sphere of 4 mm in a 2D box 0.02 m wide and ``height`` high, frictionless."""
    path = tmp_path / f"one-{force_step}.csv"
    path.write_text("x,y,z,diameter,vx,vy,vz\n" + ",".join(str(float(v)) for v in (*pos, D, *vel)) + "\n")
    case = validate_case({
        "name": "one", "particles": {
            "dimensions": 2, "force_step": force_step,
            "species": [{"name": "p", "diameter": D, "density": 2700.0, "count": 1}],
            "contact": {"model": "hard_sphere", "restitution": e, "friction": 0.0},
            "placement": {"method": "file", "file": str(path)}},
        "walls": [{"name": "box", "kind": "box", "lower": [0.0, 0.0, 0.0], "upper": [0.02, height, D]}],
        "time": {"end": 100.0, "dt": dt}})
    return HardSphereEngine(case)


@pytest.mark.parametrize("force_step", ["split", "hoomans"])
def test_free_flight_under_gravity_and_a_constant_force_follows_the_closed_form(tmp_path, force_step):
    """3000 steps of flight (0.3 s) under g and a constant horizontal force F = −0.01 m g (as a gas force would
    be), from x_0 = (0.015, 0.9) m, v_0 = (−0.02, 1.0) m/s. Split: the parabola to round-off (1e-12 of the
    distance flown, 1e-12 m/s; measured ~1e-15). Hoomans: the parabola plus ½ a DT t exactly (the same
    tolerance), so the error is the scheme's own, first order. Velocities are exact in both (a t)."""
    x0 = np.array([0.015, 0.9, R])
    v0 = np.array([-0.02, 1.0, 0.0])
    eng = one_sphere(tmp_path, force_step, x0, v0)
    m = eng.state.mass[0]
    eng.ext_force[0] = (-0.01 * m * G, 0.0, 0.0)
    a = np.array([-0.01 * G, -G, 0.0])
    n = 3000
    for _ in range(30):
        eng.advance(n // 30)
    t = n * DT
    assert eng.collisions == 0, "the sphere must stay clear of the walls"
    exact = x0 + v0 * t + 0.5 * a * t**2
    want = exact if force_step == "split" else x0 + v0 * t + a * DT**2 * n * (n + 1) / 2
    np.testing.assert_allclose(eng.state.position[0], want, rtol=0, atol=1e-12 * np.linalg.norm(exact - x0))
    np.testing.assert_allclose(eng.state.velocity[0], v0 + a * t, rtol=0, atol=1e-12)
    if force_step == "hoomans":  # the error is ½ a DT t, not round-off
        np.testing.assert_allclose(eng.state.position[0] - exact, 0.5 * a * DT * t, rtol=1e-6, atol=1e-15)


@pytest.mark.parametrize("force_step", ["split", "hoomans"])
def test_free_fall_energy_error_is_zero_for_split_and_first_order_for_hoomans(tmp_path, force_step):
    """Free fall from rest for 0.25 s: E_n − E_0 = 0 (split; to 1e-12 of E_0) or −½ m g² DT t (Hoomans; exact
    within 1e-9 relative), for DT = 1e-4 and 5e-5 s: Hoomans' error halves with DT, first order."""
    errors = {}
    for dt in (1e-4, 5e-5):
        eng = one_sphere(tmp_path, force_step, (0.01, 0.9, R), dt=dt)
        m = eng.state.mass[0]
        e0 = eng.energies()["total_J"]
        eng.advance(round(0.25 / dt))
        assert eng.collisions == 0
        errors[dt] = eng.energies()["total_J"] - e0
        want = 0.0 if force_step == "split" else -0.5 * m * G**2 * dt * 0.25
        assert errors[dt] == pytest.approx(want, rel=1e-9, abs=1e-12 * e0)
    if force_step == "hoomans":
        assert errors[1e-4] / errors[5e-5] == pytest.approx(2.0, rel=1e-9)


def flight_energies(eng, force_step, periods, period_steps, sample=37):
    """The energy invariant of each flight between bounces [J], sampled every ``sample`` steps over
    ``periods`` bounce periods: under the split step E itself is constant in flight; under Hoomans'
    step E − ½ m |g| DT v_y is (each step changes E by ½ m |g| DT (v_{n+1} − v_n)), which is E at the
    top of the flight (v_y = 0). Returns one value per sample."""
    m = eng.state.mass[0]
    out = []
    for _ in range(int(periods * period_steps / sample)):
        eng.advance(sample)
        e = eng.energies()["total_J"]
        if force_step == "hoomans":
            e -= 0.5 * m * G * eng.dt * eng.state.velocity[0, 1]
        out.append(e)
    return np.array(out)


def test_elastic_bounces_keep_two_energies_under_the_split_step(tmp_path):
    """A sphere dropped from 5 cm above the floor (e = 1, μ = 0) for 100 bounces (20 s, 2e5 steps).

    The bounce changes the energy by −(1 + e) m g y_mid (a bounce at the step's phase τ from the velocity
    v' after the first half kick: y_{n+1} = −e v' (DT − τ), y_n = −v' τ, hence E_{n+1} + E_dsp − E_n =
    −(1 + e) m g (y_n + v' DT/2)), at most 2 m g |v'| DT/2 for e = 1: 2.0e-3 of E_0 here. The next bounce
    gives it back (time reversibility), so every sample lies at E_0 or at E_0 + Δ within round-off
    (1e-12 of E_0; measured ~1e-13 after 100 bounces), and both values occur to the end: no drift."""
    eng = one_sphere(tmp_path, "split", (0.01, R + 0.05, R))
    m = eng.state.mass[0]
    e0 = eng.energies()["total_J"]
    period = 2.0 * np.sqrt(2 * 0.05 / G)
    energies = flight_energies(eng, "split", 100, period / DT)
    assert eng.collisions >= 99
    dev = (energies - e0) / e0
    delta = dev[np.argmax(np.abs(dev))]
    bound = m * G * np.sqrt(2 * G * 0.05) * DT / e0
    assert 1e-6 < abs(delta) <= bound, "one bounce's change: not zero, within its bound"
    near_e0 = np.abs(dev) < 1e-12
    near_delta = np.abs(dev - delta) < 1e-12
    assert np.all(near_e0 | near_delta), f"worst {np.max(np.minimum(np.abs(dev), np.abs(dev - delta))):.3g}"
    last = slice(-len(dev) // 10, None)  # the last ten bounces still visit both values
    assert near_e0[last].any() and near_delta[last].any()


def test_elastic_bounces_under_hoomans_step_carry_a_first_order_offset(tmp_path):
    """The same sphere under Hoomans' step. It is the split step seen half a kick later (see
    ``test_hardsphere_dynamics``), so it does not drift either: E − ½ m g DT v_y, the energy at the top
    of each flight, takes two values to round-off as above. What it adds is the offset ½ m g DT v_y of
    positions and velocities half a step apart, first order in DT and as large as the speed: −½ m g DT
    |v| just before each bounce (4.9e-4 of E_0 here), the reported energy error of a falling bed."""
    eng = one_sphere(tmp_path, "hoomans", (0.01, R + 0.05, R))
    m = eng.state.mass[0]
    e0 = eng.energies()["total_J"]
    period = 2.0 * np.sqrt(2 * 0.05 / G)
    energies = flight_energies(eng, "hoomans", 100, period / DT)
    dev = (energies - e0) / e0
    delta = dev[np.argmax(np.abs(dev))]
    near_e0 = np.abs(dev) < 1e-12
    near_delta = np.abs(dev - delta) < 1e-12
    assert np.all(near_e0 | near_delta)
    last = slice(-len(dev) // 10, None)
    assert near_e0[last].any() and near_delta[last].any()
    # the reported energy itself, against that closed form, one flight long
    eng = one_sphere(tmp_path, "hoomans", (0.01, R + 0.05, R))
    eng.advance(1000)  # 0.1 s, just before the first bounce (at 0.101 s)
    assert eng.collisions == 0
    v = eng.state.velocity[0, 1]
    assert eng.energies()["total_J"] - e0 == pytest.approx(0.5 * m * G * DT * v, rel=1e-9)
    assert 0.5 * m * G * DT * abs(v) / e0 > 4e-4
