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
about proportional to the number of cells), by SciPy's SuperLU, or (``"pyamg"``, on request)
by flexible GMRES preconditioned by an algebraic multigrid hierarchy of the pyamg library. One
step is three compiled calls (``start_step``, ``iterate``, ``end_step``); the rest of
``advance`` checks and classifies its inputs (with "pyamg" the iterations are a Python loop
over the compiled pieces of ``iterate``, the linear solves in pyamg).

Inside the solver the pressure is kept relative to ``reference_pressure``, so that
gradients of a few Pa/m in 1e5 Pa keep their digits; ``GasState.p`` is absolute.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Mapping

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..errors import CaseError
from . import _solver_kernels as K
from ._operators import TVD, UPWIND, centre_to_x_faces, centre_to_y_faces
from .boundaries import BoundaryCondition
from .grid import (FREE_SLIP, INFLOW, NO_SLIP, OUTFLOW, PERIODIC, PRESSURE, SIDES, StaggeredGrid,
                   check_sides)

GAS_CONSTANT = 8.314462618  # R [J mol^-1 K^-1]
_F64 = np.dtype(np.float64)
SCHEMES = {"upwind": UPWIND, "tvd": TVD}
SLOW_CONVERGENCE = 0.3  # refactorise the pressure matrix when an iteration cuts the residual by less than this
BAND_MAX = 64  # band LU (compiled) up to this half-width; multigrid-preconditioned GMRES beyond
LINEAR_SOLVERS = ("auto", "band", "multigrid", "superlu", "pyamg")
SOLVER_PYAMG = 3  # ipar[K.I_SOLVER] of the pyamg path (Python loop; the kernels never see it)
KRYLOV_REDUCTION = 1e-4  # multigrid path: each correction solves the linear system to this fraction of its residual
KRYLOV_RESTART = 30  # GMRES restart length
KRYLOV_MAX = 300  # GMRES iterations of one correction before the multigrid path gives way to SuperLU
COARSEST = 64  # cells of the coarsest multigrid level (dense LU) at most
AMG_RATE = 0.1  # pyamg path: keep the hierarchy while FGMRES cuts the residual at least this much per iteration


def _ready(a, shape) -> bool:
    """``a`` is a C-contiguous float64 ndarray of ``shape``: a kernel input as it is."""
    return type(a) is np.ndarray and a.shape == shape and a.dtype == _F64 and a.flags.c_contiguous


def _import_pyamg():
    """The pyamg module, or the CaseError of ``linear_solver = "pyamg"`` without it."""
    try:
        import pyamg
        import pyamg.krylov  # noqa: F401
    except ImportError as err:
        raise CaseError(f"gas.linear_solver = 'pyamg': the pyamg package is not installed ({err}); "
                        "pip install pyamg, or use 'multigrid' or 'superlu'") from None
    return pyamg


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
    """

    p: np.ndarray
    rho: np.ndarray
    u: np.ndarray
    v: np.ndarray
    voidage: np.ndarray

    def copy(self) -> "GasState":
        return GasState(*(getattr(self, k).copy() for k in ("p", "rho", "u", "v", "voidage")))

    def arrays(self) -> dict[str, np.ndarray]:
        return {k: getattr(self, k) for k in ("p", "rho", "u", "v", "voidage")}


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
        which makes its hierarchy anew every iteration, nor by pyamg, which solves with the
        current matrix and keeps its hierarchy (a preconditioner) while it works well.
    linear_solver : {"auto", "band", "multigrid", "superlu", "pyamg"}
        Solution of the pressure-correction equations: "band", a compiled band LU without
        pivoting (the matrix is diagonally dominant; the unknowns are numbered along the
        shorter or the periodic direction first, so the half-width is min(nx, ny));
        "multigrid", compiled GMRES preconditioned by an aggregation multigrid V-cycle
        (each correction solved to 1e-4 of its residual; the Newton iterations still stop
        at ``tolerance``), for large grids; "superlu", SciPy's SuperLU with its factors
        applied by compiled triangular solves. "auto": the band up to a half-width of 64
        cells unless both directions are periodic, multigrid beyond. Band and multigrid
        give way to SuperLU if they fail (a poor pivot, a stalled GMRES). "pyamg" (needs
        the pyamg package; not chosen by "auto", slower than "multigrid" on the benchmark
        beds): pyamg's flexible GMRES on the current matrix, preconditioned by a classical
        (Ruge-Stüben) algebraic multigrid V-cycle, each correction solved to the residual
        of "multigrid"; the hierarchy is kept over iterations and steps until GMRES with it
        slows down (see ``_iterate_pyamg``); a CaseError naming the key if pyamg is missing
        or fails. Its vector operations go through NumPy's BLAS: on a few shared cores,
        OPENBLAS_NUM_THREADS=1 made it about six times faster at 150 x 300.

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
    """

    def __init__(self, grid: StaggeredGrid, props: GasProperties, boundaries: Mapping[str, BoundaryCondition],
                 gravity=(0.0, -9.81), convection: str = "upwind", tolerance: float = 1e-10,
                 max_iterations: int = 50, jacobian_reuse: float = 1e-2, linear_solver: str = "auto"):
        if not isinstance(grid, StaggeredGrid):
            raise CaseError(f"gas.grid = {grid!r}: must be a StaggeredGrid(cells=..., size=..., depth=...)")
        if not isinstance(props, GasProperties):
            raise CaseError(f"gas properties = {props!r}: must be GasProperties(...)")
        check_sides(boundaries)
        g = np.asarray(gravity, float).ravel()
        if g.size not in (2, 3) or not np.all(np.isfinite(g)) or (g.size == 3 and g[2] != 0.0):
            raise CaseError(f"gravity = {_show(gravity)}: must be (gx, gy) or (gx, gy, 0) [m/s^2] for a 2D gas grid")
        if convection not in SCHEMES:
            raise CaseError(f"gas.convection = {convection!r}: allowed are {sorted(SCHEMES)}")
        if not (isinstance(tolerance, (int, float)) and 0.0 < tolerance < 1.0):
            raise CaseError(f"gas.tolerance = {tolerance!r}: must be in (0, 1)")
        if not (isinstance(max_iterations, int) and max_iterations >= 1):
            raise CaseError(f"gas.max_iterations = {max_iterations!r}: must be an integer >= 1")
        if not (0.0 <= jacobian_reuse < 1.0):
            raise CaseError(f"gas.jacobian_reuse = {jacobian_reuse!r}: must be in [0, 1)")
        if linear_solver not in LINEAR_SOLVERS:
            raise CaseError(f"gas.linear_solver = {linear_solver!r}: allowed are "
                            + ", ".join(repr(k) for k in LINEAR_SOLVERS))
        if linear_solver == "band" and all(boundaries[s].flag == PERIODIC for s in SIDES):
            raise CaseError("gas.linear_solver = 'band': not with periodic sides in both directions; use 'superlu'")
        self._pyamg = _import_pyamg() if linear_solver == "pyamg" else None
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
        self.C[K.C_PFIX_OLD] = self.C[K.C_PFIX]
        self._shapes = (grid.shape, grid.u_shape, grid.v_shape)
        self._state_ok = None  # the state arrays _check_state found right
        self._set_iterate_args()

    def _set_iterate_args(self):
        """The arguments of ``K.iterate``, all persistent arrays (the SuperLU factors change in ``_factorise``)."""
        self._iterate_args = (self.U, self.V, self.C, self.FU, self.FV, self.KU, self.KV, self.row_of, self.flags,
                              self.RULES, self.VEC, self.MAT, self.diag_pos, self.upos, self.vpos, self.pin_pos,
                              *self._factors, self._band, self._band_lu, self._order, self._band_place, self._csc_indices,
                              self._csc_indptr, self._csc_block, self._csc_ell, *self._mg, self._fpar, self._ipar,
                              self._out)

    # ------------------------------------------------------------ set-up
    def _setup_faces(self):
        """Face kinds, inward signs and fixed-value weights from the flags."""
        nx, ny, fl = self.grid.nx, self.grid.ny, self.flags
        kind_of_ghost = {FREE_SLIP: K.FIXED, NO_SLIP: K.FIXED, INFLOW: K.FIXED, PRESSURE: K.SOLVED,
                         OUTFLOW: K.OUTFLOW_FACE, PERIODIC: K.SOLVED}

        def kinds(n_faces_along, n_across, ghost_lo, ghost_hi):
            kind = np.full((n_faces_along, n_across), K.SOLVED, np.int8)
            sign = np.zeros((n_faces_along, n_across), np.int8)
            kind[0] = [kind_of_ghost[int(f)] for f in ghost_lo]
            kind[-1] = [K.COPY if f == PERIODIC else kind_of_ghost[int(f)] for f in ghost_hi]
            sign[0] = np.where(ghost_lo == PERIODIC, 0, 1)
            sign[-1] = np.where(ghost_hi == PERIODIC, 0, -1)
            return kind, sign

        uk, us = kinds(nx + 1, ny, fl[0, 1:-1], fl[-1, 1:-1])
        vk, vs = kinds(ny + 1, nx, fl[1:-1, 0], fl[1:-1, -1])
        self.KU = np.stack([uk, us])  # K_KIND, K_SIGN
        self.KV = np.ascontiguousarray(np.stack([vk.T, vs.T]))
        self.ukind, self.ubnd = self.KU[K.K_KIND], self.KU[K.K_SIGN]
        self.vkind, self.vbnd = self.KV[K.K_KIND], self.KV[K.K_SIGN]
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
        self.prule, self.erule = self.RULES[K.RULE_P], self.RULES[K.RULE_E]
        for f in (FREE_SLIP, NO_SLIP, INFLOW, OUTFLOW):
            self.prule[f] = K.R_COPY
        self.prule[PRESSURE] = K.R_FIXED
        self.prule[PERIODIC] = K.R_WRAP
        for f in (FREE_SLIP, NO_SLIP, PRESSURE, OUTFLOW):
            self.erule[f] = K.R_COPY  # Hoomans 1996 §3.5: wall cells copy the adjacent voidage
        self.erule[INFLOW] = K.R_FIXED  # Hoomans 1996 §3.5: fixed voidage in influx cells
        self.erule[PERIODIC] = K.R_WRAP
        self.C = np.zeros((K.N_C, nx + 2, ny + 2))  # stacked centre arrays, slots K.C_*
        self.P, self.RHO, self.E = self.C[K.C_P], self.C[K.C_RHO], self.C[K.C_E]
        self.pfix, self.efix = self.C[K.C_PFIX], self.C[K.C_EFIX]
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
        valid = (rows >= 0) & (cols >= 0) & (kind != K.COPY)[..., None]
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
        self._data, self._lu_data = self.MAT[K.M_DATA], self.MAT[K.M_FACTORED]

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
        self.FU = np.zeros((K.N_F,) + self.grid.u_shape)  # stacked x-face arrays, slots K.F_*
        self.FV = np.zeros((K.N_F,) + self.grid.v_shape)
        self.exu, self.exv = self.FU[K.F_EX], self.FV[K.F_EX]
        self.ufix, self.vfix = self.FU[K.F_FIX], self.FV[K.F_FIX]
        self.wout_u, self.wout_v = self.FU[K.F_WOUT], self.FV[K.F_WOUT]
        self.TAU = np.zeros((nx + 1, ny + 1))  # shear stresses at the corners (work)
        n = nx * ny
        self.VEC = np.zeros((K.N_VEC, n))  # V_R, V_DP, V_WORK, V_WORK2, V_ROW
        self.R = self.VEC[K.V_R]
        self._factors = (np.zeros((4, n + 1), np.int64), np.zeros(1, np.int64), np.zeros(1), np.zeros(1, np.int64),
                         np.zeros(1), np.ones(n))  # LUI, Li, Lx, Ui, Ux, Ud: none yet
        gd = self.grid
        self._fpar = np.zeros(K.N_FPAR)
        self._fpar[K.F_MU] = self.props.viscosity
        self._fpar[K.F_PREF] = self.props.reference_pressure
        self._fpar[[K.F_GX, K.F_GY, K.F_DX, K.F_DY, K.F_AX, K.F_AY, K.F_VOL]] = (
            self.gravity[0], self.gravity[1], gd.dx, gd.dy, gd.area_x, gd.area_y, gd.cell_volume)
        self._fpar[K.F_COMP] = self.props.compressibility
        self._fpar[K.F_RHOC] = 0.0 if self.props.ideal else float(self.props.density)
        self._fpar[K.F_TOL] = self.tolerance
        self._fpar[K.F_REUSE] = self.jacobian_reuse
        self._fpar[K.F_SLOW] = SLOW_CONVERGENCE
        self._fpar[K.F_ETA] = KRYLOV_REDUCTION
        self._ipar = np.zeros(K.N_IPAR, np.int64)
        self._ipar[[K.I_NX, K.I_NY, K.I_MAXIT, K.I_PIN, K.I_SCHEME, K.I_KRYLOV_MAX, K.I_RESTART, K.I_PX, K.I_PY]] = (
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
        solver = {"band": K.SOLVER_BAND, "multigrid": K.SOLVER_MULTIGRID, "superlu": K.SOLVER_SUPERLU,
                  "pyamg": SOLVER_PYAMG}[choice]
        if solver == K.SOLVER_MULTIGRID and not self._setup_multigrid():
            solver = K.SOLVER_SUPERLU
        if solver != K.SOLVER_MULTIGRID:
            self._no_multigrid()
        self._ipar[K.I_SOLVER] = solver
        self._ipar[K.I_BW] = bw
        banded = solver == K.SOLVER_BAND
        # block-tridiagonal LU; each block's rows padded with zeros to a multiple of 4 entries where the
        # work rows (n long) hold them: the elimination's row operations then fill whole vectors
        bwp = -(-bw // 4) * 4
        self._band = np.zeros((n // bw, bw, bwp if bwp <= n else bw) if banded else (1, 1, 1))
        self._band_lu = np.zeros((2, n // bw, bw) if banded else (2, 1, 1))
        self._csc_indices = self._indices.astype(np.int64)
        self._csc_indptr = self._indptr.astype(np.int64)
        self._csc_block = self._order[self._csc_indices] // bw  # band: block of each matrix entry's row
        self._band_place = np.stack([self._order // bw, self._order % bw])  # band: block and place of each unknown
        self._out = np.zeros(9)
        if solver == SOLVER_PYAMG:
            self._setup_pyamg()
        # step inputs: modes (K.IN_*), a 1 x 1 array per input for numbers, an empty array for none
        self._modes = np.zeros(6, np.int64)
        self._scalars = np.zeros((6, 1, 1))
        self._none = np.zeros((0, 0))

    def _no_multigrid(self):
        self._csc_ell = np.zeros(1, np.int64)
        self._mg = (np.zeros((3, 2), np.int64), np.zeros((1, 9), np.int64), np.zeros((1, 5)), np.zeros((4, 1)),
                    np.zeros((1, 1)), np.zeros(1, np.int64), np.zeros((2, 1)), np.zeros((4, 1)))

    def _setup_pyamg(self):
        """The pyamg path: the pressure matrix as CSR (its data gathered from the CSC data through
        ``_amg_gather``), no hierarchy yet."""
        n = self.grid.nx * self.grid.ny
        nnz = self._indices.size
        pattern = sp.csc_matrix((np.arange(nnz, dtype=float), self._indices, self._indptr), shape=(n, n)).tocsr()
        pattern.sort_indices()
        self._amg_gather = pattern.data.astype(np.int64)  # CSR entry k is CSC entry _amg_gather[k]
        self._amg_A = sp.csr_matrix((np.zeros(nnz), pattern.indices.copy(), pattern.indptr.copy()), shape=(n, n))
        self._amg_ml = None  # hierarchy (pyamg MultilevelSolver) of the matrix in self._lu_data
        self._amg_M = None  # its V-cycle as a preconditioner
        self._amg_rate0 = None  # residual reduction per FGMRES iteration of the first solve with it
        self._amg_stale = False  # a later solve converged much slower: make it anew

    @staticmethod
    def _grid_neighbours(a, b, px, py):
        """(a b, 4) neighbours -x, +x, -y, +y of the cells i b + j of an a × b grid (-1: none or itself)."""
        I, J = np.meshgrid(np.arange(a), np.arange(b), indexing="ij")
        me = (I * b + J).ravel()
        out = np.empty((a * b, 4), np.int64)
        for d, (di, dj) in enumerate(((-1, 0), (1, 0), (0, -1), (0, 1))):
            i2, j2 = I + di, J + dj
            if px:
                i2 = i2 % a
            if py:
                j2 = j2 % b
            ok = ((i2 >= 0) & (i2 < a) & (j2 >= 0) & (j2 < b)).ravel()
            k = (i2 * b + j2).ravel()
            out[:, d] = np.where(ok & (k != me), k, -1)
        return out

    def _setup_multigrid(self) -> bool:
        """The multigrid levels (see ``_solver_kernels``: MGL, MGI, ...) and the map of the CSC entries of
        the pressure matrix to its rows; False if the matrix pattern is not the grid's 5-point one."""
        nx, ny, px, py = self.grid.nx, self.grid.ny, self.periodic_x, self.periodic_y
        dims = [(nx, ny)]
        while dims[-1][0] * dims[-1][1] > COARSEST:
            a, b = dims[-1]
            dims.append(((a + 1) // 2, (b + 1) // 2))
        sizes = [a * b for a, b in dims]
        offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
        MGI = np.full((int(offsets[-1]), 9), -1, np.int64)
        nbs = [self._grid_neighbours(a, b, px, py) for a, b in dims]
        for l, (a, b) in enumerate(dims):
            rows = slice(offsets[l], offsets[l + 1])
            MGI[rows, K.MGI_NB:K.MGI_NB + 4] = nbs[l]
            if l + 1 == len(dims):
                break
            bc = dims[l + 1][1]
            I, J = np.meshgrid(np.arange(a), np.arange(b), indexing="ij")
            agg = ((I // 2) * bc + J // 2).ravel()
            MGI[rows, K.MGI_AGG] = agg
            for d in range(4):
                c = nbs[l][:, d]
                has = c >= 0
                ic, jc = agg, agg[np.where(has, c, 0)]
                same = ic == jc
                if np.any(has & ~same & (nbs[l + 1][ic, d] != jc)):
                    return False  # cannot happen on a rectangular grid
                MGI[rows, K.MGI_GAL + d] = np.where(has, (offsets[l + 1] + ic) * 5 + np.where(same, 0, d + 1), -1)
        # CSC entries of the finest level -> (row, slot)
        n = nx * ny
        rows = self._indices.astype(np.int64)
        cols = np.repeat(np.arange(n, dtype=np.int64), np.diff(self._indptr))
        slot = np.full(rows.size, -1, np.int64)
        slot[rows == cols] = 0
        for d in range(3, -1, -1):  # the first matching direction wins
            slot = np.where((rows != cols) & (nbs[0][rows, d] == cols), d + 1, slot)
        if np.any(slot < 0):
            return False
        self._csc_ell = rows * 5 + slot
        m = sizes[-1]
        MGL = np.zeros((3, len(dims) + 1), np.int64)
        MGL[0] = offsets
        MGL[1, :-1] = [a for a, _ in dims]
        MGL[2, :-1] = [b for _, b in dims]
        N = int(offsets[-1])
        self._mg = (MGL, MGI, np.zeros((N, 5)), np.zeros((4, N)), np.zeros((m, m)), np.zeros(m, np.int64),
                    np.zeros((2 * (KRYLOV_RESTART + 1), n)), np.zeros((KRYLOV_RESTART + 4, KRYLOV_RESTART + 1)))
        self._ipar[K.I_LEVELS] = len(dims)
        return True

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
        fixed_u, fixed_v = self.ukind == K.FIXED, self.vkind == K.FIXED
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

    def _check_state(self, state: GasState) -> None:
        """Shapes, dtype and layout of the state's arrays; arrays found right once are remembered
        (references) and not checked again while the state holds the same objects."""
        ok = self._state_ok
        if ok is not None and ok[0] is state.p and ok[1] is state.rho and ok[2] is state.voidage \
                and ok[3] is state.u and ok[4] is state.v:
            return
        c, fu, fv = self._shapes
        for key, shape in (("p", c), ("rho", c), ("voidage", c), ("u", fu), ("v", fv)):
            a = getattr(state, key, None)
            if not isinstance(a, np.ndarray) or a.shape != shape:
                got = getattr(a, "shape", type(a).__name__)
                raise CaseError(f"gas state.{key}: shape {got} does not match {shape}")
            if a.dtype != np.float64 or not a.flags.c_contiguous:
                raise CaseError(f"gas state.{key}: must be a C-contiguous float64 array (as initial_state makes it), "
                                f"not {a.dtype} {'contiguous' if a.flags.c_contiguous else 'strided'}")
        self._state_ok = (state.p, state.rho, state.voidage, state.u, state.v)

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
        self._check_state(state)
        modes = self._modes
        if voidage is None:
            eps_new = state.voidage
            modes[K.IN_VOIDAGE] = K.IN_NONE
        else:
            eps_new = voidage
            if not _ready(eps_new, c_shape):
                eps_new = np.ascontiguousarray(self._centre_array("voidage", voidage), dtype=float)
            modes[K.IN_VOIDAGE] = K.IN_CENTRE
        if isinstance(solids_u, (tuple, list)) or isinstance(solids_v, (tuple, list)):
            raise CaseError("gas solids_u / solids_v: give one array each (faces or centres), not a pair")
        if isinstance(beta, (tuple, list)) and len(beta) == 2:
            bu, bv = (b if _ready(b, shape) else
                      np.ascontiguousarray(self._face_array(f"beta[{k}]", b, shape, centre_ok=False), dtype=float)
                      for k, (b, shape) in enumerate(zip(beta, (su, sv))))
            modes[K.IN_BETA] = K.IN_FACE
        else:
            modes[K.IN_BETA], bu = self._input("beta", beta, su, K.IN_BETA)
            bv = bu
            if modes[K.IN_BETA] == K.IN_FACE:
                self._face_array("beta", bu, sv)  # raises: one face array cannot serve both directions
        modes[K.IN_SOLIDS_U], us = self._input("solids_u", solids_u, su, K.IN_SOLIDS_U)
        modes[K.IN_SOLIDS_V], vs = self._input("solids_v", solids_v, sv, K.IN_SOLIDS_V)
        modes[K.IN_SOURCE_U], qu = self._input("source_u", source_u, su, K.IN_SOURCE_U)
        modes[K.IN_SOURCE_V], qv = self._input("source_v", source_v, sv, K.IN_SOURCE_V)
        self._ipar[K.I_PRESSURE_VOIDAGE] = 0 if pressure_voidage is None else self._load_pressure_voidage(
            pressure_voidage, su, sv)
        if self._time_dependent:  # prescribed pressures at t and t + dt, inflow velocities at t + dt
            if t != self._bc_time:
                self._set_boundary_values(t)
            self.C[K.C_PFIX_OLD] = self.C[K.C_PFIX]
            self._set_boundary_values(t + dt)
        fpar, ipar, out = self._fpar, self._ipar, self._out
        U, V = self.U, self.V
        bad = K.start_step(float(dt), state.p, state.rho, state.u, state.v, state.voidage, eps_new, bu, bv, us, vs, qu,
                           qv, modes, U, V, self.G, self.H, self.C, self.FU, self.FV, self.KU, self.KV, self.flags,
                           self.RULES, fpar, ipar, out, self.TAU)
        if bad == K.BAD_VOIDAGE:
            self._check_voidage(eps_new)
        if bad == K.BAD_BETA:
            raise CaseError("gas beta: must be finite and >= 0 [kg m^-3 s^-1] on every face")
        if self._pyamg is not None:
            status = self._iterate_pyamg()
        else:
            while True:
                status = K.iterate(*self._iterate_args)
                if status == K.NEED_FACTORS:
                    self._factorise()
                    continue
                break
        o = out.tolist()
        rel = o[K.O_REL]
        if status == K.NOT_FINITE or rel > self._sqrt_tolerance:
            what = "is not finite" if status == K.NOT_FINITE else f"did not converge (mass residual {rel:.3g})"
            raise GasConvergenceError(
                f"gas step from t = {t:.6g} s with dt = {dt:g} s {what}; Courant number {o[K.O_COURANT]:.3g}: "
                "keep it below 1 (0.5 with convection='tvd'), see GasSolver.max_time_step")
        K.end_step(state.p, state.rho, state.u, state.v, U, V, self.C, self._p_ref, state.voidage, eps_new)
        return StepInfo(iterations=int(ipar[K.I_ITER]), mass_residual=rel, converged=rel <= self.tolerance,
                        inflow_rate=o[K.O_IN], outflow_rate=o[K.O_OUT], mass=o[K.O_MASS],
                        mass_change_rate=o[K.O_ACC], courant=o[K.O_COURANT])

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
        """(mode, array) of a step input for ``K.load_inputs``: K.IN_NONE, IN_SCALAR (the number in a
        1 × 1 array), IN_CENTRE or IN_FACE with a C-contiguous float64 array; a CaseError for a wrong shape."""
        if value is None:
            return K.IN_NONE, self._none
        a = value if type(value) is np.ndarray else np.asarray(value, float)
        if a.ndim == 0:
            buf = self._scalars[slot]
            buf[0, 0] = a
            return K.IN_SCALAR, buf
        if a.dtype != _F64 or not a.flags.c_contiguous:
            a = np.ascontiguousarray(a, dtype=float)
        if a.shape == face_shape:
            return K.IN_FACE, a
        if centre_ok and a.shape == self._shapes[0]:
            return K.IN_CENTRE, a
        self._face_array(name, a, face_shape, centre_ok)  # raises the CaseError of a wrong shape
        raise AssertionError("unreachable")

    def _iterate_pyamg(self) -> int:
        """``K.iterate`` for the pyamg path: the same Newton iterations from the same compiled pieces
        (residual, the current Jacobian, p += p'), with p' from pyamg's flexible GMRES on the current
        matrix, preconditioned by an algebraic multigrid V-cycle, to the residual target of the
        multigrid path, max(KRYLOV_REDUCTION ||R||, tolerance q_ref / (10 √n)). The hierarchy is only a
        preconditioner: it is kept from iteration to iteration and step to step while FGMRES with it
        reduces the residual per iteration by a factor of at most max(AMG_RATE, √(its factor when new)),
        and made anew otherwise (or when KRYLOV_MAX iterations were not enough with an older one)."""
        nx, ny = self.grid.nx, self.grid.ny
        n = nx * ny
        U, V, C, FU, FV, KU, KV = self.U, self.V, self.C, self.FU, self.FV, self.KU, self.KV
        fpar, ipar, out = self._fpar, self._ipar, self._out
        R, P = self.VEC[K.V_R], self.C[K.C_P]
        data, A, gather = self._data, self._amg_A, self._amg_gather
        it = 0
        while True:
            res, qref, fin, fout, acc, mass = K.predict_residual(U, V, C, FU, FV, KU, KV, self.row_of, R, fpar, ipar)
            rel = res / qref if qref > 0.0 else 0.0
            out[[K.O_RES, K.O_QREF, K.O_IN, K.O_OUT, K.O_ACC, K.O_MASS, K.O_REL]] = (res, qref, fin, fout, acc,
                                                                                      mass, rel)
            ipar[K.I_ITER] = it
            status = (K.NOT_FINITE if not math.isfinite(rel) else K.CONVERGED if rel <= self.tolerance
                      else K.MAX_ITERATIONS if it >= self.max_iterations else -1)
            if status >= 0:
                K.fill_face_ghosts(U, V, self.flags, nx, ny)
                out[K.O_COURANT] = K.courant_number(U, V, fpar, ipar)
                return status
            K.assemble_pressure(data, self.diag_pos, self.upos, self.vpos, self.pin_pos, U, V, C, FU, FV, KU, KV,
                                fpar, ipar)
            np.take(data, gather, out=A.data)
            b = -R
            if self.pin_diag >= 0:
                b[0] = 0.0
            target = max(KRYLOV_REDUCTION * float(np.linalg.norm(b)), 0.1 * self.tolerance * qref / math.sqrt(n))
            fresh = self._amg_ml is None or self._amg_stale
            while True:
                if fresh:
                    self._amg_setup()
                dp, its = self._amg_solve(b, target)
                ipar[K.I_KRYLOV] += its
                if dp is not None:
                    break
                if fresh:
                    raise CaseError(
                        f"gas.linear_solver = 'pyamg': GMRES with the pyamg multigrid preconditioner did not reduce "
                        f"the pressure-correction residual to {target:.3g} in {KRYLOV_MAX} iterations; use "
                        "'multigrid' or 'superlu'")
                fresh = True  # an older hierarchy: make it anew and try again
            P[1:-1, 1:-1] += dp.reshape(nx, ny)
            K.fill_centre_ghosts(P, self.flags, self.RULES[K.RULE_P], C[K.C_PFIX], nx, ny)
            K.update_density(C, fpar[K.F_COMP], fpar[K.F_RHOC], fpar[K.F_PREF])
            it += 1

    def _amg_setup(self) -> None:
        """A pyamg hierarchy (classical Ruge-Stüben AMG, symmetric Gauss-Seidel smoothing) of the current
        pressure matrix; a CaseError if pyamg cannot make one."""
        try:
            self._amg_ml = self._pyamg.ruge_stuben_solver(self._amg_A.copy(), max_coarse=COARSEST)
            self._amg_M = self._amg_ml.aspreconditioner(cycle="V")
        except Exception as err:  # noqa: BLE001 - any failure of the library is the case's to fix
            self._amg_ml = None
            raise CaseError(f"gas.linear_solver = 'pyamg': the pyamg multigrid setup failed "
                            f"({type(err).__name__}: {err}); use 'multigrid' or 'superlu'") from err
        self._amg_rate0 = None
        self._amg_stale = False
        self._lu_data[:] = self._data
        self._ipar[K.I_HAVE_LU] = 1
        self._ipar[K.I_NFACT] += 1

    def _amg_solve(self, b: np.ndarray, target: float):
        """(p', iterations) with ||b - A p'||_2 <= target by pyamg's flexible GMRES (right-preconditioned,
        its test is on the true residual; checked here and continued if its estimate was short), or
        (None, iterations) if KRYLOV_MAX iterations were not enough. Marks the hierarchy stale when the
        residual fell by less than AMG_RATE or the square root of its first rate per iteration."""
        A = self._amg_A
        bn = float(np.linalg.norm(b))
        x = np.zeros_like(b)
        if bn <= target:
            return x, 0
        its, rn = 0, bn
        while rn > target:
            if its >= KRYLOV_MAX:
                return None, its
            residuals = []
            try:
                x, _ = self._pyamg.krylov.fgmres(A, b, x0=x, tol=target / bn, restart=KRYLOV_RESTART,
                                                 maxiter=max(1, (KRYLOV_MAX - its) // KRYLOV_RESTART), M=self._amg_M,
                                                 residuals=residuals)
            except Exception as err:  # noqa: BLE001
                raise CaseError(f"gas.linear_solver = 'pyamg': the pyamg solve failed ({type(err).__name__}: "
                                f"{err}); use 'multigrid' or 'superlu'") from err
            its += max(len(residuals) - 1, 1)
            rn = float(np.linalg.norm(b - A @ x))
            if not math.isfinite(rn):
                return None, its
        rate = (rn / bn) ** (1.0 / max(its, 1))
        if self._amg_rate0 is None:
            self._amg_rate0 = rate
        else:
            self._amg_stale = rate > max(AMG_RATE, math.sqrt(self._amg_rate0))
        return x, its

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
        lui[K.L_LP] = L.indptr
        lui[K.L_UP] = Us.indptr
        lui[K.L_PERM_R, :n] = lu.perm_r
        lui[K.L_PERM_C, :n] = lu.perm_c
        self._factors = (lui, L.indices.astype(np.int64), L.data.copy(), Us.indices.astype(np.int64), Us.data.copy(),
                         Uu.diagonal().copy())
        self._lu_data[:] = self._data
        self._ipar[K.I_HAVE_LU] = 1
        self._ipar[K.I_NFACT] += 1
        self._set_iterate_args()

    # ------------------------------------------------------------ checkpoint
    FACTOR_NAMES = ("lu_index", "l_indices", "l_data", "u_indices", "u_data", "u_diagonal")

    def checkpoint_arrays(self) -> dict[str, np.ndarray]:
        """The pressure-matrix factors a step starts from, for checkpoints.

        A step's Newton corrections use factors of an earlier matrix while the new one differs from it by
        less than ``jacobian_reuse``, so the converged state depends, within the tolerance, on which
        matrix was factorised when. A run resumed with fresh factors then drifts from the uninterrupted run
        at the tolerance's level, and a bubbling bed, being chaotic, makes that a different flow within a
        second (tsuji-jet: particles 0.14 m apart 0.1 s after a resume). With these arrays restored
        (``restore_factors``) the resumed run goes on bit for bit. The band and SuperLU paths; the pyamg
        path keeps a Python hierarchy and starts afresh (a tolerance-level difference, as before)."""
        ipar = self._ipar
        out = {"matrix": self.MAT, "band": self._band, "band_lu": self._band_lu,
               "flags": np.array([ipar[K.I_HAVE_LU], ipar[K.I_SOLVER]], np.int64)}
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
        if solver == SOLVER_PYAMG or self._ipar[K.I_SOLVER] == SOLVER_PYAMG:
            have_lu = 0  # the pyamg hierarchy is not in the checkpoint: made anew
        else:
            self._ipar[K.I_SOLVER] = solver
        self._ipar[K.I_HAVE_LU] = have_lu
        self._factors = tuple(np.ascontiguousarray(arrays[k]) for k in self.FACTOR_NAMES)
        self._set_iterate_args()

    @property
    def factorisations(self) -> int:
        """Pressure-matrix factorisations so far (band or SuperLU; multigrid and pyamg: hierarchies made)."""
        return int(self._ipar[K.I_NFACT])

    @property
    def linear_solver(self) -> str:
        """'band' (compiled band LU), 'multigrid' (compiled GMRES with a multigrid preconditioner),
        'superlu' (SciPy) or 'pyamg' (FGMRES with pyamg's algebraic multigrid), whichever solves the
        pressure-correction equations now."""
        return {K.SOLVER_BAND: "band", K.SOLVER_MULTIGRID: "multigrid",
                SOLVER_PYAMG: "pyamg"}.get(int(self._ipar[K.I_SOLVER]), "superlu")

    @property
    def krylov_iterations(self) -> int:
        """GMRES iterations so far (multigrid and pyamg paths; 0 otherwise)."""
        return int(self._ipar[K.I_KRYLOV])

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


# ================================================================ benchmark
def gas_step_benchmark(grids=((15, 25), (39, 60), (150, 300)), seconds: float = 2.0, convection: str = "upwind",
                       moving_bed: tuple[bool, ...] = (False, True), verbose: bool = False,
                       linear_solver: str = "auto") -> list[dict]:
    """Wall time of one gas step on standard grids; rows for ``fluidem bench``.

    The problem is the Hoomans 1996 single-orifice bed (Table 2 geometry 0.15 m ×
    0.5 m, scaled to each grid): ideal gas, jet of 45 m/s interstitial in the centre
    of the bottom (4.5 m/s elsewhere) through influx cells of voidage 0.4, no-slip
    side walls, pressure outlet on top, a bed of voidage 0.4 in the lower 0.2 m with
    Ergun's β (eq. 45, d_p = 4 mm) recomputed from the gas velocity every step, as a
    coupled run would. ``moving_bed``: whether the bed's voidage also changes every step
    (a surface wave and a rising bubble, 0.5 m/s), which changes the pressure matrix
    as particles do. The time step is Hoomans' DT = 1e-4 s, or less where the jet would
    cross more than half the smaller cell side in a step (explicit convection):
    dt = min(1e-4, 0.5 min(dx, dy) / 45 m/s). The first 20 steps (compilation, start-up
    transient) are not timed; then ``advance`` alone is timed for about ``seconds`` per row.
    ``linear_solver``: the ``GasSolver`` option (e.g. "pyamg" against "multigrid").

    Returns
    -------
    list of dict
        One row per grid and bed: problem, grid, cells, dt_s, linear_solver, steps,
        ms_per_step, iterations_per_step (pressure corrections), factorisations_per_step.
    """
    rows = []
    for nx, ny in grids:
        for moving in moving_bed:
            solver, state, beta_of, voidage_at = _bench_problem(nx, ny, convection, linear_solver)
            t, dt = 0.0, min(1e-4, 0.5 * min(solver.grid.dx, solver.grid.dy) / 45.0)
            for _ in range(20):
                solver.advance(state, dt, t, voidage=voidage_at(t + dt) if moving else None, beta=beta_of(state),
                               solids_u=0.0, solids_v=0.0)
                t += dt
            n, its, fac0, elapsed, wall0 = 0, 0, solver.factorisations, 0.0, time.perf_counter()
            while (time.perf_counter() - wall0 < seconds or n < 3) and n < 100000:
                beta = beta_of(state)  # the coupling's work, not timed
                eps = voidage_at(t + dt) if moving else None
                t0 = time.perf_counter()
                info = solver.advance(state, dt, t, voidage=eps, beta=beta, solids_u=0.0, solids_v=0.0)
                elapsed += time.perf_counter() - t0
                t += dt
                n += 1
                its += info.iterations
            row = {"problem": f"gas step, jet bed, {'moving' if moving else 'fixed'} voidage ({convection})",
                   "grid": f"{nx}x{ny}", "cells": nx * ny, "dt_s": dt, "linear_solver": solver.linear_solver,
                   "steps": n, "ms_per_step": 1e3 * elapsed / n,
                   "iterations_per_step": its / n, "factorisations_per_step": (solver.factorisations - fac0) / n}
            rows.append(row)
            if verbose:
                print(f"{row['grid']:>8} {'moving' if moving else 'fixed ':6} dt {dt:.2g} s {row['linear_solver']:>7}"
                      f"  {row['ms_per_step']:9.3f} ms/step  {row['iterations_per_step']:.2f} it/step  "
                      f"{row['factorisations_per_step']:.3f} LU/step", flush=True)
    return rows


def _bench_problem(nx: int, ny: int, convection: str = "upwind", linear_solver: str = "auto"):
    """Solver, state, β(state) and voidage(t) of the benchmark bed on an nx × ny grid."""
    from .boundaries import Inflow, PressureOutlet, Segment, Wall

    grid = StaggeredGrid(cells=(nx, ny), size=(0.15, 0.5), depth=0.004)
    props = GasProperties()
    bcs = {"left": Wall(), "right": Wall(), "top": PressureOutlet(pressure=101325.0),
           "bottom": Inflow(segments=(Segment(interstitial=4.5), Segment(interstitial=45.0, start=0.07, end=0.08)),
                            voidage=0.4)}
    solver = GasSolver(grid, props, bcs, convection=convection, linear_solver=linear_solver)
    X, Y = grid.centres()
    state = solver.initial_state(voidage=np.where(Y < 0.2, 0.4, 1.0))
    d_p = 4e-3
    mu = props.viscosity

    def beta_of(st: GasState) -> np.ndarray:
        uc = 0.5 * (st.u[1:] + st.u[:-1])
        vc = 0.5 * (st.v[:, 1:] + st.v[:, :-1])
        slip = np.hypot(uc, vc)
        e = st.voidage
        # Hoomans 1996 eq. 45 (Ergun) in the bed; no particles above it
        b = 150.0 * (1 - e) ** 2 / e * mu / d_p**2 + 1.75 * (1 - e) * st.rho / d_p * slip
        return np.where(e < 0.8, b, 0.0)

    def voidage_at(t: float) -> np.ndarray:
        surface = 0.2 + 0.01 * np.sin(2 * np.pi * (X / 0.15 - t / 0.2))
        bed = 0.4 + 0.6 / (1.0 + np.exp(-(Y - surface) / 0.01))
        r = np.hypot(X - 0.075, Y - (0.05 + 0.5 * t) % 0.15)
        return np.clip(bed + 0.4 / (1.0 + np.exp((r - 0.02) / 0.005)), 0.4, 1.0)

    return solver, state, beta_of, voidage_at


__all__ = ["GasProperties", "GasState", "GasSolver", "StepInfo", "GasConvergenceError", "gas_step_benchmark",
           "GAS_CONSTANT"]
