"""Means of coupled runs' probes over windows of simulated time, to compare runs (e.g. two gas steps).

    fluidem run tsuji-jet-background --out runs/tj20 && fluidem run tsuji-jet-background --set gas.dt=1e-4 --out runs/tj20-dt1e-4
    python benchmarks/window_stats.py runs/tj20-dt1e-4 runs/tj20 [--windows 5-10,10-15,15-20] [--json out.json]

For each run directory and window: the means of the mean particle height, the coordination number,
the multicontact ratio, the pressure drop 20 cm above the inlet (and its standard deviation) and over
the bed, and the shares of the 20 cm pressure drop's periodogram below 4 Hz and within 4–10 Hz. A
chaotic bed's runs differ in every number; the spread over one run's windows says by how much. This
backs the case's gas step (``src/fluidem/cases/tsuji-jet-background.toml``). It reads finished runs and times
nothing, so it has no ``--repeat``; ``--json`` writes the rows with the machine and git revision as
the timing scripts do (``harness.write_json``).
"""
from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

import harness  # benchmarks/harness.py: this script's folder is first on sys.path

COLUMNS = {"mean_particle_height_m": "height [m]", "coordination": "coordination",
           "multicontact_ratio": "multicontact", "pressure_drop_20cm_Pa": "dp 20 cm [Pa]",
           "pressure_drop_bed_Pa": "dp bed [Pa]"}


def window_rows(probes: Path, windows):
    """(window, row) for each window [s] with at least 8 probe rows: column means, the 20 cm pressure
    drop's standard deviation [Pa] and its periodogram's shares below 4 Hz and within 4–10 Hz."""
    d = np.genfromtxt(probes, delimiter=",", names=True)
    for a, b in windows:
        w = d[(d["time_s"] >= a) & (d["time_s"] <= b)]
        if len(w) < 8:
            continue
        x = w["pressure_drop_20cm_Pa"] - w["pressure_drop_20cm_Pa"].mean()
        power = np.abs(np.fft.rfft(x)) ** 2
        f = np.fft.rfftfreq(x.size, float(np.median(np.diff(w["time_s"]))))
        row = {v: float(w[k].mean()) for k, v in COLUMNS.items()}
        row.update({"dp 20 cm std [Pa]": float(x.std()), "power < 4 Hz": float(power[f < 4].sum() / power.sum()),
                    "power 4-10 Hz": float(power[(f >= 4) & (f < 10)].sum() / power.sum())})
        yield (a, b), row


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("runs", nargs="+", help="run directories (with probes.csv)")
    ap.add_argument("--windows", default="5-10,10-15,15-20", help="a-b,... in simulated seconds")
    ap.add_argument("--json", metavar="PATH", help="write the rows, the machine and the git revision as JSON")
    a = ap.parse_args(argv)
    windows = [tuple(float(t) for t in w.split("-")) for w in a.windows.split(",")]
    rows, table = [], []
    for run in a.runs:
        for (lo, hi), row in window_rows(Path(run) / "probes.csv", windows):
            rows.append({"run": run, "window_s": [lo, hi], **row})
            table.append([run, f"{lo:g}-{hi:g} s", *row.values()])
    if not rows:
        print("no window holds 8 probe rows")
        return 1
    print(harness.format_table(["run", "window", *[k for k in rows[0] if k not in ("run", "window_s")]], table))
    harness.write_json(a.json, {"windows": rows})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
