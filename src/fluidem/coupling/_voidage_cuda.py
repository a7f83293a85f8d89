"""CUDA kernels of the particle → grid map (``_voidage_kernels``' deposits), one thread per particle.

``centroid_deposit`` adds each particle's volume V_p to the cell holding its centre (Sun 2007 eq. 34), a
count of 1 (Hoomans 1996 eq. 50's number average) and its weighted velocity. ``area_deposit`` adds s A_pij,
the exact area of the particle's disc in every cell it overlaps (Hoomans 1996 §3.4) times s = 1 ('area') or
V_p/(π r²) ('area_volume'), through ``_voidage_kernels.area_deposit_one`` compiled for the device from the
CPU's own source with every helper it calls (``disc_rect_area_into``, ``_segment``: the closed forms of
``disc_rect_area``), its cell additions made atomic; parts of a disc outside the grid are dropped as there.
``sauter_deposit`` adds Σ V_p/d_p and Σ V_p of the centres in each cell (DEM book 2012 two-phase chapter,
eq. 10; ``_voidage_kernels.sauter_inverse``). The additions are atomic: the cells' sums are the CPU's to
round-off, added in another order (and not bit for bit from run to run). The rest of the map (the fraction
over V_cell, smoothing, clipping, the averages, 1/D̄) works on cell arrays and runs on the host
(``_voidage_kernels.finish_map``), so only cell arrays leave the device.
"""
import math

from numba import cuda, float64

from ..particles.contact._dispatch_cuda import cached_kernel, device_function
from . import _voidage_kernels as VK
from .drag._dispatch_cuda import device_tree

THREADS = 128  # threads per block

cell_index = device_function(VK.cell_index)  # floor(x/d) clamped to the grid, as on the CPU


@cuda.jit(device=True)
def _add_weighted(out, out_vx, out_vy, i, j, w, vx, vy):
    """out[i, j] += w, out_v*[i, j] += w v* (``_voidage_kernels._add``), atomically."""
    cuda.atomic.add(out, (i, j), w)
    cuda.atomic.add(out_vx, (i, j), w * vx)
    cuda.atomic.add(out_vy, (i, j), w * vy)


@cuda.jit(device=True)
def _add_solids(out, out_vx, out_vy, i, j, w, vx, vy):
    """out[i, j] += w alone, atomically (velocity weights by number are the centres': ``centroid_deposit``)."""
    cuda.atomic.add(out, (i, j), w)


_AREA_HELPERS = {"disc_rect_area_into": device_tree(VK.disc_rect_area_into), "_segment": device_tree(VK._segment)}
# one particle's exact disc areas in the cells it overlaps (Hoomans 1996 §3.4): with its weighted velocities
# (Sun 2007 eq. 35 with area shares), or the solids alone
area_one_weighted = device_function(VK.area_deposit_one, _add=_add_weighted, **_AREA_HELPERS)
area_one_solids = device_function(VK.area_deposit_one, _add=_add_solids, **_AREA_HELPERS)


@cached_kernel
def centroid_deposit(position, velocity, volume, inv_dx, inv_dy, by_volume, solids, count, wvx, wvy):
    """solids[i, j] += V_p, count[i, j] += 1 and (wvx, wvy)[i, j] += w v_p for the cell (i, j) of each centre,
    w = V_p (``by_volume``: Sun 2007 eq. 35) or 1 (Hoomans 1996 eq. 50); cells as ``_voidage_kernels.cell_index``
    (centres outside the grid in the nearest edge cell). position, velocity : (N, 3); volume : (N,) [m³];
    solids, count, wvx, wvy : (nx, ny), accumulated into."""
    q = cuda.grid(1)
    if q >= position.shape[0]:
        return
    nx, ny = solids.shape
    i = cell_index(position[q, 0], inv_dx, nx)
    j = cell_index(position[q, 1], inv_dy, ny)
    v = volume[q]
    cuda.atomic.add(solids, (i, j), v)  # Sun 2007 eq. 34
    cuda.atomic.add(count, (i, j), 1.0)
    if by_volume:
        cuda.atomic.add(wvx, (i, j), v * velocity[q, 0])
        cuda.atomic.add(wvy, (i, j), v * velocity[q, 1])
    else:
        cuda.atomic.add(wvx, (i, j), velocity[q, 0])
        cuda.atomic.add(wvy, (i, j), velocity[q, 1])


@cached_kernel
def area_deposit(position, velocity, radius, volume, share_volume, dx, dy, by_volume, solids, count, wvx, wvy):
    """solids[i, j] += s A_pij for every cell (i, j) the disc of particle p overlaps (``_voidage_kernels.
    area_deposit``: Hoomans 1996 §3.4, parts outside the grid dropped), s = V_p/(π r_p²) with ``share_volume``
    ('area_volume'), else 1 ('area'); with ``by_volume`` (wvx, wvy)[i, j] += s A_pij v_p (Sun 2007 eq. 35),
    else count and (wvx, wvy) of the cell of the centre as ``centroid_deposit`` by number (Hoomans 1996
    eq. 50), as ``_voidage_kernels.deposit_solids``. position, velocity : (N, 3); radius, volume : (N,);
    solids, count, wvx, wvy : (nx, ny), accumulated into."""
    q = cuda.grid(1)
    if q >= position.shape[0]:
        return
    nx, ny = solids.shape
    x = position[q, 0]
    y = position[q, 1]
    vx = velocity[q, 0]
    vy = velocity[q, 1]
    r = radius[q]
    s = volume[q] / (math.pi * r * r) if share_volume else 1.0  # deposit_solids' scale[p]
    pts = cuda.local.array(6, float64)
    if by_volume:
        area_one_weighted(x, y, r, s, vx, vy, dx, dy, solids, wvx, wvy, pts)
    else:
        area_one_solids(x, y, r, s, vx, vy, dx, dy, solids, wvx, wvy, pts)
        i = cell_index(x, 1.0 / dx, nx)
        j = cell_index(y, 1.0 / dy, ny)
        cuda.atomic.add(count, (i, j), 1.0)
        cuda.atomic.add(wvx, (i, j), 1.0 * vx)
        cuda.atomic.add(wvy, (i, j), 1.0 * vy)


@cached_kernel
def sauter_deposit(position, radius, volume, inv_dx, inv_dy, by_size, by_volume):
    """by_size[i, j] += V_p/d_p and by_volume[i, j] += V_p for the cell (i, j) of each centre
    (``_voidage_kernels.sauter_inverse``'s sums: 1/D̄ = Σ V_p/d_p / Σ V_p, DEM book 2012 two-phase chapter,
    eq. 10), cells as ``cell_index``. position : (N, 3); radius, volume : (N,); by_size, by_volume : (nx, ny),
    accumulated into."""
    q = cuda.grid(1)
    if q >= position.shape[0]:
        return
    nx, ny = by_size.shape
    i = cell_index(position[q, 0], inv_dx, nx)
    j = cell_index(position[q, 1], inv_dy, ny)
    cuda.atomic.add(by_size, (i, j), volume[q] / (2.0 * radius[q]))
    cuda.atomic.add(by_volume, (i, j), volume[q])


@cached_kernel
def zero(a):
    """a[...] = 0 for a 2D array, one thread per element."""
    k = cuda.grid(1)
    m = a.shape[1]
    if k >= a.shape[0] * m:
        return
    a[k // m, k % m] = 0.0
