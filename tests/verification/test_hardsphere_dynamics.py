"""Many-particle behaviour of the event-driven hard-sphere engine.

* Event detection against a brute-force reference written here: Hoomans 1996 Fig. 3
  literally (all pairs and walls scanned for every event, eq. 30 and its wall form,
  every particle moved by eq. 32, collisions by eqs 10–29 in vector form). Both run the
  same small dense random gas, polydisperse, with gravity impulses every DT. They must
  give the same collision sequence (pairs and times) and the same final state.
* Energy: elastic, frictionless spheres without gravity in a box keep their kinetic
  energy to 1e-10 relative over 10⁶ collisions.
* Overlaps: none after any step, in a dense inelastic, frictional pour.
* The neighbour list equals the O(N²) list of pairs closer than R_i + R_j + skin.
* A run restored from a checkpoint continues bit for bit.
"""
from __future__ import annotations

import numpy as np
import pytest

from fluidem.case import validate_case
from fluidem.io.restart import load_restart, save_restart
from fluidem.particles import _hardsphere_kernels as K
from fluidem.particles.hardsphere import HardSphereEngine
from fluidem.state import ParticleState

D = 4e-3  # [m]
DENSITY = 2700.0  # [kg/m^3]


def hard(e=0.9, mu=0.3, **kw):
    return {"model": "hard_sphere", "restitution": e, "friction": mu, **kw}


def box_case(n, size, *, dimensions=2, contact=None, gravity=(0.0, 0.0, 0.0), dt=1e-4, seed=5, dist=None,
             skin=None, wall_contact=None, force_step="split"):
    species = {"name": "p", "diameter": D, "density": DENSITY, "count": n}
    if dist is not None:
        species["size_distribution"] = dist
    data = {
        "name": "hs-box", "gravity": list(gravity),
        "particles": {"dimensions": dimensions, "species": [species], "contact": contact or hard(),
                      "force_step": force_step,
                      "placement": {"method": "random", "seed": seed}},
        "walls": [{"name": "box", "kind": "box", "lower": [0.0, 0.0, 0.0], "upper": list(size)}],
        "time": {"end": 1.0, "dt": dt},
    }
    if skin is not None:
        data["neighbours"] = {"skin": skin}
    if wall_contact is not None:
        data["particles"]["wall_contact"] = wall_contact
    return validate_case(data)


def random_velocities(eng, speed, seed):
    rng = np.random.default_rng(seed)
    v = rng.normal(0.0, speed, eng.state.velocity.shape)
    if eng.dim2:
        v[:, 2] = 0.0
    eng.state.velocity[...] = v


def worst_overlap(eng):
    """Largest overlap / (R_i + R_j) over all pairs, and over particles and walls (positive = overlap)."""
    st = eng.state
    r = st.position[:, None, :] - st.position[None, :, :]
    dist = np.sqrt(np.einsum("ijk,ijk->ij", r, r))
    sig = st.radius[:, None] + st.radius[None, :]
    np.fill_diagonal(dist, np.inf)
    pair = float(np.max((sig - dist) / sig))
    wall = max(float(np.max((st.radius - (st.position - p.point) @ p.normal) / st.radius)) for p in eng.walls.planes)
    return pair, wall


# ---------------------------------------------------------------- brute-force reference (Hoomans Fig. 3)
def reference_collide(i, j, pos, vel, omega, radius, mass, inertia, e, mu, wall_normal=None):
    """Vector form of Hoomans eqs 10–29; j < 0: wall with inward normal wall_normal (infinite mass)."""
    if j >= 0:
        n = pos[i] - pos[j]
        n = n / np.linalg.norm(n)
        cp = pos[i] - radius[i] * n
        u = (vel[i] + np.cross(omega[i], cp - pos[i])) - (vel[j] + np.cross(omega[j], cp - pos[j]))
        inv_mb, kb = 1.0 / mass[j], radius[j] ** 2 / inertia[j]
    else:
        n = wall_normal
        cp = pos[i] - radius[i] * n
        u = vel[i] + np.cross(omega[i], cp - pos[i])
        inv_mb, kb = 0.0, 0.0
    c0 = u @ n
    s0 = u - c0 * n
    b2 = 1.0 / mass[i] + inv_mb
    b1 = b2 + radius[i] ** 2 / inertia[i] + kb
    pn = -(1 + e) * c0 / b2
    s = np.linalg.norm(s0)
    pt = -mu * pn * s0 / s if s >= mu * b1 * pn and s > 0 else (-s0 / b1 if s > 0 else np.zeros(3))
    J = pn * n + pt
    vel[i] += J / mass[i]
    omega[i] += np.cross(cp - pos[i], J) / inertia[i]
    if j >= 0:
        vel[j] -= J / mass[j]
        omega[j] += np.cross(cp - pos[j], -J) / inertia[j]


def reference_run(pos, vel, omega, radius, mass, inertia, planes, gravity, dt, nsteps, e, mu, split=False):
    """Hoomans 1996 Fig. 3: per step a force kick, then the earliest collision of all pairs and walls,
    move everyone, collide, repeat; returns the list of (time, a, b or wall code). ``split``: half the
    kick before the collisions and half after them."""
    n = pos.shape[0]
    iu, ju = np.triu_indices(n, 1)
    sig = radius[iu] + radius[ju]
    events = []
    kick = 0.5 * dt if split else dt
    for step in range(nsteps):
        vel += gravity * kick  # eq. 33 (its first half when split)
        t = 0.0
        while True:
            r = pos[iu] - pos[ju]
            v = vel[iu] - vel[ju]
            b = np.einsum("ij,ij->i", r, v)
            c = np.einsum("ij,ij->i", r, r) - sig**2
            v2 = np.einsum("ij,ij->i", v, v)
            disc = b * b - v2 * c
            with np.errstate(divide="ignore", invalid="ignore"):
                tp = np.where((b < 0) & (disc >= 0), c / (-b + np.sqrt(np.maximum(disc, 0.0))), np.inf)  # eq. 30
            tp = np.where((b < 0) & (c <= 0), 0.0, tp)
            k = int(np.argmin(tp)) if tp.size else -1
            best, who = (tp[k], (iu[k], ju[k])) if k >= 0 else (np.inf, None)
            for w, (p0, nrm) in enumerate(planes):
                h = (pos - p0) @ nrm - radius
                vn = vel @ nrm
                with np.errstate(divide="ignore"):
                    tw = np.where(vn < 0, np.where(h <= 0, 0.0, h / -vn), np.inf)  # eq. 31, any plane
                q = int(np.argmin(tw))
                if tw[q] < best:
                    best, who = tw[q], (q, -3 - w)
            if t + best >= dt:
                pos += vel * (dt - t)  # eq. 32 to the end of the step
                break
            pos += vel * best  # "move": eq. 32 for every particle
            t += best
            a, bb = who
            if bb >= 0:
                reference_collide(a, bb, pos, vel, omega, radius, mass, inertia, e, mu)
            else:
                reference_collide(a, -1, pos, vel, omega, radius, mass, inertia, e, mu, planes[-3 - bb][1])
            events.append((step * dt + t, a, bb))
        if split:
            vel += gravity * kick
    return events


def unordered(a, b):
    return (min(a, b), max(a, b)) if b >= 0 else (a, b)


@pytest.mark.parametrize("force_step", ["split", "hoomans"])
@pytest.mark.parametrize("dimensions", [2, 3])
def test_event_detection_matches_the_all_pairs_reference(dimensions, force_step):
    """Same collision sequence and final state as the brute-force Fig. 3 algorithm.

    40 polydisperse spheres (d = 3–5 mm; area fraction 0.35 in 2D, volume fraction 0.11 in
    3D), random velocities of 1 m/s, gravity, e = 0.9, μ = 0.3, 60 steps of 1e-4 s: about
    200 collisions, 50–90 of them with walls. The pairs and walls must match one for one.
    Times must agree to 1e-8 DT and states to 1e-9 of their scales (D, 1 m/s, 1 m/s / R).
    The reference has no collapse remedy, so it is off here too.
    The two codes round differently (the reference moves every particle at every event),
    and a dense gas amplifies a difference by a factor of a few per collision. Measured:
    times 1.4e-10 DT; positions 3e-13 D; velocities 2e-12 m/s; spins 4e-12 of v/R. A wrong
    or missed event changes the results at order one. Both force steps (``particles.force_step``), each
    against the reference with its own kicks.
    """
    L = 0.03 if dimensions == 2 else 0.018
    size = (L, L, 0.004) if dimensions == 2 else (L, L, L)
    case = box_case(40, size, dimensions=dimensions, contact=hard(0.9, 0.3, collapse_time=0.0), gravity=(0.0, -9.81, 0.0),
                    dist={"kind": "uniform", "min": 3e-3, "max": 5e-3}, seed=11, skin=0.4 * D, force_step=force_step)
    eng = HardSphereEngine(case)
    random_velocities(eng, 1.0, seed=2)
    st = eng.state
    ref = [a.copy() for a in (st.position, st.velocity, st.omega)]
    planes = [(p.point, p.normal) for p in eng.walls.planes]
    nsteps = 60
    eng.record_collisions(10000)
    eng.advance(nsteps)
    events = reference_run(*ref, st.radius, st.mass, st.inertia, planes, eng.gravity, eng.dt, nsteps, 0.9, 0.3,
                           split=force_step == "split")
    log = eng.logged
    assert len(events) > 150 and eng.wall_collisions > 30, "the test gas must collide often, also with walls"
    assert len(log) == len(events)
    assert [unordered(int(a), int(b)) for a, b in log[:, 1:3]] == [unordered(int(a), int(b)) for _, a, b in events]
    np.testing.assert_allclose(log[:, 0], [t for t, _, _ in events], rtol=0, atol=1e-8 * eng.dt)
    for got, want, scale in zip((st.position, st.velocity, st.omega), ref, (D, 1.0, 1.0 / (D / 2))):
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-9 * scale)


@pytest.mark.parametrize("dimensions", [2, 3])
def test_hoomans_step_is_the_split_step_half_a_kick_later(dimensions):
    """Under gravity alone the two force steps give the same collisions of the same trajectories.

    Hoomans' step K_DT D (kick, then the collision sequence D) repeated n times is
    K_DT/2 (K_DT/2 D K_DT/2)^n K_−DT/2 (applied from the left): the split step started from v_0 + g DT/2,
    with every reported velocity g DT/2 behind the split one. So a split run from v_0 + g DT/2 must log
    Hoomans' collisions one for one (pairs, walls, times) and end at its positions, with velocities g DT/2
    ahead. The gas of
    the reference test (40 polydisperse spheres, e = 0.9, μ = 0.3, 60 steps) and its tolerances, for the
    same reason: the two runs round differently (the kicks are split), and a dense gas amplifies that.
    This is why the split step keeps Hoomans' collision sequence (Fig. 3, eqs 30–32) and differs only in
    the instant its velocities are reported at, which the energy of eq. 51 sees."""
    L = 0.03 if dimensions == 2 else 0.018
    size = (L, L, 0.004) if dimensions == 2 else (L, L, L)
    runs = {}
    for step in ("hoomans", "split"):
        case = box_case(40, size, dimensions=dimensions, contact=hard(0.9, 0.3, collapse_time=0.0),
                        gravity=(0.0, -9.81, 0.0), dist={"kind": "uniform", "min": 3e-3, "max": 5e-3}, seed=11,
                        skin=0.4 * D, force_step=step)
        eng = HardSphereEngine(case)
        random_velocities(eng, 1.0, seed=2)
        if step == "split":
            eng.state.velocity[...] += 0.5 * eng.dt * eng.gravity
        eng.record_collisions(10000)
        eng.advance(60)
        runs[step] = eng
    h, s = runs["hoomans"], runs["split"]
    assert len(h.logged) > 150 and h.wall_collisions > 30
    assert len(s.logged) == len(h.logged)
    assert [unordered(int(a), int(b)) for a, b in s.logged[:, 1:3]] == \
        [unordered(int(a), int(b)) for a, b in h.logged[:, 1:3]]
    np.testing.assert_allclose(s.logged[:, 0], h.logged[:, 0], rtol=0, atol=1e-8 * h.dt)
    np.testing.assert_allclose(s.state.position, h.state.position, rtol=0, atol=1e-9 * D)
    np.testing.assert_allclose(s.state.velocity - 0.5 * h.dt * h.gravity, h.state.velocity, rtol=0, atol=1e-9)
    np.testing.assert_allclose(s.state.omega, h.state.omega, rtol=0, atol=1e-9 / (D / 2))


def test_elastic_frictionless_spheres_conserve_energy_over_a_million_collisions():
    """e = 1, μ = 0, no gravity: kinetic energy constant to 1e-10 relative over 10⁶ collisions.

    50 spheres in a 2D box at area fraction 0.39 with random velocities of 10 m/s (DT = 1 ms).
    Each collision changes the energy by round-off (~1e-16 relative). Over 10⁶ of them a
    random walk gives ~1e-13 (measured 4e-12), so 1e-10 fails only for a systematic
    error: a wrong impulse factor gives 1e-2 after one collision.
    """
    case = box_case(50, (0.04, 0.04, 0.004), contact=hard(1.0, 0.0), dt=1e-3, seed=3, skin=D)
    eng = HardSphereEngine(case)
    random_velocities(eng, 10.0, seed=4)
    st = eng.state
    e0 = 0.5 * np.sum(st.mass * np.sum(st.velocity**2, axis=1))
    worst = 0.0
    while eng.collisions < 1_000_000:
        eng.advance(20)
        e = 0.5 * np.sum(st.mass * np.sum(st.velocity**2, axis=1))
        worst = max(worst, abs(e - e0) / e0)
    assert worst < 1e-10, f"relative energy error {worst:.3g}"
    assert np.all(st.omega == 0.0)  # frictionless: no spin is ever created
    assert eng.dissipated_normal_J == 0.0 and eng.dissipated_tangential_J == 0.0
    assert max(worst_overlap(eng)) < 1e-12


def test_no_overlap_after_any_step_in_a_dense_pour():
    """Dense 2D pour of 150 spheres of 3–4 mm into a box, e = 0.6, μ = 0.5, until the bed rests.

    After every step no pair and no wall overlaps by more than 1e-12 of the contact
    distance. Positions of order 0.05 m carry round-off of ~1e-17 m, i.e. 1e-14 of a
    diameter. A bed this inelastic and frictional collapses without the TC remedy (see
    contact/hard_sphere.py); the default t_c = 1e-5 s is set explicitly here, and the
    test checks that the remedy acts.
    """
    case = box_case(150, (0.04, 0.1, 0.004), contact=hard(0.6, 0.5, collapse_time=1e-5),
                    gravity=(0.0, -9.81, 0.0), seed=8, dist={"kind": "uniform", "min": 3e-3, "max": 4e-3})
    eng = HardSphereEngine(case)
    worst = 0.0
    for _ in range(1500):
        eng.advance(1)
        worst = max(worst, *worst_overlap(eng))
    assert eng.collisions > 100_000 and eng.remedy_count > 10_000, "the bed must have formed, with the remedy acting"
    assert eng.energies()["kinetic_J"] < 1e-3 * eng.energies()["dissipated_J"], "the bed must have come to rest"
    assert worst < 1e-12, f"overlap {worst:.3g} of the contact distance"


@pytest.mark.parametrize("dimensions", [2, 3])
def test_neighbour_list_equals_all_pairs_within_the_cutoff(dimensions):
    rng = np.random.default_rng(1)
    n = 400
    pos = rng.uniform(0, 0.05, (n, 3))
    if dimensions == 2:
        pos[:, 2] = 0.002
    radius = rng.uniform(1e-3, 3e-3, n)
    skin = 1.5e-3
    start, nbr = K.build_neighbours(pos, radius, skin, dimensions == 2)
    got = {(i, int(j)) for i in range(n) for j in nbr[start[i]:start[i + 1]]}
    r = np.linalg.norm(pos[:, None] - pos[None], axis=2)
    cut = radius[:, None] + radius[None, :] + skin
    want = {(int(i), int(j)) for i, j in zip(*np.nonzero(r < cut)) if i != j}
    assert got == want


def test_restored_checkpoint_continues_bit_for_bit(tmp_path):
    """Engine state through a restart file (HDF5) continues exactly like the uninterrupted engine,
    also with the TC remedy on (its clocks are in the checkpoint), while a bed forms."""
    case = box_case(120, (0.042, 0.1, 0.004), contact=hard(0.8, 0.3, collapse_time=1e-5),
                    gravity=(0.0, -9.81, 0.0), seed=21, dist={"kind": "uniform", "min": 3.5e-3, "max": 4.5e-3})
    whole = HardSphereEngine(case)
    whole.advance(1000)
    save_restart(tmp_path / "r.h5", whole.checkpoint_arrays(), whole.checkpoint_scalars(), case.to_toml())
    whole.advance(300)
    arrays, scalars, _ = load_restart(tmp_path / "r.h5")
    state = ParticleState(**{k[len("state/"):]: v.copy() for k, v in arrays.items() if k.startswith("state/")})
    again = HardSphereEngine(case, state=state)
    again.restore(arrays, scalars)
    again.advance(300)
    assert again.steps == whole.steps and again.collisions == whole.collisions > 10_000
    assert whole.remedy_count > 0
    for k in ("position", "velocity", "omega"):
        np.testing.assert_array_equal(getattr(again.state, k), getattr(whole.state, k))
    assert again.energies() == whole.energies()


def test_an_engine_restored_over_its_own_later_state_repeats_it():
    """Restoring a checkpoint into the engine that wrote it, after it ran on (a run resumed in the same
    process), repeats the same steps bit for bit: nothing the engine keeps between calls (its work arrays,
    among them what it derived from the list's reference positions) outlives the restore."""
    case = box_case(120, (0.042, 0.1, 0.004), contact=hard(0.8, 0.3, collapse_time=1e-5),
                    gravity=(0.0, -9.81, 0.0), seed=21, dist={"kind": "uniform", "min": 3.5e-3, "max": 4.5e-3})
    eng = HardSphereEngine(case)
    eng.advance(600)
    arrays = {k: v.copy() for k, v in eng.checkpoint_arrays().items()}
    scalars = dict(eng.checkpoint_scalars())
    eng.advance(400)
    first = {k: getattr(eng.state, k).copy() for k in ("position", "velocity", "omega")}
    rebuilds = eng.rebuilds
    eng.restore(arrays, scalars)
    eng.advance(400)
    assert eng.rebuilds == rebuilds > int(scalars["rebuilds"]), "the list must have been rebuilt after the checkpoint"
    for k, v in first.items():
        np.testing.assert_array_equal(getattr(eng.state, k), v)
