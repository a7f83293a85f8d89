"""The command line's global flags and its logging: ``--quiet``/``--verbose`` before or after the
subcommand, the wording of each level on stderr, the command's result alone on stdout, and the
``fluidem`` logger left as it was found once a command returns.
"""
from __future__ import annotations

import io
import json
import logging
from contextlib import redirect_stderr

import pytest

import fluidem.cli as cli
from fluidem import _log
from fluidem.cli import main


@pytest.fixture(autouse=True, scope="module")
def _restore_numba_threads():
    """In-process runs with --threads 1 change Numba's thread count; give later test modules it back."""
    import numba

    before = numba.get_num_threads()
    yield
    numba.set_num_threads(before)


def _talking_command(args) -> int:
    """A stand-in for ``fluidem cases``: one record at each level, through the package's loggers, and
    its result on stdout."""
    logging.getLogger("fluidem.progress").debug("debug record")
    logging.getLogger("fluidem.progress").info("t = 0.5000 / 1.0000 s")
    logging.getLogger("fluidem.cli").info("a note")
    logging.getLogger("fluidem.io").warning("a warning")
    print("the result")
    return 0


@pytest.fixture
def talking(monkeypatch):
    monkeypatch.setattr(cli, "cmd_cases", _talking_command)


def _stderr_lines(capsys, argv) -> tuple[int, str, list[str]]:
    rc = main(argv)
    out, err = capsys.readouterr()
    return rc, out, err.splitlines()


ALL = ["DEBUG: fluidem.progress: debug record", "t = 0.5000 / 1.0000 s", "a note", "WARNING: a warning"]


FLAGS = [
    (["cases"], ALL[1:]),
    (["--quiet", "cases"], ALL[3:]),
    (["cases", "--quiet"], ALL[3:]),
    (["-q", "cases"], ALL[3:]),
    (["cases", "-q"], ALL[3:]),
    (["--verbose", "cases"], ALL),
    (["cases", "--verbose"], ALL),
    (["-v", "cases"], ALL),
]


@pytest.mark.parametrize("argv, shown", FLAGS, ids=[" ".join(argv) for argv, _ in FLAGS])
def test_levels_shown_for_each_flag(talking, capsys, argv, shown):
    rc, out, err = _stderr_lines(capsys, argv)
    assert rc == 0
    assert out == "the result\n"  # the result stays on stdout whatever the flags
    if shown is ALL:  # --verbose opens with the versions and the command line
        assert err[0].startswith("DEBUG: fluidem.cli: fluidem ") and err[0].endswith(f"command: {' '.join(argv)}")
        err = err[1:]
    assert err == shown


def test_quiet_and_verbose_exclude_each_other(talking, capsys):
    for argv in (["--quiet", "--verbose", "cases"], ["--quiet", "cases", "--verbose"], ["cases", "-q", "-v"]):
        with pytest.raises(SystemExit) as exc:
            main(argv)
        assert exc.value.code == 2
        assert "--verbose" in capsys.readouterr().err


def test_the_logger_is_left_as_it_was(talking, capsys):
    logger = logging.getLogger("fluidem")
    handlers, level = list(logger.handlers), logger.level
    assert main(["--verbose", "cases"]) == 0
    assert logger.handlers == handlers and logger.level == level
    logging.getLogger("fluidem.cli").warning("after the command")
    assert capsys.readouterr().err.count("WARNING") == 1  # the command's own warning, not this one


def test_records_follow_a_redirected_stderr(talking, capsys):
    """The handler writes to sys.stderr as it is when a record comes (contextlib.redirect_stderr)."""
    buffer = io.StringIO()
    with redirect_stderr(buffer):
        assert main(["cases"]) == 0
    assert buffer.getvalue().splitlines() == ALL[1:]
    assert capsys.readouterr().err == ""


def test_a_command_inside_main_keeps_mains_level(capsys):
    """``command_logging()`` inside ``main``'s block (what the plotting commands do) keeps --quiet."""
    with _log.command_logging(logging.WARNING):
        with _log.command_logging():
            logging.getLogger("fluidem.cli_plot").info("fluidem plot: skipped energy: no probes.csv")
            logging.getLogger("fluidem.cli_plot").warning("kept")
    assert capsys.readouterr().err == "WARNING: kept\n"


@pytest.mark.parametrize("level, text", [
    (logging.DEBUG, "DEBUG: fluidem.gas: message 3"),
    (logging.INFO, "message 3"),
    (logging.WARNING, "WARNING: message 3"),
    (logging.ERROR, "fluidem: error: message 3"),
    (logging.CRITICAL, "fluidem: error: message 3"),
])
def test_formatter_words_each_level(level, text):
    record = logging.LogRecord("fluidem.gas", level, __file__, 1, "message %d", (3,), None)
    assert _log.CommandFormatter().format(record) == text


def test_bad_input_is_an_error_line_even_when_quiet(capsys):
    for argv in (["--quiet", "run", "no-such-case"], ["run", "no-such-case", "--quiet"]):
        rc, out, err = _stderr_lines(capsys, argv)
        assert rc == 2 and out == ""
        assert len(err) == 1 and err[0].startswith("fluidem: error: case 'no-such-case'"), err


# ---------------------------------------------------------------- a real run
def _run(tmp_path, capsys, name, *flags, before=()):
    out_dir = tmp_path / name
    rc = main([*before, "run", "pour", "--until", "0.001", "--out", str(out_dir), "--threads", "1", *flags])
    out, err = capsys.readouterr()
    assert rc == 0, err
    assert json.loads(out)["status"] == "completed"
    return err.splitlines()


def test_run_shows_its_start_and_progress_lines_by_default(tmp_path, capsys):
    err = _run(tmp_path, capsys, "default")
    assert err[0].startswith("fluidem: pour: 500 particles, dt = ")
    assert err[0].endswith(f"1 thread(s) -> {tmp_path / 'default'}")
    assert any(line.startswith("t = 0.0010 / 0.0010 s") for line in err[1:]), err  # the closing progress line
    assert not [line for line in err if line.startswith(("DEBUG", "WARNING"))]


@pytest.mark.parametrize("where", ["after", "before"])
def test_run_quiet_shows_nothing(tmp_path, capsys, where):
    err = _run(tmp_path, capsys, where, *(["--quiet"] if where == "after" else []),
               before=["--quiet"] if where == "before" else [])
    assert err == []


def test_run_verbose_adds_debug_records(tmp_path, capsys):
    import fluidem

    err = _run(tmp_path, capsys, "verbose", "--verbose")
    assert err[0].startswith(f"DEBUG: fluidem.cli: fluidem {fluidem.__version__}, Python ")
    assert any(line.startswith("fluidem: pour: 500 particles") for line in err)
    assert any(line.startswith("t = 0.0010 / 0.0010 s") for line in err)
