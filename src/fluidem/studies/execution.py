"""The members of a study on Dask (``dask.distributed``): a ``LocalCluster`` of worker processes, or an
existing cluster by its scheduler's address.

Each member is one task, ``member.run_member``, that runs in a worker process with one Dask thread; the
run's compute threads are its case's ``threads`` key. A local cluster has ``cores // threads`` workers
(at most one per member to run). An existing cluster's workers must see the study folder at the same
path (a shared file system) and import the same fluidem; give them ``--nthreads 1`` so that each runs
one member at a time.

While the members run, ``study.csv`` is rewritten after each one finishes and a progress line goes
to the logger ``fluidem.progress`` (INFO): members done, running, failed and waiting, with an ETA.
Ctrl-C (``KeyboardInterrupt``) creates the study's stop file: running members stop at their next
compiled chunk with a checkpoint, members not yet started do not start, and the table is written.
"""
from __future__ import annotations

import logging
import math
import os
import time
import uuid
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import CaseError
from .definition import StudyDefinition
from .member import STOP_FILE, run_member
from .table import member_state, record_failure, status_counts, write_table

CONNECT_TIMEOUT_S = 5.0
PROGRESS_INTERVAL_S = 15.0
POLL_S = 0.25
STOP_GRACE_S = 120.0  # after Ctrl-C: how long running members have to write their checkpoint
INSTALL_HINT = "pip install 'fluidem[sweep]' (dask[distributed] and pandas)"

log = logging.getLogger("fluidem.progress")


def require_distributed() -> None:
    """Raise ``CaseError`` with the install command when ``dask.distributed`` is missing."""
    try:
        import distributed  # noqa: F401
    except ImportError:
        raise CaseError(f"fluidem sweep runs its members on Dask, which is not installed here: {INSTALL_HINT}") from None


def available_cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:
        return os.cpu_count() or 1


def default_workers(threads: int, members: int) -> int:
    """Workers of a local cluster: ``cores // threads``, at least one, at most ``members``."""
    return max(1, min(available_cores() // max(1, threads), max(1, members)))


def connect(address: str, timeout: float = CONNECT_TIMEOUT_S):
    """A ``distributed.Client`` of the scheduler at ``address``; ``CaseError`` naming it if it is not there."""
    from distributed import Client

    try:
        return Client(address, timeout=timeout, set_as_default=False)
    except Exception as err:  # noqa: BLE001 - OSError, TimeoutError, ValueError (a bad address): all one message
        raise CaseError(f"--scheduler {address}: cannot reach a Dask scheduler there within {timeout:g} s "
                        f"({' '.join(str(err).split()) or type(err).__name__}); start one with `dask scheduler` "
                        "and workers with `dask worker ADDRESS --nthreads 1`, or leave --scheduler out to run "
                        "on this machine") from None


def _worker_plugin():
    from distributed import WorkerPlugin

    class IgnoreInterrupt(WorkerPlugin):
        """Local workers leave Ctrl-C to the sweep, which stops them through the stop file."""

        name = "fluidem-ignore-interrupt"

        def setup(self, worker):
            import signal
            import threading

            if threading.current_thread() is threading.main_thread():
                signal.signal(signal.SIGINT, signal.SIG_IGN)

    return IgnoreInterrupt()


def start_local(workers: int):
    """A ``LocalCluster`` of ``workers`` processes with one thread each, and its client."""
    from distributed import Client, LocalCluster

    cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None,
                           silence_logs=logging.ERROR)
    client = Client(cluster, set_as_default=False)
    try:
        client.register_plugin(_worker_plugin())
    except Exception:  # noqa: BLE001 - without it, Ctrl-C in a terminal reaches the workers too
        pass
    return cluster, client


@dataclass
class Outcome:
    """What a sweep did: the table's columns and rows, whether Ctrl-C stopped it, each task's result."""

    columns: list[str]
    rows: list[dict]
    interrupted: bool = False
    results: list[dict] = field(default_factory=list)

    @property
    def counts(self) -> dict[str, int]:
        return status_counts(self.rows)


class _Progress:
    def __init__(self, total: int, to_run: int, interval: float):
        self.total, self.to_run, self.interval = total, to_run, interval
        self.start = time.perf_counter()
        self.finished = 0  # tasks of this sweep that ended
        self._last = -math.inf
        self._shown: tuple | None = None
        self._shown_at = -math.inf

    def due(self) -> bool:
        return time.perf_counter() - self._last >= self.interval

    def report(self, rows: list[dict], running: int | None) -> None:
        now = time.perf_counter()
        self._last = now
        c = status_counts(rows)
        elapsed = now - self.start
        left = self.to_run - self.finished
        eta = "ETA --" if self.finished == 0 else f"ETA {_duration(elapsed / self.finished * left)}"
        run = "?" if running is None else str(running)
        waiting = "?" if running is None else str(max(0, c["pending"] + c["interrupted"] - running))
        counts = (c["completed"], run, c["failed"], waiting)
        if counts == self._shown:  # the same counts again: a line only every interval
            if now - self._shown_at < self.interval:
                return
        self._shown, self._shown_at = counts, now
        log.info(f"sweep: {c['completed']}/{self.total} done, {run} running, {c['failed']} failed, "
                 f"{waiting} waiting   wall {_duration(elapsed)}   {eta}")


def _duration(seconds: float) -> str:
    if seconds < 120:
        return f"{seconds:.0f} s"
    if seconds < 7200:
        return f"{seconds / 60:.1f} min"
    return f"{seconds / 3600:.1f} h"


def _running(client, keys: set) -> int | None:
    """Members executing now: our tasks on each worker, at most its threads."""
    try:
        processing = client.processing()
        nthreads = client.nthreads()
    except Exception:  # noqa: BLE001 - the count is a courtesy
        return None
    return sum(min(sum(1 for k in ks if k in keys), nthreads.get(w, 1)) for w, ks in processing.items())


def to_run(study: StudyDefinition, folder: Path, retry: bool) -> list:
    """The members a sweep submits: all but the completed ones, and the failed ones only with ``retry``."""
    out = []
    for m in study.members():
        status = member_state(folder / m.name).status
        if status == "completed" or (status == "failed" and not retry):
            continue
        out.append(m)
    return out


def execute(study: StudyDefinition, folder: str | Path, client=None, scheduler: str | None = None,
            workers: int | None = None, retry: bool = False, connect_timeout: float = CONNECT_TIMEOUT_S,
            progress_interval: float = PROGRESS_INTERVAL_S, on_connected=None) -> Outcome:
    """Run the members of ``study`` in ``folder`` that are not done; returns the outcome.

    ``client``: a ``distributed.Client`` to use (left open); else ``scheduler``: the address of one
    to connect to; else a local cluster of ``workers`` processes (default ``default_workers``), closed at
    the end. ``on_connected()`` is called once a cluster is there, before any member starts (the
    study's files are written then, so that an unreachable scheduler leaves nothing behind).
    Ctrl-C stops the members with their checkpoints and returns with ``interrupted``.
    """
    folder = Path(folder).resolve()
    members = to_run(study, folder, retry)
    own_cluster = own_client = None
    if members and client is None:
        require_distributed()
        if scheduler:
            client = own_client = connect(scheduler, connect_timeout)
        else:
            own_cluster, client = start_local(workers or default_workers(study.threads, len(members)))
            own_client = client
    stop = folder / STOP_FILE
    interrupted = False
    results: list[dict] = []
    try:
        if on_connected is not None:
            on_connected()
        stop.unlink(missing_ok=True)
        columns, rows = write_table(study, folder)
        if not members:
            failed = status_counts(rows)["failed"]
            log.info(f"sweep: all {len(rows)} members have run"
                     + (f"; {failed} failed (--retry runs those again)" if failed else ""))
            return Outcome(columns, rows)
        if scheduler and own_client is not None and not client.scheduler_info().get("workers"):
            log.warning(f"the Dask scheduler at {scheduler} has no workers yet; the members wait for one")
        token = uuid.uuid4().hex[:8]
        futures = {}
        for m in members:
            key = f"fluidem-member-{m.name}-{token}"
            fut = client.submit(run_member, str(folder / m.name), study.member_case(m.overrides).to_toml(),
                                study.threads, str(stop), retry, key=key, pure=False)
            futures[fut] = m
        keys = {f.key for f in futures}
        progress = _Progress(len(study.members()), len(members), progress_interval)
        progress.report(rows, _running(client, keys))
        pending = set(futures)
        try:
            while pending:
                pending, ended = _collect(study, folder, futures, pending, results, progress)
                if ended:
                    rows = write_table(study, folder)[1]
                if ended or progress.due():
                    progress.report(rows, _running(client, keys))
                if pending:
                    time.sleep(POLL_S)
        except KeyboardInterrupt:
            interrupted = True
            log.warning("interrupted: the running members stop at their next checkpoint; finished members are kept")
            stop.touch()
            deadline = time.perf_counter() + STOP_GRACE_S
            while pending and time.perf_counter() < deadline:
                pending, _ = _collect(study, folder, futures, pending, results, progress)
                time.sleep(POLL_S)
            if pending:
                client.cancel(list(pending))
        columns, rows = write_table(study, folder)
        progress.report(rows, 0)
        return Outcome(columns, rows, interrupted, results)
    finally:
        stop.unlink(missing_ok=True)
        if own_client is not None:
            own_client.close()
        if own_cluster is not None:
            own_cluster.close()


def _collect(study, folder: Path, futures: dict, pending: set, results: list, progress: _Progress) -> tuple[set, int]:
    """Record the members whose tasks ended; returns the tasks still pending and how many ended."""
    done = [f for f in pending if f.done()]
    for fut in done:
        m = futures[fut]
        progress.finished += 1
        if fut.status == "finished":
            result = fut.result()
        else:  # the task itself failed: its worker died (KilledWorker), or it was cancelled
            try:
                err = fut.exception()
                error = f"{type(err).__name__}: {err}"
            except Exception as exc:  # noqa: BLE001 - a cancelled future raises here
                error = f"{type(exc).__name__}: {exc}"
            error = " ".join(error.split())
            if fut.status != "cancelled":
                try:
                    record_failure(folder / m.name, study.base.get("name", "case"), f"the Dask task failed: {error}")
                except OSError:
                    pass
            result = {"name": m.name, "status": member_state(folder / m.name).status, "error": error,
                      "action": "lost", "wall_s": math.nan}
        results.append(result)
        if result["status"] == "failed":
            log.warning(f"member {m.name} failed: {result['error']}")
    return pending - set(done), len(done)
