"""CUDA kernels of the ``particle`` exchange (``_paired_kernels``), one thread per particle.

The per-particle arithmetic is the CPU's own source compiled for the device (``drag._dispatch_cuda``'s
``device_tree``): the stencil of nodes and weights (``_paired_kernels._stencil``, Hoomans 1996 eqs 40-41), the
interpolations, the drag law of the registry (``drag._dispatch_cuda.beta_per_solids``) and the range checks,
so each particle's K_p and force are the CPU's (to round-off where the device contracts a multiply-add).

``deposit``        K_p = β/(1 − ε_p) V_p (Sun 2007 eq. 29) of each particle, kept on the device, and the face
                   sums A_f = Σ w_pf K_p, B_f = Σ w_pf K_p v_p, the cells' Σ K_p and the pressure voidage's
                   Σ w_pf V_p, added with atomics: the sums are the CPU's to round-off, in another order (the
                   gas takes them from the host, which finishes them: ``_paired_kernels._face_coefficients``,
                   ``_face_voidage``).
``forces_split``   ext = K_p u_p − V_p ∇p_p, damping K_p, the engine's total force following
                   (``_paired_kernels.particle_forces_split``; ``drag_update = "substep"``).
``forces``         F_p = K_p (u_p − v_p) − V_p ∇p_p into ext, the total following
                   (``_paired_kernels.particle_forces``; ``drag_update = "frozen"``).

With ``coupling.polydisperse = "sauter_y2"`` ``deposit`` takes 1/D̄ per cell (the host finishes it from the
device's sums: ``_voidage_cuda.sauter_deposit``, ``exchange_gpu.sauter_finish``) and each particle's
y = d/D̄ from it as the CPU does; the forces need only K_p.
"""
import math

from numba import cuda

from ..particles.contact._dispatch_cuda import cached_kernel, device_function
from . import _exchange_kernels as EK
from . import _paired_kernels as P
from .drag._dispatch_cuda import beta_per_solids, device_tree

THREADS = 128  # threads per block


@cuda.jit(device=True)
def _index(i):
    """The array index as it is (the CPU casts it to unsigned, ``_paired_kernels.U``, to skip wrap-around code)."""
    return i


stencil = device_tree(P._stencil, U=_index)
face_axis = device_tree(P._face_axis, U=_index)
mean = device_tree(P._mean, U=_index)
gas_at = device_tree(P._gas_at, U=_index)
arguments_valid = device_tree(EK._drag_arguments_valid)
store_force = device_function(EK.store_force)


@cuda.jit(device=True)
def _add(E, i0, i1, a0, a1, j0, j1, b0, b1, k):
    """E[i, j] += a_i b_j k over the two nodes of each axis (``_paired_kernels._add``), atomically."""
    cuda.atomic.add(E, (i0, j0), a0 * b0 * k)
    cuda.atomic.add(E, (i0, j1), a0 * b1 * k)
    cuda.atomic.add(E, (i1, j0), a1 * b0 * k)
    cuda.atomic.add(E, (i1, j1), a1 * b1 * k)


@cuda.jit(device=True)
def _scatter(A, B, i0, i1, a0, a1, j0, j1, b0, b1, k, vel):
    """A[i, j] += a_i b_j k, B[i, j] += a_i b_j k vel (``_paired_kernels._scatter``), atomically."""
    w = a0 * b0 * k
    cuda.atomic.add(A, (i0, j0), w)
    cuda.atomic.add(B, (i0, j0), w * vel)
    w = a0 * b1 * k
    cuda.atomic.add(A, (i0, j1), w)
    cuda.atomic.add(B, (i0, j1), w * vel)
    w = a1 * b0 * k
    cuda.atomic.add(A, (i1, j0), w)
    cuda.atomic.add(B, (i1, j0), w * vel)
    w = a1 * b1 * k
    cuda.atomic.add(A, (i1, j1), w)
    cuda.atomic.add(B, (i1, j1), w * vel)


@cached_kernel
def deposit(law, position, velocity, radius, volume, u, v, voidage, rho, mu, inv_dbar, dx, dy, min_voidage, px, py,
            fold, kp, AU, BU, AV, BV, KC, solids, EU, EV, bad):
    """K_p of each particle into kp, and its share of the face sums (``_paired_kernels.deposit``'s first two
    passes, the particles in any order): AU, BU (nx + 1, ny), AV, BV (nx, ny + 1), KC (nx, ny) Σ K_p of the
    particles centred in each cell, and with ``solids`` EU, EV the particle volume on the faces of its ∇p
    interpolation, all zeroed before and added into here. A particle whose drag arguments are out of range
    (``_exchange_kernels._drag_arguments_valid``) gets kp = NaN, deposits no drag and counts in bad[0].
    law : the packed drag law (``DragLaw.pack``); position, velocity : (N, 3); radius, volume, kp : (N,);
    u (nx + 1, ny), v (nx, ny + 1), voidage and rho (nx, ny): the gas; inv_dbar (nx, ny): 1/D̄ of each cell for
    the polydisperse drag, y = d/D̄ with 1/D̄ interpolated as ε is (DEM book 2012 eqs 10-12), or (0, 0): y = 1."""
    q = cuda.grid(1)
    if q >= position.shape[0]:
        return
    nx, ny = voidage.shape
    idx = 1.0 / dx
    idy = 1.0 / dy
    x = position[q, 0]
    y = position[q, 1]
    (ci0, ci1, cw0, cw1, fi0, fi1, fw0, fw1, cj0, cj1, cv0, cv1, fj0, fj1, fv0,
     fv1) = stencil(x, y, idx, idy, nx, ny, px, py, fold)
    if solids:  # V_p on the faces of its ∇p interpolation (always folded: ``_face_gradient``)
        if fold:
            _add(EU, fi0, fi1, fw0, fw1, cj0, cj1, cv0, cv1, volume[q])
            _add(EV, ci0, ci1, cw0, cw1, fj0, fj1, fv0, fv1, volume[q])
        else:
            gi0, gi1, gw0, gw1 = face_axis(x, idx, nx, px, True)
            gj0, gj1, gv0, gv1 = face_axis(y, idy, ny, py, True)
            _add(EU, gi0, gi1, gw0, gw1, cj0, cj1, cv0, cv1, volume[q])
            _add(EV, ci0, ci1, cw0, cw1, gj0, gj1, gv0, gv1, volume[q])
    eps = mean(voidage, ci0, ci1, cw0, cw1, cj0, cj1, cv0, cv1)
    rg = mean(rho, ci0, ci1, cw0, cw1, cj0, cj1, cv0, cv1)
    if eps < min_voidage:
        eps = min_voidage
    elif eps > 1.0:
        eps = 1.0
    vx = velocity[q, 0]
    vy = velocity[q, 1]
    vz = velocity[q, 2]
    wx = mean(u, fi0, fi1, fw0, fw1, cj0, cj1, cv0, cv1) - vx
    wy = mean(v, ci0, ci1, cw0, cw1, fj0, fj1, fv0, fv1) - vy
    wz = -vz
    slip = math.sqrt(wx * wx + wy * wy + wz * wz)
    d = 2.0 * radius[q]
    if not arguments_valid(eps, slip, d, rg, mu):
        kp[q] = math.nan
        cuda.atomic.add(bad, 0, 1)
        return
    # y = d/D̄ (DEM book 2012 eq. 11) with 1/D̄ interpolated as ε is; 1 for a monodisperse bed
    yq = d * mean(inv_dbar, ci0, ci1, cw0, cw1, cj0, cj1, cv0, cv1) if inv_dbar.shape[0] > 0 else 1.0
    k = beta_per_solids(law, eps, slip, d, rg, mu, yq) * volume[q]  # Sun 2007 eq. 29
    kp[q] = k
    ic = min(max(int(x / dx), 0), nx - 1)
    jc = min(max(int(y / dy), 0), ny - 1)
    cuda.atomic.add(KC, (ic, jc), k)
    _scatter(AU, BU, fi0, fi1, fw0, fw1, cj0, cj1, cv0, cv1, k, vx)
    _scatter(AV, BV, ci0, ci1, cw0, cw1, fj0, fj1, fv0, fv1, k, vy)


@cached_kernel
def forces_split(position, velocity, volume, kp, u, v, p, dx, dy, px, py, fold, pressure_force, dim2, ext, damp,
                 total):
    """ext[q] = K_q u_q − V_q ∇p_q, damp[q] = K_q, and total[q] += the change of the force at the current
    velocity: ``_paired_kernels.particle_forces_split`` (Sun 2007 eqs 28-29), one particle per thread."""
    q = cuda.grid(1)
    if q >= position.shape[0]:
        return
    nx, ny = p.shape
    ug, vg, gx, gy = gas_at(position[q, 0], position[q, 1], u, v, p, 1.0 / dx, 1.0 / dy, nx, ny, px, py, fold, True,
                            pressure_force)
    k = kp[q]
    ax = k * ug
    ay = k * vg
    if pressure_force:  # −V_p ∇p, Sun eq. 28
        ax -= volume[q] * gx
        ay -= volume[q] * gy
    vx = velocity[q, 0]
    vy = velocity[q, 1]
    vz = velocity[q, 2]
    c = damp[q]
    total[q, 0] += (ax - k * vx) - (ext[q, 0] - c * vx)
    total[q, 1] += (ay - k * vy) - (ext[q, 1] - c * vy)
    if not dim2:
        total[q, 2] += (0.0 - k * vz) - (ext[q, 2] - c * vz)
    ext[q, 0] = ax
    ext[q, 1] = ay
    ext[q, 2] = 0.0
    damp[q] = k


@cached_kernel
def forces(position, velocity, volume, kp, u, v, p, dx, dy, px, py, fold, pressure_force, dim2, ext, total):
    """ext[q] = K_q (u_q − v_q) − V_q ∇p_q, total[q] += its change: ``_paired_kernels.particle_forces``
    (Sun 2007 eqs 28-29; F_z = −K v_z in 3D, 0 in 2D), one particle per thread."""
    q = cuda.grid(1)
    if q >= position.shape[0]:
        return
    nx, ny = p.shape
    ug, vg, gx, gy = gas_at(position[q, 0], position[q, 1], u, v, p, 1.0 / dx, 1.0 / dy, nx, ny, px, py, fold, True,
                            pressure_force)
    k = kp[q]
    fx = k * (ug - velocity[q, 0])
    fy = k * (vg - velocity[q, 1])
    fz = -k * velocity[q, 2]
    if pressure_force:  # −V_p ∇p, Sun eq. 28
        fx -= volume[q] * gx
        fy -= volume[q] * gy
    if dim2:
        fz = 0.0
    store_force(ext, total, q, fx, fy, fz, True)
