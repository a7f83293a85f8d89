"""Compiled kernels of the grid → particle interpolation (``interpolation.py``), Hoomans 1996 eqs 40-41.

``pad`` and ``face_gradients`` build the extended node fields of ``interpolation.extend`` and
``interpolation.pressure_gradient`` (same arithmetic, so the same bits) for the fused
particle-force kernel of ``_exchange_kernels.py``.
"""
import math

from numba import njit


@njit(cache=True, inline="always")
def locate(x, xs, inv_d, shift):
    """(k, t): node interval k of the node coordinates xs holding x, and x's fraction t in it, t in [0, 1].

    Nodes are uniform (spacing 1/inv_d) except possibly the half intervals at the two ends,
    so k = floor(x inv_d + shift) clamped to [0, len(xs) − 2]; x outside is clamped to the ends.
    """
    n = xs.size
    k = int(math.floor(x * inv_d + shift))
    if k < 0:
        k = 0
    if k > n - 2:
        k = n - 2
    t = (x - xs[k]) / (xs[k + 1] - xs[k])
    if t < 0.0:
        t = 0.0
    if t > 1.0:
        t = 1.0
    return k, t


@njit(cache=True, inline="always")
def node_mean(values, i, j, tx, ty):
    """Area-weighted mean of the nodes (i, j), (i+1, j), (i+1, j+1), (i, j+1) at fractions (tx, ty) (eqs 40-41)."""
    return ((1.0 - tx) * (1.0 - ty) * values[i, j] + tx * (1.0 - ty) * values[i + 1, j]
            + tx * ty * values[i + 1, j + 1] + (1.0 - tx) * ty * values[i, j + 1])


@njit(cache=True)
def bilinear(values, xs, ys, inv_dx, inv_dy, shift_x, shift_y, px, py, out):
    """out[p] = area-weighted mean of the four nodes around (px[p], py[p]) (Hoomans 1996 eqs 40-41).

    values : (len(xs), len(ys)) node values; xs, ys node coordinates [m].
    """
    for p in range(px.size):
        i, tx = locate(px[p], xs, inv_dx, shift_x)
        j, ty = locate(py[p], ys, inv_dy, shift_y)
        out[p] = node_mean(values, i, j, tx, ty)  # eqs 40-41


@njit(cache=True)
def bilinear_weights(xs, ys, inv_dx, inv_dy, shift_x, shift_y, px, py, index, weight):
    """Lower-left node (index[p, 0], index[p, 1]) and the four weights A/(DX DY) of eq. 41 in the
    order (i, j), (i+1, j), (i+1, j+1), (i, j+1)."""
    for p in range(px.size):
        i, tx = locate(px[p], xs, inv_dx, shift_x)
        j, ty = locate(py[p], ys, inv_dy, shift_y)
        index[p, 0] = i
        index[p, 1] = j
        weight[p, 0] = (1.0 - tx) * (1.0 - ty)
        weight[p, 1] = tx * (1.0 - ty)
        weight[p, 2] = tx * ty
        weight[p, 3] = (1.0 - tx) * ty


@njit(cache=True)
def pad(field, pad_x, pad_y, linear, out):
    """out = ``field`` with one boundary node appended on both ends of x (``pad_x``) and/or y (``pad_y``).

    The boundary value is the nearest node's (``linear`` False: rule "copy") or 1.5 f_0 − 0.5 f_1,
    the linear extrapolation half a node spacing beyond it (``linear`` True; "copy" when the
    axis has a single node). x is padded first and y pads the x-padded rows, as ``interpolation.extend``.
    field : (n0, n1); out : (n0 + 2 pad_x, n1 + 2 pad_y).
    """
    n0, n1 = field.shape
    ox = 1 if pad_x else 0
    oy = 1 if pad_y else 0
    for i in range(n0):
        for j in range(n1):
            out[i + ox, j + oy] = field[i, j]
    if pad_x:
        lin = linear and n0 > 1
        for j in range(n1):
            if lin:
                out[0, j + oy] = 1.5 * field[0, j] - 0.5 * field[1, j]
                out[n0 + 1, j + oy] = 1.5 * field[n0 - 1, j] - 0.5 * field[n0 - 2, j]
            else:
                out[0, j + oy] = field[0, j]
                out[n0 + 1, j + oy] = field[n0 - 1, j]
    if pad_y:
        lin = linear and n1 > 1
        for i in range(out.shape[0]):
            if lin:
                out[i, 0] = 1.5 * out[i, 1] - 0.5 * out[i, 2]
                out[i, n1 + 1] = 1.5 * out[i, n1] - 0.5 * out[i, n1 - 1]
            else:
                out[i, 0] = out[i, 1]
                out[i, n1 + 1] = out[i, n1]


@njit(cache=True)
def face_gradients(p, dx, dy, gx, gy):
    """∂p/∂x on x-faces gx (nx + 1, ny) and ∂p/∂y on y-faces gy (nx, ny + 1) [Pa/m].

    Centred differences of neighbouring centres inside; each wall face copies its nearest
    interior face (``interpolation.pressure_gradient(boundary="copy")``); zero with one cell across.
    """
    nx, ny = p.shape
    for j in range(ny):
        gx[0, j] = 0.0
        gx[nx, j] = 0.0
        for i in range(1, nx):
            gx[i, j] = (p[i, j] - p[i - 1, j]) / dx
        if nx >= 2:
            gx[0, j] = gx[1, j]
            gx[nx, j] = gx[nx - 1, j]
    for i in range(nx):
        gy[i, 0] = 0.0
        gy[i, ny] = 0.0
        for j in range(1, ny):
            gy[i, j] = (p[i, j] - p[i, j - 1]) / dy
        if ny >= 2:
            gy[i, 0] = gy[i, 1]
            gy[i, ny] = gy[i, ny - 1]
