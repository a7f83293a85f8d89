"""Free rigid bodies (``motion.kind = 'free'``): the case keys and their errors, the default inertia of a closed
mesh (a uniform solid box: I = M (b² + c²)/12, Gere & Timoshenko tables), and the rotation kernel against the
exact rotation of a body spinning about a principal axis."""
from __future__ import annotations

import math

import numpy as np
import pytest
from _helpers.bodies import write_cube_stl

from fluidem.case import validate_case
from fluidem.errors import CaseError
from fluidem.particles import _shape_kernels as S
from fluidem.particles.shapes import build_shapes
from fluidem.particles.softsphere_gpu import gpu_refusals

PLATE = [[0, 0, 0], [0.1, 0, 0], [0.1, 0.1, 0], [0, 0.1, 0]]


def _case(walls, dimensions=3, model="linear_spring_dashpot"):
    contact = ({"model": model, "restitution": 0.9} if model == "hard_sphere" else
               {"model": model, "stiffness": 1e3, "restitution": 0.9, "friction": 0.3})
    return {
        "particles": {"dimensions": dimensions,
                      "species": [{"name": "p", "diameter": 4e-3, "density": 2500.0, "count": 1}],
                      "contact": contact,
                      "placement": {"region_lower": [0, 0, 0], "region_upper": [0.1, 0.1, 0.1]}},
        "walls": walls,
        "time": {"end": 1.0},
    }


def _plate(**motion):
    return {"name": "plate", "kind": "polygon", "points": PLATE, "motion": {"kind": "free", **motion}}


def test_a_free_plate_is_read_with_its_keys():
    case = validate_case(_case([_plate(mass=0.2, inertia=[1e-4, 2e-4, 3e-4], velocity=[0.1, 0, 0],
                                       angular_velocity=[0, 0, 2.0], fixed_axes=["y"])]))
    m = case.walls[0].motion
    assert m.mass == 0.2 and m.angular_velocity == (0.0, 0.0, 2.0) and m.fixed_axes == ["y"]
    sh = build_shapes(case).shapes[0]
    assert sh.centre == pytest.approx([0.05, 0.05, 0.0])  # the centroid of the corners by default
    assert sh.body["free"].tolist() == [1.0, 0.0, 1.0]
    assert np.array_equal(sh.body["inertia"], np.diag([1e-4, 2e-4, 3e-4]))


@pytest.mark.parametrize("motion, match", [
    ({}, "needs mass"),
    ({"mass": 0.0}, "mass"),
    ({"mass": -1.0}, "mass"),
    ({"mass": 1.0, "inertia": [1.0, 2.0]}, r"motion.inertia = \[1.0, 2.0\]: give three principal moments"),
    ({"mass": 1.0, "inertia": [1.0, -2.0, 1.0]}, "must be positive definite"),
    ({"mass": 1.0, "inertia": [[1, 0.1, 0], [0, 1, 0], [0, 0, 1]]}, "not symmetric"),
    ({"mass": 1.0, "inertia": [[1, 2, 0], [2, 1, 0], [0, 0, 1]]}, "must be positive definite"),
    ({"mass": 1.0, "inertia": [[1, 0, 0], [0, 1, 0]]}, "3 rows of 3 numbers"),
    ({"mass": 1.0, "angular_velocity": 2.0}, "angular velocity as a vector"),
    ({"mass": 1.0, "fixed_rotation": True, "angular_velocity": [0, 0, 1.0]}, "starts at rest"),
    ({"mass": 1.0, "fixed_axes": ["x", "x"]}, "names an axis twice"),
    ({"mass": 1.0, "axis": [0, 0, 1]}, r"motion.axis is not a key of a free body"),
])
def test_bad_free_body_keys_are_schema_errors(motion, match):
    with pytest.raises(CaseError, match=match):
        validate_case(_case([_plate(**motion)]))


def test_free_body_keys_belong_to_free_bodies():
    wall = {"name": "plate", "kind": "polygon", "points": PLATE,
            "motion": {"kind": "constant_velocity", "velocity": [0, 0, 1], "mass": 1.0}}
    with pytest.raises(CaseError, match=r"motion.mass is a key of a free body"):
        validate_case(_case([wall]))
    wall["motion"] = {"kind": "rotation", "axis_point": [0, 0, 0], "axis": [0, 0, 1], "angular_velocity": [0, 0, 1]}
    with pytest.raises(CaseError, match="takes a rate"):
        validate_case(_case([wall]))
    plane = {"name": "floor", "kind": "plane", "point": [0, 0, 0], "normal": [0, 0, 1],
             "motion": {"kind": "free", "mass": 1.0}}
    with pytest.raises(CaseError, match="moves shapes only"):
        validate_case(_case([plane]))


@pytest.mark.parametrize("wall, dimensions, match", [
    (_plate(mass=1.0), 3, r"walls.0 \('plate'\).motion.inertia: a free polygon needs its inertia"),
    (_plate(mass=1.0, inertia=[1, 1, 1], fixed_axes=["z"], velocity=[0, 0, 0.5]), 3,
     r"motion.velocity = \[0.0, 0.0, 0.5\]: the velocity along the fixed axis z"),
    ({"name": "l", "kind": "polyline", "points": [[0, 0], [0.1, 0]],
      "motion": {"kind": "free", "mass": 1.0}}, 2, r"walls.0 \('l'\).motion.inertia: a free polyline needs"),
    ({"name": "l", "kind": "polyline", "points": [[0, 0], [0.1, 0]],
      "motion": {"kind": "free", "mass": 1.0, "inertia": [[1, 0, 0.1], [0, 1, 0], [0.1, 0, 1]]}}, 2,
     "in 2D z must be a principal axis"),
    ({"name": "l", "kind": "polyline", "points": [[0, 0], [0.1, 0]],
      "motion": {"kind": "free", "mass": 1.0, "fixed_rotation": True, "velocity": [0, 0, 1]}}, 2,
     "in 2D a free body moves in the x-y plane"),
    ({"name": "l", "kind": "polyline", "points": [[0, 0], [0.1, 0]],
      "motion": {"kind": "free", "mass": 1.0, "inertia": [1, 1, 1], "angular_velocity": [1, 0, 0]}}, 2,
     "in 2D a free body turns about z only"),
])
def test_free_bodies_without_what_they_need_are_refused_by_name(wall, dimensions, match):
    with pytest.raises(CaseError, match=match):
        build_shapes(validate_case(_case([wall], dimensions=dimensions)))


def test_an_open_mesh_has_no_default_inertia(tmp_path):
    from stl import mesh

    m = mesh.Mesh(np.zeros(1, dtype=mesh.Mesh.dtype))
    m.vectors[0] = [[0, 0, 0], [0.1, 0, 0], [0, 0.1, 0]]
    m.save(str(tmp_path / "tri.stl"))
    wall = {"name": "m", "kind": "mesh", "file": str(tmp_path / "tri.stl"), "motion": {"kind": "free", "mass": 1.0}}
    with pytest.raises(CaseError, match=r"walls.0 \('m'\).motion.inertia: not given, and the mesh .* is not closed"):
        build_shapes(validate_case(_case([wall])))


def test_free_bodies_need_the_soft_sphere_cpu_engine():
    with pytest.raises(CaseError, match=r"walls.0.motion.kind = 'free': free bodies move with the soft-sphere"):
        validate_case(_case([_plate(mass=1.0, fixed_rotation=True)], model="hard_sphere"))
    refusals = gpu_refusals(validate_case(_case([_plate(mass=1.0, fixed_rotation=True)])))
    assert any("free bodies walls.0 ('plate') motion.kind = 'free'" in r for r in refusals)


def test_closed_mesh_default_inertia_is_that_of_a_uniform_box(tmp_path):
    """A box a × b × c of mass M: centre of mass at its centre, I_xx = M (b² + c²)/12 and so on, no products."""
    # corners as the STL file stores them (float32)
    lo = np.array([0.01, 0.02, 0.03], np.float32).astype(float)
    hi = np.array([0.05, 0.04, 0.09], np.float32).astype(float)
    write_cube_stl(tmp_path / "box.stl", lo, hi)
    wall = {"name": "box", "kind": "mesh", "file": str(tmp_path / "box.stl"), "motion": {"kind": "free", "mass": 0.3}}
    sh = build_shapes(validate_case(_case([wall]))).shapes[0]
    a, b, c = hi - lo
    assert sh.centre == pytest.approx(0.5 * (lo + hi), rel=1e-13)
    want = 0.3 / 12.0 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])
    assert np.abs(sh.body["inertia"] - want).max() < 1e-13 * want.max()
    # the same with the faces turned inwards (a solid all the same)
    from stl import mesh

    m = mesh.Mesh.from_file(str(tmp_path / "box.stl"))
    m.vectors[:] = m.vectors[:, ::-1]
    m.save(str(tmp_path / "inward.stl"))
    wall["file"] = str(tmp_path / "inward.stl")
    sh = build_shapes(validate_case(_case([wall]))).shapes[0]
    assert np.abs(sh.body["inertia"] - want).max() < 1e-13 * want.max()
    # a centre of mass given: the uniform box's inertia about that point (parallel axes)
    wall["motion"]["centre_of_mass"] = list(0.5 * (lo + hi) + [0.0, 0.0, 0.01])
    sh = build_shapes(validate_case(_case([wall]))).shapes[0]
    assert sh.body["inertia"][0, 0] == pytest.approx(want[0, 0] + 0.3 * 0.01**2, rel=1e-12)


def _spinning_row(moments, axes, omega_body):
    """A free body's motion row (no gravity, no forces) turning at ``omega_body`` (body frame) at rest."""
    from fluidem.particles.shapes import _body_row

    tensor = axes @ np.diag(moments) @ axes.T
    body = {"inertia": tensor, "velocity": np.zeros(3), "angular_velocity": np.asarray(omega_body, float),
            "free": np.ones(3), "rotates": True, "mass": 1.0}
    motion = np.zeros((1, S.MOTION_COLS + S.BODY_COLS))
    motion[0, 0] = S.FREE
    motion[0, S.MOTION_COLS:] = _body_row(body, (0.0, 0.0, 0.0), False)
    return motion


def test_spin_about_a_principal_axis_is_the_exact_rotation():
    """Spinning at ω about a principal axis u (a tilted one) the body turns by ω t about u: q = (cos ωt/2,
    sin ωt/2 u); the splitting is exact for it (the other sub-flows are the identity)."""
    axes = np.linalg.qr(np.array([[1.0, 0.3, 0.2], [0.1, 1.0, -0.4], [0.2, 0.5, 1.0]]))[0]
    if np.linalg.det(axes) < 0:
        axes[:, 0] *= -1
    u = axes[:, 1]
    w, dt, n = 7.0, 1e-3, 2000
    motion = _spinning_row([1.0, 2.0, 3.0], axes, w * u)
    for _ in range(n):
        S.body_drift(motion, 0, dt)
    q = motion[0, S.MOTION_COLS + S.BODY_Q:S.MOTION_COLS + S.BODY_Q + 4]
    th = w * n * dt
    want = np.concatenate([[math.cos(th / 2)], math.sin(th / 2) * u])
    if np.dot(q, want) < 0:
        want = -want
    assert np.abs(q - want).max() < 1e-12  # round-off of 2000 quaternion products
    P = np.empty((1, S.POSE_COLS))
    S.pose(motion, 0.0, P)
    # the angular velocity stays w u: round-off of the n sub-rotations of π, about 1e-15 ω each
    assert P[0, 15:18] == pytest.approx(w * u, abs=n * 1e-15 * w)
