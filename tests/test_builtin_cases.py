"""Smoke run of every built-in case through the command line (short --until), as CI requires."""
import json

import pytest

from fluidem.case import builtin_cases, load_case
from fluidem.cli import main


@pytest.mark.parametrize("name", sorted(builtin_cases()))
def test_builtin_case_smoke(name, tmp_path):
    case = load_case(name)
    until = min(0.01, case.time.end)
    out = tmp_path / "run"
    assert main(["run", name, "--until", str(until), "--out", str(out), "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "completed"
    assert summary["n_particles"] == sum(s.count for s in case.particles.species)
    assert abs(summary["sim_time_s"] - until) <= summary["dt_s"]
