"""Interleaved timing for the scripts of ``benchmarks/``: rounds, their statistics, a table and JSON.

The development machine is shared and its speed drifts (by up to 2x within minutes on a 2-vCPU
host), so two variants timed minutes apart compare badly. Here every variant is measured once per
round, and the order alternates from round to round (A B, B A, A B, ...; with more variants the
order is reversed every other round), so that a drift meets all variants alike. Reported for each
variant: the minimum, median and maximum over the rounds; for a pair of variants: the median of
the per-round ratios (both measured within the same round, seconds apart).

Every timing script takes the same two options (``add_options``):

``--repeat N``   rounds; each round measures every variant once (a script's default depends on
                 what one round costs)
``--json PATH``  write the machine, the command line, the git revision and each round's raw
                 values (``write_json``)

A variant is a function of no arguments that returns what it measured: a number (seconds, a
rate, ...), or a dict ``{"value": number, ...}`` whose other entries are kept as extras of that
round (e.g. the DEM's part of a gas step), or None when it could not measure (a peer code
that failed): that round then has no value for it, and the ratios leave the round out.
``timed(fn)`` makes a variant that returns the wall time of ``fn()`` [s]. Usage::

    import harness
    rounds = harness.run_rounds({"base": harness.timed(step_base), "tree": harness.timed(step_tree)}, repeat=5,
                                unit="s")
    print(rounds.table())
    print(rounds.ratio("base", "tree"))          # median over rounds of base / tree
    harness.write_json("ab.json", {"bed": rounds})

Only the standard library is used, so that ``benchmarks/peers`` and tests import it as it is.
"""
from __future__ import annotations

import argparse
import datetime
import json
import math
import os
import platform
import statistics
import subprocess
import sys
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

# environment variables that change how fast compiled code runs; recorded with every result
TIMING_ENVIRONMENT = ("NUMBA_NUM_THREADS", "NUMBA_THREADING_LAYER", "OMP_NUM_THREADS", "OMP_WAIT_POLICY",
                      "GOMP_SPINCOUNT", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")


# ---------------------------------------------------------------- rounds
def round_order(names: Sequence[str], index: int) -> list[str]:
    """Order in which round ``index`` (0, 1, ...) measures the variants: as given in even rounds,
    reversed in odd ones."""
    return list(names) if index % 2 == 0 else list(reversed(names))


def timed(fn: Callable[[], object]) -> Callable[[], float]:
    """A variant that calls ``fn()`` and returns its wall time [s] (``time.perf_counter``)."""

    def variant() -> float:
        t0 = time.perf_counter()
        fn()
        return time.perf_counter() - t0

    return variant


def spread(values: Iterable[float | None]) -> dict:
    """``{"n", "min", "median", "max"}`` of the values that are not None (None where there are none)."""
    vals = [float(v) for v in values if v is not None]
    if not vals:
        return {"n": 0, "min": None, "median": None, "max": None}
    return {"n": len(vals), "min": min(vals), "median": statistics.median(vals), "max": max(vals)}


def round_ratios(a: Sequence[float | None], b: Sequence[float | None]) -> list[float]:
    """a[k] / b[k] for every round k in which both have a value and b[k] is not zero."""
    return [float(x) / float(y) for x, y in zip(a, b, strict=True) if x is not None and y is not None and y != 0]


@dataclass
class Rounds:
    """The values of every variant in every round, in the order measured.

    ``values[name][k]``: what variant ``name`` returned in round k (None: nothing);
    ``extras[name][k]``: the other numeric entries of its dict that round; ``orders[k]``: the
    order of round k.
    """

    names: list[str]
    unit: str = ""
    orders: list[list[str]] = field(default_factory=list)
    values: dict[str, list] = field(default_factory=dict)
    extras: dict[str, list] = field(default_factory=dict)

    def __post_init__(self) -> None:
        for name in self.names:
            self.values.setdefault(name, [])
            self.extras.setdefault(name, [])

    def record(self, name: str, result) -> None:
        """Append what variant ``name`` returned in the current round."""
        if isinstance(result, dict):
            extra = {k: v for k, v in result.items() if k != "value"}
            value = result.get("value")
        else:
            extra, value = {}, result
        self.values[name].append(None if value is None else float(value))
        self.extras[name].append(extra)

    def series(self, name: str, key: str | None = None) -> list:
        """Variant ``name``'s value (or extra ``key``) round by round (None where missing)."""
        if key is None:
            return list(self.values[name])
        return [e.get(key) for e in self.extras[name]]

    def stats(self, name: str, key: str | None = None) -> dict:
        """Minimum, median and maximum over the rounds of variant ``name``'s value (or extra ``key``)."""
        return spread(self.series(name, key))

    def ratios(self, a: str, b: str, key: str | None = None) -> list[float]:
        """Per-round ratios a / b of the two variants' values (or extras ``key``)."""
        return round_ratios(self.series(a, key), self.series(b, key))

    def ratio(self, a: str, b: str, key: str | None = None) -> float | None:
        """Median over the rounds of a / b, both measured in the same round (None: no common round)."""
        per = self.ratios(a, b, key)
        return statistics.median(per) if per else None

    def table(self, key: str | None = None, label: str | None = None) -> str:
        """One row per variant: rounds with a value, min, median, max of the value (or extra ``key``)."""
        unit = f" [{self.unit}]" if self.unit and key is None else ""
        head = [(label or "variant") + unit, "rounds", "min", "median", "max"]
        rows = []
        for name in self.names:
            s = self.stats(name, key)
            rows.append([name, s["n"], s["min"], s["median"], s["max"]])
        return format_table(head, rows)

    def ratio_line(self, a: str, b: str, key: str | None = None, label: str | None = None) -> str:
        """'a / b: median of per-round ratios x (min y, max z, n rounds)'; ``label`` in place of 'a / b'."""
        per = self.ratios(a, b, key)
        label = label or f"{a} / {b}"
        if not per:
            return f"{label}: no round with both"
        s = spread(per)
        return (f"{label}: median of per-round ratios {s['median']:.3f} (min {s['min']:.3f}, "
                f"max {s['max']:.3f}, {s['n']} rounds)")

    def as_dict(self) -> dict:
        """JSON-ready: unit, orders, raw values and extras per round, and the statistics."""
        return {"unit": self.unit, "variants": list(self.names), "orders": self.orders,
                "rounds": [{"order": order, "values": {n: self.values[n][k] for n in self.names},
                            "extras": {n: self.extras[n][k] for n in self.names if self.extras[n][k]}}
                           for k, order in enumerate(self.orders)],
                "stats": {n: self.stats(n) for n in self.names}}


def run_rounds(variants: dict[str, Callable[[], object]], repeat: int, unit: str = "", warmup: int = 0,
               progress: Callable[[int, dict], None] | None = None) -> Rounds:
    """Measure every variant once per round, ``repeat`` rounds, in alternating order (``round_order``).

    ``warmup``: untimed calls of each variant before the first round (compilation, caches).
    ``progress(k, got)``: called after round k with that round's results by name.
    """
    if repeat < 1:
        raise ValueError(f"repeat = {repeat}: at least one round")
    names = list(variants)
    rounds = Rounds(names, unit)
    for _ in range(warmup):
        for name in names:
            variants[name]()
    for k in range(repeat):
        order = round_order(names, k)
        got = {name: variants[name]() for name in order}
        rounds.orders.append(order)
        for name in names:
            rounds.record(name, got[name])
        if progress is not None:
            progress(k, got)
    return rounds


# ---------------------------------------------------------------- command line, table, JSON
def _positive_int(text: str) -> int:
    n = int(text)
    if n < 1:
        raise argparse.ArgumentTypeError(f"{text}: must be a positive integer")
    return n


def add_options(parser: argparse.ArgumentParser, repeat: int) -> None:
    """Add ``--repeat N`` (rounds, default ``repeat``) and ``--json PATH`` to a script's parser."""
    parser.add_argument("--repeat", type=_positive_int, default=repeat, metavar="N",
                        help=f"rounds; each round measures every variant once, the order alternating "
                             f"(default {repeat})")
    parser.add_argument("--json", metavar="PATH", help="write the machine, the command, the git revision and "
                                                       "every round's raw values as JSON")


def _cell(x) -> str:
    if x is None:
        return "-"
    if isinstance(x, float):
        return f"{x:.4g}"
    return str(x)


def format_table(headers: Sequence[str], rows: Iterable[Sequence]) -> str:
    """A plain table: the first column left-aligned, the others right-aligned; floats to 4 digits, None as '-'."""
    cells = [[str(h) for h in headers]] + [[_cell(x) for x in row] for row in rows]
    widths = [max(len(r[i]) for r in cells) for i in range(len(headers))]
    lines = ["  ".join(c.ljust(w) if i == 0 else c.rjust(w) for i, (c, w) in enumerate(zip(r, widths, strict=True)))
             for r in cells]
    lines.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(lines)


def git_revision(root: Path = ROOT) -> str | None:
    """The checkout's commit, with ``+dirty`` when tracked files differ from it; None outside git."""
    try:
        rev = subprocess.run(["git", "-C", str(root), "rev-parse", "HEAD"], capture_output=True, text=True,
                             timeout=30, check=True).stdout.strip()
        # --no-optional-locks: only reads, never refreshes the index
        dirty = subprocess.run(["git", "--no-optional-locks", "-C", str(root), "diff", "--quiet", "HEAD", "--"],
                               capture_output=True, timeout=30).returncode == 1
    except (OSError, subprocess.SubprocessError):
        return None
    return rev + ("+dirty" if dirty else "")


def _cpu_model() -> str | None:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or None


def _memory_bytes() -> int | None:
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemTotal:"):
                return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    return None


def machine_info() -> dict:
    """What a timing depends on besides the code: CPU, cores, memory, load, Python and library versions,
    the threading environment."""
    try:
        usable = len(os.sched_getaffinity(0))
    except AttributeError:
        usable = os.cpu_count()
    try:
        load = list(os.getloadavg())
    except OSError:
        load = None
    versions = {"python": platform.python_version()}
    for mod in ("numpy", "numba", "scipy", "fluidem"):
        m = sys.modules.get(mod)
        if m is not None:
            versions[mod] = getattr(m, "__version__", None)
    fluidem = sys.modules.get("fluidem")
    return {"host": platform.node(), "platform": platform.platform(), "cpu": _cpu_model(),
            "cpu_count": os.cpu_count(), "usable_cpus": usable, "memory_bytes": _memory_bytes(),
            "load_average": load, "versions": versions,
            "fluidem_path": getattr(fluidem, "__file__", None) if fluidem else None,
            "environment": {k: os.environ[k] for k in TIMING_ENVIRONMENT if k in os.environ}}


def _jsonable(x):
    if isinstance(x, float) and not math.isfinite(x):
        return None  # strict JSON has no NaN or infinity
    if isinstance(x, Rounds):
        return _jsonable(x.as_dict())
    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    if isinstance(x, Path):
        return str(x)
    if hasattr(x, "item") and callable(x.item):  # numpy scalars
        return _jsonable(x.item())
    return x


def report(measurements: dict | None = None, **extra) -> dict:
    """The JSON document: command line, time, git revision, machine, ``measurements`` (``Rounds`` or plain
    data by name) and any further entries."""
    doc = {"command": [sys.executable, *sys.argv], "cwd": os.getcwd(),
           "time_utc": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
           "git_revision": git_revision(), "machine": machine_info(),
           "measurements": _jsonable(measurements or {})}
    doc.update(_jsonable(extra))
    return doc


def write_json(path: str | Path | None, measurements: dict | None = None, **extra) -> dict | None:
    """Write ``report(measurements, **extra)`` to ``path`` (nothing when ``path`` is None); returns it."""
    if not path:
        return None
    doc = report(measurements, **extra)
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    Path(path).write_text(json.dumps(doc, indent=2, allow_nan=False) + "\n")
    return doc
