"""The data layout that the gas solver (``solver.py``) shares with its compiled kernels.

Three kinds of names: integer codes (face kinds, ghost rules, linear solvers, step status, input
modes); the slots of the solver's stacked arrays and parameter vectors, one prefix per array, each
with a table of what its slots hold; and the named tuples that group the arrays of the step's
kernels (Numba compiles a named tuple of arrays into a struct and caches the kernels that take one;
``_solver_kernels.step``, the one the solver calls, takes them as plain tuples and names them).
Index conventions of the padded arrays are those of ``grid.py``: centre arrays ``(nx + 2, ny + 2)``
with cell (i, j) at ``[i + 1, j + 1]``; ``U`` ``(nx + 5, ny + 4)`` with x-face (i, j) at
``[i + 2, j + 2]``; ``V`` ``(nx + 4, ny + 5)`` with y-face (i, j) at ``[i + 2, j + 2]``.
"""
from typing import NamedTuple

import numpy as np

# ================================================================ integer codes
# face kinds (KU/KV[K_KIND]): momentum solved / value fixed (wall, inflow) / continuous outflow /
# periodic duplicate of face 0
SOLVED, FIXED, OUTFLOW_FACE, COPY = 0, 1, 2, 3
# ghost rules of centre scalars (RULES, per cell flag): none / zero gradient (copy the adjacent
# interior value) / prescribed value / periodic wrap (the interior value on the opposite side)
R_NONE, R_COPY, R_FIXED, R_WRAP = 0, 1, 2, 3
# linear solvers of the pressure correction (ipar[I_SOLVER])
SOLVER_SUPERLU, SOLVER_BAND, SOLVER_MULTIGRID = 0, 1, 2
# status of the step kernels, one set of codes: ``iterate`` returns the first four, ``start_step``
# INPUT_OK or a BAD_* code, ``step`` any but INPUT_OK
CONVERGED, NEED_FACTORS, MAX_ITERATIONS, NOT_FINITE, INPUT_OK, BAD_VOIDAGE, BAD_BETA = range(7)
# how a step input is given (the values of ``modes``, slots IN_*): not given / a number (at
# [0, 0] of its array) / at cell centres / on faces
MODE_NONE, MODE_SCALAR, MODE_CENTRE, MODE_FACE = 0, 1, 2, 3

# ================================================================ slots
# C (N_C, nx + 2, ny + 2) float64, centre arrays with one ring of boundary cells:
#   C_P         pressure relative to the reference pressure p_ref [Pa]
#   C_RHO       gas density ρ_g [kg/m^3]
#   C_E         voidage ε [-] (at t while the step's explicit terms are made, then at t + dt)
#   C_PFIX      prescribed pressure of the boundary cells at t + dt, relative to p_ref [Pa]
#   C_PFIX_OLD  the same at t [Pa]
#   C_EFIX      prescribed voidage of the boundary cells (influx cells) [-]
#   C_RO_OLD    (ερ) at t [kg/m^3]
#   C_SXX       normal stress σ_xx of ε τ_g at t [Pa] (work of ``explicit_momentum``)
#   C_SYY       normal stress σ_yy of ε τ_g at t [Pa] (work of ``explicit_momentum``)
C_P, C_RHO, C_E, C_PFIX, C_PFIX_OLD, C_EFIX, C_RO_OLD, C_SXX, C_SYY = range(9)
N_C = 9
# FU (N_F, nx + 1, ny) on x-faces, FV (N_F, nx, ny + 1) on y-faces, float64, without ghost faces:
#   F_OLD   velocity at t [m/s]
#   F_EX    explicit momentum terms: convection and viscous stress [N/m^3]
#   F_BETA  interphase coefficient β [kg m^-3 s^-1]
#   F_RHS   β u_s + momentum source [N/m^3]
#   F_FIX   prescribed velocity of fixed faces [m/s]
#   F_WOUT  share of the outflow of each continuous-outflow face [-]
#   F_FLUX  mass flux A (ερ)_f w along +x / +y [kg/s]
#   F_EF    face voidage ε_f at t + dt [-]
#   F_X1    u_old/dt + g [m/s^2]
#   F_X2    explicit terms + β u_s + source [N/m^3]
#   F_EP    voidage ε_p,f of the pressure term −ε_p,f ∂p/∂x: ε_f, or the step input ``pressure_voidage``
F_OLD, F_EX, F_BETA, F_RHS, F_FIX, F_WOUT, F_FLUX, F_EF, F_X1, F_X2, F_EP = range(11)
N_F = 11
# KU (2, nx + 1, ny), KV (2, nx, ny + 1) int8:
#   K_KIND  face kind (SOLVED, FIXED, OUTFLOW_FACE, COPY)
#   K_SIGN  inward sign: +1 on a low boundary face, -1 on a high one, else 0
K_KIND, K_SIGN = 0, 1
# RULES (2, 9) int64, ghost rule (R_*) per cell flag:
#   RULE_P  of the pressure
#   RULE_E  of the voidage
RULE_P, RULE_E = 0, 1
# VEC (N_VEC, nx ny) float64, vectors of the pressure correction:
#   V_R      continuity residual R [kg/s], then the right-hand side −R
#   V_DP     pressure correction p' [Pa]
#   V_WORK   work (the band and SuperLU solves)
#   V_WORK2  work (the band solve)
#   V_ROW    two rows of work (the band factorisation): V_ROW and V_ROW + 1
V_R, V_DP, V_WORK, V_WORK2, V_ROW = range(5)
N_VEC = 6
# MAT (2, nnz) float64, the pressure matrix in CSC form on a fixed pattern:
#   M_DATA      its entries now
#   M_FACTORED  the entries of the matrix last factorised (band, SuperLU) or made a hierarchy of
M_DATA, M_FACTORED = 0, 1
# fpar (N_FPAR,) float64, real parameters:
#   FP_GX, FP_GY   gravity [m/s^2]
#   FP_DT          time step of the current step [s]
#   FP_DX, FP_DY   cell sides [m]
#   FP_AX, FP_AY   areas of an x-face and a y-face [m^2]
#   FP_VOL         cell volume [m^3]
#   FP_COMP        compressibility dρ/dp = M/(RT) [s^2/m^2], 0 for constant density
#   FP_RHOC        the constant density [kg/m^3], 0 for the ideal gas
#   FP_TOL         mass-residual tolerance of a step [-]
#   FP_REUSE       jacobian_reuse: largest change of the matrix, relative to its largest entry, that
#                  keeps the factors [-]
#   FP_SLOW        factorise again when an iteration cuts the residual by less than this factor [-]
#   FP_PREF        reference pressure p_ref [Pa]
#   FP_MU          viscosity μ_g [Pa s]
#   FP_ETA         multigrid: each correction solved to this fraction of its residual [-]
#   FP_SQRT_TOL    the square root of FP_TOL: a step that ends above it fails, and ``step`` leaves the state as it was
(FP_GX, FP_GY, FP_DT, FP_DX, FP_DY, FP_AX, FP_AY, FP_VOL, FP_COMP, FP_RHOC, FP_TOL, FP_REUSE, FP_SLOW, FP_PREF,
 FP_MU, FP_ETA, FP_SQRT_TOL) = range(17)
N_FPAR = 17
# ipar (N_IPAR,) int64, integer parameters, state of the iterations and counters:
#   I_NX, I_NY          cells along x and y
#   I_MAXIT             most pressure corrections of a step
#   I_PIN               position of the diagonal entry of row 0 in the matrix data when the pressure
#                       level is pinned (p'_0 = 0), else -1
#   I_HAVE_LU           1 when factors (or a hierarchy) of an earlier matrix exist
#   I_ITER              pressure corrections made in the current step
#   I_CHECKED           1 once the current step has compared its matrix with the factorised one
#   I_REFACTORED        1 once the current step has factorised
#   I_RESUME            1: the next ``iterate`` call goes straight to the solve (after SuperLU factors)
#   I_SCHEME            convection scheme (``_operators.UPWIND``, ``TVD``)
#   I_SOLVER            linear solver now (SOLVER_*)
#   I_BW                band half-width (informative)
#   I_NFACT             factorisations (hierarchies) made so far
#   I_LEVELS            multigrid levels (informative)
#   I_KRYLOV            GMRES iterations so far
#   I_KRYLOV_MAX        GMRES iterations of one correction before the multigrid path gives way to SuperLU
#   I_RESTART           GMRES restart length (informative: the Hessenberg array's shape sets it)
#   I_PX, I_PY          1 where x (y) is periodic
#   I_BLOCKS            band blocks factorised so far
#   I_PRESSURE_VOIDAGE  1 when the current step was given ``pressure_voidage``
(I_NX, I_NY, I_MAXIT, I_PIN, I_HAVE_LU, I_ITER, I_CHECKED, I_REFACTORED, I_RESUME, I_SCHEME, I_SOLVER, I_BW,
 I_NFACT, I_LEVELS, I_KRYLOV, I_KRYLOV_MAX, I_RESTART, I_PX, I_PY, I_BLOCKS, I_PRESSURE_VOIDAGE) = range(21)
N_IPAR = 21
# out (N_OUT,) float64, diagnostics of the current step:
#   O_RES      Σ_cells |continuity residual| [kg/s]
#   O_QREF     reference flow of the mass residual [kg/s]
#   O_IN       inflow through the boundary [kg/s]
#   O_OUT      outflow through the boundary [kg/s]
#   O_ACC      accumulation Σ V ((ερ) − (ερ)_old)/dt [kg/s]
#   O_MASS     gas mass Σ ε ρ V [kg]
#   O_COURANT  max|u| dt/dx + max|v| dt/dy [-]
#   O_REL      O_RES / O_QREF: the mass residual [-]
#   O_PREV     the mass residual of the previous iteration [-]
O_RES, O_QREF, O_IN, O_OUT, O_ACC, O_MASS, O_COURANT, O_REL, O_PREV = range(9)
N_OUT = 9
# modes (N_IN,) int64, how each step input is given (MODE_*):
#   IN_VOIDAGE                voidage at t + dt
#   IN_BETA                   β
#   IN_SOLIDS_U, IN_SOLIDS_V  solids velocity
#   IN_SOURCE_U, IN_SOURCE_V  momentum source
IN_VOIDAGE, IN_BETA, IN_SOLIDS_U, IN_SOLIDS_V, IN_SOURCE_U, IN_SOURCE_V = range(6)
N_IN = 6


# ================================================================ grouped arrays
class StateArrays(NamedTuple):
    """The arrays of a ``GasState``: p [Pa] (absolute), rho [kg/m^3], voidage [-] (nx, ny); u (nx + 1, ny),
    v (nx, ny + 1) [m/s]."""

    p: np.ndarray
    rho: np.ndarray
    u: np.ndarray
    v: np.ndarray
    voidage: np.ndarray


class Fields(NamedTuple):
    """The solver's padded fields and work arrays: velocities U, V and mass fluxes G, H with their
    ghost faces, the stacks C (centres, slots C_*), FU, FV (faces, slots F_*), and TAU, the shear
    stresses at the cell corners (nx + 1, ny + 1)."""

    U: np.ndarray
    V: np.ndarray
    G: np.ndarray
    H: np.ndarray
    C: np.ndarray
    FU: np.ndarray
    FV: np.ndarray
    TAU: np.ndarray


class Boundaries(NamedTuple):
    """What the boundary conditions made of the grid: the cell flags (nx + 2, ny + 2) (``grid.py``),
    face kinds and signs KU, KV (slots K_*), ghost rules RULES (slots RULE_*), and row_of (nx + 2, ny + 2),
    the equation row of each padded cell (-1: none; a periodic boundary cell has that of its twin)."""

    flags: np.ndarray
    KU: np.ndarray
    KV: np.ndarray
    RULES: np.ndarray
    row_of: np.ndarray


class PressureSystem(NamedTuple):
    """The pressure-correction equations: MAT (slots M_*) on a fixed CSC pattern (indices, indptr
    int64), VEC (slots V_*), and where the terms go: diag_pos (nx ny) the diagonal of each row,
    upos (nx + 1, ny, 4) and vpos (nx, ny + 1, 4) the entries (L, L), (L, R), (R, L), (R, R) of
    each face (-1: none), pin_pos the entries of row 0 (when the level is pinned)."""

    MAT: np.ndarray
    VEC: np.ndarray
    indices: np.ndarray
    indptr: np.ndarray
    diag_pos: np.ndarray
    upos: np.ndarray
    vpos: np.ndarray
    pin_pos: np.ndarray


class LUFactors(NamedTuple):
    """SuperLU factors for ``_linear_kernels.lu_solve``: LUI (slots L_*), the indices and data of the
    strictly lower L and the strictly upper U (CSC), and U's diagonal."""

    LUI: np.ndarray
    Li: np.ndarray
    Lx: np.ndarray
    Ui: np.ndarray
    Ux: np.ndarray
    Ud: np.ndarray


class BandFactors(NamedTuple):
    """Block-tridiagonal LU (``_linear_kernels.band_factor``): the inverse blocks BINV, the couplings
    BLU, the band numbering ``order`` of the unknowns and ``place`` (its blocks and places), and the
    block of each matrix entry's row (``block``)."""

    BINV: np.ndarray
    BLU: np.ndarray
    order: np.ndarray
    place: np.ndarray
    block: np.ndarray


class Multigrid(NamedTuple):
    """GMRES with the grid multigrid (``_multigrid_kernels``): the hierarchy MGL, MGI, MGA, MGW, the
    coarsest level's LU (DLU, PIV), the Krylov work KRY and HES, and ``ell``, the row and slot of each
    matrix entry in MGA."""

    MGL: np.ndarray
    MGI: np.ndarray
    MGA: np.ndarray
    MGW: np.ndarray
    DLU: np.ndarray
    PIV: np.ndarray
    KRY: np.ndarray
    HES: np.ndarray
    ell: np.ndarray
