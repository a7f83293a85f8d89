"""Runs with wall shapes: a rotating drum (a cylinder closed by two rotating square caps) stopped and resumed
continues bit for bit, writes shapes.csv and shapes.stl, and keeps each contact's history with its particle
when the particles are renumbered in cell order."""
from __future__ import annotations

import csv
import math

import numpy as np
import pytest

from fluidem.case import validate_case
from fluidem.particles import _shape_kernels as S

R, L, W = 0.03, 0.012, 3.0  # drum radius, length [m], rotation rate [rad/s]
ROTATION = {"kind": "rotation", "axis_point": [0.0, 0.0, 0.0], "axis": [0.0, 1.0, 0.0], "angular_velocity": W}


def _cap(y):
    s = 1.05 * R
    return [[-s, y, -s], [s, y, -s], [s, y, s], [-s, y, s]]


def drum_case(n=60, end=0.08, reorder=None):
    data = {
        "name": "drum",
        "gravity": [0.0, 0.0, -9.81],
        "particles": {
            "species": [{"name": "glass", "diameter": 3e-3, "density": 2500.0, "count": n}],
            "contact": {"model": "linear_spring_dashpot", "stiffness": 2e3, "restitution": 0.6, "friction": 0.4},
            "placement": {"method": "lattice", "spacing": 1.1, "region_lower": [-0.6 * R, 0.0005, -0.6 * R],
                          "region_upper": [0.6 * R, L - 0.0005, 0.2 * R]},
        },
        "walls": [
            {"name": "shell", "kind": "cylinder", "point": [0.0, 0.0, 0.0], "axis": [0.0, 1.0, 0.0], "radius": R,
             "length": L, "motion": ROTATION},
            {"name": "back", "kind": "polygon", "points": _cap(0.0), "motion": ROTATION},
            {"name": "front", "kind": "polygon", "points": _cap(L), "motion": ROTATION},
        ],
        "time": {"end": end},
        "output": {"probe_interval": 0.005, "snapshot_interval": 0.02, "checkpoint_interval": 0.02},
    }
    if reorder is not None:
        data["neighbours"] = {"reorder_interval": reorder}
    return validate_case(data)


def test_drum_resumes_bit_for_bit_and_writes_the_shapes(stopped_and_resumed, tmp_path):
    whole, first, again = stopped_and_resumed(drum_case(), 0.04)
    assert np.array_equal(whole.engine.state.position, again.engine.state.position)
    assert np.array_equal(whole.engine.state.omega, again.engine.state.omega)
    assert np.array_equal(whole.engine.shapes.slot_hist, again.engine.shapes.slot_hist)
    run = tmp_path / "run"
    with open(run / "shapes.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    t = float(rows[-1]["time_s"])
    assert t == pytest.approx(0.08, abs=again.engine.dt)
    # the drum turned ω t (10 digits in the file); the particles press on the drum
    assert float(rows[-1]["shell.angle_rad"]) == pytest.approx(W * t, rel=1e-9)
    assert float(rows[-1]["back.dx_m"]) == 0.0
    fz = float(rows[-1]["shell.fz_N"]) + float(rows[-1]["back.fz_N"]) + float(rows[-1]["front.fz_N"])
    assert fz < 0.0
    from stl import mesh

    tris = mesh.Mesh.from_file(str(run / "shapes.stl")).vectors
    assert len(tris) == 64 + 2 + 2  # the shell drawn as 32 quads, each cap two triangles


def test_history_follows_renumbered_particles():
    from fluidem.particles.softsphere import SoftSphereEngine

    eng = SoftSphereEngine(drum_case(n=80, reorder=20))
    eng.advance(3000)
    assert eng.reorders > 0
    sh = eng.shapes
    st = eng.state
    P = np.empty((len(sh), S.POSE_COLS))
    S.pose(sh.motion, eng.time, P)
    # every history slot in use belongs to an element its particle touches now, and every particle touching
    # the shell keeps a spring with it
    for i in range(st.n):
        touching = set()
        for e in range(len(sh.kind)):
            k = sh.owner[e]
            b = S.to_body(P, k, *st.position[i])
            q = S.closest_point(sh.kind[e], *b, sh.geom, e)
            _, _, _, gap = S.face_side(sh.kind[e], *b, *q[:3], sh.geom, e)
            if gap < st.radius[i]:
                touching.add(e)
        held = set(int(e) for e in sh.slot_elem[i] if e >= 0)
        assert held <= touching, (i, held, touching)
        if 0 in touching:
            assert 0 in held
            h = list(sh.slot_elem[i]).index(0)
            assert np.any(sh.slot_hist[i, h] != 0.0)
    assert math.isfinite(float(st.position.sum()))


def test_a_particle_placed_across_a_shape_is_refused(tmp_path):
    from fluidem.errors import CaseError
    from fluidem.simulation import Simulation

    path = tmp_path / "p.csv"
    path.write_text("x,y,z,diameter\n0.0,0.0,0.001,0.004\n0.01,0.0,0.01,0.004\n")
    case = validate_case({
        "gravity": [0.0, 0.0, -9.81],
        "particles": {"species": [{"name": "p", "diameter": 4e-3, "density": 2500.0, "count": 2}],
                      "contact": {"model": "linear_spring_dashpot", "stiffness": 1e3, "restitution": 0.5,
                                  "friction": 0.3},
                      "placement": {"method": "file", "file": str(path)}},
        "walls": [{"name": "floor", "kind": "polygon",
                   "points": [[-0.05, -0.05, 0], [0.05, -0.05, 0], [0.05, 0.05, 0], [-0.05, 0.05, 0]]}],
        "time": {"end": 0.01},
    })
    with pytest.raises(CaseError, match=r"cross wall floor: 1 particle\(s\), e.g. particle 0 by 0.001 m"):
        Simulation(case)
