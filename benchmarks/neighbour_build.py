"""Time of one soft-sphere neighbour-list build (``_neighbours_kernels.build_pairs``), against the former one.

    NUMBA_NUM_THREADS=1 python benchmarks/neighbour_build.py [--repeat 200] [--tsuji-state DIR]

Two beds: the 10,000-sphere settled 3D bed of ``fluidem bench`` (skin 1 mm) and the
``tsuji-jet`` particles (2400 spheres of 4 mm, 2D, skin 1 mm): with ``--tsuji-state`` the
particles of a run directory of that case (made with, e.g.,
``NUMBA_NUM_THREADS=1 python -m fluidem run tsuji-jet --until 1.5 --out /tmp/nb_tj``; it is
resumed from a copy), otherwise the particles settled without gas for 0.3 s.

First the builds are checked to be bitwise those of the former kernel (kept below, frozen,
as ``former_build_pairs``): on both beds, and on random polydisperse packings in 2D and 3D
(with skins up to 2 radii, so that the pair buffers overflow and grow, a stray particle,
degenerate layouts, 0 to 3000 particles), with one thread and with all of them. Then both
are timed in interleaved rounds (the machine is shared and its speed drifts: each round
times every variant once, and the minimum over rounds is printed). A fluidised bed
rebuilds its list every 10-20 steps (tsuji-jet: 39,000 rebuilds in 700,000 steps), so
this matters there; a settled bed almost never rebuilds.
"""
from __future__ import annotations

import argparse
import atexit
import shutil
import tempfile
import time

import numba
import numpy as np
from numba import njit, prange

import fluidem as fd
from fluidem.bench import load_bed_engine
from fluidem.particles._neighbours_kernels import _bounds, _grid, build_pairs, max_slabs
from fluidem.particles.softsphere import SoftSphereEngine

# ---- the former build (git 08d3e90), frozen for the comparison ---------------------------------------------


@njit(cache=True, error_model="numpy")
def _former_counting_sort(key, nkeys):
    """CSR of the indices grouped by key: (start (nkeys+1,), members (N,)), stable within a key."""
    n = key.shape[0]
    start = np.zeros(nkeys + 1, dtype=np.int64)
    for i in range(n):
        start[key[i] + 1] += 1
    for c in range(nkeys):
        start[c + 1] += start[c]
    fill = start[:-1].copy()
    members = np.empty(n, dtype=np.int64)
    for i in range(n):
        members[fill[key[i]]] = i
        fill[key[i]] += 1
    return start, members


@njit(cache=True, error_model="numpy")
def _former_cell_grid(pos, radius, skin, dim2):
    """Cell grid of the particles: (lower corner (3,), cells per unit length (3,), cells per axis (3,)), the
    grid of ``build_pairs`` (until 2026-11-26 in ``_neighbours_kernels``, for the hard-sphere list)."""
    lo, hi, rmax = _bounds(pos, radius)
    inv, ncell = _grid(lo, hi, rmax, skin, dim2, pos.shape[0])
    return lo, inv, ncell


@njit(cache=True, error_model="numpy")
def _former_bin(pos, lo, inv, ncell):
    """Cell of each particle (x-major: (x ny + y) nz + z) and the CSR of the cells' members."""
    n = pos.shape[0]
    cell = np.empty(n, dtype=np.int64)
    for i in range(n):
        c = 0
        for d in range(3):
            k = int((pos[i, d] - lo[d]) * inv[d])
            k = max(min(k, ncell[d] - 1), 0)
            c = c * ncell[d] + k
        cell[i] = c
    start, members = _former_counting_sort(cell, ncell[0] * ncell[1] * ncell[2])
    return cell, start, members


@njit(cache=True, error_model="numpy", inline="always")
def _former_fill_row(i, pos, radius, skin, cell, start, members, ncell, slab, buf, w):
    """Append the partners j owned by particle i to ``buf`` from slot w, sorted; returns the new end.

    The append is branch-free (write j, advance by the 0/1 of "owned and within the cut-off"):
    whether a candidate is kept is a coin toss for the branch predictor, and mispredicted
    branches were most of the cost of the list build (3.5x slower in 2D, 2.5x in 3D).
    ``buf`` must have room for every candidate of the row plus one.
    """
    c = cell[i]
    cz = c % ncell[2]
    cy = (c // ncell[2]) % ncell[1]
    cx = c // (ncell[2] * ncell[1])
    xi = pos[i, 0]
    yi = pos[i, 1]
    zi = pos[i, 2]
    ai = radius[i]
    si = slab[i]
    w0 = w
    for x in range(max(cx - 1, 0), min(cx + 2, ncell[0])):
        for y in range(max(cy - 1, 0), min(cy + 2, ncell[1])):
            base = (x * ncell[1] + y) * ncell[2]
            for z in range(max(cz - 1, 0), min(cz + 2, ncell[2])):
                cc = base + z
                for m in range(start[cc], start[cc + 1]):
                    j = members[m]
                    sj = slab[j]
                    rx = xi - pos[j, 0]
                    ry = yi - pos[j, 1]
                    rz = zi - pos[j, 2]
                    cut = ai + radius[j] + skin  # as brute_force_pairs: the same rounding
                    own = (sj > si) | ((sj == si) & (j > i))
                    close = rx * rx + ry * ry + rz * rz < cut * cut
                    buf[w] = j
                    w += np.int64(own & close)
    # insertion sort of the (short) row: deterministic, cache-friendly lookups by partner
    for k in range(w0 + 1, w):
        v = buf[k]
        q = k - 1
        while q >= w0 and buf[q] > v:
            buf[q + 1] = buf[q]
            q -= 1
        buf[q + 1] = v
    return w


@njit(cache=True, error_model="numpy")
def _former_fill_rows(lo, hi, pos, radius, skin, cell, start, members, ncell, slab, buf, counts, room):
    """Rows lo..hi−1 one after the other into ``buf`` (from slot 0), their lengths into ``counts``.

    Returns the slots used, or −1 when fewer than ``room`` (the most candidates one row can
    have) slots were left before a row: the caller retries with a larger buffer."""
    w = 0
    cap = buf.shape[0]
    for i in range(lo, hi):
        if cap - w < room:
            return -1
        w2 = _former_fill_row(i, pos, radius, skin, cell, start, members, ncell, slab, buf, w)
        counts[i] = w2 - w
        w = w2
    return w


@njit(cache=True, error_model="numpy")
def _former_slabs(pos, radius, skin, dim2, max_slabs):
    """Slab index of each particle and CSR of slab members (slabs >= one cut-off wide)."""
    n = pos.shape[0]
    axis = 0
    best = -1.0
    for d in range(2 if dim2 else 3):
        lo = np.inf
        hi = -np.inf
        for i in range(n):
            lo = min(lo, pos[i, d])
            hi = max(hi, pos[i, d])
        if hi - lo > best:
            best = hi - lo
            axis = d
    lo = np.inf
    rmax = 0.0
    for i in range(n):
        lo = min(lo, pos[i, axis])
        rmax = max(rmax, radius[i])
    cut = 2.0 * rmax + skin
    nslab = max(1, min(max_slabs, int(best / cut))) if n > 0 else 1
    width = best / nslab if best > 0 else 1.0
    slab = np.empty(n, dtype=np.int64)
    for i in range(n):
        slab[i] = min(nslab - 1, int((pos[i, axis] - lo) / width))
    start, members = _former_counting_sort(slab, nslab)
    return slab, start, members


_FORMER_BUILD_CHUNKS = 16  # work items of the list build (rows lo..hi each, filled into a buffer of their own)


@njit(cache=True, error_model="numpy", parallel=True)
def former_build_pairs(pos, radius, skin, dim2, expected=0):
    """Half neighbour list (CSR by owner) of all pairs closer than a_i + a_j + skin.

    Returns (row_start (N+1,), partner (P,), slab_start (S+1,), slab_members (N,)).
    Each chunk of rows is filled in one pass into a buffer of its own, then the buffers
    are joined; ``expected`` (e.g. the previous list's length) sizes the buffers, which
    grow if too small. The result does not depend on the chunking or the thread count.
    """
    n = pos.shape[0]
    slab, slab_start, slab_members = _former_slabs(pos, radius, skin, dim2, max_slabs(n))  # as build_pairs now
    lo, inv, ncell = _former_cell_grid(pos, radius, skin, dim2)
    cell, start, members = _former_bin(pos, lo, inv, ncell)
    # the most candidates one row can have: the members of its 3 x 3 (x 3) cells
    room = 1
    for c in range(ncell[0] * ncell[1] * ncell[2]):
        room = max(room, start[c + 1] - start[c])
    room = room * (9 if ncell[2] == 1 else 27) + 1
    nchunk = max(1, min(_FORMER_BUILD_CHUNKS, n // 256))
    per = (n + nchunk - 1) // nchunk
    cap = max(expected, 6 * n) // nchunk + room
    counts = np.zeros(n, dtype=np.int64)
    used = np.zeros(nchunk, dtype=np.int64)
    while True:
        bufs = np.empty((nchunk, cap), dtype=np.int32)
        for c in prange(nchunk):
            used[c] = _former_fill_rows(min(n, c * per), min(n, (c + 1) * per), pos, radius, skin, cell, start, members,
                                 ncell, slab, bufs[c], counts, room)
        if used.min() >= 0:
            break
        cap *= 2
    row_start = np.zeros(n + 1, dtype=np.int64)
    for i in range(n):
        row_start[i + 1] = row_start[i] + counts[i]
    partner = np.empty(row_start[n], dtype=np.int32)  # 4-byte partners: less memory traffic per step
    for c in prange(nchunk):
        b = row_start[min(n, c * per)]
        for k in range(used[c]):
            partner[b + k] = bufs[c, k]
    return row_start, partner, slab_start, slab_members


# ---- checks and timing ----------------------------------------------------------------------------------------


def same_lists(a, b) -> bool:
    """The four arrays equal in dtype, shape and every value."""
    return all(x.dtype == y.dtype and x.shape == y.shape and np.array_equal(x, y) for x, y in zip(a, b))


def random_packing(seed, n, dim2, solid_fraction=0.3, spread=(0.5, 1.5)):
    """Random (overlapping) polydisperse spheres of radius spread x 1 mm at a nominal solid fraction."""
    rng = np.random.default_rng(seed)
    radius = 1e-3 * rng.uniform(*spread, n)
    if dim2:
        side = np.sqrt(np.sum(np.pi * radius**2) / solid_fraction) if n else 1e-3
        pos = np.column_stack([rng.uniform(0, side, (n, 2)), np.full(n, 0.25e-3)])
    else:
        side = np.cbrt(np.sum(4 / 3 * np.pi * radius**3) / solid_fraction) if n else 1e-3
        pos = rng.uniform(0, side, (n, 3)) - 0.3 * side
    return pos, radius


def random_cases():
    """(name, pos, radius, skin, dim2) of the random and degenerate inputs."""
    for dim2 in (False, True):
        for seed, n in ((1, 600), (2, 3000), (3, 50), (4, 5), (5, 2), (6, 1), (7, 0)):
            for skin_in_radii in (0.0, 0.1, 0.5, 2.0):
                pos, radius = random_packing(seed, n, dim2)
                yield f"random n={n} dim2={dim2} skin={skin_in_radii}", pos, radius, skin_in_radii * 1e-3, dim2
        pos, radius = random_packing(9, 800, dim2, solid_fraction=0.5, spread=(0.2, 2.0))
        yield f"wide spread dim2={dim2}", pos, radius, 0.3e-3, dim2
        pos, radius = random_packing(4, 400, dim2)
        pos = np.vstack([pos, [[1.0, -2.0, pos[0, 2]]] if dim2 else [[1.0, -2.0, 3.0]]])
        yield f"stray particle dim2={dim2}", pos, np.append(radius, 1e-3), 0.2e-3, dim2
    n = 40
    line = np.column_stack([np.linspace(0.0, 0.05, n), np.zeros(n), np.zeros(n)])
    yield "line", line, np.full(n, 0.7e-3), 0.1e-3, False
    yield "coincident", np.zeros((5, 3)), np.full(5, 1e-3), 0.0, False


def check(beds) -> int:
    """Assert the new build equals the former bit for bit on every input, with 1 and with all threads."""
    checked = 0
    for threads in sorted({1, numba.config.NUMBA_NUM_THREADS}):
        numba.set_num_threads(threads)
        cases = [(name, pos, radius, skin, dim2) for name, pos, radius, skin, dim2, _ in beds]
        for name, pos, radius, skin, dim2 in cases + list(random_cases()):
            ref = former_build_pairs(pos, radius, skin, dim2, 0)
            for expected in (0, ref[1].shape[0]):
                got = build_pairs(pos, radius, skin, dim2, expected)
                assert same_lists(ref, got), f"{name}: differs from the former build ({threads} threads)"
                checked += 1
    numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
    return checked


def interleaved_min(fns: dict, rounds: int) -> dict:
    """Minimum time of each function over ``rounds`` rounds, each round calling every function once."""
    for fn in fns.values():
        fn()
    best = {k: float("inf") for k in fns}
    for _ in range(rounds):
        for k, fn in fns.items():
            t0 = time.perf_counter()
            fn()
            best[k] = min(best[k], time.perf_counter() - t0)
    return best


def tsuji_engine(state_dir):
    if state_dir is None:
        eng = SoftSphereEngine(fd.load_case("tsuji-jet"))
        eng.advance(round(0.3 / eng.dt))
        return "tsuji-jet particles settled 0.3 s, 2D", eng
    tmp = tempfile.mkdtemp(prefix="nb_tj_")  # resuming writes to the run directory: use a copy
    atexit.register(shutil.rmtree, tmp, True)
    shutil.copytree(state_dir, tmp, dirs_exist_ok=True)
    sim = fd.Simulation.resume(tmp)
    return f"tsuji-jet at t = {sim.engine.time:.3g} s, 2D", sim.engine


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeat", type=int, default=200, help="interleaved rounds (minimum over them)")
    ap.add_argument("--tsuji-state", default=None, help="run directory of the tsuji-jet case to take the particles of")
    a = ap.parse_args()
    beds = []
    for name, eng in (tsuji_engine(a.tsuji_state), ("3D bed, 10,000 spheres", load_bed_engine(10000))):
        st = eng.state
        beds.append((name, st.position, st.radius, eng.skin, eng.dim2, eng.partner.shape[0]))
    print(f"checked bitwise equal to the former build on {check(beds)} inputs")
    print(f"{numba.get_num_threads()} thread(s); minimum of {a.repeat} interleaved rounds")
    for name, pos, radius, skin, dim2, expected in beds:
        args = (pos, radius, skin, dim2, expected)
        best = interleaved_min({"former": lambda args=args: former_build_pairs(*args),
                                "new": lambda args=args: build_pairs(*args)}, a.repeat)
        print(f"{name:40s} {expected:7d} pairs  former {1e6 * best['former']:8.1f} µs  "
              f"new {1e6 * best['new']:8.1f} µs  ({best['former'] / best['new']:.2f}x)")


if __name__ == "__main__":
    main()
