"""Python overhead of a coupled gas step: the wall time of ``GasCoupling.gas_step`` minus that of the
compiled calls inside it (voidage map, deposit, the gas solver's three kernels, the particle forces).

    NUMBA_NUM_THREADS=2 python benchmarks/gas_step_overhead.py runs/tj/restart.h5 [--profile]

The checkpoint is one of tsuji-jet (``fluidem run tsuji-jet --until 1.5 --out runs/tj``). Its gas steps
are repeated on the checkpoint's particles (no DEM in between), five rounds of 500 after 50 to warm up.
The compiled calls are timed by wrapping the module attributes the coupling calls them through (this
process only; each wrapper adds about 1 µs, six a step, to the Python share). ``--profile`` adds a
cProfile listing of 500 more steps.
"""
from __future__ import annotations

import argparse
import time
from collections import defaultdict

import fluidem as fd
from fluidem.bench import _wrap
from fluidem.coupling import _paired_kernels as P
from fluidem.coupling import _voidage_kernels as VK
from fluidem.gas import _solver_kernels as K

COMPILED = ((K, "start_step"), (K, "iterate"), (K, "end_step"), (P, "deposit"), (P, "particle_forces_split"),
            (VK, "map_solids"))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("checkpoint", help="restart.h5 of a tsuji-jet run")
    ap.add_argument("--profile", action="store_true")
    args = ap.parse_args()
    acc, calls = defaultdict(float), defaultdict(int)
    for mod, name in COMPILED:  # the module attributes the coupling calls them through
        _wrap(mod, name, "compiled", acc, calls)
    sim = fd.Simulation(fd.load_case("tsuji-jet"))
    sim.load_checkpoint(args.checkpoint)
    gas = sim.gas
    for _ in range(50):
        gas.gas_step()
    for _ in range(5):
        acc.clear()
        t0 = time.perf_counter()
        for _ in range(500):
            gas.gas_step()
        total = (time.perf_counter() - t0) / 500 * 1e6
        compiled = acc["compiled"] / 500 * 1e6
        print(f"gas_step {total:.1f} µs, compiled calls {compiled:.1f} µs, Python {total - compiled:.1f} µs")
    if args.profile:
        import cProfile
        import pstats

        prof = cProfile.Profile()
        prof.enable()
        for _ in range(500):
            gas.gas_step()
        prof.disable()
        pstats.Stats(prof).sort_stats("tottime").print_stats(25)


if __name__ == "__main__":
    main()
