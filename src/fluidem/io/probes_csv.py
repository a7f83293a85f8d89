"""Probes as one CSV row per probe time, readable with ``pandas.read_csv``.

``ProbeWriter`` appends a row of ``time_s``, ``step`` and the probes' values each time its schedule
fires; ``read_probes`` reads the file back as one float array per column.
"""
from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np

from ..schedule import EveryTime

PROBES_FILE = "probes.csv"


class ProbeWriter:
    """Observer appending the values of ``probes`` (name → fn(sim) returning a dict) to probes.csv."""

    def __init__(self, out_dir: Path, probes, schedule=None):
        self.path = Path(out_dir) / PROBES_FILE
        self.probes = probes
        self.schedule = schedule or EveryTime(0.001)
        self.columns: list[str] | None = None

    def row(self, sim) -> dict:
        row = {"time_s": sim.time, "step": sim.steps}
        for fn in self.probes:
            row.update(fn(sim))
        return row

    def __call__(self, sim) -> None:
        row = self.row(sim)
        new = not self.path.exists() or self.path.stat().st_size == 0
        if self.columns is None:
            self.columns = list(row)
        with open(self.path, "a", newline="") as f:
            # a run resumed from an older version keeps that version's columns (new ones are left out)
            w = csv.DictWriter(f, fieldnames=self.columns, extrasaction="ignore")
            if new:
                w.writeheader()
            w.writerow({k: (f"{v:.10g}" if isinstance(v, float) else v) for k, v in row.items()})

    def truncate_after(self, step: int) -> None:
        """Drop rows later than ``step`` (on resume; steps are exact where printed times are rounded)."""
        if not self.path.exists():
            return
        with open(self.path, newline="") as f:
            rows = list(csv.reader(f))
        if not rows:
            return
        header, body = rows[0], rows[1:]
        col = header.index("step")
        keep = [r for r in body if r and int(r[col]) <= step]
        with open(self.path, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(header)
            w.writerows(keep)
        self.columns = header


def _number(text: str) -> float:
    """A cell as a float; NaN for an empty or unparsable one."""
    try:
        return float(text)
    except ValueError:
        return math.nan


def read_probes(path: str | Path) -> dict[str, np.ndarray]:
    """The columns of a ``probes.csv``, each as a (rows,) float64 array, in the file's order.

    Parameters
    ----------
    path : a run directory or the path of its ``probes.csv``.

    Returns
    -------
    {column name: values}; a cell that is empty or not a number (a column a resumed run of an older
    version left out), or missing from a short row, is NaN. An empty file gives {}.

    Raises ``FileNotFoundError`` without a file, ``OSError``, ``UnicodeDecodeError`` or ``csv.Error``
    when it cannot be read.
    """
    path = Path(path)
    if path.is_dir():
        path = path / PROBES_FILE
    with open(path, newline="") as f:
        rows = [r for r in csv.reader(f) if r]
    if not rows:
        return {}
    header, body = rows[0], rows[1:]
    return {name.strip(): np.array([_number(r[k]) if k < len(r) else math.nan for r in body], float)
            for k, name in enumerate(header)}
