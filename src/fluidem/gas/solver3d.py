"""The volume-averaged gas phase (Hoomans 1996 eqs 42-48) on a 3D staggered grid.

``GasSolver(grid, ...)`` with a 3D ``StaggeredGrid`` (three ``cells`` entries) makes a ``GasSolver3D``: the
same interface, equations and pressure-correction scheme as the 2D solver (``solver.py``; read its module
docstring for the scheme), on arrays with a third axis. ``advance(state, dt, t, ...)`` moves a ``GasState``
with ``w`` (z velocity on z-faces) from t to t + dt; the particle side enters only as arrays: voidage,
β with the solids velocity (``solids_u``, ``solids_v``, ``solids_w``) and an explicit momentum source
(``source_u``, ``source_v``, ``source_w``). The loops over cells and faces are the compiled kernels of
``_solver3d_kernels``; here the Newton iterations of a step are driven one kernel call at a time (a few
calls per iteration, nothing per cell). With more than one Numba thread in use the kernels' passes over the
grid run one x plane per work item on the threads; the sums stay serial in grid order, so a step gives the
same fields, bit for bit, on any number of threads (``tests/unit/test_gas3d_threads.py``).

The pressure corrections are solved (``linear_solver``) by GMRES with an aggregation multigrid
(``_multigrid3d_kernels``, 7-point stencil, 2 cells per coarse cell along the strongly coupled axes:
``_multigrid3d.py``; 3 to 4 iterations per correction from 1e4 to 1e6 cells, the step's cost per cell
1.6 to 2.2 times higher at 1e6 than at 1e4 cells, ``benchmarks/README.md``; "multigrid")
or by SciPy's SuperLU ("superlu", its factors kept from step to step while the matrix changes by less
than ``jacobian_reuse``); "auto" is the multigrid, which gives way to SuperLU if it fails. On the multigrid
path a step's Newton iterations run in one compiled call (``_solver3d_kernels.newton_multigrid``); an iteration
after one that cut the mass residual to at most ``CHORD_REDUCTION`` of what it was keeps that iteration's
Jacobian and hierarchy (a chord step: on ``bubbling-3d`` the second iteration of every step, which saves one
assembly and one hierarchy a step with the same GMRES iterations; ``tests/unit/test_gas3d_chord.py``). Measured on the
3D bubbling bed of ``benchmarks/gas3d_step.py`` (ideal gas, moving voidage), the multigrid took less CPU
time per step than SuperLU on every grid: 0.32 against 0.36 ms at 288 cells, 0.88 against 1.7 ms at 1200,
9.9 against 190 ms at 1e4 (SuperLU's fill-in grows fast in 3D).

Where later physics goes (no rewrite needed):

* a body force per face (the virtual force of immersed boundaries, DEM book 2012 two-phase chapter, IBM
  eqs 1-10) is one more explicit momentum source: it adds to ``F[F_RHS]`` like ``source_u/v/w`` (the
  per-face arrays that ``advance`` takes already), or, when implicit (direct forcing towards a body
  velocity), to ``F[F_BETA]`` and ``F[F_RHS]`` as β (w − w_s) does;
* the fluid fraction of a cell partly occupied by a solid object multiplies its voidage: the kernels read
  the voidage only through ``C[C_E]`` (and the face means made from it), so ε_cell = ε_particles × φ_fluid
  is given as ``voidage=`` (the mass, momentum and pressure-matrix terms then all see the blocked volume),
  with φ_fluid = 0 cells flagged as walls.

The coupling to particles is ``coupling/exchange3d.py`` (the 3D voidage map, the trilinear interpolation
and the paired exchange); it hands the solver β and u_s on the faces and the pressure term's voidage
(``pressure_voidage``).
"""
from __future__ import annotations

import math
from collections.abc import Mapping

import numba
import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..errors import CaseError
from . import _layout3d as lay
from . import _solver3d_kernels as K3
from ._multigrid3d import multigrid_arrays
from .boundaries import BoundaryCondition
from .grid import (
    FREE_SLIP,
    INFLOW,
    NO_SLIP,
    OUTFLOW,
    PERIODIC,
    PRESSURE,
    SIDE_AXIS,
    StaggeredGrid,
    check_sides,
)
from .solver import (
    COARSEST,
    check_options,
    KRYLOV_MAX,
    KRYLOV_RESTART,
    SCHEMES,
    SLOW_CONVERGENCE,
    GasConvergenceError,
    GasProperties,
    GasSolver,
    GasState,
    StepInfo,
    _show,
)

LINEAR_SOLVERS_3D = ("auto", "multigrid", "superlu")
# multigrid path: each correction is solved to this fraction of its residual (10 times tighter than 2D's
# KRYLOV_REDUCTION: one more GMRES iteration, and the Newton iterations no longer stop on a pressure
# correction left 1e-4 short, e.g. a closed box's hydrostatic profile off by 1e-9 Pa, not 1e-11)
KRYLOV_REDUCTION_3D = 1e-5
# multigrid path: a Newton iteration keeps the last iteration's Jacobian and hierarchy (a chord step) where that
# iteration cut the mass residual to at most this fraction. Where the cut is that deep the Jacobian has stopped
# changing; on a start-up with pressure changes of 1-2 kPa a step (cuts of 1e-2 to 1e-3), a threshold of 1e-2
# took 4-5 iterations a step where fresh Jacobians took 3, and 1e-3 took 3 (``tests/unit/test_gas3d_chord.py``)
CHORD_REDUCTION = 1e-3
_LOW_SIDES = ("left", "bottom", "front")
# grids of fewer cells run the kernels' passes serially on any number of threads: on a 2-core machine the
# threaded passes saved nothing at 1800 cells, and lost at 1800 to 1e5 cells whenever another process
# shared a core (``benchmarks/README.md``, "3D coupled gas step"); above, not yet measured on an idle machine
PARALLEL_MIN_CELLS = 200_000


class GasSolver3D(GasSolver):
    """Pressure-correction solver of the volume-averaged gas equations on a 3D grid (Hoomans 1996 eqs 42-48).

    Made by ``GasSolver(grid, ...)`` when ``grid`` is 3D; the parameters are those of ``GasSolver``, with
    ``boundaries`` naming the six sides (``front`` at z = 0 and ``back`` at z = Lz besides the four of 2D),
    ``gravity`` (gx, gy, gz) [m/s^2] (default −9.81 along y: bottom and top are the y sides), and
    ``linear_solver`` one of "auto", "multigrid", "superlu" ("band" is the 2D block-tridiagonal LU).

    Examples
    --------
    >>> grid = StaggeredGrid(cells=(10, 20, 10), size=(0.1, 0.2, 0.1))
    >>> solver = GasSolver(grid, GasProperties(), {"left": Wall(), "right": Wall(), "front": Wall(),
    ...     "back": Wall(), "top": PressureOutlet(),
    ...     "bottom": Inflow(superficial=0.2, voidage=0.4,
    ...                      patches=[Circle(centre=(0.05, 0.05), radius=0.01, interstitial=10.0)])})
    >>> state = solver.initial_state()
    >>> info = solver.advance(state, dt=1e-4, t=0.0)
    """

    def __init__(self, grid: StaggeredGrid, props: GasProperties, boundaries: Mapping[str, BoundaryCondition],
                 gravity=(0.0, -9.81, 0.0), convection: str = "upwind", tolerance: float = 1e-10,
                 max_iterations: int = 50, jacobian_reuse: float = 1e-2, linear_solver: str = "auto"):
        if not isinstance(grid, StaggeredGrid) or grid.dimensions != 3:
            raise CaseError(f"gas.grid = {grid!r}: GasSolver3D needs a 3D StaggeredGrid(cells=(nx, ny, nz), ...)")
        if not isinstance(props, GasProperties):
            raise CaseError(f"gas properties = {props!r}: must be GasProperties(...)")
        check_sides(boundaries, grid.sides)
        g = np.asarray(gravity, float).ravel()
        if g.size != 3 or not np.all(np.isfinite(g)):
            raise CaseError(f"gravity = {_show(gravity)}: must be (gx, gy, gz) [m/s^2] for a 3D gas grid")
        check_options(convection, tolerance, max_iterations, jacobian_reuse, linear_solver)
        if linear_solver not in LINEAR_SOLVERS_3D:
            raise CaseError(f"gas.linear_solver = {linear_solver!r}: on a 3D grid allowed are "
                            + ", ".join(repr(k) for k in LINEAR_SOLVERS_3D)
                            + (" ('band' is the 2D block-tridiagonal LU)" if linear_solver == "band" else ""))
        self.grid, self.props = grid, props
        self.boundaries = dict(boundaries)
        self.gravity = tuple(float(x) for x in g)
        self.convection = convection
        self.tolerance = float(tolerance)
        self._sqrt_tolerance = math.sqrt(self.tolerance)
        self.max_iterations = max_iterations
        self.jacobian_reuse = float(jacobian_reuse)
        self.flags = grid.cell_flags(self.boundaries)
        self.periodic = tuple(self.boundaries[s].flag == PERIODIC for s in _LOW_SIDES)
        self.periodic_x, self.periodic_y, self.periodic_z = self.periodic
        self._setup_faces()
        self._setup_maps()
        self._setup_matrix()
        self._setup_work(linear_solver)
        self._set_boundary_values(0.0)
        self.C[lay.C_PFIX_OLD] = self.C[lay.C_PFIX]

    # ------------------------------------------------------------ set-up
    def _setup_faces(self):
        """Face kinds and inward signs from the flags; the sides with prescribed velocities and pressures."""
        gd = self.grid
        kind_of_ghost = {FREE_SLIP: lay.FIXED, NO_SLIP: lay.FIXED, INFLOW: lay.FIXED, PRESSURE: lay.SOLVED,
                         OUTFLOW: lay.OUTFLOW_FACE, PERIODIC: lay.SOLVED}
        self.K = np.zeros((2, 3, gd.nx + 1, gd.ny + 1, gd.nz + 1), np.int8)
        for side, bc in self.boundaries.items():
            a = SIDE_AXIS[side]
            low = side in _LOW_SIDES
            layer = self._face_layer(a, 0 if low else gd.cells[a])
            kind = lay.COPY if (bc.flag == PERIODIC and not low) else kind_of_ghost[bc.flag]
            self.K[(lay.K_KIND, a) + layer] = kind
            self.K[(lay.K_SIGN, a) + layer] = 0 if bc.flag == PERIODIC else (1 if low else -1)
        self._inflows = []
        for side in gd.sides:
            bc = self.boundaries[side]
            velocity = bc.face_velocity(side, gd.side_faces(side))
            if velocity is not None:
                self._inflows.append((side, velocity))
        self._pressure_sides = [(s, bc) for s, bc in self.boundaries.items() if bc.flag == PRESSURE]
        self._time_dependent = any(bc.time_dependent for bc in self.boundaries.values())
        self.has_outflow = any(bc.flag == OUTFLOW for bc in self.boundaries.values())

    def _face_layer(self, a: int, p: int) -> tuple:
        """Index of the faces of axis ``a`` at face position ``p`` along it, within that axis's extent."""
        idx = [slice(0, n) for n in self.grid.cells]
        idx[a] = p
        return tuple(idx)

    @staticmethod
    def _ghost_index(side: str) -> tuple:
        """Index of a side's boundary cells (its ring layer without the edges) in padded centre arrays."""
        idx = [slice(1, -1)] * 3
        idx[SIDE_AXIS[side]] = 0 if side in _LOW_SIDES else -1
        return tuple(idx)

    def _setup_maps(self):
        """row_of / col_of: padded centre cell -> equation row / pressure unknown (-1: none); ghost rules."""
        gd, fl = self.grid, self.flags
        nx, ny, nz = gd.cells
        k = np.arange(nx * ny * nz, dtype=np.int64).reshape(nx, ny, nz)
        row = np.full((nx + 2, ny + 2, nz + 2), -1, np.int64)
        col = np.full((nx + 2, ny + 2, nz + 2), -1, np.int64)
        row[1:-1, 1:-1, 1:-1] = col[1:-1, 1:-1, 1:-1] = k
        zero_gradient = (FREE_SLIP, NO_SLIP, INFLOW, OUTFLOW)
        for side in gd.sides:
            a = SIDE_AXIS[side]
            low = side in _LOW_SIDES
            ghost = self._ghost_index(side)
            adjacent = np.take(k, 0 if low else -1, axis=a)
            opposite = np.take(k, -1 if low else 0, axis=a)
            f = fl[ghost]
            row[ghost] = np.where(f == PERIODIC, opposite, -1)
            col[ghost] = np.where(f == PERIODIC, opposite, np.where(np.isin(f, zero_gradient), adjacent, -1))
        self.row_of, self.col_of = row, col
        self.RULES = np.zeros((2, 9), np.int64)
        prule, erule = self.RULES[lay.RULE_P], self.RULES[lay.RULE_E]
        for f in (FREE_SLIP, NO_SLIP, INFLOW, OUTFLOW):
            prule[f] = lay.R_COPY
        prule[PRESSURE] = lay.R_FIXED
        prule[PERIODIC] = lay.R_WRAP
        for f in (FREE_SLIP, NO_SLIP, PRESSURE, OUTFLOW):
            erule[f] = lay.R_COPY  # Hoomans 1996 §3.5: wall cells copy the adjacent voidage
        erule[INFLOW] = lay.R_FIXED  # Hoomans 1996 §3.5: fixed voidage in influx cells
        erule[PERIODIC] = lay.R_WRAP
        self.C = np.zeros((lay.N_C, nx + 2, ny + 2, nz + 2))
        self.C[lay.C_EFIX] = 1.0
        for side, bc in self.boundaries.items():
            if bc.flag == INFLOW:
                self.C[(lay.C_EFIX,) + self._ghost_index(side)] = bc.voidage

    def _setup_matrix(self):
        """Fixed CSC pattern of the pressure-correction matrix and where each face writes into it."""
        gd = self.grid
        nx, ny, nz = gd.cells
        n = nx * ny * nz
        rows_all, cols_all, parts = [], [], []
        for a in range(3):
            e = [int(a == q) for q in range(3)]
            I, J, L = np.meshgrid(*(np.arange(m + e[q]) for q, m in enumerate(gd.cells)), indexing="ij")
            left = (I + 1 - e[0], J + 1 - e[1], L + 1 - e[2])
            right = (I + 1, J + 1, L + 1)
            kind = self.K[(lay.K_KIND, a, slice(0, nx + e[0]), slice(0, ny + e[1]), slice(0, nz + e[2]))]
            rl, cl = self.row_of[left], self.col_of[left]
            rr, cr = self.row_of[right], self.col_of[right]
            rows = np.stack([rl, rl, rr, rr], axis=-1)
            cols = np.stack([cl, cr, cl, cr], axis=-1)
            valid = (rows >= 0) & (cols >= 0) & ((kind != lay.COPY) & (kind != lay.OUTFLOW_FACE))[..., None]
            parts.append((rows, cols, valid))
            rows_all.append(rows[valid])
            cols_all.append(cols[valid])
        diag = np.arange(n, dtype=np.int64)
        keys = np.unique(np.concatenate(cols_all + [diag]) * n + np.concatenate(rows_all + [diag]))
        self._indices = (keys % n).astype(np.int64)
        self._indptr = np.searchsorted(keys, np.arange(n + 1) * n).astype(np.int64)
        self.MAT = np.zeros((2, keys.size))  # the matrix now, and the one last factorised
        self.pos = np.full((3, nx + 1, ny + 1, nz + 1, 4), -1, np.int64)
        for a, (rows, cols, valid) in enumerate(parts):
            p = np.searchsorted(keys, cols * n + rows)
            sub = self.pos[a, :rows.shape[0], :rows.shape[1], :rows.shape[2]]
            sub[...] = np.where(valid, p, -1)
        self.diag_pos = np.searchsorted(keys, diag * n + diag).astype(np.int64)
        # a constant-density gas with no pressure boundary has its level fixed by p'(cell 0) = 0
        self.pinned = (not self.props.ideal) and not self._pressure_sides
        self.pin_pos = np.flatnonzero(self._indices == 0).astype(np.int64) if self.pinned else np.zeros(0, np.int64)
        self.pin_diag = int(self.diag_pos[0]) if self.pinned else -1

    def _setup_work(self, linear_solver: str):
        gd = self.grid
        nx, ny, nz = gd.cells
        n = nx * ny * nz
        self.W = np.zeros((3, nx + 5, ny + 5, nz + 5))  # velocities with two layers of ghost faces
        self.Q = np.zeros((3, nx + 5, ny + 5, nz + 5))  # mass flux densities
        self.F = np.zeros((lay.N_F, 3, nx + 1, ny + 1, nz + 1))
        self.S = np.zeros((3, nx + 2, ny + 2, nz + 2))  # normal stresses at centres
        self.T = np.zeros((3, nx + 1, ny + 1, nz + 1))  # shear stresses on the cell edges
        self.R = np.zeros(n)
        self.dp = np.zeros(n)
        self._fpar = np.zeros(lay.N_FPAR)
        self._fpar[lay.FP_G:lay.FP_G + 3] = self.gravity
        self._fpar[lay.FP_H:lay.FP_H + 3] = gd.spacing
        self._fpar[lay.FP_A:lay.FP_A + 3] = (gd.area_x, gd.area_y, gd.area_z)
        self._fpar[lay.FP_VOL] = gd.cell_volume
        self._fpar[lay.FP_COMP] = self.props.compressibility
        self._fpar[lay.FP_RHOC] = 0.0 if self.props.ideal else float(self.props.density)
        self._fpar[lay.FP_PREF] = self.props.reference_pressure
        self._fpar[lay.FP_MU] = self.props.viscosity
        self._ipar = np.zeros(lay.N_IPAR, np.int64)
        self._ipar[lay.I_N:lay.I_N + 3] = gd.cells
        self._ipar[lay.I_SCHEME] = SCHEMES[self.convection]
        self._ipar[lay.I_PIN] = self.pin_diag
        self._out = np.zeros(lay.N_OUT)
        self._face_shapes = tuple(gd.face_shape(a) for a in range(3))
        self._face_shape_table = np.array(self._face_shapes, np.int64)  # (3, 3), for ``K3.load_face_inputs``
        self._none = np.zeros((0, 0, 0))  # "no array" for the input kernels
        self._state_ok = None  # the state arrays _check_state found right (references)
        self.parallel_min_cells = PARALLEL_MIN_CELLS  # fewer cells: the kernels' passes serial on any threads
        choice = "multigrid" if linear_solver == "auto" else linear_solver
        self._mg = None
        if choice == "multigrid":
            h = gd.spacing
            self._mg = multigrid_arrays(gd.cells, self.periodic, self._indices, self._indptr, COARSEST, KRYLOV_RESTART,
                                        tuple(h[(q + 1) % 3] * h[(q + 2) % 3] / h[q] for q in range(3)))
            if self._mg is None:
                choice = "superlu"
        self._solver = choice
        self._lu = None
        self._nfact = 0
        self._counts = np.zeros(2, np.int64)  # multigrid path: hierarchies made, GMRES iterations
        self.krylov_max = KRYLOV_MAX  # GMRES iterations of one correction before the multigrid gives way to SuperLU
        self._rhs = np.zeros(self.R.size)

    # ------------------------------------------------------------ boundary values
    def _set_boundary_values(self, t: float) -> None:
        """Inflow face velocities (F[F_FIX]) and prescribed boundary-cell pressures (C[C_PFIX]) at time t."""
        self._bc_time = t
        gd = self.grid
        for side, velocity in self._inflows:
            a = SIDE_AXIS[side]
            low = side in _LOW_SIDES
            vel = velocity(t)  # interstitial, positive inward, (n_a, n_b) over the side's in-plane axes
            self.F[(lay.F_FIX, a) + self._face_layer(a, 0 if low else gd.cells[a])] = vel if low else -vel
        for side, bc in self._pressure_sides:
            p = bc.prescribed_pressure(t)
            p = self.props.reference_pressure if p is None else p
            self.C[(lay.C_PFIX,) + self._ghost_index(side)] = p - self.props.reference_pressure

    # ------------------------------------------------------------ initial state
    def hydrostatic_pressure(self, t: float = 0.0) -> np.ndarray:
        """(nx, ny, nz) pressure [Pa] of gas at rest under gravity, in exact discrete balance.

        Anchored at the prescribed pressure of the first ``PressureOutlet`` side (top first), at its
        boundary-cell centres; without one, at ``reference_pressure`` in the domain centre. Ideal gas:
        p = p_a exp(k·(x − x_a)), k per axis the rate that the staggered balance of eqs 43-44 gives
        (M g/(RT) up to O((g h M/(RT))²)); constant density: p = p_a + ρ g·(x − x_a)."""
        gd = self.grid
        X = gd.centres()
        anchor = [0.5 * L for L in gd.size]
        sides = sorted(self._pressure_sides, key=lambda s: s[0] != "top")
        p_a = self.props.reference_pressure
        if sides:
            side, bc = sides[0]
            pa = bc.prescribed_pressure(t)
            p_a = p_a if pa is None else pa
            a = SIDE_AXIS[side]
            h = gd.spacing[a]
            anchor[a] = -0.5 * h if side in _LOW_SIDES else gd.size[a] + 0.5 * h
        if not self.props.ideal:
            return p_a + self.props.density * sum(g * (x - x0) for g, x, x0 in zip(self.gravity, X, anchor))
        f = self.props.compressibility

        def rate(g, h):  # p_{+1}/p = (1 + g h f/2)/(1 - g h f/2) across one face
            q = 0.5 * g * h * f
            return math.log((1.0 + q) / (1.0 - q)) / h

        return p_a * np.exp(sum(rate(g, h) * (x - x0) for g, h, x, x0 in zip(self.gravity, gd.spacing, X, anchor)))

    def initial_state(self, voidage=1.0, velocity=(0.0, 0.0, 0.0), pressure=None, t: float = 0.0) -> GasState:
        """A ``GasState`` (with ``w``) that meets the boundary conditions at time ``t`` [s].

        Parameters
        ----------
        voidage : float or (nx, ny, nz) array
            ε [-], in (0, 1].
        velocity : (ux, uy, uz) numbers or face arrays (u (nx+1, ny, nz), v (nx, ny+1, nz), w (nx, ny, nz+1))
            Interstitial gas velocity [m/s]; boundary faces are overwritten by the boundary conditions.
        pressure : None, float or (nx, ny, nz) array
            [Pa]; None: hydrostatic (``hydrostatic_pressure``).
        """
        gd = self.grid
        eps = self._centre_array("voidage", voidage)
        self._check_voidage(eps)
        if len(velocity) != 3:
            raise CaseError(f"gas initial velocity: give three components (u, v, w) on a 3D grid, not {len(velocity)}")
        vel = [np.array(np.broadcast_to(np.asarray(c, float), gd.face_shape(a)) if np.ndim(c) == 0
                        else self._face(f"velocity[{a}]", c, a, centre_ok=False)) for a, c in enumerate(velocity)]
        p = self.hydrostatic_pressure(t) if pressure is None else self._centre_array("pressure", pressure).copy()
        if not np.all(p > 0.0) and self.props.ideal:
            raise CaseError("gas initial pressure: must be > 0 [Pa] everywhere for the ideal gas")
        self._set_boundary_values(t)
        for a in range(3):
            sl = tuple(slice(0, n) for n in gd.face_shape(a))
            kind = self.K[(lay.K_KIND, a) + sl]
            fixed = kind == lay.FIXED
            vel[a][fixed] = self.F[(lay.F_FIX, a) + sl][fixed]
            if self.periodic[a]:
                last = [slice(None)] * 3
                first = [slice(None)] * 3
                last[a], first[a] = -1, 0
                vel[a][tuple(last)] = vel[a][tuple(first)]
        return GasState(p=np.ascontiguousarray(p, float), rho=self.props.density_at(p) * np.ones(gd.shape),
                        u=vel[0], v=vel[1], w=vel[2], voidage=np.array(eps, float))

    # ------------------------------------------------------------ input checks and conversions
    def _centre_array(self, name, value):
        a = np.asarray(value, float)
        if a.ndim == 0:
            return np.full(self.grid.shape, float(a))
        if a.shape != self.grid.shape:
            raise CaseError(f"gas {name}: shape {a.shape} does not match the cell-centre shape {self.grid.shape} "
                            "(nx, ny, nz)")
        return a

    def _face(self, name, value, axis, centre_ok=True) -> np.ndarray:
        """A face array of ``axis`` from a number, a face array, or (centre_ok) a centre array averaged onto the
        faces (boundary faces: the adjacent cell; periodic: the mean of the two cells the face joins)."""
        shape = self.grid.face_shape(axis)
        a = np.asarray(value, float)
        if a.ndim == 0:
            return np.full(shape, float(a))
        if a.shape == shape:
            return a
        if centre_ok and a.shape == self.grid.shape:
            out = np.empty(shape)
            lo, hi = [slice(None)] * 3, [slice(None)] * 3
            lo[axis], hi[axis] = slice(0, -1), slice(1, None)
            mid = [slice(None)] * 3
            mid[axis] = slice(1, -1)
            out[tuple(mid)] = 0.5 * (a[tuple(lo)] + a[tuple(hi)])
            first, last = [slice(None)] * 3, [slice(None)] * 3
            first[axis], last[axis] = 0, -1
            if self.periodic[axis]:
                out[tuple(first)] = out[tuple(last)] = 0.5 * (a[tuple(first)] + a[tuple(last)])
            else:
                out[tuple(first)] = a[tuple(first)]
                out[tuple(last)] = a[tuple(last)]
            return out
        allowed = f"{shape} (faces)" + (f" or {self.grid.shape} (cell centres)" if centre_ok else "")
        raise CaseError(f"gas {name}: shape {a.shape} does not match {allowed}")

    def _load_inputs(self, beta, solids, sources) -> None:
        """F[F_BETA] = β and F[F_RHS] = β u_s + source on the faces of every axis, in one compiled call
        (``K3.load_face_inputs``: no temporaries); CaseError when out of range."""
        per_face = isinstance(beta, (tuple, list))
        if per_face and len(beta) != 3:
            raise CaseError("gas beta: give a number, a centre array or three face arrays (x, y, z faces)")
        if beta is None:
            self.F[lay.F_BETA] = 0.0
        none = self._none
        b, us, src = [none, none, none], [none, none, none], [none, none, none]
        for a in range(3):
            if beta is not None:
                b[a] = (self._face(f"beta[{a}]", beta[a], a, centre_ok=False) if per_face
                        else self._face("beta", beta, a))
                if solids[a] is not None:  # the solids velocity counts only where β is given
                    us[a] = self._face(f"solids velocity {'uvw'[a]}", solids[a], a)
            if sources[a] is not None:
                src[a] = self._face(f"source {'uvw'[a]}", sources[a], a)
        if K3.load_face_inputs(self.F, *b, *us, *src, self._face_shape_table) >= 0:
            raise CaseError("gas beta: must be finite and >= 0 [kg m^-3 s^-1] on every face")

    def _check_state(self, state: GasState) -> None:
        """Shapes, dtype and layout of the state's arrays; arrays found right once are remembered (references)
        and not checked again while the state holds the same objects."""
        ok = self._state_ok
        if ok is not None and ok[0] is state.p and ok[1] is state.rho and ok[2] is state.voidage \
                and ok[3] is state.u and ok[4] is state.v and ok[5] is getattr(state, "w", None):
            return
        gd = self.grid
        shapes = {"p": gd.shape, "rho": gd.shape, "voidage": gd.shape, "u": gd.u_shape, "v": gd.v_shape,
                  "w": gd.w_shape}
        for key, shape in shapes.items():
            a = getattr(state, key, None)
            if not isinstance(a, np.ndarray) or a.shape != shape:
                got = getattr(a, "shape", type(a).__name__)
                raise CaseError(f"gas state.{key}: shape {got} does not match {shape}" +
                                (" (a 3D gas state has w; make it with GasSolver.initial_state)" if key == "w" else ""))
            if a.dtype != np.float64 or not a.flags.c_contiguous:
                raise CaseError(f"gas state.{key}: must be a C-contiguous float64 array (as initial_state makes it)")
        self._state_ok = (state.p, state.rho, state.voidage, state.u, state.v, state.w)

    def _pressure_voidage(self, value) -> tuple:
        """The step input ``pressure_voidage``: three face arrays in (0, 1]; CaseError otherwise."""
        if not (isinstance(value, (tuple, list)) and len(value) == 3):
            raise CaseError("gas pressure_voidage: give three face arrays (x-faces, y-faces, z-faces) on a 3D grid")
        out = []
        for a, e in enumerate(value):
            e = np.asarray(e, float)
            if e.shape != self._face_shapes[a]:
                raise CaseError(f"gas pressure_voidage[{a}]: shape {e.shape}, expected {self.grid.face_shape(a)}")
            out.append(e)
        bad = K3.unit_interval3(*out)
        if bad >= 0:
            raise CaseError(f"gas pressure_voidage[{bad}]: every face value must lie in (0, 1]")
        return tuple(out)

    # ------------------------------------------------------------ time step
    def advance(self, state: GasState, dt: float, t: float = 0.0, *, voidage=None, beta=None, solids_u=None,
                solids_v=None, solids_w=None, source_u=None, source_v=None, source_w=None,
                pressure_voidage=None) -> StepInfo:
        """Advance ``state`` in place from time ``t`` to ``t + dt`` [s] (see ``GasSolver.advance``).

        voidage : None, float or (nx, ny, nz) array, ε at t + dt [-]
        beta : None, float, centre array, or (x-face, y-face, z-face) arrays: β ≥ 0 [kg m^-3 s^-1], implicit
        solids_u, solids_v, solids_w : None, float, centre or face arrays: solids velocity in β(u − u_s) [m/s]
        source_u, source_v, source_w : None, float, centre or face arrays: explicit momentum source [N/m^3]
            (the place of a body force of immersed boundaries)
        pressure_voidage : None or (x-face, y-face, z-face) arrays in (0, 1]: the voidage ε_p,f of the pressure
            term −ε_p,f ∂p/∂x on each face (None: ε_f, the face value of ``voidage``), as in 2D

        Returns a ``StepInfo``; raises ``CaseError`` for bad input and ``GasConvergenceError`` when the step
        fails (the state is then left as it was at t)."""
        if pressure_voidage is not None:
            pressure_voidage = self._pressure_voidage(pressure_voidage)
        if not (isinstance(dt, (int, float, np.floating)) and math.isfinite(dt) and dt > 0.0):
            raise CaseError(f"gas time step dt = {_show(dt)}: must be > 0 [s]")
        dt = float(dt)
        self._check_state(state)
        if voidage is None:
            eps_new = state.voidage
        else:
            eps_new = np.ascontiguousarray(self._centre_array("voidage", voidage), dtype=float)
            if not K3.unit_interval(eps_new):
                self._check_voidage(eps_new)  # raises the CaseError that names the value
        self._load_inputs(beta, (solids_u, solids_v, solids_w), (source_u, source_v, source_w))
        if self._time_dependent:  # prescribed pressures at t and t + dt, inflow velocities at t + dt
            if t != self._bc_time:
                self._set_boundary_values(t)
            self.C[lay.C_PFIX_OLD] = self.C[lay.C_PFIX]
            self._set_boundary_values(t + dt)
        fpar, ipar, out = self._fpar, self._ipar, self._out
        fpar[lay.FP_DT] = dt
        # the kernels' passes on that many threads (bitwise the same on any number)
        ipar[lay.I_THREADS] = numba.get_num_threads() if self.R.size >= self.parallel_min_cells else 1
        K3.begin_step(state.p, state.rho, state.u, state.v, state.w, state.voidage, eps_new, self.W, self.Q, self.C,
                      self.F, self.K, self.S, self.T, self.flags, self.RULES, fpar, ipar)
        if pressure_voidage is not None:  # replaces the ε_f that begin_step gave the pressure term
            K3.load_faces(self.F, lay.F_EP, *pressure_voidage)
        it = 0
        prev = math.inf
        fresh = False  # the factors (SuperLU) are of this iteration's matrix
        if self._solver == "multigrid":  # the Newton iterations in one compiled call
            mg = self._mg
            it, rel, failed = K3.newton_multigrid(
                self.W, self.C, self.F, self.K, self.row_of, self.R, fpar, ipar, out, self.MAT[0], self.diag_pos,
                self.pos, self.pin_pos, self.flags, self.RULES, mg.ell, mg.MGL, mg.MGI, mg.MGA, mg.MGS, mg.MGW, mg.DLU,
                mg.PIV, mg.KRY, mg.HES, self._rhs, self.dp, self.pinned, self.tolerance, self.max_iterations,
                KRYLOV_REDUCTION_3D, 0.1 * self.tolerance, self.krylov_max, self._counts, CHORD_REDUCTION)
            if failed:  # the hierarchy failed or GMRES stalled: SuperLU from this iteration on
                self._solver = "superlu"
                self._lu = None
                fresh = self._solve(it, False)
                prev = rel
                K3.correct_pressure(self.C, self.dp, self.flags, self.RULES, fpar, ipar)
                it += 1
        if self._solver != "multigrid":
            while True:
                rel = K3.predict_residual(self.W, self.C, self.F, self.K, self.row_of, self.R, fpar, ipar, out)
                if not math.isfinite(rel) or rel <= self.tolerance or it >= self.max_iterations:
                    break
                fresh = self._solve(it, rel > SLOW_CONVERGENCE * prev and not fresh)
                prev = rel
                K3.correct_pressure(self.C, self.dp, self.flags, self.RULES, fpar, ipar)
                it += 1
        courant = K3.courant_number(self.W, fpar, ipar)
        if not math.isfinite(rel) or rel > self._sqrt_tolerance:  # the state is left as it was at t
            what = "is not finite" if not math.isfinite(rel) else f"did not converge (mass residual {rel:.3g})"
            raise GasConvergenceError(
                f"gas step from t = {t:.6g} s with dt = {dt:g} s {what}; Courant number {courant:.3g}: "
                "keep it below 1 (0.5 with convection='tvd'), see GasSolver.max_time_step")
        K3.end_step(state.p, state.rho, state.u, state.v, state.w, state.voidage, eps_new, self.W, self.C, self.flags,
                    fpar, ipar)
        o = out
        return StepInfo(iterations=it, mass_residual=rel, converged=rel <= self.tolerance,
                        inflow_rate=float(o[lay.O_IN]), outflow_rate=float(o[lay.O_OUT]), mass=float(o[lay.O_MASS]),
                        mass_change_rate=float(o[lay.O_ACC]), courant=courant)

    def _solve(self, it: int, slow: bool) -> bool:
        """p' (``self.dp``) of the Newton iteration ``it`` from the residuals ``self.R`` by SuperLU, the Jacobian
        assembled (``K3.assemble_pressure``): factors kept while the matrix differs from theirs by at most
        ``jacobian_reuse`` of its largest entry and the iterations converge (``slow``: the last one did not).
        The multigrid path (``K3.newton_multigrid``) does its iterations in one compiled call and comes here
        only when it fails. Returns whether SuperLU factorised this iteration's matrix."""
        data, factored = self.MAT
        K3.assemble_pressure(data, self.diag_pos, self.pos, self.pin_pos, self.W, self.C, self.F, self.K, self._fpar,
                             self._ipar)
        rhs = -self.R
        if self.pinned:
            rhs[0] = 0.0
        fresh = False
        if self._lu is None or slow or (it == 0 and np.max(np.abs(data - factored))
                                        > self.jacobian_reuse * np.max(np.abs(factored))):
            n = self.R.size
            A = sp.csc_matrix((data.copy(), self._indices, self._indptr), shape=(n, n))
            self._lu = spla.splu(A)
            factored[:] = data
            self._nfact += 1
            fresh = True
        self.dp[:] = self._lu.solve(rhs)
        return fresh

    # ------------------------------------------------------------ diagnostics
    def checkpoint_arrays(self) -> dict[str, np.ndarray]:
        """What the next step starts from besides the state, for checkpoints: the linear solver in use (the
        multigrid gives way to SuperLU for good when it fails) and the matrix whose SuperLU factors the next
        step may reuse (``jacobian_reuse``). The multigrid makes its hierarchy anew every step. With
        these restored (``restore_factors``, which factorises the same matrix again) a resumed run goes on
        bit for bit."""
        have = self._lu is not None
        return {"matrix": self.MAT[1] if have else np.zeros(0),
                "flags": np.array([int(have), int(self._solver == "superlu")], np.int64)}

    def restore_factors(self, arrays: dict[str, np.ndarray]) -> None:
        """Take back ``checkpoint_arrays``: the solver in use and the SuperLU factors of the saved matrix."""
        have, superlu = (int(x) for x in arrays["flags"])
        if superlu:
            self._solver = "superlu"
        self._lu = None
        if have:
            m = np.asarray(arrays["matrix"], float)
            if m.shape != self.MAT[1].shape:
                raise CaseError(f"checkpoint gas solver matrix: shape {m.shape}, this case's is {self.MAT[1].shape} "
                                "(a checkpoint of another grid or boundaries)")
            self.MAT[1] = m
            n = self.R.size
            self._lu = spla.splu(sp.csc_matrix((m.copy(), self._indices, self._indptr), shape=(n, n)))

    @property
    def factorisations(self) -> int:
        """SuperLU factorisations (multigrid: hierarchies made) so far."""
        return self._nfact + int(self._counts[0])

    @property
    def linear_solver(self) -> str:
        """'multigrid' or 'superlu', whichever solves the pressure-correction equations now."""
        return self._solver

    @property
    def krylov_iterations(self) -> int:
        """GMRES iterations so far (multigrid path; 0 otherwise)."""
        return int(self._counts[1])

    def max_time_step(self, state: GasState, courant: float = 0.5) -> float:
        """Largest dt [s] of the explicit terms for ``state``: Courant number ``courant`` and viscous number
        ν dt Σ 2/h² ≤ 1/2 (drag and pressure are implicit)."""
        gd = self.grid
        rate = sum(np.abs(c).max() / h for c, h in zip((state.u, state.v, state.w), gd.spacing))
        nu = self.props.viscosity / max(float(state.rho.min()), 1e-300)
        dt_c = courant / rate if rate > 0.0 else math.inf
        dt_v = 0.5 / (nu * sum(2.0 / h**2 for h in gd.spacing)) if nu > 0.0 else math.inf
        return min(dt_c, dt_v)


__all__ = ["LINEAR_SOLVERS_3D", "GasSolver3D"]
