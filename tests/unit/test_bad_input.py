"""Bad input of ``fluidem run``: each is refused before the run directory exists, with exit status 2 and
one message that names the key (or file), the value and what is allowed; no traceback, nothing written.

Most tests call ``fluidem.cli.main`` in-process and only validate (no step is taken); the thread-count
test runs the pour for one millisecond, and the resume tests make one short run to resume.
"""
from __future__ import annotations

import hashlib
import subprocess
import sys
import traceback
from importlib import resources
from pathlib import Path

import numba
import pytest

from fluidem.cli import main

POUR_TOML = (resources.files("fluidem") / "cases" / "pour.toml").read_text()


@pytest.fixture(autouse=True)
def _keep_threads():
    before = numba.get_num_threads()
    yield
    numba.set_num_threads(before)


def cli(argv, capsys):
    """``fluidem ARGV`` in-process: (exit status, stdout, stderr); an escaping exception is a crash
    (status 1) with its traceback in stderr, as the console script would show it."""
    try:
        rc = main([str(a) for a in argv])
    except SystemExit as exc:
        rc = exc.code
    except Exception:  # noqa: BLE001 - the test inspects it
        out, err = capsys.readouterr()
        return 1, out, err + traceback.format_exc()
    out, err = capsys.readouterr()
    return rc, out, err


def refused(argv, capsys, tmp_path, fragments):
    """Run ``fluidem run ARGV --out tmp_path/run``; assert exit 2, one error message holding every fragment,
    no traceback and no run directory. Returns the message."""
    out_dir = tmp_path / "run"
    rc, out, err = cli(["run", *argv, "--out", out_dir], capsys)
    assert rc == 2, f"exit status {rc}, stderr:\n{err}"
    assert "Traceback" not in err
    text = err.strip()
    assert text.startswith("fluidem: error:"), text
    for frag in fragments:
        assert frag in text, f"{frag!r} not in message:\n{text}"
    assert out == ""
    assert not out_dir.exists(), f"{out_dir} was created: {sorted(p.name for p in out_dir.iterdir())}"
    return text


def pour_file(tmp_path, old=None, new=None, name="case.toml"):
    """The pour case as a TOML file in ``tmp_path``, with ``old`` replaced by ``new``."""
    text = POUR_TOML if old is None else POUR_TOML.replace(old, new)
    assert old is None or text != POUR_TOML
    path = tmp_path / name
    path.write_text(text)
    return path


def file_case(tmp_path, rows, count, header="x,y,z,diameter,vx,vy,vz"):
    """A 2D case whose ``count`` particles come from a CSV of ``rows`` (strings, comma separated)."""
    csv = tmp_path / "particles.csv"
    csv.write_text(header + "\n" + "".join(r + "\n" for r in rows))
    toml = tmp_path / "filecase.toml"
    toml.write_text(f"""
name = "filecase"
[particles]
dimensions = 2
[[particles.species]]
diameter = 0.004
density = 2700.0
count = {count}
[particles.contact]
model = "linear_spring_dashpot"
stiffness = 800.0
[particles.placement]
method = "file"
file = "particles.csv"
[[walls]]
name = "box"
kind = "box"
lower = [0.0, 0.0, 0.0]
upper = [0.05, 0.05, 0.004]
[time]
end = 0.01
""")
    return toml, csv


ROWS = ["0.010,0.010,0.002,0.004,0.0,0.0,0.0",
        "0.020,0.010,0.002,0.004,0.0,0.0,0.0",
        "0.030,0.010,0.002,0.004,0.0,0.0,0.0"]


def tree_digest(folder: Path) -> dict:
    """Name → (size, mtime, sha256) of every file under ``folder``."""
    return {str(p.relative_to(folder)): (p.stat().st_size, p.stat().st_mtime_ns,
                                         hashlib.sha256(p.read_bytes()).hexdigest())
            for p in sorted(folder.rglob("*")) if p.is_file()}


# ---------------------------------------------------------------- 1. infinite end time
def test_infinite_end_time_in_a_case_file(tmp_path, capsys):
    toml = pour_file(tmp_path, "end = 1.5", "end = inf")
    refused([toml], capsys, tmp_path, ["time.end", "inf", "finite"])


def test_infinite_until(tmp_path, capsys):
    refused(["pour", "--until", "inf"], capsys, tmp_path, ["--until", "inf", "finite positive"])


@pytest.mark.parametrize("value", ["nan", "0", "-1"])
def test_until_must_be_a_positive_number(tmp_path, capsys, value):
    refused(["pour", "--until", value], capsys, tmp_path, ["--until", value, "finite positive"])


# ---------------------------------------------------------------- 2. a species without particles
def test_species_count_zero(tmp_path, capsys):
    refused(["pour", "--until", "0.01", "--set", "particles.species.0.count=0"], capsys, tmp_path,
            ["particles.species.0.count = 0", "no inlet feeds it", "count >= 1"])


# ---------------------------------------------------------------- 3. unreadable case files
def test_binary_case_file(tmp_path, capsys):
    bad = tmp_path / "garbage.toml"
    bad.write_bytes(b"\x00\xff\xfe\x89PNG\r\n\x1a\n garbage")
    refused([bad], capsys, tmp_path, [str(bad), "not a text (UTF-8) file", "0xff", "line 1"])


def test_case_path_that_is_a_folder(tmp_path, capsys):
    folder = tmp_path / "cases"
    folder.mkdir()
    refused([folder], capsys, tmp_path, [str(folder), "is a folder", "TOML"])


def test_toml_syntax_error_names_the_file_and_line(tmp_path, capsys):
    toml = pour_file(tmp_path, "[particles.contact]", "[particles.contact")
    line = POUR_TOML.splitlines().index("[particles.contact]") + 1
    refused([toml], capsys, tmp_path, [str(toml), "not valid TOML", f"line {line}"])


def test_binary_case_file_in_a_real_process(tmp_path):
    bad = tmp_path / "garbage.toml"
    bad.write_bytes(bytes(range(256)))
    res = subprocess.run([sys.executable, "-m", "fluidem", "run", str(bad), "--out", str(tmp_path / "run")],
                         capture_output=True, text=True, timeout=120)
    assert res.returncode == 2, res.stderr
    assert "Traceback" not in res.stderr and str(bad) in res.stderr and "UTF-8" in res.stderr
    assert not (tmp_path / "run").exists()


# ---------------------------------------------------------------- 4. non-finite numbers
@pytest.mark.parametrize("setting, key, value", [
    ("gravity=[0.0, nan, 0.0]", "gravity.1", "nan"),
    ("gravity=[0.0, -inf, 0.0]", "gravity.1", "-inf"),
    ("particles.contact.friction=inf", "particles.contact.friction", "inf"),
    ("particles.species.0.diameter=nan", "particles.species.0.diameter", "nan"),
    ("particles.placement.velocity=[0.0, inf, 0.0]", "particles.placement.velocity.1", "inf"),
    ("walls.0.upper=[0.096, inf, 0.004]", "walls.0.upper.1", "inf"),
])
def test_non_finite_number_in_the_case(tmp_path, capsys, setting, key, value):
    refused(["pour", "--until", "0.01", "--set", setting], capsys, tmp_path,
            [f"{key} = {value}", "must be a finite number"])


def test_non_finite_gas_initial_velocity(tmp_path, capsys):
    refused(["goldschmidt", "--until", "0.01", "--set", "gas.initial_velocity=[0, inf]"], capsys, tmp_path,
            ["gas.initial_velocity.1 = inf", "must be a finite number"])


def test_non_finite_number_in_a_case_file(tmp_path, capsys):
    toml = pour_file(tmp_path, "friction = 0.3", "friction = nan")
    refused([toml], capsys, tmp_path, ["particles.contact.friction = nan", "must be a finite number"])


@pytest.mark.parametrize("row, column, value", [
    ("0.020,0.010,0.002,0.004,0.0,nan,0.0", "vy", "nan"),
    ("0.020,nan,0.002,0.004,0.0,0.0,0.0", "y", "nan"),
    ("0.020,,0.002,0.004,0.0,0.0,0.0", "y", "nan (an empty cell reads as nan)"),
    ("0.020,0.010,0.002,inf,0.0,0.0,0.0", "diameter", "inf"),
    ("0.020,0.010,0.002,0.004,-inf,0.0,0.0", "vx", "-inf"),
])
def test_non_finite_number_in_a_placement_file(tmp_path, capsys, row, column, value):
    toml, csv = file_case(tmp_path, [ROWS[0], row, ROWS[2]], 3)
    refused([toml], capsys, tmp_path, [str(csv), f"column {column!r}", "row 1 (line 3)", value, "finite"])


def test_text_in_a_number_column_of_a_placement_file(tmp_path, capsys):
    toml, csv = file_case(tmp_path, [ROWS[0], "0.020,abc,0.002,0.004,0.0,0.0,0.0", ROWS[2]], 3)
    refused([toml], capsys, tmp_path, [str(csv), "column 'y'", "row 1 (line 3)", "'abc' is not a number"])


# ---------------------------------------------------------------- 5. placement file against the counts
@pytest.mark.parametrize("count", [2, 10])
def test_placement_file_rows_must_match_the_count(tmp_path, capsys, count):
    toml, csv = file_case(tmp_path, ROWS, count)
    refused([toml], capsys, tmp_path, [str(csv), "3 rows", f"particles.species.0.count = {count}"])


def test_placement_file_rows_per_species(tmp_path, capsys):
    toml, csv = file_case(tmp_path, [r.replace("0.004,", "0.004,a,", 1) for r in ROWS[:2]]
                          + [ROWS[2].replace("0.004,", "0.004,b,", 1)], 2,
                          header="x,y,z,diameter,species,vx,vy,vz")
    toml.write_text(toml.read_text().replace(
        "[[particles.species]]\ndiameter = 0.004\ndensity = 2700.0\ncount = 2",
        "[[particles.species]]\nname = \"a\"\ndiameter = 0.004\ndensity = 2700.0\ncount = 1\n"
        "[[particles.species]]\nname = \"b\"\ndiameter = 0.004\ndensity = 2700.0\ncount = 1"))
    refused([toml], capsys, tmp_path, [str(csv), "2 rows of species 'a'", "particles.species.0.count = 1"])


def test_placement_file_without_rows(tmp_path, capsys):
    toml, csv = file_case(tmp_path, [], 1)
    refused([toml], capsys, tmp_path, [str(csv), "no particle rows"])


# ---------------------------------------------------------------- 6. gas grid against the particle box
def test_gas_grid_narrower_than_the_particle_box(tmp_path, capsys):
    refused(["goldschmidt", "--until", "0.01", "--set", "gas.grid.size=[0.10,0.45]"], capsys, tmp_path,
            ["gas.grid.size = [0.1, 0.45]", "walls.0", "upper = [0.15, 0.45, 0.0025]", "x from 0 to 0.15 m",
             "0 to 0.1 m"])


def test_gas_grid_depth_other_than_the_box_depth(tmp_path, capsys):
    refused(["goldschmidt", "--until", "0.01", "--set", "gas.grid.depth=0.004"], capsys, tmp_path,
            ["gas.grid.depth = 0.004", "walls.0", "0.0025", "must be equal"])


def test_placement_region_outside_the_gas_grid(tmp_path, capsys):
    refused(["tsuji-jet", "--until", "0.01", "--set", "particles.placement.region_upper=[0.15,0.95,0.002]"],
            capsys, tmp_path, ["particles.placement.region_upper = [0.15, 0.95, 0.002]", "gas.grid.size",
                               "y from 0 to 0.95 m", "0 to 0.9 m"])


# ---------------------------------------------------------------- 7. more threads than cores
def test_more_threads_than_cores_runs_on_the_cores_and_says_so(tmp_path, capsys, monkeypatch):
    """One core as far as Numba knows (so that the run is short and the test means the same on any machine)."""
    monkeypatch.setattr(numba.config, "NUMBA_NUM_THREADS", 1)
    out_dir = tmp_path / "run"
    rc, out, err = cli(["run", "pour", "--until", "0.001", "--threads", "64", "--quiet", "--out", out_dir], capsys)
    assert rc == 0, err
    assert "WARNING: 64 threads asked, 1 core: using 1" in err
    assert '"status": "completed"' in out
    assert numba.get_num_threads() == 1


def test_threads_below_one(tmp_path, capsys):
    refused(["pour", "--threads", "0"], capsys, tmp_path, ["--threads 0", "at least 1"])


# ---------------------------------------------------------------- 8. resume to a time already reached
@pytest.fixture(scope="module")
def finished_run(tmp_path_factory):
    run = tmp_path_factory.mktemp("resume") / "run"
    assert main(["run", "pour", "--until", "0.002", "--threads", "1", "--quiet", "--out", str(run)]) == 0
    return run


@pytest.mark.parametrize("until", ["0.002", "0.001"])
def test_resume_until_a_time_already_reached(finished_run, capsys, until):
    before = tree_digest(finished_run)
    rc, out, err = cli(["run", "--resume", finished_run, "--until", until], capsys)
    assert rc == 2, err
    assert "Traceback" not in err and out == ""
    assert str(finished_run) in err and "already at t = 0.002" in err and f"--until {until}" in err
    assert "ETA" not in err
    assert tree_digest(finished_run) == before


def test_resume_of_a_finished_run_without_until(finished_run, capsys):
    """The run went to 0.002 s, its case.toml says time.end = 0.002 s: nothing is left to run."""
    before = tree_digest(finished_run)
    rc, out, err = cli(["run", "--resume", finished_run], capsys)
    assert rc == 2, err
    assert "already at t = 0.002" in err and "time.end = 0.002" in err and "later --until" in err
    assert tree_digest(finished_run) == before


def test_resume_until_infinity(finished_run, capsys):
    before = tree_digest(finished_run)
    rc, out, err = cli(["run", "--resume", finished_run, "--until", "inf"], capsys)
    assert rc == 2 and "--until inf" in err and "Traceback" not in err
    assert tree_digest(finished_run) == before


def test_resume_with_an_unreadable_case_toml(tmp_path, capsys):
    run = tmp_path / "run"
    run.mkdir()
    (run / "case.toml").write_bytes(b"\xff\xfe not toml")
    before = tree_digest(run)
    rc, out, err = cli(["run", "--resume", run], capsys)
    assert rc == 2 and "case.toml: not a text file" in err and "Traceback" not in err
    assert tree_digest(run) == before
