"""Time of one soft-sphere neighbour-list build (``_neighbours_kernels.build_pairs``).

    NUMBA_NUM_THREADS=1 python benchmarks/neighbour_build.py [--repeat 30]

Two beds: the 10,000-sphere settled 3D bed of ``fluidem bench`` (skin 1 mm) and the
``tsuji-jet`` particles (2400 spheres of 4 mm, 2D, skin 1 mm) settled without gas for
0.3 s. Prints the minimum over ``--repeat`` builds (the machine is shared: the minimum is
the least disturbed) and the number of pairs. A fluidised bed rebuilds its list every
10–20 steps (tsuji-jet: 39,000 rebuilds in 700,000 steps), so this matters there; a
settled bed almost never rebuilds.
"""
from __future__ import annotations

import argparse
import time

import fluidem as fd
from fluidem.bench import load_bed_engine
from fluidem.particles._neighbours_kernels import build_pairs
from fluidem.particles.softsphere import SoftSphereEngine


def best_of(fn, repeat):
    fn()
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeat", type=int, default=30)
    a = ap.parse_args()
    bed = load_bed_engine(10000)
    jet = SoftSphereEngine(fd.load_case("tsuji-jet"))
    jet.advance(int(round(0.3 / jet.dt)))
    for name, eng in (("3D bed, 10,000 spheres", bed), ("tsuji-jet particles, 2400, 2D", jet)):
        st = eng.state
        t = best_of(lambda: build_pairs(st.position, st.radius, eng.skin, eng.dim2), a.repeat)
        print(f"{name:32s} {eng.partner.shape[0]:7d} pairs  build {1e3 * t:7.3f} ms (min of {a.repeat})")


if __name__ == "__main__":
    main()
