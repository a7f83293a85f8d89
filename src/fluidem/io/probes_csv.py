"""Probes as one CSV row per probe time, readable with ``pandas.read_csv``."""
from __future__ import annotations

import csv
from pathlib import Path

from ..schedule import EveryTime


class ProbeWriter:
    """Observer appending the values of ``probes`` (name → fn(sim) returning a dict) to probes.csv."""

    def __init__(self, out_dir: Path, probes, schedule=None):
        self.path = Path(out_dir) / "probes.csv"
        self.probes = probes
        self.schedule = schedule or EveryTime(0.001)
        self.columns: list[str] | None = None

    def row(self, sim) -> dict:
        row = {"time_s": sim.time, "step": sim.step}
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
