"""Checkpoint recovery: ``restart.h5`` (newest) and ``restart.prev.h5`` (the one before) in a run directory.

A damaged or missing newest checkpoint resumes from the previous one with a warning, and the run ends bit
for bit where an uninterrupted run ends, with the same output rows; two unusable checkpoints, or an unusable
``case.toml``, are one clear error (exit 2) that changes nothing in the folder; a run killed (SIGKILL) after
its checkpoint at t = 0 resumes with t = 0 once in every output; a failed checkpoint write (a full disk)
leaves both checkpoints as they were.

Runs are short ``pour`` runs (500 soft spheres, no gas) in-process, and ``tsuji-jet-background`` (coupled) runs of a few
milliseconds of simulated time.
"""
from __future__ import annotations

import csv
import hashlib
import os
import shutil
import signal
import subprocess
import sys
import time
import traceback
from pathlib import Path

import h5py
import numpy as np
import pytest

from fluidem.cli import main
from fluidem.io.restart import PREVIOUS_RESTART_NAME, RESTART_NAME, load_restart

COMMON = ["--threads", "1", "--quiet"]
POUR_STOP, POUR_END = "0.01", "0.02"  # [s]: checkpoints every 1 ms (time.end / 10) to the stop


@pytest.fixture(autouse=True, scope="module")
def _restore_numba_threads():
    """In-process runs with --threads 1 change Numba's thread count; give later test modules it back."""
    import numba

    before = numba.get_num_threads()
    yield
    numba.set_num_threads(before)


def cli(argv, capsys):
    """``fluidem ARGV`` in-process: (exit status, stdout, stderr); an escaping exception is a crash (1)."""
    try:
        rc = main([str(a) for a in argv])
    except SystemExit as exc:
        rc = exc.code
    except Exception:  # noqa: BLE001 - the test inspects it
        out, err = capsys.readouterr()
        return 1, out, err + traceback.format_exc()
    out, err = capsys.readouterr()
    return rc, out, err


def step_of(path) -> int:
    return int(load_restart(path)[1]["steps"])


def assert_checkpoints_bitwise_equal(a, b):
    """Every array of the newest checkpoints of run directories ``a`` and ``b`` is equal, bit for bit."""
    arrays_a, scalars_a, _ = load_restart(Path(a) / RESTART_NAME)
    arrays_b, scalars_b, _ = load_restart(Path(b) / RESTART_NAME)
    assert scalars_a["steps"] == scalars_b["steps"]
    assert sorted(arrays_a) == sorted(arrays_b)
    for k in arrays_a:
        assert np.array_equal(arrays_a[k], arrays_b[k]), f"{k} differs between {a} and {b}"


def probe_steps(run_dir) -> list[int]:
    with open(Path(run_dir) / "probes.csv", newline="") as f:
        return [int(r["step"]) for r in csv.DictReader(f)]


def snapshot_times(path) -> list[float]:
    with h5py.File(path, "r") as f:
        return [float(f["snapshots"][k].attrs["time"]) for k in sorted(f["snapshots"])]


def xdmf_times(path) -> list[str]:
    return [line.strip() for line in Path(path).read_text().splitlines() if "<Time " in line]


def folder_digest(folder) -> dict[str, str]:
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in sorted(Path(folder).iterdir())}


def assert_outputs_as_reference(run_dir, ref):
    """probes.csv, the snapshot times and the XDMF index as those of the uninterrupted run: no row twice,
    none missing."""
    assert (Path(run_dir) / "probes.csv").read_text() == (Path(ref) / "probes.csv").read_text()
    assert snapshot_times(Path(run_dir) / "particles.h5") == snapshot_times(Path(ref) / "particles.h5")
    assert (Path(run_dir) / "particles.xdmf").read_text() == (Path(ref) / "particles.xdmf").read_text()


# ---------------------------------------------------------------- damage
def truncate(path: Path) -> str:
    with open(path, "r+b") as f:
        f.truncate(path.stat().st_size // 2)
    return "truncated"


def zero_bytes(path: Path) -> str:
    path.write_bytes(b"")
    return "empty (0 bytes)"


def not_hdf5(path: Path) -> str:
    path.write_bytes(b"these are not the bytes of an HDF5 file\n" * 10)
    return "not an HDF5 file"


def missing_file(path: Path) -> str:
    path.unlink()  # as after a crash between the two renames of a checkpoint write
    return "missing"


def missing_array(path: Path) -> str:
    """An array the engine needs is absent (a file of a writer without checksums: the engine notices)."""
    with h5py.File(path, "a") as f:
        del f["engine/hist"]
        del f.attrs["checksums"]
    return "lacks the array 'engine/hist'"


def flipped_value(path: Path) -> str:
    """A value changed in place: the file is valid HDF5, the checksum tells."""
    with h5py.File(path, "a") as f:
        f["state/position"][0, 0] += 1e-3
    return "does not match its checksum"


DAMAGE = [truncate, zero_bytes, not_hdf5, missing_file, missing_array, flipped_value]


# ---------------------------------------------------------------- pour runs
@pytest.fixture(scope="module")
def pour_runs(tmp_path_factory):
    """(reference run to POUR_END, run to POUR_STOP with both checkpoints), made once for this module."""
    base = tmp_path_factory.mktemp("recovery")
    ref, stopped = base / "ref", base / "stopped"
    assert main(["run", "pour", "--until", POUR_END, "--out", str(ref), *COMMON]) == 0
    assert main(["run", "pour", "--until", POUR_STOP, "--out", str(stopped), *COMMON]) == 0
    return ref, stopped


def test_a_run_keeps_the_previous_checkpoint(pour_runs):
    _, stopped = pour_runs
    newest, previous = stopped / RESTART_NAME, stopped / PREVIOUS_RESTART_NAME
    assert previous.exists()
    # the checkpoint at the end of the run (the same step as the last periodic one, or later) keeps an older one
    assert 0 < step_of(previous) < step_of(newest)
    assert not [p for p in stopped.iterdir() if p.name.endswith(".tmp")]


@pytest.mark.parametrize("damage", DAMAGE, ids=lambda f: f.__name__)
def test_damaged_newest_checkpoint_resumes_from_the_previous(pour_runs, tmp_path, capsys, damage):
    ref, stopped = pour_runs
    run_dir = tmp_path / "run"
    shutil.copytree(stopped, run_dir)
    previous_step = step_of(run_dir / PREVIOUS_RESTART_NAME)
    what = damage(run_dir / RESTART_NAME)

    rc, _, err = cli(["run", "--resume", run_dir, "--until", POUR_END, "--quiet"], capsys)
    assert rc == 0, err
    assert "Traceback" not in err
    warning = [line for line in err.splitlines() if line.startswith("WARNING:")]
    assert len(warning) == 1, err
    assert str(run_dir / RESTART_NAME) in warning[0] and what in warning[0]
    assert str(run_dir / PREVIOUS_RESTART_NAME) in warning[0]
    assert f"step {previous_step})" in warning[0] and "t = " in warning[0]

    assert_checkpoints_bitwise_equal(ref, run_dir)
    assert_outputs_as_reference(run_dir, ref)
    # the damaged file is gone: both checkpoints are usable again, the previous one older
    assert step_of(run_dir / PREVIOUS_RESTART_NAME) < step_of(run_dir / RESTART_NAME)


@pytest.mark.parametrize("newest, previous", [(truncate, zero_bytes), (not_hdf5, missing_file),
                                              (flipped_value, missing_array)], ids=lambda f: f.__name__)
def test_both_checkpoints_unusable_is_a_clear_error(pour_runs, tmp_path, capsys, newest, previous):
    _, stopped = pour_runs
    run_dir = tmp_path / "run"
    shutil.copytree(stopped, run_dir)
    what_newest = newest(run_dir / RESTART_NAME)
    what_previous = previous(run_dir / PREVIOUS_RESTART_NAME)
    before = folder_digest(run_dir)

    rc, out, err = cli(["run", "--resume", run_dir, "--until", POUR_END, "--quiet"], capsys)
    assert rc == 2, err
    assert out == "" and "Traceback" not in err
    assert err.startswith("fluidem: error:") and len(err.strip().splitlines()) == 1, err
    assert str(run_dir / RESTART_NAME) in err and what_newest in err
    assert str(run_dir / PREVIOUS_RESTART_NAME) in err and what_previous in err
    assert "no usable checkpoint" in err
    assert folder_digest(run_dir) == before, "the failed resume changed the run directory"


def test_no_checkpoint_at_all_is_a_clear_error(pour_runs, tmp_path, capsys):
    _, stopped = pour_runs
    run_dir = tmp_path / "run"
    shutil.copytree(stopped, run_dir)
    (run_dir / RESTART_NAME).unlink()
    (run_dir / PREVIOUS_RESTART_NAME).unlink()
    before = folder_digest(run_dir)
    rc, _, err = cli(["run", "--resume", run_dir, "--quiet"], capsys)
    assert rc == 2 and "Traceback" not in err
    assert "no checkpoint" in err and RESTART_NAME in err and PREVIOUS_RESTART_NAME in err
    assert folder_digest(run_dir) == before


@pytest.mark.parametrize("content, what", [
    (b"\xff\xfe\x00\x81garbage\x00", "not a text file"),
    (b"[particles\ncount = 3\n", "not valid TOML"),
    (b"name = 'x'\nunknown_key = 1\n", "not a valid case"),
], ids=["garbage-bytes", "invalid-toml", "invalid-case"])
def test_corrupt_case_toml_is_a_clear_error(pour_runs, tmp_path, capsys, content, what):
    _, stopped = pour_runs
    run_dir = tmp_path / "run"
    shutil.copytree(stopped, run_dir)
    (run_dir / "case.toml").write_bytes(content)
    before = folder_digest(run_dir)
    rc, out, err = cli(["run", "--resume", run_dir, "--quiet"], capsys)
    assert rc == 2, err
    assert out == "" and "Traceback" not in err and err.startswith("fluidem: error:")
    assert str(run_dir / "case.toml") in err and what in err
    assert folder_digest(run_dir) == before


def test_full_disk_during_a_checkpoint_keeps_both_checkpoints(pour_runs, tmp_path, capsys, monkeypatch):
    """A checkpoint write that fails (no space left) changes neither checkpoint and leaves no temporary file;
    the run then resumes from the newest and ends as the uninterrupted run."""
    ref, stopped = pour_runs
    run_dir = tmp_path / "run"
    shutil.copytree(stopped, run_dir)
    before = {name: (run_dir / name).read_bytes() for name in (RESTART_NAME, PREVIOUS_RESTART_NAME)}

    real_create = h5py.Group.create_dataset

    def full_disk(group, name, *args, **kw):  # the disk fills up while the new checkpoint is written
        if Path(group.file.filename).name == RESTART_NAME + ".tmp" and name.startswith("engine/"):
            raise OSError(28, "No space left on device")
        return real_create(group, name, *args, **kw)

    monkeypatch.setattr(h5py.Group, "create_dataset", full_disk)
    rc, _, err = cli(["run", "--resume", run_dir, "--until", POUR_END, "--quiet"], capsys)
    assert rc != 0 and "No space left on device" in err and "Traceback" not in err
    for name, data in before.items():
        assert (run_dir / name).read_bytes() == data, f"{name} changed by a failed checkpoint write"
    assert not [p for p in run_dir.iterdir() if p.name.endswith(".tmp")]

    monkeypatch.undo()
    rc, _, err = cli(["run", "--resume", run_dir, "--until", POUR_END, "--quiet"], capsys)
    assert rc == 0, err
    assert "WARNING" not in err
    assert_checkpoints_bitwise_equal(ref, run_dir)
    assert_outputs_as_reference(run_dir, ref)


# ---------------------------------------------------------------- SIGKILL before the first periodic checkpoint
def kill_after_first_checkpoint(run_dir: Path, argv: list[str], rows: int = 4) -> None:
    """Start ``fluidem run ARGV --out RUN_DIR`` in a process and SIGKILL it once its checkpoint at t = 0
    exists and probes.csv has ``rows`` lines (the header included)."""
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    proc = subprocess.Popen([sys.executable, "-m", "fluidem", "run", *argv, "--out", str(run_dir), *COMMON],
                            env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 120
        probes = run_dir / "probes.csv"
        while time.monotonic() < deadline and proc.poll() is None:
            if (run_dir / RESTART_NAME).exists() and probes.exists() and len(probes.read_text().splitlines()) >= rows:
                break
            time.sleep(0.002)
        assert proc.poll() is None, f"the run ended before it could be killed: {proc.stderr.read()}"
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        proc.stderr.close()
    assert step_of(run_dir / RESTART_NAME) == 0, "killed after a later checkpoint; the test needs the one at t = 0"


def test_kill_before_the_first_periodic_checkpoint_writes_t0_once(tmp_path, capsys):
    argv = ["pour", "--until", "0.05", "--set", "output.checkpoint_interval=1.0",
            "--set", "output.probe_interval=0.0005", "--set", "output.snapshot_interval=0.002"]
    run_dir, ref = tmp_path / "killed", tmp_path / "ref"
    kill_after_first_checkpoint(run_dir, argv)
    rc, _, err = cli(["run", "--resume", run_dir, "--quiet"], capsys)
    assert rc == 0, err
    steps = probe_steps(run_dir)
    assert steps.count(0) == 1 and len(steps) == len(set(steps))
    times = snapshot_times(run_dir / "particles.h5")
    assert times.count(0.0) == 1 and len(times) == len(set(times))
    assert xdmf_times(run_dir / "particles.xdmf").count('<Time Value="0"/>') == 1

    assert cli(["run", *argv, "--out", ref, *COMMON], capsys)[0] == 0
    assert_checkpoints_bitwise_equal(ref, run_dir)
    assert_outputs_as_reference(run_dir, ref)


# ---------------------------------------------------------------- a coupled case
TSUJI = ["tsuji-jet-background", "--set", "output.probe_interval=0.0002", "--set", "output.snapshot_interval=0.0005"]


def test_coupled_kill_before_the_first_periodic_checkpoint_writes_t0_once(tmp_path, capsys):
    argv = [*TSUJI, "--until", "0.005", "--set", "output.checkpoint_interval=1.0"]
    run_dir, ref = tmp_path / "killed", tmp_path / "ref"
    kill_after_first_checkpoint(run_dir, argv, rows=3)
    rc, _, err = cli(["run", "--resume", run_dir, "--quiet"], capsys)
    assert rc == 0, err
    assert probe_steps(run_dir).count(0) == 1
    for name in ("particles.h5", "gas.h5"):
        times = snapshot_times(run_dir / name)
        assert times.count(0.0) == 1 and len(times) == len(set(times)), name
    for name in ("particles.xdmf", "gas.xdmf"):
        assert xdmf_times(run_dir / name).count('<Time Value="0"/>') == 1, name

    assert cli(["run", *argv, "--out", ref, *COMMON], capsys)[0] == 0
    assert_checkpoints_bitwise_equal(ref, run_dir)
    assert_outputs_as_reference(run_dir, ref)
    assert snapshot_times(run_dir / "gas.h5") == snapshot_times(ref / "gas.h5")
    assert (run_dir / "gas.xdmf").read_text() == (ref / "gas.xdmf").read_text()


def test_coupled_checkpoint_without_gas_arrays_resumes_from_the_previous(tmp_path, capsys):
    """A newest checkpoint without the gas arrays a coupled case needs (``gas/p``): the previous one is used,
    and the gas outputs are cut back to its step."""
    setup = [*TSUJI, "--set", "output.checkpoint_interval=0.001"]
    run_dir, ref = tmp_path / "run", tmp_path / "ref"
    assert cli(["run", *setup, "--until", "0.003", "--out", run_dir, *COMMON], capsys)[0] == 0
    with h5py.File(run_dir / RESTART_NAME, "a") as f:
        for k in [k for k in f["gas"]]:
            del f[f"gas/{k}"]
        del f.attrs["checksums"]
    rc, _, err = cli(["run", "--resume", run_dir, "--until", "0.005", "--quiet"], capsys)
    assert rc == 0, err
    assert "lacks the array 'gas/" in err and PREVIOUS_RESTART_NAME in err and "run without gas" in err

    assert cli(["run", *setup, "--until", "0.005", "--out", ref, *COMMON], capsys)[0] == 0
    assert_checkpoints_bitwise_equal(ref, run_dir)
    assert (run_dir / "probes.csv").read_text() == (ref / "probes.csv").read_text()
    assert snapshot_times(run_dir / "gas.h5") == snapshot_times(ref / "gas.h5")
    assert (run_dir / "gas.xdmf").read_text() == (ref / "gas.xdmf").read_text()
