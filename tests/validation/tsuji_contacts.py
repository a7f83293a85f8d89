"""Where a jet bed's coordination number comes from: Sun 2007's N_c read several ways, and split by region.

    python tests/validation/tsuji_contacts.py RUN [RUN ...] [--window A B] [--rest V] [--lag S]

Each RUN is a run directory of ``fluidem run tsuji-jet --until 10`` (or another box bed with a linear
spring-dashpot). For each run:

1. the run's ``coordination`` probe (``probes.csv``, every probe interval) averaged over the window (5-10 s,
   Sun's), over 0-10 s and 2-10 s, the range of its 1 s means, and its mean at the snapshot times alone;
2. from the snapshots of ``particles.h5`` in the window, the bulk coordination number and multicontact ratio
   under each reading of ``analysis.contact_census`` (``overlap``: the run's own; ``force``: pairs whose
   normal force repels, Sun's eq. 21; ``walls``: wall planes of the box counted as neighbours) and the mean
   N_c over the particles in contact;
3. the ``overlap`` N_c split by region, each row: its share of the particles, its mean N_c and its part of
   the bulk coordination number (share × mean; the rows of one split add up to the bulk value):
   the jet column (centre of the jet ± 2 cm) against the rest; particles at rest (speed below ``--rest``,
   0.05 m/s) against moving ones; particles of a dead zone (moved less than one radius over the next
   ``--lag`` seconds, 1 s: a defluidised region that does not circulate; over the snapshots with one a lag
   later in the window) against the others; and five columns of 3 cm across the bed.
"""
import argparse
import sys
from pathlib import Path

import numpy as np

from fluidem.analysis.contact_census import bulk, census
from fluidem.analysis.fluidised import read_probes
from fluidem.case import load_case
from fluidem.io.snapshots import iter_snapshots

JET_HALF_WIDTH = 0.02  # [m] the jet column: the jet's centre ± 2 cm (the jet cell and one and a half beside it)


def jet_centre(case) -> float:
    """x [m] of the centre of the fastest inflow segment of the bottom (the jet); the box's middle without one."""
    bottom = case.gas.boundaries["bottom"]
    segs = [s for s in (getattr(bottom, "segments", None) or []) if s.start is not None and s.end is not None]
    if segs:
        s = max(segs, key=lambda s: s.superficial or 0.0)
        return 0.5 * (s.start + s.end)
    return 0.5 * case.gas.grid.size[0]


def probe_means(run: Path, window, snap_times):
    c = read_probes(run / "probes.csv")
    t, v = c["time_s"], c["coordination"]

    def mean(a, b):
        sel = (t >= a - 1e-9) & (t <= b + 1e-9)
        return float(np.mean(v[sel]))

    second = [mean(a, a + 1.0) for a in np.arange(window[0], window[1] - 0.5)]
    at_snaps = np.isin(np.round(t, 6), np.round(snap_times, 6))
    return {"probe window": mean(*window), "probe 0-10 s": mean(0.0, 10.0), "probe 2-10 s": mean(2.0, 10.0),
            "probe 1 s means": (min(second), max(second)),
            "probe at snapshot times": float(np.mean(v[at_snaps])) if at_snaps.any() else float("nan")}


def analyse(run: Path, window, rest: float, lag: float):
    case = load_case(run / "case.toml")
    contact = case.particles.contact
    box = next(w for w in case.walls if w.kind == "box")
    lower, upper = box.lower, box.upper
    xj = jet_centre(case)
    readings = {"overlap": [], "force": [], "walls": []}
    touching_mean = []
    splits = {"jet column": [], "beside the jet": [], "at rest": [], "moving": [], "dead zone": [],
              "circulating": []}
    columns = np.linspace(lower[0], upper[0], 6)
    col_rows = [[] for _ in range(5)]
    snaps = [(t, s) for t, s in iter_snapshots(run, fields=("position", "velocity", "diameter", "contacts", "id"))
             if window[0] - 1e-9 <= t <= window[1] + 1e-9]
    times = [t for t, _ in snaps]
    mismatch = 0
    for k_snap, (t, snap) in enumerate(snaps):
        pos, vel, rad = snap["position"], snap["velocity"], 0.5 * snap["diameter"]
        nc = census(pos, vel, rad, contact.stiffness, contact.damping, lower, upper)
        if "contacts" in snap:
            mismatch += int(np.count_nonzero(snap["contacts"] != nc["overlap"]))
        for k in readings:
            readings[k].append(bulk(nc[k]))
        o = nc["overlap"]
        touching_mean.append(float(o[o >= 1].mean()) if (o >= 1).any() else 0.0)
        n = o.size
        jet = np.abs(pos[:, 0] - xj) < JET_HALF_WIDTH
        still = np.linalg.norm(vel, axis=1) < rest
        for name, sel in (("jet column", jet), ("beside the jet", ~jet), ("at rest", still), ("moving", ~still)):
            splits[name].append((sel.sum() / n, o[sel].mean() if sel.any() else 0.0, o[sel].sum() / n))
        later = [s for tt, s in snaps[k_snap:] if tt >= t + lag - 1e-9]
        if later and np.array_equal(later[0]["id"], snap["id"]):  # rows are particles by id in every snapshot
            dead = np.linalg.norm(later[0]["position"] - pos, axis=1) < rad
            for name, sel in (("dead zone", dead), ("circulating", ~dead)):
                splits[name].append((sel.sum() / n, o[sel].mean() if sel.any() else 0.0, o[sel].sum() / n))
        col = np.clip(np.searchsorted(columns, pos[:, 0]) - 1, 0, 4)
        for k in range(5):
            sel = col == k
            col_rows[k].append((sel.sum() / n, o[sel].mean() if sel.any() else 0.0, o[sel].sum() / n))
    print(f"## {run}  ({len(times)} snapshots in {window[0]}-{window[1]} s; jet centre x = {xj * 100:.1f} cm;"
          f" snapshot N_c differing from the run's own: {mismatch})")
    for k, v in probe_means(run, window, np.array(times)).items():
        print(f"{k:28s} " + (f"{v[0]:.3f}-{v[1]:.3f}" if isinstance(v, tuple) else f"{v:.3f}"))
    print("| reading | coordination | multicontact |\n| --- | ---: | ---: |")
    for k, v in readings.items():
        a = np.array(v)
        print(f"| {k} | {np.mean(a[:, 0]):.3f} | {np.nanmean(a[:, 1]):.3f} |")
    print(f"| overlap, mean over particles in contact | {np.mean(touching_mean):.3f} | |")
    print("| region | share of particles | mean N_c | part of the bulk coordination |\n| --- | ---: | ---: | ---: |")
    for name, rows in splits.items():
        if not rows:
            continue
        a = np.array(rows)
        print(f"| {name} | {a[:, 0].mean():.3f} | {a[:, 1].mean():.3f} | {a[:, 2].mean():.3f} |")
    for k, rows in enumerate(col_rows):
        a = np.array(rows)
        print(f"| x {columns[k] * 100:.0f}-{columns[k + 1] * 100:.0f} cm | {a[:, 0].mean():.3f} | "
              f"{a[:, 1].mean():.3f} | {a[:, 2].mean():.3f} |")


def main(argv):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("runs", nargs="+", type=Path)
    p.add_argument("--window", nargs=2, type=float, default=(5.0, 10.0))
    p.add_argument("--rest", type=float, default=0.05, help="speed below which a particle is at rest [m/s]")
    p.add_argument("--lag", type=float, default=1.0, help="time over which a dead-zone particle moves less than "
                                                          "its radius [s]")
    a = p.parse_args(argv)
    for run in a.runs:
        analyse(run, tuple(a.window), a.rest, a.lag)


if __name__ == "__main__":
    main(sys.argv[1:])
