"""Compiled cell-list + Verlet-list construction with tangential-history carry-over.

Pairs closer than a_i + a_j + skin are stored once (a half list, CSR by owner).
The domain is cut into slabs at least one cut-off wide along its longest axis;
a pair belongs to the particle in the lower slab (the lower index within a
slab), so the pairs of slab s touch only particles of slabs s and s + 1. Force
loops then run the even slabs in parallel, then the odd ones, adding straight
into per-particle sums without races. The slab partition depends on geometry
only, so sums have the same order for any thread count: results are bitwise
independent of the number of threads.

How ``build_pairs`` finds the pairs, and why so. Measured with one thread on the tsuji-jet-background
state at t = 1.5 s (2400 spheres in one layer, 24,800 candidates, 4006 pairs) and on the
10,000-sphere 3D bed of ``fluidem bench`` (584,000 candidates, 46,052 pairs). The former build filled each particle's row in turn: 27 (9)
cells, a loop of 0-6 candidates each, read through ``members[m]`` from the particle arrays,
then an insertion sort of the row. Its fill cost ~27 ns a candidate in 2D and 11 ns in 3D,
where a loop over candidates should take 2-3 ns. Three causes:

* signed indices: Numba wraps negative indices round, so each ``a[k]`` with a signed k costs
  a sign test, a masked add and an address rebuild, and the extra live values spilled the
  inner loop to the stack. Indexing with ``np.uintp`` drops that (the former fill with
  unsigned indices: -15 % in 2D, -23 % in 3D). The loops here index through ``U``.
* a short loop per cell: a loop of 0-6 trips ends in a mispredicted branch, ~10 ns (summing
  ``members`` cell by cell took 320 µs in 2D, the cells' bounds alone 80 µs). Here the
  particles are copied in cell order, (x, y, z, a) side by side, and cells are numbered
  x-major, so cells (x, y, z-1..z+1) are one run of slots, and with one cell in z so are
  (x, y-1..y+1): 9 (3) loops a particle instead of 27 (9), and no gather through
  ``members`` (a further -45 % in 2D, -36 % in 3D).
* every pair was tested from both ends, and each row insertion-sorted with a data-dependent
  branch a step (20 % of the fill).

So each pair of neighbouring cells is visited once (a cell's later particles and the 13 (4)
cells "after" it: 5 (2) runs of slots a particle), the pairs within the cut-off are appended
without a branch as owner << 32 | partner, and two stable counting sorts (by partner, then by
owner) make the CSR with every row sorted. A build went from 690 to 170 µs (tsuji-jet-background) and
from 6.6 to 1.9 ms (10k bed). The pairs are the former ones (the same cells, the same
expressions for the distance and the cut-off, symmetric in i and j to the last bit) and their
order is fixed by the sort, so the output is bitwise the former one for any chunking and
thread count.
"""
import numpy as np
from numba import njit, prange

U = np.uintp  # unsigned array index: no wrap-around code for negative indices (see above)


@njit(cache=True, error_model="numpy")
def _bounds(pos, radius):
    """Lower and upper corner of the particle centres (3,) and the largest radius, in one pass."""
    n = pos.shape[0]
    x0 = np.inf
    y0 = np.inf
    z0 = np.inf
    x1 = -np.inf
    y1 = -np.inf
    z1 = -np.inf
    rmax = 0.0
    for i in range(n):
        ui = U(i)
        x = pos[ui, U(0)]
        y = pos[ui, U(1)]
        z = pos[ui, U(2)]
        x0 = min(x0, x)
        x1 = max(x1, x)
        y0 = min(y0, y)
        y1 = max(y1, y)
        z0 = min(z0, z)
        z1 = max(z1, z)
        rmax = max(rmax, radius[ui])
    lo = np.empty(3)
    hi = np.empty(3)
    lo[0] = x0
    lo[1] = y0
    lo[2] = z0
    hi[0] = x1
    hi[1] = y1
    hi[2] = z1
    return lo, hi, rmax


@njit(cache=True, error_model="numpy")
def _grid(lo, hi, rmax, skin, dim2, n):
    """Cells per axis (at least 2 R_max + skin wide) and cells per unit length, for the bounds lo, hi."""
    size = 2.0 * rmax + skin
    ncell = np.ones(3, dtype=np.int64)
    # grow cells if a stray particle would make the grid too large
    while True:
        total = 1
        for d in range(3):
            if dim2 and d == 2:
                ncell[d] = 1
            else:
                ncell[d] = max(1, int((hi[d] - lo[d]) / size))
            total *= ncell[d]
        if total <= 4 * n + 64:
            break
        size *= 1.5
    inv = np.empty(3)
    for d in range(3):
        ext = hi[d] - lo[d]
        inv[d] = ncell[d] / ext if ext > 0 else 0.0
    return inv, ncell


@njit(cache=True, error_model="numpy")
def _sort_by_cell(pos, radius, lo, hi, rmax, skin, dim2, max_slabs, inv, ncell):
    """Slabs and cells of the particles, in one pass over them and one scatter.

    Returns (slab_start (S+1,), slab_members (N,)): the slabs (at least one cut-off
    2 R_max + skin wide along the longest axis, at most ``max_slabs``) as CSR, members
    ascending; (start (C+1,), xs (N, 4), key (N,), kmax): the particles in cell order (x-major
    cells, ascending index within a cell), start[c] the first slot of cell c, xs[m] = (x, y, z, a)
    and key[m] = slab << 32 | index of the particle in slot m, and the most particles in a cell.
    The key orders a pair's ends as the list does: the smaller key owns the pair.
    """
    n = pos.shape[0]
    axis = 0
    best = -1.0
    for d in range(2 if dim2 else 3):
        if hi[d] - lo[d] > best:
            best = hi[d] - lo[d]
            axis = d
    a0 = lo[axis]
    nslab = max(1, min(max_slabs, int(best / (2.0 * rmax + skin)))) if n > 0 else 1
    width = best / nslab if best > 0 else 1.0
    nx = ncell[0]
    ny = ncell[1]
    nz = ncell[2]
    ncells = nx * ny * nz
    slab = np.empty(n, dtype=np.int64)
    cell = np.empty(n, dtype=np.int64)
    slab_start = np.zeros(nslab + 1, dtype=np.int64)
    start = np.zeros(ncells + 1, dtype=np.int64)
    for i in range(n):
        ui = U(i)
        s = min(nslab - 1, int((pos[ui, U(axis)] - a0) / width))
        kx = min(max(int((pos[ui, U(0)] - lo[0]) * inv[0]), 0), nx - 1)
        ky = min(max(int((pos[ui, U(1)] - lo[1]) * inv[1]), 0), ny - 1)
        kz = min(max(int((pos[ui, U(2)] - lo[2]) * inv[2]), 0), nz - 1)
        c = (kx * ny + ky) * nz + kz
        slab[ui] = s
        cell[ui] = c
        slab_start[U(s + 1)] += 1
        start[U(c + 1)] += 1
    t = 0
    for k in range(nslab + 1):
        t += slab_start[U(k)]
        slab_start[U(k)] = t
    t = 0
    kmax = 1
    for c in range(ncells + 1):
        kmax = max(kmax, start[U(c)])  # a count still
        t += start[U(c)]
        start[U(c)] = t
    sfill = slab_start[:-1].copy()
    fill = start[:-1].copy()
    slab_members = np.empty(n, dtype=np.int64)
    xs = np.empty((n, 4))
    key = np.empty(n, dtype=np.int64)
    for i in range(n):
        ui = U(i)
        s = slab[ui]
        q = sfill[U(s)]
        sfill[U(s)] = q + 1
        slab_members[U(q)] = i
        c = cell[ui]
        m = fill[U(c)]
        fill[U(c)] = m + 1
        um = U(m)
        xs[um, U(0)] = pos[ui, U(0)]
        xs[um, U(1)] = pos[ui, U(1)]
        xs[um, U(2)] = pos[ui, U(2)]
        xs[um, U(3)] = radius[ui]
        key[um] = (s << 32) | i
    return slab_start, slab_members, start, xs, key, kmax


@njit(cache=True, error_model="numpy", inline="always")
def _scan(xi, yi, zi, ai, kh, a, b, skin, xs, key, out, w):
    """Append the pairs of the particle (xi, yi, zi, ai, key kh) with slots a..b−1 to ``out`` from w.

    A pair is written as owner << 32 | partner, at w, which then advances by the 0/1 of
    "within the cut-off": no branch on that coin toss (the former fill measured mispredicted
    branches there as most of its cost, 3.5x in 2D). The distance and cut-off are the
    expressions of the O(N²) search the tests compare with (``tests/_helpers/neighbours.py``), to the same
    rounding whichever end is i.
    """
    for m in range(a, b):
        um = U(m)
        rx = xi - xs[um, U(0)]
        ry = yi - xs[um, U(1)]
        rz = zi - xs[um, U(2)]
        cut = ai + xs[um, U(3)] + skin
        km = key[um]
        out[U(w)] = ((kh << 32) | (km & 0xFFFFFFFF)) if km > kh else ((km << 32) | (kh & 0xFFFFFFFF))
        w += np.int64(rx * rx + ry * ry + rz * rz < cut * cut)
    return w


@njit(cache=True, error_model="numpy")
def _pairs_from(h0, h1, skin, ncell, start, xs, key, out, room):
    """The pairs found from the particles in slots h0..h1−1 (cell order) into ``out``; returns their number.

    The particle in slot h is tested against the later slots of its own cell and the cells
    "after" its cell, so that each pair of neighbouring cells is visited once: in 3D cell
    (x, y, z+1) (contiguous with the own cell), (x, y+1, z-1..z+1) and (x+1, y-1..y+1, z-1..z+1),
    5 contiguous runs of slots; with one cell in z, (x, y+1) and (x+1, y-1..y+1), 2 runs.
    Returns −1 when fewer than ``room`` slots (the most one particle can append) were left
    before a particle: the caller retries with a larger buffer.
    """
    nx = ncell[0]
    ny = ncell[1]
    nz = ncell[2]
    cap = out.shape[0]
    w = 0
    if h0 >= h1:
        return 0
    lo = 0  # the cell of slot h0: the last c with start[c] <= h0 (bisection)
    hi = start.shape[0] - 1
    while lo < hi:
        mid = (lo + hi + 1) // 2
        if start[U(mid)] <= h0:
            lo = mid
        else:
            hi = mid - 1
    c = lo
    cz = c % nz
    cy = (c // nz) % ny
    cx = c // (nz * ny)
    h = h0
    while h < h1:  # cell by cell; (cx, cy, cz) follow c without divisions
        e = start[U(c + 1)]
        if e > h:
            y0 = max(cy - 1, 0)
            y1 = min(cy + 2, ny)
            z0 = max(cz - 1, 0)
            z1 = min(cz + 2, nz)
            if nz == 1:
                e1 = start[U(min(c + 2, (cx + 1) * ny))]  # own cell and (x, y+1)
                xn = min(cx + 1, nx - 1)
                a2 = start[U(xn * ny + y0)]  # (x+1, y-1..y+1), empty at the last x
                b2 = start[U(xn * ny + y1)] if cx + 1 < nx else a2
            else:
                e1 = start[U(c + 2)] if cz + 1 < nz else e  # own cell and (x, y, z+1)
            for hh in range(h, min(e, h1)):
                if cap - w < room:
                    return -1
                uh = U(hh)
                xi = xs[uh, U(0)]
                yi = xs[uh, U(1)]
                zi = xs[uh, U(2)]
                ai = xs[uh, U(3)]
                kh = key[uh]
                w = _scan(xi, yi, zi, ai, kh, hh + 1, e1, skin, xs, key, out, w)
                if nz == 1:
                    w = _scan(xi, yi, zi, ai, kh, a2, b2, skin, xs, key, out, w)
                else:
                    if cy + 1 < ny:
                        base = (cx * ny + cy + 1) * nz
                        w = _scan(xi, yi, zi, ai, kh, start[U(base + z0)], start[U(base + z1)], skin, xs, key,
                                  out, w)
                    if cx + 1 < nx:
                        for y in range(y0, y1):
                            base = ((cx + 1) * ny + y) * nz
                            w = _scan(xi, yi, zi, ai, kh, start[U(base + z0)], start[U(base + z1)], skin, xs, key,
                                      out, w)
            h = min(e, h1)
        c += 1
        cz += 1
        if cz == nz:
            cz = 0
            cy += 1
            if cy == ny:
                cy = 0
                cx += 1
    return w


@njit(cache=True, error_model="numpy", parallel=True)
def _pairs_parallel(n, skin, ncell, start, xs, key, out, used, room):
    """Chunk c of the slots (n c / C .. n (c+1) / C − 1) into out[c], its count (or −1) into used[c]."""
    nchunk = used.shape[0]
    for c in prange(nchunk):
        used[c] = _pairs_from(n * c // nchunk, n * (c + 1) // nchunk, skin, ncell, start, xs, key, out[c], room)


@njit(cache=True, error_model="numpy")
def _csr_of_pairs(n, out, used):
    """(row_start (N+1,), partner (P,) int32) of the pairs out[c, :used[c]] (owner << 32 | partner).

    Two stable counting sorts, by partner then by owner, leave each row sorted: no sort per row
    (an insertion sort per row after the scatter by owner cost twice as much, 51 against 27 µs
    on the tsuji-jet-background state, 610 against 320 µs on the 10k bed, its short loops mispredicted).
    """
    npair = 0
    for c in range(used.shape[0]):
        npair += used[c]
    by_partner = np.zeros(n + 1, dtype=np.int64)
    row_start = np.zeros(n + 1, dtype=np.int64)
    for c in range(used.shape[0]):
        for k in range(used[c]):
            v = out[U(c), U(k)]
            by_partner[U((v & 0xFFFFFFFF) + 1)] += 1
            row_start[U((v >> 32) + 1)] += 1
    s = 0
    t = 0
    for i in range(n + 1):
        s += by_partner[U(i)]
        by_partner[U(i)] = s
        t += row_start[U(i)]
        row_start[U(i)] = t
    sorted_p = np.empty(npair, dtype=np.int64)
    for c in range(used.shape[0]):
        for k in range(used[c]):
            v = out[U(c), U(k)]
            p = v & 0xFFFFFFFF
            q = by_partner[U(p)]
            by_partner[U(p)] = q + 1
            sorted_p[U(q)] = v
    fill = row_start[:-1].copy()
    partner = np.empty(npair, dtype=np.int32)  # 4-byte partners: less memory traffic per step
    for q in range(npair):
        v = sorted_p[U(q)]
        o = v >> 32
        r = fill[U(o)]
        fill[U(o)] = r + 1
        partner[U(r)] = v & 0xFFFFFFFF
    return row_start, partner


BUILD_CHUNKS = 16  # work items of the pair search (slots lo..hi each, into a buffer of their own)
PARTICLES_PER_SLAB = 150  # slabs: about one per this many particles, 8 to 64 (``max_slabs``)


@njit(cache=True, error_model="numpy")
def max_slabs(n):
    """Most slabs for n particles: n / PARTICLES_PER_SLAB, at least 8 and at most 64.

    The pair forces run slab by slab (``_pair_kernels``), with a fixed cost per slab, and threads take
    contiguous blocks of slabs (two parities each), so a bed needs enough slabs to share out evenly and
    few enough that each slab's contacts fill the vector chunks. On the 2400-sphere tsuji-jet-background bed
    (about 590 contacts among 3859 listed pairs) the pair phase took 59 µs in 64 slabs and 51 µs in 16 (one
    thread); the 10,000- and 100,000-sphere beds keep 64. A function of the particle count only, never
    of the thread count: the sums stay bitwise the same for any number of threads.
    """
    return min(64, max(8, n // PARTICLES_PER_SLAB))


@njit(cache=True, error_model="numpy")
def build_pairs(pos, radius, skin, dim2, expected=0, slabs=0):
    """Half neighbour list (CSR by owner) of all pairs closer than a_i + a_j + skin.

    Returns (row_start (N+1,), partner (P,) int32, slab_start (S+1,), slab_members (N,)); each
    row lists its partners ascending. The particles are copied in cell order, chunks of them
    search their pairs in parallel (``_pairs_from``), each chunk into a buffer of its own,
    and a counting sort makes the CSR (``_csr_of_pairs``); ``expected`` (e.g. the previous
    list's length) sizes the buffers, which grow if too small. The result does not depend
    on the chunking or the thread count: it is the sorted set of pairs. Pairs are packed as
    owner << 32 | partner, which needs N < 2^31 (as the int32 partners do). ``slabs``: the most slabs
    (0: ``max_slabs(N)``, what the engine uses).
    """
    n = pos.shape[0]
    lo, hi, rmax = _bounds(pos, radius)
    inv, ncell = _grid(lo, hi, rmax, skin, dim2, n)
    slab_start, slab_members, start, xs, key, kmax = _sort_by_cell(pos, radius, lo, hi, rmax, skin, dim2,
                                                                   slabs if slabs > 0 else max_slabs(n), inv, ncell)
    # the most pairs one particle can append: 2 + 3 cells (one cell in z) or 2 + 3 + 9 cells of kmax
    room = kmax * (5 if ncell[2] == 1 else 14) + 1
    nchunk = max(1, min(BUILD_CHUNKS, n // 256))
    cap = max(expected, 6 * n) // nchunk + room
    used = np.zeros(nchunk, dtype=np.int64)
    while True:
        out = np.empty((nchunk, cap), dtype=np.int64)
        _pairs_parallel(n, skin, ncell, start, xs, key, out, used, room)
        if used.min() >= 0:
            break
        cap *= 2
    row_start, partner = _csr_of_pairs(n, out, used)
    return row_start, partner, slab_start, slab_members


@njit(cache=True, error_model="numpy")
def cell_order(pos, radius, skin, dim2):
    """(N,) int64: the particles ordered by slab, then by cell (x-major), then by index, with the slabs and
    cells of ``build_pairs`` (new particle k is old particle order[k]).

    Numbered so, the particles of a slab are one run of memory and a pair's two ends lie close: the force
    loops then walk their arrays in order, and two threads working on different slabs no longer write into
    the same cache lines (see ``_softsphere_kernels.reorder``)."""
    n = pos.shape[0]
    lo, hi, rmax = _bounds(pos, radius)
    inv, ncell = _grid(lo, hi, rmax, skin, dim2, n)
    slab_start, _, _, _, key, _ = _sort_by_cell(pos, radius, lo, hi, rmax, skin, dim2, max_slabs(n), inv, ncell)
    fill = slab_start[:-1].copy()
    order = np.empty(n, dtype=np.int64)
    for m in range(n):  # slots in cell order, dealt into their slabs (stable)
        k = key[U(m)]
        s = k >> 32
        q = fill[U(s)]
        fill[U(s)] = q + 1
        order[U(q)] = k & 0xFFFFFFFF
    return order


@njit(cache=True, error_model="numpy")
def renumber_pairs(row_start, partner, hist, new_index):
    """The half list (row_start, partner, hist) with particle i renamed new_index[i]: rows by new owner,
    partners ascending; a pair keeps its owner and its history."""
    n = row_start.shape[0] - 1
    npair = partner.shape[0]
    keys = np.empty(npair, dtype=np.int64)
    for i in range(n):
        a = new_index[U(i)]
        for p in range(row_start[U(i)], row_start[U(i + 1)]):
            keys[U(p)] = (a << 32) | new_index[U(partner[U(p)])]
    order = np.argsort(keys)  # keys are distinct: the order is unique
    new_start = np.zeros(n + 1, dtype=np.int64)
    new_partner = np.empty(npair, dtype=np.int32)
    new_hist = np.empty((npair, hist.shape[1]))
    for q in range(npair):
        p = order[U(q)]
        k = keys[U(p)]
        new_start[U((k >> 32) + 1)] += 1
        new_partner[U(q)] = k & 0xFFFFFFFF
        new_hist[U(q), U(0)] = hist[U(p), U(0)]
        new_hist[U(q), U(1)] = hist[U(p), U(1)]
        new_hist[U(q), U(2)] = hist[U(p), U(2)]
        for e in range(3, hist.shape[1]):  # columns of an adhesive law (scalars of the pair)
            new_hist[U(q), U(e)] = hist[U(p), U(e)]
    for i in range(n):
        new_start[U(i + 1)] += new_start[U(i)]
    return new_start, new_partner, new_hist


@njit(cache=True, error_model="numpy", inline="always")
def _find(start, partner, i, j):
    """Slot of partner j in row i, or −1 (a linear scan: rows hold a few partners, and the soft-sphere
    engine keeps them in contact-first order, not sorted; see ``contacts_first``)."""
    for q in range(start[i], start[i + 1]):
        if partner[q] == j:
            return q
    return -1


ROWS_PER_ITEM = 256  # rows per parallel work item of contacts_first


@njit(cache=True, error_model="numpy", parallel=True)
def contacts_first(pos, radius, row_start, partner, hist):
    """Reorder every row in place so that the pairs touching now come first, each part ascending.

    The pair loop branches on contact; in a dense bed about half the listed pairs touch, in an
    order the branch predictor cannot learn (a mispredicted branch a pair). Contacts outlive list
    rebuilds, so with the touching pairs first each row costs about one misprediction (10,000-sphere
    bench bed: pair loop −13 %). Same pairs and histories, other order: force sums are taken in
    another order (round-off), still the same for any thread count: rows are reordered independently,
    in work items of ROWS_PER_ITEM rows on all threads.
    """
    n = row_start.shape[0] - 1
    m = np.int64(0)
    for i in range(n):
        m = max(m, row_start[i + 1] - row_start[i])
    for c in prange((n + ROWS_PER_ITEM - 1) // ROWS_PER_ITEM):
        _contacts_first_rows(c * ROWS_PER_ITEM, min(n, (c + 1) * ROWS_PER_ITEM), m, pos, radius, row_start, partner,
                             hist)


@njit(cache=True, error_model="numpy")
def _contacts_first_rows(lo, hi, m, pos, radius, row_start, partner, hist):
    """``contacts_first`` for rows lo..hi−1; m: the longest row."""
    tmp_p = np.empty(m, dtype=partner.dtype)
    width = hist.shape[1]
    tmp_h = np.empty((m, width))
    for i_ in range(lo, hi):
        i = U(i_)
        r0 = row_start[i]
        r1 = row_start[i + U(1)]
        if r1 - r0 < 2:
            continue
        a = 0
        b = 0
        for p_ in range(r0, r1):
            p = U(p_)
            j = U(partner[p])
            rx = pos[i, U(0)] - pos[j, U(0)]
            ry = pos[i, U(1)] - pos[j, U(1)]
            rz = pos[i, U(2)] - pos[j, U(2)]
            cut = radius[i] + radius[j]
            if rx * rx + ry * ry + rz * rz < cut * cut:
                q = U(a)
                a += 1
            else:
                b += 1
                q = U(m - b)
            tmp_p[q] = partner[p]
            tmp_h[q, U(0)] = hist[p, U(0)]
            tmp_h[q, U(1)] = hist[p, U(1)]
            tmp_h[q, U(2)] = hist[p, U(2)]
            for e in range(3, width):
                tmp_h[q, U(e)] = hist[p, U(e)]
        for k in range(a):  # touching pairs, in their former order
            p = U(r0 + k)
            partner[p] = tmp_p[U(k)]
            hist[p, U(0)] = tmp_h[U(k), U(0)]
            hist[p, U(1)] = tmp_h[U(k), U(1)]
            hist[p, U(2)] = tmp_h[U(k), U(2)]
            for e in range(3, width):
                hist[p, U(e)] = tmp_h[U(k), U(e)]
        for k in range(b):  # then the others, in their former order (stored backwards from the end)
            p = U(r0 + a + k)
            q = U(m - 1 - k)
            partner[p] = tmp_p[q]
            hist[p, U(0)] = tmp_h[q, U(0)]
            hist[p, U(1)] = tmp_h[q, U(1)]
            hist[p, U(2)] = tmp_h[q, U(2)]
            for e in range(3, width):
                hist[p, U(e)] = tmp_h[q, U(e)]


@njit(cache=True, error_model="numpy", parallel=True)
def carry_history(old_start, old_partner, old_hist, new_start, new_partner):
    """Tangential history of the new list, copied from the old list where a pair persists.

    A pair whose owner changed (a particle crossed a slab boundary) is found in the
    old row of its partner; its history, kept relative to the owner, changes sign.
    Column 3 (an adhesive law's pull-off distance) is a scalar of the pair: copied as it is; columns 4-6 (an
    ``epsd`` law's rolling spring torque, ``contact.base.ROLLING_HISTORY``) are kept relative to the owner, as
    the tangential spring: they change sign with it.
    """
    n = new_start.shape[0] - 1
    hist = np.zeros((new_partner.shape[0], old_hist.shape[1]))
    for i in prange(n):
        for p in range(new_start[i], new_start[i + 1]):
            j = new_partner[p]
            q = _find(old_start, old_partner, i, j)
            sign = 1.0
            if q < 0:
                q = _find(old_start, old_partner, j, i)
                sign = -1.0
            if q >= 0:
                hist[p, 0] = sign * old_hist[q, 0]
                hist[p, 1] = sign * old_hist[q, 1]
                hist[p, 2] = sign * old_hist[q, 2]
                for e in range(3, old_hist.shape[1]):
                    hist[p, e] = (sign if e >= 4 else 1.0) * old_hist[q, e]
    return hist


# ---------------------------------------------------------------- periodic sides
# A box side made periodic (``walls.periodic``) joins the box's two planes on that axis: a particle leaving
# through one re-enters through the other, and two particles interact through their nearest images
# (minimum image convention, Allen & Tildesley 1987 §1.5.3, eq. 1.9: r_ij ← r_ij − L round(r_ij / L)).
# ``period`` (3,) holds the box length L_d [m] of each periodic axis and 0 elsewhere, ``box_lo`` (3,) the
# box's lower corner. Positions are kept in [lo_d, lo_d + L_d] (``_softsphere_kernels.wrap_positions``), so
# |x_i − x_j| ≤ L_d and one correction by ±L_d gives the nearest image. The kernels above, for boxes without
# periodic sides, are left as they are; those below serve periodic boxes only.


@njit(cache=True, error_model="numpy", inline="always")
def nearest_image(r, length):
    """The component r = x_i − x_j [m] of the nearest image along an axis of period ``length`` (0: not
    periodic, r unchanged): r − L if r > L/2, r + L if r < −L/2 (Allen & Tildesley 1987 eq. 1.9 for
    |r| ≤ L)."""
    if r > 0.5 * length:
        return r - length
    if r < -0.5 * length:
        return r + length
    return r


@njit(cache=True, error_model="numpy", inline="always")
def _owns(si, i, sj, j, wrap):
    """True if particle i (slab si) owns the pair with j (slab sj): the lower key (slab << 32 | index), as
    ``build_pairs`` orders them, except across the periodic seam of the slab axis (``wrap``: slabs 0 and
    S − 1 are neighbours), where the particle of slab S − 1 owns it, so that slab s's pairs still touch
    only slabs s and s + 1 (mod S)."""
    if wrap and (si - sj > 1 or sj - si > 1):
        return si > sj
    return ((si << 32) | i) < ((sj << 32) | j)


@njit(cache=True, error_model="numpy")
def periodic_layout(pos, radius, skin, dim2, period, box_lo, max_slabs):
    """Cells and slabs of a box with periodic sides: the grid of ``_grid`` over the particles' bounds,
    except that a periodic axis spans the box [lo, lo + L) exactly (cells at least 2 R_max + skin wide,
    so the nearest image of a neighbour lies in a neighbouring cell, across the seam too). Slabs along the
    longest axis, an even number of them (at least 3) where that axis is periodic, so that the parities
    alternate round the seam.

    Returns (lo (3,), inv (3,), ncell (3,), axis, nslab, width, wrap)."""
    n = pos.shape[0]
    lo, hi, rmax = _bounds(pos, radius)
    for d in range(3):
        if period[d] > 0.0:
            lo[d] = box_lo[d]
            hi[d] = box_lo[d] + period[d]
    inv, ncell = _grid(lo, hi, rmax, skin, dim2, n)
    axis = 0
    best = -1.0
    for d in range(2 if dim2 else 3):
        if hi[d] - lo[d] > best:
            best = hi[d] - lo[d]
            axis = d
    nslab = max(1, min(max_slabs, int(best / (2.0 * rmax + skin)))) if n > 0 else 1
    if period[axis] > 0.0 and nslab >= 3 and nslab % 2 == 1:
        nslab -= 1
    width = best / nslab if best > 0 else 1.0
    wrap = period[axis] > 0.0 and nslab >= 3
    return lo, inv, ncell, axis, nslab, width, wrap


@njit(cache=True, error_model="numpy")
def _periodic_row(i, pos, radius, skin, period, ncell, cell_of, cstart, cmembers, slab, wrap, out, count_only):
    """The partners j of particle i that i owns (``_owns``) with |r_ij| < a_i + a_j + skin by nearest image,
    written to ``out`` unless ``count_only``; returns their number. The 3 × 3 × 3 stencil of i's cell wraps
    round a periodic axis (an axis of fewer than three cells is searched whole, each cell once)."""
    c = cell_of[i]
    nz = ncell[2]
    ny = ncell[1]
    cc = (c // (ny * nz), (c // nz) % ny, c % nz)
    k_lo = np.empty(3, dtype=np.int64)
    k_hi = np.empty(3, dtype=np.int64)
    for d in range(3):
        nd = ncell[d]
        if period[d] > 0.0 and nd < 3:
            k_lo[d] = 0
            k_hi[d] = nd - 1
        elif period[d] > 0.0:
            k_lo[d] = cc[d] - 1
            k_hi[d] = cc[d] + 1
        else:
            k_lo[d] = max(cc[d] - 1, 0)
            k_hi[d] = min(cc[d] + 1, nd - 1)
    xi = pos[i, 0]
    yi = pos[i, 1]
    zi = pos[i, 2]
    ai = radius[i]
    si = slab[i]
    w = 0
    for kx_ in range(k_lo[0], k_hi[0] + 1):
        kx = kx_ % ncell[0]
        for ky_ in range(k_lo[1], k_hi[1] + 1):
            ky = ky_ % ny
            for kz_ in range(k_lo[2], k_hi[2] + 1):
                cell = (kx * ny + ky) * nz + kz_ % nz
                for m in range(cstart[cell], cstart[cell + 1]):
                    j = cmembers[m]
                    if j == i or not _owns(si, i, slab[j], j, wrap):
                        continue
                    rx = nearest_image(xi - pos[j, 0], period[0])
                    ry = nearest_image(yi - pos[j, 1], period[1])
                    rz = nearest_image(zi - pos[j, 2], period[2])
                    cut = ai + radius[j] + skin
                    if rx * rx + ry * ry + rz * rz < cut * cut:
                        if not count_only:
                            out[w] = j
                        w += 1
    return w


@njit(cache=True, error_model="numpy", parallel=True)
def build_pairs_periodic(pos, radius, skin, dim2, period, box_lo, slabs=0):
    """``build_pairs`` for a box with periodic sides: the half list (CSR by owner, rows ascending) of all
    pairs closer than a_i + a_j + skin between nearest images (``nearest_image``), and the slabs
    (``periodic_layout``). A pair across the seam of a periodic slab axis belongs to its particle in the
    last slab (``_owns``), so the pair loops' two parities (even slabs, then odd ones) stay free of races.
    Needs L_d ≥ 2 (2 R_max + skin) on each periodic axis (checked by the engine), so that a pair has one
    nearest image. Positions within [lo_d, lo_d + L_d] on the periodic axes."""
    n = pos.shape[0]
    lo, inv, ncell, axis, nslab, width, wrap = periodic_layout(pos, radius, skin, dim2, period, box_lo,
                                                               slabs if slabs > 0 else max_slabs(n))
    ncells = ncell[0] * ncell[1] * ncell[2]
    slab = np.empty(n, dtype=np.int64)
    cell_of = np.empty(n, dtype=np.int64)
    slab_start = np.zeros(nslab + 1, dtype=np.int64)
    cstart = np.zeros(ncells + 1, dtype=np.int64)
    for i in range(n):
        s = min(nslab - 1, max(0, int((pos[i, axis] - lo[axis]) / width)))
        kx = min(max(int((pos[i, 0] - lo[0]) * inv[0]), 0), ncell[0] - 1)
        ky = min(max(int((pos[i, 1] - lo[1]) * inv[1]), 0), ncell[1] - 1)
        kz = min(max(int((pos[i, 2] - lo[2]) * inv[2]), 0), ncell[2] - 1)
        slab[i] = s
        cell_of[i] = (kx * ncell[1] + ky) * ncell[2] + kz
        slab_start[s + 1] += 1
        cstart[cell_of[i] + 1] += 1
    for k in range(nslab):
        slab_start[k + 1] += slab_start[k]
    for c in range(ncells):
        cstart[c + 1] += cstart[c]
    sfill = slab_start[:-1].copy()
    cfill = cstart[:-1].copy()
    slab_members = np.empty(n, dtype=np.int64)
    cmembers = np.empty(n, dtype=np.int64)
    for i in range(n):  # ascending index within each slab and cell
        slab_members[sfill[slab[i]]] = i
        sfill[slab[i]] += 1
        cmembers[cfill[cell_of[i]]] = i
        cfill[cell_of[i]] += 1
    counts = np.zeros(n + 1, dtype=np.int64)
    none = np.empty(0, dtype=np.int32)
    for i in prange(n):
        counts[i + 1] = _periodic_row(np.int64(i), pos, radius, skin, period, ncell, cell_of, cstart, cmembers, slab,
                                      wrap, none, True)
    row_start = np.cumsum(counts)
    partner = np.empty(row_start[n], dtype=np.int32)
    for i in prange(n):
        row = partner[row_start[i]:row_start[i + 1]]
        _periodic_row(np.int64(i), pos, radius, skin, period, ncell, cell_of, cstart, cmembers, slab, wrap, row, False)
        row.sort()
    return row_start, partner, slab_start, slab_members


@njit(cache=True, error_model="numpy", parallel=True)
def contacts_first_periodic(pos, radius, row_start, partner, hist, period):
    """``contacts_first`` with distances between nearest images (a box with periodic sides)."""
    n = row_start.shape[0] - 1
    m = np.int64(0)
    for i in range(n):
        m = max(m, row_start[i + 1] - row_start[i])
    for c in prange((n + ROWS_PER_ITEM - 1) // ROWS_PER_ITEM):
        _contacts_first_rows_periodic(c * ROWS_PER_ITEM, min(n, (c + 1) * ROWS_PER_ITEM), m, pos, radius, row_start,
                                      partner, hist, period)


@njit(cache=True, error_model="numpy")
def _contacts_first_rows_periodic(lo, hi, m, pos, radius, row_start, partner, hist, period):
    """``_contacts_first_rows`` by nearest image."""
    tmp_p = np.empty(m, dtype=partner.dtype)
    width = hist.shape[1]
    tmp_h = np.empty((m, width))
    for i in range(lo, hi):
        r0 = row_start[i]
        r1 = row_start[i + 1]
        if r1 - r0 < 2:
            continue
        a = 0
        b = 0
        for p in range(r0, r1):
            j = partner[p]
            rx = nearest_image(pos[i, 0] - pos[j, 0], period[0])
            ry = nearest_image(pos[i, 1] - pos[j, 1], period[1])
            rz = nearest_image(pos[i, 2] - pos[j, 2], period[2])
            cut = radius[i] + radius[j]
            if rx * rx + ry * ry + rz * rz < cut * cut:
                q = a
                a += 1
            else:
                b += 1
                q = m - b
            tmp_p[q] = partner[p]
            for e in range(width):
                tmp_h[q, e] = hist[p, e]
        for k in range(a):
            partner[r0 + k] = tmp_p[k]
            for e in range(width):
                hist[r0 + k, e] = tmp_h[k, e]
        for k in range(b):
            partner[r0 + a + k] = tmp_p[m - 1 - k]
            for e in range(width):
                hist[r0 + a + k, e] = tmp_h[m - 1 - k, e]
