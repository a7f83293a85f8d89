"""Relative file paths of a case (``walls[].file``, ``walls[].motion.file``, ``particles.placement.file``) are
taken from the directory of the case file, so a case runs, and its run resumes, from any working directory; a
case given as data keeps the working directory."""
from __future__ import annotations

import json

import numpy as np
import pytest

from fluidem.case import load_case, validate_case
from fluidem.cli import main

CASE = """
name = "paths"
gravity = [0.0, 0.0, -9.81]

[particles]
[[particles.species]]
name = "glass"
diameter = 0.004
density = 2500.0
count = 2

[particles.contact]
model = "linear_spring_dashpot"
stiffness = 1000.0
restitution = 0.5
friction = 0.3

[particles.placement]
method = "file"
file = "data/start.csv"

[[walls]]
name = "floor"
kind = "mesh"
file = "data/floor.stl"

[walls.motion]
kind = "table"
file = "poses.csv"

[time]
end = 0.02

[output]
checkpoint_interval = 0.005
"""


def _write_case(folder):
    from stl import mesh

    (folder / "data").mkdir(parents=True)
    floor = mesh.Mesh(np.zeros(2, dtype=mesh.Mesh.dtype))
    s = 0.05
    floor.vectors[0] = [[-s, -s, 0.0], [s, -s, 0.0], [s, s, 0.0]]
    floor.vectors[1] = [[-s, -s, 0.0], [s, s, 0.0], [-s, s, 0.0]]
    floor.save(str(folder / "data" / "floor.stl"))
    (folder / "data" / "start.csv").write_text("x,y,z,diameter\n0.0,0.0,0.01,0.004\n0.01,0.0,0.01,0.004\n")
    (folder / "poses.csv").write_text("t,dx,dy,dz,angle\n0.0,0.0,0.0,0.0,0.0\n1.0,0.0,0.0,0.001,0.0\n")
    path = folder / "case.toml"
    path.write_text(CASE)
    return path


def test_relative_paths_are_taken_from_the_case_file(tmp_path, monkeypatch):
    path = _write_case(tmp_path / "cases")
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    case = load_case(path)
    folder = (tmp_path / "cases").resolve()
    assert case.walls[0].file == str(folder / "data" / "floor.stl")
    assert case.walls[0].motion.file == str(folder / "poses.csv")
    assert case.particles.placement.file == str(folder / "data" / "start.csv")
    # a relative path of a case given as data is the working directory's (the old rule): not found here
    data = case.model_dump(mode="json", exclude_none=True)
    data["walls"][0]["file"] = "data/floor.stl"
    from fluidem.errors import CaseError
    from fluidem.simulation import Simulation

    with pytest.raises(CaseError, match=r"walls.0 \('floor'\).file = 'data/floor.stl': no such file"):
        Simulation(validate_case(data))


def test_a_run_and_its_resume_find_the_files_from_other_directories(tmp_path, monkeypatch):
    path = _write_case(tmp_path / "cases")
    first, second = tmp_path / "a", tmp_path / "b"
    first.mkdir()
    second.mkdir()
    out = tmp_path / "runs" / "run"
    monkeypatch.chdir(first)
    assert main(["run", str(path), "--until", "0.01", "--out", str(out), "--quiet"]) == 0
    stored = (out / "case.toml").read_text()
    assert str((tmp_path / "cases" / "data" / "floor.stl").resolve()) in stored
    monkeypatch.chdir(second)
    assert main(["run", "--resume", str(out), "--until", "0.02", "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "completed"
    assert summary["sim_time_s"] == pytest.approx(0.02, abs=summary["dt_s"])
    assert summary["n_particles"] == 2
