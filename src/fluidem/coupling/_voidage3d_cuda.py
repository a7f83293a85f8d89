"""CUDA kernels of the particle → grid map on a 3D grid (``_voidage3d_kernels``' deposits), one thread per particle.

``centroid_deposit3d`` adds each particle's volume V_p to the cell holding its centre (Sun 2007 eq. 34 in 3D);
``volume_deposit3d`` adds the exact volume V_pc of the sphere inside every cell c it overlaps
(``_voidage3d_kernels.sphere_box_volume``, the closed form of that module's docstring, compiled for the device
from the CPU's own source with every helper it calls: ``drag._dispatch_cuda.device_tree``), periodic axes
wrapped and the edge cells of a non-periodic axis unbounded, as ``_voidage3d_kernels.volume_deposit``. Both
add the velocity weights of ``_voidage3d_kernels.deposit_solids3d`` too: by volume (Sun 2007 eq. 35, the
deposit itself) or by number (Hoomans 1996 eq. 50: a count of 1 and v_p in the cell of the centre). The
``sauter_deposit3d`` adds Σ V_p/d_p and Σ V_p of the centres in each cell (``_voidage3d_kernels.
sauter_inverse3d``'s sums; the host finishes 1/D̄: ``exchange_gpu.sauter_finish``). The additions are atomic:
the cells' sums are the CPU's to round-off, added in another order (and not bit for
bit from run to run). The rest of the map (the fraction over V_cell, smoothing, clipping, the averages) works
on cell arrays and runs on the host (``exchange3d_gpu.DeviceExchange3D.map``), so only cell arrays leave the
device.
"""
import math

from numba import cuda

from ..particles.contact._dispatch_cuda import cached_kernel
from . import _voidage3d_kernels as VK3
from ._voidage_cuda import THREADS, cell_index  # noqa: F401 - THREADS: the launches' block size
from .drag._dispatch_cuda import device_tree

sphere_box_volume = device_tree(VK3.sphere_box_volume)  # exact V of a sphere in a box, module docstring of VK3
cell_range = device_tree(VK3._cell_range)  # cells of one axis an interval touches (unwrapped when periodic)
cell_bounds = device_tree(VK3._bounds)  # a cell's coordinates, the edge cells of a non-periodic axis unbounded


@cuda.jit(device=True)
def _add4(solids, wvx, wvy, wvz, i, j, k, w, vx, vy, vz):
    """solids[i, j, k] += w, wv*[i, j, k] += w v*, atomically."""
    cuda.atomic.add(solids, (i, j, k), w)
    cuda.atomic.add(wvx, (i, j, k), w * vx)
    cuda.atomic.add(wvy, (i, j, k), w * vy)
    cuda.atomic.add(wvz, (i, j, k), w * vz)


@cuda.jit(device=True)
def _count(count, wvx, wvy, wvz, i, j, k, vx, vy, vz):
    """count[i, j, k] += 1 and wv*[i, j, k] += 1.0 v* (Hoomans 1996 eq. 50), atomically."""
    cuda.atomic.add(count, (i, j, k), 1.0)
    cuda.atomic.add(wvx, (i, j, k), 1.0 * vx)
    cuda.atomic.add(wvy, (i, j, k), 1.0 * vy)
    cuda.atomic.add(wvz, (i, j, k), 1.0 * vz)


@cached_kernel
def centroid_deposit3d(position, velocity, volume, inv_dx, inv_dy, inv_dz, by_volume, solids, count, wvx, wvy, wvz):
    """solids[c] += V_p, count[c] += 1 and wv*[c] += w v_p for the cell c = (i, j, k) of each centre, w = V_p
    (``by_volume``: Sun 2007 eq. 35) or 1 (Hoomans 1996 eq. 50); cells as ``_voidage_kernels.cell_index``
    (centres outside the grid in the nearest edge cell), as ``_voidage3d_kernels.centroid_deposit3d``.
    position, velocity : (N, 3); volume : (N,) [m³]; solids, count, wvx, wvy, wvz : (nx, ny, nz), accumulated
    into."""
    q = cuda.grid(1)
    if q >= position.shape[0]:
        return
    nx, ny, nz = solids.shape
    i = cell_index(position[q, 0], inv_dx, nx)
    j = cell_index(position[q, 1], inv_dy, ny)
    k = cell_index(position[q, 2], inv_dz, nz)
    v = volume[q]
    cuda.atomic.add(solids, (i, j, k), v)  # Sun 2007 eq. 34
    w = v if by_volume else 1.0
    cuda.atomic.add(count, (i, j, k), 1.0)
    cuda.atomic.add(wvx, (i, j, k), w * velocity[q, 0])
    cuda.atomic.add(wvy, (i, j, k), w * velocity[q, 1])
    cuda.atomic.add(wvz, (i, j, k), w * velocity[q, 2])


@cached_kernel
def volume_deposit3d(position, velocity, radius, dx, dy, dz, inv_dx, inv_dy, inv_dz, px, py, pz, by_volume, solids,
                     count, wvx, wvy, wvz):
    """solids[c] += V_pc, the exact volume of the sphere of particle p in every cell c it overlaps
    (``_voidage3d_kernels.volume_deposit``: periodic axes wrapped, the edge cells of a non-periodic axis
    unbounded, a sphere inside one cell its whole 4/3 π r³); with ``by_volume`` wv*[c] += V_pc v_p (Sun 2007
    eq. 35), else count and wv* of the cell of the centre as ``centroid_deposit3d`` by number (Hoomans 1996
    eq. 50). position, velocity : (N, 3); radius : (N,) [m]; solids, count, wvx, wvy, wvz : (nx, ny, nz),
    accumulated into."""
    q = cuda.grid(1)
    if q >= position.shape[0]:
        return
    nx, ny, nz = solids.shape
    r = radius[q]
    x, y, z = position[q, 0], position[q, 1], position[q, 2]
    vx, vy, vz = velocity[q, 0], velocity[q, 1], velocity[q, 2]
    if not by_volume:
        _count(count, wvx, wvy, wvz, cell_index(x, inv_dx, nx), cell_index(y, inv_dy, ny), cell_index(z, inv_dz, nz),
               vx, vy, vz)
    a0, a1 = cell_range(x, r, dx, nx, px)
    b0, b1 = cell_range(y, r, dy, ny, py)
    c0, c1 = cell_range(z, r, dz, nz, pz)
    if a0 == a1 and b0 == b1 and c0 == c1:  # inside one cell: its whole volume
        v = 1.0 * 4.0 / 3.0 * math.pi * r * r * r  # as the CPU's scale[p] 4/3 π r³, scale 1
        i, j, k = a0 % nx, b0 % ny, c0 % nz
        if by_volume:
            _add4(solids, wvx, wvy, wvz, i, j, k, v, vx, vy, vz)
        else:
            cuda.atomic.add(solids, (i, j, k), v)
        return
    for i in range(a0, a1 + 1):
        xl, xh = cell_bounds(i, dx, nx, px)
        for j in range(b0, b1 + 1):
            yl, yh = cell_bounds(j, dy, ny, py)
            for k in range(c0, c1 + 1):
                zl, zh = cell_bounds(k, dz, nz, pz)
                v = sphere_box_volume(x, y, z, r, xl, xh, yl, yh, zl, zh)
                if v > 0.0:
                    if by_volume:
                        _add4(solids, wvx, wvy, wvz, i % nx, j % ny, k % nz, v, vx, vy, vz)
                    else:
                        cuda.atomic.add(solids, (i % nx, j % ny, k % nz), v)


@cached_kernel
def sauter_deposit3d(position, radius, volume, inv_dx, inv_dy, inv_dz, by_size, by_volume):
    """by_size[c] += V_p/d_p and by_volume[c] += V_p for the cell c = (i, j, k) of each centre
    (``_voidage3d_kernels.sauter_inverse3d``'s sums: 1/D̄ = Σ V_p/d_p / Σ V_p, DEM book 2012 two-phase chapter,
    eq. 10), cells as ``cell_index``. position : (N, 3); radius, volume : (N,); by_size, by_volume :
    (nx, ny, nz), accumulated into."""
    q = cuda.grid(1)
    if q >= position.shape[0]:
        return
    nx, ny, nz = by_size.shape
    i = cell_index(position[q, 0], inv_dx, nx)
    j = cell_index(position[q, 1], inv_dy, ny)
    k = cell_index(position[q, 2], inv_dz, nz)
    cuda.atomic.add(by_size, (i, j, k), volume[q] / (2.0 * radius[q]))
    cuda.atomic.add(by_volume, (i, j, k), volume[q])


@cached_kernel
def zero3(a):
    """a[...] = 0 for a 3D array, one thread per element."""
    m = cuda.grid(1)
    n1, n2 = a.shape[1], a.shape[2]
    if m >= a.shape[0] * n1 * n2:
        return
    a[m // (n1 * n2), (m // n2) % n1, m % n2] = 0.0
