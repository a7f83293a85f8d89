"""CUDA kernels of the ``cell`` exchange on a 3D grid (``_exchange3d_kernels``' ``cell_beta3d``,
``pressure_voidage3d`` and ``cell_forces3d``), one thread per particle.

The per-particle arithmetic is the CPU's own source compiled for the device (``drag._dispatch_cuda``'s
``device_tree``): the cell of a centre (``_exchange_kernels._cell``), a particle's β/(1 − ε) at its cell's
voidage, gas density and slip |u_c − v_s,c| (``_exchange3d_kernels.cell_drag3d``, Sun 2007 eq. 33, y = d/D̄ of
the cell for the polydisperse drag), its volume on the faces of its folded ∇p interpolation
(``_exchange3d_kernels.pressure_deposit_one3d``, the CPU's ``_add3`` replaced by its atomic twin) and its share
of its cell's drag with −V_p ∇p (``_exchange3d_kernels.cell_force3d``, Sun 2007 eq. 28).

``cell_beta_deposit3d``  Σ_p β/(1 − ε) V_p of the particles centred in each cell (the host divides by V_cell);
                         a particle whose drag arguments are out of range adds nothing and counts in bad[0].
``pressure_deposit3d``   Σ_p w_pf V_p on the x-, y- and z-faces of each particle's ∇p interpolation (the host
                         finishes ε_p,f = max(1 − Σ/V_f, ε_min): ``_paired3d_kernels._voidage_of``).
``cell_solids3d``        Σ V_p of the particles centred in each cell, by ``_cell`` (the share's denominator).
``cell_forces3d``        F_p = V_p/Σ V_r β_c V_c (u_c − u_s,c) − V_p ∇p_p into ext, the total following.
``kp_now3d``             K_p = β/(1 − ε_p) V_p (Sun 2007 eq. 29) of each particle at the current gas, without face
                         sums (``_paired3d_kernels.kp3d``, its ``_kp_range`` compiled for the device and run on one
                         particle per thread): the "cell_beta" exchange's own drag on the particles, with
                         ``_paired3d_cuda.forces3d`` after it.

The sums are atomic: the CPU's to round-off, added in another order.
"""
from numba import cuda

from ..particles.contact._dispatch_cuda import cached_kernel
from . import _exchange3d_kernels as X3
from . import _paired3d_kernels as P3
from ._cell_cuda import cell_of
from ._paired3d_cuda import THREADS, _add3, _index, store_force  # noqa: F401 - THREADS: the launches' block size
from .drag._dispatch_cuda import beta_per_solids, device_tree

cell_drag3d = device_tree(X3.cell_drag3d, beta_per_solids=beta_per_solids)
pressure_deposit_one3d = device_tree(X3.pressure_deposit_one3d, _add3=_add3, U=_index)
cell_force3d = device_tree(X3.cell_force3d, U=_index)
kp_range = device_tree(P3._kp_range, beta_per_solids=beta_per_solids, U=_index)


@cached_kernel
def cell_beta_deposit3d(law, position, radius, volume, u, v, w, rho, voidage, solids_u, solids_v, solids_w, mu,
                        inv_dbar, dx, dy, dz, out, bad):
    """out[i, j, k] += β/(1 − ε) V_p for the cell (i, j, k) of each centre (``_exchange3d_kernels.cell_beta3d``
    before its division by V_cell, Sun 2007 eq. 33); bad[0] counts the particles whose drag arguments are out of
    range. position : (N, 3); radius, volume : (N,); u (nx + 1, ny, nz), v (nx, ny + 1, nz), w (nx, ny, nz + 1),
    rho, voidage, solids_u, solids_v, solids_w, out (nx, ny, nz); inv_dbar (nx, ny, nz) 1/D̄ of each cell, or
    (0, 0, 0) for a monodisperse drag."""
    q = cuda.grid(1)
    if q >= position.shape[0]:
        return
    nx, ny, nz = out.shape
    i = cell_of(position[q, 0], dx, nx)
    j = cell_of(position[q, 1], dy, ny)
    k = cell_of(position[q, 2], dz, nz)
    ok, b = cell_drag3d(law, u, v, w, rho, voidage, solids_u, solids_v, solids_w, mu, inv_dbar,
                        inv_dbar.shape[0] > 0, i, j, k, 2.0 * radius[q])
    if not ok:
        cuda.atomic.add(bad, 0, 1)
        return
    cuda.atomic.add(out, (i, j, k), b * volume[q])  # eq. 33


@cached_kernel
def pressure_deposit3d(position, volume, dx, dy, dz, px, py, pz, EU, EV, EW):
    """EU, EV, EW += w_pf V_p over the faces of each particle's ∇p interpolation (boundary faces folded:
    ``_exchange3d_kernels.pressure_voidage3d`` before ``_voidage_of``). position : (N, 3); volume : (N,);
    EU (nx + 1, ny, nz), EV (nx, ny + 1, nz), EW (nx, ny, nz + 1), accumulated into."""
    q = cuda.grid(1)
    if q >= position.shape[0]:
        return
    nx, ny, nz = EU.shape[0] - 1, EV.shape[1] - 1, EW.shape[2] - 1
    pressure_deposit_one3d(position[q, 0], position[q, 1], position[q, 2], volume[q], 1.0 / dx, 1.0 / dy, 1.0 / dz,
                           nx, ny, nz, px, py, pz, EU, EV, EW)


@cached_kernel
def cell_solids3d(position, volume, dx, dy, dz, solids):
    """solids[i, j, k] += V_p for the cell (i, j, k) of each centre by ``_exchange_kernels._cell``
    (``_exchange3d_kernels.cell_forces3d``' first pass). position : (N, 3); volume : (N,); solids (nx, ny, nz),
    accumulated into."""
    q = cuda.grid(1)
    if q >= position.shape[0]:
        return
    nx, ny, nz = solids.shape
    cuda.atomic.add(solids, (cell_of(position[q, 0], dx, nx), cell_of(position[q, 1], dy, ny),
                             cell_of(position[q, 2], dz, nz)), volume[q])


@cached_kernel
def cell_forces3d(position, volume, solids, beta, solids_u, solids_v, solids_w, u, v, w, p, dx, dy, dz, cell_volume,
                  px, py, pz, pressure_force, ext, total):
    """ext[q] = (V_q/Σ_{r in c} V_r) β_c V_c (u_c − u_s,c) − V_q ∇p_q for the cell c of q's centre, total[q] += its
    change: ``_exchange3d_kernels.cell_forces3d`` with ``solids`` from ``cell_solids3d``, one particle per
    thread."""
    q = cuda.grid(1)
    if q >= position.shape[0]:
        return
    nx, ny, nz = beta.shape
    x, y, z = position[q, 0], position[q, 1], position[q, 2]
    fx, fy, fz = cell_force3d(x, y, z, volume[q], cell_of(x, dx, nx), cell_of(y, dy, ny), cell_of(z, dz, nz), solids,
                              beta, solids_u, solids_v, solids_w, u, v, w, p, 1.0 / dx, 1.0 / dy, 1.0 / dz,
                              cell_volume, px, py, pz, pressure_force)
    store_force(ext, total, q, fx, fy, fz, True)


@cached_kernel
def kp_now3d(law, position, velocity, radius, volume, u, v, w, voidage, rho, mu, inv_dbar, dx, dy, dz, min_voidage, px,
             py, pz, fold, kp, valid, bad):
    """kp[q] = β/(1 − ε_q) V_q [kg/s] (Sun 2007 eq. 29) at the particle's interpolated voidage (clipped to
    [min_voidage, 1]), gas density and slip, valid[q] whether its drag arguments are in range (else kp[q] = NaN,
    counted in bad[0]): ``_paired3d_kernels.kp3d``, one particle per thread. position, velocity : (N, 3); radius,
    volume, kp, valid : (N,); u, v, w on their faces; voidage, rho (nx, ny, nz); inv_dbar (nx, ny, nz) or
    (0, 0, 0) as there."""
    q = cuda.grid(1)
    if q >= position.shape[0]:
        return
    if kp_range(q, q + 1, law, position, velocity, radius, volume, u, v, w, voidage, rho, mu, inv_dbar, 1.0 / dx,
                1.0 / dy, 1.0 / dz, min_voidage, px, py, pz, fold, kp, valid) > 0:
        cuda.atomic.add(bad, 0, 1)
