"""``fluidem sweep``: members equal to the same runs made alone, resume after a kill and after Ctrl-C, a
failing member recorded while the others finish, an existing Dask cluster, bad input (exit 2, nothing
written), and the study's figures and report.

The sweeps run the ``pour`` case for a few hundredths of a simulated second, one thread per member, on
local clusters of one or two worker processes. Sweeps that must be stopped from outside run in a real
``python -m fluidem`` process; the others call ``fluidem.cli.main`` in this process.
"""
from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import time
import tomllib
import traceback
from pathlib import Path

import h5py
import numpy as np
import pytest

pytest.importorskip("distributed")

from fluidem.case import load_case  # noqa: E402
from fluidem.cli import main  # noqa: E402
from fluidem.errors import CaseError  # noqa: E402
from fluidem.studies import StudyDefinition, parse_seeds, parse_vary  # noqa: E402
from fluidem.studies.definition import key_labels  # noqa: E402
from fluidem.studies.table import member_state  # noqa: E402

SRC = Path(__file__).resolve().parents[2] / "src"
UNTIL = "0.02"
RESTITUTION = ("0.8", "0.9")
FRICTION = ("0", "0.3")
VARY = ["--vary", f"particles.contact.restitution={','.join(RESTITUTION)}",
        "--vary", f"particles.contact.friction={','.join(FRICTION)}"]
# what differs between two identical runs: wall-clock figures
TIMING_KEYS = {"wall_time_s", "particle_steps_per_s", "startup_s", "particle_time_s", "gas_time_s", "output_time_s",
               "collisions_per_s", "collisions_per_particle_s", "check_time_s"}


@pytest.fixture(autouse=True, scope="module")
def _restore_numba_threads():
    """In-process runs with --threads 1 change Numba's thread count; give later test modules it back."""
    import numba

    before = numba.get_num_threads()
    yield
    numba.set_num_threads(before)


def cli(argv, capsys=None):
    """``fluidem ARGV`` in this process: (exit status, stdout, stderr)."""
    try:
        rc = main([str(a) for a in argv])
    except SystemExit as exc:
        rc = exc.code
    except Exception:  # noqa: BLE001 - shown in the failure
        out, err = capsys.readouterr() if capsys else ("", "")
        return 1, out, err + traceback.format_exc()
    out, err = capsys.readouterr() if capsys else ("", "")
    return rc, out, err


def env():
    return dict(os.environ, PYTHONUNBUFFERED="1",
                PYTHONPATH=os.pathsep.join([str(SRC), *filter(None, [os.environ.get("PYTHONPATH")])]))


def restart_arrays(run_dir) -> dict:
    out = {}
    with h5py.File(Path(run_dir) / "restart.h5", "r") as f:
        f.visititems(lambda name, obj: out.__setitem__(name, np.asarray(obj)) if isinstance(obj, h5py.Dataset) else None)
    return out


def assert_same_run(a, b):
    """Two run directories hold the same run: checkpoint arrays bit for bit, the summary but for timings."""
    ra, rb = restart_arrays(a), restart_arrays(b)
    assert ra.keys() == rb.keys()
    for k in ra:
        assert np.array_equal(ra[k], rb[k]), f"restart.h5 {k} differs between {a} and {b}"
    sa, sb = (json.loads((Path(d) / "summary.json").read_text()) for d in (a, b))
    assert sa.keys() == sb.keys()
    assert {k: v for k, v in sa.items() if k not in TIMING_KEYS} == {k: v for k, v in sb.items() if k not in TIMING_KEYS}


def read_table(study) -> list[dict]:
    import csv

    with open(Path(study) / "study.csv", newline="") as f:
        return list(csv.DictReader(f))


def folder_snapshot(path: Path) -> dict:
    return {str(p.relative_to(path)): p.stat().st_mtime_ns for p in sorted(path.rglob("*"))} if path.exists() else {}


# ---------------------------------------------------------------- the study, its members, their names
def test_parse_vary_reads_values_as_set_does():
    assert parse_vary(["a.b=0.8,0.9,1", "c=hertz,linear", "d=true,false", "e=[1,2],[3,4]"]) == {
        "a.b": [0.8, 0.9, 1], "c": ["hertz", "linear"], "d": [True, False], "e": [[1, 2], [3, 4]]}
    for bad in (["a.b"], ["a.b="], ["a=1,,2"], ["a=1", "a=2"]):
        with pytest.raises(CaseError):
            parse_vary(bad)


def test_parse_seeds():
    assert parse_seeds("3") == [1, 2, 3]
    assert parse_seeds("7,11") == [7, 11]
    assert parse_seeds(None) is None
    for bad in ("0", "x", "1,1"):
        with pytest.raises(CaseError):
            parse_seeds(bad)


def test_key_labels_are_short_and_unique():
    assert key_labels(["particles.contact.friction", "time.end"]) == {"particles.contact.friction": "friction",
                                                                       "time.end": "end"}
    labels = key_labels(["particles.contact.friction", "particles.pairs.0.friction"])
    assert labels == {"particles.contact.friction": "contact.friction", "particles.pairs.0.friction": "0.friction"}


def test_members_product_zip_and_seeds():
    vary = {"particles.contact.restitution": [0.8, 0.9], "particles.contact.friction": [0, 0.3]}
    study = StudyDefinition.build("pour", vary, seeds=[1, 2], until=0.01)
    names = [m.name for m in study.members()]
    assert names[:3] == ["restitution=0.8_friction=0_seed=1", "restitution=0.8_friction=0_seed=2",
                         "restitution=0.8_friction=0.3_seed=1"]
    assert len(names) == 8
    m = study.members()[1]
    assert m.overrides == {"particles.contact.restitution": 0.8, "particles.contact.friction": 0,
                           "particles.placement.seed": 2}
    case = study.member_case(m.overrides)
    assert case.particles.placement.seed == 2 and case.time.end == 0.01 and case.threads == 1
    zipped = StudyDefinition.build("pour", vary, combine="zip", until=0.01)
    assert [m.name for m in zipped.members()] == ["restitution=0.8_friction=0", "restitution=0.9_friction=0.3"]
    again = StudyDefinition.from_toml(study.to_toml())
    assert again.differences(study) == [] and [m.name for m in again.members()] == names
    other = StudyDefinition.build("pour", {**vary, "particles.contact.friction": [0, 0.1]}, seeds=[1, 2], until=0.01)
    assert any("--vary" in line for line in other.differences(study))


# ---------------------------------------------------------------- a study on a local cluster
@pytest.fixture(scope="module")
def study4(tmp_path_factory):
    """A 2 × 2 study of the pour on a local cluster of two workers, and the same four runs made alone."""
    root = tmp_path_factory.mktemp("sweep")
    rc, _, err = cli(["sweep", "pour", *VARY, "--until", UNTIL, "--threads", "1", "--workers", "2",
                      "--out", root / "study"])
    assert rc == 0, err
    alone = {}
    for e in RESTITUTION:
        for mu in FRICTION:
            name = f"restitution={e}_friction={mu}"
            rc, _, err = cli(["run", "pour", "--until", UNTIL, "--threads", "1", "--quiet", "--out", root / name,
                              "--set", f"particles.contact.restitution={e}", "--set", f"particles.contact.friction={mu}"])
            assert rc == 0, err
            alone[name] = root / name
    return root / "study", alone


def test_members_equal_the_same_runs_made_alone(study4):
    study, alone = study4
    for name, run in alone.items():
        assert (study / name / "case.toml").read_text() == (run / "case.toml").read_text()
        assert_same_run(study / name, run)


def test_study_table_and_definition(study4):
    study, alone = study4
    rows = read_table(study)
    assert [r["member"] for r in rows] == list(alone)
    assert list(rows[0])[:5] == ["member", "particles.contact.restitution", "particles.contact.friction", "status",
                                 "error"]
    summary = json.loads((study / rows[0]["member"] / "summary.json").read_text())
    for row in rows:
        assert row["status"] == "completed" and row["error"] == ""
        assert float(row["sim_time_s"]) == pytest.approx(float(UNTIL), abs=1e-4)
    assert {k for k, v in summary.items() if not isinstance(v, (list, dict))} - {"status"} <= set(rows[0])
    definition = tomllib.loads((study / "study.toml").read_text())
    assert definition["case"] == "pour" and definition["until"] == float(UNTIL)
    assert definition["vary"] == {"particles.contact.restitution": [0.8, 0.9], "particles.contact.friction": [0, 0.3]}
    assert [m["name"] for m in definition["members"]] == list(alone)
    assert not (study / ".stop").exists()


def test_rerun_of_a_finished_study_runs_nothing(study4, capsys):
    study, _ = study4
    before = folder_snapshot(study)
    rc, out, err = cli(["sweep", "pour", *VARY, "--until", UNTIL, "--threads", "1", "--out", study], capsys)
    assert rc == 0, err
    after = folder_snapshot(study)
    assert {k: v for k, v in after.items() if k != "study.csv"} == {k: v for k, v in before.items() if k != "study.csv"}
    assert out.splitlines()[0].startswith("member,")


# ---------------------------------------------------------------- figures and report of a study
def test_plot_and_report_of_a_study(study4, tmp_path, capsys):
    pytest.importorskip("matplotlib")
    study, _ = study4
    rc, out, err = cli(["plot", study, "--out", tmp_path / "figures"], capsys)
    assert rc == 0, err
    written = [Path(p) for p in out.split()]
    assert tmp_path / "figures" / "study_mean_bed_height_m.png" in written
    assert all(p.stat().st_size > 0 for p in written)
    rc, out, err = cli(["report", study, "--out", tmp_path / "report.html"], capsys)
    assert rc == 0, err
    page = (tmp_path / "report.html").read_text()
    assert "restitution=0.9_friction=0.3" in page and page.count("data:image/png;base64,") >= 1
    assert "http://" not in page and "https://" not in page


# ---------------------------------------------------------------- a failing member
def test_a_failing_member_is_recorded_and_the_others_finish(tmp_path, capsys):
    # 20,000 particles do not fit the pour's box: the schema takes the count, the placement refuses it
    argv = ["sweep", "pour", "--vary", "particles.species.0.count=50,20000", "--until", "0.002", "--workers", "1",
            "--out", tmp_path / "study"]
    rc, out, err = cli(argv, capsys)
    assert rc == 1, err
    rows = {r["member"]: r for r in read_table(tmp_path / "study")}
    assert rows["count=50"]["status"] == "completed"
    assert rows["count=20000"]["status"] == "failed"
    assert "could place only" in rows["count=20000"]["error"]
    assert "failed" in err and "--retry" in err
    summary = json.loads((tmp_path / "study" / "count=20000" / "summary.json").read_text())
    assert summary["status"] == "failed" and "could place only" in summary["error"]
    # a rerun leaves the failed member alone; --retry runs it again
    before = (tmp_path / "study" / "count=20000" / "summary.json").stat().st_mtime_ns
    rc, _, _ = cli(argv, capsys)
    assert rc == 1 and (tmp_path / "study" / "count=20000" / "summary.json").stat().st_mtime_ns == before
    rc, _, _ = cli([*argv, "--retry"], capsys)
    assert rc == 1 and (tmp_path / "study" / "count=20000" / "summary.json").stat().st_mtime_ns != before
    assert read_table(tmp_path / "study")[0]["status"] == "completed"


# ---------------------------------------------------------------- stopped from outside, then resumed
def start_sweep(study: Path, until: str, cwd: Path) -> subprocess.Popen:
    argv = [sys.executable, "-m", "fluidem", "sweep", "pour", "--vary", "particles.contact.restitution=0.7,0.8,0.9",
            "--until", until, "--threads", "1", "--workers", "1", "--out", str(study)]
    return subprocess.Popen(argv, cwd=cwd, env=env(), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def wait_for_first_member(proc, study: Path, timeout: float = 90.0) -> str:
    """The name of the first member to complete, once a second one is running with a checkpoint."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        states = {d.name: member_state(d).status for d in sorted(study.glob("restitution=*"))}
        if "completed" in states.values() and "interrupted" in states.values():
            return next(n for n, s in states.items() if s == "completed")
        if proc.poll() is not None:
            pytest.fail(f"the sweep ended before its first member: {proc.communicate()}")
        time.sleep(0.05)
    proc.kill()
    pytest.fail("no member finished in time")


def killed_while_a_member_runs(tmp_path, until: str, attempts: int = 3):
    """A sweep killed (SIGKILL) once its first member has completed and its second is running with a checkpoint:
    (study, the completed member, every member's state after the kill). The kill can land just after the
    running member ended (it steps for a fraction of a second): then the sweep is started afresh, up to
    ``attempts`` times, so that a member killed while running is there to resume."""
    for attempt in range(attempts):
        study = tmp_path / f"study{attempt}"
        proc = start_sweep(study, until, tmp_path)
        first = wait_for_first_member(proc, study)
        proc.send_signal(signal.SIGKILL)
        proc.communicate(timeout=30)
        time.sleep(1.5)  # the worker processes see their parent gone and exit
        states = {d.name: member_state(d).status for d in study.glob("restitution=*")}
        if "interrupted" in states.values():
            return study, first, states
    pytest.fail(f"in {attempts} sweeps the kill never landed while a member ran: {states}")


def test_killed_sweep_resumes_without_rerunning_finished_members(tmp_path):
    study, first, states = killed_while_a_member_runs(tmp_path, "0.4")
    kept = {p: (study / first / p).stat().st_mtime_ns for p in ("summary.json", "restart.h5", "probes.csv")}
    assert states[first] == "completed" and list(states.values()).count("completed") < 3
    rerun = start_sweep(study, "0.4", tmp_path)
    out, err = rerun.communicate(timeout=120)
    assert rerun.returncode == 0, err
    assert {p: (study / first / p).stat().st_mtime_ns for p in kept} == kept
    rows = read_table(study)
    assert [r["status"] for r in rows] == ["completed"] * 3
    assert out.splitlines()[0].startswith("member,") and len(out.splitlines()) == 4
    # a member killed while running went on from its checkpoint to the run it would have been
    name = next(n for n, s in states.items() if s == "interrupted")
    rc, _, err = cli(["run", "pour", "--until", "0.4", "--threads", "1", "--quiet", "--out", tmp_path / "alone",
                      "--set", f"particles.contact.restitution={name.split('=')[1]}"])
    assert rc == 0, err
    assert_same_run(study / name, tmp_path / "alone")


def test_ctrl_c_stops_the_study_and_keeps_finished_members(tmp_path):
    study = tmp_path / "study"
    # members of 1 s of pour (seconds of wall time each, warm): Ctrl-C lands while the second one runs,
    # where members of 0.1 s all end before the signal on an idle machine
    proc = start_sweep(study, "1.0", tmp_path)
    first = wait_for_first_member(proc, study)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert "interrupted" in err and "continue with the same command" in err
    rows = {r["member"]: r for r in read_table(study)}
    assert rows[first]["status"] == "completed"
    assert all(r["status"] in ("completed", "interrupted", "pending") for r in rows.values())
    for name, r in rows.items():  # a member stopped while running wrote its checkpoint and says so
        if r["status"] == "interrupted":
            assert json.loads((study / name / "summary.json").read_text())["status"] == "interrupted"
    assert not (study / ".stop").exists()


# ---------------------------------------------------------------- an existing cluster
def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture
def dask_cluster(tmp_path):
    """A ``dask scheduler`` and one ``dask worker`` (one thread) on 127.0.0.1, as subprocesses."""
    from distributed import Client

    port = free_port()
    address = f"tcp://127.0.0.1:{port}"
    logs = [open(tmp_path / name, "w") for name in ("scheduler.log", "worker.log")]
    procs = [subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1",
                               "--port", str(port), "--dashboard-address", ":0", "--no-show"],
                              cwd=tmp_path, env=env(), stdout=logs[0], stderr=subprocess.STDOUT)]
    try:
        procs.append(subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_worker", address, "--nthreads", "1",
                                       "--nworkers", "1", "--no-dashboard"],
                                      cwd=tmp_path, env=env(), stdout=logs[1], stderr=subprocess.STDOUT))
        try:
            with Client(address, timeout=30) as client:
                client.wait_for_workers(1, timeout=60)
        except Exception as err:  # noqa: BLE001
            pytest.skip(f"a local dask scheduler and worker did not start: {err}")
        yield address
    finally:
        for p in reversed(procs):
            p.send_signal(signal.SIGINT)
        for p in reversed(procs):
            try:
                p.wait(timeout=20)
            except subprocess.TimeoutExpired:
                p.kill()
        for f in logs:
            f.close()


def test_sweep_on_an_existing_scheduler(study4, dask_cluster, tmp_path, capsys):
    reference, _ = study4
    rc, out, err = cli(["sweep", "pour", "--vary", "particles.contact.restitution=0.8,0.9", "--set",
                        "particles.contact.friction=0.3", "--until", UNTIL, "--threads", "1",
                        "--scheduler", dask_cluster, "--out", tmp_path / "study"], capsys)
    assert rc == 0, err
    for e in RESTITUTION:
        assert_same_run(tmp_path / "study" / f"restitution={e}", reference / f"restitution={e}_friction=0.3")


# ---------------------------------------------------------------- bad input: exit 2, a message, nothing written
@pytest.mark.parametrize("argv, fragments", [
    (["--vary", "particles.contact.restitutio=0.8,0.9"], ["particles.contact.restitutio", "unknown key", "restitution"]),
    (["--vary", "particles.contact.restitution=0.8,1.5"], ["particles.contact.restitution=1.5", "less than or equal to 1"]),
    (["--vary", "particles.contact.restitution=0.8,0.9", "--scheduler", "tcp://127.0.0.1:9", "--connect-timeout", "1"],
     ["tcp://127.0.0.1:9", "cannot reach"]),
    (["--vary", "particles.contact.restitution=0.8", "--vary", "particles.contact.friction=0,1", "--zip"],
     ["--zip", "particles.contact.friction (2)"]),
    (["--vary", "particles.contact.restitution=0.8,0.9", "--set", "particles.contact.restitution=1.0"],
     ["particles.contact.restitution", "--set"]),
])
def test_bad_input_exits_2_and_writes_nothing(tmp_path, capsys, argv, fragments):
    out_dir = tmp_path / "study"
    rc, out, err = cli(["sweep", "pour", *argv, "--until", "0.001", "--out", out_dir], capsys)
    assert rc == 2, err
    assert "Traceback" not in err
    for fragment in fragments:
        assert fragment in err
    assert not out_dir.exists()


def test_a_member_refused_in_combination_is_named(tmp_path, capsys):
    # each value is fine alone on the base case (sizes 3-6 mm); min 5 mm with max 4.5 mm is not
    case = load_case("pour", {"particles.species.0.size_distribution": {"kind": "uniform", "min": 0.003, "max": 0.006}})
    (tmp_path / "sized.toml").write_text(case.to_toml())
    rc, _, err = cli(["sweep", tmp_path / "sized.toml", "--vary", "particles.species.0.size_distribution.min=0.0035,0.005",
                      "--vary", "particles.species.0.size_distribution.max=0.0045,0.006",
                      "--until", "0.001", "--out", tmp_path / "study"], capsys)
    assert rc == 2
    assert "member min=0.005_max=0.0045" in err and "exceeds max" in err
    assert "member min=0.0035" not in err
    assert not (tmp_path / "study").exists()


def test_a_different_study_into_the_same_folder_is_refused(study4, capsys):
    study, _ = study4
    before = folder_snapshot(study)
    rc, _, err = cli(["sweep", "pour", "--vary", "particles.contact.restitution=0.8,0.95", "--until", UNTIL,
                      "--out", study], capsys)
    assert rc == 2
    assert "holds a different study" in err and "--vary" in err and "0.8,0.95 now" in err
    assert folder_snapshot(study) == before


def test_a_folder_that_is_not_a_study_is_refused(tmp_path, capsys):
    (tmp_path / "study").mkdir()
    (tmp_path / "study" / "notes.txt").write_text("mine")
    rc, _, err = cli(["sweep", "pour", "--vary", "particles.contact.restitution=0.8,0.9", "--until", "0.001",
                      "--out", tmp_path / "study"], capsys)
    assert rc == 2 and "holds no study" in err
    assert sorted(p.name for p in (tmp_path / "study").iterdir()) == ["notes.txt"]


# ---------------------------------------------------------------- Python
def test_python_api_returns_the_table(study4):
    pd = pytest.importorskip("pandas")
    import fluidem

    study, _ = study4
    frame = fluidem.sweep("pour", vary={"particles.contact.restitution": [0.8, 0.9],
                                        "particles.contact.friction": [0, 0.3]},
                          until=float(UNTIL), threads=1, out=study)  # all done: reads the table back
    assert isinstance(frame, pd.DataFrame) and len(frame) == 4
    assert (frame["status"] == "completed").all()
    assert frame["particles.contact.restitution"].tolist() == [0.8, 0.8, 0.9, 0.9]
    assert load_case("pour").particles.placement.seed == 1996  # the case's own seed when --seeds is not given


def test_the_test_and_sweep_extras_bring_dask_and_pandas():
    project = tomllib.loads((SRC.parent / "pyproject.toml").read_text())["project"]
    for extra in ("test", "sweep"):
        names = {r.split(">")[0].split("=")[0].strip() for r in project["optional-dependencies"][extra]}
        assert {"dask[distributed]", "pandas"} <= names, extra
