"""Soft-sphere collisions across periodic sides against the same collisions in the interior.

A pair that meets across a periodic side sees the same centre offset (by nearest image) as the pair shifted
into the interior, so its post-collision velocities and spins must be those of the interior collision, to
the round-off of the shifted coordinates (the offsets differ in their last bits: 1e-9 relative is far
above that and far below any physical difference; a lost tangential spring would change the spins by
tens of per cent). In a fully periodic box without gravity every contact force acts equally and
oppositely on its two particles, so the total momentum is conserved to round-off through many collisions.
A periodic run resumed from its checkpoint continues bit for bit.
"""
from __future__ import annotations

import numpy as np
import pytest

from fluidem.case import validate_case
from fluidem.particles.softsphere import SoftSphereEngine
from fluidem.state import ParticleState

from _helpers.periodic import DENSITY, DIAMETER, law, periodic_case_dict

D = DIAMETER
L = 12 * D


def engine(tmp_path, pos, vel, periodic, dimensions=3, contact=None, name="p.csv"):
    depth = L if dimensions == 3 else D
    return SoftSphereEngine(validate_case(periodic_case_dict(tmp_path / name, pos, vel, upper=(L, L, depth),
                                                             periodic=periodic, dimensions=dimensions,
                                                             contact=contact)))


def collide(eng, steps):
    eng.advance(steps)
    return eng.state.velocity.copy(), eng.state.omega.copy()


@pytest.mark.parametrize("dimensions", [2, 3])
@pytest.mark.parametrize("model", ["linear_spring_dashpot", "hertz_mindlin"])
@pytest.mark.parametrize("axis", [0, 1])
def test_oblique_collision_across_the_side_equals_the_interior_one(tmp_path, dimensions, model, axis):
    """Particle A runs into B at rest, off-centre (friction spins both); A's centre crosses the side during
    the contact. Interior: the same pair shifted by L/2 along the axis."""
    other = 1 - axis
    zc = 0.5 * D if dimensions == 2 else 0.5 * L
    a = np.zeros(3)
    b = np.zeros(3)
    touch = np.sqrt(1.0 - 0.3**2) * D  # axial offset of the centres at first touch (lateral offset 0.3 D)
    a[axis] = L - 20e-6 - 0.1 * D  # A first touches B 20 µm before its centre reaches the side
    b[axis] = a[axis] + 0.1 * D + touch  # B's centre beyond the side: the engine wraps it to b − L
    a[other] = 0.5 * L
    b[other] = 0.5 * L + 0.3 * D
    a[2] = b[2] = zc
    v = np.zeros((2, 3))
    v[0, axis] = 1.5
    v[0, other] = 0.1
    contact = law(model)
    ax = "xy"[axis]
    seam = engine(tmp_path, [a, b], v, [ax], dimensions, contact, "seam.csv")
    shift = np.eye(3)[axis] * 0.5 * L
    inner = engine(tmp_path, [a - shift, b - shift], v, [ax], dimensions, contact, "inner.csv")
    assert seam.state.position[1, axis] < D  # B was wrapped into the box at set-up
    steps = int(round(6 * seam.contact_time / seam.dt))
    crossed = False
    for _ in range(steps // 10):
        seam.advance(10)
        crossed |= seam.state.image[0, axis] != 0
    inner.advance(10 * (steps // 10))
    assert crossed, "A's centre did not cross the side"
    assert np.abs(inner.state.velocity[1]).max() > 0.5, "no collision happened"
    assert np.abs(inner.state.omega).max() > 1.0, "no friction torque"
    for name in ("velocity", "omega"):
        got, want = getattr(seam.state, name), getattr(inner.state, name)
        assert np.allclose(got, want, rtol=1e-9, atol=1e-9 * np.abs(want).max()), name
    unwrapped = seam.state.position + seam.state.image * seam.period
    assert np.allclose(unwrapped - shift, inner.state.position + inner.state.image * inner.period, rtol=0.0,
                       atol=1e-12 * L)


@pytest.mark.parametrize("dimensions", [2, 3])
def test_momentum_conserved_through_many_collisions_in_a_fully_periodic_box(tmp_path, dimensions):
    """400 (2D) or 500 (3D) spheres with random velocities, no gravity, no walls: the total momentum after
    0.03 s of collisions equals the initial one to round-off, 1e-12 of Σ m |v|."""
    rng = np.random.default_rng(4)
    n = 400 if dimensions == 2 else 500
    per_axis = 20 if dimensions == 2 else 8
    pitch = 1.5 * D
    side = pitch * per_axis
    idx = np.arange(n)
    pos = np.zeros((n, 3))
    pos[:, 0] = (idx % per_axis + 0.5) * pitch
    pos[:, 1] = (idx // per_axis % per_axis + 0.5) * pitch
    pos[:, 2] = (idx // per_axis**2 + 0.5) * pitch if dimensions == 3 else 0.5 * D
    vel = rng.normal(0.0, 1.0, (n, 3))
    if dimensions == 2:
        vel[:, 2] = 0.0
    depth = side if dimensions == 3 else D
    axes = ["x", "y", "z"] if dimensions == 3 else ["x", "y"]
    eng = SoftSphereEngine(validate_case(periodic_case_dict(tmp_path / "gas.csv", pos, vel, upper=(side, side, depth),
                                                            periodic=axes, dimensions=dimensions)))
    assert eng.walls.planes == [] or dimensions == 2
    m = eng.state.mass[:, None]
    p0 = np.sum(m * eng.state.velocity, axis=0)
    scale = float(np.sum(m[:, 0] * np.linalg.norm(eng.state.velocity, axis=1)))
    ke0 = 0.5 * np.sum(m * eng.state.velocity**2)
    crossings = 0
    for _ in range(30):  # 0.03 s: a sphere at the mean speed runs a quarter (2D) to half (3D) the box
        eng.advance(int(1e-3 / eng.dt))
        crossings = int(np.abs(eng.state.image).sum())
    p1 = np.sum(m * eng.state.velocity, axis=0)
    ke1 = 0.5 * np.sum(m * eng.state.velocity**2)
    assert ke1 < 0.8 * ke0, "too few collisions (restitution 0.9 dissipates energy at each)"
    assert crossings > 20, "too few crossings of the sides"
    assert np.all(np.abs(p1 - p0) < 1e-12 * scale), (p1 - p0) / scale


def test_checkpoint_restart_of_a_periodic_run_is_bit_for_bit(tmp_path, stopped_and_resumed):
    """A bed drifting sideways in a box periodic along x and y under gravity: resumed from its checkpoint it
    ends where the run made in one go ends, bit for bit (positions, velocities, spins, image counts); the
    snapshots carry the image counts."""
    data = {
        "name": "periodic-drift", "gravity": [0.0, 0.0, -9.81],
        "particles": {"dimensions": 3,
                      "species": [{"name": "p", "diameter": D, "density": DENSITY, "count": 120}],
                      "contact": law(),
                      "placement": {"method": "lattice", "spacing": 1.1, "seed": 5, "velocity": [0.4, 0.25, 0.0]}},
        "walls": [{"name": "box", "kind": "box", "lower": [0.0, 0.0, 0.0], "upper": [6 * D, 6 * D, 12 * D],
                   "periodic": ["x", "y"]}],
        "time": {"end": 0.06},
        "output": {"snapshot_interval": 0.02, "checkpoint_interval": 0.02},
    }
    case = validate_case(data)
    whole, first, again = stopped_and_resumed(case, 0.03)
    a, b = whole.engine.state, again.engine.state
    assert np.abs(a.image).sum() > 0, "no particle crossed a side"
    for name in ("position", "velocity", "omega", "image", "ids"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name
    from fluidem.io.snapshots import read_snapshot

    snap = read_snapshot(tmp_path / "run", -1)
    assert "image" in snap and snap["image"].shape == (120, 3)
    assert snap["period"].tolist() == [6 * D, 6 * D, 0.0]
    by_id = np.argsort(a.ids)
    assert np.array_equal(snap["position"] + snap["image"] * snap["period"],
                          (a.position + a.image * whole.engine.period)[by_id])


def test_state_restored_into_a_new_engine_continues_bit_for_bit(tmp_path):
    """Engine level: checkpoint_arrays/restore of a periodic engine, including the image counts."""
    rng = np.random.default_rng(9)
    n = 60
    pos = np.column_stack([(np.arange(n) % 5 + 0.5) * 2.4 * D, (np.arange(n) // 5 % 5 + 0.5) * 2.4 * D,
                           (np.arange(n) // 25 + 0.5) * 2.4 * D])
    vel = rng.normal(0.0, 0.8, (n, 3))
    one = engine(tmp_path, pos, vel, ["x", "y", "z"])
    one.advance(700)
    arrays = {k: v.copy() for k, v in one.checkpoint_arrays().items()}
    scalars = dict(one.checkpoint_scalars())
    two = engine(tmp_path, pos, vel, ["x", "y", "z"], name="q.csv")
    two.restore(arrays, scalars)
    one.advance(900)
    two.advance(900)
    assert np.abs(one.state.image).sum() > 0
    for name in ("position", "velocity", "omega", "image"):
        assert np.array_equal(getattr(one.state, name), getattr(two.state, name)), name
    assert isinstance(two.state, ParticleState)
