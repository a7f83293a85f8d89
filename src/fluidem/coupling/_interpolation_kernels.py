"""Compiled kernels of the grid → particle interpolation (``interpolation.py``), Hoomans 1996 eqs 40-41."""
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


@njit(cache=True)
def bilinear(values, xs, ys, inv_dx, inv_dy, shift_x, shift_y, px, py, out):
    """out[p] = area-weighted mean of the four nodes around (px[p], py[p]) (Hoomans 1996 eqs 40-41).

    values : (len(xs), len(ys)) node values; xs, ys node coordinates [m].
    """
    for p in range(px.size):
        i, tx = locate(px[p], xs, inv_dx, shift_x)
        j, ty = locate(py[p], ys, inv_dy, shift_y)
        out[p] = ((1.0 - tx) * (1.0 - ty) * values[i, j] + tx * (1.0 - ty) * values[i + 1, j]
                  + tx * ty * values[i + 1, j + 1] + (1.0 - tx) * ty * values[i, j + 1])  # eqs 40-41


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
