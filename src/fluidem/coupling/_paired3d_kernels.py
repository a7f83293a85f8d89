"""Compiled kernels of the momentum-paired ``particle`` exchange on a 3D grid (``exchange3d.py``).

The 2D kernels (``_paired_kernels.py``, whose module docstring gives the scheme) with a third axis: the
gas velocity at a particle is the trilinear interpolation (Hoomans 1996 eqs 40-41 in 3D: the weights are the
products of the 1D weights along the three axes) of u from the x-faces (faces along x, centres along y
and z), of v from the y-faces and of w from the z-faces; the voidage, density and 1/D̄ from the cell
centres; ∇p from the face gradients like the velocity on their faces. Each axis uses the 1D node rules of
``_paired_kernels._centre_axis`` and ``_face_axis`` (folding of boundary nodes and faces, wrapping on
periodic axes), so Σ_f w_pf = 1 for every particle and face direction.

``deposit3d``              K_p = β/(1 − ε_p) V_p (Sun 2007 eq. 29) at the particle's interpolated ε_p and
                           slip, and the face sums A_f = Σ_p w_pf K_p, B_f = Σ_p w_pf K_p v_p (three face
                           directions); the gas takes β_f = A_f / V_f and u_s,f = B_f / A_f, implicitly, and
                           ε_p,f = 1 − Σ_p w_pf V_p / V_f in its pressure term.
``particle_forces3d``      after the gas step: F_p = K_p (Σ_f w_pf u_f − v_p) − V_p ∇p_p (Sun 2007 eqs 28-29),
                           so that Σ_f V_f β_f (u_f − u_s,f) = Σ_p K_p (u_p − v_p): the gas loses exactly what
                           the particles gain.
``particle_forces_split3d`` the same as ext = K_p u_p − V_p ∇p_p and damp = K_p, which the engine evaluates at
                           each sub-step's own velocity (``drag_update = "substep"``).
``sample3d``               gas velocity (u, v, w) and voidage at points, the same weights (trilinear).

The per-particle work (each K_p with its interpolation and drag law, each particle's force) runs in chunks
of ``CHUNK`` particles on Numba's threads (``prange``); ``deposit3d`` then adds the K_p onto the faces in
particle order (recomputing the weights there: on ``bubbling-3d`` that took half the time of keeping them in
a scratch array and reading them back), on all threads too: the grid is split along x into one slab of
whole yz planes per thread (``_voidage3d_kernels.slab_count``, ``slab_bounds``: cells and faces of x index
lo … hi − 1, the face nx in the last slab). A first pass over the particles (in chunks) marks the slabs of
each particle's x nodes (centres, faces, ∇p faces, centre cell) as the bits of one integer (``_face_slabs``);
then each slab walks the particles in particle order, skips those not marked for it, adds all the terms of a
particle marked for it alone and, of one that straddles two slabs, the terms whose x node lies in it
(``_face_sums_slab``). Every face and cell then receives the same numbers, in the same order, as in one
serial pass, so the results are bitwise the same for any number of threads; at most ``CHUNK``
particles, or one thread, take the one serial pass.
"""
import math

import numpy as np
from numba import njit, prange

from ._exchange_kernels import _drag_arguments_valid, store_force
from ._paired_kernels import CHUNK, _centre_axis, _face_axis
from ._voidage3d_kernels import slab_bits, slab_bounds, slab_count
from .drag._dispatch import beta_per_solids


@njit(cache=True, inline="always")
def _axis(x, inv_d, n, periodic, fold):
    """(c0, c1, cw0, cw1, f0, f1, fw0, fw1): the centre and the face nodes of one axis around x with weights."""
    c0, c1, cw0, cw1 = _centre_axis(x, inv_d, n, periodic)
    f0, f1, fw0, fw1 = _face_axis(x, inv_d, n, periodic, fold)
    return c0, c1, cw0, cw1, f0, f1, fw0, fw1


@njit(cache=True, inline="always")
def _mean3(f, i0, i1, a0, a1, j0, j1, b0, b1, k0, k1, c0, c1):
    """Σ a_i b_j c_k f[i, j, k] over the two nodes of each axis (trilinear)."""
    return (a0 * (b0 * (c0 * f[i0, j0, k0] + c1 * f[i0, j0, k1]) + b1 * (c0 * f[i0, j1, k0] + c1 * f[i0, j1, k1]))
            + a1 * (b0 * (c0 * f[i1, j0, k0] + c1 * f[i1, j0, k1]) + b1 * (c0 * f[i1, j1, k0] + c1 * f[i1, j1, k1])))


@njit(cache=True, inline="always")
def _add3(E, i0, i1, a0, a1, j0, j1, b0, b1, k0, k1, c0, c1, q):
    """E[i, j, k] += a_i b_j c_k q over the two nodes of each axis."""
    E[i0, j0, k0] += a0 * b0 * c0 * q
    E[i0, j0, k1] += a0 * b0 * c1 * q
    E[i0, j1, k0] += a0 * b1 * c0 * q
    E[i0, j1, k1] += a0 * b1 * c1 * q
    E[i1, j0, k0] += a1 * b0 * c0 * q
    E[i1, j0, k1] += a1 * b0 * c1 * q
    E[i1, j1, k0] += a1 * b1 * c0 * q
    E[i1, j1, k1] += a1 * b1 * c1 * q


@njit(cache=True, inline="always")
def _add3_slab(E, i0, i1, a0, a1, j0, j1, b0, b1, k0, k1, c0, c1, q, lo, hi):
    """``_add3`` restricted to the x nodes i in [lo, hi): the same products added in the same order."""
    if lo <= i0 < hi:
        E[i0, j0, k0] += a0 * b0 * c0 * q
        E[i0, j0, k1] += a0 * b0 * c1 * q
        E[i0, j1, k0] += a0 * b1 * c0 * q
        E[i0, j1, k1] += a0 * b1 * c1 * q
    if lo <= i1 < hi:
        E[i1, j0, k0] += a1 * b0 * c0 * q
        E[i1, j0, k1] += a1 * b0 * c1 * q
        E[i1, j1, k0] += a1 * b1 * c0 * q
        E[i1, j1, k1] += a1 * b1 * c1 * q


@njit(cache=True, inline="always")
def _face_gradient3(p, a, i, j, k, n, inv_d, periodic):
    """∂p/∂x_a on the face (i, j, k) of axis a [Pa/m] (its index along a is the face's): the centred difference
    of the two cells; across a periodic side the wrapped cells; a wall face copies its nearest interior face;
    0 with one cell across."""
    if n < 2:
        return 0.0
    m = i if a == 0 else (j if a == 1 else k)
    if m == 0 or m == n:
        if periodic:
            lo, hi = n - 1, 0
        elif m == 0:
            lo, hi = 0, 1
        else:
            lo, hi = n - 2, n - 1
    else:
        lo, hi = m - 1, m
    if a == 0:
        return (p[hi, j, k] - p[lo, j, k]) * inv_d
    if a == 1:
        return (p[i, hi, k] - p[i, lo, k]) * inv_d
    return (p[i, j, hi] - p[i, j, lo]) * inv_d


@njit(cache=True, inline="always")
def _gradient_mean(p, a, i0, i1, a0, a1, j0, j1, b0, b1, k0, k1, c0, c1, n, inv_d, periodic):
    """The face gradients of axis a interpolated trilinearly from the faces (i*, j*, k*) with the weights."""
    out = 0.0
    for s in range(2):
        ii = i0 if s == 0 else i1
        wa = a0 if s == 0 else a1
        for t in range(2):
            jj = j0 if t == 0 else j1
            wb = b0 if t == 0 else b1
            for u in range(2):
                kk = k0 if u == 0 else k1
                wc = c0 if u == 0 else c1
                out += wa * wb * wc * _face_gradient3(p, a, ii, jj, kk, n, inv_d, periodic)
    return out


@njit(cache=True, inline="always")
def _gas_at3(x, y, z, u, v, w, p, idx, idy, idz, nx, ny, nz, px, py, pz, fold, pressure):
    """Gas velocity (u, v, w) and ∇p at (x, y, z) with the weights of ``deposit3d``; ∇p 0 unless ``pressure``."""
    ci0, ci1, cwx0, cwx1, fi0, fi1, fwx0, fwx1 = _axis(x, idx, nx, px, fold)
    cj0, cj1, cwy0, cwy1, fj0, fj1, fwy0, fwy1 = _axis(y, idy, ny, py, fold)
    ck0, ck1, cwz0, cwz1, fk0, fk1, fwz0, fwz1 = _axis(z, idz, nz, pz, fold)
    ug = _mean3(u, fi0, fi1, fwx0, fwx1, cj0, cj1, cwy0, cwy1, ck0, ck1, cwz0, cwz1)
    vg = _mean3(v, ci0, ci1, cwx0, cwx1, fj0, fj1, fwy0, fwy1, ck0, ck1, cwz0, cwz1)
    wg = _mean3(w, ci0, ci1, cwx0, cwx1, cj0, cj1, cwy0, cwy1, fk0, fk1, fwz0, fwz1)
    gx = gy = gz = 0.0
    if pressure:
        gx = _gradient_mean(p, 0, fi0, fi1, fwx0, fwx1, cj0, cj1, cwy0, cwy1, ck0, ck1, cwz0, cwz1, nx, idx, px)
        gy = _gradient_mean(p, 1, ci0, ci1, cwx0, cwx1, fj0, fj1, fwy0, fwy1, ck0, ck1, cwz0, cwz1, ny, idy, py)
        gz = _gradient_mean(p, 2, ci0, ci1, cwx0, cwx1, cj0, cj1, cwy0, cwy1, fk0, fk1, fwz0, fwz1, nz, idz, pz)
    return ug, vg, wg, gx, gy, gz


@njit(cache=True, error_model="numpy")
def _face_gradients3(p, idx, idy, idz, px, py, pz):
    """(GX, GY, GZ): ∂p/∂x on every x-face, (nx + 1, ny, nz), ∂p/∂y on every y-face and ∂p/∂z on every z-face
    [Pa/m] (``_face_gradient3``), for the force passes: each face's gradient once per pass, not once per
    particle around it."""
    nx, ny, nz = p.shape
    GX = np.empty((nx + 1, ny, nz))
    GY = np.empty((nx, ny + 1, nz))
    GZ = np.empty((nx, ny, nz + 1))
    for i in range(nx + 1):
        for j in range(ny):
            for k in range(nz):
                GX[i, j, k] = _face_gradient3(p, 0, i, j, k, nx, idx, px)
    for i in range(nx):
        for j in range(ny + 1):
            for k in range(nz):
                GY[i, j, k] = _face_gradient3(p, 1, i, j, k, ny, idy, py)
    for i in range(nx):
        for j in range(ny):
            for k in range(nz + 1):
                GZ[i, j, k] = _face_gradient3(p, 2, i, j, k, nz, idz, pz)
    return GX, GY, GZ


@njit(cache=True, inline="always")
def _face_mean3(G, i0, i1, a0, a1, j0, j1, b0, b1, k0, k1, c0, c1):
    """``_gradient_mean`` from the face gradients G of ``_face_gradients3``: the same products added in the
    same order."""
    out = 0.0
    for s in range(2):
        ii = i0 if s == 0 else i1
        wa = a0 if s == 0 else a1
        for t in range(2):
            jj = j0 if t == 0 else j1
            wb = b0 if t == 0 else b1
            for u in range(2):
                kk = k0 if u == 0 else k1
                wc = c0 if u == 0 else c1
                out += wa * wb * wc * G[ii, jj, kk]
    return out


@njit(cache=True, inline="always")
def _gas_at3_faces(x, y, z, u, v, w, GX, GY, GZ, idx, idy, idz, nx, ny, nz, px, py, pz, fold, pressure):
    """``_gas_at3`` with ∇p from the face gradients of ``_face_gradients3`` (bitwise the same numbers)."""
    ci0, ci1, cwx0, cwx1, fi0, fi1, fwx0, fwx1 = _axis(x, idx, nx, px, fold)
    cj0, cj1, cwy0, cwy1, fj0, fj1, fwy0, fwy1 = _axis(y, idy, ny, py, fold)
    ck0, ck1, cwz0, cwz1, fk0, fk1, fwz0, fwz1 = _axis(z, idz, nz, pz, fold)
    ug = _mean3(u, fi0, fi1, fwx0, fwx1, cj0, cj1, cwy0, cwy1, ck0, ck1, cwz0, cwz1)
    vg = _mean3(v, ci0, ci1, cwx0, cwx1, fj0, fj1, fwy0, fwy1, ck0, ck1, cwz0, cwz1)
    wg = _mean3(w, ci0, ci1, cwx0, cwx1, cj0, cj1, cwy0, cwy1, fk0, fk1, fwz0, fwz1)
    gx = gy = gz = 0.0
    if pressure:
        gx = _face_mean3(GX, fi0, fi1, fwx0, fwx1, cj0, cj1, cwy0, cwy1, ck0, ck1, cwz0, cwz1)
        gy = _face_mean3(GY, ci0, ci1, cwx0, cwx1, fj0, fj1, fwy0, fwy1, ck0, ck1, cwz0, cwz1)
        gz = _face_mean3(GZ, ci0, ci1, cwx0, cwx1, cj0, cj1, cwy0, cwy1, fk0, fk1, fwz0, fwz1)
    return ug, vg, wg, gx, gy, gz


@njit(cache=True, error_model="numpy")
def sample3d(position, u, v, w, voidage, dx, dy, dz, px, py, pz, fold, out):
    """out[q] = (u, v, w, ε) at point q: the face velocities and the centre voidage interpolated trilinearly
    (Hoomans 1996 eqs 40-41 in 3D) with the weights of ``deposit3d``. position (N, 3); out (N, 4)."""
    nx, ny, nz = voidage.shape
    idx, idy, idz = 1.0 / dx, 1.0 / dy, 1.0 / dz
    for q in range(position.shape[0]):
        x, y, z = position[q, 0], position[q, 1], position[q, 2]
        ug, vg, wg, _, _, _ = _gas_at3(x, y, z, u, v, w, voidage, idx, idy, idz, nx, ny, nz, px, py, pz, fold,
                                       False)
        ci0, ci1, cwx0, cwx1 = _centre_axis(x, idx, nx, px)
        cj0, cj1, cwy0, cwy1 = _centre_axis(y, idy, ny, py)
        ck0, ck1, cwz0, cwz1 = _centre_axis(z, idz, nz, pz)
        out[q, 0] = ug
        out[q, 1] = vg
        out[q, 2] = wg
        out[q, 3] = _mean3(voidage, ci0, ci1, cwx0, cwx1, cj0, cj1, cwy0, cwy1, ck0, ck1, cwz0, cwz1)


@njit(cache=True, error_model="numpy")
def _kp_range(lo, hi, law, position, velocity, radius, volume, u, v, w, voidage, rho, mu, inv_dbar, idx, idy, idz,
              min_voidage, px, py, pz, fold, kp, valid):
    """``kp3d`` for the particles [lo, hi); returns the number out of range."""
    nx, ny, nz = voidage.shape
    mixture = inv_dbar.shape[0] > 0
    bad = 0
    for q in range(lo, hi):
        x, y, z = position[q, 0], position[q, 1], position[q, 2]
        ug, vg, wg, _, _, _ = _gas_at3(x, y, z, u, v, w, voidage, idx, idy, idz, nx, ny, nz, px, py, pz, fold,
                                       False)
        ci0, ci1, cwx0, cwx1 = _centre_axis(x, idx, nx, px)
        cj0, cj1, cwy0, cwy1 = _centre_axis(y, idy, ny, py)
        ck0, ck1, cwz0, cwz1 = _centre_axis(z, idz, nz, pz)
        eps = _mean3(voidage, ci0, ci1, cwx0, cwx1, cj0, cj1, cwy0, cwy1, ck0, ck1, cwz0, cwz1)
        rg = _mean3(rho, ci0, ci1, cwx0, cwx1, cj0, cj1, cwy0, cwy1, ck0, ck1, cwz0, cwz1)
        if eps < min_voidage:
            eps = min_voidage
        elif eps > 1.0:
            eps = 1.0
        sx = ug - velocity[q, 0]
        sy = vg - velocity[q, 1]
        sz = wg - velocity[q, 2]
        slip = math.sqrt(sx * sx + sy * sy + sz * sz)
        d = 2.0 * radius[q]
        ok = _drag_arguments_valid(eps, slip, d, rg, mu)
        valid[q] = ok
        if not ok:
            bad += 1
            kp[q] = math.nan
            continue
        yq = d * _mean3(inv_dbar, ci0, ci1, cwx0, cwx1, cj0, cj1, cwy0, cwy1, ck0, ck1, cwz0, cwz1) if mixture else 1.0
        kp[q] = beta_per_solids(law, eps, slip, d, rg, mu, yq) * volume[q]
    return bad


@njit(cache=True, error_model="numpy", parallel=True)
def _kp_parallel(law, position, velocity, radius, volume, u, v, w, voidage, rho, mu, inv_dbar, idx, idy, idz,
                 min_voidage, px, py, pz, fold, kp, valid):
    """``_kp_range`` over all particles in chunks of CHUNK on all threads."""
    n = position.shape[0]
    bad = 0
    for c in prange((n + CHUNK - 1) // CHUNK):
        bad += _kp_range(c * CHUNK, min(n, (c + 1) * CHUNK), law, position, velocity, radius, volume, u, v, w, voidage,
                         rho, mu, inv_dbar, idx, idy, idz, min_voidage, px, py, pz, fold, kp, valid)
    return bad


@njit(cache=True, error_model="numpy")
def kp3d(law, position, velocity, radius, volume, u, v, w, voidage, rho, mu, inv_dbar, dx, dy, dz, min_voidage, px,
         py, pz, fold, kp, valid):
    """kp[q] = β/(1 − ε_q) V_q [kg/s] (Sun 2007 eq. 29) of the law packed in ``law`` at the particle's
    interpolated voidage (clipped to [min_voidage, 1]), gas density and slip |u_q − v_q|; valid[q] whether its
    drag arguments are in range (else kp[q] = NaN). inv_dbar (nx, ny, nz): 1/D̄ of each cell (polydisperse
    drag, y = d/D̄ with 1/D̄ interpolated as ε is), or (0, 0, 0). Returns the number out of range. Particles in
    parallel chunks above CHUNK."""
    n = position.shape[0]
    idx, idy, idz = 1.0 / dx, 1.0 / dy, 1.0 / dz
    if n > CHUNK:
        return _kp_parallel(law, position, velocity, radius, volume, u, v, w, voidage, rho, mu, inv_dbar, idx, idy,
                            idz, min_voidage, px, py, pz, fold, kp, valid)
    return _kp_range(np.int64(0), n, law, position, velocity, radius, volume, u, v, w, voidage, rho, mu, inv_dbar, idx,
                     idy, idz, min_voidage, px, py, pz, fold, kp, valid)


@njit(cache=True, error_model="numpy")
def _coefficients(A, B, VF, beta, solids):
    """beta = A / V_f, solids = B / A (0 where A = 0): the face β and u_s the gas takes."""
    n0, n1, n2 = A.shape
    for i in range(n0):
        for j in range(n1):
            for k in range(n2):
                a = A[i, j, k]
                beta[i, j, k] = a / VF[i, j, k]
                solids[i, j, k] = B[i, j, k] / a if a > 0.0 else 0.0


@njit(cache=True, error_model="numpy")
def _voidage_of(E, VF, min_voidage):
    """E (the particle volume on each face) → max(1 − E / V_f, min_voidage)."""
    n0, n1, n2 = E.shape
    for i in range(n0):
        for j in range(n1):
            for k in range(n2):
                E[i, j, k] = max(1.0 - E[i, j, k] / VF[i, j, k], min_voidage)


@njit(cache=True, error_model="numpy")
def _face_slabs(lo, hi, position, ok, idx, nx, px, fold, pair, bit, slabs):
    """slabs[q] for q in [lo, hi): the bits ``bit[i]`` (1 << the slab of x index i, ``slab_of``) of the x nodes of
    particle q that ``_face_sums_serial`` adds to (centres, faces, ∇p faces, centre cell), OR-ed."""
    for q in range(lo, hi):
        x = position[q, 0]
        ci0, ci1, _, _, fi0, fi1, _, _ = _axis(x, idx, nx, px, fold)
        b = bit[ci0] | bit[ci1]
        if ok[q]:
            b |= bit[fi0] | bit[fi1] | bit[min(max(int(x * idx), 0), nx - 1)]
        if pair:
            gi0, gi1, _, _ = _face_axis(x, idx, nx, px, True)
            b |= bit[gi0] | bit[gi1]
        slabs[q] = b


@njit(cache=True, error_model="numpy")
def _face_sums_serial(position, velocity, volume, kp, ok, idx, idy, idz, px, py, pz, fold, pair, AU, BU, AV, BV, AW,
                      BW, KC, EU, EV, EW):
    """The face and cell sums of ``deposit3d`` (accumulated into), in particle order: A_f += w_pf K_p,
    B_f += w_pf K_p v_p, KC += K_p of the centre's cell and, with ``pair``, E_f += w_pf V_p (∇p weights, boundary
    faces folded). The one pass of one thread, or of at most ``CHUNK`` particles."""
    nx, ny, nz = KC.shape
    for q in range(position.shape[0]):
        x, y, z = position[q, 0], position[q, 1], position[q, 2]
        ci0, ci1, cwx0, cwx1, fi0, fi1, fwx0, fwx1 = _axis(x, idx, nx, px, fold)
        cj0, cj1, cwy0, cwy1, fj0, fj1, fwy0, fwy1 = _axis(y, idy, ny, py, fold)
        ck0, ck1, cwz0, cwz1, fk0, fk1, fwz0, fwz1 = _axis(z, idz, nz, pz, fold)
        if pair:  # V_p on the faces of its ∇p interpolation (always folded)
            gi0, gi1, gwx0, gwx1 = _face_axis(x, idx, nx, px, True)
            gj0, gj1, gwy0, gwy1 = _face_axis(y, idy, ny, py, True)
            gk0, gk1, gwz0, gwz1 = _face_axis(z, idz, nz, pz, True)
            vq = volume[q]
            _add3(EU, gi0, gi1, gwx0, gwx1, cj0, cj1, cwy0, cwy1, ck0, ck1, cwz0, cwz1, vq)
            _add3(EV, ci0, ci1, cwx0, cwx1, gj0, gj1, gwy0, gwy1, ck0, ck1, cwz0, cwz1, vq)
            _add3(EW, ci0, ci1, cwx0, cwx1, cj0, cj1, cwy0, cwy1, gk0, gk1, gwz0, gwz1, vq)
        if not ok[q]:
            continue
        k = kp[q]
        ic = min(max(int(x * idx), 0), nx - 1)
        jc = min(max(int(y * idy), 0), ny - 1)
        kc = min(max(int(z * idz), 0), nz - 1)
        KC[ic, jc, kc] += k
        _add3(AU, fi0, fi1, fwx0, fwx1, cj0, cj1, cwy0, cwy1, ck0, ck1, cwz0, cwz1, k)
        _add3(BU, fi0, fi1, fwx0, fwx1, cj0, cj1, cwy0, cwy1, ck0, ck1, cwz0, cwz1, k * velocity[q, 0])
        _add3(AV, ci0, ci1, cwx0, cwx1, fj0, fj1, fwy0, fwy1, ck0, ck1, cwz0, cwz1, k)
        _add3(BV, ci0, ci1, cwx0, cwx1, fj0, fj1, fwy0, fwy1, ck0, ck1, cwz0, cwz1, k * velocity[q, 1])
        _add3(AW, ci0, ci1, cwx0, cwx1, cj0, cj1, cwy0, cwy1, fk0, fk1, fwz0, fwz1, k)
        _add3(BW, ci0, ci1, cwx0, cwx1, cj0, cj1, cwy0, cwy1, fk0, fk1, fwz0, fwz1, k * velocity[q, 2])


@njit(cache=True, error_model="numpy")
def _face_sums_slab(s, lo, hi, slabs, position, velocity, volume, kp, ok, idx, idy, idz, px, py, pz, fold, pair, AU,
                    BU, AV, BV, AW, BW, KC, EU, EV, EW):
    """The sums of ``_face_sums_serial`` onto the x nodes [lo, hi) of slab s, in particle order: the particles
    whose slabs (``_face_slabs``) include s, each term whose x node lies in the slab (all of them where the
    particle's nodes lie in s alone). Every node receives the terms of the serial pass, in the same order.
    Written out beside the serial pass rather than sharing a per-particle helper with it: such a helper, inlined
    or called, made the deposit of ``bubbling-3d`` 15-30 % slower (0.59-0.68 against 0.50-0.52 ms on two threads)."""
    nx, ny, nz = KC.shape
    own = np.int64(1) << s  # slab_bits of its x indices
    for q in range(position.shape[0]):
        b = slabs[q]
        if b & own == 0:
            continue
        whole = b == own
        x, y, z = position[q, 0], position[q, 1], position[q, 2]
        ci0, ci1, cwx0, cwx1, fi0, fi1, fwx0, fwx1 = _axis(x, idx, nx, px, fold)
        cj0, cj1, cwy0, cwy1, fj0, fj1, fwy0, fwy1 = _axis(y, idy, ny, py, fold)
        ck0, ck1, cwz0, cwz1, fk0, fk1, fwz0, fwz1 = _axis(z, idz, nz, pz, fold)
        if pair:
            gi0, gi1, gwx0, gwx1 = _face_axis(x, idx, nx, px, True)
            gj0, gj1, gwy0, gwy1 = _face_axis(y, idy, ny, py, True)
            gk0, gk1, gwz0, gwz1 = _face_axis(z, idz, nz, pz, True)
            vq = volume[q]
            if whole:  # no tests: they cost as much as the adds
                _add3(EU, gi0, gi1, gwx0, gwx1, cj0, cj1, cwy0, cwy1, ck0, ck1, cwz0, cwz1, vq)
                _add3(EV, ci0, ci1, cwx0, cwx1, gj0, gj1, gwy0, gwy1, ck0, ck1, cwz0, cwz1, vq)
                _add3(EW, ci0, ci1, cwx0, cwx1, cj0, cj1, cwy0, cwy1, gk0, gk1, gwz0, gwz1, vq)
            else:
                _add3_slab(EU, gi0, gi1, gwx0, gwx1, cj0, cj1, cwy0, cwy1, ck0, ck1, cwz0, cwz1, vq, lo, hi)
                _add3_slab(EV, ci0, ci1, cwx0, cwx1, gj0, gj1, gwy0, gwy1, ck0, ck1, cwz0, cwz1, vq, lo, hi)
                _add3_slab(EW, ci0, ci1, cwx0, cwx1, cj0, cj1, cwy0, cwy1, gk0, gk1, gwz0, gwz1, vq, lo, hi)
        if not ok[q]:
            continue
        k = kp[q]
        ic = min(max(int(x * idx), 0), nx - 1)
        if whole or lo <= ic < hi:
            jc = min(max(int(y * idy), 0), ny - 1)
            kc = min(max(int(z * idz), 0), nz - 1)
            KC[ic, jc, kc] += k
        if whole:
            _add3(AU, fi0, fi1, fwx0, fwx1, cj0, cj1, cwy0, cwy1, ck0, ck1, cwz0, cwz1, k)
            _add3(BU, fi0, fi1, fwx0, fwx1, cj0, cj1, cwy0, cwy1, ck0, ck1, cwz0, cwz1, k * velocity[q, 0])
            _add3(AV, ci0, ci1, cwx0, cwx1, fj0, fj1, fwy0, fwy1, ck0, ck1, cwz0, cwz1, k)
            _add3(BV, ci0, ci1, cwx0, cwx1, fj0, fj1, fwy0, fwy1, ck0, ck1, cwz0, cwz1, k * velocity[q, 1])
            _add3(AW, ci0, ci1, cwx0, cwx1, cj0, cj1, cwy0, cwy1, fk0, fk1, fwz0, fwz1, k)
            _add3(BW, ci0, ci1, cwx0, cwx1, cj0, cj1, cwy0, cwy1, fk0, fk1, fwz0, fwz1, k * velocity[q, 2])
        else:
            _add3_slab(AU, fi0, fi1, fwx0, fwx1, cj0, cj1, cwy0, cwy1, ck0, ck1, cwz0, cwz1, k, lo, hi)
            _add3_slab(BU, fi0, fi1, fwx0, fwx1, cj0, cj1, cwy0, cwy1, ck0, ck1, cwz0, cwz1, k * velocity[q, 0], lo, hi)
            _add3_slab(AV, ci0, ci1, cwx0, cwx1, fj0, fj1, fwy0, fwy1, ck0, ck1, cwz0, cwz1, k, lo, hi)
            _add3_slab(BV, ci0, ci1, cwx0, cwx1, fj0, fj1, fwy0, fwy1, ck0, ck1, cwz0, cwz1, k * velocity[q, 1], lo, hi)
            _add3_slab(AW, ci0, ci1, cwx0, cwx1, cj0, cj1, cwy0, cwy1, fk0, fk1, fwz0, fwz1, k, lo, hi)
            _add3_slab(BW, ci0, ci1, cwx0, cwx1, cj0, cj1, cwy0, cwy1, fk0, fk1, fwz0, fwz1, k * velocity[q, 2], lo, hi)


@njit(cache=True, error_model="numpy", parallel=True)
def _face_sums_parallel(position, velocity, volume, kp, ok, idx, idy, idz, px, py, pz, fold, pair, AU, BU, AV, BV,
                        AW, BW, KC, EU, EV, EW):
    """``_face_sums_serial`` on all threads: each particle's slabs (``_face_slabs``, in chunks of ``CHUNK``), then
    the sums of each x slab (``_voidage3d_kernels.slab_count``, ``slab_bounds``; ``_face_sums_slab``)."""
    nx = KC.shape[0]
    m = slab_count(nx)
    n = position.shape[0]
    bit = slab_bits(m, nx)
    slabs = np.empty(n, np.int64)
    for c in prange((n + CHUNK - 1) // CHUNK):
        _face_slabs(c * CHUNK, min(n, (c + 1) * CHUNK), position, ok, idx, nx, px, fold, pair, bit, slabs)
    for s in prange(m):
        lo, hi = slab_bounds(s, m, nx)
        _face_sums_slab(np.int64(s), lo, hi, slabs, position, velocity, volume, kp, ok, idx, idy, idz, px, py, pz, fold,
                        pair, AU, BU, AV, BV, AW, BW, KC, EU, EV, EW)


@njit(cache=True, error_model="numpy")
def deposit3d(law, position, velocity, radius, volume, u, v, w, voidage, rho, mu, inv_dbar, dx, dy, dz, min_voidage,
              px, py, pz, fold, kp, AU, BU, AV, BV, AW, BW, KC, VU, VV, VW, beta_u, su, beta_v, sv, beta_w, sw, pair,
              EU, EV, EW, valid=None):
    """K_p and the face sums of the ``particle`` exchange on a 3D grid (module docstring); returns the number of
    particles whose drag arguments are out of range (K_p NaN, nothing deposited for them).

    position, velocity : (N, 3); radius, volume, kp : (N,); u, AU, BU, VU, beta_u, su : (nx + 1, ny, nz) and
    likewise on the y- and z-faces; voidage (ε at the end of the gas step), rho, KC : (nx, ny, nz). A*, B* are
    overwritten, KC[i, j, k] becomes Σ K_p of the particles whose centre lies in the cell. The gas takes
    beta_* = A / V_f with the face volumes V* (``exchange3d.face_volumes3d``) and u_s = B / A. ``pair``: EU,
    EV, EW (face shapes) become the pressure term's voidage 1 − Σ_p w_pf V_p / V_f (clipped below at
    min_voidage), V_p deposited with the weights of ∇p (boundary faces always folded, as ``_face_gradient3``
    copies the interior face).

    valid : (N,) bool scratch of the drag checks, allocated here if None or shorter. K_p is computed first (in
    parallel chunks, ``kp3d``), then added to the faces in particle order (``_face_sums``, x slabs on all
    threads)."""
    nx = voidage.shape[0]
    idx, idy, idz = 1.0 / dx, 1.0 / dy, 1.0 / dz
    n = position.shape[0]
    if valid is None:
        ok = np.empty(n, dtype=np.bool_)
    elif valid.shape[0] < n:
        ok = np.empty(n, dtype=np.bool_)
    else:
        ok = valid
    bad = kp3d(law, position, velocity, radius, volume, u, v, w, voidage, rho, mu, inv_dbar, dx, dy, dz, min_voidage,
               px, py, pz, fold, kp, ok)
    for arr in (AU, BU, AV, BV, AW, BW, KC):
        arr[:, :, :] = 0.0
    if pair:
        EU[:, :, :] = 0.0
        EV[:, :, :] = 0.0
        EW[:, :, :] = 0.0
    if n > CHUNK and slab_count(nx) > 1:
        _face_sums_parallel(position, velocity, volume, kp, ok, idx, idy, idz, px, py, pz, fold, pair, AU, BU, AV,
                            BV, AW, BW, KC, EU, EV, EW)
    else:
        _face_sums_serial(position, velocity, volume, kp, ok, idx, idy, idz, px, py, pz, fold, pair, AU, BU, AV, BV,
                          AW, BW, KC, EU, EV, EW)
    _coefficients(AU, BU, VU, beta_u, su)
    _coefficients(AV, BV, VV, beta_v, sv)
    _coefficients(AW, BW, VW, beta_w, sw)
    if pair:
        _voidage_of(EU, VU, min_voidage)
        _voidage_of(EV, VV, min_voidage)
        _voidage_of(EW, VW, min_voidage)
    return bad


@njit(cache=True, error_model="numpy")
def _pressure_faces(p, idx, idy, idz, px, py, pz, pressure):
    """``_face_gradients3`` where the pressure force is on, else three empty arrays."""
    if pressure:
        return _face_gradients3(p, idx, idy, idz, px, py, pz)
    e = np.empty((0, 0, 0))
    return e, e, e


@njit(cache=True, error_model="numpy")
def _forces_range(lo, hi, position, velocity, volume, kp, u, v, w, GX, GY, GZ, idx, idy, idz, px, py, pz, fold,
                  pressure_force, out, total):
    """``particle_forces3d`` for the particles [lo, hi)."""
    nx, ny, nz = u.shape[0] - 1, u.shape[1], u.shape[2]
    follow = total.shape[0] > 0
    for q in range(lo, hi):
        ug, vg, wg, gx, gy, gz = _gas_at3_faces(position[q, 0], position[q, 1], position[q, 2], u, v, w, GX, GY, GZ,
                                                idx, idy, idz, nx, ny, nz, px, py, pz, fold, pressure_force)
        k = kp[q]
        fx = k * (ug - velocity[q, 0])
        fy = k * (vg - velocity[q, 1])
        fz = k * (wg - velocity[q, 2])
        if pressure_force:  # −V_p ∇p, Sun 2007 eq. 28
            fx -= volume[q] * gx
            fy -= volume[q] * gy
            fz -= volume[q] * gz
        store_force(out, total, q, fx, fy, fz, follow)


@njit(cache=True, error_model="numpy", parallel=True)
def _forces_parallel(position, velocity, volume, kp, u, v, w, GX, GY, GZ, idx, idy, idz, px, py, pz, fold,
                     pressure_force, out, total):
    """``_forces_range`` over all particles in chunks of CHUNK on all threads."""
    n = position.shape[0]
    for c in prange((n + CHUNK - 1) // CHUNK):
        _forces_range(c * CHUNK, min(n, (c + 1) * CHUNK), position, velocity, volume, kp, u, v, w, GX, GY, GZ, idx,
                      idy, idz, px, py, pz, fold, pressure_force, out, total)


@njit(cache=True, error_model="numpy")
def particle_forces3d(position, velocity, volume, kp, u, v, w, p, dx, dy, dz, px, py, pz, fold, pressure_force, out,
                      total):
    """out[q] = K_q (u_q − v_q) − V_q ∇p_q [N] (Sun 2007 eqs 28-29) with the weights of ``deposit3d``; ``total``
    (N, 3) follows the change of ``out`` (``_exchange_kernels.store_force``) or is (0, 3). Particles in parallel
    chunks above CHUNK."""
    n = position.shape[0]
    idx, idy, idz = 1.0 / dx, 1.0 / dy, 1.0 / dz
    GX, GY, GZ = _pressure_faces(p, idx, idy, idz, px, py, pz, pressure_force)
    if n > CHUNK:
        _forces_parallel(position, velocity, volume, kp, u, v, w, GX, GY, GZ, idx, idy, idz, px, py, pz, fold,
                         pressure_force, out, total)
    else:
        _forces_range(np.int64(0), n, position, velocity, volume, kp, u, v, w, GX, GY, GZ, idx, idy, idz, px, py, pz,
                      fold, pressure_force, out, total)


@njit(cache=True, error_model="numpy")
def _split_range(lo, hi, position, velocity, volume, kp, u, v, w, GX, GY, GZ, idx, idy, idz, px, py, pz, fold,
                 pressure_force, ext, damp, total):
    """``particle_forces_split3d`` for the particles [lo, hi)."""
    nx, ny, nz = u.shape[0] - 1, u.shape[1], u.shape[2]
    for q in range(lo, hi):
        ug, vg, wg, gx, gy, gz = _gas_at3_faces(position[q, 0], position[q, 1], position[q, 2], u, v, w, GX, GY, GZ,
                                                idx, idy, idz, nx, ny, nz, px, py, pz, fold, pressure_force)
        k = kp[q]
        a0 = k * ug
        a1 = k * vg
        a2 = k * wg
        if pressure_force:  # −V_p ∇p, Sun 2007 eq. 28
            a0 -= volume[q] * gx
            a1 -= volume[q] * gy
            a2 -= volume[q] * gz
        c = damp[q]
        for m in range(3):
            vm = velocity[q, m]
            new = a0 if m == 0 else (a1 if m == 1 else a2)
            total[q, m] += (new - k * vm) - (ext[q, m] - c * vm)
            ext[q, m] = new
        damp[q] = k


@njit(cache=True, error_model="numpy", parallel=True)
def _split_parallel(position, velocity, volume, kp, u, v, w, GX, GY, GZ, idx, idy, idz, px, py, pz, fold,
                    pressure_force, ext, damp, total):
    """``_split_range`` over all particles in chunks of CHUNK on all threads."""
    n = position.shape[0]
    for c in prange((n + CHUNK - 1) // CHUNK):
        _split_range(c * CHUNK, min(n, (c + 1) * CHUNK), position, velocity, volume, kp, u, v, w, GX, GY, GZ, idx,
                     idy, idz, px, py, pz, fold, pressure_force, ext, damp, total)


@njit(cache=True, error_model="numpy")
def particle_forces_split3d(position, velocity, volume, kp, u, v, w, p, dx, dy, dz, px, py, pz, fold, pressure_force,
                            ext, damp, total):
    """``particle_forces3d`` split for a drag that follows the particle's own velocity (``drag_update =
    "substep"``): ext[q] = K_q u_q − V_q ∇p_q and damp[q] = K_q, the engine evaluating ext − K v at each
    sub-step's velocity (Sun 2007 eq. 29 with u_q held from the step). ``total`` (N, 3) follows the change of
    the force at the current velocity: += (ext_new − K_new v) − (ext_old − K_old v). Particles in parallel
    chunks above CHUNK."""
    n = position.shape[0]
    idx, idy, idz = 1.0 / dx, 1.0 / dy, 1.0 / dz
    GX, GY, GZ = _pressure_faces(p, idx, idy, idz, px, py, pz, pressure_force)
    if n > CHUNK:
        _split_parallel(position, velocity, volume, kp, u, v, w, GX, GY, GZ, idx, idy, idz, px, py, pz, fold,
                        pressure_force, ext, damp, total)
    else:
        _split_range(np.int64(0), n, position, velocity, volume, kp, u, v, w, GX, GY, GZ, idx, idy, idz, px, py, pz,
                     fold, pressure_force, ext, damp, total)
