"""Wall-shape contacts in the outputs: a sphere at rest on a meshed floor (an STL square of two triangles).

At rest its contact force is its weight, m g upward, and its overlap the static one: m g/k_n for the linear
law, (m g/(4/3 E* sqrt(a)))^(2/3) for Hertz (a wall of the particle's material: 1/E* = 2 (1 − ν²)/E). The
snapshot's ``contact_force``, the probes' ``wall_contacts`` and ``max_overlap_rel`` (overlap over the
diameter) and the run check's largest overlap must see it as they see a plane wall.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from fluidem.case import validate_case
from fluidem.checks import RunFailure
from fluidem.io.probes_csv import read_probes
from fluidem.io.snapshots import read_snapshot
from fluidem.simulation import Simulation

DIAMETER = 4e-3  # [m]
DENSITY = 2500.0  # [kg/m^3]
G = 9.81  # [m/s^2]
# TOL = 1e-6: the sphere starts touching and settles within 0.03 s (e = 0.3 damps the bounce as e^-100);
#   what remains is round-off. A contact missed by the outputs gives 0, a plane-only count 0 contacts.
TOL = 1e-6


def _floor_stl(path):
    from stl import mesh

    s = 0.02
    corners = np.array([[-s, -s, 0.0], [s, -s, 0.0], [s, s, 0.0], [-s, s, 0.0]])
    m = mesh.Mesh(np.zeros(2, dtype=mesh.Mesh.dtype))
    m.vectors[0] = corners[[0, 1, 2]]
    m.vectors[1] = corners[[0, 2, 3]]
    m.save(str(path))
    return path


def _case(tmp_path, law, max_overlap=0.1):
    stl = _floor_stl(tmp_path / "floor.stl")
    csv = tmp_path / "p.csv"
    csv.write_text(f"x,y,z,diameter\n0.001,0.002,{0.5 * DIAMETER!r},{DIAMETER!r}\n")
    return validate_case({
        "name": "rest", "gravity": [0.0, 0.0, -G],
        "particles": {"species": [{"name": "p", "diameter": DIAMETER, "density": DENSITY, "count": 1}],
                      "contact": law, "placement": {"method": "file", "file": str(csv)}},
        "walls": [{"name": "floor", "kind": "mesh", "file": str(stl)}],
        "time": {"end": 0.03, "impact_velocity": 0.1},
        "output": {"snapshot_interval": 0.015, "probe_interval": 0.015},
        "checks": {"max_overlap": max_overlap}})


def _static_overlap(law, mass):
    if law["model"] == "linear_spring_dashpot":
        return mass * G / law["stiffness"]
    e_star = law["youngs_modulus"] / (2.0 * (1.0 - law["poisson_ratio"] ** 2))
    return (mass * G / (4.0 / 3.0 * e_star * math.sqrt(0.5 * DIAMETER))) ** (2.0 / 3.0)


@pytest.mark.parametrize("model", ["linear_spring_dashpot", "hertz_mindlin"])
def test_sphere_resting_on_a_mesh_floor_in_the_outputs(tmp_path, contact_law, model):
    law = contact_law(model, restitution=0.3, friction=0.5)
    mass = DENSITY * math.pi * DIAMETER**3 / 6.0
    delta = _static_overlap(law, mass)
    sim = Simulation(_case(tmp_path, law), out_dir=tmp_path / "run")
    sim.run()
    snap = read_snapshot(tmp_path / "run")
    np.testing.assert_allclose(snap["contact_force"][0], [0.0, 0.0, mass * G], rtol=TOL, atol=TOL * mass * G)
    probes = read_probes(tmp_path / "run" / "probes.csv")
    assert probes["wall_contacts"][-1] == 1
    assert probes["max_overlap_rel"][-1] == pytest.approx(delta / DIAMETER, rel=TOL)
    assert 0.5 * DIAMETER - sim.engine.state.position[0, 2] == pytest.approx(delta, rel=TOL)

    # the run check sees the shape's overlap: a limit below it stops the run, naming the wall
    tight = Simulation(_case(tmp_path, law, max_overlap=0.5 * delta / DIAMETER), out_dir=tmp_path / "tight")
    with pytest.raises(RunFailure, match="overlaps wall 'floor'") as err:
        tight.run()
    assert err.value.check == "overlap"
    assert err.value.value > 0.5 * delta / DIAMETER
