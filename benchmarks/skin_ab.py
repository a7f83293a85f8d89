"""Verlet skins against each other on the same coupled run, in one process, in alternating bursts.

    fluidem run tsuji-jet --until 1.5 --out runs/tj
    NUMBA_NUM_THREADS=2 python benchmarks/skin_ab.py --from runs/tj --skins 0.001,0.0015,0.002 [--bursts 16]

Each skin gets a copy of the checkpoint's simulation with ``neighbours.skin`` set (the list is built anew
with it at the first step), then they advance 50 gas steps a burst in turn, the order reversed every round.
Printed per skin: median and fastest milliseconds per gas step, DEM steps per list rebuild, listed pairs.
"""
from __future__ import annotations

import argparse
import statistics
import time

import fluidem as fd
from fluidem.case import load_case


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--from", dest="run_dir", required=True, help="run directory with case.toml and restart.h5")
    ap.add_argument("--skins", required=True, help="comma-separated skins [m]")
    ap.add_argument("--bursts", type=int, default=16)
    ap.add_argument("--per", type=int, default=50, help="gas steps per burst")
    a = ap.parse_args()
    skins = [float(x) for x in a.skins.split(",")]
    sims = {}
    for sk in skins:
        sim = fd.Simulation(load_case(f"{a.run_dir}/case.toml", {"neighbours.skin": sk}))
        sim.load_checkpoint(f"{a.run_dir}/restart.h5")
        sim.engine.skin = sk
        sim.engine.ref_pos[:] = 1e9  # every particle "moved": the list is built with this skin at the first step
        sim.step_once(5 * sim.gas.substeps)  # compile or load the caches
        sims[sk] = sim
    times = {sk: [] for sk in skins}
    rebuilds = {sk: 0 for sk in skins}
    for r in range(a.bursts):
        for sk in (skins if r % 2 == 0 else skins[::-1]):
            sim = sims[sk]
            r0 = sim.engine.rebuilds
            t0 = time.perf_counter()
            sim.step_once(a.per * sim.gas.substeps)
            times[sk].append(1e3 * (time.perf_counter() - t0) / a.per)
            rebuilds[sk] += sim.engine.rebuilds - r0
    for sk in skins:
        steps = a.bursts * a.per * sims[sk].gas.substeps
        print(f"skin {sk * 1e3:.2f} mm: ms per gas step median {statistics.median(times[sk]):.3f}, fastest "
              f"{min(times[sk]):.3f}; DEM steps per rebuild {steps / max(rebuilds[sk], 1):.1f}; "
              f"listed pairs {sims[sk].engine.partner.shape[0]}")


if __name__ == "__main__":
    main()
