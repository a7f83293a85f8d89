"""Volume-averaged gas phase (Hoomans 1996 eqs 42-48, after Kuipers et al. 1992) on a staggered grid.

``GasSolver.advance(state, dt, t, ...)`` moves a ``GasState`` from t to t + dt. The
particle side enters only as arrays: voidage ε, the interphase coefficient β with the
solids velocity, and/or an explicit momentum source. Orchestration lives here; the
loops over cells and faces are the compiled kernels of ``_solver_kernels``.

Equations (ε voidage, ρ gas density, u gas velocity (interstitial), v solids velocity)::

    ∂(ερ)/∂t + ∇·(ερu) = 0                                              eq. 42
    ∂(ερu)/∂t + ∇·(ερuu) = −ε∇p − β(u − v) − ∇·(ετ_g) + ερg + s          eq. 43
    ρ = p M/(RT)  (or a constant)                                       eq. 44
    τ_g = −[(λ_g − 2/3 μ_g)(∇·u) I + μ_g (∇u + ∇uᵀ)],  λ_g = 0          eq. 48

The ε of −ε∇p is the face mean of the cells' (``face_voidage``) unless the step is given a
``pressure_voidage`` per face: a coupling whose particles take −V_p∇p passes the voidage that makes
the two pressure forces add up to −∇p V_f (``coupling.exchange``).

Time step (semi-implicit, as Kuipers et al. 1992): convection (mass fluxes with face
means of ε and ρ; upwind or TVD face velocities) and viscous stress are explicit;
pressure, interphase drag and the density of inertia and gravity are implicit. Each
face velocity is then u = û − D ∂p/∂x with a scalar D, so the pressure correction of
the SIMPLE family is exact here: the outer iterations are Newton iterations of the
continuity equation for the pressure, with ρ(p) of eq. 44 (the matrix is their exact
Jacobian, including the density in the inertia of the face momentum). They stop when the
summed cell mass residual, relative to the gas flow through the domain, is below
``tolerance``. The constant-density gas converges in one correction (with a freshly
factorised matrix); the ideal gas in about three, the first Newton step and then
corrections with the matrix of the first (chord). Stability needs the Courant number
|u| dt/dx + |v| dt/dy below about 1 (upwind) or 0.5 (TVD) and the viscous number
ν dt (2/dx² + 2/dy²) below 1; drag never limits dt.

The corrections are solved (``linear_solver``) by a compiled block-tridiagonal LU on grids
up to 64 cells across (factors reused from step to step while the matrix changes little,
and after a change factorised again only from the first changed line of cells, counted from
the pressure outlet), by GMRES with an aggregation-multigrid preconditioner beyond (cost
about proportional to the number of cells), or by SciPy's SuperLU. One step is one compiled
call (``_solver_kernels.step``; one more after each SuperLU factorisation, which SciPy makes);
the rest of ``advance`` checks and classifies its inputs. The kernels' linear algebra is in
``_linear_kernels.py`` (band LU, SuperLU factors) and ``_multigrid_kernels.py`` (set up by
``_multigrid.py``); the slots of the solver's stacked arrays and the named tuples that group
them for the kernels are in ``_layout.py``.

Inside the solver the pressure is kept relative to ``reference_pressure``, so that
gradients of a few Pa/m in 1e5 Pa keep their digits; ``GasState.p`` is absolute.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Mapping

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..errors import CaseError
from . import _layout as lay
from . import _linear_kernels as LK
from . import _solver_kernels as K
from ._multigrid import multigrid_arrays, no_multigrid
from ._operators import TVD, UPWIND, centre_to_x_faces, centre_to_y_faces
from .boundaries import BoundaryCondition
from .grid import (FREE_SLIP, INFLOW, NO_SLIP, OUTFLOW, PERIODIC, PRESSURE, SIDES, StaggeredGrid,
                   check_sides)

GAS_CONSTANT = 8.314462618  # R [J mol^-1 K^-1]
_F64 = np.dtype(np.float64)
SCHEMES = {"upwind": UPWIND, "tvd": TVD}
SLOW_CONVERGENCE = 0.3  # refactorise the pressure matrix when an iteration cuts the residual by less than this
BAND_MAX = 64  # band LU (compiled) up to this half-width; multigrid-preconditioned GMRES beyond
LINEAR_SOLVERS = ("auto", "band", "multigrid", "superlu")
# names refused, with the reason: on the benchmark bed (``fluidem.bench.gas_step_benchmark``) pyamg's AMG-preconditioned
# GMRES took 1.2 to 4 times as long per gas step as "multigrid" at 150 x 300 and 300 x 600 cells (2.6 to 3.5
# times in the fastest of three repeats; 2.4 to 50 times on the smaller grids), with as many Krylov iterations
REFUSED_SOLVERS = {"pyamg": "not offered: 'multigrid' (compiled GMRES with a grid multigrid) solves the same "
                            "corrections faster on every grid measured, 15 x 25 to 300 x 600 cells"}
KRYLOV_REDUCTION = 1e-4  # multigrid path: each correction solves the linear system to this fraction of its residual
KRYLOV_RESTART = 30  # GMRES restart length
KRYLOV_MAX = 300  # GMRES iterations of one correction before the multigrid path gives way to SuperLU
COARSEST = 64  # cells of the coarsest multigrid level (dense LU) at most


def _ready(a, shape) -> bool:
    """``a`` is a C-contiguous float64 ndarray of ``shape``: a kernel input as it is."""
    return type(a) is np.ndarray and a.shape == shape and a.dtype == _F64 and a.flags.c_contiguous


def check_options(convection, tolerance, max_iterations, jacobian_reuse, linear_solver) -> None:
    """CaseError naming the key for a solver option out of range (the 2D and the 3D solver take the same)."""
    if convection not in SCHEMES:
        raise CaseError(f"gas.convection = {convection!r}: allowed are {sorted(SCHEMES)}")
    if not (isinstance(tolerance, (int, float)) and 0.0 < tolerance < 1.0):
        raise CaseError(f"gas.tolerance = {tolerance!r}: must be in (0, 1)")
    if not (isinstance(max_iterations, int) and max_iterations >= 1):
        raise CaseError(f"gas.max_iterations = {max_iterations!r}: must be an integer >= 1")
    if not (0.0 <= jacobian_reuse < 1.0):
        raise CaseError(f"gas.jacobian_reuse = {jacobian_reuse!r}: must be in [0, 1)")
    if linear_solver in REFUSED_SOLVERS:
        raise _refused(linear_solver)


def _refused(name: str) -> CaseError:
    """The CaseError of a ``linear_solver`` name in ``REFUSED_SOLVERS``."""
    return CaseError(f"gas.linear_solver = {name!r}: {REFUSED_SOLVERS[name]}; allowed are "
                     + ", ".join(repr(k) for k in LINEAR_SOLVERS))


def _show(value) -> str:
    """repr of a value for messages, with NumPy scalars and arrays shown as plain numbers."""
    try:
        a = np.asarray(value, float)
    except (TypeError, ValueError):
        return repr(value)
    return repr(float(a)) if a.ndim == 0 else repr(tuple(a.ravel().tolist()))


# ================================================================ properties and state
@dataclass(frozen=True)
class GasProperties:
    """Physical properties of the gas (Hoomans 1996 §3.2: air at 293 K).

    Parameters
    ----------
    viscosity : float
        Shear viscosity μ_g [Pa s], constant (eq. 48; the bulk viscosity λ_g is zero).
    molar_mass : float
        M_g [kg/mol] of the ideal-gas law, eq. 44.
    temperature : float
        T [K]; the gas is isothermal.
    density : float or None
        None: ideal gas, ρ_g = p M_g/(R T) (eq. 44). A number: constant density [kg/m^3].
    reference_pressure : float
        [Pa]: default outlet pressure, and the pressure level of hydrostatic initial
        states without a pressure boundary.
    """

    viscosity: float = 1.8e-5
    molar_mass: float = 28.8e-3
    temperature: float = 293.0
    density: float | None = None
    reference_pressure: float = 101325.0

    def __post_init__(self):
        def bad(key, value, allowed):
            raise CaseError(f"gas.{key} = {value!r}: must be {allowed}")

        for key in ("viscosity", "molar_mass", "temperature", "reference_pressure"):
            value = getattr(self, key)
            if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
                bad(key, value, "a number")
        if not (math.isfinite(self.viscosity) and self.viscosity >= 0.0):
            bad("viscosity", self.viscosity, ">= 0 [Pa s]")
        if not (math.isfinite(self.molar_mass) and self.molar_mass > 0.0):
            bad("molar_mass", self.molar_mass, "> 0 [kg/mol]")
        if not (math.isfinite(self.temperature) and self.temperature > 0.0):
            bad("temperature", self.temperature, "> 0 [K]")
        if not (math.isfinite(self.reference_pressure) and self.reference_pressure > 0.0):
            bad("reference_pressure", self.reference_pressure, "> 0 [Pa]")
        if self.density is not None and not (isinstance(self.density, (int, float, np.floating, np.integer))
                                             and math.isfinite(self.density) and self.density > 0.0):
            bad("density", self.density, "None (ideal gas) or > 0 [kg/m^3]")

    @property
    def ideal(self) -> bool:
        """True for the ideal gas of eq. 44, False for constant density."""
        return self.density is None

    @property
    def compressibility(self) -> float:
        """dρ/dp = M/(RT) [s^2/m^2] of the ideal gas; 0 for constant density."""
        return self.molar_mass / (GAS_CONSTANT * self.temperature) if self.ideal else 0.0

    def density_at(self, pressure):
        """Gas density [kg/m^3] at ``pressure`` [Pa] (eq. 44, or the constant)."""
        if self.ideal:
            return np.asarray(pressure, float) * self.compressibility
        return np.full(np.shape(pressure), float(self.density)) if np.ndim(pressure) else float(self.density)


@dataclass
class GasState:
    """Gas fields on the staggered grid, SI units (layout in ``gas/grid.py``).

    p, rho, voidage : (nx, ny) float64   pressure [Pa], density [kg/m^3], voidage ε [-] at centres
    u : (nx + 1, ny) float64             interstitial x velocity on x-faces [m/s]
    v : (nx, ny + 1) float64             interstitial y velocity on y-faces [m/s]
    w : None (2D) or (nx, ny, nz + 1)    interstitial z velocity on z-faces [m/s] of a 3D grid, whose
                                         other arrays then have the third axis nz: (nx, ny, nz), ...
    """

    p: np.ndarray
    rho: np.ndarray
    u: np.ndarray
    v: np.ndarray
    voidage: np.ndarray
    w: np.ndarray | None = None

    def _keys(self) -> tuple[str, ...]:
        return ("p", "rho", "u", "v", "voidage") + (() if self.w is None else ("w",))

    def copy(self) -> "GasState":
        return GasState(**{k: getattr(self, k).copy() for k in self._keys()})

    def arrays(self) -> dict[str, np.ndarray]:
        return {k: getattr(self, k) for k in self._keys()}


@dataclass(frozen=True)
class StepInfo:
    """What one ``GasSolver.advance`` did.

    iterations : pressure corrections made (0: the predicted velocities already conserved mass)
    mass_residual : Σ_cells |continuity residual| / reference flow [-] at the end of the step,
        the reference flow being inflow + outflow + Σ|accumulation| + 1e-4 × mass/dt [kg/s]
    converged : mass_residual <= tolerance
    inflow_rate, outflow_rate : gas mass flow into / out of the domain through its boundary faces [kg/s]
    mass : gas mass in the domain after the step, Σ ε ρ V [kg]
    mass_change_rate : (mass after − mass before) / dt [kg/s]
    courant : max|u| dt/dx + max|v| dt/dy after the step [-]
    """

    iterations: int
    mass_residual: float
    converged: bool
    inflow_rate: float
    outflow_rate: float
    mass: float
    mass_change_rate: float
    courant: float

    @property
    def mass_balance_error(self) -> float:
        """|inflow − outflow − d(mass)/dt| / inflow [-] (absolute [kg/s] when nothing flows in)."""
        err = abs(self.inflow_rate - self.outflow_rate - self.mass_change_rate)
        return err / self.inflow_rate if self.inflow_rate > 0.0 else err


class GasConvergenceError(RuntimeError):
    """A gas step failed: its solution is not finite, or its mass residual stayed above the square
    root of the tolerance after ``max_iterations`` (a time step far beyond the stability limit)."""


# ================================================================ solver
class GasSolver:
    """Pressure-correction solver of the volume-averaged gas equations (Hoomans 1996 eqs 42-48).

    Parameters
    ----------
    grid : StaggeredGrid
    props : GasProperties
    boundaries : dict
        A condition on each side: ``{"left": Wall(), "right": Wall(), "bottom": Inflow(...),
        "top": PressureOutlet()}``; see ``fluidem.gas.boundaries``.
    gravity : (gx, gy) or (gx, gy, 0)
        [m/s^2].
    convection : {"upwind", "tvd"}
        Face values of the convected momentum: first-order upwind (donor cell) or the
        second-order TVD scheme with the van Leer limiter.
    tolerance : float
        Mass-residual tolerance of every step (see ``StepInfo.mass_residual``).
    max_iterations : int
        Most pressure corrections per step.
    jacobian_reuse : float
        The factorised pressure matrix is reused while the new matrix differs from it
        by at most this fraction (max norm); the iterations then converge a little
        slower but skip the factorisation. 0 refactorises whenever anything changed.
        The band factorises again only the blocks (lines of cells) from the first one
        whose rows changed by more than 0.3 times this fraction. Not used by multigrid,
        which makes its hierarchy anew every iteration (on 3D grids anew every step: an
        iteration after a cut of the residual to ``solver3d.CHORD_REDUCTION`` or less keeps
        the last one).
    linear_solver : {"auto", "band", "multigrid", "superlu"}
        Solution of the pressure-correction equations: "band", a compiled band LU without
        pivoting (the matrix is diagonally dominant; the unknowns are numbered along the
        shorter or the periodic direction first, so the half-width is min(nx, ny));
        "multigrid", compiled GMRES preconditioned by an aggregation multigrid V-cycle
        (each correction solved to 1e-4 of its residual; the Newton iterations still stop
        at ``tolerance``), for large grids; "superlu", SciPy's SuperLU with its factors
        applied by compiled triangular solves. "auto": the band up to a half-width of 64
        cells unless both directions are periodic, multigrid beyond. Band and multigrid
        give way to SuperLU if they fail (a poor pivot, a stalled GMRES). "pyamg" is
        refused (``REFUSED_SOLVERS``).

    Examples
    --------
    >>> grid = StaggeredGrid(cells=(15, 25), size=(0.15, 0.5), depth=0.004)
    >>> solver = GasSolver(grid, GasProperties(), {"left": Wall(), "right": Wall(),
    ...     "bottom": Inflow(superficial=1.8, voidage=0.4), "top": PressureOutlet()})
    >>> state = solver.initial_state(voidage=0.4)
    >>> beta = np.full(grid.shape, 2000.0)  # from a drag law, [kg m^-3 s^-1]
    >>> info = solver.advance(state, dt=1e-4, t=0.0, beta=beta, solids_u=0.0, solids_v=0.0)
    >>> info.converged
    True

    A 3D grid (``StaggeredGrid(cells=(nx, ny, nz), ...)``) makes a ``GasSolver3D`` (``solver3d.py``): the
    same interface with six sides, a third velocity component and 3D arrays.
    """

    def __new__(cls, grid=None, *args, **kwargs):
        if cls is GasSolver and isinstance(grid, StaggeredGrid) and grid.dimensions == 3:
            from .solver3d import GasSolver3D

            return super().__new__(GasSolver3D)
        return super().__new__(cls)

    def __init__(self, grid: StaggeredGrid, props: GasProperties, boundaries: Mapping[str, BoundaryCondition],
                 gravity=(0.0, -9.81), convection: str = "upwind", tolerance: float = 1e-10,
                 max_iterations: int = 50, jacobian_reuse: float = 1e-2, linear_solver: str = "auto"):
        if not isinstance(grid, StaggeredGrid):
            raise CaseError(f"gas.grid = {grid!r}: must be a StaggeredGrid(cells=..., size=..., depth=...)")
        if grid.dimensions != 2:
            raise CaseError(f"gas.grid = {grid!r}: this solver is the 2D one; GasSolver(grid, ...) makes the 3D one")
        if not isinstance(props, GasProperties):
            raise CaseError(f"gas properties = {props!r}: must be GasProperties(...)")
        check_sides(boundaries)
        g = np.asarray(gravity, float).ravel()
        if g.size not in (2, 3) or not np.all(np.isfinite(g)) or (g.size == 3 and g[2] != 0.0):
            raise CaseError(f"gravity = {_show(gravity)}: must be (gx, gy) or (gx, gy, 0) [m/s^2] for a 2D gas grid")
        check_options(convection, tolerance, max_iterations, jacobian_reuse, linear_solver)
        if linear_solver not in LINEAR_SOLVERS:
            raise CaseError(f"gas.linear_solver = {linear_solver!r}: allowed are "
                            + ", ".join(repr(k) for k in LINEAR_SOLVERS))
        if linear_solver == "band" and all(boundaries[s].flag == PERIODIC for s in SIDES):
            raise CaseError("gas.linear_solver = 'band': not with periodic sides in both directions; use 'superlu'")
        self._linear_solver = linear_solver
        self.grid, self.props = grid, props
        self.boundaries = dict(boundaries)
        self.gravity = (float(g[0]), float(g[1]))
        self.convection = convection
        self.tolerance = float(tolerance)
        self._sqrt_tolerance = math.sqrt(self.tolerance)
        self._p_ref = float(props.reference_pressure)
        self.max_iterations = max_iterations
        self.jacobian_reuse = float(jacobian_reuse)
        self.flags = grid.cell_flags(self.boundaries)
        self.periodic_x = self.boundaries["left"].flag == PERIODIC
        self.periodic_y = self.boundaries["bottom"].flag == PERIODIC
        self._setup_faces()
        self._setup_maps()
        self._setup_matrix()
        self._setup_work()
        self._set_boundary_values(0.0)
        self.C[lay.C_PFIX_OLD] = self.C[lay.C_PFIX]
        self._shapes = (grid.shape, grid.u_shape, grid.v_shape)
        self._state_arrays = None  # the state arrays _check_state found right (a lay.StateArrays, and as a tuple)
        self._state_tuple = ()
        self._fields = lay.Fields(self.U, self.V, self.G, self.H, self.C, self.FU, self.FV, self.TAU)
        self._bnd = lay.Boundaries(self.flags, self.KU, self.KV, self.RULES, self.row_of)
        self._system = lay.PressureSystem(self.MAT, self.VEC, self._csc_indices, self._csc_indptr, self.diag_pos,
                                          self.upos, self.vpos, self.pin_pos)
        self._band_factors = lay.BandFactors(self._band, self._band_lu, self._order, self._band_place, self._csc_block)
        self._set_groups()

    def _set_groups(self):
        """The grouped arrays of ``K.step`` after the inputs, as plain tuples (see ``K.step``), all persistent
        (the SuperLU factors change in ``_factorise`` and ``restore_factors``)."""
        self._groups = tuple(tuple(g) for g in (self._fields, self._bnd, self._system, self._factors,
                                                self._band_factors, self._mg))

    # ------------------------------------------------------------ set-up
    def _setup_faces(self):
        """Face kinds, inward signs and fixed-value weights from the flags."""
        nx, ny, fl = self.grid.nx, self.grid.ny, self.flags
        kind_of_ghost = {FREE_SLIP: lay.FIXED, NO_SLIP: lay.FIXED, INFLOW: lay.FIXED, PRESSURE: lay.SOLVED,
                         OUTFLOW: lay.OUTFLOW_FACE, PERIODIC: lay.SOLVED}

        def kinds(n_faces_along, n_across, ghost_lo, ghost_hi):
            kind = np.full((n_faces_along, n_across), lay.SOLVED, np.int8)
            sign = np.zeros((n_faces_along, n_across), np.int8)
            kind[0] = [kind_of_ghost[int(f)] for f in ghost_lo]
            kind[-1] = [lay.COPY if f == PERIODIC else kind_of_ghost[int(f)] for f in ghost_hi]
            sign[0] = np.where(ghost_lo == PERIODIC, 0, 1)
            sign[-1] = np.where(ghost_hi == PERIODIC, 0, -1)
            return kind, sign

        uk, us = kinds(nx + 1, ny, fl[0, 1:-1], fl[-1, 1:-1])
        vk, vs = kinds(ny + 1, nx, fl[1:-1, 0], fl[1:-1, -1])
        self.KU = np.stack([uk, us])  # K_KIND, K_SIGN
        self.KV = np.ascontiguousarray(np.stack([vk.T, vs.T]))
        self.ukind, self.ubnd = self.KU[lay.K_KIND], self.KU[lay.K_SIGN]
        self.vkind, self.vbnd = self.KV[lay.K_KIND], self.KV[lay.K_SIGN]
        # sides with a prescribed normal velocity: t -> velocity of each boundary face (BoundaryCondition)
        self._inflows = []
        for side in SIDES:
            bc = self.boundaries[side]
            velocity = bc.face_velocity(side, self.grid.side_faces(side))
            if velocity is not None:
                self._inflows.append((side, bc, velocity))
        self._pressure_sides = [(s, bc) for s, bc in self.boundaries.items() if bc.flag == PRESSURE]
        self._time_dependent = any(bc.time_dependent for bc in self.boundaries.values())
        self.has_outflow = any(bc.flag == OUTFLOW for bc in self.boundaries.values())

    def _setup_maps(self):
        """row_of / col_of: padded centre cell -> equation row / pressure unknown (-1: none)."""
        nx, ny, fl = self.grid.nx, self.grid.ny, self.flags
        k = np.arange(nx * ny, dtype=np.int64).reshape(nx, ny)
        row = np.full((nx + 2, ny + 2), -1, np.int64)
        col = np.full((nx + 2, ny + 2), -1, np.int64)
        row[1:-1, 1:-1] = col[1:-1, 1:-1] = k
        zero_gradient = (FREE_SLIP, NO_SLIP, INFLOW, OUTFLOW)
        for ghost, adjacent, opposite in (((0, slice(1, -1)), k[0], k[-1]), ((-1, slice(1, -1)), k[-1], k[0]),
                                          ((slice(1, -1), 0), k[:, 0], k[:, -1]),
                                          ((slice(1, -1), -1), k[:, -1], k[:, 0])):
            f = fl[ghost]
            row[ghost] = np.where(f == PERIODIC, opposite, -1)
            col[ghost] = np.where(f == PERIODIC, opposite, np.where(np.isin(f, zero_gradient), adjacent, -1))
        self.row_of, self.col_of = row, col
        # ghost rules of centre scalars, indexed by flag
        self.RULES = np.zeros((2, 9), np.int64)
        self.prule, self.erule = self.RULES[lay.RULE_P], self.RULES[lay.RULE_E]
        for f in (FREE_SLIP, NO_SLIP, INFLOW, OUTFLOW):
            self.prule[f] = lay.R_COPY
        self.prule[PRESSURE] = lay.R_FIXED
        self.prule[PERIODIC] = lay.R_WRAP
        for f in (FREE_SLIP, NO_SLIP, PRESSURE, OUTFLOW):
            self.erule[f] = lay.R_COPY  # Hoomans 1996 §3.5: wall cells copy the adjacent voidage
        self.erule[INFLOW] = lay.R_FIXED  # Hoomans 1996 §3.5: fixed voidage in influx cells
        self.erule[PERIODIC] = lay.R_WRAP
        self.C = np.zeros((lay.N_C, nx + 2, ny + 2))  # stacked centre arrays, slots lay.C_*
        self.P, self.RHO, self.E = self.C[lay.C_P], self.C[lay.C_RHO], self.C[lay.C_E]
        self.pfix, self.efix = self.C[lay.C_PFIX], self.C[lay.C_EFIX]
        self.efix[:] = 1.0
        for side, bc in self.boundaries.items():
            if bc.flag == INFLOW:
                self.efix[self._ghost_index(side)] = bc.voidage

    @staticmethod
    def _ghost_index(side):
        return {"left": (0, slice(1, -1)), "right": (-1, slice(1, -1)),
                "bottom": (slice(1, -1), 0), "top": (slice(1, -1), -1)}[side]

    def _face_pairs(self, kind, left, right):
        """(n_faces, 4) (row, col) pairs L-L, L-R, R-L, R-R of faces; left/right: padded centre index arrays."""
        rl, cl = self.row_of[left], self.col_of[left]
        rr, cr = self.row_of[right], self.col_of[right]
        rows = np.stack([rl, rl, rr, rr], axis=-1)
        cols = np.stack([cl, cr, cl, cr], axis=-1)
        valid = (rows >= 0) & (cols >= 0) & (kind != lay.COPY)[..., None]
        return rows, cols, valid

    def _setup_matrix(self):
        """Fixed CSC pattern of the pressure-correction matrix and where each face writes into it."""
        nx, ny = self.grid.nx, self.grid.ny
        n = nx * ny
        I, J = np.meshgrid(np.arange(nx + 1), np.arange(ny), indexing="ij")
        ur, uc, uv = self._face_pairs(self.ukind, (I, J + 1), (I + 1, J + 1))
        I, J = np.meshgrid(np.arange(nx), np.arange(ny + 1), indexing="ij")
        vr, vc, vv = self._face_pairs(self.vkind, (I + 1, J), (I + 1, J + 1))
        diag = np.arange(n, dtype=np.int64)
        rows = np.concatenate([ur[uv], vr[vv], diag])
        cols = np.concatenate([uc[uv], vc[vv], diag])
        keys = np.unique(cols * n + rows)  # CSC order: by column, then row
        self._indices = (keys % n).astype(np.int32)
        self._indptr = np.searchsorted(keys, np.arange(n + 1) * n).astype(np.int32)
        self.MAT = np.zeros((2, keys.size))  # M_DATA, M_FACTORED
        self._data, self._lu_data = self.MAT[lay.M_DATA], self.MAT[lay.M_FACTORED]

        def pos(r, c, valid):
            p = np.searchsorted(keys, c * n + r)
            return np.where(valid, p, -1).astype(np.int64)

        self.upos = np.ascontiguousarray(pos(ur, uc, uv))
        self.vpos = np.ascontiguousarray(pos(vr, vc, vv))
        self.diag_pos = pos(diag, diag, np.ones(n, bool))
        # a constant-density gas with no pressure boundary has its level fixed by p'(cell 0) = 0
        self.pinned = (not self.props.ideal) and not self._pressure_sides
        if self.pinned:
            self.pin_pos = np.flatnonzero(self._indices == 0).astype(np.int64)
            self.pin_diag = int(self.diag_pos[0])
        else:
            self.pin_pos = np.zeros(0, np.int64)
            self.pin_diag = -1

    def _setup_work(self):
        nx, ny = self.grid.nx, self.grid.ny
        self.U, self.G = np.zeros((nx + 5, ny + 4)), np.zeros((nx + 5, ny + 4))
        self.V, self.H = np.zeros((nx + 4, ny + 5)), np.zeros((nx + 4, ny + 5))
        self.FU = np.zeros((lay.N_F,) + self.grid.u_shape)  # stacked x-face arrays, slots lay.F_*
        self.FV = np.zeros((lay.N_F,) + self.grid.v_shape)
        self.exu, self.exv = self.FU[lay.F_EX], self.FV[lay.F_EX]
        self.ufix, self.vfix = self.FU[lay.F_FIX], self.FV[lay.F_FIX]
        self.wout_u, self.wout_v = self.FU[lay.F_WOUT], self.FV[lay.F_WOUT]
        self.TAU = np.zeros((nx + 1, ny + 1))  # shear stresses at the corners (work)
        n = nx * ny
        self.VEC = np.zeros((lay.N_VEC, n))  # slots lay.V_*
        self.R = self.VEC[lay.V_R]
        self._factors = lay.LUFactors(np.zeros((4, n + 1), np.int64), np.zeros(1, np.int64), np.zeros(1),
                                      np.zeros(1, np.int64), np.zeros(1), np.ones(n))  # none yet
        gd = self.grid
        self._fpar = np.zeros(lay.N_FPAR)
        self._fpar[lay.FP_MU] = self.props.viscosity
        self._fpar[lay.FP_PREF] = self.props.reference_pressure
        self._fpar[[lay.FP_GX, lay.FP_GY, lay.FP_DX, lay.FP_DY, lay.FP_AX, lay.FP_AY, lay.FP_VOL]] = (
            self.gravity[0], self.gravity[1], gd.dx, gd.dy, gd.area_x, gd.area_y, gd.cell_volume)
        self._fpar[lay.FP_COMP] = self.props.compressibility
        self._fpar[lay.FP_RHOC] = 0.0 if self.props.ideal else float(self.props.density)
        self._fpar[lay.FP_TOL] = self.tolerance
        self._fpar[lay.FP_REUSE] = self.jacobian_reuse
        self._fpar[lay.FP_SLOW] = SLOW_CONVERGENCE
        self._fpar[lay.FP_ETA] = KRYLOV_REDUCTION
        self._fpar[lay.FP_SQRT_TOL] = self._sqrt_tolerance
        self._ipar = np.zeros(lay.N_IPAR, np.int64)
        self._ipar[[lay.I_NX, lay.I_NY, lay.I_MAXIT, lay.I_PIN, lay.I_SCHEME, lay.I_KRYLOV_MAX, lay.I_RESTART,
                    lay.I_PX, lay.I_PY]] = (
            nx, ny, self.max_iterations, self.pin_diag, SCHEMES[self.convection], KRYLOV_MAX, KRYLOV_RESTART,
            self.periodic_x, self.periodic_y)
        # band (block-tridiagonal) LU: number the unknowns along the shorter direction first (along the
        # periodic one if there is one, so that its wrap-around stays inside a block); the blocks (lines
        # of cells across the other direction) from the pressure/outflow side, where the gas is usually
        # free of particles and its matrix rows change least: after a change only the blocks from the
        # first changed one on are factorised again
        x_fast = self.periodic_x or (not self.periodic_y and nx < ny)
        bw = nx if x_fast else ny
        I, J = np.meshgrid(np.arange(nx), np.arange(ny), indexing="ij")  # unknown i ny + j ...
        open_sides = (PRESSURE, OUTFLOW)
        lo_side, hi_side = ("bottom", "top") if x_fast else ("left", "right")
        if self.boundaries[hi_side].flag in open_sides and self.boundaries[lo_side].flag not in open_sides:
            J, I = (ny - 1 - J, I) if x_fast else (J, nx - 1 - I)
        self._order = ((J * nx + I) if x_fast else (I * ny + J)).ravel().astype(np.int64)  # ... is band row
        both_periodic = self.periodic_x and self.periodic_y
        choice = self._linear_solver
        if choice == "auto":
            choice = "band" if bw <= BAND_MAX and not both_periodic else "multigrid"
        solver = {"band": lay.SOLVER_BAND, "multigrid": lay.SOLVER_MULTIGRID, "superlu": lay.SOLVER_SUPERLU}[choice]
        self._mg = None
        if solver == lay.SOLVER_MULTIGRID:
            self._mg = multigrid_arrays(nx, ny, self.periodic_x, self.periodic_y, self._indices, self._indptr, COARSEST,
                                        KRYLOV_RESTART)
            if self._mg is None:
                solver = lay.SOLVER_SUPERLU
            else:
                self._ipar[lay.I_LEVELS] = self._mg.MGL.shape[1] - 1
        if self._mg is None:
            self._mg = no_multigrid()
        self._ipar[lay.I_SOLVER] = solver
        self._ipar[lay.I_BW] = bw
        banded = solver == lay.SOLVER_BAND
        # block-tridiagonal LU; each block's rows padded with zeros to a multiple of 4 entries where the
        # work rows (n long) hold them: the elimination's row operations then fill whole vectors
        bwp = -(-bw // 4) * 4
        self._band = np.zeros((n // bw, bw, bwp if bwp <= n else bw) if banded else (1, 1, 1))
        self._band_lu = np.zeros((2, n // bw, bw) if banded else (2, 1, 1))
        self._csc_indices = self._indices.astype(np.int64)
        self._csc_indptr = self._indptr.astype(np.int64)
        self._csc_block = self._order[self._csc_indices] // bw  # band: block of each matrix entry's row
        self._band_place = np.stack([self._order // bw, self._order % bw])  # band: block and place of each unknown
        self._out = np.zeros(lay.N_OUT)
        # step inputs: how each is given (lay.MODE_* in slots lay.IN_*), a 1 x 1 array per input for numbers,
        # an empty array for none
        self._modes = np.zeros(lay.N_IN, np.int64)
        self._scalars = np.zeros((lay.N_IN, 1, 1))
        self._none = np.zeros((0, 0))

    # ------------------------------------------------------------ boundary values
    def _set_boundary_values(self, t: float) -> None:
        """Inflow face velocities (ufix/vfix) and prescribed boundary-cell pressures (pfix) at time t."""
        self._bc_time = t
        for side, _, velocity in self._inflows:
            vel = velocity(t)  # interstitial, positive inward
            if side == "left":
                self.ufix[0] = vel
            elif side == "right":
                self.ufix[-1] = -vel
            elif side == "bottom":
                self.vfix[:, 0] = vel
            else:
                self.vfix[:, -1] = -vel
        for side, bc in self._pressure_sides:
            p = bc.prescribed_pressure(t)
            p = self.props.reference_pressure if p is None else p
            self.pfix[self._ghost_index(side)] = p - self.props.reference_pressure  # gauge

    # ------------------------------------------------------------ initial state
    def hydrostatic_pressure(self, t: float = 0.0) -> np.ndarray:
        """(nx, ny) pressure [Pa] of gas at rest under gravity, in exact discrete balance.

        Anchored at the prescribed pressure of the first ``PressureOutlet`` side (top
        first), at its boundary-cell centres; without one, at ``reference_pressure`` in
        the domain centre. Ideal gas: p = p_a exp(k·(x − x_a)), the exponential of
        M g/(RT) as the staggered balance of eqs 43-44 gives it; constant density:
        p = p_a + ρ g·(x − x_a).
        """
        gd = self.grid
        X, Y = gd.centres()
        sides = sorted(self._pressure_sides, key=lambda s: s[0] != "top")
        if sides:
            side, bc = sides[0]
            p_a = bc.prescribed_pressure(t)
            p_a = self.props.reference_pressure if p_a is None else p_a
            x_a, y_a = {"left": (-0.5 * gd.dx, 0.5 * gd.size[1]), "right": (gd.size[0] + 0.5 * gd.dx, 0.5 * gd.size[1]),
                        "bottom": (0.5 * gd.size[0], -0.5 * gd.dy),
                        "top": (0.5 * gd.size[0], gd.size[1] + 0.5 * gd.dy)}[side]
        else:
            p_a, x_a, y_a = self.props.reference_pressure, 0.5 * gd.size[0], 0.5 * gd.size[1]
        gx, gy = self.gravity
        if not self.props.ideal:
            return p_a + self.props.density * (gx * (X - x_a) + gy * (Y - y_a))
        f = self.props.compressibility

        def rate(g, h):  # p_{+1}/p = (1 + g h f/2)/(1 - g h f/2) across one face
            a = 0.5 * g * h * f
            return math.log((1.0 + a) / (1.0 - a)) / h

        return p_a * np.exp(rate(gx, gd.dx) * (X - x_a) + rate(gy, gd.dy) * (Y - y_a))

    def initial_state(self, voidage=1.0, velocity=(0.0, 0.0), pressure=None, t: float = 0.0) -> GasState:
        """A ``GasState`` that meets the boundary conditions at time ``t`` [s].

        Parameters
        ----------
        voidage : float or (nx, ny) array
            ε [-], in (0, 1].
        velocity : (ux, uy) numbers or (u (nx+1, ny), v (nx, ny+1)) arrays
            Interstitial gas velocity [m/s]; boundary faces are overwritten by the
            boundary conditions (walls 0, inflow as prescribed).
        pressure : None, float or (nx, ny) array
            [Pa]; None: hydrostatic (``hydrostatic_pressure``).
        """
        gd = self.grid
        eps = self._centre_array("voidage", voidage)
        self._check_voidage(eps)
        ux, uy = velocity
        u = self._face_array("velocity[0]", ux, gd.u_shape, centre_ok=False).copy()
        v = self._face_array("velocity[1]", uy, gd.v_shape, centre_ok=False).copy()
        p = self.hydrostatic_pressure(t) if pressure is None else self._centre_array("pressure", pressure).copy()
        if not np.all(p > 0.0) and self.props.ideal:
            raise CaseError("gas initial pressure: must be > 0 [Pa] everywhere for the ideal gas")
        self._set_boundary_values(t)
        fixed_u, fixed_v = self.ukind == lay.FIXED, self.vkind == lay.FIXED
        u[fixed_u] = self.ufix[fixed_u]
        v[fixed_v] = self.vfix[fixed_v]
        if self.periodic_x:
            u[-1] = u[0]
        if self.periodic_y:
            v[:, -1] = v[:, 0]
        return GasState(p=p, rho=self.props.density_at(p) * np.ones(gd.shape), u=u, v=v, voidage=eps.copy())

    # ------------------------------------------------------------ input checks and conversions
    def _centre_array(self, name, value):
        a = np.asarray(value, float)
        if a.ndim == 0:
            return np.full(self.grid.shape, float(a))
        if a.shape != self.grid.shape:
            raise CaseError(f"gas {name}: shape {a.shape} does not match the cell-centre shape {self.grid.shape} "
                            "(nx, ny)")
        return a

    def _face_array(self, name, value, shape, centre_ok=True, periodic=False, axis=0, out=None):
        """A face array from a scalar, a face array of ``shape``, or (centre_ok) a centre array
        averaged onto the faces; written into ``out`` when given."""
        a = np.asarray(value, float)
        if a.ndim == 0:
            if out is None:
                return np.full(shape, float(a))
            out.fill(float(a))
            return out
        if a.shape == shape:
            if out is None:
                return a
            out[...] = a
            return out
        if centre_ok and a.shape == self._shapes[0]:
            out = np.empty(shape) if out is None else out
            (centre_to_x_faces if axis == 0 else centre_to_y_faces)(np.ascontiguousarray(a), periodic, out)
            return out
        allowed = f"{shape} (faces)" + (f" or {self._shapes[0]} (cell centres)" if centre_ok else "")
        raise CaseError(f"gas {name}: shape {a.shape} does not match {allowed}")

    def _check_voidage(self, eps):
        if not (np.all(eps > 0.0) and np.all(eps <= 1.0)):
            bad = float(eps[~((eps > 0.0) & (eps <= 1.0))].ravel()[0])
            raise CaseError(f"gas voidage: value {bad!r} outside (0, 1]")

    def _check_state(self, state: GasState) -> tuple:
        """Shapes, dtype and layout of the state's arrays, returned as the tuple of ``lay.StateArrays`` for
        ``K.step``; arrays found right once are remembered (references) and not checked again while the
        state holds the same objects."""
        ok = self._state_arrays
        if ok is not None and ok.p is state.p and ok.rho is state.rho and ok.voidage is state.voidage \
                and ok.u is state.u and ok.v is state.v:
            return self._state_tuple
        c, fu, fv = self._shapes
        for key, shape in (("p", c), ("rho", c), ("voidage", c), ("u", fu), ("v", fv)):
            a = getattr(state, key, None)
            if not isinstance(a, np.ndarray) or a.shape != shape:
                got = getattr(a, "shape", type(a).__name__)
                raise CaseError(f"gas state.{key}: shape {got} does not match {shape}")
            if a.dtype != np.float64 or not a.flags.c_contiguous:
                raise CaseError(f"gas state.{key}: must be a C-contiguous float64 array (as initial_state makes it), "
                                f"not {a.dtype} {'contiguous' if a.flags.c_contiguous else 'strided'}")
        self._state_arrays = lay.StateArrays(state.p, state.rho, state.u, state.v, state.voidage)
        self._state_tuple = tuple(self._state_arrays)
        return self._state_tuple

    # ------------------------------------------------------------ time step
    def advance(self, state: GasState, dt: float, t: float = 0.0, *, voidage=None, beta=None, solids_u=None,
                solids_v=None, source_u=None, source_v=None, pressure_voidage=None) -> StepInfo:
        """Advance ``state`` in place from time ``t`` to ``t + dt`` [s].

        Parameters
        ----------
        state : GasState
            Fields at time t; overwritten with those at t + dt.
        dt : float
            Time step [s] (Hoomans' DT).
        t : float
            Time at the start of the step [s]; boundary values are taken at t + dt.
        voidage : None, float or (nx, ny) array
            ε at t + dt [-] (Hoomans 1996 eqs 49-50 map it from the particles);
            None keeps ``state.voidage``.
        beta : None, float, (nx, ny) array, or (x-face array, y-face array)
            Interphase momentum-transfer coefficient β ≥ 0 [kg m^-3 s^-1] (eqs 45-46),
            treated implicitly. Centre values are averaged onto faces.
        solids_u, solids_v : None, float, centre or face arrays
            Solids velocity v in β(u − v) [m/s] (eq. 50).
        source_u, source_v : None, float, centre or face arrays
            Explicit momentum source added to the gas [N/m^3] (e.g. minus the drag handed
            to the particles when that is how the coupling is done).
        pressure_voidage : None or (x-face array, y-face array)
            The voidage ε_p,f of the pressure term −ε_p,f ∂p/∂x of eq. 43 on each face, in (0, 1];
            None takes ε_f, the face value of ``voidage``. A coupling whose particles take −V_p ∇p
            gives 1 − (their volume deposited on the face) / V_f, so that the gas loses exactly the
            pressure force the particles gain (``coupling.exchange``).

        Returns
        -------
        StepInfo
            ``converged`` is False when the mass residual ended between ``tolerance`` and its
            square root after ``max_iterations`` corrections.

        Raises
        ------
        CaseError
            Input of the wrong shape or out of range (dt ≤ 0, voidage outside (0, 1], β < 0).
        GasConvergenceError
            The step failed (see the class); ``state`` is left as it was at t.
        """
        c_shape, su, sv = self._shapes
        if not (isinstance(dt, (int, float, np.floating)) and math.isfinite(dt) and dt > 0.0):
            raise CaseError(f"gas time step dt = {_show(dt)}: must be > 0 [s]")
        st = self._check_state(state)
        modes = self._modes
        if voidage is None:
            eps_new = state.voidage
            modes[lay.IN_VOIDAGE] = lay.MODE_NONE
        else:
            eps_new = voidage
            if not _ready(eps_new, c_shape):
                eps_new = np.ascontiguousarray(self._centre_array("voidage", voidage), dtype=float)
            modes[lay.IN_VOIDAGE] = lay.MODE_CENTRE
        if isinstance(solids_u, (tuple, list)) or isinstance(solids_v, (tuple, list)):
            raise CaseError("gas solids_u / solids_v: give one array each (faces or centres), not a pair")
        if isinstance(beta, (tuple, list)) and len(beta) == 2:
            bu, bv = (b if _ready(b, shape) else
                      np.ascontiguousarray(self._face_array(f"beta[{k}]", b, shape, centre_ok=False), dtype=float)
                      for k, (b, shape) in enumerate(zip(beta, (su, sv))))
            modes[lay.IN_BETA] = lay.MODE_FACE
        else:
            modes[lay.IN_BETA], bu = self._input("beta", beta, su, lay.IN_BETA)
            bv = bu
            if modes[lay.IN_BETA] == lay.MODE_FACE:
                self._face_array("beta", bu, sv)  # raises: one face array cannot serve both directions
        modes[lay.IN_SOLIDS_U], us = self._input("solids_u", solids_u, su, lay.IN_SOLIDS_U)
        modes[lay.IN_SOLIDS_V], vs = self._input("solids_v", solids_v, sv, lay.IN_SOLIDS_V)
        modes[lay.IN_SOURCE_U], qu = self._input("source_u", source_u, su, lay.IN_SOURCE_U)
        modes[lay.IN_SOURCE_V], qv = self._input("source_v", source_v, sv, lay.IN_SOURCE_V)
        self._ipar[lay.I_PRESSURE_VOIDAGE] = 0 if pressure_voidage is None else self._load_pressure_voidage(
            pressure_voidage, su, sv)
        if self._time_dependent:  # prescribed pressures at t and t + dt, inflow velocities at t + dt
            if t != self._bc_time:
                self._set_boundary_values(t)
            self.C[lay.C_PFIX_OLD] = self.C[lay.C_PFIX]
            self._set_boundary_values(t + dt)
        fpar, ipar, out = self._fpar, self._ipar, self._out
        dt = float(dt)
        # the whole step in one compiled call, again after each SuperLU factorisation
        status = K.step(False, dt, st, eps_new, bu, bv, us, vs, qu, qv, modes, *self._groups, fpar, ipar, out)
        while status == lay.NEED_FACTORS:
            self._factorise()
            status = K.step(True, dt, st, eps_new, bu, bv, us, vs, qu, qv, modes, *self._groups, fpar, ipar, out)
        if status == lay.BAD_VOIDAGE:
            self._check_voidage(eps_new)
        if status == lay.BAD_BETA:
            raise CaseError("gas beta: must be finite and >= 0 [kg m^-3 s^-1] on every face")
        o = out.tolist()
        rel = o[lay.O_REL]
        if status == lay.NOT_FINITE or rel > self._sqrt_tolerance:  # ``K.step`` left the state as it was
            what = "is not finite" if status == lay.NOT_FINITE else f"did not converge (mass residual {rel:.3g})"
            raise GasConvergenceError(
                f"gas step from t = {t:.6g} s with dt = {dt:g} s {what}; Courant number {o[lay.O_COURANT]:.3g}: "
                "keep it below 1 (0.5 with convection='tvd'), see GasSolver.max_time_step")
        return StepInfo(iterations=int(ipar[lay.I_ITER]), mass_residual=rel, converged=rel <= self.tolerance,
                        inflow_rate=o[lay.O_IN], outflow_rate=o[lay.O_OUT], mass=o[lay.O_MASS],
                        mass_change_rate=o[lay.O_ACC], courant=o[lay.O_COURANT])

    def _load_pressure_voidage(self, value, su, sv) -> int:
        """Copy the (x-face, y-face) pair ``pressure_voidage`` into the face stacks; CaseError if wrong."""
        if not (isinstance(value, (tuple, list)) and len(value) == 2):
            raise CaseError("gas pressure_voidage: give a pair (x-face array, y-face array)")
        eu, ev = value
        if not (_ready(eu, su) and _ready(ev, sv)):
            eu, ev = (np.ascontiguousarray(a, dtype=float) for a in value)
            for k, (a, shape) in enumerate(((eu, su), (ev, sv))):
                if a.shape != shape:
                    raise CaseError(f"gas pressure_voidage[{k}]: shape {a.shape}, expected {shape}")
        if not K.load_pressure_voidage(eu, ev, self.FU, self.FV):
            both = np.concatenate([eu.ravel(), ev.ravel()])
            bad = both[~((both > 0.0) & (both <= 1.0))]
            raise CaseError(f"gas pressure_voidage: {bad.size} face values outside (0, 1], e.g. {float(bad[0])!r}; "
                            "each must lie in (0, 1]")
        return 1

    def _input(self, name, value, face_shape, slot, centre_ok=True):
        """(mode, array) of a step input for ``K.load_inputs``: lay.MODE_NONE, MODE_SCALAR (the number in a
        1 × 1 array), MODE_CENTRE or MODE_FACE with a C-contiguous float64 array; a CaseError for a wrong shape."""
        if value is None:
            return lay.MODE_NONE, self._none
        a = value if type(value) is np.ndarray else np.asarray(value, float)
        if a.ndim == 0:
            buf = self._scalars[slot]
            buf[0, 0] = a
            return lay.MODE_SCALAR, buf
        if a.dtype != _F64 or not a.flags.c_contiguous:
            a = np.ascontiguousarray(a, dtype=float)
        if a.shape == face_shape:
            return lay.MODE_FACE, a
        if centre_ok and a.shape == self._shapes[0]:
            return lay.MODE_CENTRE, a
        self._face_array(name, a, face_shape, centre_ok)  # raises the CaseError of a wrong shape
        raise AssertionError("unreachable")

    def _factorise(self) -> None:
        """Factorise the assembled pressure-correction matrix (SuperLU) and keep its factors as CSC arrays
        for the compiled triangular solves."""
        n = self.grid.nx * self.grid.ny
        A = sp.csc_matrix((self._data.copy(), self._indices, self._indptr), shape=(n, n))
        lu = spla.splu(A, permc_spec="MMD_AT_PLUS_A")
        L = sp.tril(lu.L, k=-1, format="csc")
        Uu = lu.U.tocsc()
        Us = sp.triu(Uu, k=1, format="csc")
        lui = np.zeros((4, n + 1), np.int64)
        lui[LK.L_LP] = L.indptr
        lui[LK.L_UP] = Us.indptr
        lui[LK.L_PERM_R, :n] = lu.perm_r
        lui[LK.L_PERM_C, :n] = lu.perm_c
        self._factors = lay.LUFactors(lui, L.indices.astype(np.int64), L.data.copy(), Us.indices.astype(np.int64),
                                      Us.data.copy(), Uu.diagonal().copy())
        self._lu_data[:] = self._data
        self._ipar[lay.I_HAVE_LU] = 1
        self._ipar[lay.I_NFACT] += 1
        self._set_groups()

    # ------------------------------------------------------------ checkpoint
    FACTOR_NAMES = ("lu_index", "l_indices", "l_data", "u_indices", "u_data", "u_diagonal")

    def checkpoint_arrays(self) -> dict[str, np.ndarray]:
        """The pressure-matrix factors a step starts from, for checkpoints.

        A step's Newton corrections use factors of an earlier matrix while the new one differs from it by
        less than ``jacobian_reuse``, so the converged state depends, within the tolerance, on which
        matrix was factorised when. A run resumed with fresh factors then drifts from the uninterrupted run
        at the tolerance's level, and a bubbling bed, being chaotic, makes that a different flow within a
        second (tsuji-jet-background: particles 0.14 m apart 0.1 s after a resume). With these arrays restored
        (``restore_factors``) the resumed run goes on bit for bit. The band and SuperLU paths (the
        multigrid makes its hierarchy anew every iteration, on 3D grids every step)."""
        ipar = self._ipar
        out = {"matrix": self.MAT, "band": self._band, "band_lu": self._band_lu,
               "flags": np.array([ipar[lay.I_HAVE_LU], ipar[lay.I_SOLVER]], np.int64)}
        out.update(zip(self.FACTOR_NAMES, self._factors))
        return out

    def restore_factors(self, arrays: dict[str, np.ndarray]) -> None:
        """Take back ``checkpoint_arrays`` (a CaseError when they are not this solver's: another grid or
        boundaries, whose matrix has other entries)."""
        for name, mine in (("matrix", self.MAT), ("band", self._band), ("band_lu", self._band_lu)):
            if arrays[name].shape != mine.shape:
                raise CaseError(f"checkpoint gas solver {name}: shape {arrays[name].shape}, this case's is "
                                f"{mine.shape} (a checkpoint of another grid or boundaries)")
        self.MAT[...] = arrays["matrix"]
        self._band[...] = arrays["band"]
        self._band_lu[...] = arrays["band_lu"]
        have_lu, solver = (int(x) for x in arrays["flags"])
        if solver in (lay.SOLVER_SUPERLU, lay.SOLVER_BAND, lay.SOLVER_MULTIGRID):
            self._ipar[lay.I_SOLVER] = solver
        else:  # a code the kernels do not know (3: written by the pyamg path): no factors to take back
            have_lu = 0
        self._ipar[lay.I_HAVE_LU] = have_lu
        self._factors = lay.LUFactors(*(np.ascontiguousarray(arrays[k]) for k in self.FACTOR_NAMES))
        self._set_groups()

    @property
    def factorisations(self) -> int:
        """Pressure-matrix factorisations so far (band or SuperLU; multigrid: hierarchies made)."""
        return int(self._ipar[lay.I_NFACT])

    @property
    def linear_solver(self) -> str:
        """'band' (compiled band LU), 'multigrid' (compiled GMRES with a multigrid preconditioner) or
        'superlu' (SciPy), whichever solves the pressure-correction equations now."""
        return {lay.SOLVER_BAND: "band", lay.SOLVER_MULTIGRID: "multigrid"}.get(int(self._ipar[lay.I_SOLVER]),
                                                                                "superlu")

    @property
    def krylov_iterations(self) -> int:
        """GMRES iterations so far (multigrid path; 0 otherwise)."""
        return int(self._ipar[lay.I_KRYLOV])

    # ------------------------------------------------------------ helpers
    def max_time_step(self, state: GasState, courant: float = 0.5) -> float:
        """Largest dt [s] of the explicit terms for ``state``: Courant number ``courant`` and
        viscous number ν dt (2/dx² + 2/dy²) ≤ 1/2 (drag and pressure are implicit)."""
        gd = self.grid
        rate = np.abs(state.u).max() / gd.dx + np.abs(state.v).max() / gd.dy
        nu = self.props.viscosity / max(float(state.rho.min()), 1e-300)
        dt_c = courant / rate if rate > 0.0 else math.inf
        dt_v = 0.5 / (nu * (2.0 / gd.dx**2 + 2.0 / gd.dy**2)) if nu > 0.0 else math.inf
        return min(dt_c, dt_v)


__all__ = ["GasProperties", "GasState", "GasSolver", "StepInfo", "GasConvergenceError",
           "GAS_CONSTANT"]
