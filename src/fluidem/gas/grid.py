"""Staggered (MAC) grid of the gas phase and its cell flags (Hoomans 1996 §3.3, §3.5, Table 1).

A ``StaggeredGrid`` is a uniform 2D Cartesian grid of ``nx × ny`` cells of a given
depth. Scalars (pressure, density, voidage) live at cell centres, the x velocity on
x-faces and the y velocity on y-faces. ``cell_flags`` turns the boundary-condition
objects of the four sides into Hoomans' flag matrix once, at set-up; the compiled
kernels read only flags (and integer face kinds derived from them).

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

SIDES = ("left", "right", "bottom", "top")
CENTRE_GHOSTS = 1  # ring of boundary cells around centre arrays (the flag matrix)
FACE_GHOSTS = 2  # layers of ghost faces around velocity arrays (TVD needs two)


@dataclass(frozen=True)
class StaggeredGrid:
    """Uniform 2D staggered grid of ``cells = (nx, ny)`` cells over ``size = (Lx, Ly)`` [m].

    Parameters
    ----------
    cells : (int, int)
        Number of cells along x and y (Hoomans' NX, NY).
    size : (float, float)
        Domain width and height [m]; the lower-left corner is the origin.
    depth : float
        Extent along z [m] of the 2D grid: cell volumes are ``dx dy depth`` and face
        areas ``dy depth`` (x-faces) and ``dx depth`` (y-faces). Mass rates scale with
        it; velocities and pressures do not. For a one-layer particle bed the depth is
        usually the particle diameter or the bed's real depth.

    Notes
    -----
    Written for 2D; a 3D grid will add ``nz``, ``w`` on z-faces and two more sides
    (``front``, ``back``) with the same flags and the same solver interface.
    """

    cells: tuple[int, int]
    size: tuple[float, float]
    depth: float = 1.0

    def __post_init__(self):
        try:
            cells = tuple(int(c) for c in self.cells)
            size = tuple(float(s) for s in self.size)
        except (TypeError, ValueError):
            raise CaseError(f"gas.grid: cells = {self.cells!r} and size = {self.size!r} must be pairs of numbers") from None
        if len(cells) != 2 or any(c != c0 for c, c0 in zip(cells, self.cells)) or min(cells) < 1:
            raise CaseError(f"gas.grid.cells = {self.cells!r}: must be two integers >= 1 (nx, ny)")
        if len(size) != 2 or not all(np.isfinite(size)) or min(size) <= 0.0:
            raise CaseError(f"gas.grid.size = {self.size!r}: must be two lengths > 0 [m] (Lx, Ly)")
        if not (np.isfinite(self.depth) and self.depth > 0.0):
            raise CaseError(f"gas.grid.depth = {self.depth!r}: must be > 0 [m]")
        object.__setattr__(self, "cells", cells)
        object.__setattr__(self, "size", size)
        object.__setattr__(self, "depth", float(self.depth))

    # ------------------------------------------------------------ sizes
    # cached: the grid is frozen, and a coupled run reads these many times a gas step
    @cached_property
    def nx(self) -> int:
        return self.cells[0]

    @cached_property
    def ny(self) -> int:
        return self.cells[1]

    @cached_property
    def dx(self) -> float:
        """Cell width [m] (Hoomans' DX)."""
        return self.size[0] / self.nx

    @cached_property
    def dy(self) -> float:
        """Cell height [m] (Hoomans' DY)."""
        return self.size[1] / self.ny

    @cached_property
    def cell_volume(self) -> float:
        """dx dy depth [m^3]."""
        return self.dx * self.dy * self.depth

    @cached_property
    def area_x(self) -> float:
        """Area of an x-face, dy depth [m^2]."""
        return self.dy * self.depth

    @cached_property
    def area_y(self) -> float:
        """Area of a y-face, dx depth [m^2]."""
        return self.dx * self.depth

    @cached_property
    def shape(self) -> tuple[int, int]:
        """Shape of centre arrays (p, rho, voidage): (nx, ny)."""
        return (self.nx, self.ny)

    @cached_property
    def u_shape(self) -> tuple[int, int]:
        """Shape of x-face arrays (u): (nx + 1, ny)."""
        return (self.nx + 1, self.ny)

    @cached_property
    def v_shape(self) -> tuple[int, int]:
        """Shape of y-face arrays (v): (nx, ny + 1)."""
        return (self.nx, self.ny + 1)

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
    def x_faces(self) -> np.ndarray:
        """(nx + 1,) x of x-faces [m]."""
        return np.arange(self.nx + 1) * self.dx

    @property
    def y_faces(self) -> np.ndarray:
        """(ny + 1,) y of y-faces [m]."""
        return np.arange(self.ny + 1) * self.dy

    def centres(self) -> tuple[np.ndarray, np.ndarray]:
        """(X, Y), each (nx, ny): coordinates of the cell centres [m]."""
        return np.meshgrid(self.x_centres, self.y_centres, indexing="ij")

    def side_length(self, side: str) -> float:
        """Length of a side [m]: Ly for left/right, Lx for bottom/top."""
        return self.size[1] if side in ("left", "right") else self.size[0]

    def side_faces(self, side: str) -> np.ndarray:
        """(n + 1,) positions [m] along ``side`` of the edges of its boundary faces."""
        return self.y_faces if side in ("left", "right") else self.x_faces

    # ------------------------------------------------------------ flags
    def cell_flags(self, boundaries: Mapping[str, object]) -> np.ndarray:
        """Hoomans' flag matrix ``fl(i, j)`` (Table 1) for boundary conditions on the four sides.

        Parameters
        ----------
        boundaries : dict
            ``{"left": BC, "right": BC, "bottom": BC, "top": BC}`` with objects from
            ``fluidem.gas.boundaries`` (each has an integer ``flag``).

        Returns
        -------
        (nx + 2, ny + 2) int8
            ``INTERIOR`` inside, the side's flag in its ring of boundary cells,
            ``CORNER`` in the four corners. See the module docstring for the layout.
        """
        check_sides(boundaries)
        fl = np.full((self.nx + 2, self.ny + 2), INTERIOR, np.int8)
        fl[0, 1:-1] = boundaries["left"].flag
        fl[-1, 1:-1] = boundaries["right"].flag
        fl[1:-1, 0] = boundaries["bottom"].flag
        fl[1:-1, -1] = boundaries["top"].flag
        fl[0, 0] = fl[0, -1] = fl[-1, 0] = fl[-1, -1] = CORNER
        return fl


def check_sides(boundaries: Mapping[str, object]) -> None:
    """Raise ``CaseError`` unless ``boundaries`` names exactly the four sides with valid objects,
    and periodic sides come in opposite pairs."""
    from .boundaries import BoundaryCondition, boundary_conditions

    if not isinstance(boundaries, Mapping):
        raise CaseError(f"gas.boundaries = {boundaries!r}: must be a dict of sides {list(SIDES)}")
    unknown = [k for k in boundaries if k not in SIDES]
    if unknown:
        raise CaseError(f"gas.boundaries: unknown side(s) {unknown}; allowed are {list(SIDES)}")
    missing = [k for k in SIDES if k not in boundaries]
    if missing:
        raise CaseError(f"gas.boundaries: side(s) {missing} missing; give a condition for each of {list(SIDES)}")
    for side in SIDES:
        bc = boundaries[side]
        if not isinstance(bc, BoundaryCondition):
            kinds = ", ".join(f"{boundary_conditions.get(n).__name__}(...)" for n in boundary_conditions.names())
            raise CaseError(f"gas.boundaries.{side} = {bc!r}: must be one of {kinds}")
    for a, b in (("left", "right"), ("bottom", "top")):
        pa, pb = boundaries[a].flag == PERIODIC, boundaries[b].flag == PERIODIC
        if pa != pb:
            raise CaseError(f"gas.boundaries: {a} is {type(boundaries[a]).__name__}() and {b} is "
                            f"{type(boundaries[b]).__name__}(); periodic sides come in pairs ({a} and {b} both Periodic())")
