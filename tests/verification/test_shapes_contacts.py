"""Spheres against wall shapes, checked against planes and analytic states.

* A flat square of two triangles is the plane it lies in: a sphere dropped across their shared edge follows
  the plane's trajectory to round-off (no double contact on the edge), also when the floor oscillates, and
  at rest it feels one contact of force m g.
* A sphere at rest in a horizontal cylinder of radius R sits at the bottom, its centre R − a + m g/k below
  the axis (linear spring), with the contact force m g.
* A box read from an STL file of twelve triangles gives the same trajectory as the box of six planes for a
  sphere thrown into a corner (three faces, the diagonals of each face and the box edges nearby).
* A sphere on the wall of a drum rotating at ω is carried without slip: its surface at the contact point
  moves at the wall's velocity ω R.
* A 2D hopper of segments empties through its outlet.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

G = 9.81
D = 4e-3  # [m]
RHO = 2500.0  # [kg/m^3]
MASS = RHO * math.pi * D**3 / 6.0


def _law(contact_law, **kw):
    return contact_law("linear_spring_dashpot", **{"stiffness": 1e3, "restitution": 0.5, "friction": 0.3, **kw})


SQUARE = {"name": "floor", "kind": "polygon", "points": [[-0.05, -0.05, 0], [0.05, -0.05, 0], [0.05, 0.05, 0],
                                                           [-0.05, 0.05, 0]]}
PLANE = {"name": "floor", "kind": "plane", "point": [0, 0, 0], "normal": [0, 0, 1]}
SHAKE = {"kind": "oscillation", "amplitude": [0.0, 0.0, 5e-4], "frequency": 30.0, "phase": 0.4}


@pytest.mark.parametrize("motion", [None, SHAKE], ids=["static", "oscillating"])
def test_square_of_two_triangles_is_a_plane(make_engine, contact_law, motion):
    """The square's diagonal y = x is the shared edge: the sphere starts on it and crosses it."""
    law = _law(contact_law)
    pos, vel = (0.01, 0.01, 0.0035), (0.2, -0.1, -0.3)
    extra = {} if motion is None else {"motion": motion}
    plane = make_engine(pos, D, vel, contact=law, walls=[{**PLANE, **extra}], gravity=(0, 0, -G))
    square = make_engine(pos, D, vel, contact=law, walls=[{**SQUARE, **extra}], gravity=(0, 0, -G))
    assert square.dt == plane.dt
    for _ in range(60):
        plane.advance(100)
        square.advance(100)
        # the two differ by the round-off of the closest point (1e-18 m) carried through the contacts
        for a, b, scale in ((plane.state.position, square.state.position, 0.01),
                            (plane.state.velocity, square.state.velocity, 1.0),
                            (plane.state.omega, square.state.omega, 100.0)):
            assert np.abs(a - b).max() < 1e-10 * scale


def test_sphere_resting_on_the_shared_edge_feels_one_contact(make_engine, contact_law):
    law = _law(contact_law, restitution=0.3)
    square = make_engine((0.0, 0.0, 0.00201), D, (0, 0, 0), contact=law, walls=[SQUARE], gravity=(0, 0, -G))
    square.advance(20000)  # 0.2 s: 40 contact times of damping
    sh = square.shapes
    assert abs(square.state.velocity[0]).max() < 1e-9
    assert (sh.slot_elem[0] >= 0).sum() == 1  # one contact, not one per triangle
    # the reaction on the floor is the sphere's weight (one contact: m g, not 2 m g)
    assert sh.load[0, 2] == pytest.approx(-MASS * G, rel=1e-6)
    assert sh.load[0, :2] == pytest.approx([0.0, 0.0], abs=1e-15)
    # and the overlap is that of the plane, m g / k
    assert 0.002 - square.state.position[0, 2] == pytest.approx(MASS * G / 1e3, rel=1e-6)


def test_sphere_rests_at_the_bottom_of_a_horizontal_cylinder(make_engine, contact_law):
    R, k = 0.05, 1e3
    law = _law(contact_law, restitution=0.3, stiffness=k)
    drum = {"name": "drum", "kind": "cylinder", "point": [-0.01, 0.0, 0.0], "axis": [1, 0, 0], "radius": R,
            "length": 0.02}
    eng = make_engine((0.0, 0.0, -(R - 0.0021)), D, (0, 0, 0), contact=law, walls=[drum], gravity=(0, 0, -G))
    eng.advance(30000)
    x = eng.state.position[0]
    assert abs(eng.state.velocity[0]).max() < 1e-9
    assert x[1] == pytest.approx(0.0, abs=1e-12)
    # centre R − a + δ below the axis, δ = m g / k (linear spring at rest)
    assert -x[2] == pytest.approx(R - D / 2 + MASS * G / k, rel=1e-9)
    assert eng.shapes.load[0, 2] == pytest.approx(-MASS * G, rel=1e-6)


def _write_box_stl(path, lo, hi):
    from stl import mesh

    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    c = np.array([[lo[0] if i & 1 == 0 else hi[0], lo[1] if i & 2 == 0 else hi[1], lo[2] if i & 4 == 0 else hi[2]]
                  for i in range(8)])
    quads = [(0, 1, 3, 2), (4, 5, 7, 6), (0, 1, 5, 4), (2, 3, 7, 6), (0, 2, 6, 4), (1, 3, 7, 5)]
    tris = []
    for a, b, cc, d in quads:
        tris += [(a, b, cc), (a, cc, d)]
    m = mesh.Mesh(np.zeros(len(tris), dtype=mesh.Mesh.dtype))
    for j, t in enumerate(tris):
        m.vectors[j] = c[list(t)]
    m.save(str(path))


def test_stl_box_matches_the_box_of_planes(make_engine, contact_law, tmp_path):
    law = _law(contact_law)
    lo, hi = (0.0, 0.0, 0.0), (0.03, 0.02, 0.04)
    # the STL file in millimetres, scaled and shifted back into place
    stl = tmp_path / "box.stl"
    _write_box_stl(stl, (10.0, 10.0, 10.0), (40.0, 30.0, 50.0))
    mesh_wall = {"name": "box", "kind": "mesh", "file": str(stl), "scale": 1e-3, "offset": [-0.01, -0.01, -0.01]}
    box_wall = {"name": "box", "kind": "box", "lower": list(lo), "upper": list(hi)}
    pos, vel = (0.02, 0.012, 0.01), (-0.4, 0.3, -0.5)
    planes = make_engine(pos, D, vel, contact=law, walls=[box_wall], gravity=(0, 0, -G))
    mesh = make_engine(pos, D, vel, contact=law, walls=[mesh_wall], gravity=(0, 0, -G))
    assert len(mesh.shapes.kind) == 12
    for _ in range(100):
        planes.advance(100)
        mesh.advance(100)
        for a, b, scale in ((planes.state.position, mesh.state.position, 0.01),
                            (planes.state.velocity, mesh.state.velocity, 1.0),
                            (planes.state.omega, mesh.state.omega, 100.0)):
            assert np.abs(a - b).max() < 1e-9 * scale
    # it reached the corner region: touched at least two sides on the way
    assert planes.state.position[0, 2] < 0.003


def test_sphere_on_a_rotating_drum_is_carried_without_slip(make_engine, contact_law):
    """Drum of radius R about y at ω: the sphere spins up at the bottom until its surface at the contact point
    moves with the wall, v + ω_p × (x_c − x) = ω × (x_c − c), |ω × (x_c − c)| = ω R (no-slip)."""
    R, w = 0.05, 2.0
    law = _law(contact_law, friction=0.5)
    drum = {"name": "drum", "kind": "cylinder", "point": [0.0, -0.01, 0.0], "axis": [0, 1, 0], "radius": R,
            "length": 0.02, "motion": {"kind": "rotation", "axis_point": [0, 0, 0], "axis": [0, 1, 0],
                                       "angular_velocity": w}}
    eng = make_engine((0.0, 0.0, -(R - D / 2)), D, (0, 0, 0), contact=law, walls=[drum], gravity=(0, 0, -G))
    eng.advance(int(0.1 / eng.dt))
    slips = []
    for _ in range(50):
        eng.advance(200)
        x, v, om = eng.state.position[0], eng.state.velocity[0], eng.state.omega[0]
        n = np.array([x[0], 0.0, x[2]])
        n /= np.linalg.norm(n)  # outward: from the axis to the wall through the centre
        xc = x + (D / 2) * n
        v_surface = v + np.cross(om, xc - x)
        v_wall = np.cross([0.0, w, 0.0], xc - [0.0, x[1], 0.0])
        assert np.linalg.norm(v_wall) == pytest.approx(w * R, rel=0.01)
        slips.append(np.linalg.norm(v_surface - v_wall))
    # the tangential spring's elastic give is the only difference: within 1 % of ω R
    assert max(slips) < 0.01 * w * R
    # the surface moves at ω R; at rest the sphere slipped by all of it
    assert np.mean(np.abs(eng.state.omega[0, 1])) > 0.5 * w * R / (D / 2)


def test_2d_hopper_of_segments_discharges(make_engine, contact_law):
    law = _law(contact_law, restitution=0.5, friction=0.3)
    left = {"name": "left", "kind": "polyline", "points": [[-0.03, 0.06], [-0.006, 0.0]]}
    right = {"name": "right", "kind": "polyline", "points": [[0.006, 0.0], [0.03, 0.06]]}
    xs = -0.0126 + 0.0042 * np.arange(7)
    ys = 0.03 + 0.0042 * np.arange(6)
    pos = np.array([(x, y, 0.0) for y in ys for x in xs])
    eng = make_engine(pos, D, contact=law, walls=[left, right], gravity=(0, -G, 0), dimensions=2)
    t_end, below = 0.6, []
    for _ in range(30):
        eng.advance(int(t_end / 30 / eng.dt))
        p = eng.state.position
        # no particle gets through a wall: above the outlet every centre is inside the V by at least ~a
        inside = p[:, 1] > 0.0
        half = 0.006 + 0.4 * p[inside, 1]
        assert np.all(np.abs(p[inside, 0]) < half)
        below.append(int(np.sum(p[:, 1] < -0.01)))
    assert below[0] < len(pos)  # it takes time to flow out
    assert below[-1] == len(pos)  # and it empties
    assert np.all(np.diff(below) >= 0)


def test_a_table_of_poses_moves_a_drum_as_its_rotation_does(make_engine, contact_law, tmp_path):
    """The drum turned by a table of angles θ = ω t (two rows, linear in between) carries the sphere as the
    rotation motion does, to round-off."""
    R, w = 0.05, 2.0
    law = _law(contact_law, friction=0.5)
    table = tmp_path / "poses.csv"
    table.write_text(f"t,dx,dy,dz,angle\n0,0,0,0,0\n10,0,0,0,{10 * w!r}\n")
    runs = []
    for motion in ({"kind": "rotation", "axis_point": [0, 0, 0], "axis": [0, 1, 0], "angular_velocity": w},
                   {"kind": "table", "file": str(table), "axis_point": [0, 0, 0], "axis": [0, 1, 0]}):
        drum = {"name": "drum", "kind": "cylinder", "point": [0.0, -0.01, 0.0], "axis": [0, 1, 0], "radius": R,
                "length": 0.02, "motion": motion}
        eng = make_engine((0.0, 0.0, -(R - D / 2)), D, (0, 0, 0), contact=law, walls=[drum], gravity=(0, 0, -G))
        eng.advance(int(0.1 / eng.dt))
        runs.append(eng)
    a, b = runs
    assert np.abs(a.state.velocity - b.state.velocity).max() < 1e-9
    assert np.abs(a.state.omega - b.state.omega).max() < 1e-7
    assert np.linalg.norm(a.state.velocity) > 1e-3  # it moved
