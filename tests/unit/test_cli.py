"""The ``fluidem`` command: bad input (exit 2, one message, nothing written), the run directory
contract (case.toml, summary.json, probes.csv, particles.h5 + .xdmf, restart.h5), bit-for-bit
resume (after a finished run and after Ctrl-C) and ``fluidem cases``.

Most runs call ``fluidem.cli.main`` in-process (fast: Numba kernels load once); a few use a real
``python -m fluidem`` subprocess for exit codes and SIGINT.
"""
from __future__ import annotations

import csv
import json
import os
import signal
import subprocess
import sys
import time
import traceback
import xml.etree.ElementTree as ET
from pathlib import Path

import h5py
import numpy as np
import pytest

from fluidem.case import load_case
from fluidem.cli import main

PROBE_COLUMNS = ["time_s", "kinetic_J", "potential_J", "rotational_J", "contacts", "coordination", "max_overlap_rel"]
SUMMARY_KEYS = ["case", "status", "sim_time_s", "wall_time_s", "n_particles", "particle_steps_per_s",
                "packing_fraction"]


@pytest.fixture(autouse=True, scope="module")
def _restore_numba_threads():
    """In-process runs with --threads 1 change Numba's thread count; give later test modules it back."""
    import numba

    before = numba.get_num_threads()
    yield
    numba.set_num_threads(before)


def cli(argv, capsys):
    """Run ``fluidem ARGV`` in-process: (exit status, stdout, stderr). An escaping exception counts
    as a crash with a traceback (status 1), as it would from the console script."""
    try:
        rc = main([str(a) for a in argv])
    except SystemExit as exc:  # argparse usage errors
        rc = exc.code
    except Exception:  # noqa: BLE001 - the test inspects it
        out, err = capsys.readouterr()
        return 1, out, err + traceback.format_exc()
    out, err = capsys.readouterr()
    return rc, out, err


def cli_subprocess(argv, cwd, **kw):
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    return subprocess.run([sys.executable, "-m", "fluidem", *map(str, argv)], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=120, **kw)


def final_state(run_dir):
    """Particle arrays of the last checkpoint of a run."""
    with h5py.File(Path(run_dir) / "restart.h5", "r") as f:
        return {k: np.asarray(f[f"state/{k}"]) for k in ("position", "velocity", "omega")}


def probe_rows(run_dir):
    with open(Path(run_dir) / "probes.csv", newline="") as f:
        return list(csv.DictReader(f))


def assert_states_bitwise_equal(a, b):
    sa, sb = final_state(a), final_state(b)
    for k in sa:
        assert np.array_equal(sa[k], sb[k]), f"{k} differs between {a} and {b}"


# ---------------------------------------------------------------- a file-placement case
OVERLAP_ROWS = [  # x, y, z, diameter: particles 1 and 3 overlap by 1 mm
    (0.010, 0.010, 0.002, 0.004),
    (0.030, 0.010, 0.002, 0.004),
    (0.020, 0.030, 0.002, 0.004),
    (0.033, 0.010, 0.002, 0.004),
]
APART_ROWS = [(0.010 + 0.006 * i, 0.010 + 0.006 * j, 0.002, 0.004) for i in range(5) for j in range(4)]


def file_case_toml(folder: Path, rows, name="filecase") -> Path:
    csv_path = folder / f"{name}.csv"
    csv_path.write_text("x,y,z,diameter\n" + "".join(",".join(map(repr, r)) + "\n" for r in rows))
    toml = folder / f"{name}.toml"
    toml.write_text(f"""
name = "{name}"
description = "particles from a CSV file"
[particles]
dimensions = 2
[[particles.species]]
diameter = 0.004
density = 2700.0
count = {len(rows)}
[particles.contact]
model = "linear_spring_dashpot"
stiffness = 800.0
[particles.placement]
method = "file"
file = "{csv_path.as_posix()}"
[[walls]]
name = "box"
kind = "box"
lower = [0.0, 0.0, 0.0]
upper = [0.05, 0.05, 0.004]
[time]
end = 0.01
[output]
snapshot_interval = 0.002
probe_interval = 0.0005
""")
    return toml


# ---------------------------------------------------------------- bad input
BAD_INPUT = {
    # id: (extra argv after `run`, fragments stderr must contain)
    "unknown-key": (["pour", "--set", "particles.foo=1"],
                    ["particles.foo", "1", "allowed keys", "species", "contact"]),
    "negative-diameter": (["pour", "--set", "particles.species.0.diameter=-0.004"],
                          ["particles.species.0.diameter", "-0.004", "greater than 0"]),
    "restitution-above-one": (["pour", "--set", "particles.contact.restitution=1.5"],
                              ["particles.contact.restitution", "1.5", "less than or equal to 1"]),
    "unknown-contact-model": (["pour", "--set", "particles.contact.model=hookean"],
                              ["particles.contact", "hookean", "linear_spring_dashpot", "hertz_mindlin"]),
    "too-many-particles": (["pour", "--set", "particles.species.0.count=5000"],
                           ["particles.placement", "5000"]),
    "dt-above-limit": (["pour", "--set", "time.dt=0.01"], ["time.dt", "0.01", "stability limit"]),
    "negative-until": (["pour", "--until=-1"], ["time.end", "-1"]),
    "zero-threads": (["pour", "--threads", "0"], ["threads", "0"]),
    "unknown-case": (["no-such-case"], ["no-such-case", "pour"]),
    "malformed-set-no-equals": (["pour", "--set", "particles.contact.restitution"],
                                ["particles.contact.restitution", "key=value"]),
    "malformed-set-bad-index": (["pour", "--set", "particles.species.7.diameter=0.001"],
                                ["particles.species.7", "below 1"]),
    "malformed-set-text-for-number": (["pour", "--set", "particles.contact.friction=lots"],
                                      ["particles.contact.friction", "'lots'"]),
}


def assert_clean_failure(rc, out, err, fragments):
    assert rc == 2, f"exit status {rc}, stderr:\n{err}"
    assert "Traceback" not in err
    text = err.strip()
    assert text, "no message on stderr"
    assert "\n\n" not in text, f"more than one paragraph:\n{text}"
    assert text.startswith("fluidem: error:")
    for frag in fragments:
        assert frag in text, f"{frag!r} not in message:\n{text}"
    assert out == ""


@pytest.mark.parametrize("argv, fragments", BAD_INPUT.values(), ids=BAD_INPUT.keys())
def test_bad_input_exits_2_and_writes_nothing(tmp_path, capsys, argv, fragments):
    out_dir = tmp_path / "run"
    rc, out, err = cli(["run", *argv, "--out", out_dir], capsys)
    assert_clean_failure(rc, out, err, fragments)
    assert not out_dir.exists()
    assert list(tmp_path.iterdir()) == []


def test_overlapping_initial_particles(tmp_path, capsys):
    toml = file_case_toml(tmp_path, OVERLAP_ROWS)
    before = sorted(tmp_path.iterdir())
    out_dir = tmp_path / "run"
    rc, out, err = cli(["run", toml, "--out", out_dir], capsys)
    assert_clean_failure(rc, out, err, ["overlap", "particles 1 and 3"])
    assert not out_dir.exists()
    assert sorted(tmp_path.iterdir()) == before


def test_unknown_key_in_a_case_file(tmp_path, capsys):
    toml = file_case_toml(tmp_path, APART_ROWS)
    toml.write_text(toml.read_text().replace("stiffness = 800.0", "stiffness = 800.0\nstiffnes = 3.0"))
    out_dir = tmp_path / "run"
    rc, out, err = cli(["run", toml, "--out", out_dir], capsys)
    assert_clean_failure(rc, out, err, ["particles.contact.stiffnes", "3.0", "allowed keys", "stiffness"])
    assert not out_dir.exists()


def test_unwritable_output_folder(tmp_path, capsys):
    blocker = tmp_path / "FILE"
    blocker.write_text("keep me")
    out_dir = blocker / "sub"
    rc, out, err = cli(["run", "pour", "--until", "0.001", "--out", out_dir], capsys)
    assert_clean_failure(rc, out, err, [str(out_dir), "not writable"])
    assert blocker.is_file() and blocker.read_text() == "keep me"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["FILE"]


def test_output_folder_that_is_a_file(tmp_path, capsys):
    blocker = tmp_path / "FILE"
    blocker.write_text("keep me")
    rc, out, err = cli(["run", "pour", "--until", "0.001", "--out", blocker], capsys)
    assert_clean_failure(rc, out, err, [str(blocker)])
    assert blocker.read_text() == "keep me"


def test_non_empty_output_folder_is_left_alone(tmp_path, capsys):
    out_dir = tmp_path / "run"
    out_dir.mkdir()
    (out_dir / "notes.txt").write_text("mine")
    rc, out, err = cli(["run", "pour", "--until", "0.001", "--out", out_dir], capsys)
    assert_clean_failure(rc, out, err, [str(out_dir), "not empty", "--resume"])
    assert sorted(p.name for p in out_dir.iterdir()) == ["notes.txt"]


def test_resume_of_a_folder_without_a_run(tmp_path, capsys):
    rc, out, err = cli(["run", "--resume", tmp_path / "nothing"], capsys)
    assert_clean_failure(rc, out, err, [str(tmp_path / "nothing")])
    assert not (tmp_path / "nothing").exists()


def test_resume_with_set_is_refused(tmp_path, capsys):
    rc, out, err = cli(["run", "--resume", tmp_path, "--set", "time.end=1"], capsys)
    assert_clean_failure(rc, out, err, ["--resume", "--set"])


def test_run_without_case(capsys):
    rc, out, err = cli(["run"], capsys)
    assert_clean_failure(rc, out, err, ["CASE"])


def test_set_through_a_value_is_bad_input(tmp_path, capsys):
    out_dir = tmp_path / "run"
    rc, out, err = cli(["run", "pour", "--set", "time.end.x=1", "--out", out_dir], capsys)
    assert_clean_failure(rc, out, err, ["time.end"])
    assert not out_dir.exists()


def test_bad_input_in_a_real_process(tmp_path):
    """Exit status, stderr and no traceback as the shell sees them."""
    out_dir = tmp_path / "run"
    res = cli_subprocess(["run", "pour", "--set", "particles.contact.restitution=1.5", "--out", out_dir], tmp_path)
    assert_clean_failure(res.returncode, res.stdout, res.stderr, ["particles.contact.restitution", "1.5"])
    assert not out_dir.exists()
    assert list(tmp_path.iterdir()) == []


# ---------------------------------------------------------------- a short run
@pytest.fixture(scope="module")
def pour_run(tmp_path_factory):
    """`fluidem run pour --until 0.02` in-process: (run folder, stdout summary)."""
    out_dir = tmp_path_factory.mktemp("pour") / "run"
    rc = main(["run", "pour", "--until", "0.02", "--out", str(out_dir), "--threads", "1", "--quiet"])
    assert rc == 0
    return out_dir


def test_run_folder_contents(pour_run):
    names = {p.name for p in pour_run.iterdir()}
    assert {"case.toml", "summary.json", "probes.csv", "particles.h5", "particles.xdmf", "restart.h5"} <= names
    assert not [n for n in names if n.endswith(".tmp")], "temporary files left behind"


def test_run_prints_the_summary(tmp_path, capsys):
    rc, out, err = cli(["run", "pour", "--until", "0.001", "--out", tmp_path / "r", "--threads", "1"], capsys)
    assert rc == 0
    assert json.loads(out) == json.loads((tmp_path / "r" / "summary.json").read_text())
    assert "pour" in err and "500 particles" in err  # the start line (no --quiet)


def test_case_toml_is_resolved_and_reloadable(pour_run):
    case = load_case(pour_run / "case.toml")
    pour = load_case("pour")
    assert case.name == "pour"
    assert case.time.end == 0.02  # --until
    assert case.threads == 1  # --threads
    assert case.time.dt is not None and 0 < case.time.dt < 1e-4  # the time step actually used
    assert case.particles == pour.particles
    assert case.walls == pour.walls
    assert case.gravity == (0.0, -9.81, 0.0)
    summary = json.loads((pour_run / "summary.json").read_text())
    assert case.time.dt == summary["dt_s"]


def test_case_toml_reproduces_the_run(pour_run, tmp_path, capsys):
    rc, _, _ = cli(["run", pour_run / "case.toml", "--out", tmp_path / "again", "--quiet"], capsys)
    assert rc == 0
    assert_states_bitwise_equal(pour_run, tmp_path / "again")


def test_summary_json(pour_run):
    s = json.loads((pour_run / "summary.json").read_text())
    for k in SUMMARY_KEYS:
        assert k in s, f"summary.json lacks {k!r}"
    assert s["case"] == "pour"
    assert s["status"] == "completed"
    dt = load_case(pour_run / "case.toml").time.dt
    assert abs(s["sim_time_s"] - 0.02) <= dt
    assert s["wall_time_s"] > 0
    assert s["n_particles"] == 500
    assert s["particle_steps_per_s"] > 0
    assert 0.0 < s["packing_fraction"] < 1.0
    # no gas: the wall time splits into the engine, the writers and the loop's own rest
    assert s["gas_time_s"] == 0.0 and s["particle_time_s"] > 0.0 and s["output_time_s"] > 0.0
    assert s["particle_time_s"] + s["output_time_s"] <= s["wall_time_s"]


def test_probes_csv(pour_run):
    with open(pour_run / "probes.csv", newline="") as f:
        reader = csv.DictReader(f)
        assert set(PROBE_COLUMNS) <= set(reader.fieldnames)
        rows = list(reader)
    times = [float(r["time_s"]) for r in rows]
    assert times[0] == 0.0
    assert all(b > a for a, b in zip(times, times[1:])), "probe times must increase"
    assert len(rows) == 5  # probe_interval 0.005 s: t = 0, 0.005, ..., 0.02
    dt = load_case(pour_run / "case.toml").time.dt
    for k, t in enumerate(times):
        assert 0.005 * k <= t + 1e-12 < 0.005 * k + dt
    for r in rows:
        for c in PROBE_COLUMNS:
            assert np.isfinite(float(r[c])), f"{c} = {r[c]}"
        assert int(r["contacts"]) >= 0
        assert float(r["kinetic_J"]) >= 0 and float(r["rotational_J"]) >= 0
    # the particles fall: potential energy goes down, kinetic up
    assert float(rows[-1]["potential_J"]) < float(rows[0]["potential_J"])
    assert float(rows[-1]["kinetic_J"]) > 0.0


NUMPY_TYPES = {("Float", "8"): np.float64, ("Float", "4"): np.float32, ("Int", "4"): np.int32,
               ("Int", "8"): np.int64}


def test_xdmf_points_at_existing_hdf5_datasets(pour_run):
    root = ET.parse(pour_run / "particles.xdmf").getroot()
    assert root.tag == "Xdmf"
    collection = root.find("Domain/Grid")
    assert collection.get("GridType") == "Collection" and collection.get("CollectionType") == "Temporal"
    grids = collection.findall("Grid")
    items = root.findall(".//DataItem")
    assert items
    with h5py.File(pour_run / "particles.h5", "r") as h5:
        assert len(grids) == len(h5["snapshots"])
        times = []
        for grid in grids:
            t = float(grid.find("Time").get("Value"))
            times.append(t)
            n = int(grid.find("Topology").get("NumberOfElements"))
            assert n == 500
            names = {a.get("Name") for a in grid.findall("Attribute")}
            assert {"velocity", "diameter"} <= names
            assert grid.find("Geometry/DataItem") is not None
        assert times == sorted(times) and times[0] == 0.0 and abs(times[-1] - 0.02) < 1e-4
        for item in items:
            assert item.get("Format") == "HDF"
            file_name, _, dataset = item.text.strip().partition(":")
            assert (pour_run / file_name).resolve() == (pour_run / "particles.h5").resolve()
            assert dataset in h5, f"{dataset} missing from particles.h5"
            dims = tuple(int(x) for x in item.get("Dimensions").split())
            assert h5[dataset].shape == dims, dataset
            expected = NUMPY_TYPES[(item.get("NumberType"), item.get("Precision"))]
            assert h5[dataset].dtype == expected, f"{dataset}: {h5[dataset].dtype} vs {expected}"
            # the grid's time is the snapshot's time
            snap = h5[dataset].parent
            grid_time = [float(g.find("Time").get("Value")) for g in grids if item in g.iter("DataItem")][0]
            assert abs(float(snap.attrs["time"]) - grid_time) <= 1e-9 * max(1.0, grid_time)


def test_restart_file_holds_the_final_state(pour_run):
    with h5py.File(pour_run / "particles.h5", "r") as h5:
        last = h5["snapshots"][sorted(h5["snapshots"])[-1]]
        final_pos = np.asarray(last["position"])
        final_vel = np.asarray(last["velocity"])
    st = final_state(pour_run)
    assert st["position"].shape == (500, 3)
    assert np.array_equal(st["position"], final_pos)
    assert np.array_equal(st["velocity"], final_vel)


# ---------------------------------------------------------------- resume
@pytest.fixture(scope="module")
def resumed_pair(tmp_path_factory):
    """(uninterrupted run to 0.04, run to 0.02 resumed to 0.04)."""
    base = tmp_path_factory.mktemp("resume")
    full, part = base / "full", base / "part"
    common = ["--threads", "1", "--quiet"]
    assert main(["run", "pour", "--until", "0.04", "--out", str(full), *common]) == 0
    assert main(["run", "pour", "--until", "0.02", "--out", str(part), *common]) == 0
    assert main(["run", "--resume", str(part), "--until", "0.04", "--quiet"]) == 0
    return full, part


def test_resume_is_bitwise_identical(resumed_pair):
    full, part = resumed_pair
    assert_states_bitwise_equal(full, part)
    s_full = json.loads((full / "summary.json").read_text())
    s_part = json.loads((part / "summary.json").read_text())
    assert s_part["status"] == "completed"
    assert s_part["sim_time_s"] == s_full["sim_time_s"]
    assert s_part["steps"] == s_full["steps"]


def test_resume_keeps_snapshots_consistent(resumed_pair):
    full, part = resumed_pair
    with h5py.File(full / "particles.h5", "r") as a, h5py.File(part / "particles.h5", "r") as b:
        assert sorted(a["snapshots"]) == sorted(b["snapshots"])
        for k in a["snapshots"]:
            assert a["snapshots"][k].attrs["time"] == b["snapshots"][k].attrs["time"]
            assert np.array_equal(a["snapshots"][k]["position"], b["snapshots"][k]["position"])
    assert (full / "particles.xdmf").read_text() == (part / "particles.xdmf").read_text()


def test_resume_probes_have_no_duplicates(resumed_pair):
    _, part = resumed_pair
    times = [r["time_s"] for r in probe_rows(part)]
    assert len(times) == len(set(times))


def test_resume_probes_have_no_missing_times(resumed_pair):
    full, part = resumed_pair
    assert [r["time_s"] for r in probe_rows(part)] == [r["time_s"] for r in probe_rows(full)]


def test_resume_probe_values_match_where_present(resumed_pair):
    full, part = resumed_pair
    ref = {r["step"]: r for r in probe_rows(full)}
    for r in probe_rows(part):
        assert r == ref[r["step"]]


def test_interrupted_run_resumes_bitwise(tmp_path, capsys):
    """SIGINT to a real process mid-run: exit 130, a checkpoint, and a resume that ends where an
    uninterrupted run ends, bit for bit."""
    until = "0.1"  # about 1.7 s of stepping on one thread: room to interrupt in the middle
    run_dir = tmp_path / "stopped"
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    proc = subprocess.Popen([sys.executable, "-m", "fluidem", "run", "pour", "--until", until, "--out", str(run_dir),
                             "--threads", "1", "--quiet"], cwd=tmp_path, env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    try:
        # wait until stepping is under way: two probe rows (t = 0 and t = 0.005 s) are written
        deadline = time.monotonic() + 60
        probes = run_dir / "probes.csv"
        while time.monotonic() < deadline and proc.poll() is None:
            if probes.exists() and len(probes.read_text().splitlines()) >= 3:
                break
            time.sleep(0.005)
        assert proc.poll() is None, "the run ended before it could be interrupted"
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert proc.returncode == 130, err
    assert "Traceback" not in err
    assert f"--resume {run_dir}" in err
    stopped = json.loads((run_dir / "summary.json").read_text())
    assert stopped["status"] == "interrupted"
    assert 0.0 < stopped["sim_time_s"] < float(until)
    assert not [p for p in run_dir.iterdir() if p.name.endswith(".tmp")]

    rc, out, err = cli(["run", "--resume", run_dir, "--quiet"], capsys)
    assert rc == 0, err
    assert json.loads(out)["status"] == "completed"

    ref = tmp_path / "reference"
    rc, _, _ = cli(["run", "pour", "--until", until, "--out", ref, "--threads", "1", "--quiet"], capsys)
    assert rc == 0
    assert_states_bitwise_equal(ref, run_dir)

    times_resumed = [r["time_s"] for r in probe_rows(run_dir)]
    times_ref = [r["time_s"] for r in probe_rows(ref)]
    assert len(times_resumed) == len(set(times_resumed)), "duplicated probe times after resume"
    assert times_resumed == times_ref, "probe rows missing or extra after resume"


def test_resume_does_not_need_the_placement_file(tmp_path, capsys):
    toml = file_case_toml(tmp_path, APART_ROWS)
    run_dir = tmp_path / "run"
    rc, _, err = cli(["run", toml, "--until", "0.002", "--out", run_dir, "--threads", "1", "--quiet"], capsys)
    assert rc == 0, err
    (tmp_path / "filecase.csv").unlink()
    rc, _, err = cli(["run", "--resume", run_dir, "--until", "0.004", "--quiet"], capsys)
    assert rc == 0, err


def test_file_case_runs_and_resumes(tmp_path, capsys):
    toml = file_case_toml(tmp_path, APART_ROWS)
    full, part = tmp_path / "full", tmp_path / "part"
    common = ["--threads", "1", "--quiet"]
    assert cli(["run", toml, "--until", "0.004", "--out", full, *common], capsys)[0] == 0
    assert cli(["run", toml, "--until", "0.002", "--out", part, *common], capsys)[0] == 0
    assert cli(["run", "--resume", part, "--until", "0.004", "--quiet"], capsys)[0] == 0
    assert_states_bitwise_equal(full, part)
    assert json.loads((full / "summary.json").read_text())["n_particles"] == len(APART_ROWS)


# ---------------------------------------------------------------- fluidem cases
def test_cases_lists_pour_with_a_description(capsys):
    rc, out, err = cli(["cases"], capsys)
    assert rc == 0
    lines = {line.split(None, 1)[0]: line.split(None, 1)[1] for line in out.splitlines() if line.strip()}
    assert "pour" in lines
    assert lines["pour"].strip() == load_case("pour").description
    assert len(lines["pour"]) > 10


def test_cases_in_a_real_process(tmp_path):
    res = cli_subprocess(["cases"], tmp_path)
    assert res.returncode == 0, res.stderr
    assert any(line.startswith("pour ") for line in res.stdout.splitlines())
    assert res.stderr == ""


def test_write_failure_keeps_the_checkpoint_resumable(tmp_path, capsys, monkeypatch):
    """A failing output write (as on a full disk) stops the run cleanly; the checkpoint stays usable."""
    from fluidem.io import snapshots

    out_dir = tmp_path / "run"
    rc, _, err = cli(["run", "pour", "--until", "0.01", "--out", out_dir, "--threads", "1", "--quiet"], capsys)
    assert rc == 0, err
    calls = {"n": 0}
    real_call = snapshots.ParticleWriter.__call__

    def full_disk(self, sim):
        calls["n"] += 1
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(snapshots.ParticleWriter, "__call__", full_disk)
    rc, out, err = cli(["run", "--resume", out_dir, "--until", "0.05", "--quiet"], capsys)
    assert rc == 1 and calls["n"] == 1
    assert "No space left on device" in err and "--resume" in err and "Traceback" not in err
    monkeypatch.setattr(snapshots.ParticleWriter, "__call__", real_call)
    rc, _, err = cli(["run", "--resume", out_dir, "--until", "0.03", "--quiet"], capsys)
    assert rc == 0, err
    # the failed snapshot was rewritten on resume: same snapshot times as an uninterrupted run
    ref = tmp_path / "ref"
    rc, _, err = cli(["run", "pour", "--until", "0.03", "--out", ref, "--threads", "1", "--quiet"], capsys)
    assert rc == 0, err
    import h5py

    def times(d):
        with h5py.File(d / "particles.h5") as f:
            return [float(f["snapshots"][k].attrs["time"]) for k in sorted(f["snapshots"])]

    assert times(out_dir) == times(ref)


def test_cases_shows_each_case_size_length_and_a_rough_wall_time(capsys):
    from fluidem.estimate import _dt, wall_time_estimate
    from fluidem.particles import engine_for

    rc, out, err = cli(["cases"], capsys)
    assert rc == 0
    lines = out.splitlines()
    below_pour = lines[[k for k, line in enumerate(lines) if line.startswith("pour ")][0] + 1]
    assert below_pour.split()[:5] == ["500", "particles,", "1.5", "s", "simulated,"] and "on one core" in below_pour
    # the estimate's time step is the one the engine takes (the contact time of the smallest pair)
    case = load_case("pour")
    assert _dt(case) == pytest.approx(engine_for(case).dt, rel=1e-12)
    assert 1.0 < wall_time_estimate(case) < 60.0  # 500 particles × 1e5 steps at millions of particle-steps/s


def test_the_wall_time_estimate_counts_every_cell_of_a_3d_gas_grid():
    """The gas term is gas steps × cells: a 3D grid of twice the depth in cells costs twice the gas time."""
    from fluidem.estimate import GAS_CELL_STEP, wall_time_estimate

    base = load_case("bubbling-3d-large", {"time.end": 1.0})
    deep = load_case("bubbling-3d-large", {"time.end": 1.0, "gas.grid.cells": [15, 35, 16]})
    gas_steps = 1.0 / base.gas.dt
    assert wall_time_estimate(deep) - wall_time_estimate(base) == pytest.approx(
        gas_steps * 15 * 35 * 8 * GAS_CELL_STEP, rel=1e-9)


# ---------------------------------------------------------------- the end of a run
def test_a_run_ends_at_the_time_asked_with_its_last_probe_row_and_snapshot(tmp_path, capsys):
    """--until between two steps: the run takes the step that reaches it (never stops short), and the probe
    row and snapshot of that end time are written even where their schedules do not fall on it; the closing
    lines say where the outputs are and how to plot them."""
    from fluidem.io.probes_csv import read_probes
    from fluidem.io.snapshots import snapshot_index

    out = tmp_path / "run"
    until = 0.0123  # pour: dt = 1.495e-5 s, so 822.8 steps; probes every 1.5 ms, snapshots every 15 ms
    rc, stdout, err = cli(["run", "pour", "--until", until, "--out", out], capsys)
    assert rc == 0
    summary = json.loads(stdout)
    dt = summary["dt_s"]
    assert until <= summary["sim_time_s"] < until + dt
    assert read_probes(out / "probes.csv")["time_s"][-1] == pytest.approx(summary["sim_time_s"], rel=1e-9)
    assert snapshot_index(out / "particles.h5")[-1][1] == pytest.approx(summary["sim_time_s"], rel=1e-12)
    assert f"outputs in {out}/" in err and f"fluidem plot {out}" in err and f"fluidem report {out}" in err


def test_the_first_chunk_that_compiles_is_announced_and_left_out_of_the_rate(tmp_path, caplog, monkeypatch):
    """A first chunk slower than COMPILE_NOTICE_SECONDS (here made 1.5 s slow) is announced, and the summary's
    particle_steps_per_s counts only the chunks after it."""
    import logging

    from fluidem import simulation as S

    case = load_case("pour", {"time.end": 0.02})
    sim = S.Simulation(case, out_dir=tmp_path / "run")
    advance, calls = sim.advance, []

    def slow_first(n):
        calls.append(n)
        if len(calls) == 1:
            time.sleep(1.5)
        advance(n)

    monkeypatch.setattr(sim, "advance", slow_first)
    monkeypatch.setattr(S, "_kernels_ready", False)
    monkeypatch.setattr(S, "COMPILE_NOTICE_SECONDS", 0.5)
    with caplog.at_level(logging.INFO, logger="fluidem"):
        summary = sim.run()
    assert any("compiling the kernels" in r.getMessage() for r in caplog.records)
    naive = sim.particle_steps / sim.wall_time
    assert sim.warm_seconds < sim.wall_time - 1.5
    assert summary["particle_steps_per_s"] == pytest.approx(sim.warm_particle_steps / sim.warm_seconds)
    assert summary["particle_steps_per_s"] > naive
