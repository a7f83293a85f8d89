"""Staggered (MAC) grid of the gas phase and its cell flags (Hoomans 1996 §3.3, §3.5, Table 1).

A ``StaggeredGrid`` is a uniform Cartesian grid of ``nx × ny`` cells of a given depth (2D)
or of ``nx × ny × nz`` cells (3D). Scalars (pressure, density, voidage) live at cell
centres, the x velocity on x-faces, the y velocity on y-faces and (3D) the z velocity on
z-faces. ``cell_flags`` turns the boundary-condition objects of the four (2D) or six (3D)
sides into Hoomans' flag matrix once, at set-up; the compiled kernels read only flags (and
integer face kinds derived from them). 2D is the special case it always was: two
``cells`` entries, a ``depth``, no ``nz``, the sides left, right, bottom, top.

Index layout (user-facing arrays, 0-based; ``nx = 3, ny = 2`` drawn)::

      y
      ^        v[0,2]          v[1,2]          v[2,2]
      |  +-------o-------+-------o-------+-------o-------+   y-faces j = ny (top boundary)
      |  |               |               |               |
      |  x     p[0,1]    x     p[1,1]    x     p[2,1]    x   x-faces of row 1: u[0..3, 1]
      |  |               |               |               |
      |  +-------o-------+-------o-------+-------o-------+   y-faces j = 1: v[0..2, 1]
      |  |               |               |               |
      |  x     p[0,0]    x     p[1,0]    x     p[2,0]    x   x-faces of row 0: u[0..3, 0]
      |  |               |               |               |
      |  +-------o-------+-------o-------+-------o-------+   y-faces j = 0 (bottom boundary)
      |        v[0,0]          v[1,0]          v[2,0]
      +--x---------------x---------------x---------------x--> x
       u[0,j]          u[1,j]          u[2,j]          u[3,j]  (u[0,j], u[nx,j]: left and right boundary)

    x: u on x-faces (the left face of cell i is u[i, j]);  o: v on y-faces (the bottom face
    of cell j is v[i, j]);  p, rho, voidage at the centres.

    p, rho, voidage : (nx, ny)      cell (i, j) has centre ((i + 1/2) dx, (j + 1/2) dy)
    u               : (nx + 1, ny)  x-face (i, j) at (i dx, (j + 1/2) dy), between cells i-1 and i
    v               : (nx, ny + 1)  y-face (i, j) at ((i + 1/2) dx, j dy), between cells j-1 and j

The flag matrix has one ring of boundary cells around the interior, as in Hoomans'
Fig. 6: ``flags[i + 1, j + 1]`` is cell (i, j); ``flags[0, 1:-1]`` the left boundary
cells, ``flags[-1, 1:-1]`` the right, ``flags[1:-1, 0]`` the bottom, ``flags[1:-1, -1]``
the top, and the four corners carry ``CORNER``::

        7 5 5 5 7          a 3 x 2 box: pressure outlet on top,
        3 1 1 1 3          no-slip side walls,
        3 1 1 1 3          inflow at the bottom
        7 4 4 4 7

(printed with y upwards: ``flags.T[::-1]``). The solver pads its internal arrays the
same way: centre arrays by one ring, velocity arrays by two (for the TVD stencil);
``CENTRE_GHOSTS`` and ``FACE_GHOSTS`` say how many.

3D adds the z axis, in the same pattern::

    p, rho, voidage : (nx, ny, nz)      cell (i, j, k) centred at ((i + 1/2) dx, (j + 1/2) dy, (k + 1/2) dz)
    u               : (nx + 1, ny, nz)  x-face (i, j, k) at (i dx, (j + 1/2) dy, (k + 1/2) dz)
    v               : (nx, ny + 1, nz)  y-face (i, j, k) at ((i + 1/2) dx, j dy, (k + 1/2) dz)
    w               : (nx, ny, nz + 1)  z-face (i, j, k) at ((i + 1/2) dx, (j + 1/2) dy, k dz)

and two sides, ``front`` (z = 0) and ``back`` (z = Lz): left/right are the x sides,
bottom/top the y sides, front/back the z sides, whichever way gravity points. The flag
matrix is ``(nx + 2, ny + 2, nz + 2)``: ``flags[0, 1:-1, 1:-1]`` the left boundary cells,
``flags[:, :, 0]``'s interior the front ones, and so on; the cells on the twelve edges and
eight corners of the ring carry ``CORNER``. A side's boundary faces form a 2D array indexed
by the side's two in-plane axes, in the order x, y, z with the normal left out: (y, z) on
left/right, (x, z) on bottom/top, (x, y) on front/back.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Mapping

import numpy as np

from ..errors import CaseError

# Cell flags, Hoomans 1996 Table 1 (1-7) plus periodic sides (8, our extension).
INTERIOR = 1  # interior cell, no boundary conditions
FREE_SLIP = 2  # impermeable wall, free-slip boundaries
NO_SLIP = 3  # impermeable wall, no-slip boundaries
INFLOW = 4  # influx cell, velocities specified
PRESSURE = 5  # prescribed-pressure cell, free-slip boundaries
OUTFLOW = 6  # continuous-outflow cell, free-slip boundaries
CORNER = 7  # corner cell, no boundary conditions
PERIODIC = 8  # periodic side: the boundary cell is the interior cell on the opposite side

FLAG_NAMES = {
    INTERIOR: "interior",
    FREE_SLIP: "free-slip wall",
    NO_SLIP: "no-slip wall",
    INFLOW: "inflow",
    PRESSURE: "prescribed pressure",
    OUTFLOW: "continuous outflow",
    CORNER: "corner",
    PERIODIC: "periodic",
}

SIDES = ("left", "right", "bottom", "top")  # the sides of a 2D grid
SIDES_3D = SIDES + ("front", "back")  # the sides of a 3D grid: front at z = 0, back at z = Lz
SIDE_AXIS = {"left": 0, "right": 0, "bottom": 1, "top": 1, "front": 2, "back": 2}  # axis normal to each side
OPPOSITE_PAIRS = (("left", "right"), ("bottom", "top"), ("front", "back"))
CENTRE_GHOSTS = 1  # ring of boundary cells around centre arrays (the flag matrix)
FACE_GHOSTS = 2  # layers of ghost faces around velocity arrays (TVD needs two)


@dataclass(frozen=True)
class StaggeredGrid:
    """Uniform staggered grid of ``cells = (nx, ny)`` cells over ``size = (Lx, Ly)`` [m] (2D) or of
    ``cells = (nx, ny, nz)`` cells over ``size = (Lx, Ly, Lz)`` [m] (3D).

    Parameters
    ----------
    cells : (int, int) or (int, int, int)
        Number of cells along x, y (and z) (Hoomans' NX, NY). Three entries make a 3D grid.
    size : (float, float) or (float, float, float)
        Domain extent along each axis [m]; the lower-left(-front) corner is the origin.
    depth : float, optional
        2D: extent along z [m] of the grid (default 1): cell volumes are ``dx dy depth`` and face
        areas ``dy depth`` (x-faces) and ``dx depth`` (y-faces). Mass rates scale with it;
        velocities and pressures do not. For a one-layer particle bed the depth is usually the
        particle diameter or the bed's real depth. 3D: Lz; giving another value is an error.
    """

    cells: tuple[int, ...]
    size: tuple[float, ...]
    depth: float | None = None

    def __post_init__(self):
        try:
            cells = tuple(int(c) for c in self.cells)
            size = tuple(float(s) for s in self.size)
        except (TypeError, ValueError):
            raise CaseError(f"gas.grid: cells = {self.cells!r} and size = {self.size!r} must be pairs (2D) or "
                            "triples (3D) of numbers") from None
        if len(cells) not in (2, 3) or any(c != c0 for c, c0 in zip(cells, self.cells)) or min(cells) < 1:
            raise CaseError(f"gas.grid.cells = {self.cells!r}: must be two (nx, ny) or three (nx, ny, nz) "
                            "integers >= 1")
        if len(size) != len(cells):
            raise CaseError(f"gas.grid.cells = {self.cells!r} and gas.grid.size = {self.size!r}: give one size per cells "
                            "entry, (Lx, Ly) [m] for a 2D grid (two cells entries), (Lx, Ly, Lz) for a 3D one (three)")
        if not all(np.isfinite(size)) or min(size) <= 0.0:
            axes = "(Lx, Ly)" if len(cells) == 2 else "(Lx, Ly, Lz)"
            raise CaseError(f"gas.grid.size = {self.size!r}: must be {len(cells)} lengths > 0 [m] {axes}, one per "
                            "cells entry")
        if len(cells) == 2:
            depth = 1.0 if self.depth is None else self.depth
            if not (isinstance(depth, (int, float, np.floating, np.integer)) and np.isfinite(depth) and depth > 0.0):
                raise CaseError(f"gas.grid.depth = {self.depth!r}: must be > 0 [m]")
        else:
            depth = size[2]
            if self.depth is not None and not (isinstance(self.depth, (int, float, np.floating, np.integer))
                                               and abs(float(self.depth) - depth) <= 1e-12 * depth):
                raise CaseError(f"gas.grid.depth = {self.depth!r}: a 3D grid has no depth of its own (its extent "
                                f"along z is size[2] = {depth!r} m); leave depth out")
        object.__setattr__(self, "cells", cells)
        object.__setattr__(self, "size", size)
        object.__setattr__(self, "depth", float(depth))

    # ------------------------------------------------------------ sizes
    # cached: the grid is frozen, and a coupled run reads these many times a gas step
    @cached_property
    def dimensions(self) -> int:
        """2 or 3: the number of ``cells`` entries."""
        return len(self.cells)

    @cached_property
    def sides(self) -> tuple[str, ...]:
        """The sides that take a boundary condition: ``SIDES`` in 2D, ``SIDES_3D`` in 3D."""
        return SIDES if self.dimensions == 2 else SIDES_3D

    @cached_property
    def nx(self) -> int:
        return self.cells[0]

    @cached_property
    def ny(self) -> int:
        return self.cells[1]

    @cached_property
    def nz(self) -> int | None:
        """Cells along z (3D); None for a 2D grid."""
        return self.cells[2] if self.dimensions == 3 else None

    @cached_property
    def dx(self) -> float:
        """Cell width [m] (Hoomans' DX)."""
        return self.size[0] / self.nx

    @cached_property
    def dy(self) -> float:
        """Cell height [m] (Hoomans' DY)."""
        return self.size[1] / self.ny

    @cached_property
    def dz(self) -> float:
        """Cell extent along z [m]: Lz / nz (3D), the depth (2D: one layer of cells)."""
        return self.size[2] / self.cells[2] if self.dimensions == 3 else self.depth

    @cached_property
    def spacing(self) -> tuple[float, ...]:
        """(dx, dy) or (dx, dy, dz) [m]."""
        return (self.dx, self.dy) if self.dimensions == 2 else (self.dx, self.dy, self.dz)

    @cached_property
    def cell_volume(self) -> float:
        """dx dy depth (2D) or dx dy dz (3D) [m^3]."""
        return self.dx * self.dy * self.depth if self.dimensions == 2 else self.dx * self.dy * self.dz

    @cached_property
    def area_x(self) -> float:
        """Area of an x-face, dy depth (2D) or dy dz (3D) [m^2]."""
        return self.dy * self.depth if self.dimensions == 2 else self.dy * self.dz

    @cached_property
    def area_y(self) -> float:
        """Area of a y-face, dx depth (2D) or dx dz (3D) [m^2]."""
        return self.dx * self.depth if self.dimensions == 2 else self.dx * self.dz

    @cached_property
    def area_z(self) -> float:
        """Area of a z-face, dx dy [m^2]."""
        return self.dx * self.dy

    @cached_property
    def shape(self) -> tuple[int, ...]:
        """Shape of centre arrays (p, rho, voidage): (nx, ny) or (nx, ny, nz)."""
        return tuple(self.cells)

    def face_shape(self, axis: int) -> tuple[int, ...]:
        """Shape of the arrays on the faces normal to ``axis`` (0: u, 1: v, 2: w): one more along it."""
        return tuple(n + (a == axis) for a, n in enumerate(self.cells))

    @cached_property
    def u_shape(self) -> tuple[int, ...]:
        """Shape of x-face arrays (u): (nx + 1, ny) or (nx + 1, ny, nz)."""
        return self.face_shape(0)

    @cached_property
    def v_shape(self) -> tuple[int, ...]:
        """Shape of y-face arrays (v): (nx, ny + 1) or (nx, ny + 1, nz)."""
        return self.face_shape(1)

    @cached_property
    def w_shape(self) -> tuple[int, int, int] | None:
        """Shape of z-face arrays (w) of a 3D grid: (nx, ny, nz + 1); None in 2D."""
        return self.face_shape(2) if self.dimensions == 3 else None

    # ------------------------------------------------------------ coordinates
    @property
    def x_centres(self) -> np.ndarray:
        """(nx,) x of cell centres [m]."""
        return (np.arange(self.nx) + 0.5) * self.dx

    @property
    def y_centres(self) -> np.ndarray:
        """(ny,) y of cell centres [m]."""
        return (np.arange(self.ny) + 0.5) * self.dy

    @property
    def z_centres(self) -> np.ndarray:
        """(nz,) z of cell centres [m] (3D; 2D: the one layer's mid-depth)."""
        return (np.arange(self.cells[2] if self.dimensions == 3 else 1) + 0.5) * self.dz

    @property
    def x_faces(self) -> np.ndarray:
        """(nx + 1,) x of x-faces [m]."""
        return np.arange(self.nx + 1) * self.dx

    @property
    def y_faces(self) -> np.ndarray:
        """(ny + 1,) y of y-faces [m]."""
        return np.arange(self.ny + 1) * self.dy

    @property
    def z_faces(self) -> np.ndarray:
        """(nz + 1,) z of z-faces [m] (3D; 2D: 0 and the depth)."""
        return np.arange((self.cells[2] if self.dimensions == 3 else 1) + 1) * self.dz

    def centres(self) -> tuple[np.ndarray, ...]:
        """(X, Y), each (nx, ny), or (X, Y, Z), each (nx, ny, nz): coordinates of the cell centres [m]."""
        if self.dimensions == 2:
            return np.meshgrid(self.x_centres, self.y_centres, indexing="ij")
        return np.meshgrid(self.x_centres, self.y_centres, self.z_centres, indexing="ij")

    def side_axes(self, side: str) -> tuple[int, ...]:
        """The in-plane axes of ``side``, in the order of its face arrays: 2D one axis (y on left/right,
        x on bottom/top); 3D two ((y, z) on left/right, (x, z) on bottom/top, (x, y) on front/back)."""
        normal = SIDE_AXIS[side]
        return tuple(a for a in range(self.dimensions) if a != normal)

    def side_length(self, side: str) -> float:
        """Length of a side [m]: Ly for left/right, Lx for bottom/top (2D; in 3D its first in-plane extent)."""
        return self.size[self.side_axes(side)[0]]

    def side_faces(self, side: str):
        """Positions [m] along ``side`` of the edges of its boundary faces: 2D an (n + 1,) array; 3D a pair of
        such arrays, one per in-plane axis (``side_axes``)."""
        edges = (self.x_faces, self.y_faces, self.z_faces)
        if self.dimensions == 2:
            return self.y_faces if side in ("left", "right") else self.x_faces
        a, b = self.side_axes(side)
        return edges[a], edges[b]

    # ------------------------------------------------------------ flags
    def cell_flags(self, boundaries: Mapping[str, object]) -> np.ndarray:
        """Hoomans' flag matrix ``fl(i, j)`` (Table 1) for boundary conditions on the sides.

        Parameters
        ----------
        boundaries : dict
            ``{"left": BC, "right": BC, "bottom": BC, "top": BC}`` (3D: also ``"front"``, ``"back"``) with
            objects from ``fluidem.gas.boundaries`` (each has an integer ``flag``).

        Returns
        -------
        (nx + 2, ny + 2) or (nx + 2, ny + 2, nz + 2) int8
            ``INTERIOR`` inside, the side's flag in its ring of boundary cells,
            ``CORNER`` in the corners (3D: on the edges and corners of the ring). See the module
            docstring for the layout.
        """
        check_sides(boundaries, self.sides)
        if self.dimensions == 2:
            fl = np.full((self.nx + 2, self.ny + 2), INTERIOR, np.int8)
            fl[0, 1:-1] = boundaries["left"].flag
            fl[-1, 1:-1] = boundaries["right"].flag
            fl[1:-1, 0] = boundaries["bottom"].flag
            fl[1:-1, -1] = boundaries["top"].flag
            fl[0, 0] = fl[0, -1] = fl[-1, 0] = fl[-1, -1] = CORNER
            return fl
        fl = np.full(tuple(n + 2 for n in self.cells), CORNER, np.int8)
        fl[1:-1, 1:-1, 1:-1] = INTERIOR
        inner = slice(1, -1)
        for side in SIDES_3D:
            axis = SIDE_AXIS[side]
            index = [inner, inner, inner]
            index[axis] = 0 if side in ("left", "bottom", "front") else -1
            fl[tuple(index)] = boundaries[side].flag
        return fl


def check_sides(boundaries: Mapping[str, object], sides: tuple[str, ...] = SIDES) -> None:
    """Raise ``CaseError`` unless ``boundaries`` names exactly the ``sides`` (the four of a 2D grid, or the
    six of a 3D one) with valid objects, and periodic sides come in opposite pairs."""
    from .boundaries import BoundaryCondition, boundary_conditions

    if not isinstance(boundaries, Mapping):
        raise CaseError(f"gas.boundaries = {boundaries!r}: must be a dict of sides {list(sides)}")
    unknown = [k for k in boundaries if k not in sides]
    if unknown:
        raise CaseError(f"gas.boundaries: unknown side(s) {unknown}; allowed are {list(sides)}")
    missing = [k for k in sides if k not in boundaries]
    if missing:
        raise CaseError(f"gas.boundaries: side(s) {missing} missing; give a condition for each of {list(sides)}")
    for side in sides:
        bc = boundaries[side]
        if not isinstance(bc, BoundaryCondition):
            kinds = ", ".join(f"{boundary_conditions.get(n).__name__}(...)" for n in boundary_conditions.names())
            raise CaseError(f"gas.boundaries.{side} = {bc!r}: must be one of {kinds}")
    for a, b in OPPOSITE_PAIRS[:len(sides) // 2]:
        pa, pb = boundaries[a].flag == PERIODIC, boundaries[b].flag == PERIODIC
        if pa != pb:
            raise CaseError(f"gas.boundaries: {a} is {type(boundaries[a]).__name__}() and {b} is "
                            f"{type(boundaries[b]).__name__}(); periodic sides come in pairs ({a} and {b} both Periodic())")
