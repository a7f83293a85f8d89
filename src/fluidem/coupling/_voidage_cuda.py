"""CUDA kernels of the particle → grid map (``_voidage_kernels``' centroid deposit), one thread per particle.

``centroid_deposit`` adds each particle's volume V_p to the cell holding its centre (Sun 2007 eq. 34), a
count of 1 (Hoomans 1996 eq. 50's number average) and its weighted velocity, with atomic additions: the
cells' sums are the CPU's to round-off, added in another order (and not bit for bit from run to run). The
rest of the map (the fraction over V_cell, smoothing, clipping, the averages) works on cell arrays and runs
on the host (``_voidage_kernels.finish_map``), so only cell arrays leave the device.
"""
from numba import cuda

from ..particles.contact._dispatch_cuda import cached_kernel, device_function
from . import _voidage_kernels as VK

THREADS = 128  # threads per block

cell_index = device_function(VK.cell_index)  # floor(x/d) clamped to the grid, as on the CPU


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
def zero(a):
    """a[...] = 0 for a 2D array, one thread per element."""
    k = cuda.grid(1)
    m = a.shape[1]
    if k >= a.shape[0] * m:
        return
    a[k // m, k % m] = 0.0
