"""Compiled kernels of the gas–particle exchange (``exchange.py``): cell β and the gas force on each particle.

``cell_beta``    Σ_p β/(1 − ε)(ε, |u_cell − v_s|, d_p) V_p / V_cell per cell (Sun 2007 eq. 33)
``gas_forces``   per particle, in one pass: gas velocity, voidage, density and ∇p interpolated
                 from the staggered grid (Hoomans 1996 eqs 40-41), the drag β V_p/(1 − ε) (u − v)
                 (Sun 2007 eq. 29) and −V_p ∇p (eq. 28), optionally swapped straight into the
                 engine's external and total forces

The drag law is its packed row ``law`` (``DragLaw.pack``; ``drag/_dispatch.py``). Both force kernels check the
drag arguments as ``DragLaw.beta_per_solids`` does and return the number of particles whose
arguments are out of range (``cell_beta`` leaves them out, ``gas_forces`` gives them NaN; the
caller raises).
"""
import math

import numpy as np
from numba import njit

from ._interpolation_kernels import face_gradients, locate, pad
from .drag._dispatch import beta_per_solids


@njit(cache=True, inline="always")
def _cell(x, d, n):
    """Cell of coordinate x on n cells of width d: trunc(x / d) clamped to [0, n − 1].

    As the NumPy coupling counted it; the voidage map's ``cell_index`` takes floor(x (1/d)),
    which for a centre exactly on a face can be the next cell (0.03/0.01 < 3, 0.03 · 100 = 3).
    """
    q = x / d
    if not q >= 1.0:  # below 1, negative or NaN
        return 0
    if q >= n:
        return n - 1
    return int(q)


@njit(cache=True, inline="always")
def _drag_arguments_valid(eps, slip, d, rho, mu):
    """The range checks of ``DragLaw.beta_per_solids``: 0 < ε ≤ 1, slip ≥ 0, d, ρ, μ > 0 (a NaN fails only in ε)."""
    return eps > 0.0 and eps <= 1.0 and not slip < 0.0 and not d <= 0.0 and not rho <= 0.0 and not mu <= 0.0


@njit(cache=True, inline="always")
def store_force(out, total, q, fx, fy, fz, follow):
    """out[q] = (fx, fy, fz); if ``follow``, total[q] += the change first (the engine's stored
    total force follows its external force)."""
    if follow:
        total[q, 0] += fx - out[q, 0]
        total[q, 1] += fy - out[q, 1]
        total[q, 2] += fz - out[q, 2]
    out[q, 0] = fx
    out[q, 1] = fy
    out[q, 2] = fz


@njit(cache=True, inline="always", error_model="numpy")
def cell_drag(law, u, v, rho, voidage, solids_u, solids_v, mu, inv_dbar, mixture, i, j, d):
    """(in range, β/(1 − ε)) of a particle of diameter d in cell (i, j) for ``cell_beta`` (Sun 2007 eq. 33): the
    cell's ε and gas density, the slip |(u_cell, v_cell) − (v_s,x, v_s,y)| with u_cell, v_cell the means of the
    cell's two faces, y = d/D̄ of the cell with ``mixture`` (else 1); (False, 0) where the drag arguments are out
    of range."""
    slip = math.hypot(0.5 * (u[i, j] + u[i + 1, j]) - solids_u[i, j],
                      0.5 * (v[i, j] + v[i, j + 1]) - solids_v[i, j])
    eps = voidage[i, j]
    rg = rho[i, j]
    if not _drag_arguments_valid(eps, slip, d, rg, mu):
        return False, 0.0
    return True, beta_per_solids(law, eps, slip, d, rg, mu, d * inv_dbar[i, j] if mixture else 1.0)


@njit(cache=True, error_model="numpy")
def cell_beta(law, position, radius, volume, u, v, rho, voidage, solids_u, solids_v, mu, inv_dbar, dx, dy,
              cell_volume, out):
    """out[i, j] = Σ_{p in (i, j)} β/(1 − ε) V_p / V_cell [kg m^-3 s^-1] (Sun 2007 eq. 33).

    Each particle counts in the cell of its centre; β/(1 − ε) of the drag law packed in ``law`` is taken with the
    cell's voidage ε and gas density, the particle's diameter and the cell's slip
    |(u_cell, v_cell) − (v_s,x, v_s,y)|, u_cell and v_cell the means of the two faces.
    position : (N, ≥2) [m]; radius, volume : (N,); u : (nx + 1, ny); v : (nx, ny + 1);
    rho, voidage, solids_u, solids_v, out : (nx, ny). Returns the number of particles whose drag
    arguments are out of range. β/(1 − ε) is evaluated once per cell and diameter. inv_dbar (nx, ny):
    1/D̄ of each cell's mixture [1/m] for the polydisperse drag, y = d/D̄ of the cell (DEM book 2012
    eqs 10-12, ``drag._dispatch.beta_per_solids``); (0, 0) for a monodisperse bed (y = 1).
    """
    nx, ny = out.shape
    mixture = inv_dbar.shape[0] > 0
    done_d = np.full((nx, ny), np.nan)  # diameter whose β/(1 − ε) done_b holds, per cell
    done_b = np.empty((nx, ny))
    for i in range(nx):
        for j in range(ny):
            out[i, j] = 0.0
    bad = 0
    for p in range(position.shape[0]):
        i = _cell(position[p, 0], dx, nx)
        j = _cell(position[p, 1], dy, ny)
        d = 2.0 * radius[p]
        if d == done_d[i, j]:  # same cell, same diameter: same β/(1 − ε)
            b = done_b[i, j]
        else:
            ok, b = cell_drag(law, u, v, rho, voidage, solids_u, solids_v, mu, inv_dbar, mixture, i, j, d)
            if not ok:
                bad += 1
                continue
            done_d[i, j] = d
            done_b[i, j] = b
        out[i, j] += b * volume[p]  # eq. 33
    for i in range(nx):
        for j in range(ny):
            out[i, j] /= cell_volume
    return bad


@njit(cache=True, inline="always")
def _weights(tx, ty):
    """Eq. 41's A/(DX DY) of the nodes (i, j), (i+1, j), (i+1, j+1), (i, j+1) (as ``node_mean`` forms them)."""
    return (1.0 - tx) * (1.0 - ty), tx * (1.0 - ty), tx * ty, (1.0 - tx) * ty


@njit(cache=True, inline="always")
def _mean2(f, i, j, w):
    """``node_mean`` of the two fields f[:, :, 0] and f[:, :, 1] around (i, j), the weights formed once."""
    a = w[0] * f[i, j, 0] + w[1] * f[i + 1, j, 0] + w[2] * f[i + 1, j + 1, 0] + w[3] * f[i, j + 1, 0]
    b = w[0] * f[i, j, 1] + w[1] * f[i + 1, j, 1] + w[2] * f[i + 1, j + 1, 1] + w[3] * f[i, j + 1, 1]
    return a, b


@njit(cache=True, error_model="numpy")
def gas_forces(law, position, velocity, radius, volume, u, v, voidage, rho, p, mu, inv_dbar, xc, yc, xf, yf, dx,
               dy, min_voidage, pressure_force, dim2, out, total):
    """out[q] = gas force on particle q [N]: β V_p/(1 − ε) (u − v_q) (Sun 2007 eq. 29), minus V_p ∇p if
    ``pressure_force`` (eq. 28); z component 0 if ``dim2``.

    At each centre, by area weighting of the four surrounding nodes (Hoomans 1996 eqs 40-41):
    u on x-faces and v on y-faces with linearly extrapolated wall values, ε (then clipped to
    [min_voidage, 1]) and ρ at centres with copied wall values, ∂p/∂x and ∂p/∂y on the faces
    (centred differences, wall faces copied). These are the fields and rules of
    ``interpolation.sample_gas``; fields on the same nodes are stored side by side (ε with ρ,
    u with ∂p/∂x, v with ∂p/∂y) and share one set of weights. xc, yc : node coordinates of the
    wall-extended centre field; xf, yf : x-face and y-face coordinates [m] (``interpolation._axes``).
    position, velocity, out : (N, 3); radius, volume : (N,); u : (nx + 1, ny); v : (nx, ny + 1);
    voidage, rho, p : (nx, ny). ``total``: (N, 3) to make it follow the change of ``out``
    (total += new − out, then out = new: the engine's stored total force and its ``ext_force``),
    or (0, 3) for none. Returns the number of particles whose drag arguments are out of range
    (their force is NaN). inv_dbar (nx, ny): 1/D̄ of each cell's mixture [1/m], interpolated to the
    centre as ε is, for the polydisperse drag y = d/D̄ (DEM book 2012 eqs 10-12); (0, 0) for a
    monodisperse bed (y = 1). Serial: at the particle counts of coupled 2D beds a parallel region
    costs more than it saves, and beside the DEM of large beds this kernel is small.
    """
    nx, ny = voidage.shape
    mixture = inv_dbar.shape[0] > 0
    cen = np.empty((nx + 2, ny + 2, 2))
    xfa = np.zeros((nx + 1, ny + 2, 2))
    yfa = np.zeros((nx + 2, ny + 1, 2))
    dbar = np.empty((nx + 2, ny + 2) if mixture else (0, 0))
    gas_force_fields(u, v, voidage, rho, p, inv_dbar, dx, dy, pressure_force, cen, xfa, yfa, dbar)
    inv_dx = 1.0 / dx
    inv_dy = 1.0 / dy
    three = velocity.shape[1] > 2
    follow = total.shape[0] > 0
    bad = 0
    for q in range(position.shape[0]):
        ok, fx, fy, fz = gas_force_one(law, q, position, velocity, radius, volume, cen, xfa, yfa, dbar, mixture, xc,
                                       yc, xf, yf, inv_dx, inv_dy, mu, min_voidage, pressure_force, dim2, three)
        if not ok:
            bad += 1
        store_force(out, total, q, fx, fy, fz, follow)
    return bad


@njit(cache=True)
def gas_force_fields(u, v, voidage, rho, p, inv_dbar, dx, dy, pressure_force, cen, xfa, yfa, dbar):
    """The wall-extended node fields ``gas_forces`` interpolates (``interpolation.sample_gas``' rules, Hoomans
    1996 eqs 40-41): cen (nx + 2, ny + 2, 2) ← ε, ρ at the centres (wall values copied); xfa (nx + 1, ny + 2, 2)
    ← u (linearly extrapolated) and, with ``pressure_force``, ∂p/∂x on x-faces; yfa (nx + 2, ny + 1, 2) ← v and
    ∂p/∂y on y-faces (xfa, yfa zeroed by the caller); dbar (nx + 2, ny + 2) ← 1/D̄ at the centres (copied), or
    (0, 0) for a monodisperse drag."""
    yes, no = np.bool_(True), np.bool_(False)  # run-time values: one compiled ``pad``, not one per combination
    pad(voidage, yes, yes, no, cen[:, :, 0])
    pad(rho, yes, yes, no, cen[:, :, 1])
    pad(u, no, yes, yes, xfa[:, :, 0])
    pad(v, yes, no, yes, yfa[:, :, 0])
    if pressure_force:
        nx, ny = voidage.shape
        gx = np.empty((nx + 1, ny))
        gy = np.empty((nx, ny + 1))
        face_gradients(p, dx, dy, gx, gy)
        pad(gx, no, yes, no, xfa[:, :, 1])
        pad(gy, yes, no, no, yfa[:, :, 1])
    if dbar.shape[0] > 0:
        pad(inv_dbar, yes, yes, no, dbar)


@njit(cache=True, inline="always", error_model="numpy")
def gas_force_one(law, q, position, velocity, radius, volume, cen, xfa, yfa, dbar, mixture, xc, yc, xf, yf, inv_dx,
                  inv_dy, mu, min_voidage, pressure_force, dim2, three):
    """(in range, fx, fy, fz): the gas force on particle q [N] of ``gas_forces``: β V_q/(1 − ε) (u − v_q) (Sun
    2007 eq. 29), minus V_q ∇p if ``pressure_force`` (eq. 28), with u, ε (clipped to [min_voidage, 1]), ρ, ∇p
    and 1/D̄ (``mixture``) area-weighted from the four nodes around the centre (Hoomans 1996 eqs 40-41) of the
    fields of ``gas_force_fields``; z 0 if ``dim2``, the z velocity read if ``three``. (False, NaN, NaN, NaN)
    where the drag arguments are out of range."""
    x = position[q, 0]
    y = position[q, 1]
    ic, txc = locate(x, xc, inv_dx, 0.5)
    jc, tyc = locate(y, yc, inv_dy, 0.5)
    i_f, txf = locate(x, xf, inv_dx, 0.0)
    j_f, tyf = locate(y, yf, inv_dy, 0.0)
    eps, rg = _mean2(cen, ic, jc, _weights(txc, tyc))
    ug, dpdx = _mean2(xfa, i_f, jc, _weights(txf, tyc))
    vg, dpdy = _mean2(yfa, ic, j_f, _weights(txc, tyf))
    if eps < min_voidage:
        eps = min_voidage
    elif eps > 1.0:
        eps = 1.0
    wx = ug - velocity[q, 0]
    wy = vg - velocity[q, 1]
    wz = 0.0
    if three:
        wz = 0.0 - velocity[q, 2]
    slip = math.sqrt(wx * wx + wy * wy + wz * wz)
    d = 2.0 * radius[q]
    if not _drag_arguments_valid(eps, slip, d, rg, mu):
        return False, math.nan, math.nan, math.nan
    yq = 1.0
    if mixture:
        w = _weights(txc, tyc)
        yq = d * (w[0] * dbar[ic, jc] + w[1] * dbar[ic + 1, jc] + w[2] * dbar[ic + 1, jc + 1]
                  + w[3] * dbar[ic, jc + 1])
    c = beta_per_solids(law, eps, slip, d, rg, mu, yq) * volume[q]  # β V_p/(1 − ε), eq. 29
    fx = c * wx
    fy = c * wy
    fz = c * wz
    if pressure_force:  # −V_p ∇p, eq. 28
        fx -= volume[q] * dpdx
        fy -= volume[q] * dpdy
    if dim2:
        fz = 0.0
    return True, fx, fy, fz
