"""CUDA kernels of the ``particle`` exchange on a 3D grid (``_paired3d_kernels``), one thread per particle.

The per-particle arithmetic is the CPU's own source compiled for the device (``drag._dispatch_cuda``'s
``device_tree``): the trilinear weights of each axis (``_paired3d_kernels._axis``, Hoomans 1996 eqs 40-41 in
3D), the interpolation of the gas and of ∇p to the particle (``_gas_at3``, ``_mean3``), the drag law of the
registry (``drag._dispatch_cuda.beta_per_solids``) and the range checks, so each particle's K_p and force are
the CPU's (to round-off where the device contracts a multiply-add).

``deposit3d``        K_p = β/(1 − ε_p) V_p (Sun 2007 eq. 29) of each particle, kept on the device, and the face
                     sums A_f = Σ w_pf K_p, B_f = Σ w_pf K_p v_p on the x-, y- and z-faces, the cells' Σ K_p and
                     the pressure voidage's Σ w_pf V_p, added with atomics: the sums are the CPU's to round-off,
                     in another order (the host finishes them: ``_paired3d_kernels._coefficients``,
                     ``_voidage_of``).
``forces_split3d``   ext = K_p u_p − V_p ∇p_p, damping K_p, the engine's total force following
                     (``_paired3d_kernels.particle_forces_split3d``; ``drag_update = "substep"``).
``forces3d``         F_p = K_p (u_p − v_p) − V_p ∇p_p into ext, the total following
                     (``_paired3d_kernels.particle_forces3d``; ``drag_update = "frozen"``).

With ``coupling.polydisperse = "sauter_y2"`` ``deposit3d`` takes 1/D̄ per cell (the host finishes it from the
device's sums: ``_voidage3d_cuda.sauter_deposit3d``, ``exchange_gpu.sauter_finish``) and each particle's
y = d/D̄ from it as the CPU does; the forces need only K_p.
"""
import math

from numba import cuda

from ..particles.contact._dispatch_cuda import cached_kernel
from . import _paired3d_kernels as P3
from . import _paired_kernels as P
from ._paired_cuda import THREADS, _index, arguments_valid, store_force  # noqa: F401 - THREADS: block size
from .drag._dispatch_cuda import beta_per_solids, device_tree

axis = device_tree(P3._axis, U=_index)  # centre and face nodes of one axis with their weights
centre_axis = device_tree(P._centre_axis, U=_index)
face_axis = device_tree(P._face_axis, U=_index)
mean3 = device_tree(P3._mean3, U=_index)  # Σ a_i b_j c_k f[i, j, k] (trilinear)
gas_at3 = device_tree(P3._gas_at3, U=_index)  # (u, v, w, ∂p/∂x, ∂p/∂y, ∂p/∂z) at a point


@cuda.jit(device=True)
def _add3(E, i0, i1, a0, a1, j0, j1, b0, b1, k0, k1, c0, c1, q):
    """E[i, j, k] += a_i b_j c_k q over the two nodes of each axis (``_paired3d_kernels._add3``), atomically."""
    cuda.atomic.add(E, (i0, j0, k0), a0 * b0 * c0 * q)
    cuda.atomic.add(E, (i0, j0, k1), a0 * b0 * c1 * q)
    cuda.atomic.add(E, (i0, j1, k0), a0 * b1 * c0 * q)
    cuda.atomic.add(E, (i0, j1, k1), a0 * b1 * c1 * q)
    cuda.atomic.add(E, (i1, j0, k0), a1 * b0 * c0 * q)
    cuda.atomic.add(E, (i1, j0, k1), a1 * b0 * c1 * q)
    cuda.atomic.add(E, (i1, j1, k0), a1 * b1 * c0 * q)
    cuda.atomic.add(E, (i1, j1, k1), a1 * b1 * c1 * q)


@cached_kernel
def deposit3d(law, position, velocity, radius, volume, u, v, w, voidage, rho, mu, inv_dbar, dx, dy, dz, min_voidage,
              px, py, pz, fold, kp, AU, BU, AV, BV, AW, BW, KC, pair, EU, EV, EW, bad):
    """K_p of each particle into kp, and its share of the face sums (``_paired3d_kernels.deposit3d`` before
    ``_coefficients``, the particles in any order): AU, BU (nx + 1, ny, nz), AV, BV (nx, ny + 1, nz), AW, BW
    (nx, ny, nz + 1), KC (nx, ny, nz) Σ K_p of the particles centred in each cell, and with ``pair`` EU, EV, EW
    the particle volume on the faces of its ∇p interpolation (always folded), all zeroed before and added into
    here. A particle whose drag arguments are out of range (``_exchange_kernels._drag_arguments_valid``) gets
    kp = NaN, deposits no drag and counts in bad[0]. law : the packed drag law (``DragLaw.pack``); position,
    velocity : (N, 3); radius, volume, kp : (N,); u, v, w on their faces; voidage and rho (nx, ny, nz); inv_dbar
    (nx, ny, nz): 1/D̄ of each cell for the polydisperse drag, y = d/D̄ with 1/D̄ interpolated as ε is (DEM book
    2012 eqs 10-12), or (0, 0, 0): y = 1."""
    q = cuda.grid(1)
    if q >= position.shape[0]:
        return
    nx, ny, nz = voidage.shape
    idx, idy, idz = 1.0 / dx, 1.0 / dy, 1.0 / dz
    x, y, z = position[q, 0], position[q, 1], position[q, 2]
    ci0, ci1, cwx0, cwx1, fi0, fi1, fwx0, fwx1 = axis(x, idx, nx, px, fold)
    cj0, cj1, cwy0, cwy1, fj0, fj1, fwy0, fwy1 = axis(y, idy, ny, py, fold)
    ck0, ck1, cwz0, cwz1, fk0, fk1, fwz0, fwz1 = axis(z, idz, nz, pz, fold)
    if pair:  # V_p on the faces of its ∇p interpolation (always folded)
        gi0, gi1, gwx0, gwx1 = face_axis(x, idx, nx, px, True)
        gj0, gj1, gwy0, gwy1 = face_axis(y, idy, ny, py, True)
        gk0, gk1, gwz0, gwz1 = face_axis(z, idz, nz, pz, True)
        vq = volume[q]
        _add3(EU, gi0, gi1, gwx0, gwx1, cj0, cj1, cwy0, cwy1, ck0, ck1, cwz0, cwz1, vq)
        _add3(EV, ci0, ci1, cwx0, cwx1, gj0, gj1, gwy0, gwy1, ck0, ck1, cwz0, cwz1, vq)
        _add3(EW, ci0, ci1, cwx0, cwx1, cj0, cj1, cwy0, cwy1, gk0, gk1, gwz0, gwz1, vq)
    # K_p as ``_paired3d_kernels.kp3d``: ε and ρ_g at the centre weights, the slip at the face weights
    ug, vg, wg, _, _, _ = gas_at3(x, y, z, u, v, w, voidage, idx, idy, idz, nx, ny, nz, px, py, pz, fold, False)
    eps = mean3(voidage, ci0, ci1, cwx0, cwx1, cj0, cj1, cwy0, cwy1, ck0, ck1, cwz0, cwz1)
    rg = mean3(rho, ci0, ci1, cwx0, cwx1, cj0, cj1, cwy0, cwy1, ck0, ck1, cwz0, cwz1)
    if eps < min_voidage:
        eps = min_voidage
    elif eps > 1.0:
        eps = 1.0
    vx, vy, vz = velocity[q, 0], velocity[q, 1], velocity[q, 2]
    sx = ug - vx
    sy = vg - vy
    sz = wg - vz
    slip = math.sqrt(sx * sx + sy * sy + sz * sz)
    d = 2.0 * radius[q]
    if not arguments_valid(eps, slip, d, rg, mu):
        kp[q] = math.nan
        cuda.atomic.add(bad, 0, 1)
        return
    yq = 1.0  # y = d/D̄ (DEM book 2012 eq. 11), 1/D̄ interpolated as ε is; 1 for a monodisperse bed
    if inv_dbar.shape[0] > 0:
        yq = d * mean3(inv_dbar, ci0, ci1, cwx0, cwx1, cj0, cj1, cwy0, cwy1, ck0, ck1, cwz0, cwz1)
    k = beta_per_solids(law, eps, slip, d, rg, mu, yq) * volume[q]  # Sun 2007 eq. 29
    kp[q] = k
    ic = min(max(int(x * idx), 0), nx - 1)
    jc = min(max(int(y * idy), 0), ny - 1)
    kc = min(max(int(z * idz), 0), nz - 1)
    cuda.atomic.add(KC, (ic, jc, kc), k)
    _add3(AU, fi0, fi1, fwx0, fwx1, cj0, cj1, cwy0, cwy1, ck0, ck1, cwz0, cwz1, k)
    _add3(BU, fi0, fi1, fwx0, fwx1, cj0, cj1, cwy0, cwy1, ck0, ck1, cwz0, cwz1, k * vx)
    _add3(AV, ci0, ci1, cwx0, cwx1, fj0, fj1, fwy0, fwy1, ck0, ck1, cwz0, cwz1, k)
    _add3(BV, ci0, ci1, cwx0, cwx1, fj0, fj1, fwy0, fwy1, ck0, ck1, cwz0, cwz1, k * vy)
    _add3(AW, ci0, ci1, cwx0, cwx1, cj0, cj1, cwy0, cwy1, fk0, fk1, fwz0, fwz1, k)
    _add3(BW, ci0, ci1, cwx0, cwx1, cj0, cj1, cwy0, cwy1, fk0, fk1, fwz0, fwz1, k * vz)


@cached_kernel
def forces_split3d(position, velocity, volume, kp, u, v, w, p, dx, dy, dz, px, py, pz, fold, pressure_force, ext, damp,
                   total):
    """ext[q] = K_q u_q − V_q ∇p_q, damp[q] = K_q, and total[q] += the change of the force at the current
    velocity: ``_paired3d_kernels.particle_forces_split3d`` (Sun 2007 eqs 28-29), one particle per thread."""
    q = cuda.grid(1)
    if q >= position.shape[0]:
        return
    nx, ny, nz = p.shape
    ug, vg, wg, gx, gy, gz = gas_at3(position[q, 0], position[q, 1], position[q, 2], u, v, w, p, 1.0 / dx, 1.0 / dy,
                                     1.0 / dz, nx, ny, nz, px, py, pz, fold, pressure_force)
    k = kp[q]
    a0 = k * ug
    a1 = k * vg
    a2 = k * wg
    if pressure_force:  # −V_p ∇p, Sun 2007 eq. 28
        a0 -= volume[q] * gx
        a1 -= volume[q] * gy
        a2 -= volume[q] * gz
    c = damp[q]
    vx, vy, vz = velocity[q, 0], velocity[q, 1], velocity[q, 2]
    total[q, 0] += (a0 - k * vx) - (ext[q, 0] - c * vx)
    total[q, 1] += (a1 - k * vy) - (ext[q, 1] - c * vy)
    total[q, 2] += (a2 - k * vz) - (ext[q, 2] - c * vz)
    ext[q, 0] = a0
    ext[q, 1] = a1
    ext[q, 2] = a2
    damp[q] = k


@cached_kernel
def forces3d(position, velocity, volume, kp, u, v, w, p, dx, dy, dz, px, py, pz, fold, pressure_force, ext, total):
    """ext[q] = K_q (u_q − v_q) − V_q ∇p_q, total[q] += its change: ``_paired3d_kernels.particle_forces3d``
    (Sun 2007 eqs 28-29), one particle per thread."""
    q = cuda.grid(1)
    if q >= position.shape[0]:
        return
    nx, ny, nz = p.shape
    ug, vg, wg, gx, gy, gz = gas_at3(position[q, 0], position[q, 1], position[q, 2], u, v, w, p, 1.0 / dx, 1.0 / dy,
                                     1.0 / dz, nx, ny, nz, px, py, pz, fold, pressure_force)
    k = kp[q]
    fx = k * (ug - velocity[q, 0])
    fy = k * (vg - velocity[q, 1])
    fz = k * (wg - velocity[q, 2])
    if pressure_force:  # −V_p ∇p, Sun 2007 eq. 28
        fx -= volume[q] * gx
        fy -= volume[q] * gy
        fz -= volume[q] * gz
    store_force(ext, total, q, fx, fy, fz, True)
