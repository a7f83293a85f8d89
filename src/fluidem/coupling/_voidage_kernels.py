"""Compiled kernels of the particle → grid mapping (``voidage.py``): deposits, exact disc–cell areas, diffusion."""
import math

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
    a = max(x0 - cx, -r)
    b = min(x1 - cx, r)
    if a >= b:
        return 0.0
    lo = y0 - cy
    hi = y1 - cy
    if lo >= r or hi <= -r:
        return 0.0
    pts = [a, b]
    for yc in (lo, hi):
        if -r < yc < r:
            xc = math.sqrt(r * r - yc * yc)
            if a < xc < b:
                pts.append(xc)
            if a < -xc < b:
                pts.append(-xc)
    pts.sort()
    area = 0.0
    for k in range(len(pts) - 1):
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


@njit(cache=True)
def area_deposit(px, py, radius, scale, vx, vy, dx, dy, out, out_vx, out_vy):
    """Add scale[p] A_pij (and scale[p] A_pij v[p]) to every cell (i, j) whose rectangle the disc of p overlaps.

    A_pij is the exact area of the disc (radius[p], centre (px, py)) in cell (i, j)
    (Hoomans 1996 §3.4, multiple-cell overlap). Parts of a disc outside the grid are dropped.
    """
    nx, ny = out.shape
    for p in range(px.size):
        r = radius[p]
        i0 = max(int(math.floor((px[p] - r) / dx)), 0)
        i1 = min(int(math.floor((px[p] + r) / dx)), nx - 1)
        j0 = max(int(math.floor((py[p] - r) / dy)), 0)
        j1 = min(int(math.floor((py[p] + r) / dy)), ny - 1)
        for i in range(i0, i1 + 1):
            for j in range(j0, j1 + 1):
                a = disc_rect_area(px[p], py[p], r, i * dx, (i + 1) * dx, j * dy, (j + 1) * dy)
                if a > 0.0:
                    w = scale[p] * a
                    out[i, j] += w
                    out_vx[i, j] += w * vx[p]
                    out_vy[i, j] += w * vy[p]


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
