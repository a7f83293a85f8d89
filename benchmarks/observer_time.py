"""Wall time of a whole run and of each of its observers (snapshots, gas fields, probes, checkpoint).

    NUMBA_NUM_THREADS=1 python benchmarks/observer_time.py hoomans-orifice [--until 1.5] [--out DIR]
    python benchmarks/observer_time.py tsuji-jet --calls 400 [--from runs/tj/restart.h5]

Runs a built-in case (or a case file) from its start with the default observers, each timed on
every call, and prints the run's wall time, the time in each observer and the rest (the
stepping). Writing the output must stay a small part of a run however long it is: a writer whose
cost grows with the number of snapshots already written shows up here on a long run.

``--calls N`` steps nothing: it calls each observer N times in a row on the case's starting state (or a
checkpoint's, ``--from``), as a run of N snapshots would, and prints the mean time of the first and the
last tenth of the calls: a writer whose cost grows with the snapshots already written shows it at once.
"""
from __future__ import annotations

import argparse
import tempfile
import time
from collections import defaultdict
from pathlib import Path

import fluidem as fd


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("case", help="built-in case name or case file")
    ap.add_argument("--until", type=float, default=None, help="simulated seconds (default: the case's end)")
    ap.add_argument("--out", default=None, help="run directory (default: a temporary one)")
    ap.add_argument("--calls", type=int, default=0, help="call each observer this many times, no stepping")
    ap.add_argument("--from", dest="start", default=None, help="checkpoint to start from (restart.h5)")
    args = ap.parse_args()
    out = Path(args.out) if args.out else Path(tempfile.mkdtemp(prefix="observer_time_")) / "run"
    sim = fd.Simulation(fd.load_case(args.case), out_dir=out)
    if args.start:
        sim.load_checkpoint(args.start)
    if args.calls > 0:
        _calls_only(sim, args.calls)
        return
    spent, calls = defaultdict(float), defaultdict(int)
    for name, obs in sim.observers.items():
        call = obs.__call__

        def timed(s, call=call, name=name):
            t0 = time.perf_counter()
            try:
                return call(s)
            finally:
                spent[name] += time.perf_counter() - t0
                calls[name] += 1

        sim.observers[name] = _Wrapped(obs, timed)
    t0 = time.perf_counter()
    sim.run(until=args.until)
    total = time.perf_counter() - t0
    print(f"{args.case}: {sim.time:.4g} s simulated in {total:.2f} s wall ({out})")
    for name in spent:
        print(f"  {name:12s} {spent[name]:7.2f} s in {calls[name]:5d} calls ({1e3 * spent[name] / calls[name]:.2f} ms each)")
    print(f"  {'the rest':12s} {total - sum(spent.values()):7.2f} s (stepping)")


def _calls_only(sim, n: int) -> None:
    tenth = max(1, n // 10)
    for name, obs in sim.observers.items():
        times = []
        for _ in range(n):
            t0 = time.perf_counter()
            obs(sim)
            times.append(time.perf_counter() - t0)
        first, last = sum(times[:tenth]) / tenth, sum(times[-tenth:]) / tenth
        print(f"  {name:12s} {sum(times):7.2f} s in {n} calls; first tenth {1e3 * first:.2f} ms, "
              f"last tenth {1e3 * last:.2f} ms a call")


class _Wrapped:
    """An observer whose calls go through ``timed``; everything else (schedule, finalize, ...) is the observer's."""

    def __init__(self, obs, timed):
        self._obs, self._timed = obs, timed

    def __call__(self, sim):
        return self._timed(sim)

    def __getattr__(self, name):
        return getattr(self._obs, name)


if __name__ == "__main__":
    main()
