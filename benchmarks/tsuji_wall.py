"""The whole 20 s tsuji-jet run against the clock, with LAMMPS timed around it as the machine's yardstick.

    python benchmarks/tsuji_wall.py [--until 20] [--segments 4] [--out runs/tsuji_wall] [--json out.json]

The issue's target is wall time: 20 simulated seconds of ``tsuji-jet`` in at most 3 minutes on 2 cores.
This shared machine's speed moves by up to 2x within the hour (the same developed bed took 1.68 and
2.92 ms per gas step an hour apart), so one wall time says as much about the machine as about
fluidem. Here the run goes in ``--segments`` pieces (``fluidem run tsuji-jet --until t1``, then
``--resume`` to t2, ...; a resumed run is the same run bit for bit), and before each piece and after
the last LAMMPS steps the 10,000-sphere bench bed of shared/PEERS.md on one core (1000 steps,
``benchmarks/peers/run_peers.py``). Each piece's stepping time (the growth of ``wall_time_s`` in
``summary.json``: stepping and output, no start-up or compilation) is scaled by the mean LAMMPS
rate at its two ends over the rate PEERS.md gives for a machine of our kind (6.07e6
particle-steps/s on one core): what the piece would have taken at that machine's speed.

Prints the pieces, the total wall time, the LAMMPS rates and the total scaled so; the run directory
stays (its probes, fields and summary are those of a plain ``fluidem run tsuji-jet``).
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

from compare_peers import (
    _peers_module,  # benchmarks/ is this script's folder, first on sys.path
)

from fluidem.bench import settled_bed

LAMMPS_ANCHOR_1CORE = 6.07e6  # shared/PEERS.md: LAMMPS 29 Sep 2021 GRANULAR, 10k bed, one core


def lammps_rate(peers, bed, steps: int) -> float:
    row = peers.run_one("lammps", bed, steps, 1)
    if "error" in row:
        raise SystemExit(f"LAMMPS failed: {row['error']} (apt-get install lammps; benchmarks/README.md)")
    return float(row["particle_steps_per_s"])


def wall_so_far(out: Path) -> float:
    return float(json.loads((out / "summary.json").read_text())["wall_time_s"])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--until", type=float, default=20.0, help="simulated seconds in all")
    ap.add_argument("--segments", type=int, default=4, help="pieces of the run, LAMMPS timed between them")
    ap.add_argument("--out", default="runs/tsuji_wall", help="run directory (must be new or empty)")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--lammps-steps", type=int, default=1000)
    ap.add_argument("--json", help="write the figures as JSON")
    a = ap.parse_args()
    peers = _peers_module()
    bed = peers.load_bed(settled_bed(10000))
    out = Path(a.out)
    env = dict(os.environ, NUMBA_NUM_THREADS=str(a.threads))
    rates = [lammps_rate(peers, bed, a.lammps_steps)]
    pieces, before = [], 0.0
    for k in range(a.segments):
        t_end = a.until * (k + 1) / a.segments
        cmd = [sys.executable, "-m", "fluidem", "run", "--until", f"{t_end:.10g}", "--quiet",
               "--threads", str(a.threads)]
        cmd += ["--resume", str(out)] if k else ["tsuji-jet", "--out", str(out)]
        subprocess.run(cmd, check=True, env=env, stdout=subprocess.DEVNULL)  # its summary.json is read below
        now = wall_so_far(out)
        rates.append(lammps_rate(peers, bed, a.lammps_steps))
        scale = 0.5 * (rates[-2] + rates[-1]) / LAMMPS_ANCHOR_1CORE
        pieces.append({"until_s": t_end, "wall_s": now - before, "lammps_before": rates[-2],
                       "lammps_after": rates[-1], "scaled_wall_s": (now - before) * scale})
        before = now
        p = pieces[-1]
        print(f"to {t_end:6.3f} s: {p['wall_s']:7.1f} s wall; LAMMPS {p['lammps_before']:.3g} -> "
              f"{p['lammps_after']:.3g} particle-steps/s; at PEERS.md's machine speed {p['scaled_wall_s']:7.1f} s",
              flush=True)
    total = sum(p["wall_s"] for p in pieces)
    scaled = sum(p["scaled_wall_s"] for p in pieces)
    summary = json.loads((out / "summary.json").read_text())
    print(f"tsuji-jet {a.until:g} s on {a.threads} threads: {total:.1f} s wall "
          f"({summary['particle_steps_per_s']:.3g} particle-steps/s, gas included); LAMMPS one core "
          f"{min(rates):.3g}-{max(rates):.3g} here against {LAMMPS_ANCHOR_1CORE:.3g} in PEERS.md; "
          f"at that machine's speed {scaled:.1f} s (target 180 s)")
    if a.json:
        Path(a.json).write_text(json.dumps({"pieces": pieces, "wall_s": total, "scaled_wall_s": scaled,
                                            "lammps_rates": rates, "threads": a.threads, "until_s": a.until},
                                           indent=2) + "\n")


if __name__ == "__main__":
    main()
