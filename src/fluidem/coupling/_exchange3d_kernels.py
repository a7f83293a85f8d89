"""Compiled kernels of the cell-averaged exchanges on a 3D gas grid (``exchange3d.py``, ``momentum_exchange``
"cell" and "cell_beta"): the 2D kernels of ``_exchange_kernels.py`` and ``_paired_kernels.py`` with a third axis.

``cell_beta3d``         β_c = Σ_{p in c} β/(1 − ε)(ε_c, |u_c − v_s,c|, d_p) V_p / V_c per cell (Sun 2007 eq. 33),
                        u_c = (u, v, w) at the centre, each the mean of the cell's two faces of its axis;
``cell_faces3d``        the "cell" exchange's face β_f = (β_a + β_b)/2 and u_s,f = (β_a u_s,a + β_b u_s,b)/(β_a + β_b)
                        of the two cells a face joins (a ghost cell counts β = 0; a periodic side joins the two
                        edge cells), on the x-, y- and z-faces;
``cell_forces3d``       D_c = β_c V_c (u_c − u_s,c), shared by the particles whose centre lies in cell c in
                        proportion to V_p, minus V_p ∇p (Sun 2007 eq. 28) with ∇p interpolated as the "particle"
                        exchange does (``_paired3d_kernels._gas_at3``, boundary faces folded);
``pressure_voidage3d``  the gas's pressure-term voidage ε_p,f = 1 − Σ_p w_pf V_p / V_f on the faces of every axis,
                        w_pf the weights of the particles' ∇p: the pressure force paired as ``deposit3d`` pairs it.

Their per-particle arithmetic is in ``inline="always"`` helpers (``cell_drag3d``, ``cell_force3d``,
``pressure_deposit_one3d``) that ``_cell3d_cuda`` compiles for the device.

Σ_faces V_c (β_f u_f − (β u_s)_f) = Σ_c D_c exactly (each face carries half of each of its two cells), so with
``cell_forces3d`` the gas loses exactly the drag the particles gain. Each particle counts in the cell of its
centre, trunc(x / d) clamped to the grid (``_exchange_kernels._cell``), as in 2D. The drag law is its packed row
``law`` (``drag/_dispatch.py``).
"""
import math

import numpy as np
from numba import njit

from ._exchange_kernels import _cell, _drag_arguments_valid, store_force
from ._paired3d_kernels import _add3, _gas_at3, _voidage_of
from ._paired_kernels import _centre_axis, _face_axis
from .drag._dispatch import beta_per_solids


@njit(cache=True, inline="always", error_model="numpy")
def cell_drag3d(law, u, v, w, rho, voidage, solids_u, solids_v, solids_w, mu, inv_dbar, mixture, i, j, k, d):
    """(in range, β/(1 − ε) [kg m^-3 s^-1]) of a particle of diameter d in cell (i, j, k) for ``cell_beta3d``
    (Sun 2007 eq. 33): the cell's voidage ε and gas density, the slip |(u_c, v_c, w_c) − (v_s,x, v_s,y, v_s,z)|
    with u_c, v_c, w_c the means of the cell's two faces of each axis, y = d/D̄ of the cell with ``mixture``
    (else 1); (False, 0) where the drag arguments are out of range (the 2D ``_exchange_kernels.cell_drag``)."""
    sx = 0.5 * (u[i, j, k] + u[i + 1, j, k]) - solids_u[i, j, k]
    sy = 0.5 * (v[i, j, k] + v[i, j + 1, k]) - solids_v[i, j, k]
    sz = 0.5 * (w[i, j, k] + w[i, j, k + 1]) - solids_w[i, j, k]
    slip = math.sqrt(sx * sx + sy * sy + sz * sz)
    eps = voidage[i, j, k]
    rg = rho[i, j, k]
    if not _drag_arguments_valid(eps, slip, d, rg, mu):
        return False, 0.0
    return True, beta_per_solids(law, eps, slip, d, rg, mu, d * inv_dbar[i, j, k] if mixture else 1.0)


@njit(cache=True, error_model="numpy")
def cell_beta3d(law, position, radius, volume, u, v, w, rho, voidage, solids_u, solids_v, solids_w, mu, inv_dbar,
                dx, dy, dz, cell_volume, out):
    """out[i, j, k] = Σ_{p in (i, j, k)} β/(1 − ε) V_p / V_cell [kg m^-3 s^-1] (Sun 2007 eq. 33).

    β/(1 − ε) of the law packed in ``law`` at the cell's voidage ε and gas density, the particle's diameter and
    the cell's slip |(u_c, v_c, w_c) − (v_s,x, v_s,y, v_s,z)|, u_c the mean of the cell's two x-faces (v_c, w_c
    likewise). position (N, 3); radius, volume (N,); u (nx + 1, ny, nz), v (nx, ny + 1, nz), w (nx, ny, nz + 1);
    rho, voidage, solids_*, out (nx, ny, nz). inv_dbar (nx, ny, nz): 1/D̄ of each cell's mixture for the
    polydisperse drag, y = d/D̄ (DEM book 2012 eqs 10-12), or (0, 0, 0) for y = 1. β/(1 − ε) is evaluated once
    per cell and diameter. Returns the number of particles whose drag arguments are out of range (left out)."""
    nx, ny, nz = out.shape
    mixture = inv_dbar.shape[0] > 0
    done_d = np.full((nx, ny, nz), np.nan)  # diameter whose β/(1 − ε) done_b holds, per cell
    done_b = np.empty((nx, ny, nz))
    out[:, :, :] = 0.0
    bad = 0
    for p in range(position.shape[0]):
        i = _cell(position[p, 0], dx, nx)
        j = _cell(position[p, 1], dy, ny)
        k = _cell(position[p, 2], dz, nz)
        d = 2.0 * radius[p]
        if d == done_d[i, j, k]:  # same cell, same diameter: same β/(1 − ε)
            b = done_b[i, j, k]
        else:
            ok, b = cell_drag3d(law, u, v, w, rho, voidage, solids_u, solids_v, solids_w, mu, inv_dbar, mixture, i, j,
                                k, d)
            if not ok:
                bad += 1
                continue
            done_d[i, j, k] = d
            done_b[i, j, k] = b
        out[i, j, k] += b * volume[p]  # eq. 33
    for i in range(nx):
        for j in range(ny):
            for k in range(nz):
                out[i, j, k] /= cell_volume
    return bad


@njit(cache=True, inline="always")
def _at(f, a, m, i, j, k):
    """f at index m along axis a and (i, j, k) along the others."""
    if a == 0:
        return f[m, j, k]
    if a == 1:
        return f[i, m, k]
    return f[i, j, m]


@njit(cache=True, error_model="numpy")
def _faces_of_axis3(beta, solids, a, periodic, bf, sf):
    """``cell_faces3d`` along axis ``a``: bf, sf (the face shape of axis a) from the cell β and u_s."""
    n = beta.shape[a]
    f0, f1, f2 = bf.shape
    for i in range(f0):
        for j in range(f1):
            for k in range(f2):
                m = i if a == 0 else (j if a == 1 else k)
                lo, hi = m - 1, m
                if periodic and (m == 0 or m == n):
                    lo, hi = n - 1, 0
                ba = _at(beta, a, lo, i, j, k) if lo >= 0 else 0.0
                bb = _at(beta, a, hi, i, j, k) if hi < n else 0.0
                ma = ba * _at(solids, a, lo, i, j, k) if lo >= 0 else 0.0
                mb = bb * _at(solids, a, hi, i, j, k) if hi < n else 0.0
                bf[i, j, k] = 0.5 * (ba + bb)
                sf[i, j, k] = (ma + mb) / (ba + bb) if ba + bb > 0.0 else 0.0


@njit(cache=True, error_model="numpy")
def cell_faces3d(beta, solids_u, solids_v, solids_w, px, py, pz, bu, su, bv, sv, bw, sw):
    """Face β (bu, bv, bw) and solids velocity (su, sv, sw) of the "cell" exchange from the cell β and u_s
    (nx, ny, nz): β_f = (β_a + β_b)/2, u_s,f = (β_a u_s,a + β_b u_s,b)/(β_a + β_b) (0 where β_f = 0), a ghost cell
    counting β = 0 and a periodic side joining its two edge cells (face n = face 0); the 2D ``cell_faces``."""
    _faces_of_axis3(beta, solids_u, 0, px, bu, su)
    _faces_of_axis3(beta, solids_v, 1, py, bv, sv)
    _faces_of_axis3(beta, solids_w, 2, pz, bw, sw)


@njit(cache=True, inline="always", error_model="numpy")
def cell_force3d(x, y, z, vq, i, j, k, solids, beta, solids_u, solids_v, solids_w, u, v, w, p, idx, idy, idz,
                 cell_volume, px, py, pz, pressure_force):
    """(F_x, F_y, F_z) [N] of ``cell_forces3d`` for a particle of volume vq centred at (x, y, z) in cell (i, j, k),
    ``solids`` Σ V_r of the cells' particles: its share V_q/Σ V_r of its cell's drag β V_c (u_c − u_s,c), minus
    V_q ∇p_q (Sun 2007 eq. 28) if ``pressure_force`` (the 2D ``_paired_kernels.cell_force``)."""
    nx, ny, nz = beta.shape
    share = vq / solids[i, j, k] * beta[i, j, k] * cell_volume
    fx = share * (0.5 * (u[i, j, k] + u[i + 1, j, k]) - solids_u[i, j, k])
    fy = share * (0.5 * (v[i, j, k] + v[i, j + 1, k]) - solids_v[i, j, k])
    fz = share * (0.5 * (w[i, j, k] + w[i, j, k + 1]) - solids_w[i, j, k])
    if pressure_force:  # −V_p ∇p, Sun 2007 eq. 28
        _, _, _, gx, gy, gz = _gas_at3(x, y, z, u, v, w, p, idx, idy, idz, nx, ny, nz, px, py, pz, True, True)
        fx -= vq * gx
        fy -= vq * gy
        fz -= vq * gz
    return fx, fy, fz


@njit(cache=True, error_model="numpy")
def cell_forces3d(position, velocity, volume, beta, solids_u, solids_v, solids_w, u, v, w, p, dx, dy, dz, cell_volume,
                  px, py, pz, pressure_force, out, total):
    """out[q] = (V_q / Σ_{r in c} V_r) β_c V_c (u_c − u_s,c) − V_q ∇p_q [N] for the cell c of q's centre (Sun 2007's
    cell-averaged drag shared in the cell; u_c = (u, v, w) at the centre from the means of the cell's faces),
    ∇p_q the face gradients interpolated trilinearly with boundary faces folded (``_paired3d_kernels``) if
    ``pressure_force``. ``total`` (N, 3) follows the change of ``out`` (``_exchange_kernels.store_force``) or is
    (0, 3)."""
    nx, ny, nz = beta.shape
    solids = np.zeros((nx, ny, nz))
    n = position.shape[0]
    cell = np.empty((n, 3), np.int64)
    for q in range(n):
        i = _cell(position[q, 0], dx, nx)
        j = _cell(position[q, 1], dy, ny)
        k = _cell(position[q, 2], dz, nz)
        cell[q, 0] = i
        cell[q, 1] = j
        cell[q, 2] = k
        solids[i, j, k] += volume[q]
    idx, idy, idz = 1.0 / dx, 1.0 / dy, 1.0 / dz
    follow = total.shape[0] > 0
    for q in range(n):
        fx, fy, fz = cell_force3d(position[q, 0], position[q, 1], position[q, 2], volume[q], cell[q, 0], cell[q, 1],
                                  cell[q, 2], solids, beta, solids_u, solids_v, solids_w, u, v, w, p, idx, idy, idz,
                                  cell_volume, px, py, pz, pressure_force)
        store_force(out, total, q, fx, fy, fz, follow)


@njit(cache=True, inline="always")
def pressure_deposit_one3d(x, y, z, vq, idx, idy, idz, nx, ny, nz, px, py, pz, EU, EV, EW):
    """EU, EV, EW += w_pf vq on the faces of the ∇p interpolation of a particle of volume vq at (x, y, z): the
    trilinear weights of ``_paired3d_kernels`` (centre nodes across, face nodes along each axis, boundary faces
    folded); ``pressure_voidage3d``'s sum, one particle."""
    ci0, ci1, cwx0, cwx1 = _centre_axis(x, idx, nx, px)
    cj0, cj1, cwy0, cwy1 = _centre_axis(y, idy, ny, py)
    ck0, ck1, cwz0, cwz1 = _centre_axis(z, idz, nz, pz)
    gi0, gi1, gwx0, gwx1 = _face_axis(x, idx, nx, px, True)
    gj0, gj1, gwy0, gwy1 = _face_axis(y, idy, ny, py, True)
    gk0, gk1, gwz0, gwz1 = _face_axis(z, idz, nz, pz, True)
    _add3(EU, gi0, gi1, gwx0, gwx1, cj0, cj1, cwy0, cwy1, ck0, ck1, cwz0, cwz1, vq)
    _add3(EV, ci0, ci1, cwx0, cwx1, gj0, gj1, gwy0, gwy1, ck0, ck1, cwz0, cwz1, vq)
    _add3(EW, ci0, ci1, cwx0, cwx1, cj0, cj1, cwy0, cwy1, gk0, gk1, gwz0, gwz1, vq)


@njit(cache=True, error_model="numpy")
def pressure_voidage3d(position, volume, dx, dy, dz, px, py, pz, VU, VV, VW, min_voidage, EU, EV, EW):
    """EU, EV, EW (the face shapes) = max(1 − Σ_p w_pf V_p / V_f, min_voidage): the voidage of the gas's pressure
    term on each face, w_pf the trilinear weights by which the face gradients are interpolated to particle p
    (boundary faces folded, ``_paired3d_kernels._gradient_mean``) and V_f the face volumes VU, VV, VW
    (``exchange3d.face_volumes3d``). Then Σ_f (1 − ε_p,f) V_f ∂p/∂x_f = Σ_p V_p ∂p/∂x_p on every axis wherever no
    face is clipped: the gas's −ε_p,f ∇p and the particles' −V_p ∇p (Sun 2007 eq. 28) add up to −V_f ∇p
    (``_paired_kernels.pressure_voidage`` in 3D)."""
    nx, ny, nz = EU.shape[0] - 1, EV.shape[1] - 1, EW.shape[2] - 1
    idx, idy, idz = 1.0 / dx, 1.0 / dy, 1.0 / dz
    EU[:, :, :] = 0.0
    EV[:, :, :] = 0.0
    EW[:, :, :] = 0.0
    for q in range(position.shape[0]):
        pressure_deposit_one3d(position[q, 0], position[q, 1], position[q, 2], volume[q], idx, idy, idz, nx, ny, nz,
                               px, py, pz, EU, EV, EW)
    _voidage_of(EU, VU, min_voidage)
    _voidage_of(EV, VV, min_voidage)
    _voidage_of(EW, VW, min_voidage)
