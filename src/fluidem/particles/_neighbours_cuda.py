"""CUDA kernels of the GPU neighbour list: a full Verlet list on a cell grid, with history carried by partner.

The GPU sibling of ``_neighbours_kernels``. Pairs closer than a_i + a_j + skin (the same expression and
cut-off as the CPU list) are listed from both ends: row i holds every partner of i, so that the force
kernel (``_softsphere_cuda.pair_and_wall_forces``) writes particle i's own force only, without atomics.
A row is column k of ``nbr`` (K, N) int32, ``nbr[k, i]`` its k-th partner, ``count[i]`` its length, and
each row is sorted by partner: the list is a function of the positions alone (the order in which threads
filled the cells does not matter), so a run gives the same sums in every repetition and after a restore.
The tangential springs ``hist`` (3, K, N) sit in the same slots, each relative to the row's particle (the
spring of j in row i is minus that of i in row j, bitwise: the law is odd in n and v).

A build (``softsphere_gpu``): ``bounds`` (corners of the centres and the largest radius, to the host) →
the CPU's own ``_grid`` there → ``bin_cells`` (cells of at most ``cap`` members, grown on overflow) →
``fill_rows`` (partners found in the 27 (9) neighbouring cells; rows longer than K reported, K grown) →
``carry_history`` (the spring of each persisting partner copied from the old row). Kernels take their
outputs pre-allocated and return nothing.
"""
import math

from numba import cuda, float64

from .contact._dispatch_cuda import cached_kernel

BOUNDS_THREADS = 256  # threads of a ``bounds`` block (a power of two: its tree reduction)


@cached_kernel
def fill_int(a, value):
    """a[:] = value for a 1D int array."""
    i = cuda.grid(1)
    if i < a.shape[0]:
        a[i] = value


@cached_kernel
def bounds(pos, radius, out):
    """Lower corner (out[0:3]), upper corner (out[3:6]) of the centres and the largest radius (out[6]).

    Grid-stride loop, a tree in shared memory per block, then one atomic per block and value; ``out`` must
    hold (+inf, +inf, +inf, −inf, −inf, −inf, 0) on entry."""
    s = cuda.shared.array((7, BOUNDS_THREADS), float64)
    t = cuda.threadIdx.x
    n = pos.shape[0]
    x0 = math.inf
    y0 = math.inf
    z0 = math.inf
    x1 = -math.inf
    y1 = -math.inf
    z1 = -math.inf
    rmax = 0.0
    i = cuda.grid(1)
    stride = cuda.gridsize(1)
    while i < n:
        x = pos[i, 0]
        y = pos[i, 1]
        z = pos[i, 2]
        x0 = min(x0, x)
        y0 = min(y0, y)
        z0 = min(z0, z)
        x1 = max(x1, x)
        y1 = max(y1, y)
        z1 = max(z1, z)
        rmax = max(rmax, radius[i])
        i += stride
    s[0, t] = x0
    s[1, t] = y0
    s[2, t] = z0
    s[3, t] = x1
    s[4, t] = y1
    s[5, t] = z1
    s[6, t] = rmax
    cuda.syncthreads()
    h = BOUNDS_THREADS // 2
    while h > 0:
        if t < h:
            for q in range(3):
                s[q, t] = min(s[q, t], s[q, t + h])
            for q in range(3, 7):
                s[q, t] = max(s[q, t], s[q, t + h])
        cuda.syncthreads()
        h //= 2
    if t == 0:
        for q in range(3):
            cuda.atomic.min(out, q, s[q, 0])
        for q in range(3, 7):
            cuda.atomic.max(out, q, s[q, 0])


@cuda.jit(device=True)
def cell_of(x, y, z, lx, ly, lz, ix, iy, iz, nx, ny, nz):
    """Cell indices (kx, ky, kz) of a centre, clamped to the grid (the CPU's ``_sort_by_cell``)."""
    kx = min(max(int((x - lx) * ix), 0), nx - 1)
    ky = min(max(int((y - ly) * iy), 0), ny - 1)
    kz = min(max(int((z - lz) * iz), 0), nz - 1)
    return kx, ky, kz


@cached_kernel
def bin_cells(pos, lx, ly, lz, ix, iy, iz, nx, ny, nz, cell_count, members, overflow):
    """Each particle into its cell: ``members[c, :cell_count[c]]`` (any order; at most ``members.shape[1]``
    stored, overflow[0] = 1 when a cell holds more). ``cell_count`` must be zero on entry."""
    i = cuda.grid(1)
    if i >= pos.shape[0]:
        return
    kx, ky, kz = cell_of(pos[i, 0], pos[i, 1], pos[i, 2], lx, ly, lz, ix, iy, iz, nx, ny, nz)
    c = (kx * ny + ky) * nz + kz
    slot = cuda.atomic.add(cell_count, c, 1)
    if slot < members.shape[1]:
        members[c, slot] = i
    else:
        overflow[0] = 1


@cached_kernel
def fill_rows(pos, radius, skin, lx, ly, lz, ix, iy, iz, nx, ny, nz, cell_count, members, nbr, count, longest):
    """Row i of the full list: every j ≠ i with |x_i − x_j|² < (a_i + a_j + skin)², sorted by j.

    ``count[i]`` is the row's length even where it exceeds K = nbr.shape[0] (only the first K are stored);
    ``longest[0]`` is raised (atomic max) to the length of such a row, for the caller to grow K and build
    again."""
    i = cuda.grid(1)
    if i >= pos.shape[0]:
        return
    cap = members.shape[1]
    kmax = nbr.shape[0]
    xi = pos[i, 0]
    yi = pos[i, 1]
    zi = pos[i, 2]
    ai = radius[i]
    kx, ky, kz = cell_of(xi, yi, zi, lx, ly, lz, ix, iy, iz, nx, ny, nz)
    k = 0
    for cx in range(max(kx - 1, 0), min(kx + 2, nx)):
        for cy in range(max(ky - 1, 0), min(ky + 2, ny)):
            for cz in range(max(kz - 1, 0), min(kz + 2, nz)):
                c = (cx * ny + cy) * nz + cz
                for q in range(min(cell_count[c], cap)):
                    j = members[c, q]
                    if j == i:
                        continue
                    rx = xi - pos[j, 0]
                    ry = yi - pos[j, 1]
                    rz = zi - pos[j, 2]
                    cut = ai + radius[j] + skin
                    if rx * rx + ry * ry + rz * rz < cut * cut:
                        if k < kmax:
                            nbr[k, i] = j
                        k += 1
    count[i] = k
    if k > kmax:
        cuda.atomic.max(longest, 0, k)
        return
    for a in range(1, k):  # insertion sort of the row by partner (rows are short)
        v = nbr[a, i]
        b = a - 1
        while b >= 0 and nbr[b, i] > v:
            nbr[b + 1, i] = nbr[b, i]
            b -= 1
        nbr[b + 1, i] = v


@cached_kernel
def carry_history(old_nbr, old_count, old_hist, nbr, count, hist):
    """hist of the new list: the old row's spring where the partner was listed before, else zero (a pair's
    spring is kept relative to the row's particle, so no sign changes). Both lists' rows are sorted: one
    merge-like pass per row."""
    i = cuda.grid(1)
    if i >= count.shape[0]:
        return
    m = old_count[i]
    q = 0
    for k in range(count[i]):
        j = nbr[k, i]
        while q < m and old_nbr[q, i] < j:
            q += 1
        if q < m and old_nbr[q, i] == j:
            hist[0, k, i] = old_hist[0, q, i]
            hist[1, k, i] = old_hist[1, q, i]
            hist[2, k, i] = old_hist[2, q, i]
        else:
            hist[0, k, i] = 0.0
            hist[1, k, i] = 0.0
            hist[2, k, i] = 0.0
