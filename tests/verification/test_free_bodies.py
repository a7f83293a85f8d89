"""Free rigid bodies (``motion.kind = 'free'``) in the soft-sphere engine, against analytic motion and the
conservation laws:

* a plate in free fall, no contacts: x = x0 + v0 t + g t²/2 and v = v0 + g t to round-off (velocity Verlet is
  exact for a constant force);
* a torque-free asymmetric top started near its intermediate axis (it tumbles): its angular momentum L is
  kept to round-off (each sub-step of the splitting is an exact rotation) and its energy ½ ω·L to
  O((ω dt)²) (Miller et al. 2002: the splitting is symplectic, its energy error bounded);
* a closed-mesh cube resting on a layer of particles settles and is held by them: the sum of the contact
  forces on it equals its weight M g within 1 %;
* particles inside a closed-mesh box without gravity: the momentum of particles plus box is conserved to
  round-off while they collide with its faces;
* a run stopped and resumed from its checkpoint continues bit for bit, and shapes.csv carries the body's
  state.
"""
from __future__ import annotations

import csv
import math

import numpy as np
import pytest
from _helpers.bodies import write_cube_stl

G = 9.81
D = 4e-3  # [m]
RHO = 2500.0  # [kg/m^3]
M_P = RHO * math.pi * D**3 / 6.0  # particle mass [kg]
PLATE = [[-0.05, -0.05, 0.0], [0.05, -0.05, 0.0], [0.05, 0.05, 0.0], [-0.05, 0.05, 0.0]]
LAW = {"model": "linear_spring_dashpot", "stiffness": 1e3, "restitution": 0.5, "friction": 0.3}


def _plate(**motion):
    return {"name": "plate", "kind": "polygon", "points": PLATE, "motion": {"kind": "free", **motion}}


def test_free_fall_is_g_t2_over_2(make_engine):
    v0 = np.array([0.1, -0.2, 0.5])
    eng = make_engine((1.0, 1.0, 1.0), D, contact=LAW, dt=1e-5, gravity=(0, 0, -G),
                      walls=[_plate(mass=0.1, inertia=[1e-4, 2e-4, 3e-4], velocity=list(v0),
                                    angular_velocity=[1.0, 2.0, 3.0])])
    sh = eng.shapes
    for _ in range(4):
        eng.advance(2500)  # in calls of 2500 steps: the same as one call (fused kicks)
    t = eng.time
    b = sh.body_state(0)
    g = np.array([0.0, 0.0, -G])
    # round-off: one rounding of each of the 2 n half kicks and n drifts, eps times the largest value each
    n, eps = eng.steps, np.finfo(float).eps
    assert np.abs(b["velocity"] - (v0 + g * t)).max() < 2 * n * eps * 0.5
    assert np.abs(b["position"] - (v0 * t + 0.5 * g * t * t)).max() < n * eps * 0.05
    assert np.array_equal(b["force"], 0.1 * g)  # gravity only: no contact
    # the plate never touched the particle (far away), which fell as it did
    assert eng.state.position[0, 2] == pytest.approx(1.0 - 0.5 * G * t * t, abs=n * eps)


def test_torque_free_top_keeps_angular_momentum_and_energy(make_engine):
    moments = np.array([1e-4, 2e-4, 3e-4])
    w0 = np.array([0.2, 20.0, 0.2])  # near the intermediate axis: unstable, it tumbles
    eng = make_engine((1.0, 1.0, 1.0), D, contact=LAW, dt=1e-5,
                      walls=[_plate(mass=0.1, inertia=list(moments), angular_velocity=list(w0))])
    sh = eng.shapes
    L0 = moments * w0
    E0 = 0.5 * np.dot(w0, L0)
    worst_e, worst_l, wy = 0.0, 0.0, []
    for _ in range(100):
        eng.advance(1000)  # 1 s in all: 20 rad/s, the spin about y turns over (growth rate 11.5 /s)
        b = sh.body_state(0)
        worst_l = max(worst_l, np.abs(b["angular_momentum"] - L0).max() / np.linalg.norm(L0))
        worst_e = max(worst_e, abs(0.5 * np.dot(b["angular_velocity"], b["angular_momentum"]) - E0) / E0)
        wy.append(b["angular_velocity"] @ _body_y(b["quaternion"]))
    assert min(wy) < -10.0  # it tumbled: the body-frame y component of ω changed sign
    # round-off of 1e5 steps of five rotations each, eps (2.2e-16) per step at worst: 2.2e-11 (measured 1.1e-13)
    assert worst_l < 1e5 * np.finfo(float).eps
    # bounded energy error of the splitting, of order (ω dt)² = 4e-8 (measured 2.8e-10)
    assert worst_e < (20.0 * eng.dt) ** 2


def _body_y(q):
    """The body's y axis in the world (second column of the rotation of q = (w, x, y, z))."""
    w, x, y, z = q
    return np.array([2 * (x * y - w * z), 1 - 2 * (x * x + z * z), 2 * (y * z + w * x)])


def _bed_case(make_case, tmp_path, mass, end=1.0):
    """A 3 x 3 layer of particles on the floor of a box, and a closed-mesh cube (side 2.8 d) above them."""
    gap = 1.01 * D
    xy = [(0.5 * D + 0.005 * D + i * gap, 0.5 * D + 0.005 * D + j * gap) for i in range(3) for j in range(3)]
    pos = [(x, y, 0.5 * D + 1e-6) for x, y in xy]
    side = 3 * gap + 0.01 * D
    c = 0.5 * D + 0.005 * D + gap  # over the middle particle: the layer stays symmetric (spheres roll freely)
    cube = write_cube_stl(tmp_path / "cube.stl", (c - 1.4 * D, c - 1.4 * D, 1.2 * D), (c + 1.4 * D, c + 1.4 * D, 4.0 * D))
    walls = [{"name": "box", "kind": "box", "lower": [0, 0, 0], "upper": [side, side, 10 * D]},
             {"name": "cube", "kind": "mesh", "file": str(cube), "motion": {"kind": "free", "mass": mass}}]
    return make_case(pos, D, contact=LAW, walls=walls, gravity=(0, 0, -G), end=end)


def test_a_cube_on_a_particle_layer_is_held_by_its_weight(make_case, tmp_path):
    from fluidem.particles.softsphere import SoftSphereEngine

    M = 5.0 * M_P
    eng = SoftSphereEngine(_bed_case(make_case, tmp_path, M))
    eng.advance(int(0.3 / eng.dt))  # 0.3 s: the cube drops 0.2 d, bounces and comes to rest
    b = eng.shapes.body_state(0)
    assert np.abs(b["velocity"]).max() < 1e-6
    # at rest: the particles carry the cube's weight, as they would a particle of its mass
    assert eng.shapes.load[0, 2] == pytest.approx(M * G, rel=0.01)
    # it lies on them: its bottom (1.2 d at rest) a little below the particles' tops (d)
    assert b["position"][2] == pytest.approx(2.6 * D - 0.2 * D, abs=0.05 * D)


def test_momentum_of_particles_and_a_closed_body_is_conserved(make_engine, tmp_path):
    rng = np.random.default_rng(3)
    box = write_cube_stl(tmp_path / "box.stl", (0.0, 0.0, 0.0), (0.02, 0.02, 0.02))
    pos = [(0.005 + 0.01 * i, 0.005 + 0.01 * j, 0.005 + 0.01 * k) for i in range(2) for j in range(2)
           for k in range(2)]
    vel = rng.normal(0.0, 0.3, (8, 3))
    M = 10.0 * M_P
    eng = make_engine(pos, D, vel, contact=LAW, walls=[{"name": "shell", "kind": "mesh", "file": str(box),
                                                        "motion": {"kind": "free", "mass": M}}])
    st, sh = eng.state, eng.shapes

    def momentum():
        return (st.mass[:, None] * st.velocity).sum(axis=0) + M * sh.body_state(0)["velocity"]

    p0 = momentum()
    scale = float(np.sum(st.mass * np.linalg.norm(st.velocity, axis=1)))
    hits = 0
    for _ in range(40):
        eng.advance(500)  # 0.2 s: each particle crosses the box several times
        hits += int(np.any(sh.load[0] != 0.0))
        assert np.abs(momentum() - p0).max() < 1e-13 * scale
    assert np.linalg.norm(sh.body_state(0)["velocity"]) > 1e-3 * scale / M  # the box was pushed about
    assert hits > 0


def test_a_body_on_a_bed_resumes_bit_for_bit(stopped_and_resumed, make_case, tmp_path):
    case = _bed_case(make_case, tmp_path, 5.0 * M_P, end=0.04)
    case = case.with_overrides({"output.probe_interval": 0.005, "output.checkpoint_interval": 0.02})
    whole, first, again = stopped_and_resumed(case, 0.02)
    for k in ("position", "velocity", "quaternion", "angular_velocity", "force", "torque"):
        assert np.array_equal(whole.engine.shapes.body_state(0)[k], again.engine.shapes.body_state(0)[k]), k
    assert np.array_equal(whole.engine.state.position, again.engine.state.position)
    assert whole.engine.shapes.body_state(0)["position"][2] < 2.6 * D  # it fell onto the layer
    with open(tmp_path / "run" / "shapes.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    last = rows[-1]
    b = again.engine.shapes.body_state(0)
    assert float(last["cube.vz_m/s"]) == pytest.approx(b["velocity"][2], rel=1e-9, abs=1e-15)
    rest = again.engine.shapes.shapes[0].centre  # its centre of mass at rest (the STL file's float32 corners)
    assert float(last["cube.dz_m"]) == pytest.approx(b["position"][2] - rest[2], rel=1e-9)
    q = [float(last[f"cube.q{c}"]) for c in "wxyz"]
    assert np.linalg.norm(q) == pytest.approx(1.0, rel=1e-9)


def test_a_2d_body_falls_and_spins_in_the_plane(make_engine):
    """In 2D a free polyline square moves in the x-y plane and turns about z only: z, v_z, ω_x and ω_y stay
    exact zeros, a spin about z stays as it is (no torque), and it falls as g t²/2."""
    square = {"name": "frame", "kind": "polyline", "points": [[-0.05, -0.05], [0.05, -0.05], [0.05, 0.05],
                                                              [-0.05, 0.05]], "closed": True,
              "motion": {"kind": "free", "mass": 0.1, "inertia": [[2e-4, 1e-5, 0], [1e-5, 3e-4, 0], [0, 0, 4e-4]],
                         "velocity": [0.2, 0.0, 0.0], "angular_velocity": [0.0, 0.0, 5.0]}}
    eng = make_engine((1.0, 1.0, 0.0), D, contact=LAW, dt=1e-5, dimensions=2, gravity=(0, -G, 0), walls=[square])
    eng.advance(10000)
    b = eng.shapes.body_state(0)
    t, n, eps = eng.time, eng.steps, np.finfo(float).eps
    assert b["position"][2] == 0.0 and b["velocity"][2] == 0.0
    assert b["angular_velocity"][0] == 0.0 and b["angular_velocity"][1] == 0.0
    assert b["angular_velocity"][2] == pytest.approx(5.0, rel=n * eps)
    assert b["position"][:2] == pytest.approx([0.2 * t, -0.5 * G * t * t], abs=n * eps * 0.1)
    # the rotation: by 5 t about z
    assert 2.0 * math.atan2(b["quaternion"][3], b["quaternion"][0]) == pytest.approx(5.0 * t, rel=n * eps)


def test_fixed_axes_and_fixed_rotation_hold(make_engine):
    """A plate with fixed_axes = ["z"] under gravity keeps its height while it slides along x; a plate with
    fixed_rotation = true struck off-centre by a particle takes its momentum but does not turn."""
    eng = make_engine((1.0, 1.0, 1.0), D, contact=LAW, dt=1e-5, gravity=(0, 0, -G),
                      walls=[_plate(mass=0.1, inertia=[1e-4, 2e-4, 3e-4], velocity=[0.3, 0.0, 0.0],
                                    fixed_axes=["z"])])
    eng.advance(5000)
    b = eng.shapes.body_state(0)
    assert b["position"][2] == 0.0 and b["velocity"][2] == 0.0 and b["force"][2] == 0.0
    assert b["position"][0] == pytest.approx(0.3 * eng.time, rel=1e-12)

    M = 10.0 * M_P
    eng = make_engine((0.03, 0.0, -0.0025), D, (0.0, 0.0, 0.5), contact=LAW, dt=1e-5,
                      walls=[_plate(mass=M, fixed_rotation=True)])
    p0 = M_P * 0.5
    eng.advance(5000)  # 0.05 s: the particle strikes the plate and flies back
    b = eng.shapes.body_state(0)
    assert np.array_equal(b["quaternion"], [1.0, 0.0, 0.0, 0.0])
    assert np.array_equal(b["angular_velocity"], [0.0, 0.0, 0.0])
    assert b["velocity"][2] > 0.0 and eng.state.velocity[0, 2] < 0.0  # the strike happened
    assert M * b["velocity"][2] + eng.state.mass[0] * eng.state.velocity[0, 2] == pytest.approx(p0, rel=1e-12)


def test_a_body_lighter_than_a_particle_is_refused(make_case):
    from fluidem.errors import CaseError
    from fluidem.particles.softsphere import SoftSphereEngine

    case = make_case((1.0, 1.0, 1.0), D, contact=LAW, walls=[_plate(mass=0.5 * M_P, fixed_rotation=True)])
    with pytest.raises(CaseError, match=r"walls.0.motion.mass = .* kg \('plate'\): a free body must be heavier"):
        SoftSphereEngine(case)
