"""Goldschmidt's bed, one choice at a time, two placements each: the table of docs/gallery.md.

    python tests/validation/goldschmidt_table.py RUN [RUN ...]

Each RUN is a run directory of ``fluidem run goldschmidt --until 10 [--set ...]`` whose name ends in
``-s<seed>`` (the placement seed); runs of the same choice form one row, the choice named by the keys
where the run's ``case.toml`` differs from the built-in ``goldschmidt``, apart from ``time.end``, the
placement seed, the threads, the device and the particle step (resolved from the contact time):
``default`` where none differs; a run of another case keeps its name before ``-s<seed>``. For each run
the window averages of its summary.json (``analysis.fluidised.time_averages``: 5-10 s of a 10 s run) and
the standard deviation of ``pressure_drop_20cm_Pa`` of probes.csv over the same window; then, per choice,
the mean of the placements and their half spread.
"""
import json
import sys
import tomllib
from collections import defaultdict
from pathlib import Path

import numpy as np

from fluidem.analysis.fluidised import read_probes
from fluidem.case import load_case

COLUMNS = (("mean height [cm]", "mean_particle_height_avg_m", 100.0, "{:.2f}"),
           ("bed surface [cm]", "bed_surface_height_avg_m", 100.0, "{:.2f}"),
           ("coordination", "coordination_number_avg", 1.0, "{:.3f}"),
           ("multicontact", "multicontact_ratio_avg", 1.0, "{:.3f}"),
           ("dp(20 cm) std [Pa]", "p20_std", 1.0, "{:.0f}"),
           ("dominant [Hz]", "pressure_20cm_dominant_frequency_Hz", 1.0, "{:.2f}"))


IGNORED = ("time.end", "particles.placement.seed", "threads", "device", "time.dt")  # the run's, not the choice's


def flat(d: dict, prefix: str = "") -> dict:
    """Dotted keys of a nested case dict."""
    out = {}
    for k, v in d.items():
        key = f"{prefix}{k}"
        out.update(flat(v, key + ".") if isinstance(v, dict) else {key: v})
    return out


def choice(run: Path, base: dict) -> str | None:
    """``key=value, ...`` of the run's departures from ``goldschmidt`` (``default`` for none); None for a run
    of another case."""
    case = flat(tomllib.loads((run / "case.toml").read_text()))
    if case.get("name") != base.get("name"):
        return None
    diff = [f"{k}={json.dumps(v, separators=(',', ':')).replace(chr(34), '')}" for k, v in sorted(case.items())
            if k not in IGNORED and base.get(k) != v]
    return ", ".join(f"`{d}`" for d in diff) or "default"


def measures(run: Path) -> dict:
    s = json.loads((run / "summary.json").read_text())
    a, b = s["averages_window_s"]
    c = read_probes(run / "probes.csv")
    t = c["time_s"]
    sel = (t >= a - 1e-9) & (t <= b + 1e-9)
    s["p20_std"] = float(np.std(c["pressure_drop_20cm_Pa"][sel]))
    return s


def main(runs):
    rows = defaultdict(list)
    base = flat(tomllib.loads(load_case("goldschmidt").to_toml()))
    for r in map(Path, runs):
        if not (r / "summary.json").exists():
            print(f"{r}: no summary.json (running or failed)", file=sys.stderr)
            continue
        name, _, seed = r.name.rpartition("-s")
        rows[choice(r, base) or name].append((seed, measures(r)))
    window = None
    print("| variant | seed | " + " | ".join(c[0] for c in COLUMNS) + " |")
    print("| --- | --- | " + " | ".join("---:" for _ in COLUMNS) + " |")
    for name, runs_ in rows.items():
        for seed, m in runs_:
            window = m["averages_window_s"]
            print(f"| {name} | {seed} | " + " | ".join(f.format(m[k] * s) for _, k, s, f in COLUMNS) + " |")
        if len(runs_) > 1:
            vals = [[m[k] * s for _, m in runs_] for _, k, s, _ in COLUMNS]
            print(f"| {name} | both: mean ± half spread | " + " | ".join(
                f"{f.format(np.mean(v))} ± {f.format(np.ptp(v) / 2)}" for v, (_, _, _, f) in zip(vals, COLUMNS)) + " |")
    print(f"window {window} s")


if __name__ == "__main__":
    if len(sys.argv) < 2 or sys.argv[1] in ("-h", "--help"):
        print(__doc__)
        sys.exit(0)
    main(sys.argv[1:])
