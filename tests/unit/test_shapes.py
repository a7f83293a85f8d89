"""Wall shapes: closest points of spheres on triangles, segments and cylinders against independent reference
computations, the rigid-motion pose against SciPy's rotations, and the case keys' checks."""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from fluidem.case import validate_case
from fluidem.errors import CaseError
from fluidem.particles import _shape_kernels as S
from fluidem.particles.shapes import build_shapes
from fluidem.particles.softsphere_gpu import gpu_refusals


def _segment_closest(p, a, b):
    ab = b - a
    s = np.clip(np.dot(p - a, ab) / np.dot(ab, ab), 0.0, 1.0)
    return a + s * ab, s


def _reference_triangle(p, tri):
    """Closest point by projection onto the plane when the foot lies inside (barycentric test), else the
    nearest of the three edges' closest points: a different route from the kernel's Voronoi-region walk."""
    a, b, c = tri
    n = np.cross(b - a, c - a)
    n /= np.linalg.norm(n)
    foot = p - np.dot(p - a, n) * n
    # barycentric coordinates of the foot
    v0, v1, v2 = b - a, c - a, foot - a
    d00, d01, d11 = v0 @ v0, v0 @ v1, v1 @ v1
    d20, d21 = v2 @ v0, v2 @ v1
    den = d00 * d11 - d01 * d01
    v = (d11 * d20 - d01 * d21) / den
    w = (d00 * d21 - d01 * d20) / den
    if v > 0 and w > 0 and v + w < 1:
        return foot, S.FACE
    best, feat = None, None
    for e0, e1 in ((a, b), (b, c), (c, a)):
        q, s = _segment_closest(p, e0, e1)
        if best is None or np.linalg.norm(p - q) < np.linalg.norm(p - best):
            best, feat = q, (S.EDGE if 0.0 < s < 1.0 else S.VERTEX)
    return best, feat


def test_triangle_closest_point_matches_reference_in_every_region():
    rng = np.random.default_rng(7)
    seen = set()
    for _ in range(2000):
        tri = rng.normal(size=(3, 3))
        if np.linalg.norm(np.cross(tri[1] - tri[0], tri[2] - tri[0])) < 0.1:
            continue
        p = rng.normal(size=3) * 2.0
        geom = tri.reshape(1, 9).copy()
        qx, qy, qz, feat = S.closest_on_triangle(p[0], p[1], p[2], geom, 0)
        ref, ref_feat = _reference_triangle(p, tri)
        # distances to 1e-12 of the scale (round-off of a few products of O(1) numbers)
        assert abs(np.linalg.norm(p - [qx, qy, qz]) - np.linalg.norm(p - ref)) < 1e-12
        assert np.allclose([qx, qy, qz], ref, atol=1e-10)
        assert feat == ref_feat
        seen.add(feat)
    assert seen == {S.FACE, S.EDGE, S.VERTEX}


def test_triangle_distance_is_the_minimum_over_the_surface():
    """Brute force: no point of a fine barycentric sampling of the triangle is nearer than the kernel's."""
    rng = np.random.default_rng(3)
    u, v = np.meshgrid(np.linspace(0, 1, 201), np.linspace(0, 1, 201))
    keep = u + v <= 1.0
    u, v = u[keep], v[keep]
    for _ in range(50):
        tri = rng.normal(size=(3, 3))
        pts = tri[0] + u[:, None] * (tri[1] - tri[0]) + v[:, None] * (tri[2] - tri[0])
        p = rng.normal(size=3) * 2.0
        d = S.element_distance(S.TRIANGLE, p[0], p[1], p[2], tri.reshape(1, 9).copy(), 0)
        brute = np.linalg.norm(pts - p, axis=1).min()
        assert d <= brute + 1e-12
        assert brute - d < 0.02 * np.ptp(tri, axis=0).max()  # the sampling's spacing bounds the gap


def test_segment_closest_point_is_taken_in_the_plane_at_the_particle_z():
    geom = np.array([[0.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0, 0, 0]])
    assert S.closest_on_segment(1.0, 0.0, 0.3, geom, 0) == pytest.approx((0.5, 0.5, 0.3, S.FACE))
    assert S.closest_on_segment(-1.0, -0.5, 0.3, geom, 0) == pytest.approx((0.0, 0.0, 0.3, S.VERTEX))
    assert S.closest_on_segment(3.0, 2.0, 0.0, geom, 0) == pytest.approx((1.0, 1.0, 0.0, S.VERTEX))


@pytest.mark.parametrize("side", [1.0, -1.0])
def test_cylinder_gap_and_normal(side):
    """Gap R − ρ inside (normal to the axis), ρ − R outside (normal away from it); at a rim the distance
    to the rim circle."""
    R, L = 0.1, 0.2
    geom = np.array([[0.0, 0.0, 0.0, 0.0, 1.0, 0.0, R, L, side]])  # axis along y from the origin
    p = (0.03, 0.05, -0.04)  # ρ = 0.05
    q = S.closest_on_cylinder(*p, geom, 0)
    n0, n1, n2, gap = S.face_side(S.CYLINDER, *p, *q[:3], geom, 0)
    rho = math.hypot(p[0], p[2])
    assert gap == pytest.approx(side * (R - rho), rel=1e-12)
    radial = np.array([p[0], 0.0, p[2]]) / rho
    assert np.allclose([n0, n1, n2], -side * radial, atol=1e-12)
    assert q[3] == S.FACE
    # beyond the end y = L: the rim is the nearest point
    p = (0.0, L + 0.03, 0.06)
    q = S.closest_on_cylinder(*p, geom, 0)
    assert q[3] == S.EDGE
    assert np.allclose(q[:3], (0.0, L, R), atol=1e-12)
    assert S.element_distance(S.CYLINDER, *p, geom, 0) == pytest.approx(math.hypot(0.03, R - 0.06), rel=1e-12)


def test_rotation_pose_matches_scipy():
    motion = np.zeros((1, 16))
    motion[0, 0] = S.ROTATION
    c = np.array([0.1, -0.2, 0.3])
    u = np.array([1.0, 2.0, 2.0]) / 3.0
    motion[0, 6:9] = c
    motion[0, 9:12] = u
    motion[0, 12] = 2.5  # rad/s
    t = 0.7
    P = np.empty((1, S.POSE_COLS))
    S.pose(motion, t, P)
    R = Rotation.from_rotvec(u * 2.5 * t).as_matrix()
    assert np.allclose(P[0, 3:12].reshape(3, 3), R, atol=1e-14)
    x_b = np.array([0.4, 0.5, -0.6])
    x_w = c + R @ (x_b - c)
    assert np.allclose(S.to_world(P, 0, *x_b), x_w, atol=1e-14)
    assert np.allclose(S.to_body(P, 0, *x_w), x_b, atol=1e-14)
    assert np.allclose(P[0, 15:18], 2.5 * u)


def test_oscillation_pose_is_that_of_planes():
    motion = np.zeros((1, 16))
    motion[0, 0] = S.OSCILLATING
    motion[0, 1:4] = (0.0, 0.0, 1e-3)
    motion[0, 4] = 20.0
    motion[0, 5] = 0.3
    P = np.empty((1, S.POSE_COLS))
    t = 0.013
    S.pose(motion, t, P)
    om = 2 * math.pi * 20.0
    assert P[0, 2] == pytest.approx(1e-3 * math.sin(om * t + 0.3), rel=1e-14)
    assert P[0, 14] == pytest.approx(1e-3 * om * math.cos(om * t + 0.3), rel=1e-14)


# ---------------------------------------------------------------- case keys
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


QUAD = {"name": "q", "kind": "polygon", "points": [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]}


def test_polygon_is_split_into_a_fan_of_triangles():
    shapes = build_shapes(validate_case(_case([QUAD])))
    assert shapes.names == ["q"]
    assert shapes.shapes[0].kind.tolist() == [S.TRIANGLE, S.TRIANGLE]


@pytest.mark.parametrize("wall, match", [
    ({"name": "q", "kind": "polygon", "points": [[0, 0, 0], [1, 0, 0], [1, 1, 0.1], [0, 1, 0]]}, "off the plane"),
    ({"name": "q", "kind": "polygon", "points": [[0, 0, 0], [1, 0, 0], [0.2, 0.2, 0], [0, 1, 0]]}, "not convex"),
    ({"name": "m", "kind": "mesh", "file": "/nonexistent/box.stl"}, "no such file"),
    ({"name": "l", "kind": "polyline", "points": [[0, 0], [1, 0]]}, "2D wall"),
])
def test_bad_shapes_are_refused_by_name(wall, match):
    with pytest.raises(CaseError, match=match) as err:
        build_shapes(validate_case(_case([wall])))
    assert "walls.0" in str(err.value)


@pytest.mark.parametrize("wall, match", [
    ({"name": "l", "kind": "polyline", "points": [[0, 0, 0], [1, 0, 0]]}, "has 3 coordinates"),
    ({"name": "c", "kind": "cylinder", "point": [0, 0, 0], "radius": 0.1, "length": 0.1}, "needs point, axis"),
    ({"name": "p", "kind": "plane", "point": [0, 0, 0], "normal": [0, 0, 1],
      "motion": {"kind": "rotation", "axis_point": [0, 0, 0], "axis": [0, 0, 1], "angular_velocity": 1.0}},
     "moves shapes only"),
    ({"name": "c", "kind": "cylinder", "point": [0, 0, 0], "axis": [0, 0, 1], "radius": 0.1, "length": 0.1,
      "motion": {"kind": "rotation", "axis_point": [0, 0, 0], "axis": [0, 0, 0], "angular_velocity": 1.0}},
     "must not be zero"),
])
def test_bad_shape_keys_are_schema_errors(wall, match):
    with pytest.raises(CaseError, match=match):
        validate_case(_case([wall], dimensions=2 if wall["kind"] == "polyline" else 3))


def test_shapes_need_soft_spheres_and_the_cpu():
    with pytest.raises(CaseError, match="wall shapes take soft-sphere"):
        validate_case(_case([QUAD], model="hard_sphere"))
    refusals = gpu_refusals(validate_case(_case([QUAD])))
    assert any("walls.0 ('q') kind = 'polygon'" in r for r in refusals)


def _flat_grid(n, size=1.0):
    """A square [0, size]² at z = 0 split into n × n squares of two triangles each: (E, 9) geometry."""
    s = np.linspace(0.0, size, n + 1)
    tris = []
    for i in range(n):
        for j in range(n):
            q0, q1, q2, q3 = ((s[i], s[j], 0), (s[i + 1], s[j], 0), (s[i + 1], s[j + 1], 0), (s[i], s[j + 1], 0))
            tris += [q0 + q1 + q2, q0 + q2 + q3]
    return np.array(tris, float)


def test_a_sphere_on_a_finely_meshed_plane_has_the_plane_contact_only():
    """Anywhere over a plane of 200 triangles (on faces, edges, vertices, diagonals), a sphere touching it
    has exactly one contact, with the plane's normal and overlap: no edge contact of a neighbour."""
    geom = _flat_grid(10, 0.01)  # squares of 1 mm, sphere radius 2 mm: up to ~30 triangles within reach
    ne = len(geom)
    kind = np.full(ne, S.TRIANGLE, np.int64)
    owner = np.zeros(ne, np.int64)
    P = np.zeros((1, S.POSE_COLS))
    P[0, 3] = P[0, 7] = P[0, 11] = 1.0
    rng = np.random.default_rng(11)
    pos = np.column_stack([rng.uniform(0.003, 0.007, 400), rng.uniform(0.003, 0.007, 400),
                           rng.uniform(0.0015, 0.00199, 400)])
    pos[:50, :2] = np.round(pos[:50, :2], 3)  # on vertices
    pos[50:100, 0] = np.round(pos[50:100, 0], 3)  # on edges
    pos[100:150, 1] = pos[100:150, 0] - np.floor(pos[100:150, 0] * 1e3) * 1e-3 + np.floor(pos[100:150, 1] * 1e3) * 1e-3
    radius = np.full(len(pos), 0.002)
    near_count = np.full(len(pos), ne, np.int64)
    near_elem = np.tile(np.arange(ne), (len(pos), 1))
    cand_e = np.empty(S.MAX_CANDIDATES, np.int64)
    cand_f = np.empty((S.MAX_CANDIDATES, 8))
    keep = np.empty(S.MAX_CANDIDATES, np.bool_)
    for i in range(len(pos)):
        m = S.particle_contacts(i, pos, radius, kind, owner, geom, P, near_count, near_elem, cand_e, cand_f, keep)
        assert m == 1, (i, pos[i], cand_e[:m], cand_f[:m])
        assert np.allclose(cand_f[0, 3:6], (0.0, 0.0, 1.0), atol=1e-12)
        assert cand_f[0, 6] == pytest.approx(0.002 - pos[i, 2], rel=1e-9)


def test_a_sphere_beyond_a_convex_edge_or_vertex_has_one_contact():
    """A box corner from outside: two faces meet at an edge, three at a vertex; a sphere beyond them touches
    the edge (vertex) once, along the direction from that point to its centre."""
    # the corner of the unit cube at the origin, the three faces as two triangles each, seen from outside
    faces = [((0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)), ((0, 0, 0), (0, 1, 0), (0, 1, 1), (0, 0, 1)),
             ((0, 0, 0), (0, 0, 1), (1, 0, 1), (1, 0, 0))]
    geom = np.array([a + b + c for f in faces for a, b, c in ((f[0], f[1], f[2]), (f[0], f[2], f[3]))], float)
    kind = np.full(len(geom), S.TRIANGLE, np.int64)
    owner = np.zeros(len(geom), np.int64)
    P = np.zeros((1, S.POSE_COLS))
    P[0, 3] = P[0, 7] = P[0, 11] = 1.0
    near_count = np.array([len(geom)], np.int64)
    near_elem = np.arange(len(geom)).reshape(1, -1)
    cand_e = np.empty(S.MAX_CANDIDATES, np.int64)
    cand_f = np.empty((S.MAX_CANDIDATES, 8))
    keep = np.empty(S.MAX_CANDIDATES, np.bool_)
    for pos, point in (([-0.1, -0.1, -0.1], (0, 0, 0)), ([0.5, -0.1, -0.1], (0.5, 0, 0))):
        pos = np.array([pos])
        m = S.particle_contacts(0, pos, np.array([0.2]), kind, owner, geom, P, near_count, near_elem, cand_e,
                                cand_f, keep)
        assert m == 1
        assert np.allclose(cand_f[0, :3], point, atol=1e-12)
        d = np.linalg.norm(pos[0] - point)
        assert cand_f[0, 6] == pytest.approx(0.2 - d, rel=1e-12)


def test_table_pose_is_interpolated_linearly_and_held_at_the_ends():
    rows = np.array([[0.0, 0.0, 0.0, 0.0, 0.0], [1.0, 0.1, 0.0, -0.2, 0.5], [3.0, 0.3, 0.2, -0.2, -0.5]])
    motion = np.zeros((1, S.MOTION_COLS + rows.size))
    motion[0, 0] = S.TABLE
    motion[0, 9:12] = (0.0, 0.0, 1.0)
    motion[0, 13] = len(rows)
    motion[0, S.MOTION_COLS:] = rows.ravel()
    P = np.empty((1, S.POSE_COLS))
    S.pose(motion, 2.0, P)  # half-way between rows 1 and 2
    assert P[0, 0:3] == pytest.approx([0.2, 0.1, -0.2], abs=1e-15)
    assert P[0, 12:15] == pytest.approx([0.1, 0.1, 0.0], abs=1e-15)  # (row 2 − row 1) / 2 s
    assert P[0, 21] == pytest.approx(0.0, abs=1e-15)
    assert P[0, 15:18] == pytest.approx([0.0, 0.0, -0.5], abs=1e-15)  # dθ/dt about z
    S.pose(motion, 0.25, P)
    assert np.allclose(P[0, 3:12].reshape(3, 3), Rotation.from_rotvec([0, 0, 0.125]).as_matrix(), atol=1e-15)
    S.pose(motion, 5.0, P)  # after the last row: held there, at rest
    assert P[0, 0:3] == pytest.approx([0.3, 0.2, -0.2], abs=1e-15)
    assert np.all(P[0, 12:18] == 0.0)
    S.pose(motion, -1.0, P)
    assert np.all(P[0, 0:3] == 0.0) and np.all(P[0, 12:18] == 0.0)


def test_table_file_errors_name_the_key(tmp_path):
    bad = tmp_path / "poses.csv"
    bad.write_text("t,dx,dy,dz,angle\n0,0,0,0,0\n1,0,0,0.1,0\n0.5,0,0,0.2,0\n")
    wall = {**QUAD, "motion": {"kind": "table", "file": str(bad)}}
    with pytest.raises(CaseError, match=r"walls.0 \('q'\).motion.file = .*t must increase.*row 3"):
        build_shapes(validate_case(_case([wall])))
    bad.write_text("t,dx,dy,dz\n0,0,0,0\n")
    with pytest.raises(CaseError, match="no column angle"):
        build_shapes(validate_case(_case([wall])))
    bad.write_text("t,dx,dy,dz,angle\n0,0,0,0,0\n1,0,0,0,0.3\n")
    with pytest.raises(CaseError, match="needs axis_point and axis"):
        build_shapes(validate_case(_case([wall])))
