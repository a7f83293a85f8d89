"""The ``[gas]`` section of a case: grid, properties, named boundary sides, initial velocity, time step DT.

Every boundary side is a condition of the ``boundary_conditions`` registry (``gas/boundaries/``),
chosen by its ``kind``: the objects a case holds are the ones the solver takes (``Wall()``,
``Inflow(...)`` in Python; ``{kind = "wall"}``, ``{kind = "inflow", ...}`` in TOML), each with its own keys.
``GasSection.build(gravity)`` gives the ``GasSolver``; the section is validated by
building its parts once, so a case that loads also builds.

Three ``cells`` entries make a 3D grid (``grid = { cells = [nx, ny, nz], size = [Lx, Ly, Lz] }``, no
depth), with the six sides left, right, bottom, top, front (z = 0) and back (z = Lz), and ``build`` gives
the 3D solver. A case with particles refuses a 3D grid for now (``Case``): the 3D gas is not coupled to
particles yet; the section is used on its own (``GasSection.model_validate(...).build(gravity)``).

Example (TOML)::

    [gas]
    dt = 1e-4                      # gas time step DT [s]; the DEM dt divides it
    linear_solver = "auto"         # pressure correction: auto, band, multigrid, superlu
    [gas.grid]
    cells = [15, 25]
    size = [0.15, 0.5]             # [m], lower-left corner at the origin
    depth = 0.004                  # [m]
    [gas.properties]
    density = 1.2                  # omit for the ideal gas of Hoomans 1996 eq. 44
    [gas.boundaries.left]
    kind = "wall"
    [gas.boundaries.bottom]
    kind = "inflow"
    voidage = 0.4
    segments = [{superficial = 1.8}, {interstitial = 45.0, start = 0.07, end = 0.08}]

``linear_solver`` picks the solution of the pressure-correction equations (``GasSolver``):
"auto" (compiled band LU up to 64 cells across, compiled GMRES + grid multigrid beyond),
"band", "multigrid" or "superlu" (SciPy). "pyamg" is refused with the measurement behind it
(``REFUSED_SOLVERS`` in ``solver.py``): the compiled multigrid solved the same corrections faster on
every grid measured.

A velocity may change in time: ``{pulse = 2.5, start = 0.0, duration = 0.2, otherwise = 0.5}``
(Hoomans 1996 §5.4) or ``{table = [[0.0, 0.0], [2.0, 0.4]]}`` (linear between (t, value) points).
"""
from __future__ import annotations

from typing import Annotated, Literal, Union

from pydantic import BaseModel, ConfigDict, Field, ValidationInfo, field_validator, model_validator

from ..errors import CaseError
from .boundaries import boundary_conditions
from .grid import OPPOSITE_PAIRS, PERIODIC, SIDE_AXIS, SIDES, SIDES_3D, StaggeredGrid
from .solver import REFUSED_SOLVERS, GasProperties, GasSolver

class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, validate_assignment=True)


class GridSpec(_Strict):
    """Uniform staggered grid (``StaggeredGrid``): 2D with two ``cells`` entries and a depth, 3D with three."""

    cells: tuple[int, ...] = Field(description="number of cells (nx, ny) of a 2D grid or (nx, ny, nz) of a 3D one")
    size: tuple[float, ...] = Field(description="domain extent (Lx, Ly) or (Lx, Ly, Lz) [m]; the lower-left(-front) "
                                                "corner at 0; must cover every box wall and the placement region")
    depth: float | None = Field(None, gt=0.0, description="extent along z of a 2D grid [m] (required there), equal "
                                                          "to the z extent of the particles' box walls; a 3D grid "
                                                          "has none (its z extent is size[2])")

    @model_validator(mode="after")
    def _check(self):
        if len(self.cells) == 2 and self.depth is None:
            raise ValueError("depth [m] is required for a 2D grid (two cells entries); a 3D grid has three")
        self.build()
        return self

    @property
    def dimensions(self) -> int:
        return len(self.cells)

    def build(self) -> StaggeredGrid:
        try:
            return StaggeredGrid(cells=self.cells, size=self.size, depth=self.depth)
        except CaseError as err:
            raise ValueError(str(err)) from None


class PropertiesSpec(_Strict):
    """Gas properties (``GasProperties``): air at 293 K by default."""

    viscosity: float = Field(1.8e-5, ge=0.0, description="shear viscosity [Pa s]")
    molar_mass: float = Field(28.8e-3, gt=0.0, description="[kg/mol] of the ideal gas")
    temperature: float = Field(293.0, gt=0.0, description="[K]")
    density: float | None = Field(None, gt=0.0, description="constant density [kg/m^3]; omit for the ideal gas")
    reference_pressure: float = Field(101325.0, gt=0.0, description="[Pa]")

    def build(self) -> GasProperties:
        return GasProperties(**self.model_dump())


# every registered boundary condition, chosen by its ``kind`` key (the registry is the only list of conditions)
BoundaryChoice = Annotated[Union[tuple(boundary_conditions.get(n) for n in boundary_conditions.names())],
                           Field(discriminator="kind")]


class GasSection(_Strict):
    """The gas phase of a coupled run (Hoomans 1996 eqs 42-48 on a staggered grid)."""

    dt: float = Field(gt=0.0, description="gas time step DT [s]; the DEM dt is DT / ceil(DT / dt_DEM)")
    grid: GridSpec
    properties: PropertiesSpec = Field(default_factory=PropertiesSpec)
    boundaries: dict[str, BoundaryChoice] = Field(description="a condition on each of left, right, bottom, top "
                                                              "(and front, back on a 3D grid)")
    initial_velocity: tuple[float, ...] = Field(
        (0.0, 0.0), description="interstitial gas velocity at t = 0 [m/s]: (u, v), or (u, v, w) on a 3D grid (a "
                                "pair there means w = 0)")
    convection: Literal["upwind", "tvd"] = Field(
        "upwind", description="convection scheme of the momentum equations: first-order upwind or TVD "
                              "(second order, Courant limit 0.5)")
    tolerance: float = Field(1e-10, gt=0.0, lt=1.0, description="mass-residual tolerance of each gas step [-]")
    linear_solver: Literal["auto", "band", "multigrid", "superlu"] = Field(
        "auto", description="pressure-correction solver: 'auto' (band LU up to 64 cells across, compiled "
        "GMRES + grid multigrid beyond), 'band', 'multigrid' or 'superlu' (SciPy)")

    @field_validator("linear_solver", mode="before")
    @classmethod
    def _not_refused(cls, v):
        if isinstance(v, str) and v in REFUSED_SOLVERS:  # the reason, not only the allowed names
            raise ValueError(REFUSED_SOLVERS[v])
        return v

    @field_validator("boundaries", mode="before")
    @classmethod
    def _known_sides(cls, v, info: ValidationInfo):
        """Side names first: an unknown side is reported as such, whatever its value (front and back are
        sides of a 3D grid only)."""
        grid = info.data.get("grid")
        sides = SIDES_3D if grid is not None and grid.dimensions == 3 else SIDES
        unknown = sorted(set(v) - set(sides), key=str) if isinstance(v, dict) else []
        if unknown:
            more = " (front and back are the z sides of a 3D grid)" if set(unknown) & {"front", "back"} else ""
            raise ValueError(f"unknown side(s) {', '.join(map(repr, unknown))}; allowed: {', '.join(sides)}{more}")
        return v

    @field_validator("boundaries")
    @classmethod
    def _sides(cls, v, info: ValidationInfo):
        grid = info.data.get("grid")
        sides = SIDES_3D if grid is not None and grid.dimensions == 3 else SIDES
        unknown = sorted(set(v) - set(sides))
        if unknown:
            more = " (front and back are the z sides of a 3D grid)" if set(unknown) & {"front", "back"} else ""
            raise ValueError(f"unknown side(s) {', '.join(map(repr, unknown))}; allowed: {', '.join(sides)}{more}")
        missing = [s for s in sides if s not in v]
        if missing:
            raise ValueError(f"missing side(s) {', '.join(missing)}: give a kind for each of {', '.join(sides)}")
        periodic = {s for s, b in v.items() if b.flag == PERIODIC}
        for a, b in OPPOSITE_PAIRS[:len(sides) // 2]:
            if (a in periodic) != (b in periodic):
                raise ValueError(f"sides {a} and {b}: periodic needs both opposite sides periodic")
        return v

    @field_validator("initial_velocity")
    @classmethod
    def _two_or_three(cls, v):
        if len(v) not in (2, 3):
            raise ValueError(f"a velocity has 2 components (u, v) or, on a 3D grid, 3 (u, v, w); got {len(v)}")
        return v

    @model_validator(mode="after")
    def _dimensions(self):
        if self.grid.dimensions == 3 and self.linear_solver == "band":
            raise ValueError("linear_solver = 'band' is the 2D block-tridiagonal LU; on a 3D grid use 'auto', "
                             "'multigrid' or 'superlu'")
        if self.grid.dimensions == 2 and len(self.initial_velocity) == 3:
            raise ValueError(f"initial_velocity = {list(self.initial_velocity)}: a 2D grid takes (u, v)")
        return self

    @model_validator(mode="after")
    def _inflow_courant(self):
        """The gas step against the fastest inflow: its interstitial velocity must not cross more than the
        Courant limit of a cell in DT (1 with upwind convection, 0.5 with TVD; ``GasSolver``). Flow inside can
        be faster still (a jet accelerates through the bed): the run then stops with the Courant number it
        reached, and summary ``gas_courant_max`` tells how close a finished run came."""
        limit = 0.5 if self.convection == "tvd" else 1.0
        for side, bc in self.boundaries.items():
            speed = bc.fastest_inflow()
            if speed == 0.0:
                continue
            k = SIDE_AXIS[side]
            width = self.grid.size[k] / self.grid.cells[k]
            courant = speed * self.dt / width
            if courant > limit:
                raise ValueError(
                    f"gas.dt = {self.dt:g} s: the {side} inflow's {speed:.4g} m/s (interstitial) crosses "
                    f"{courant:.3g} cells of {width:g} m in one gas step; the Courant number must stay at most "
                    f"{limit:g} with convection = {self.convection!r}: use gas.dt <= {limit * width / speed:.3g} s")
        return self

    def build(self, gravity) -> GasSolver:
        """The ``GasSolver`` of this section under ``gravity`` (gx, gy[, 0]) [m/s^2]; on a 3D grid the
        ``GasSolver3D`` under (gx, gy, gz)."""
        grid = self.grid.build()
        g = tuple(gravity)[:2] if grid.dimensions == 2 else tuple(gravity)
        return GasSolver(grid, self.properties.build(), dict(self.boundaries), gravity=g, convection=self.convection,
                         tolerance=self.tolerance, linear_solver=self.linear_solver)

    @property
    def velocity(self) -> tuple[float, ...]:
        """``initial_velocity`` with one entry per axis of the grid (w = 0 when a 3D grid was given a pair)."""
        v = tuple(self.initial_velocity)
        return v + (0.0,) * (self.grid.dimensions - len(v))
