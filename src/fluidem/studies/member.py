"""Run one member of a study in the process that calls it (a Dask worker): start it, resume it from its
checkpoint, or leave it as it is, by what its folder holds (``table.member_state``).

``run_member`` never raises for a member's own failure: a bad value, a blow-up or any exception is
recorded in the member's ``summary.json`` (status ``failed`` and the error) and returned, so that the
other members go on. A stop file (``STOP_FILE`` in the study folder) asks a running member to stop at
its next compiled chunk with a checkpoint, as Ctrl-C stops ``fluidem run``.
"""
from __future__ import annotations

import shutil
import threading
import time
import tomllib
from pathlib import Path

from .table import member_state, record_failure

STOP_FILE = ".stop"
STOP_POLL_S = 0.2


class _StopWhenAsked:
    """While the block runs, a thread asks ``sim`` to stop (as Ctrl-C does) once ``stop_file`` exists."""

    def __init__(self, sim, stop_file: Path | None):
        self.sim, self.stop_file = sim, stop_file
        self._done = threading.Event()
        self._thread = None

    def _watch(self) -> None:
        while not self._done.wait(STOP_POLL_S):
            if self.stop_file.exists():
                # the flag that Simulation.run's Ctrl-C handler sets: the loop stops between chunks
                self.sim._stop_requested = True

    def __enter__(self):
        if self.stop_file is not None:
            self._thread = threading.Thread(target=self._watch, name="fluidem-stop-watch", daemon=True)
            self._thread.start()
        return self

    def __exit__(self, *exc):
        self._done.set()
        if self._thread is not None:
            self._thread.join()
        return False


def run_member(out_dir: str, case_toml: str, threads: int, stop_file: str | None = None,
               restart_failed: bool = False) -> dict:
    """Bring the member in ``out_dir`` to its end: skip it when completed, resume it when interrupted,
    start it (afresh) otherwise. A failed member is left as it is unless ``restart_failed``.

    Parameters
    ----------
    out_dir : the member's run directory.
    case_toml : the member's case (TOML text), used when it starts afresh.
    threads : compute threads of the run.
    stop_file : a path whose existence asks the run to stop with a checkpoint.

    Returns a dict: ``name``, ``status`` (``completed``, ``failed``, ``interrupted``, ``skipped``),
    ``error``, ``action`` (``skipped``, ``resumed``, ``started``) and ``wall_s`` (seconds spent here).
    """
    from ..case import validate_case
    from ..errors import CaseError
    from ..simulation import Simulation

    out = Path(out_dir)
    stop = Path(stop_file) if stop_file else None
    t0 = time.perf_counter()
    state = member_state(out)
    result = {"name": out.name, "status": state.status, "error": state.error, "action": "skipped", "wall_s": 0.0}
    if state.status == "completed" or (state.status == "failed" and not restart_failed):
        return result
    if stop is not None and stop.exists():
        result["status"] = "interrupted" if state.status == "interrupted" else "pending"
        return result
    case = None
    try:
        if state.status == "interrupted":
            result["action"] = "resumed"
            sim = Simulation.resume(out, threads=threads)
        else:
            result["action"] = "started"
            if out.exists():  # a start that left no checkpoint, or a failed member run again: begin afresh
                shutil.rmtree(out)
            case = validate_case(tomllib.loads(case_toml))
            sim = Simulation(case, out_dir=out)
        case = sim.case
        with _StopWhenAsked(sim, stop):
            summary = sim.run(until=sim.case.time.end)
        result["status"] = "completed" if summary.get("status") == "completed" else member_state(out).status
    except KeyboardInterrupt:
        result["status"] = "interrupted"
    except Exception as err:  # noqa: BLE001 - a member's failure is recorded, never raised
        message = str(err) if isinstance(err, (CaseError, FloatingPointError, OSError)) \
            else f"{type(err).__name__}: {err}"
        message = " ".join(message.split())  # one line: a cell of study.csv
        name = case.name if case is not None else _case_name(case_toml)
        try:
            record_failure(out, name, message)
        except OSError:
            pass
        result.update(status="failed", error=member_state(out).error or message)
    result["wall_s"] = time.perf_counter() - t0
    return result


def _case_name(case_toml: str) -> str:
    try:
        return str(tomllib.loads(case_toml).get("name", "case"))
    except tomllib.TOMLDecodeError:
        return "case"
