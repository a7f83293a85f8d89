"""Compiled kernels of the particle → grid mapping (``voidage.py``): deposits, exact disc–cell areas, diffusion.

``map_solids`` is the whole mapping in one call (deposit, smoothing, eq. 49, clipping, averages).
Method codes are the indices in ``voidage.METHODS`` (0 centroid, 1 area, 2 area_volume) and
weighting codes those in ``voidage.WEIGHTINGS`` (0 number, 1 volume).
"""
import math

import numpy as np
from numba import njit


@njit(cache=True, inline="always")
def cell_index(x, inv_d, n):
    """Index of the cell holding coordinate x on a uniform axis of n cells; clamped to [0, n-1]."""
    i = int(math.floor(x * inv_d))
    if i < 0:
        return 0
    if i > n - 1:
        return n - 1
    return i


@njit(cache=True)
def centroid_deposit(px, py, weight, vx, vy, inv_dx, inv_dy, out, out_vx, out_vy):
    """Add weight[p] (and weight[p] v[p]) to the cell holding the centre of particle p (Sun 2007 eq. 34).

    px, py, weight, vx, vy : (N,) float64; out, out_vx, out_vy : (nx, ny) float64, accumulated into.
    """
    nx, ny = out.shape
    for p in range(px.size):
        i = cell_index(px[p], inv_dx, nx)
        j = cell_index(py[p], inv_dy, ny)
        w = weight[p]
        out[i, j] += w
        out_vx[i, j] += w * vx[p]
        out_vy[i, j] += w * vy[p]


@njit(cache=True, inline="always")
def _circle_primitive(x, r):
    """∫_0^x sqrt(r² − s²) ds for |x| ≤ r."""
    if x >= r:
        return 0.25 * math.pi * r * r
    if x <= -r:
        return -0.25 * math.pi * r * r
    return 0.5 * (x * math.sqrt(r * r - x * x) + r * r * math.asin(x / r))


@njit(cache=True)
def disc_rect_area(cx, cy, r, x0, x1, y0, y1):
    """Exact area [m²] of the disc of radius r centred at (cx, cy) inside the rectangle [x0,x1]×[y0,y1].

    Integrates min(y1, h) − max(y0, −h), h = sqrt(r² − x²), between the points where the
    disc's edge crosses y0 or y1; on each piece both bounds are a constant or ±h.
    """
    return disc_rect_area_into(cx, cy, r, x0, x1, y0, y1, np.empty(6))


@njit(cache=True, inline="always")
def _insert(pts, n, x):
    """Insert x into the ascending pts[:n]; returns n + 1."""
    k = n
    while k > 0 and pts[k - 1] > x:
        pts[k] = pts[k - 1]
        k -= 1
    pts[k] = x
    return n + 1


@njit(cache=True)
def disc_rect_area_into(cx, cy, r, x0, x1, y0, y1, pts):
    """``disc_rect_area`` with a scratch array ``pts`` (≥ 6 float64) for the sorted break points."""
    a = max(x0 - cx, -r)
    b = min(x1 - cx, r)
    if a >= b:
        return 0.0
    lo = y0 - cy
    hi = y1 - cy
    if lo >= r or hi <= -r:
        return 0.0
    pts[0] = a
    pts[1] = b
    n = 2
    for yc in (lo, hi):
        if -r < yc < r:
            xc = math.sqrt(r * r - yc * yc)
            if a < xc < b:
                n = _insert(pts, n, xc)
            if a < -xc < b:
                n = _insert(pts, n, -xc)
    area = 0.0
    for k in range(n - 1):
        s0 = pts[k]
        s1 = pts[k + 1]
        if s1 <= s0:
            continue
        m = 0.5 * (s0 + s1)
        h = math.sqrt(max(r * r - m * m, 0.0))
        hint = _circle_primitive(s1, r) - _circle_primitive(s0, r)  # ∫ h dx over the piece
        upper_is_h = h < hi
        lower_is_h = -h > lo
        up = h if upper_is_h else hi
        down = -h if lower_is_h else lo
        if up <= down:
            continue
        piece = hint if upper_is_h else hi * (s1 - s0)
        piece -= -hint if lower_is_h else lo * (s1 - s0)
        area += piece
    return area


@njit(cache=True, inline="always")
def _segment(h, r):
    """Area of the disc of radius r beyond the line at signed distance h from its centre (h ≥ r: 0; h ≤ −r:
    the whole disc): r² acos(h/r) − h sqrt(r² − h²)."""
    c = min(max(h / r, -1.0), 1.0)
    return r * r * math.acos(c) - h * math.sqrt(max(r * r - h * h, 0.0))


@njit(cache=True, inline="always")
def _add(out, out_vx, out_vy, i, j, w, vx, vy):
    out[i, j] += w
    out_vx[i, j] += w * vx
    out_vy[i, j] += w * vy


@njit(cache=True)
def area_deposit(px, py, radius, scale, vx, vy, dx, dy, out, out_vx, out_vy):
    """Add scale[p] A_pij (and scale[p] A_pij v[p]) to every cell (i, j) whose rectangle the disc of p overlaps.

    A_pij is the exact area of the disc (radius[p], centre (px, py)) in cell (i, j)
    (Hoomans 1996 §3.4, multiple-cell overlap). Parts of a disc outside the grid are dropped.
    """
    pts = np.empty(6)
    for p in range(px.size):
        area_deposit_one(px[p], py[p], radius[p], scale[p], vx[p], vy[p], dx, dy, out, out_vx, out_vy, pts)


@njit(cache=True, inline="always")
def area_deposit_one(x, y, r, s, vx, vy, dx, dy, out, out_vx, out_vy, pts):
    """One particle of ``area_deposit``: s A_ij (and s A_ij v) into every cell (i, j) the disc of radius r centred
    at (x, y) overlaps, through ``_add`` (a device version adds atomically); pts: scratch of ≥ 6 float64."""
    nx, ny = out.shape
    a0 = int(math.floor((x - r) / dx))
    a1 = int(math.floor((x + r) / dx))
    b0 = int(math.floor((y - r) / dy))
    b1 = int(math.floor((y + r) / dy))
    full = math.pi * r * r
    if a0 == a1 and b0 == b1 and 0 <= a0 < nx and 0 <= b0 < ny:
        # the disc lies inside one cell (about half the particles of Hoomans' beds): its whole area
        _add(out, out_vx, out_vy, a0, b0, s * full, vx, vy)
        return
    if b0 == b1 and a1 == a0 + 1 and 0 <= b0 < ny:
        # cut by one vertical cell face only: a circular segment on either side (another third)
        low = full - _segment(a1 * dx - x, r)  # the part left of the face, in cell a0
        if 0 <= a0 < nx:
            _add(out, out_vx, out_vy, a0, b0, s * low, vx, vy)
        if 0 <= a1 < nx:
            _add(out, out_vx, out_vy, a1, b0, s * (full - low), vx, vy)
        return
    if a0 == a1 and b1 == b0 + 1 and 0 <= a0 < nx:
        low = full - _segment(b1 * dy - y, r)  # cut by one horizontal face: the part below it
        if 0 <= b0 < ny:
            _add(out, out_vx, out_vy, a0, b0, s * low, vx, vy)
        if 0 <= b1 < ny:
            _add(out, out_vx, out_vy, a0, b1, s * (full - low), vx, vy)
        return
    i0 = max(a0, 0)
    i1 = min(a1, nx - 1)
    j0 = max(b0, 0)
    j1 = min(b1, ny - 1)
    for i in range(i0, i1 + 1):
        for j in range(j0, j1 + 1):
            a = disc_rect_area_into(x, y, r, i * dx, (i + 1) * dx, j * dy, (j + 1) * dy, pts)
            if a > 0.0:
                _add(out, out_vx, out_vy, i, j, s * a, vx, vy)


@njit(cache=True)
def diffuse(field, rx, ry, steps, work):
    """``steps`` explicit diffusion steps f += rx δ²_x f + ry δ²_y f with zero flux through the grid's sides.

    Conserves Σ f exactly up to round-off; stable for rx + ry ≤ 1/2. field, work : (nx, ny).
    """
    nx, ny = field.shape
    for _ in range(steps):
        for i in range(nx):
            for j in range(ny):
                f = field[i, j]
                lap_x = 0.0
                if i > 0:
                    lap_x += field[i - 1, j] - f
                if i < nx - 1:
                    lap_x += field[i + 1, j] - f
                lap_y = 0.0
                if j > 0:
                    lap_y += field[i, j - 1] - f
                if j < ny - 1:
                    lap_y += field[i, j + 1] - f
                work[i, j] = f + rx * lap_x + ry * lap_y
        for i in range(nx):
            for j in range(ny):
                field[i, j] = work[i, j]


@njit(cache=True)
def deposit_solids(method, weighting, position, radius, volume, velocity, dx, dy, norm, frac, wsum, wvx, wvy):
    """Solids fraction ``frac`` (unsmoothed) and the velocity weights ``wsum``, ``wvx``, ``wvy`` of each cell.

    method 0 (centroid): V_p into the cell of the centre (Sun 2007 eq. 34); 1 (area): the exact
    disc area A_pij into every cell it overlaps; 2 (area_volume): V_p A_pij/(π r²). ``frac`` is
    the deposit over ``norm`` (V_cell, or dx dy for area). weighting 0 (number): wsum counts
    centres, wvx, wvy sum their velocities (Hoomans 1996 eq. 50); 1 (volume): wsum is the
    deposit and wvx, wvy the deposit-weighted velocities (Sun 2007 eq. 35).
    position, velocity : (N, ≥2); radius, volume : (N,); the rest (nx, ny), overwritten.
    """
    nx, ny = frac.shape
    frac[:, :] = 0.0
    wvx[:, :] = 0.0
    wvy[:, :] = 0.0
    n = position.shape[0]
    px = position[:, 0]
    py = position[:, 1]
    vx = velocity[:, 0]
    vy = velocity[:, 1]
    if method == 0 and weighting == 0:  # both deposits in one pass
        wsum[:, :] = 0.0
        for p in range(n):
            i = cell_index(px[p], 1.0 / dx, nx)
            j = cell_index(py[p], 1.0 / dy, ny)
            frac[i, j] += volume[p]  # Sun 2007 eq. 34
            wsum[i, j] += 1.0  # Hoomans 1996 eq. 50
            wvx[i, j] += vx[p]
            wvy[i, j] += vy[p]
        for i in range(nx):
            for j in range(ny):
                frac[i, j] /= norm
        return
    if method == 0:
        centroid_deposit(px, py, volume, vx, vy, 1.0 / dx, 1.0 / dy, frac, wvx, wvy)  # Sun 2007 eq. 34
    else:
        scale = np.empty(n)
        for p in range(n):
            r = radius[p]
            scale[p] = 1.0 if method == 1 else volume[p] / (math.pi * r * r)
        area_deposit(px, py, radius, scale, vx, vy, dx, dy, frac, wvx, wvy)  # Hoomans 1996 §3.4
    for i in range(nx):
        for j in range(ny):
            wsum[i, j] = frac[i, j]
            frac[i, j] /= norm
    if weighting == 0:  # Hoomans 1996 eq. 50: by centres, each particle counts once
        wsum[:, :] = 0.0
        wvx[:, :] = 0.0
        wvy[:, :] = 0.0
        centroid_deposit(px, py, np.ones(n), vx, vy, 1.0 / dx, 1.0 / dy, wsum, wvx, wvy)


@njit(cache=True)
def map_solids(method, weighting, position, radius, volume, velocity, dx, dy, norm, rx, ry, steps, to_3d,
               eq49_factor, min_voidage, voidage, solids_u, solids_v):
    """The particle → grid map of ``VoidageMapping.map``; returns the number of clipped cells.

    ``deposit_solids``; then ``steps`` diffusion steps of the fraction (``diffuse(rx, ry)``; 0: none);
    ε = 1 − fraction, with ``to_3d`` ε = 1 − eq49_factor max(1 − ε, 0)^{3/2} (Hoomans 1996 eq. 49);
    ε < min_voidage raised to it and counted; solids velocity wv/wsum, 0 where wsum = 0.
    voidage, solids_u, solids_v : (nx, ny) outputs.
    """
    nx, ny = voidage.shape
    frac = np.empty((nx, ny))
    wsum = np.empty((nx, ny))
    wvx = np.empty((nx, ny))
    wvy = np.empty((nx, ny))
    deposit_solids(method, weighting, position, radius, volume, velocity, dx, dy, norm, frac, wsum, wvx, wvy)
    return finish_map(frac, wsum, wvx, wvy, rx, ry, steps, to_3d, eq49_factor, min_voidage, voidage, solids_u,
                      solids_v)


@njit(cache=True)
def finish_map(frac, wsum, wvx, wvy, rx, ry, steps, to_3d, eq49_factor, min_voidage, voidage, solids_u, solids_v):
    """The cell part of ``map_solids`` after the deposit (``deposit_solids``' outputs, or the device's): ``steps``
    diffusion steps of ``frac`` (changed in place), ε = 1 − frac (Hoomans 1996 eq. 49 with ``to_3d``), clipped
    to ``min_voidage`` and counted, solids velocity wv/wsum (0 where wsum = 0); returns the clipped count."""
    nx, ny = voidage.shape
    if steps > 0:
        diffuse(frac, rx, ry, steps, np.empty((nx, ny)))
    clipped = 0
    for i in range(nx):
        for j in range(ny):
            e = 1.0 - frac[i, j]
            if to_3d:
                s = 1.0 - e
                if s < 0.0:
                    s = 0.0
                e = 1.0 - eq49_factor * s ** 1.5  # Hoomans 1996 eq. 49
            if e < min_voidage:
                e = min_voidage
                clipped += 1
            voidage[i, j] = e
            w = wsum[i, j]
            if w > 0.0:
                solids_u[i, j] = wvx[i, j] / w
                solids_v[i, j] = wvy[i, j] / w
            else:
                solids_u[i, j] = 0.0
                solids_v[i, j] = 0.0
    return clipped


@njit(cache=True)
def sauter_inverse(position, radius, volume, dx, dy, out):
    """out[i, j] = 1/D̄ [1/m] of the particles whose centre lies in cell (i, j): Σ V_p/d_p / Σ V_p, the
    inverse of the Sauter mean diameter D̄ = (Σ_i x_i/D_i)^−1 with x_i the volume fraction of size D_i
    among the cell's solids (DEM book 2012 two-phase chapter, eq. 10). A cell without particles takes
    the value of the whole bed.

    position : (N, ≥2) [m]; radius, volume : (N,) [m], [m³]; out : (nx, ny). Returns 1/D̄ of the bed.
    """
    nx, ny = out.shape
    vol = np.zeros((nx, ny))
    out[:, :] = 0.0
    inv_dx = 1.0 / dx
    inv_dy = 1.0 / dy
    total = 0.0
    total_v = 0.0
    for p in range(position.shape[0]):
        i = cell_index(position[p, 0], inv_dx, nx)
        j = cell_index(position[p, 1], inv_dy, ny)
        w = volume[p] / (2.0 * radius[p])
        out[i, j] += w
        vol[i, j] += volume[p]
        total += w
        total_v += volume[p]
    bed = total / total_v if total_v > 0.0 else 0.0
    for i in range(nx):
        for j in range(ny):
            out[i, j] = out[i, j] / vol[i, j] if vol[i, j] > 0.0 else bed
    return bed
