"""Particles → grid: voidage and cell-averaged solids velocity at the centres of a ``StaggeredGrid``.

Particles are spheres whose centres lie in the grid's x–y plane (z ignored). Three ways
to get the solids fraction of cell (i, j), all exactly conservative:

``"centroid"``     Σ V_p / V_cell over particles whose centre is in the cell, V_cell = dx dy depth
                   (Sun 2007 eq. 34; Sun takes depth = one particle diameter, after eq. 35).
                   Conserves Σ (1−ε) V_cell = Σ V_p.
``"area"``         Σ A_pij / (dx dy): the exact area of each particle's disc (its cross-section
                   in the plane of the centres) inside the cell, over every cell it touches
                   (Hoomans 1996 §3.4). A 2D area fraction; conserves Σ (1−ε) dx dy = Σ π r².
                   ``to_3d=True`` converts it with Hoomans eq. 49.
``"area_volume"``  Σ V_p A_pij/(π r_p²) / V_cell: each particle's volume shared among the cells
                   in proportion to its disc area in them. Conserves Σ (1−ε) V_cell = Σ V_p.

Optional smoothing (``smooth``) diffuses the solids fraction with zero flux through the
sides, which is a Gaussian filter of standard deviation ``width`` away from walls and
conserves the total. Solids velocity is the number average over the centres in a cell
(Hoomans 1996 eq. 50) or the volume average (Sun 2007 eq. 35; with area methods each
particle is weighted by its share in the cell); cells with no solids get 0. Overfull cells
are clipped to a minimum voidage and counted. Parts of discs outside the grid are
dropped by the area methods; centres outside are counted in the nearest edge cell.

On a 3D grid (three ``cells`` entries) the particles are spheres anywhere in the box and the fields
are (nx, ny, nz) (``_voidage3d_kernels``): ``"centroid"`` puts V_p into the cell holding the centre,
``"volume"`` (3D only) the exact volume of the sphere inside each cell it overlaps (a closed form of the
sphere ∩ box volume), both conserving Σ (1−ε) V_cell = Σ V_p to round-off (periodic axes wrap, the edge
cells of a non-periodic axis take what pokes out); ``"area"``, ``"area_volume"`` and ``to_3d`` are 2D
ideas and refused. ``smooth`` diffuses along the three axes (zero flux through non-periodic sides,
wrapped on periodic ones): a Gaussian filter of standard deviation ``width`` along each axis.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field

from ..gas.grid import StaggeredGrid
from . import _voidage3d_kernels as K3
from . import _voidage_kernels as K

METHODS = ("centroid", "area", "area_volume", "volume")
WEIGHTINGS = ("number", "volume")
EQ49_FACTOR = 2.0 / math.sqrt(math.pi * math.sqrt(3.0))  # Hoomans 1996 eq. 49


def _particles(position, diameter):
    """(position (N, 2|3) float64, diameter (N,) float64), checked."""
    pos = np.asarray(position, float)
    if pos.ndim != 2 or pos.shape[1] not in (2, 3):
        raise ValueError(f"position must be (N, 3) or (N, 2) [m]; got shape {pos.shape}")
    d = np.ascontiguousarray(np.broadcast_to(np.asarray(diameter, float), (pos.shape[0],)))
    if np.any(~(d > 0.0)):
        raise ValueError("diameter must be > 0 [m] for every particle")
    return pos, d


def _velocities(velocity, n, three=False):
    """velocity (N, 2|3) float64; zeros (N, 2) for None ((N, 3) if ``three``)."""
    if velocity is None:
        return np.zeros((n, 3 if three else 2))
    vel = np.asarray(velocity, float)
    if vel.shape[:1] != (n,) or vel.ndim != 2 or vel.shape[1] < 2:
        raise ValueError(f"velocity must be (N, 3) or (N, 2) [m/s] with N = {n}; got shape {vel.shape}")
    return vel


def _codes(method, weighting, dimensions=2):
    if method not in METHODS:
        raise ValueError(f"method = {method!r}: allowed are {', '.join(METHODS)}")
    check_method(method, dimensions)
    if weighting not in WEIGHTINGS:
        raise ValueError(f"weighting = {weighting!r}: allowed are {', '.join(WEIGHTINGS)}")
    return METHODS.index(method), WEIGHTINGS.index(weighting)


def check_method(method: str, dimensions: int) -> None:
    """ValueError where ``method`` does not apply to a grid of ``dimensions``: 'volume' is of 3D grids, 'area'
    and 'area_volume' (disc areas in the plane of the centres) of 2D ones."""
    if dimensions == 3 and method in ("area", "area_volume"):
        raise ValueError(f"method = {method!r} maps disc areas in the plane of a 2D grid; on a 3D grid allowed are "
                         "'centroid' and 'volume' (the exact sphere volume in each cell)")
    if dimensions == 2 and method == "volume":
        raise ValueError("method = 'volume' (exact sphere volumes in 3D cells) needs a 3D grid; on a 2D grid allowed "
                         "are 'centroid', 'area' and 'area_volume'")


def _periodic3(periodic):
    """(px, py, pz) booleans of a 3D map (default: no periodic axis)."""
    if periodic is None:
        return False, False, False
    px, py, pz = (bool(a) for a in periodic)
    return px, py, pz


def _norm(grid, method):
    """What the deposit is divided by: dx dy for the 2D area fraction, else V_cell."""
    return grid.dx * grid.dy if method == "area" else grid.cell_volume


def _deposit(grid, pos, d, method, vel, weighting, periodic=None):
    """(fraction, weight sum, weighted vx, weighted vy[, weighted vz]), each (nx, ny) or (nx, ny, nz);
    ``_voidage_kernels.deposit_solids``, ``_voidage3d_kernels.deposit_solids3d``."""
    mcode, wcode = _codes(method, weighting, grid.dimensions)
    if grid.dimensions == 3:
        if pos.shape[1] != 3 or vel.shape[1] != 3:
            raise ValueError("a 3D grid needs positions and velocities (N, 3)")
        out = tuple(np.empty(grid.shape) for _ in range(5))
        K3.deposit_solids3d(mcode, wcode, np.ascontiguousarray(pos), 0.5 * d, math.pi / 6.0 * d**3,
                            np.ascontiguousarray(vel), grid.dx, grid.dy, grid.dz, *_periodic3(periodic),
                            grid.cell_volume, *out)
        return out
    frac, wsum, wvx, wvy = (np.empty(grid.shape) for _ in range(4))
    volume = math.pi / 6.0 * d**3
    K.deposit_solids(mcode, wcode, pos, 0.5 * d, volume, vel, grid.dx, grid.dy, _norm(grid, method),
                     frac, wsum, wvx, wvy)
    return frac, wsum, wvx, wvy


def solids_fraction(grid: StaggeredGrid, position, diameter, method: str = "centroid", periodic=None) -> np.ndarray:
    """Solids fraction 1 − ε at the cell centres, (nx, ny) or (nx, ny, nz) float64 [-] (module docstring).

    position : (N, 3) [m] (x, y used on a 2D grid); diameter : (N,) or scalar [m]; periodic : (px, py, pz) of
    a 3D grid, the axes that wrap (default none).
    """
    pos, d = _particles(position, diameter)
    vel = _velocities(None, d.size, grid.dimensions == 3)
    return _deposit(grid, pos, d, method, vel, "volume", periodic)[0]


def solids_velocity(grid: StaggeredGrid, position, diameter, velocity, weighting: str = "number",
                    method: str = "centroid", periodic=None) -> tuple[np.ndarray, ...]:
    """Cell-averaged solids velocity (v_x, v_y), each (nx, ny) [m/s]; 0 where a cell holds no solids.

    ``weighting="number"``: Σ v_k / n over centres in the cell (Hoomans 1996 eq. 50).
    ``weighting="volume"``: Σ v_k w_k / Σ w_k with w_k the particle's solids share in the cell
    under ``method`` (V_p for centroid counting: Sun 2007 eq. 35). On a 3D grid (v_x, v_y, v_z), each
    (nx, ny, nz).
    """
    pos, d = _particles(position, diameter)
    _, wsum, *wv = _deposit(grid, pos, d, method, _velocities(velocity, d.size), weighting, periodic)
    return _average(wsum, *wv)


def _average(wsum, *wv):
    safe = np.where(wsum > 0.0, wsum, 1.0)
    return tuple(np.where(wsum > 0.0, w / safe, 0.0) for w in wv)


def voidage_3d_from_2d(voidage_2d):
    """ε_3D = 1 − 2/sqrt(π√3) (1 − ε_2D)^{3/2} (Hoomans 1996 eq. 49; hexagonal 2D ↔ FCC 3D)."""
    e = np.asarray(voidage_2d, float)
    return 1.0 - EQ49_FACTOR * np.clip(1.0 - e, 0.0, None) ** 1.5


def smooth(grid: StaggeredGrid, field, width: float, periodic=None) -> np.ndarray:
    """Diffuse a centre field over a length ``width`` [m]; returns a new (nx, ny) or (nx, ny, nz) array.

    On a 3D grid the same along z too, the sides of the axes in ``periodic`` (px, py, pz) wrapped.

    Explicit diffusion with zero flux through the four sides for a total D t = width²/2,
    so away from walls it is a Gaussian filter of standard deviation ``width`` in x and y
    (each explicit step adds exactly 2 D Δt to the variance of a spike). Σ field is
    conserved to round-off. ``width = 0`` returns a copy.
    """
    f = np.array(field, dtype=float, copy=True)
    if not (math.isfinite(width) and width >= 0.0):
        raise ValueError(f"smoothing width = {width!r}: must be >= 0 [m]")
    if width == 0.0:
        return f
    if grid.dimensions == 3:
        rx, ry, rz, steps = _diffusion_steps3d(grid, width)
        K3.diffuse3d(f, rx, ry, rz, *_periodic3(periodic), steps, np.empty_like(f))
        return f
    rx, ry, steps = _diffusion_steps(grid, width)
    K.diffuse(f, rx, ry, steps, np.empty_like(f))
    return f


def _diffusion_steps(grid: StaggeredGrid, width: float) -> tuple[float, float, int]:
    """(rx, ry, steps) of ``smooth`` for a width [m] > 0: D t = width²/2 in steps with rx + ry ≤ 0.4."""
    total = 0.5 * width * width  # D t
    k = 1.0 / grid.dx**2 + 1.0 / grid.dy**2
    steps = max(1, math.ceil(total * k / 0.4))  # rx + ry ≤ 0.4 < 1/2: stable
    ddt = total / steps
    return ddt / grid.dx**2, ddt / grid.dy**2, steps


def _diffusion_steps3d(grid: StaggeredGrid, width: float) -> tuple[float, float, float, int]:
    """(rx, ry, rz, steps) of ``smooth`` on a 3D grid: D t = width²/2 in steps with rx + ry + rz ≤ 0.4."""
    total = 0.5 * width * width  # D t
    k = 1.0 / grid.dx**2 + 1.0 / grid.dy**2 + 1.0 / grid.dz**2
    steps = max(1, math.ceil(total * k / 0.4))  # rx + ry + rz ≤ 0.4 < 1/2: stable
    ddt = total / steps
    return ddt / grid.dx**2, ddt / grid.dy**2, ddt / grid.dz**2, steps


def sauter_inverse(grid: StaggeredGrid, position, diameter) -> np.ndarray:
    """1/D̄ [1/m] of each cell (nx, ny): the inverse Sauter mean diameter of the particles whose centre lies
    in it, Σ V_p/d_p / Σ V_p (DEM book 2012 two-phase chapter, eq. 10); cells without particles take the
    bed's value. The polydisperse drag takes y = d/D̄ from it (eq. 11)."""
    pos, d = _particles(position, diameter)
    out = np.empty(grid.shape)
    if grid.dimensions == 3:
        K3.sauter_inverse3d(np.ascontiguousarray(pos), 0.5 * d, math.pi / 6.0 * d**3, grid.dx, grid.dy, grid.dz, out)
        return out
    K.sauter_inverse(pos, 0.5 * d, math.pi / 6.0 * d**3, grid.dx, grid.dy, out)
    return out


def clip_voidage(voidage, minimum: float) -> tuple[np.ndarray, int]:
    """(max(ε, minimum), number of cells that were below ``minimum``)."""
    e = np.asarray(voidage, float)
    low = e < minimum
    return np.where(low, minimum, e), int(np.count_nonzero(low))


@dataclass(frozen=True)
class SolidsMap:
    """Result of ``VoidageMapping.map``: fields at cell centres (nx, ny) or (nx, ny, nz) float64.

    voidage ε [-] (clipped), solids_u / solids_v (/ solids_w on a 3D grid, else None) cell-averaged solids
    velocity [m/s], clipped: number of cells whose voidage was raised to the minimum.
    """

    voidage: np.ndarray
    solids_u: np.ndarray
    solids_v: np.ndarray
    clipped: int
    solids_w: np.ndarray | None = None


class VoidageMapping(BaseModel):
    """Choices of the particle → grid mapping (a case-file section).

    method : "centroid" | "area" | "area_volume" (2D grids) | "volume" (3D grids) (module docstring)
    to_3d : convert the 2D area voidage with Hoomans 1996 eq. 49 (method "area" only)
    smoothing_width : standard deviation of the diffusion filter [m]; 0 = none
    velocity_weighting : "number" (Hoomans eq. 50) | "volume" (Sun eq. 35)
    minimum_voidage : overfull cells are clipped to this ε [-]
    """

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True)

    method: Literal["centroid", "area", "area_volume", "volume"] = Field(
        "centroid", description="solids fraction of a cell: particle volumes by centre (Sun 2007 eq. 34), exact "
                                "disc areas (Hoomans 1996 §3.4), or volumes shared by disc area (2D grids); on a "
                                "3D grid 'centroid' or 'volume', the exact volume of each sphere in each cell")
    to_3d: bool = Field(False, description="convert the 2D area voidage to 3D with Hoomans 1996 eq. 49 "
                                           "(method 'area' only)")
    smoothing_width: float = Field(0.0, ge=0.0, description="standard deviation of the diffusion filter of the "
                                                            "solids fraction [m]; 0: none")
    velocity_weighting: Literal["number", "volume"] = Field(
        "number", description="solids velocity of a cell: number average (Hoomans 1996 eq. 50) or volume "
                              "average (Sun 2007 eq. 35)")
    minimum_voidage: float = Field(0.3, gt=0.0, lt=1.0, description="overfull cells are clipped to this "
                                                                    "voidage [-] (and counted)")

    def _check(self, dimensions: int = 2) -> None:
        if self.to_3d and self.method != "area":
            raise ValueError(f"to_3d (Hoomans 1996 eq. 49) converts 2D area voidage; method is {self.method!r}")
        check_method(self.method, dimensions)

    def map(self, grid: StaggeredGrid, position, diameter, velocity=None, periodic=None) -> SolidsMap:
        """Voidage and solids velocity of particles at ``position`` (N, 3|2) [m] with ``diameter`` (N,) or
        scalar [m] and ``velocity`` (N, 3|2) [m/s] (None: at rest); ``periodic`` (px, py, pz): the axes of a
        3D grid that wrap."""
        self._check(grid.dimensions)
        pos, d = _particles(position, diameter)
        vel = _velocities(velocity, d.size, grid.dimensions == 3)
        if grid.dimensions == 3:
            pos, vel = np.ascontiguousarray(pos), np.ascontiguousarray(vel)
        return self.map_particles(grid, pos, 0.5 * d, math.pi / 6.0 * d**3, vel, periodic)

    def map_particles(self, grid: StaggeredGrid, position, radius, volume, velocity, periodic=None,
                      work=None) -> SolidsMap:
        """``map`` without argument checks, for a coupled run's every gas step.

        position, velocity : (N, ≥2) float64 [m], [m/s]; radius (N,) [m] > 0 and volume (N,) = π/6 (2r)³ [m³].
        One compiled call (``_voidage_kernels.map_solids``; on a 3D grid ``_voidage3d_kernels.map_solids3d``, with
        position and velocity (N, 3), ``periodic`` (px, py, pz) the axes that wrap and ``work`` the caller's float64
        scratch of the deposit, or None).
        """
        self._check(grid.dimensions)
        if grid.dimensions == 3:
            return self._map3d(grid, position, radius, volume, velocity, periodic, work)
        mcode, wcode = _codes(self.method, self.velocity_weighting)
        rx, ry, steps = _diffusion_steps(grid, self.smoothing_width) if self.smoothing_width > 0.0 else (0.0, 0.0, 0)
        shape = grid.shape
        eps, su, sv = np.empty(shape), np.empty(shape), np.empty(shape)
        clipped = K.map_solids(mcode, wcode, position, radius, volume, velocity, grid.dx, grid.dy,
                               _norm(grid, self.method), rx, ry, steps, self.to_3d, EQ49_FACTOR,
                               self.minimum_voidage, eps, su, sv)
        return SolidsMap(eps, su, sv, int(clipped))

    def _map3d(self, grid, position, radius, volume, velocity, periodic, work=None) -> SolidsMap:
        """``map_particles`` on a 3D grid."""
        mcode, wcode = _codes(self.method, self.velocity_weighting, 3)
        w = self.smoothing_width
        rx, ry, rz, steps = _diffusion_steps3d(grid, w) if w > 0.0 else (0.0, 0.0, 0.0, 0)
        eps, su, sv, sw = (np.empty(grid.shape) for _ in range(4))
        clipped = K3.map_solids3d(mcode, wcode, position, radius, volume, velocity, grid.dx, grid.dy, grid.dz,
                                  *_periodic3(periodic), grid.cell_volume, rx, ry, rz, steps, self.minimum_voidage,
                                  eps, su, sv, sw, work)
        return SolidsMap(eps, su, sv, int(clipped), sw)
