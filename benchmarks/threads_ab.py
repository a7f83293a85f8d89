"""Thread counts against each other on the same problem, in one process, in alternating bursts.

    NUMBA_NUM_THREADS=2 python benchmarks/threads_ab.py --problem bed --n 100000 --repeat 10 [--per 20]
    fluidem run tsuji-jet-background --out runs/tj20                      # a developed bed to start from
    NUMBA_NUM_THREADS=2 python benchmarks/threads_ab.py --problem coupled --from runs/tj20 --repeat 20 [--per 50]
    NUMBA_NUM_THREADS=2 python benchmarks/threads_ab.py --problem bed --n 10000 --repeat 1 --per 2   # a quick check

The shared machine's speed drifts by up to 2x within minutes, so timings of 1 and 2 threads from runs
minutes apart compare badly. Here the thread counts of ``--threads`` (default 1,2) take turns, one burst
each per round, the order alternating (``harness.round_order``); ``numba.set_num_threads`` is set
before each burst.

``bed``: the dense bench bed of ``fluidem bench`` (settled, Hertz–Mindlin; ``--n`` 10000 or a multiple
of it), one engine that every thread count advances by ``--per`` steps a burst (default 20); measured:
particle-steps per second. ``coupled``: a coupled run resumed from the checkpoint of ``--from`` (a run
directory, copied, not changed), one copy per thread count (``Simulation.resume(threads=k)``),
``--per`` gas steps a burst (default 50); measured: milliseconds per gas step and the DEM part of
them (``engine.advance``). The copies must end bitwise alike (results do not depend on the thread
count): printed as ``same state``.

Printed: min, median and max over the rounds of each thread count, and the speed-up of each count over
the first as the median of the per-round ratios.
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
from fluidem.bench import load_bed_engine

import harness  # benchmarks/harness.py: this script's folder is first on sys.path


def label(k: int) -> str:
    return f"{k} thread" + ("s" if k > 1 else "")


def bed_variants(n: int, threads: list[int], per: int) -> tuple[dict, object]:
    """One engine on the bench bed; a variant per thread count returning particle-steps per second."""
    eng = load_bed_engine(n)
    for k in threads:  # compile and warm up with every thread count
        numba.set_num_threads(k)
        eng.advance(5)

    def variant(k):
        def measure() -> float:
            numba.set_num_threads(k)
            t0 = time.perf_counter()
            eng.advance(per)
            return per * n / (time.perf_counter() - t0)

        return measure

    return {label(k): variant(k) for k in threads}, None


def coupled_variants(run_dir: Path, threads: list[int], per: int, tmp: Path) -> tuple[dict, dict]:
    """A resumed copy of the run per thread count; variants returning ms per gas step and the DEM's part."""
    sims = {}
    for k in threads:
        shutil.copytree(run_dir, tmp / f"run{k}")
        sims[k] = fd.Simulation.resume(tmp / f"run{k}", threads=k)
        numba.set_num_threads(k)
        sims[k].advance(sims[k].gas.substeps)  # compile or load the caches

    def variant(k):
        sim = sims[k]

        def measure() -> dict:
            numba.set_num_threads(k)
            acc = [0.0]
            advance = sim.engine.advance

            def timed(nsteps):
                t = time.perf_counter()
                advance(nsteps)
                acc[0] += time.perf_counter() - t

            sim.engine.advance = timed
            try:
                t0 = time.perf_counter()
                sim.advance(per * sim.gas.substeps)
                total = time.perf_counter() - t0
            finally:
                del sim.engine.advance
            return {"value": 1e3 * total / per, "dem_ms": 1e3 * acc[0] / per}

        return measure

    return {label(k): variant(k) for k in threads}, sims


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--problem", choices=("bed", "coupled"), default="bed")
    ap.add_argument("--n", type=int, default=100000, help="spheres of the bed (10000 or a multiple of it)")
    ap.add_argument("--from", dest="run_dir", type=Path, help="run directory with restart.h5 (problem 'coupled')")
    ap.add_argument("--threads", default="1,2", help="thread counts, the first the reference of the speed-ups")
    ap.add_argument("--per", type=int, default=0, help="steps a burst (default 20 DEM steps / 50 gas steps)")
    harness.add_options(ap, repeat=10)
    a = ap.parse_args(argv)
    threads = [int(t) for t in a.threads.split(",") if t]
    if max(threads) > numba.config.NUMBA_NUM_THREADS:
        ap.error(f"--threads {a.threads}: run with NUMBA_NUM_THREADS={max(threads)} (or more)")
    if a.problem == "coupled" and not a.run_dir:
        ap.error("--problem coupled needs --from RUN_DIR")
    tmp = Path(tempfile.mkdtemp(prefix="threads_ab_"))
    try:
        if a.problem == "bed":
            per = a.per or 20
            variants, sims = bed_variants(a.n, threads, per)
            unit, what = "particle-steps/s", f"{a.n} spheres, bursts of {per} steps"
        else:
            per = a.per or 50
            variants, sims = coupled_variants(a.run_dir, threads, per, tmp)
            unit, what = "ms per gas step", f"{a.run_dir}, bursts of {per} gas steps"
        rounds = harness.run_rounds(variants, a.repeat, unit=unit)
        print(f"{what}, {a.repeat} rounds")
        print(rounds.table(label="threads"))
        names = rounds.names
        for name in names[1:]:  # speed-up over the first count: a rate grows, a time shrinks
            pair = (name, names[0]) if a.problem == "bed" else (names[0], name)
            print(rounds.ratio_line(*pair, label=f"speed-up of {name} over {names[0]}"))
        same = None
        if sims is not None:
            print(rounds.table(key="dem_ms", label="DEM [ms per gas step]"))
            states = [sims[k].state for k in threads]
            same = all(np.array_equal(getattr(states[0], f), getattr(s, f))
                       for s in states[1:] for f in ("position", "velocity", "omega", "ids"))
            print(f"same state: {same}")
        harness.write_json(a.json, {a.problem: rounds}, problem=a.problem, n=a.n if a.problem == "bed" else None,
                           run_dir=a.run_dir, per=per, threads=threads, same_state=same)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
