"""The pair phase of one soft-sphere sub-step alone, by slab count and by thread block, on a checkpoint's bed.

    NUMBA_NUM_THREADS=1 python benchmarks/pair_phase.py runs/tj [--slabs 64,16,8,4] [--repeat 1000]

The run directory is one of tsuji-jet (``fluidem run tsuji-jet --until 1.5 --out runs/tj``). For each
upper bound on the slab count the list is built again at the checkpoint's reference positions
(``build_pairs(..., slabs=k)``, springs carried over, contacts first, as a rebuild leaves them) and the
chunked pair forces (``_pair_kernels.chunk_run``, both parities, springs not updated) are timed on
one thread: all slabs, then the slabs of each of the two blocks ``thread_blocks`` gives two threads,
with their listed pairs, contacts and particles. Minimum of three rounds of ``--repeat`` calls each.
What ``_neighbours_kernels.max_slabs`` was chosen from (benchmarks/README.md, twelfth session).
"""
from __future__ import annotations

import argparse
import time

import numpy as np
from numba import njit

import fluidem as fd
from fluidem.particles import _softsphere_kernels as K
from fluidem.particles._neighbours_kernels import build_pairs, carry_history, contacts_first
from fluidem.particles._pair_kernels import chunk_run, make_work


@njit(cache=True)
def _slabs(start, stop, flat, state, pp, lists, hist, dt, sum_f, sum_c, work):
    """Slabs start … stop − 1, even ones then odd ones, as one thread of the pair phase runs them."""
    for phase in range(2):
        chunk_run(start + (start + phase) % 2, stop, flat, state, pp, lists, hist, dt, False, sum_f, sum_c, work, 0)


def _best(f, repeat):
    f()
    out = []
    for _ in range(3):
        t0 = time.perf_counter()
        for _ in range(repeat):
            f()
        out.append((time.perf_counter() - t0) / repeat)
    return 1e6 * min(out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("run_dir")
    ap.add_argument("--slabs", default="64,16,8,4", help="upper bounds on the slab count")
    ap.add_argument("--repeat", type=int, default=1000)
    a = ap.parse_args()
    sim = fd.Simulation.resume(a.run_dir)
    e, st = sim.engine, sim.engine.state
    state = (st.position, st.velocity, st.omega, st.radius, st.mass, st.species)
    flat = bool(e.dim2 and K.is_flat(st.position, st.velocity, st.omega, e.hist))
    sf, sc = np.zeros_like(st.position), np.zeros_like(st.position)
    print(f"{st.n} particles, flat {flat}; µs per call, one thread")
    for cap in (int(x) for x in a.slabs.split(",")):
        rs, pa, ss, sm = build_pairs(e.ref_pos, st.radius, e.skin, e.dim2, 0, cap)
        hist = carry_history(e.row_start, e.partner, e.hist, rs, pa)
        contacts_first(st.position, st.radius, rs, pa, hist)
        lists, work = (rs, pa, ss, sm), make_work(e.pp, rs, hist, ss, sm, 1)
        nslab = ss.shape[0] - 1
        total = _best(lambda: _slabs(0, nslab, flat, state, e.pp, lists, hist, e.dt, sf, sc, work), a.repeat)
        block = K.thread_blocks(rs, ss, sm, 2)
        parts = []
        for k in range(2):
            members = sm[ss[block[k]]:ss[block[k + 1]]]
            rows = [np.arange(rs[i], rs[i + 1]) for i in members]
            p = np.concatenate(rows) if rows else np.zeros(0, np.int64)
            i = np.repeat(members, [len(r) for r in rows])
            d = np.linalg.norm(st.position[i] - st.position[pa[p]], axis=1)
            touching = int(np.sum(d < st.radius[i] + st.radius[pa[p]]))
            t = _best(lambda k=k: _slabs(block[k], block[k + 1], flat, state, e.pp, lists, hist, e.dt, sf, sc, work),
                      a.repeat)
            parts.append(f"block {k}: {t:6.1f} ({p.size} listed, {touching} touching, {members.size} particles)")
        print(f"at most {cap:3d} slabs: {nslab:3d} slabs, {pa.size} listed pairs, all {total:6.1f}; " + "; ".join(parts))


if __name__ == "__main__":
    main()
