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


@pytest.mark.parametrize("name", ["tsuji-jet", "goldschmidt"])
def test_sun_case_summary_gives_the_largest_cell_contact_to_gas_force_ratio(name, tmp_path):
    """``contact_drag_ratio_max`` (Sun 2007 Figs 7/12) is the largest cell mean ratio of the final
    snapshot's contact and gas forces, recomputed here from particles.h5."""
    import numpy as np

    from fluidem.analysis.fluidised import cell_force_maps
    from fluidem.io.snapshots import read_snapshot

    case = load_case(name)
    out = tmp_path / "run"
    until = 0.02
    assert main(["run", name, "--until", str(until), "--out", str(out), "--quiet",
                 "--set", "output.snapshot_interval=0.01"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    snap = read_snapshot(out / "particles.h5")
    assert snap["time"] == pytest.approx(until)
    d = snap["diameter"] if "diameter" in snap else 2.0 * snap["radius"]
    rho = case.particles.species[0].density
    mass = rho * np.pi / 6.0 * d**3
    ratio = cell_force_maps(load_case(name).gas.build(case.gravity).grid, snap["position"], mass,
                            snap["contact_force"], snap["gas_force"], np.asarray(case.gravity))["force_ratio"]
    expected = float(np.nanmax(np.where(ratio >= 0.0, ratio, np.nan)))
    assert summary["contact_drag_ratio_max"] == pytest.approx(expected, rel=1e-9)
    assert summary["contact_drag_ratio_max"] > 0.0
    # the same figure at every probe time in probes.csv; the summary's average is over the second half of
    # this short run (Sun's 5-10 s window for full runs)
    import csv

    with open(out / "probes.csv", newline="") as f:
        rows = [(float(r["time_s"]), float(r["contact_drag_ratio_max"])) for r in csv.DictReader(f)]
    assert rows[-1][1] == pytest.approx(expected, rel=1e-9)
    lo, hi = summary["averages_window_s"]
    window = [v for t, v in rows if lo - 1e-9 <= t <= hi + 1e-9]
    assert len(window) >= 2
    assert summary["contact_drag_ratio_max_avg"] == pytest.approx(np.mean(window), rel=1e-9)
