"""Hard-sphere runs through Simulation and the command line: summary keys, resume.

Short runs of the built-in ``hoomans-pour`` (no gas) and ``hoomans-orifice`` (coupled)
cases, and the start-up of the Table 2 gas cases (u_mf background before the jet onset T0).
The energy balance, also of ``hoomans-pour`` through the command line, is verified in
tests/verification/test_hardsphere_pour.py.
"""
import json

import numpy as np
import pytest

from fluidem.case import load_case
from fluidem.cli import main
from fluidem.simulation import Simulation


def test_hard_sphere_run_resumes_bit_for_bit(tmp_path):
    case = load_case("hoomans-pour", {"time.end": 0.12, "output.checkpoint_interval": 0.06})
    whole = Simulation(case, out_dir=tmp_path / "whole")
    whole.run()
    part = Simulation(case, out_dir=tmp_path / "part")
    part.run(until=0.06)
    again = Simulation.resume(tmp_path / "part")
    again.run()
    assert np.array_equal(whole.state.position, again.state.position)
    assert np.array_equal(whole.state.velocity, again.state.velocity)
    sw = json.loads((tmp_path / "whole" / "summary.json").read_text())
    sp = json.loads((tmp_path / "part" / "summary.json").read_text())
    assert sw["collisions"] == sp["collisions"]
    assert sw["energy_error_rel"] == sp["energy_error_rel"]


def _reject(name):
    raise ValueError(f"summary.json holds {name}, which is not JSON")


def test_coupled_hard_sphere_bed_runs_with_gas(tmp_path):
    out = tmp_path / "run"
    assert main(["run", "hoomans-orifice", "--until", "0.02", "--out", str(out), "--quiet"]) == 0
    s = json.loads((out / "summary.json").read_text(), parse_constant=_reject)  # strict JSON: no NaN
    assert s["gas_steps"] == 200 and s["dem_substeps"] == 1  # collisions within each gas step DT
    assert s["multicontact_ratio"] is None  # hard spheres never rest in contact: the ratio is undefined
    assert "energy_error_rel" not in s  # the gas does work: no closed energy balance
    assert (out / "gas.h5").exists()
    # where the wall time went: the engine, the gas side of the coupled steps, the writers; the loop's own rest
    parts = s["particle_time_s"], s["gas_time_s"], s["output_time_s"]
    assert all(p > 0.0 for p in parts) and sum(parts) <= s["wall_time_s"]
    assert s["collisions_per_particle_s"] == pytest.approx(s["collisions"] / s["particle_time_s"], rel=1e-12)
    assert s["collisions_per_particle_s"] > s["collisions_per_s"]


T0 = 0.5  # [s] jet onset of the Table 2 cases (tests/validation/test_hoomans1996.py)


@pytest.mark.parametrize("name, jet", [("hoomans-orifice", 45.0), ("hoomans-slug", 7.5), ("hoomans-tsuji", 6.5)])
def test_table2_cases_start_at_umf_and_switch_the_jet_on_at_t0(name, jet):
    """Hoomans §4.1 start-up: 4.5 m/s interstitial on every bottom face before T0, the case's inflow from T0
    (the central face for an orifice, every face for the uniform inflow), and T0 + 1 s simulated (§5.3)."""
    case = load_case(name)
    assert case.time.end == pytest.approx(T0 + 1.0)
    grid = case.gas.grid.build()
    bottom = case.gas.boundaries["bottom"]  # the Inflow itself
    weights = bottom.face_weights(grid.x_faces)

    def faces(t):
        return bottom.velocities(t) @ weights

    for t in (0.0, 0.25, T0 - 1e-4):
        assert np.allclose(faces(t), 4.5)
    for t in (T0, T0 + 1e-4, T0 + 1.0):
        v = faces(t)
        expected = np.full(grid.nx, 4.5)
        expected[slice(None) if name == "hoomans-slug" else grid.nx // 2] = jet
        assert np.allclose(v, expected), (t, v)


def test_coupled_hard_sphere_run_resumes(stopped_and_resumed):
    """hoomans-orifice (Hoomans' own coupling: cell_beta exchange, no −V_p∇p) stopped at a checkpoint and
    resumed matches the run made in one go bit for bit (the gas solver's reused factors are in the
    checkpoint: tests/verification/test_coupled_restart.py)."""
    case = load_case("hoomans-orifice", {"time.end": 0.02, "output.checkpoint_interval": 0.01,
                                         "output.snapshot_interval": 0.01, "output.probe_interval": 0.005})
    whole, first, again = stopped_and_resumed(case, 0.01)
    assert again.steps == whole.steps == 200
    # the time split goes on from the checkpoint: the resumed run's totals include the first part's
    for k in ("particle_time_s", "gas_time_s", "output_time_s"):
        assert again.summary()[k] > first.summary()[k] > 0.0
    assert again.engine.collisions == whole.engine.collisions > 0
    for k in ("position", "velocity", "omega"):
        assert np.array_equal(getattr(again.state, k), getattr(whole.state, k)), k
    for k in ("p", "u", "v", "voidage"):
        assert np.array_equal(getattr(again.gas.state, k), getattr(whole.gas.state, k)), k
