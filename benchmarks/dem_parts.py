"""The parts of a soft-sphere DEM step timed alone on a checkpoint's bed, with the threads Numba has.

    NUMBA_NUM_THREADS=2 python benchmarks/dem_parts.py runs/tj20/restart.h5 [--case tsuji-jet] [--repeat 300]

Loads the checkpoint into ``Simulation(load_case(case))``, advances one gas step, then times the
kernels of ``_softsphere_kernels.advance`` one at a time on that frozen state (median of
``--repeat`` calls, three rounds): the pair phase (``pair_forces``, springs not updated) and the
force pass (``gather_forces``, forces only) with the engine's thread blocks and on one block (the
serial order), and the pieces of a list rebuild (the pair search, springs carried over, contacts
first, walls within reach, the work arrays, the flatness check). Then the engine's own
``advance`` over 700 steps, for the whole step as the parts add up to it (a rebuild every ~16
steps on the tsuji-jet bed).
"""
from __future__ import annotations

import argparse
import time

import numba
import numpy as np

import fluidem as fd
from fluidem.particles import _softsphere_kernels as K
from fluidem.particles._neighbours_kernels import build_pairs, carry_history, contacts_first
from fluidem.particles._pair_kernels import make_work


def median_us(fn, n: int, setup=None) -> float:
    """Median wall time of ``fn()`` [µs] over n calls (``setup()`` before each, not timed)."""
    fn()
    times = []
    for _ in range(n):
        if setup is not None:
            setup()
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return 1e6 * float(np.median(times))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("checkpoint", help="restart.h5 of a run of --case")
    ap.add_argument("--case", default="tsuji-jet")
    ap.add_argument("--repeat", type=int, default=300)
    a = ap.parse_args()
    sim = fd.Simulation(fd.load_case(a.case))
    sim.load_checkpoint(a.checkpoint)
    e = sim.engine
    sim.run(until=sim.time + sim.gas.gas_dt if sim.gas is not None else sim.time + e.dt)
    st, nt = e.state, numba.get_num_threads()
    flat = bool(e.dim2 and K.is_flat(st.position, st.velocity, st.omega, e.hist))
    work = make_work(e.pp, e.row_start, e.hist, e.slab_start, e.slab_members, nt)
    block = K.thread_blocks(e.row_start, e.slab_start, e.slab_members, nt)
    serial = np.array([0, e.slab_start.shape[0] - 1])
    sum_f, sum_c = np.zeros_like(st.force), np.zeros_like(st.force)
    hist = e.hist.copy()
    force, torque = np.empty_like(st.force), np.empty_like(st.force)
    axes = K.wall_axes(e.wall_normal)
    wall_hist, wall_touch = e.wall_hist.copy(), e.wall_touch.copy()

    def zero():
        sum_f[:] = 0.0
        sum_c[:] = 0.0

    def pair(b):
        K.pair_forces(st.position, st.velocity, st.omega, st.radius, st.mass, st.species, e.pp, e.row_start,
                      e.partner, e.slab_start, e.slab_members, hist, e.dt, False, sum_f, sum_c, b, flat, work)

    def gather(b):
        K.gather_forces(st.position, st.velocity, st.omega, st.radius, st.mass, st.species, e.pw, e.wall_motion,
                        e.wall_point0, e.wall_normal, axes, wall_hist, wall_touch, e.near_count, e.near_wall,
                        e.gravity, e.ext_force, e.ext_damping, True, e.dim2, sum_f, sum_c, e.time, e.dt, force,
                        torque, e.inv_mass, e.inv_inertia, 0, e.ref_pos, 1.0, e.slab_start[b], flat)

    pos = st.position.copy()
    rs, pa, ss, sm = build_pairs(pos, st.radius, e.skin, e.dim2, e.partner.shape[0])
    h = carry_history(e.row_start, e.partner, e.hist, rs, pa)
    first = ss[K.thread_blocks(rs, ss, sm, nt)]
    near = (e.wall_hist.copy(), e.wall_touch.copy(), e.near_count.copy(), e.near_wall.copy())
    print(f"{st.n} particles, {e.partner.size} listed pairs, {nt} thread(s), flat {flat}; µs per call, median")
    for _ in range(3):
        parts = {
            "pair phase": median_us(lambda: pair(block), a.repeat, zero),
            "pair phase serial": median_us(lambda: pair(serial), a.repeat, zero),
            "force pass": median_us(lambda: gather(block), a.repeat),
            "force pass serial": median_us(lambda: gather(serial), a.repeat),
        }
        rebuild = {
            "search": median_us(lambda: build_pairs(pos, st.radius, e.skin, e.dim2, e.partner.shape[0]), a.repeat),
            "carry springs": median_us(lambda: carry_history(e.row_start, e.partner, e.hist, rs, pa), a.repeat),
            "contacts first": median_us(lambda: contacts_first(pos, st.radius, rs, pa, h), a.repeat),
            "walls in reach": median_us(lambda: K.near_walls(pos, st.radius, e.wall_motion, e.wall_point0,
                                                             e.wall_normal, e.skin, e.dim2, *near, first), a.repeat),
            "work arrays": median_us(lambda: make_work(e.pp, rs, h, ss, sm, nt), a.repeat),
            "flatness": median_us(lambda: K.is_flat(pos, st.velocity, st.omega, h), a.repeat),
        }
        print("  ".join(f"{k} {v:.1f}" for k, v in parts.items()))
        print("  rebuild: " + "  ".join(f"{k} {v:.1f}" for k, v in rebuild.items())
              + f"  (all {sum(rebuild.values()):.1f})")
    # the engine's own steps (no gas step between them: the drag stays as the checkpoint left it)
    for _ in range(3):
        r0 = e.rebuilds
        t0 = time.perf_counter()
        e.advance(700)
        dt = time.perf_counter() - t0
        print(f"engine.advance(700): {1e6 * dt / 700:.1f} µs per DEM step, a rebuild every "
              f"{700 / max(e.rebuilds - r0, 1):.1f} steps")


if __name__ == "__main__":
    main()
