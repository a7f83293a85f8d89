"""One and two threads on the dense bench bed, in one process, in alternating bursts.

    NUMBA_NUM_THREADS=2 python benchmarks/bed_threads.py [--n 100000] [--bursts 10] [--per 20]

The issue's scaling target is 2 threads at least 1.7× faster than 1 at 100,000 spheres. The shared
machine's speed moves within minutes, so both thread counts advance the same engine (the bench bed of
``fluidem bench``, settled, Hertz–Mindlin) in alternating bursts of ``--per`` steps, the order
swapped every round; printed: the median and fastest particle-steps per second of each and their
ratios.
"""
from __future__ import annotations

import argparse
import statistics
import time

import numba

from fluidem.bench import load_bed_engine


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--n", type=int, default=100000, help="spheres (10000 or a multiple of it)")
    ap.add_argument("--bursts", type=int, default=10)
    ap.add_argument("--per", type=int, default=20, help="steps per burst")
    a = ap.parse_args()
    if numba.config.NUMBA_NUM_THREADS < 2:
        ap.error("run with NUMBA_NUM_THREADS=2 (or more)")
    eng = load_bed_engine(a.n)
    for k in (1, 2):  # compile and warm up both
        numba.set_num_threads(k)
        eng.advance(5)
    rates = {1: [], 2: []}
    for r in range(a.bursts):
        for k in ((1, 2) if r % 2 == 0 else (2, 1)):
            numba.set_num_threads(k)
            t0 = time.perf_counter()
            eng.advance(a.per)
            rates[k].append(a.per * a.n / (time.perf_counter() - t0))
    m1, m2 = statistics.median(rates[1]), statistics.median(rates[2])
    print(f"{a.n} spheres, {a.bursts} bursts of {a.per} steps each")
    print(f"1 thread : median {m1:.3g}, fastest {max(rates[1]):.3g} particle-steps/s")
    print(f"2 threads: median {m2:.3g}, fastest {max(rates[2]):.3g} particle-steps/s")
    print(f"2 threads / 1 thread: median {m2 / m1:.2f}, fastest {max(rates[2]) / max(rates[1]):.2f}")


if __name__ == "__main__":
    main()
