"""What an engine call costs beyond its steps: calls of k steps against one call of 10 k.

    python benchmarks/advance_calls.py --from runs/tj [--per 7] [--rounds 20]

A coupled run calls ``engine.advance`` once per gas step (7 DEM steps on the tsuji-jet bed); work done
once per call (the opening kick and drift, argument dispatch, allocations) is paid every gas step. The
engine of the checkpoint in ``--from`` (a run directory, e.g. ``fluidem run tsuji-jet --until 1.5 --out
runs/tj``) advances alternately in 10 calls of ``--per`` steps and in one call of 10 × ``--per`` steps
(the gas is not stepped: the particles keep the checkpoint's gas force); printed: the median time per
step of each and the difference per call.
"""
from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import fluidem as fd
from fluidem.case import load_case


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--from", dest="run_dir", required=True, help="run directory with case.toml and restart.h5")
    ap.add_argument("--per", type=int, default=7, help="steps per short call")
    ap.add_argument("--rounds", type=int, default=20)
    a = ap.parse_args()
    run = Path(a.run_dir)
    sim = fd.Simulation(load_case(run / "case.toml"))
    sim.load_checkpoint(run / "restart.h5")
    eng = sim.engine
    eng.advance(10 * a.per)  # compile and warm up
    short, long_ = [], []
    for _ in range(a.rounds):
        t0 = time.perf_counter()
        for _ in range(10):
            eng.advance(a.per)
        t1 = time.perf_counter()
        eng.advance(10 * a.per)
        t2 = time.perf_counter()
        short.append((t1 - t0) / (10 * a.per))
        long_.append((t2 - t1) / (10 * a.per))
    s, l = statistics.median(short), statistics.median(long_)
    print(f"per step: calls of {a.per} {s * 1e6:.1f} µs, one call of {10 * a.per} {l * 1e6:.1f} µs; "
          f"each call costs {(s - l) * a.per * 1e6:.0f} µs beyond its steps")


if __name__ == "__main__":
    main()
