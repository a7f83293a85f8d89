"""Walls checked per particle only when reachable before the next list rebuild (``near_walls``).

The DEM step checks each particle against the walls it can reach before the Verlet list is
rebuilt (a static wall within a + skin of its place at the last rebuild, in 2D a + skin |n_xy|;
a moving wall always). These tests hold the rule itself and its consequences: a particle
arriving from far away, or hit by a moving wall, still meets the wall at the right speed.
"""
import math

import numpy as np
import pytest

from fluidem.case import validate_case
from fluidem.particles import _softsphere_kernels as K
from fluidem.particles.softsphere import SoftSphereEngine

A, SKIN = 0.1, 0.05
# a unit box: x = 0 (normal +x), x = 1 (−x), y = 0, y = 1, z = 0, z = 1
NORMALS = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], float)
POINTS = np.array([[0, 0, 0], [1, 0, 0], [0, 0, 0], [0, 1, 0], [0, 0, 0], [0, 0, 1]], float)


def run_near(pos, motion=None, dim2=False, hist=None, radius=A):
    pos = np.asarray(pos, float)
    n = pos.shape[0]
    motion = np.zeros((6, 6)) if motion is None else motion
    hist = np.zeros((n, 6, 3)) if hist is None else hist
    touch = np.zeros((n, 6), dtype=bool)
    count, near = np.empty(n, dtype=np.int64), np.empty((n, 6), dtype=np.int64)
    K.near_walls(pos, np.full(n, radius), motion, POINTS, NORMALS, SKIN, dim2, hist, touch, count, near)
    np.testing.assert_array_equal(touch, K.touching_walls(hist))  # filled: where a spring is set
    return [list(near[i, :count[i]]) for i in range(n)], hist, touch


def test_only_walls_within_radius_plus_skin_are_listed():
    lists, _, _ = run_near([[0.5, 0.5, 0.5],                     # centre: none
                            [0.149, 0.5, 0.5],                   # gap 0.149 < a + skin = 0.15: x = 0
                            [0.151, 0.5, 0.5],                   # gap 0.151: none
                            [0.12, 0.95, 0.5],                   # x = 0 and y = 1
                            [0.05, 0.05, 0.05]])                 # overlapping three walls, ascending order
    assert lists == [[], [0], [], [0, 3], [0, 2, 4]]


def test_a_moving_wall_is_listed_for_every_particle():
    motion = np.zeros((6, 6))
    motion[3, 0] = K.OSCILLATING
    motion[3, 2], motion[3, 4] = 0.01, 50.0  # y = 1 oscillates along y
    lists, _, _ = run_near([[0.5, 0.5, 0.5], [0.12, 0.5, 0.5]], motion=motion)
    assert lists == [[3], [0, 3]]


def test_2d_front_and_back_walls_at_one_radius_are_not_listed():
    """Centres at z = a between walls at z = 0 and z = 2a never touch them (gap = a, no z motion)."""
    lists, _, _ = run_near([[0.5, 0.5, A], [0.12, 0.5, A]], dim2=True)
    assert lists == [[], [0]]
    # in 3D the same particles can move towards them
    lists3, _, _ = run_near([[0.5, 0.5, A]], dim2=False)
    assert lists3 == [[4]]
    # a bed thinner than a diameter does touch them in 2D
    lists_thin, _, _ = run_near([[0.5, 0.5, 0.9 * A]], dim2=True)
    assert lists_thin == [[4]]


def test_spring_on_an_unreachable_wall_is_reset():
    hist = np.zeros((2, 6, 3))
    hist[0, 1] = [1e-6, 0.0, 2e-6]  # particle 0 far from x = 1: its old spring there is cleared
    hist[1, 0] = [3e-6, 0.0, 0.0]   # particle 1 near x = 0: kept
    lists, hist, touch = run_near([[0.5, 0.5, 0.5], [0.12, 0.5, 0.5]], hist=hist)
    assert not hist[0].any() and not touch[0].any()
    assert hist[1, 0, 0] == 3e-6 and touch[1, 0]


def one_particle_case(position, velocity, walls, dimensions=2, tmp_path=None):
    csv = tmp_path / "p.csv"
    csv.write_text("x,y,z,diameter,vx,vy,vz\n" + ",".join(str(v) for v in (*position, 0.004, *velocity)) + "\n")
    return validate_case({
        "name": "near-walls", "gravity": [0.0, 0.0, 0.0],
        "particles": {
            "dimensions": dimensions,
            "species": [{"diameter": 0.004, "density": 2700.0, "count": 1}],
            "contact": {"model": "linear_spring_dashpot", "stiffness": 800.0, "restitution": 0.7, "friction": 0.3},
            "placement": {"method": "file", "file": str(csv)},
        },
        "walls": walls, "time": {"end": 1.0},
    })


def test_particle_from_far_away_rebounds_with_the_restitution(tmp_path):
    """Starts 20 d from the floor at 1 m/s: the floor is out of reach at first and is listed at a later
    rebuild; the rebound speed is e v within 1 % (the linear law's time-step error)."""
    walls = [{"name": "box", "kind": "box", "lower": [0, 0, 0], "upper": [0.2, 0.2, 0.004]}]
    eng = SoftSphereEngine(one_particle_case((0.1, 0.08, 0.002), (0.0, -1.0, 0.0), walls, tmp_path=tmp_path))
    eng.advance(int(0.09 / eng.dt))  # 0.076 m of flight, then a contact of ~1 ms
    assert eng.rebuilds >= 10
    assert eng.state.velocity[0, 1] == pytest.approx(0.7, rel=0.01)


def test_a_moving_wall_from_far_away_strikes_a_resting_particle(tmp_path):
    """A piston (plane y = 0 moving up at 0.5 m/s, infinite mass) reaches a particle at rest 10 d above it:
    afterwards the particle moves at (1 + e) v_wall within 1 %."""
    walls = [{"name": "piston", "kind": "plane", "point": [0.0, 0.0, 0.0], "normal": [0.0, 1.0, 0.0],
              "motion": {"kind": "constant_velocity", "velocity": [0.0, 0.5, 0.0]}}]
    eng = SoftSphereEngine(one_particle_case((0.1, 0.042, 0.002), (0.0, 0.0, 0.0), walls, tmp_path=tmp_path))
    eng.advance(int(0.1 / eng.dt))  # the piston arrives after 0.08 s
    assert eng.state.velocity[0, 1] == pytest.approx(1.7 * 0.5, rel=0.01)
    assert math.isclose(eng.state.position[0, 0], 0.1)


@pytest.mark.parametrize("first", [[0, 150, 400], [0, 0, 400], [0, 37, 38, 400], [0, 400, 400, 400]])
def test_any_split_over_threads_gives_the_same_lists(all_threads, first):
    """The threads' particle ranges (``first``, as the engine passes them) change nothing: each particle's rows are
    its own. Random particles near and far from the walls, springs set on some walls (reset where out of reach)."""
    rng = np.random.default_rng(4)
    n = 400
    pos = rng.uniform(0.0, 1.0, (n, 3))
    hist = np.where(rng.uniform(size=(n, 6, 1)) < 0.3, rng.normal(0.0, 1e-6, (n, 6, 3)), 0.0)
    outs = []
    for split in (None, np.array(first)):
        h = hist.copy()
        touch = np.zeros((n, 6), dtype=bool)
        count, near = np.full(n, -1, dtype=np.int64), np.full((n, 6), -1, dtype=np.int64)
        K.near_walls(pos, np.full(n, A), np.zeros((6, 6)), POINTS, NORMALS, SKIN, False, h, touch, count, near, split)
        outs.append((h, touch, count, [list(near[i, :count[i]]) for i in range(n)]))
    serial, split = outs
    assert 0 < sum(len(r) for r in serial[3]) < 6 * n
    for a, b in zip(serial[:3], split[:3]):
        np.testing.assert_array_equal(a, b)
    assert serial[3] == split[3]
