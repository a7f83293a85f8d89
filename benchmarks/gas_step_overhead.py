"""Python overhead of a coupled gas step: the wall time of ``GasCoupling.gas_step`` minus that of the
compiled calls inside it (map, deposit, the gas solver's three kernels, the particle forces).

    NUMBA_NUM_THREADS=2 python benchmarks/gas_step_overhead.py RUN_DIR/restart.h5 [--profile]

RUN_DIR: a run of tsuji-jet (e.g. ``fluidem run tsuji-jet --until 1.5 --out runs/tj``). The gas steps
are repeated on the checkpoint's particles (no DEM in between), five rounds of 500; ``--profile``
adds a cProfile listing of the Python functions. Each compiled call is timed by a wrapper (about
1 µs each, six a step, counted in the Python share).
"""
import time, sys
from collections import defaultdict
import numba
import fluidem as fd
from fluidem.gas import _solver_kernels as K
from fluidem.coupling import _paired_kernels as P, _voidage_kernels as VK
acc = defaultdict(float)
def wrap(mod, name):
    fn = getattr(mod, name)
    def w(*a, **k):
        t0 = time.perf_counter()
        try: return fn(*a, **k)
        finally: acc["kernels"] += time.perf_counter() - t0
    setattr(mod, name, w)
for n in ("start_step", "iterate", "end_step"): wrap(K, n)
wrap(P, "deposit"); wrap(P, "particle_forces_split"); wrap(VK, "map_solids")
case = fd.load_case("tsuji-jet")
sim = fd.Simulation(case)
sim.load_checkpoint(sys.argv[1])
g = sim.gas
for _ in range(50): g.gas_step()
for r in range(5):
    acc.clear()
    t0 = time.perf_counter()
    for _ in range(500): g.gas_step()
    tot = (time.perf_counter() - t0) / 500 * 1e6
    k = acc["kernels"] / 500 * 1e6
    print(f"gas_step {tot:.1f} us, compiled calls {k:.1f} us, python {tot - k:.1f} us")
if "--profile" not in sys.argv:
    sys.exit()
import cProfile, pstats
pr = cProfile.Profile(); pr.enable()
for _ in range(500): g.gas_step()
pr.disable(); pstats.Stats(pr).sort_stats("tottime").print_stats(25)
