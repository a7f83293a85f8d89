"""Smoke run of every built-in case through the command line (short --until), as CI requires."""
import json

import numpy as np
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
    # the particles at t = 0, plus those an inlet added, less those an outlet removed
    inserted = sum(summary[f"inlet_{i.name}_count"] for i in case.inlets)
    removed = sum(summary[f"outlet_{o.name}_count"] for o in case.outlets)
    assert summary["n_particles"] == sum(s.count for s in case.particles.species) + inserted - removed
    assert abs(summary["sim_time_s"] - until) <= summary["dt_s"]
    if name.startswith("drum-"):  # a drum reports the angle of repose of its bed
        assert "repose_angle_deg" in summary and "repose_angle_avg_deg" in summary


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


def test_a_binary_bed_reports_its_species_and_draws_their_segregation(tmp_path):
    """A bed of two species: probes.csv has each species' height and the segregation and Lacey indices
    (``analysis.mixing``), the summary their averages, and ``fluidem plot`` the ``segregation`` figure."""
    from fluidem.analysis.mixing import segregation_index
    from fluidem.io.probes_csv import read_probes

    out = tmp_path / "run"
    assert main(["run", "binary-size", "--until", "0.005", "--set", "output.probe_interval=0.001", "--out", str(out),
                 "--quiet"]) == 0
    probes = read_probes(out / "probes.csv")
    small, large = probes["height_small_m"], probes["height_large_m"]
    np.testing.assert_allclose(probes["segregation_index"], [segregation_index(a, b) for a, b in zip(small, large)],
                               rtol=1e-7)  # of heights written to 10 significant digits, 1 % apart
    assert len(small) == 6
    assert np.all((probes["lacey_index"] > 0.5) & (probes["lacey_index"] < 1.5))  # filled at random: mixed
    summary = json.loads((out / "summary.json").read_text())
    a, b = summary["averages_window_s"]
    window = (probes["time_s"] >= a - 1e-9) & (probes["time_s"] <= b + 1e-9)
    assert summary["segregation_index_avg"] == pytest.approx(np.mean(probes["segregation_index"][window]), rel=1e-9)
    assert {"height_small_avg_m", "height_large_avg_m", "lacey_index_avg"} <= set(summary)
    assert main(["plot", str(out), "--out", str(tmp_path / "fig"), "--quiet"]) == 0
    assert (tmp_path / "fig" / "segregation.png").exists()
