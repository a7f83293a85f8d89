"""The whole 20 s tsuji-jet-background run against the clock, with LAMMPS timed around it as the machine's yardstick.

    python benchmarks/tsuji_wall.py --out runs/tsuji_wall [--until 20] [--segments 4] [--repeat 3] [--json out.json]
    python benchmarks/tsuji_wall.py --out /tmp/tw --until 0.01 --segments 2 --lammps-steps 100   # a quick check

The target is wall time: 20 simulated seconds of ``tsuji-jet-background`` in at most 3 minutes on 2 cores. The
shared machine's speed moves by up to 2x within the hour, so one wall time says as much about the
machine as about fluidem. Each round is one whole run, in ``--segments`` pieces (``fluidem run
tsuji-jet-background --until t1``, then ``--resume`` to t2, ...; a resumed run is the same run bit for bit) in
``OUT/round-K``; before each piece and after the last, LAMMPS steps the 10,000-sphere bench bed of
shared/PEERS.md on one core (``--lammps-steps``, ``benchmarks/peers/run_peers.py``). Each piece's
stepping time (the growth of ``wall_time_s`` in ``summary.json``: stepping and output, no start-up or
compilation) is scaled by the mean LAMMPS rate at its two ends over the rate PEERS.md gives for a
machine of our kind (6.07e6 particle-steps/s on one core): what the piece would have taken at that
machine's speed. Without LAMMPS the runs are timed all the same, unscaled. A short run first loads
(or compiles) the kernels, untimed.

Printed: each piece, then over the rounds the wall time, the scaled wall time, particle-steps per
second and the LAMMPS rates (min, median, max). The run directories stay (their probes, fields and
summaries are those of a plain ``fluidem run tsuji-jet-background``).
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

from compare_peers import peers_module  # benchmarks/ is this script's folder, first on sys.path

from fluidem.bench import settled_bed

import harness

LAMMPS_ANCHOR_1CORE = 6.07e6  # shared/PEERS.md: LAMMPS 29 Sep 2021 GRANULAR, 10k bed, one core [particle-steps/s]


def wall_so_far(out: Path) -> float:
    """``wall_time_s`` of the run directory's summary [s]: stepping and output since the run began."""
    return float(json.loads((out / "summary.json").read_text())["wall_time_s"])


def whole_run(out: Path, until: float, segments: int, threads: int, lammps) -> dict:
    """One run of tsuji-jet-background to ``until`` in ``segments`` pieces; ``lammps()`` gives the yardstick rate or None."""
    env = dict(os.environ, NUMBA_NUM_THREADS=str(threads))
    rates = [lammps()]
    pieces, before = [], 0.0
    for k in range(segments):
        t_end = until * (k + 1) / segments
        cmd = [sys.executable, "-m", "fluidem", "run", "--until", f"{t_end:.10g}", "--quiet", "--threads", str(threads)]
        cmd += ["--resume", str(out)] if k else ["tsuji-jet-background", "--out", str(out)]
        subprocess.run(cmd, check=True, env=env, stdout=subprocess.DEVNULL)  # its summary.json is read below
        now = wall_so_far(out)
        rates.append(lammps())
        piece = {"until_s": t_end, "wall_s": now - before, "lammps_before": rates[-2], "lammps_after": rates[-1],
                 "scaled_wall_s": None}
        if rates[-2] is not None and rates[-1] is not None:
            piece["scaled_wall_s"] = piece["wall_s"] * 0.5 * (rates[-2] + rates[-1]) / LAMMPS_ANCHOR_1CORE
        pieces.append(piece)
        before = now
        yard = ("LAMMPS {:.3g} -> {:.3g} particle-steps/s; at PEERS.md's machine speed {:.1f} s".format(
            piece["lammps_before"], piece["lammps_after"], piece["scaled_wall_s"])
            if piece["scaled_wall_s"] is not None else "no LAMMPS yardstick")
        print(f"  to {t_end:g} s: {piece['wall_s']:7.1f} s wall; {yard}", flush=True)
    summary = json.loads((out / "summary.json").read_text())
    scaled = [p["scaled_wall_s"] for p in pieces]
    known = [r for r in rates if r is not None]
    return {"value": sum(p["wall_s"] for p in pieces),
            "scaled_wall_s": sum(scaled) if None not in scaled else None,
            "particle_steps_per_s": summary["particle_steps_per_s"],
            "lammps_min": min(known) if known else None, "lammps_max": max(known) if known else None,
            "pieces": pieces, "run_dir": str(out)}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--until", type=float, default=20.0, help="simulated seconds of each run [s]")
    ap.add_argument("--segments", type=int, default=4, help="pieces of a run, LAMMPS timed between them")
    ap.add_argument("--out", default="runs/tsuji_wall", help="folder of the runs (OUT/round-1, ...; each new or empty)")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--lammps-steps", type=int, default=1000, help="steps of each LAMMPS yardstick run")
    harness.add_options(ap, repeat=1)
    a = ap.parse_args(argv)
    peers = peers_module()
    bed = peers.load_bed(settled_bed(10000))
    lammps_error = []

    def lammps():
        if lammps_error:
            return None
        row = peers.run_one("lammps", bed, a.lammps_steps, 1)
        if "error" in row:
            lammps_error.append(row["error"])
            print(f"LAMMPS cannot run, so the runs are not scaled to PEERS.md's machine: {row['error']}", flush=True)
            return None
        return float(row["particle_steps_per_s"])

    with tempfile.TemporaryDirectory() as tmp:  # compile or load the kernels' caches, untimed
        subprocess.run([sys.executable, "-m", "fluidem", "run", "tsuji-jet-background", "--until", "4e-4", "--quiet", "--threads",
                        str(a.threads), "--out", str(Path(tmp) / "warm-up")], check=True, stdout=subprocess.DEVNULL,
                       env=dict(os.environ, NUMBA_NUM_THREADS=str(a.threads)))
    counter = iter(range(1, a.repeat + 1))

    def run_once() -> dict:
        k = next(counter)
        print(f"round {k}: tsuji-jet-background to {a.until:g} s on {a.threads} threads in {a.segments} pieces", flush=True)
        return whole_run(Path(a.out) / f"round-{k}", a.until, a.segments, a.threads, lammps)

    rounds = harness.run_rounds({"tsuji-jet-background": run_once}, a.repeat, unit="s")
    rows = [["wall [s]", *_stats(rounds, None)],
            ["at PEERS.md's machine speed [s]", *_stats(rounds, "scaled_wall_s")],
            ["particle-steps/s (gas included)", *_stats(rounds, "particle_steps_per_s")],
            ["LAMMPS one core, slowest [particle-steps/s]", *_stats(rounds, "lammps_min")],
            ["LAMMPS one core, fastest [particle-steps/s]", *_stats(rounds, "lammps_max")]]
    print(f"\ntsuji-jet-background {a.until:g} s on {a.threads} threads, {a.repeat} run(s); PEERS.md's LAMMPS one core: "
          f"{LAMMPS_ANCHOR_1CORE:.3g} particle-steps/s; target 180 s")
    print(harness.format_table(["", "runs", "min", "median", "max"], rows))
    harness.write_json(a.json, {"tsuji-jet-background": rounds}, until_s=a.until, segments=a.segments, threads=a.threads,
                       lammps_anchor=LAMMPS_ANCHOR_1CORE, lammps_error=lammps_error[0] if lammps_error else None)
    return 0


def _stats(rounds, key):
    s = rounds.stats("tsuji-jet-background", key)
    return [s["n"], s["min"], s["median"], s["max"]]


if __name__ == "__main__":
    raise SystemExit(main())
