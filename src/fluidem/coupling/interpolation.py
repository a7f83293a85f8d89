"""Grid → particles: area-weighted (bilinear) interpolation of staggered gas fields (Hoomans 1996 eqs 40-41).

A field lives at centres ``(nx, ny)``, x-faces ``(nx + 1, ny)`` or y-faces ``(nx, ny + 1)``
(layout in ``gas/grid.py``). Its nodes are extended to the walls with one boundary value
per side, so every point of the domain lies in a cell of four nodes and eq. 40 applies
unchanged; the cells along a wall are half as wide. Boundary values per side:

``"linear"``  extrapolated from the two nearest nodes (reproduces linear fields up to the wall)
``"copy"``    the nearest node's value (zero gradient; Hoomans' rule for wall-cell voidage)
a number      that value on the wall (e.g. 0.0 for the tangential velocity at a no-slip wall)

Positions outside the domain are clamped to it.
"""
from __future__ import annotations

from typing import Mapping, Union

import numpy as np

from ..gas.grid import StaggeredGrid
from . import _interpolation_kernels as K

LOCATIONS = ("centre", "x_face", "y_face")
Boundary = Union[str, float, Mapping[str, Union[str, float]]]


def _axes(grid: StaggeredGrid, location: str):
    """(xs, ys, shift_x, shift_y, pad_x, pad_y): node coordinates of the extended field."""
    xc = np.concatenate(([0.0], grid.x_centres, [grid.size[0]]))
    yc = np.concatenate(([0.0], grid.y_centres, [grid.size[1]]))
    if location == "centre":
        return xc, yc, 0.5, 0.5, True, True
    if location == "x_face":
        return grid.x_faces, yc, 0.0, 0.5, False, True
    if location == "y_face":
        return xc, grid.y_faces, 0.5, 0.0, True, False
    raise ValueError(f"location = {location!r}: allowed are {', '.join(LOCATIONS)}")


def _side_rule(boundary: Boundary, side: str):
    rule = boundary.get(side, "linear") if isinstance(boundary, Mapping) else boundary
    if isinstance(rule, str) and rule not in ("linear", "copy"):
        raise ValueError(f"boundary {side} = {rule!r}: allowed are 'linear', 'copy' or a number")
    return rule


def _edge(first, second, rule):
    if isinstance(rule, str):
        if rule == "copy" or second is None:
            return first
        return 1.5 * first - 0.5 * second  # half a node spacing beyond `first`
    return np.full_like(first, float(rule))


def extend(grid: StaggeredGrid, field, location: str = "centre", boundary: Boundary = "linear") -> np.ndarray:
    """The field with boundary values appended on the sides where its nodes stop half a cell short."""
    f = np.asarray(field, float)
    shapes = {"centre": grid.shape, "x_face": grid.u_shape, "y_face": grid.v_shape}
    if location not in shapes:
        raise ValueError(f"location = {location!r}: allowed are {', '.join(LOCATIONS)}")
    if f.shape != shapes[location]:
        raise ValueError(f"{location} field must have shape {shapes[location]}; got {f.shape}")
    _, _, _, _, pad_x, pad_y = _axes(grid, location)
    if pad_x:
        nx = f.shape[0]
        left = _edge(f[0], f[1] if nx > 1 else None, _side_rule(boundary, "left"))
        right = _edge(f[-1], f[-2] if nx > 1 else None, _side_rule(boundary, "right"))
        f = np.concatenate((left[None, :], f, right[None, :]), axis=0)
    if pad_y:
        ny = f.shape[1]
        bottom = _edge(f[:, 0], f[:, 1] if ny > 1 else None, _side_rule(boundary, "bottom"))
        top = _edge(f[:, -1], f[:, -2] if ny > 1 else None, _side_rule(boundary, "top"))
        f = np.concatenate((bottom[:, None], f, top[:, None]), axis=1)
    return np.ascontiguousarray(f)


def _xy(position):
    pos = np.asarray(position, float)
    if pos.ndim != 2 or pos.shape[1] not in (2, 3):
        raise ValueError(f"position must be (N, 3) or (N, 2) [m]; got shape {pos.shape}")
    return np.ascontiguousarray(pos[:, 0]), np.ascontiguousarray(pos[:, 1])


def interpolate(grid: StaggeredGrid, field, position, location: str = "centre",
                boundary: Boundary = "linear", out=None) -> np.ndarray:
    """Field value at each particle centre, (N,) float64 (Hoomans 1996 eqs 40-41)."""
    xs, ys, sx, sy, _, _ = _axes(grid, location)
    values = extend(grid, field, location, boundary)
    px, py = _xy(position)
    if out is None:
        out = np.empty(px.size)
    K.bilinear(values, xs, ys, 1.0 / grid.dx, 1.0 / grid.dy, sx, sy, px, py, out)
    return out


def weights(grid: StaggeredGrid, position, location: str = "centre"):
    """(index (N, 2) int64, weight (N, 4)): lower-left node in the extended field and eq. 41's
    A/(DX DY) for nodes (i, j), (i+1, j), (i+1, j+1), (i, j+1)."""
    xs, ys, sx, sy, _, _ = _axes(grid, location)
    px, py = _xy(position)
    index = np.empty((px.size, 2), np.int64)
    w = np.empty((px.size, 4))
    K.bilinear_weights(xs, ys, 1.0 / grid.dx, 1.0 / grid.dy, sx, sy, px, py, index, w)
    return index, w


def pressure_gradient(grid: StaggeredGrid, p, boundary: str = "copy",
                      periodic=(False, False)) -> tuple[np.ndarray, np.ndarray]:
    """(∂p/∂x on x-faces (nx + 1, ny), ∂p/∂y on y-faces (nx, ny + 1)) [Pa/m].

    Interior faces: centred differences of neighbouring centres (exact for quadratic p at
    the face). Wall faces: the nearest interior face value (``"copy"``) or its linear
    extrapolation (``"linear"``); with a single cell across, zero. On a side of a periodic axis
    (``periodic`` = (x, y)) both boundary faces take the difference of the two cells it joins.
    """
    p = np.asarray(p, float)
    if p.shape != grid.shape:
        raise ValueError(f"p must have shape {grid.shape}; got {p.shape}")
    gx = np.zeros(grid.u_shape)
    gy = np.zeros(grid.v_shape)
    gx[1:-1] = np.diff(p, axis=0) / grid.dx
    gy[:, 1:-1] = np.diff(p, axis=1) / grid.dy
    for g, axis in ((gx, 0), (gy, 1)):
        n = g.shape[axis]
        if n < 3:
            continue
        a = np.moveaxis(g, axis, 0)
        if periodic[axis]:
            q = np.moveaxis(p, axis, 0)
            a[0] = a[-1] = (q[0] - q[-1]) / (grid.dx, grid.dy)[axis]
        elif boundary == "linear" and n >= 4:
            a[0] = 2.0 * a[1] - a[2]
            a[-1] = 2.0 * a[-2] - a[-3]
        elif boundary in ("copy", "linear"):
            a[0] = a[1]
            a[-1] = a[-2]
        else:
            raise ValueError(f"boundary = {boundary!r}: allowed are 'copy', 'linear'")
    return gx, gy


def sample_gas(grid: StaggeredGrid, state, position, boundary: Boundary = "linear",
               gradient_boundary: str = "copy") -> dict[str, np.ndarray]:
    """Gas velocity (u, v), voidage, pressure and pressure gradient at particle centres, each (N,).

    ``state`` is a ``GasState``; keys: u, v, voidage, p, dpdx, dpdy.
    """
    gx, gy = pressure_gradient(grid, state.p, gradient_boundary)
    return {
        "u": interpolate(grid, state.u, position, "x_face", boundary),
        "v": interpolate(grid, state.v, position, "y_face", boundary),
        "voidage": interpolate(grid, state.voidage, position, "centre", "copy"),
        "p": interpolate(grid, state.p, position, "centre", boundary),
        "dpdx": interpolate(grid, gx, position, "x_face", "copy"),
        "dpdy": interpolate(grid, gy, position, "y_face", "copy"),
    }


def sample_gas3d(grid: StaggeredGrid, state, position, periodic=(False, False, False),
                 fold: bool = True) -> dict[str, np.ndarray]:
    """Gas velocity (u, v, w) and voidage at particle centres on a 3D grid, each (N,): the trilinear weights of
    the 3D coupling (``_paired3d_kernels.sample3d``; Hoomans 1996 eqs 40-41 along each axis), u from the
    x-faces, v from the y-faces, w from the z-faces, ε from the centres; ``periodic`` (px, py, pz) the axes that
    wrap, ``fold`` as ``coupling.boundary_faces = "fold"``. A linear field is reproduced exactly between the
    outermost nodes. ``state`` is a 3D ``GasState``; position (N, 3) [m]."""
    from . import _paired3d_kernels as P3

    if grid.dimensions != 3:
        raise ValueError("sample_gas3d needs a 3D grid; on a 2D grid use sample_gas")
    pos = np.ascontiguousarray(position, dtype=float)
    if pos.ndim != 2 or pos.shape[1] != 3:
        raise ValueError(f"position must be (N, 3) [m]; got shape {pos.shape}")
    out = np.empty((pos.shape[0], 4))
    P3.sample3d(pos, state.u, state.v, state.w, state.voidage, grid.dx, grid.dy, grid.dz,
                *(bool(a) for a in periodic), bool(fold), out)
    return {"u": out[:, 0], "v": out[:, 1], "w": out[:, 2], "voidage": out[:, 3]}
