"""One and two threads on the same coupled run, in one process, in alternating bursts.

    fluidem run tsuji-jet --until 1.5 --out runs/tj
    NUMBA_NUM_THREADS=2 python benchmarks/threads_ab.py --from runs/tj [--bursts 30] [--per 50]

The shared machine's speed drifts by up to 2x within minutes, so 1- and 2-thread timings from
runs minutes apart compare badly. Here two copies of the run directory are resumed, one with
each thread count (``Simulation.resume(threads=k)``; ``numba.set_num_threads`` before each of its
bursts), and advanced ``--per`` gas steps a burst, the order swapped every round. Prints the
median and fastest milliseconds per gas step and the DEM part of them (``engine.advance``), and
whether both copies end bitwise alike (they must: results do not depend on the thread count).
"""
from __future__ import annotations

import argparse
import shutil
import tempfile
import time
from pathlib import Path

import numba
import numpy as np

import fluidem as fd


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--from", dest="run_dir", required=True, help="run directory with restart.h5")
    ap.add_argument("--bursts", type=int, default=30, help="bursts per thread count")
    ap.add_argument("--per", type=int, default=50, help="gas steps a burst")
    a = ap.parse_args()
    if numba.config.NUMBA_NUM_THREADS < 2:
        ap.error("needs NUMBA_NUM_THREADS >= 2")
    tmp = Path(tempfile.mkdtemp(prefix="threads_ab_"))
    try:
        sims, total, dem = {}, {1: [], 2: []}, {1: [], 2: []}
        for k in (1, 2):
            shutil.copytree(a.run_dir, tmp / f"run{k}")
            sims[k] = fd.Simulation.resume(tmp / f"run{k}", threads=k)
            numba.set_num_threads(k)
            sims[k].step_once(sims[k].gas.substeps)  # compile or load the caches
        for r in range(a.bursts):
            for k in ((1, 2) if r % 2 == 0 else (2, 1)):
                sim, acc = sims[k], [0.0]
                numba.set_num_threads(k)
                advance = sim.engine.advance

                def timed(n, advance=advance, acc=acc):
                    t = time.perf_counter()
                    advance(n)
                    acc[0] += time.perf_counter() - t

                sim.engine.advance = timed
                t0 = time.perf_counter()
                sim.step_once(a.per * sim.gas.substeps)
                total[k].append(1e3 * (time.perf_counter() - t0) / a.per)
                dem[k].append(1e3 * acc[0] / a.per)
                del sim.engine.advance
        for k in (1, 2):
            t, d = np.array(total[k]), np.array(dem[k])
            print(f"{k} thread{'s' if k > 1 else ' '}: ms per gas step median {np.median(t):.3f}, fastest {t.min():.3f}; "
                  f"DEM median {np.median(d):.3f}, fastest {d.min():.3f}")
        s1, s2 = sims[1].state, sims[2].state
        same = all(np.array_equal(getattr(s1, n), getattr(s2, n)) for n in ("position", "velocity", "omega", "ids"))
        print(f"same state: {same}")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
