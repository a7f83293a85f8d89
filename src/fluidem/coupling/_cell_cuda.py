"""CUDA kernels of the ``cell`` exchange on a 2D grid (``_exchange_kernels.cell_beta``, ``_paired_kernels``'
``pressure_voidage`` and ``cell_forces``), one thread per particle.

The per-particle arithmetic is the CPU's own source compiled for the device (``drag._dispatch_cuda``'s
``device_tree``): the cell of a centre (``_exchange_kernels._cell``), a particle's β/(1 − ε) at its cell's
voidage, gas density and slip (``_exchange_kernels.cell_drag``, Sun 2007 eq. 33, y = d/D̄ of the cell for the
polydisperse drag), the folded stencil of the pressure voidage (``_paired_kernels._stencil``) and a particle's
share of its cell's drag with −V_p ∇p (``_paired_kernels.cell_force``), a particle's drag and pressure force at its
interpolated gas (``_exchange_kernels.gas_force_one``).

``cell_beta_deposit``  Σ_p β/(1 − ε) V_p of the particles centred in each cell (the host divides by V_cell);
                       a particle whose drag arguments are out of range adds nothing and counts in bad[0].
``pressure_deposit``   Σ_p w_pf V_p on the faces of each particle's ∇p interpolation (the host finishes
                       ε_p,f = 1 − Σ/V_f: ``_paired_kernels._face_voidage``).
``cell_solids``        Σ V_p of the particles centred in each cell, by ``_cell`` (the share's denominator).
``forces``             F_p = V_p/Σ V_r β_c V_c (u_c − u_s,c) − V_p ∇p_p into ext, the total following.
``gas_forces``         F_p = β V_p/(1 − ε_p) (u_p − v_p) − V_p ∇p_p (Sun 2007 eqs 28-29) at the particle's
                       interpolated gas, into ext, the total following: the "cell_beta" exchange's own drag
                       (``_exchange_kernels.gas_force_one``, the CPU's ``gas_forces`` one particle per thread).

The sums are atomic: the CPU's to round-off, added in another order.
"""
from numba import cuda

from ..particles.contact._dispatch_cuda import cached_kernel
from . import _exchange_kernels as EK
from . import _paired_kernels as P
from ._paired_cuda import THREADS, _add, _index, store_force  # noqa: F401 - THREADS: the launches' block size
from .drag._dispatch_cuda import beta_per_solids, device_tree

cell_of = device_tree(EK._cell)  # trunc(x/d) clamped, as the CPU's cell exchange counts a centre
cell_drag = device_tree(EK.cell_drag, beta_per_solids=beta_per_solids)
stencil = device_tree(P._stencil, U=_index)
cell_force = device_tree(P.cell_force, U=_index)


@cached_kernel
def cell_beta_deposit(law, position, radius, volume, u, v, rho, voidage, solids_u, solids_v, mu, inv_dbar, dx, dy,
                      out, bad):
    """out[i, j] += β/(1 − ε) V_p for the cell (i, j) of each centre (``_exchange_kernels.cell_beta`` before its
    division by V_cell, Sun 2007 eq. 33); bad[0] counts the particles whose drag arguments are out of range.
    position : (N, 3); radius, volume : (N,); u (nx + 1, ny), v (nx, ny + 1), rho, voidage, solids_u, solids_v,
    out (nx, ny); inv_dbar (nx, ny) 1/D̄ of each cell, or (0, 0) for a monodisperse drag."""
    q = cuda.grid(1)
    if q >= position.shape[0]:
        return
    nx, ny = out.shape
    i = cell_of(position[q, 0], dx, nx)
    j = cell_of(position[q, 1], dy, ny)
    ok, b = cell_drag(law, u, v, rho, voidage, solids_u, solids_v, mu, inv_dbar, inv_dbar.shape[0] > 0, i, j,
                      2.0 * radius[q])
    if not ok:
        cuda.atomic.add(bad, 0, 1)
        return
    cuda.atomic.add(out, (i, j), b * volume[q])  # eq. 33


@cached_kernel
def pressure_deposit(position, volume, dx, dy, px, py, EU, EV):
    """EU, EV += w_pf V_p over the faces of each particle's ∇p interpolation (folded: ``_paired_kernels.
    pressure_voidage`` before ``_face_voidage``). position : (N, 3); volume : (N,); EU (nx + 1, ny), EV
    (nx, ny + 1), accumulated into."""
    q = cuda.grid(1)
    if q >= position.shape[0]:
        return
    nx, ny = EU.shape[0] - 1, EU.shape[1]
    (ci0, ci1, cw0, cw1, fi0, fi1, fw0, fw1, cj0, cj1, cv0, cv1, fj0, fj1, fv0,
     fv1) = stencil(position[q, 0], position[q, 1], 1.0 / dx, 1.0 / dy, nx, ny, px, py, True)
    _add(EU, fi0, fi1, fw0, fw1, cj0, cj1, cv0, cv1, volume[q])
    _add(EV, ci0, ci1, cw0, cw1, fj0, fj1, fv0, fv1, volume[q])


@cached_kernel
def cell_solids(position, volume, dx, dy, solids):
    """solids[i, j] += V_p for the cell (i, j) of each centre by ``_exchange_kernels._cell`` (``_paired_kernels.
    cell_forces``' first pass). position : (N, 3); volume : (N,); solids (nx, ny), accumulated into."""
    q = cuda.grid(1)
    if q >= position.shape[0]:
        return
    nx, ny = solids.shape
    cuda.atomic.add(solids, (cell_of(position[q, 0], dx, nx), cell_of(position[q, 1], dy, ny)), volume[q])


@cached_kernel
def forces(position, volume, solids, beta, solids_u, solids_v, u, v, p, dx, dy, cell_volume, px, py, pressure_force,
           ext, total):
    """ext[q] = (V_q/Σ_{r in c} V_r) β_c V_c (u_c − u_s,c) − V_q ∇p_q (z 0) for the cell c of q's centre, total[q]
    += its change: ``_paired_kernels.cell_forces`` with ``solids`` from ``cell_solids``, one particle per
    thread."""
    q = cuda.grid(1)
    if q >= position.shape[0]:
        return
    nx, ny = beta.shape
    x = position[q, 0]
    y = position[q, 1]
    fx, fy = cell_force(x, y, volume[q], cell_of(x, dx, nx), cell_of(y, dy, ny), solids, beta, solids_u, solids_v,
                        u, v, p, 1.0 / dx, 1.0 / dy, cell_volume, px, py, pressure_force)
    store_force(ext, total, q, fx, fy, 0.0, True)


gas_force_one = device_tree(EK.gas_force_one, beta_per_solids=beta_per_solids)


@cached_kernel
def gas_forces(law, position, velocity, radius, volume, cen, xfa, yfa, dbar, xc, yc, xf, yf, dx, dy, mu, min_voidage,
               pressure_force, dim2, ext, total, bad):
    """ext[q] = β V_q/(1 − ε) (u − v_q) − V_q ∇p (Sun 2007 eqs 28-29) at particle q's interpolated gas (Hoomans 1996
    eqs 40-41), total[q] += its change: ``_exchange_kernels.gas_forces``' per-particle pass
    (``gas_force_one``), one particle per thread, for the "cell_beta" exchange. cen, xfa, yfa, dbar: the
    wall-extended fields of ``_exchange_kernels.gas_force_fields``; xc, yc, xf, yf its interpolation nodes. A
    particle whose drag arguments are out of range gets NaN and counts in bad[0]. position, velocity, ext,
    total : (N, 3); radius, volume : (N,)."""
    q = cuda.grid(1)
    if q >= position.shape[0]:
        return
    ok, fx, fy, fz = gas_force_one(law, q, position, velocity, radius, volume, cen, xfa, yfa, dbar,
                                   dbar.shape[0] > 0, xc, yc, xf, yf, 1.0 / dx, 1.0 / dy, mu, min_voidage,
                                   pressure_force, dim2, velocity.shape[1] > 2)
    if not ok:
        cuda.atomic.add(bad, 0, 1)
    store_force(ext, total, q, fx, fy, fz, True)
