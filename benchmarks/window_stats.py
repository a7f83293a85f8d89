"""Means of a coupled run's probes over windows of simulated time, to compare runs (e.g. two gas steps).

    python benchmarks/window_stats.py runs/tj20 runs/tj20-dt1e-4 [--windows 5-10,10-15,15-20]

For each run directory and window: the means of the mean particle height, coordination number,
multicontact ratio, the pressure drop 20 cm above the inlet (and its standard deviation) and over
the bed, and the share of the 20 cm pressure drop's periodogram below 4 Hz and within 4-10 Hz.
A chaotic bed's runs differ in every number; the spread over one run's windows says by how much.
"""
from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

COLUMNS = {"mean_particle_height_m": "height m", "coordination": "coord", "multicontact_ratio": "multi",
           "pressure_drop_20cm_Pa": "dp20 Pa", "pressure_drop_bed_Pa": "dp bed Pa"}


def window_rows(probes: Path, windows):
    d = np.genfromtxt(probes, delimiter=",", names=True)
    for a, b in windows:
        w = d[(d["time_s"] >= a) & (d["time_s"] <= b)]
        if len(w) < 8:
            continue
        x = w["pressure_drop_20cm_Pa"] - w["pressure_drop_20cm_Pa"].mean()
        power = np.abs(np.fft.rfft(x)) ** 2
        f = np.fft.rfftfreq(x.size, float(np.median(np.diff(w["time_s"]))))
        row = {v: float(w[k].mean()) for k, v in COLUMNS.items()}
        row.update({"dp20 std": float(x.std()), "P<4Hz": power[f < 4].sum() / power.sum(),
                    "P4-10Hz": power[(f >= 4) & (f < 10)].sum() / power.sum()})
        yield (a, b), row


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("runs", nargs="+", help="run directories (with probes.csv)")
    ap.add_argument("--windows", default="5-10,10-15,15-20", help="a-b,... in simulated seconds")
    args = ap.parse_args()
    windows = [tuple(float(t) for t in w.split("-")) for w in args.windows.split(",")]
    for run in args.runs:
        for (a, b), row in window_rows(Path(run) / "probes.csv", windows):
            print(f"{run} {a:g}-{b:g} s: " + ", ".join(f"{k} {v:.4g}" for k, v in row.items()))


if __name__ == "__main__":
    main()
