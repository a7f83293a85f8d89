"""Compiled kernels of the gas solver: ghost values from cell flags, explicit momentum terms,
momentum prediction with the continuity residual, pressure-correction matrix, correction, and
``step``, the one kernel the solver calls per step (``start_step``, ``iterate``, ``end_step``).

Arrays are the solver's padded arrays (``grid.py``): centre arrays ``(nx + 2, ny + 2)``
with cell (i, j) at ``[i + 1, j + 1]``; ``U`` ``(nx + 5, ny + 4)`` with x-face (i, j)
at ``[i + 2, j + 2]``; ``V`` ``(nx + 4, ny + 5)`` with y-face (i, j) at ``[i + 2, j + 2]``.
Boundary behaviour comes only from the integer cell flags (Hoomans 1996 Table 1) and
the face kinds derived from them at set-up. The solver keeps most arrays in a few stacks
(``C``, ``FU``, ``FV``, ...) and parameter vectors (``fpar``, ``ipar``, ``out``), whose slots
``_layout.py`` names; the kernels it calls from Python take them grouped in the named tuples of
``_layout.py``. The linear solves are those of ``_linear_kernels`` (band LU, SuperLU factors) and
``_multigrid_kernels`` (GMRES with a grid multigrid).

Symbols inside kernels: ``E`` voidage ε, ``RHO`` gas density ρ_g, ``P`` pressure relative to
the reference pressure p_ref (so that small differences of a large pressure keep their digits),
``G``/``H`` mass flux densities (ερ)_f u, (ερ)_f v [kg m^-2 s^-1], ``beta`` the interphase
momentum-transfer coefficient β [kg m^-3 s^-1].

Face values of ε and ρ (``face_voidage``): the mean of the two cells, except on fixed
(inflow, wall) boundary faces, where the voidage is that of the boundary cell: the influx
cell's 0.4 of Hoomans 1996 §5.2, so that its mass flux is ε_in ρ u_interstitial. Kuipers
et al. (1992) take donor-cell ερ because their solids voidage is transported with the
flow; here ε comes from the particles, and face means keep the continuity residual a
smooth function of the pressure (donor switching made the Newton iteration cycle where
voidage jumps between cells with almost no flow).

Speed: on the small grids of coupled runs (15 × 45) a step costs a few tens of microseconds
per kernel, and on the shared machines of this project the cost follows the chains of
dependent operations more than the operation count. Hence the residual is gathered per cell
from face fluxes (no read-after-write through memory), divisions by dx, dy are multiplications,
and one compiled call (``step``) makes a whole step: Numba's dispatch costs per call and per argument.
"""
import numpy as np
from numba import njit

from ._layout import (  # codes and slots: the tables are in _layout.py
    BAD_BETA,
    BAD_VOIDAGE,
    C_E,
    C_EFIX,
    C_P,
    C_PFIX,
    C_PFIX_OLD,
    C_RHO,
    C_RO_OLD,
    C_SXX,
    C_SYY,
    CONVERGED,
    COPY,
    F_BETA,
    F_EF,
    F_EP,
    F_EX,
    F_FIX,
    F_FLUX,
    F_OLD,
    F_RHS,
    F_WOUT,
    F_X1,
    F_X2,
    FIXED,
    FP_AX,
    FP_AY,
    FP_COMP,
    FP_DT,
    FP_DX,
    FP_DY,
    FP_ETA,
    FP_GX,
    FP_GY,
    FP_MU,
    FP_PREF,
    FP_REUSE,
    FP_RHOC,
    FP_SLOW,
    FP_SQRT_TOL,
    FP_TOL,
    FP_VOL,
    I_BLOCKS,
    I_CHECKED,
    I_HAVE_LU,
    I_ITER,
    I_KRYLOV,
    I_KRYLOV_MAX,
    I_MAXIT,
    I_NFACT,
    I_NX,
    I_NY,
    I_PIN,
    I_PRESSURE_VOIDAGE,
    I_PX,
    I_PY,
    I_REFACTORED,
    I_RESUME,
    I_SCHEME,
    I_SOLVER,
    IN_BETA,
    IN_SOLIDS_U,
    IN_SOLIDS_V,
    IN_SOURCE_U,
    IN_SOURCE_V,
    IN_VOIDAGE,
    INPUT_OK,
    K_KIND,
    K_SIGN,
    M_DATA,
    M_FACTORED,
    MAX_ITERATIONS,
    MODE_CENTRE,
    MODE_FACE,
    MODE_NONE,
    MODE_SCALAR,
    NEED_FACTORS,
    NOT_FINITE,
    O_ACC,
    O_COURANT,
    O_IN,
    O_MASS,
    O_OUT,
    O_PREV,
    O_QREF,
    O_REL,
    O_RES,
    OUTFLOW_FACE,
    R_COPY,
    R_FIXED,
    R_WRAP,
    RULE_E,
    RULE_P,
    SOLVED,
    SOLVER_BAND,
    SOLVER_MULTIGRID,
    SOLVER_SUPERLU,
    V_DP,
    V_R,
    V_ROW,
    V_WORK,
    V_WORK2,
)
from ._layout import BandFactors, Boundaries, Fields, LUFactors, Multigrid, PressureSystem, StateArrays
from ._linear_kernels import band_factor, band_solve, lu_solve
from ._multigrid_kernels import gmres, mg_setup
from ._operators import (
    centre_to_x_faces,
    centre_to_y_faces,
    face_value,
    normal_stresses_at_centre,
    shear_stress_at_corner,
)
from .grid import (  # cell flags, Hoomans 1996 Table 1
    FREE_SLIP,
    INFLOW,
    NO_SLIP,
    PERIODIC,
)

UI = np.uintp  # unsigned array index: no wrap-around code for negative indices (``U`` is the x velocity here)
MASS_FLOOR = 1e-4  # share of (gas mass / dt) in the reference flow of the mass residual
BLOCK_REUSE = 0.3  # band: blocks whose rows changed by less than this share of FP_REUSE keep their factors


# ---------------------------------------------------------------------------- ghosts
@njit(cache=True, error_model="numpy")
def fill_centre_ghosts(q, flags, rule, fixed, nx, ny):
    """Boundary-cell values of a centre scalar from the flags: ``rule[flag]`` is R_COPY
    (adjacent interior value), R_FIXED (``fixed`` at that cell) or R_WRAP (opposite side).
    Corners (flag 7, no condition of their own): wrapped like the boundary cells beside them
    when a side is periodic, else the mean of those two boundary cells."""
    for j in range(1, ny + 1):
        r = rule[flags[0, j]]
        if r == R_COPY:
            q[0, j] = q[1, j]
        elif r == R_FIXED:
            q[0, j] = fixed[0, j]
        elif r == R_WRAP:
            q[0, j] = q[nx, j]
        r = rule[flags[nx + 1, j]]
        if r == R_COPY:
            q[nx + 1, j] = q[nx, j]
        elif r == R_FIXED:
            q[nx + 1, j] = fixed[nx + 1, j]
        elif r == R_WRAP:
            q[nx + 1, j] = q[1, j]
    for i in range(1, nx + 1):
        r = rule[flags[i, 0]]
        if r == R_COPY:
            q[i, 0] = q[i, 1]
        elif r == R_FIXED:
            q[i, 0] = fixed[i, 0]
        elif r == R_WRAP:
            q[i, 0] = q[i, ny]
        r = rule[flags[i, ny + 1]]
        if r == R_COPY:
            q[i, ny + 1] = q[i, ny]
        elif r == R_FIXED:
            q[i, ny + 1] = fixed[i, ny + 1]
        elif r == R_WRAP:
            q[i, ny + 1] = q[i, 1]
    if flags[0, 1] == PERIODIC:  # wrap the bottom and top boundary rows along x
        q[0, 0] = q[nx, 0]
        q[nx + 1, 0] = q[1, 0]
        q[0, ny + 1] = q[nx, ny + 1]
        q[nx + 1, ny + 1] = q[1, ny + 1]
    elif flags[1, 0] == PERIODIC:  # wrap the left and right boundary columns along y
        q[0, 0] = q[0, ny]
        q[nx + 1, 0] = q[nx + 1, ny]
        q[0, ny + 1] = q[0, 1]
        q[nx + 1, ny + 1] = q[nx + 1, 1]
    else:
        q[0, 0] = 0.5 * (q[1, 0] + q[0, 1])
        q[nx + 1, 0] = 0.5 * (q[nx, 0] + q[nx + 1, 1])
        q[0, ny + 1] = 0.5 * (q[1, ny + 1] + q[0, ny])
        q[nx + 1, ny + 1] = 0.5 * (q[nx, ny + 1] + q[nx + 1, ny])


@njit(cache=True, error_model="numpy", inline="always")
def _tangential(flag, mirror, wrapped):
    """Ghost value of a tangential velocity: no-slip reflects with a sign change (zero on the
    wall), free slip / pressure / outflow reflect (zero shear), inflow cells hold zero."""
    if flag == NO_SLIP:
        return -mirror
    if flag == INFLOW:
        return 0.0
    if flag == PERIODIC:
        return wrapped
    return mirror


@njit(cache=True, error_model="numpy", inline="always")
def _normal(flag, boundary, mirror, wrapped):
    """Ghost value of a normal velocity beyond a boundary face: walls reflect antisymmetrically
    (zero on the face), inflow / pressure / outflow extrapolate the face value."""
    if flag == NO_SLIP or flag == FREE_SLIP:
        return -mirror
    if flag == PERIODIC:
        return wrapped
    return boundary


@njit(cache=True, error_model="numpy")
def fill_face_ghosts(U, V, flags, nx, ny):
    """Ghost faces of a face-vector field (velocity or mass flux) from the flags; also the
    periodic duplicate faces (x-face nx = x-face 0, y-face ny = y-face 0)."""
    # U: tangential ghost rows below and above, then normal ghost columns for every row
    for i in range(nx + 1):
        c = min(i, nx - 1)
        fb = flags[c + 1, 0]
        ft = flags[c + 1, ny + 1]
        for k in range(1, 3):
            U[i + 2, 2 - k] = _tangential(fb, U[i + 2, 1 + k], U[i + 2, 2 + (ny - k) % ny])
            U[i + 2, ny + 1 + k] = _tangential(ft, U[i + 2, ny + 2 - k], U[i + 2, 2 + (k - 1) % ny])
    for jp in range(ny + 4):
        jc = min(max(jp - 2, 0), ny - 1)
        fl = flags[0, jc + 1]
        fr = flags[nx + 1, jc + 1]
        if fr == PERIODIC:
            U[nx + 2, jp] = U[2, jp]
        for k in range(1, 3):
            U[2 - k, jp] = _normal(fl, U[2, jp], U[2 + k, jp], U[2 + (nx - k) % nx, jp])
            U[nx + 2 + k, jp] = _normal(fr, U[nx + 2, jp], U[nx + 2 - k, jp], U[2 + k % nx, jp])
    # V: tangential ghost columns left and right, then normal ghost rows for every column
    for j in range(ny + 1):
        r = min(j, ny - 1)
        fl = flags[0, r + 1]
        fr = flags[nx + 1, r + 1]
        for k in range(1, 3):
            V[2 - k, j + 2] = _tangential(fl, V[1 + k, j + 2], V[2 + (nx - k) % nx, j + 2])
            V[nx + 1 + k, j + 2] = _tangential(fr, V[nx + 2 - k, j + 2], V[2 + (k - 1) % nx, j + 2])
    for ip in range(nx + 4):
        ic = min(max(ip - 2, 0), nx - 1)
        fb = flags[ic + 1, 0]
        ft = flags[ic + 1, ny + 1]
        if ft == PERIODIC:
            V[ip, ny + 2] = V[ip, 2]
        for k in range(1, 3):
            V[ip, 2 - k] = _normal(fb, V[ip, 2], V[ip, 2 + k], V[ip, 2 + (ny - k) % ny])
            V[ip, ny + 2 + k] = _normal(ft, V[ip, ny + 2], V[ip, ny + 2 - k], V[ip, 2 + k % ny])


# ---------------------------------------------------------------------------- copies and centre values
@njit(cache=True, error_model="numpy")
def copy_into(dst, src):
    """Copy ``src`` into the middle of the (padded) ``dst``, e.g. u (nx + 1, ny) into U
    (nx + 5, ny + 4). A loop: slice assignment costs much compile time."""
    i0 = (dst.shape[0] - src.shape[0]) // 2
    j0 = (dst.shape[1] - src.shape[1]) // 2
    for i in range(src.shape[0]):
        for j in range(src.shape[1]):
            dst[i0 + i, j0 + j] = src[i, j]


@njit(cache=True, error_model="numpy")
def copy_from(dst, src):
    """Copy the middle of the (padded) ``src`` into ``dst``."""
    i0 = (src.shape[0] - dst.shape[0]) // 2
    j0 = (src.shape[1] - dst.shape[1]) // 2
    for i in range(dst.shape[0]):
        for j in range(dst.shape[1]):
            dst[i, j] = src[i0 + i, j0 + j]


@njit(cache=True, error_model="numpy", inline="always")
def face_axis(centre, K):
    """(da, db) of a face stack ``K`` (or ``F``) against a padded centre array (nx + 2, ny + 2):
    (1, 0) for x-faces (nx + 1, ny), (0, 1) for y-faces (nx, ny + 1). Face (i, j) lies between
    the padded cells (i + 1 − da, j + 1 − db) and (i + 1, j + 1)."""
    da = K.shape[1] - (centre.shape[0] - 2)
    return da, 1 - da


@njit(cache=True, error_model="numpy")
def update_density(C, rho_factor, rho_const, p_ref):
    """ρ = (p' + p_ref) M/(RT) everywhere (Hoomans 1996 eq. 44; C[C_P] is the pressure relative
    to p_ref), or the constant density when rho_factor is 0."""
    P, RHO = C[C_P], C[C_RHO]
    if rho_factor != 0.0:
        for i in range(P.shape[0]):
            for j in range(P.shape[1]):
                RHO[i, j] = rho_factor * (P[i, j] + p_ref)
    else:
        for i in range(P.shape[0]):
            for j in range(P.shape[1]):
                RHO[i, j] = rho_const


@njit(cache=True, error_model="numpy")
def boundary_cells(C, pfix, flags, RULES, fpar, ipar):
    """Boundary cells of voidage and pressure (prescribed values from ``pfix``) from the flags,
    then the density everywhere."""
    nx, ny = ipar[I_NX], ipar[I_NY]
    fill_centre_ghosts(C[C_E], flags, RULES[RULE_E], C[C_EFIX], nx, ny)
    fill_centre_ghosts(C[C_P], flags, RULES[RULE_P], pfix, nx, ny)
    update_density(C, fpar[FP_COMP], fpar[FP_RHOC], fpar[FP_PREF])


# ---------------------------------------------------------------------------- step inputs
@njit(cache=True, error_model="numpy")
def _to_faces(mode, q, periodic, axis, out):
    """Face values ``out`` of an input given as a number (q[0, 0]), at centres or on faces."""
    if mode == MODE_SCALAR:
        x = q[0, 0]
        for i in range(out.shape[0]):
            for j in range(out.shape[1]):
                out[i, j] = x
    elif mode == MODE_CENTRE:
        if axis == 0:
            centre_to_x_faces(q, periodic, out)
        else:
            centre_to_y_faces(q, periodic, out)
    elif mode == MODE_FACE:
        for i in range(out.shape[0]):
            for j in range(out.shape[1]):
                out[i, j] = q[i, j]
    else:
        for i in range(out.shape[0]):
            for j in range(out.shape[1]):
                out[i, j] = 0.0


@njit(cache=True, error_model="numpy")
def _add_product(mode, q, periodic, axis, beta, rhs, work):
    """rhs += beta * (the face values of the input q), or rhs += the face values when beta is empty."""
    if mode == MODE_NONE:
        return
    _to_faces(mode, q, periodic, axis, work)
    if beta.shape[0] == 0:
        for i in range(rhs.shape[0]):
            for j in range(rhs.shape[1]):
                rhs[i, j] += work[i, j]
    else:
        for i in range(rhs.shape[0]):
            for j in range(rhs.shape[1]):
                rhs[i, j] += beta[i, j] * work[i, j]


@njit(cache=True, error_model="numpy")
def load_inputs(eps_in, bu, bv, su, sv, qu, qv, modes, FU, FV, px, py):
    """β, β u_s + source (FU/FV[F_BETA], [F_RHS]) from the step inputs (``modes`` per input, see
    IN_*; a centre array is averaged onto the faces as ``centre_to_x_faces`` does) and the checks
    of the new voidage (0 < ε ≤ 1) and of β (finite, ≥ 0). Returns INPUT_OK, BAD_VOIDAGE or BAD_BETA.
    The solids velocity counts only where β is given."""
    if modes[IN_VOIDAGE] != MODE_NONE:
        for i in range(eps_in.shape[0]):
            for j in range(eps_in.shape[1]):
                e = eps_in[i, j]
                if not (e > 0.0 and e <= 1.0):
                    return BAD_VOIDAGE
    bmode = modes[IN_BETA]
    _to_faces(bmode, bu, px, 0, FU[F_BETA])
    _to_faces(bmode, bv, py, 1, FV[F_BETA])
    for F in (FU, FV):
        beta = F[F_BETA]
        for i in range(beta.shape[0]):
            for j in range(beta.shape[1]):
                x = beta[i, j]
                if not (x >= 0.0 and x < np.inf):
                    return BAD_BETA
        rhs = F[F_RHS]
        for i in range(rhs.shape[0]):
            for j in range(rhs.shape[1]):
                rhs[i, j] = 0.0
    none = FU[F_BETA, :0]
    if bmode != MODE_NONE:
        _add_product(modes[IN_SOLIDS_U], su, px, 0, FU[F_BETA], FU[F_RHS], FU[F_WOUT])
        _add_product(modes[IN_SOLIDS_V], sv, py, 1, FV[F_BETA], FV[F_RHS], FV[F_WOUT])
    _add_product(modes[IN_SOURCE_U], qu, px, 0, none, FU[F_RHS], FU[F_WOUT])
    _add_product(modes[IN_SOURCE_V], qv, py, 1, FV[F_BETA, :0], FV[F_RHS], FV[F_WOUT])
    return INPUT_OK


@njit(cache=True, error_model="numpy")
def load_pressure_voidage(eu, ev, FU, FV):
    """The step input ``pressure_voidage`` (x-face, y-face arrays) into FU/FV[F_EP]; False if a value
    lies outside (0, 1] (NaN included)."""
    ok = True
    for E, F in ((eu, FU), (ev, FV)):
        EP = F[F_EP]
        for i in range(E.shape[0]):
            for j in range(E.shape[1]):
                e = E[i, j]
                if not (e > 0.0 and e <= 1.0):
                    ok = False
                EP[i, j] = e
    return ok


# ---------------------------------------------------------------------------- explicit terms
@njit(cache=True, error_model="numpy", inline="always")
def face_voidage(E, la, lb, ra, rb, kind, sign):
    """ε on the face between padded cells (la, lb) and (ra, rb): the mean, or on a fixed boundary
    face the boundary cell's (sign > 0: the boundary cell is on the low side)."""
    if kind == FIXED:
        return E[la, lb] if sign > 0 else E[ra, rb]
    return 0.5 * (E[la, lb] + E[ra, rb])


@njit(cache=True, error_model="numpy")
def _mass_flux(W, Q, E, RHO, K):
    """Q = (ερ)_f w on the faces of one direction [kg m^-2 s^-1]."""
    kind, sign = K[K_KIND], K[K_SIGN]
    da, db = face_axis(E, K)
    for i in range(kind.shape[0]):
        for j in range(kind.shape[1]):
            la, lb, ra, rb = i + 1 - da, j + 1 - db, i + 1, j + 1
            ef = face_voidage(E, la, lb, ra, rb, kind[i, j], sign[i, j])
            Q[i + 2, j + 2] = ef * 0.5 * (RHO[la, lb] + RHO[ra, rb]) * W[i + 2, j + 2]


@njit(cache=True, error_model="numpy")
def mass_fluxes(U, V, E, RHO, G, H, KU, KV, flags, nx, ny):
    """G = (ερ)_f u on x-faces and H = (ερ)_f v on y-faces [kg m^-2 s^-1], ghosts filled like velocities."""
    _mass_flux(U, G, E, RHO, KU)
    _mass_flux(V, H, E, RHO, KV)
    fill_face_ghosts(G, H, flags, nx, ny)


@njit(cache=True, error_model="numpy")
def _stresses(U, V, E, mu, dx, dy, SXX, SYY, TAU, nx, ny):
    """The stresses of ε τ_g that ``explicit_momentum`` differences, each computed once:
    σ_xx at centres (ci, cj), ci = -1..nx, cj = 0..ny-1 and σ_yy at ci = 0..nx-1, cj = -1..ny,
    stored at [ci + 1, cj + 1]; the shear stress at every corner (i, j), i = 0..nx, j = 0..ny."""
    for ci in range(-1, nx + 1):
        for cj in range(-1, ny + 1):
            if (ci < 0 or ci >= nx) and (cj < 0 or cj >= ny):
                continue
            sxx, syy = normal_stresses_at_centre(U, V, E, mu, dx, dy, ci, cj)
            SXX[ci + 1, cj + 1] = sxx
            SYY[ci + 1, cj + 1] = syy
    for i in range(nx + 1):
        for j in range(ny + 1):
            TAU[i, j] = shear_stress_at_corner(U, V, E, mu, dx, dy, i, j)


@njit(cache=True, error_model="numpy")
def explicit_momentum(U, V, G, H, E, mu, dx, dy, scheme, ukind, vkind, exu, exv, nx, ny, SXX, SYY, TAU):
    """Explicit part of the momentum balance (Hoomans 1996 eq. 43) on every solved face [N m^-3]:
    exu = −[∇·(ερ u u) − u ∇·(ερ u)] − ∇·(ε τ_g), the convection in advective form (the mass
    fluxes G, H of the continuity equation; face velocities by ``scheme``) and the viscous
    stress of eq. 48 (λ_g = 0); SXX, SYY (centre), TAU (corner) are work arrays for the stresses."""
    _stresses(U, V, E, mu, dx, dy, SXX, SYY, TAU, nx, ny)
    idx, idy = 1.0 / dx, 1.0 / dy
    for i in range(nx + 1):
        for j in range(ny):
            if ukind[i, j] != SOLVED:
                exu[i, j] = 0.0
                continue
            I, J = i + 2, j + 2
            up = U[I, J]
            fe = 0.5 * (G[I, J] + G[I + 1, J])
            fw = 0.5 * (G[I - 1, J] + G[I, J])
            fn = 0.5 * (H[i + 1, j + 3] + H[i + 2, j + 3])
            fs = 0.5 * (H[i + 1, j + 2] + H[i + 2, j + 2])
            ue = face_value(fe, U[I - 1, J], up, U[I + 1, J], U[I + 2, J], scheme)
            uw = face_value(fw, U[I - 2, J], U[I - 1, J], up, U[I + 1, J], scheme)
            un = face_value(fn, U[I, J - 1], up, U[I, J + 1], U[I, J + 2], scheme)
            us = face_value(fs, U[I, J - 2], U[I, J - 1], up, U[I, J + 1], scheme)
            adv = (fe * (ue - up) - fw * (uw - up)) * idx + (fn * (un - up) - fs * (us - up)) * idy
            exu[i, j] = -adv + (SXX[i + 1, j + 1] - SXX[i, j + 1]) * idx + (TAU[i, j + 1] - TAU[i, j]) * idy
    for i in range(nx):
        for j in range(ny + 1):
            if vkind[i, j] != SOLVED:
                exv[i, j] = 0.0
                continue
            I, J = i + 2, j + 2
            vp = V[I, J]
            fn = 0.5 * (H[I, J] + H[I, J + 1])
            fs = 0.5 * (H[I, J - 1] + H[I, J])
            fe = 0.5 * (G[i + 3, j + 1] + G[i + 3, j + 2])
            fw = 0.5 * (G[i + 2, j + 1] + G[i + 2, j + 2])
            vn = face_value(fn, V[I, J - 1], vp, V[I, J + 1], V[I, J + 2], scheme)
            vs = face_value(fs, V[I, J - 2], V[I, J - 1], vp, V[I, J + 1], scheme)
            ve = face_value(fe, V[I - 1, J], vp, V[I + 1, J], V[I + 2, J], scheme)
            vw = face_value(fw, V[I - 2, J], V[I - 1, J], vp, V[I + 1, J], scheme)
            adv = (fn * (vn - vp) - fs * (vs - vp)) * idy + (fe * (ve - vp) - fw * (vw - vp)) * idx
            exv[i, j] = -adv + (SYY[i + 1, j + 1] - SYY[i + 1, j]) * idy + (TAU[i + 1, j] - TAU[i, j]) * idx


@njit(cache=True, error_model="numpy")
def _outflow_shares(F, K, C, area, total):
    """Outward mass flux through the interior face next to each continuous-outflow face, at t
    (zero normal gradient), into F[F_WOUT]; adds them to ``total`` = [sum, sum of |.|, area]."""
    RHO, E = C[C_RHO], C[C_E]
    kind, sign, old, share = K[K_KIND], K[K_SIGN], F[F_OLD], F[F_WOUT]
    da, db = face_axis(C[0], K)
    n1, n2 = kind.shape[0], kind.shape[1]
    for i in range(n1):
        for j in range(n2):
            if kind[i, j] != OUTFLOW_FACE:
                share[i, j] = 0.0
                continue
            s = sign[i, j]
            w = old[min(max(i + s * da, 0), n1 - 1), min(max(j + s * db, 0), n2 - 1)]
            ca, cb = (i + 1, j + 1) if s > 0 else (i + 1 - da, j + 1 - db)  # the interior cell
            f = -s * w * E[ca, cb] * RHO[ca, cb] * area
            share[i, j] = f
            total[0] += f
            total[1] += abs(f)
            total[2] += area


@njit(cache=True, error_model="numpy")
def _normalise_shares(F, K, area, total):
    kind, share = K[K_KIND], F[F_WOUT]
    by_flow = total[0] > 1e-9 * total[1] and total[0] > 0.0
    for i in range(share.shape[0]):
        for j in range(share.shape[1]):
            if kind[i, j] == OUTFLOW_FACE:
                share[i, j] = share[i, j] / total[0] if by_flow else area / total[2]


@njit(cache=True, error_model="numpy")
def _face_constants(C, F, K, gravity, idt, given):
    """Per step, on the faces of one direction: ε_f at t + dt (``face_voidage``), X1 = u_old/dt + g,
    X2 = explicit terms + β u_s + source; the pressure term's ε_p,f = ε_f unless ``given`` (then
    F[F_EP] holds the step input ``pressure_voidage``)."""
    E = C[C_E]
    kind, sign = K[K_KIND], K[K_SIGN]
    EF, X1, X2, old, ex, rhs, EP = F[F_EF], F[F_X1], F[F_X2], F[F_OLD], F[F_EX], F[F_RHS], F[F_EP]
    da, db = face_axis(E, K)
    for i in range(kind.shape[0]):
        for j in range(kind.shape[1]):
            k = kind[i, j]
            la, lb, ra, rb = i + 1 - da, j + 1 - db, i + 1, j + 1
            EF[i, j] = face_voidage(E, la, lb, ra, rb, k, sign[i, j])
            if not given:
                EP[i, j] = EF[i, j]
            X1[i, j] = old[i, j] * idt + gravity
            X2[i, j] = ex[i, j] + rhs[i, j]


@njit(cache=True, error_model="numpy")
def begin_step(state, eps_new, fields, bnd, fpar, ipar):
    """Load the state at t (``state``, a ``StateArrays``; p as gauge pressure), fill its ghosts, its
    mass fluxes and the explicit momentum terms FU[F_EX], FV[F_EX]; the shares of the
    continuous outflow; then the new voidage (``eps_new``, (nx, ny)) and the boundary cells at
    t + dt, and the per-step face constants. FU/FV[F_BETA] and [F_RHS] must hold this step's
    β and β u_s + source (``load_inputs``). ``fields``: ``Fields``, ``bnd``: ``Boundaries``."""
    p, rho, u, v, eps_old = state.p, state.rho, state.u, state.v, state.voidage
    U, V, G, H, C, FU, FV, TAU = fields.U, fields.V, fields.G, fields.H, fields.C, fields.FU, fields.FV, fields.TAU
    flags, KU, KV, RULES = bnd.flags, bnd.KU, bnd.KV, bnd.RULES
    nx, ny = ipar[I_NX], ipar[I_NY]
    p_ref = fpar[FP_PREF]
    P, E, RO = C[C_P], C[C_E], C[C_RO_OLD]
    for i in range(nx):
        for j in range(ny):
            P[i + 1, j + 1] = p[i, j] - p_ref
            E[i + 1, j + 1] = eps_old[i, j]
            RO[i + 1, j + 1] = eps_old[i, j] * rho[i, j]
    copy_into(U, u)
    copy_into(V, v)
    copy_into(FU[F_OLD], u)
    copy_into(FV[F_OLD], v)
    boundary_cells(C, C[C_PFIX_OLD], flags, RULES, fpar, ipar)
    fill_face_ghosts(U, V, flags, nx, ny)
    mass_fluxes(U, V, E, C[C_RHO], G, H, KU, KV, flags, nx, ny)
    explicit_momentum(U, V, G, H, E, fpar[FP_MU], fpar[FP_DX], fpar[FP_DY], ipar[I_SCHEME], KU[K_KIND],
                      KV[K_KIND], FU[F_EX], FV[F_EX], nx, ny, C[C_SXX], C[C_SYY], TAU)
    total = np.zeros(3)
    _outflow_shares(FU, KU, C, fpar[FP_AX], total)
    _outflow_shares(FV, KV, C, fpar[FP_AY], total)
    if total[2] > 0.0:
        _normalise_shares(FU, KU, fpar[FP_AX], total)
        _normalise_shares(FV, KV, fpar[FP_AY], total)
    for i in range(nx):
        for j in range(ny):
            E[i + 1, j + 1] = eps_new[i, j]
    boundary_cells(C, C[C_PFIX], flags, RULES, fpar, ipar)
    idt = 1.0 / fpar[FP_DT]
    given = ipar[I_PRESSURE_VOIDAGE] != 0
    _face_constants(C, FU, KU, fpar[FP_GX], idt, given)
    _face_constants(C, FV, KV, fpar[FP_GY], idt, given)


@njit(cache=True, error_model="numpy")
def start_step(dt, state, eps_new, bu, bv, su, sv, qu, qv, modes, fields, bnd, fpar, ipar, out):
    """``load_inputs`` (returns BAD_VOIDAGE or BAD_BETA when an input is out of range), then
    ``begin_step`` for a step of ``dt`` [s], and the counters of ``iterate`` reset; returns INPUT_OK."""
    status = load_inputs(eps_new, bu, bv, su, sv, qu, qv, modes, fields.FU, fields.FV, ipar[I_PX] != 0,
                         ipar[I_PY] != 0)
    if status != INPUT_OK:
        return status
    fpar[FP_DT] = dt
    begin_step(state, eps_new, fields, bnd, fpar, ipar)
    ipar[I_ITER] = 0
    ipar[I_CHECKED] = 0
    ipar[I_REFACTORED] = 0
    ipar[I_RESUME] = 0
    out[O_PREV] = np.inf
    return INPUT_OK


@njit(cache=True, error_model="numpy")
def end_step(state, eps_new, fields, p_ref):
    """Write the fields at t + dt back into the state arrays (p as absolute pressure, ε = eps_new)."""
    p, rho, u, v, eps = state.p, state.rho, state.u, state.v, state.voidage
    nx, ny = p.shape
    C = fields.C
    P, RHO = C[C_P], C[C_RHO]
    for i in range(nx):
        for j in range(ny):
            p[i, j] = P[i + 1, j + 1] + p_ref
            rho[i, j] = RHO[i + 1, j + 1]
            eps[i, j] = eps_new[i, j]
    copy_from(u, fields.U)
    copy_from(v, fields.V)


# ---------------------------------------------------------------------------- one iteration
@njit(cache=True, error_model="numpy")
def _face_fluxes(W, C, F, K, idt, ih, area):
    """Momentum of the faces of one direction (x-faces: W = U, F = FU; y-faces: V, FV) at the
    current pressure, and their mass fluxes A (ερ)_f w along +x (+y) [kg/s] into F[F_FLUX]:
    0 on outflow faces (``_outflow`` adds theirs), periodic duplicates those of face 0.
    Returns whether there are outflow faces."""
    P, RHO = C[C_P], C[C_RHO]
    kind = K[K_KIND]
    EF, X1, X2, beta, fix, FL, EP = F[F_EF], F[F_X1], F[F_X2], F[F_BETA], F[F_FIX], F[F_FLUX], F[F_EP]
    has_outflow = False
    da, db = face_axis(P, K)
    n1, n2 = kind.shape[0], kind.shape[1]
    for i_ in range(n1):  # unsigned indices (``UI``): no wrap-around code
        i = UI(i_)
        for j_ in range(n2):
            j = UI(j_)
            k = kind[i, j]
            la, lb, ra, rb = UI(i_ + 1 - da), UI(j_ + 1 - db), i + UI(1), j + UI(1)
            if k == SOLVED:
                rf = 0.5 * (RHO[la, lb] + RHO[ra, rb])
                ef = EF[i, j]
                m = ef * rf
                a = m * idt + beta[i, j]
                w = (m * X1[i, j] + X2[i, j] - EP[i, j] * (P[ra, rb] - P[la, lb]) * ih) / a
                W[i + UI(2), j + UI(2)] = w
                FL[i, j] = area * ef * rf * w
            elif k == FIXED:
                w = fix[i, j]
                W[i + UI(2), j + UI(2)] = w
                FL[i, j] = area * EF[i, j] * 0.5 * (RHO[la, lb] + RHO[ra, rb]) * w
            elif k == OUTFLOW_FACE:
                FL[i, j] = 0.0
                has_outflow = True
    if da == 1:
        for j in range(n2):
            if kind[n1 - 1, j] == COPY:
                FL[n1 - 1, j] = FL[0, j]
    else:
        for i in range(n1):
            if kind[i, n2 - 1] == COPY:
                FL[i, n2 - 1] = FL[i, 0]
    return has_outflow


@njit(cache=True, error_model="numpy")
def _boundary_flows(F, K):
    """(inflow, outflow, net inflow) [kg/s] through the boundary faces of one direction (F[F_FLUX])."""
    kind, sign, FL = K[K_KIND], K[K_SIGN], F[F_FLUX]
    inflow = 0.0
    outflow = 0.0
    net_in = 0.0
    n1, n2 = kind.shape[0], kind.shape[1]
    for i in range(n1):
        edge = i == 0 or i == n1 - 1
        step = 1 if edge or n2 < 2 else n2 - 1  # inside rows: their first and last face only
        for j in range(0, n2, step):
            s = sign[i, j]
            k = kind[i, j]
            if s == 0 or k == COPY or k == OUTFLOW_FACE:
                continue
            fin = s * FL[i, j]
            net_in += fin
            if fin > 0.0:
                inflow += fin
            else:
                outflow -= fin
    return inflow, outflow, net_in


@njit(cache=True, error_model="numpy")
def _outflow(W, C, F, K, row_of, R, area, need):
    """Continuous-outflow faces of one direction carry their share F[F_WOUT] of the outflow
    ``need`` [kg/s]; their velocity follows from the interior cell's ε ρ. Returns (in, out)."""
    RHO, E = C[C_RHO], C[C_E]
    kind, sign, share = K[K_KIND], K[K_SIGN], F[F_WOUT]
    inflow = 0.0
    outflow = 0.0
    da, db = face_axis(E, K)
    for i in range(kind.shape[0]):
        for j in range(kind.shape[1]):
            if kind[i, j] != OUTFLOW_FACE:
                continue
            s = sign[i, j]
            fout = share[i, j] * need
            la, lb, ra, rb = i + 1 - da, j + 1 - db, i + 1, j + 1
            ca, cb = (la, lb) if s < 0 else (ra, rb)  # the interior cell
            f = -s * fout  # flux along +x (+y)
            W[i + 2, j + 2] = f / (area * E[ca, cb] * RHO[ca, cb])
            rl = row_of[la, lb]
            rr = row_of[ra, rb]
            if rl >= 0:
                R[rl] += f
            if rr >= 0:
                R[rr] -= f
            if fout > 0.0:
                outflow += fout
            else:
                inflow -= fout
    return inflow, outflow


@njit(cache=True, error_model="numpy")
def predict_residual(U, V, C, FU, FV, KU, KV, row_of, R, fpar, ipar):
    """Face velocities from the momentum balance at the current pressure, then the cell
    continuity residuals (Hoomans 1996 eqs 42-43).

    Momentum on a solved face, implicit in pressure and drag (Kuipers et al. 1992)::

        (ερ)_f (u - u_old)/dt = ex - ε_f ∂p/∂x - β (u - u_s) + (ερ)_f g_x + source
        u = û - D ∂p/∂x,   D = ε_f / ((ερ)_f/dt + β)

    with ``F_RHS = β u_s + source``. Continuity residual of cell c [kg/s]::

        R_c = V [(ερ)_c - (ερ)_c,old]/dt + Σ_faces A (ερ)_f u_out

    Outflow faces carry F_WOUT × the outflow that closes the mass balance. Returns
    (Σ|R|, reference flow, inflow, outflow, accumulation, mass). Ghost faces are not filled.
    """
    nx, ny = ipar[I_NX], ipar[I_NY]
    dt, vol = fpar[FP_DT], fpar[FP_VOL]
    idt = 1.0 / dt
    RHO, E, RO = C[C_RHO], C[C_E], C[C_RO_OLD]
    of_x = _face_fluxes(U, C, FU, KU, idt, 1.0 / fpar[FP_DX], fpar[FP_AX])
    of_y = _face_fluxes(V, C, FV, KV, idt, 1.0 / fpar[FP_DY], fpar[FP_AY])
    FLU, FLV = FU[F_FLUX], FV[F_FLUX]
    acc = 0.0
    acc_abs = 0.0
    mass = 0.0
    vdt = vol * idt
    for i_ in range(nx):
        i = UI(i_)
        for j_ in range(ny):
            j = UI(j_)
            er = E[i + UI(1), j + UI(1)] * RHO[i + UI(1), j + UI(1)]
            a = vdt * (er - RO[i + UI(1), j + UI(1)])
            R[i * UI(ny) + j] = a + ((FLU[i + UI(1), j] - FLU[i, j]) + (FLV[i, j + UI(1)] - FLV[i, j]))
            acc += a
            acc_abs += abs(a)
            mass += er
    mass *= vol
    in_x, out_x, net_x = _boundary_flows(FU, KU)
    in_y, out_y, net_y = _boundary_flows(FV, KV)
    inflow = in_x + in_y
    outflow = out_x + out_y
    if of_x or of_y:
        need = net_x + net_y - acc
        a, b = _outflow(U, C, FU, KU, row_of, R, fpar[FP_AX], need)
        c, d = _outflow(V, C, FV, KV, row_of, R, fpar[FP_AY], need)
        inflow += a + c
        outflow += b + d
    res = 0.0
    for k in range(nx * ny):
        res += abs(R[k])
    qref = inflow + outflow + acc_abs + MASS_FLOOR * mass * idt
    return res, qref, inflow, outflow, acc, mass


@njit(cache=True, error_model="numpy")
def courant_number(U, V, fpar, ipar):
    """max|u| dt/dx + max|v| dt/dy over the faces [-]."""
    nx, ny = ipar[I_NX], ipar[I_NY]
    umax = 0.0
    for i in range(nx + 1):
        for j in range(ny):
            umax = max(umax, abs(U[i + 2, j + 2]))
    vmax = 0.0
    for i in range(nx):
        for j in range(ny + 1):
            vmax = max(vmax, abs(V[i + 2, j + 2]))
    dt = fpar[FP_DT]
    return umax * dt / fpar[FP_DX] + vmax * dt / fpar[FP_DY]


# ---------------------------------------------------------------------------- pressure correction
@njit(cache=True, error_model="numpy")
def _assemble_faces(data, pos, W, C, F, K, area, h, comp, idt):
    """Face terms of the pressure matrix for one direction (see ``assemble_pressure``)."""
    RHO = C[C_RHO]
    kind, EF, beta, X1, EP = K[K_KIND], F[F_EF], F[F_BETA], F[F_X1], F[F_EP]
    da, db = face_axis(RHO, K)
    half_comp = 0.5 * comp
    for i in range(kind.shape[0]):
        for j in range(kind.shape[1]):
            k = kind[i, j]
            if k == COPY or k == OUTFLOW_FACE:
                continue
            la, lb, ra, rb = i + 1 - da, j + 1 - db, i + 1, j + 1
            w = W[i + 2, j + 2]
            ef = EF[i, j]
            rf = 0.5 * (RHO[la, lb] + RHO[ra, rb])
            base = area * ef * rf
            a = ef * rf * idt + beta[i, j]
            d = EP[i, j] / a if k == SOLVED else 0.0  # D = ε_p,f / a
            c = base * d / h
            # d(flux)/dp of either cell through ρ_f = (ρ_L + ρ_R)/2, in the flux and (solved faces)
            # in the inertia (ερ)_f of the face velocity: du/dρ_f = ε_f ((u_old - u)/dt + g) / a
            t = area * ef * w * half_comp
            if k == SOLVED and comp != 0.0:
                t += base * (ef / a) * half_comp * (X1[i, j] - w * idt)
            # flux out of L: (c + t) p'_L + (t - c) p'_R ; out of R: the negative
            p_ll, p_lr, p_rl, p_rr = pos[i, j, 0], pos[i, j, 1], pos[i, j, 2], pos[i, j, 3]
            if p_ll >= 0:
                data[p_ll] += c + t
            if p_lr >= 0:
                data[p_lr] += t - c
            if p_rl >= 0:
                data[p_rl] -= c + t
            if p_rr >= 0:
                data[p_rr] += c - t


@njit(cache=True, error_model="numpy")
def assemble_pressure(data, diag_pos, upos, vpos, pin_pos, U, V, C, FU, FV, KU, KV, fpar, ipar):
    """Matrix of the pressure correction p' (CSC ``data`` of a fixed pattern): the Newton
    derivative (Jacobian) of the continuity residuals R_c with respect to the cell pressures.

    Terms: compressibility ε V comp / dt on the diagonal (comp = M/(RT), 0 for constant
    density; Hoomans 1996 eq. 44), A (ερ)_f D / h between the two cells of each solved
    face, and per cell, through the face density (ρ_L + ρ_R)/2 of every face with flow,
    A ε_f u comp / 2 (the density in the flux) plus, on solved faces, A (ερ)_f D comp/2
    ((u_old - u)/dt + g) (the density in the inertia of the face momentum).
    ``upos[i, j]`` holds the positions of (row L, col L), (row L, col R), (row R, col L),
    (row R, col R), −1 where a row or column does not exist. ``pin_pos``: positions of
    row 0, replaced by p'_0 = 0 (constant-density gas without a pressure boundary).
    """
    nx, ny, pin_diag = ipar[I_NX], ipar[I_NY], ipar[I_PIN]
    comp, dt, vol = fpar[FP_COMP], fpar[FP_DT], fpar[FP_VOL]
    E = C[C_E]
    for k in range(data.size):
        data[k] = 0.0
    if comp != 0.0:
        for i in range(nx):
            for j in range(ny):
                data[diag_pos[i * ny + j]] += comp * E[i + 1, j + 1] * vol / dt
    _assemble_faces(data, upos, U, C, FU, KU, fpar[FP_AX], fpar[FP_DX], comp, 1.0 / dt)
    _assemble_faces(data, vpos, V, C, FV, KV, fpar[FP_AY], fpar[FP_DY], comp, 1.0 / dt)
    if pin_diag >= 0:
        for p in pin_pos:
            data[p] = 0.0
        data[pin_diag] = 1.0


# ---------------------------------------------------------------------------- the iterations of a step
@njit(cache=True, error_model="numpy")
def iterate(fields, bnd, system, lu, band, mg, fpar, ipar, out):
    """Pressure-correction (Newton) iterations of one time step until the mass residual is below
    ``fpar[FP_TOL]``; the arrays grouped as ``_layout`` names them (``Fields``, ``Boundaries``,
    ``PressureSystem``, ``LUFactors``, ``BandFactors``, ``Multigrid``).

    Each iteration: momentum prediction and continuity residual (``predict_residual``), then
    p' from the pressure matrix (the Jacobian of the residuals) and p += p'. Band and SuperLU:
    the factors are those of an earlier matrix while no entry of the current one differs from it
    by more than ``FP_REUSE`` times its largest entry; when one does, or an iteration reduces the
    residual by less than ``FP_SLOW``, the matrix is factorised again: here as a band
    (``band_factor``; after a change of the step's matrix from the first block whose rows
    changed by more than BLOCK_REUSE × FP_REUSE), or else by the caller with SuperLU: the kernel
    returns NEED_FACTORS with the current matrix in ``MAT[M_DATA]`` and is called again
    (``I_RESUME`` then skips straight to the solve). Multigrid: the matrix and its hierarchy
    are made again on every iteration (Newton); each p' comes from GMRES to a residual ``FP_ETA``
    times that of the iteration (no smaller than a tenth of the step's tolerance); if GMRES
    stalls, or the hierarchy cannot be made, the solver falls back to SuperLU. Returns
    CONVERGED, MAX_ITERATIONS or NOT_FINITE, with the ghost faces filled and the step's
    diagnostics in ``out``.
    """
    U, V, C, FU, FV = fields.U, fields.V, fields.C, fields.FU, fields.FV
    flags, KU, KV, RULES, row_of = bnd.flags, bnd.KU, bnd.KV, bnd.RULES, bnd.row_of
    MAT, VEC = system.MAT, system.VEC
    diag_pos, upos, vpos, pin_pos = system.diag_pos, system.upos, system.vpos, system.pin_pos
    BAND, BLU, order = band.BINV, band.BLU, band.order
    nx, ny, max_it, pin_diag = ipar[I_NX], ipar[I_NY], ipar[I_MAXIT], ipar[I_PIN]
    R, dp, work = VEC[V_R], VEC[V_DP], VEC[V_WORK]
    data, factored = MAT[M_DATA], MAT[M_FACTORED]
    n = nx * ny
    it = ipar[I_ITER]
    while True:
        if ipar[I_RESUME] == 0:
            res, qref, fin, fout, acc, mass = predict_residual(U, V, C, FU, FV, KU, KV, row_of, R, fpar, ipar)
            rel = res / qref if qref > 0.0 else 0.0
            out[O_RES], out[O_QREF], out[O_IN], out[O_OUT] = res, qref, fin, fout
            out[O_ACC], out[O_MASS], out[O_REL] = acc, mass, rel
            ipar[I_ITER] = it
            status = -1
            if not np.isfinite(rel):
                status = NOT_FINITE
            elif rel <= fpar[FP_TOL]:
                status = CONVERGED
            elif it >= max_it:
                status = MAX_ITERATIONS
            if status >= 0:
                fill_face_ghosts(U, V, flags, nx, ny)
                out[O_COURANT] = courant_number(U, V, fpar, ipar)
                return status
            need = False
            j0 = 0  # band: first block to factorise again
            solver = ipar[I_SOLVER]
            if ipar[I_CHECKED] == 0:
                ipar[I_CHECKED] = 1
                assemble_pressure(data, diag_pos, upos, vpos, pin_pos, U, V, C, FU, FV, KU, KV, fpar, ipar)
                if ipar[I_HAVE_LU] == 0 or solver == SOLVER_MULTIGRID:
                    need = True
                else:
                    amax = 0.0
                    for k in range(data.size):
                        amax = max(amax, abs(factored[k]))
                    tol = fpar[FP_REUSE] * amax
                    for k in range(data.size):
                        if abs(data[k] - factored[k]) > tol:
                            need = True
                            break
                    if need and solver == SOLVER_BAND:
                        # from the first block (in elimination order) that changed by more than a share
                        # BLOCK_REUSE of the tolerance: the blocks before it keep their factors
                        j0 = BAND.shape[0]
                        tol *= BLOCK_REUSE
                        for k in range(data.size):
                            if abs(data[k] - factored[k]) > tol:
                                j0 = min(j0, band.block[k])
            elif solver == SOLVER_MULTIGRID or (rel > fpar[FP_SLOW] * out[O_PREV] and ipar[I_REFACTORED] == 0):
                # multigrid: a new Jacobian every iteration (Newton), its hierarchy costs little
                assemble_pressure(data, diag_pos, upos, vpos, pin_pos, U, V, C, FU, FV, KU, KV, fpar, ipar)
                need = True
            if need:
                ipar[I_REFACTORED] = 1
                if solver == SOLVER_BAND and band_factor(data, system.indices, system.indptr, band.place, BAND, BLU,
                                                         VEC[V_ROW:V_ROW + 2], j0) > 1e-12:
                    for k in range(data.size):
                        if band.block[k] >= j0:
                            factored[k] = data[k]
                    ipar[I_HAVE_LU] = 1
                    ipar[I_NFACT] += 1
                    ipar[I_BLOCKS] += BAND.shape[0] - j0
                elif solver == SOLVER_MULTIGRID and mg_setup(data, mg.ell, mg.MGL, mg.MGI, mg.MGA, mg.MGW, mg.DLU,
                                                             mg.PIV):
                    for k in range(data.size):
                        factored[k] = data[k]
                    ipar[I_HAVE_LU] = 1
                    ipar[I_NFACT] += 1
                else:  # SuperLU, by the caller (from now on, if the band had a poor pivot)
                    ipar[I_SOLVER] = SOLVER_SUPERLU
                    ipar[I_RESUME] = 1
                    return NEED_FACTORS
        ipar[I_RESUME] = 0
        out[O_PREV] = out[O_REL]
        for k in range(n):
            R[k] = -R[k]
        if pin_diag >= 0:
            R[0] = 0.0
        solver = ipar[I_SOLVER]
        if solver == SOLVER_BAND:
            band_solve(BAND, BLU, order, R, dp, work, VEC[V_ROW], VEC[V_WORK2])
        elif solver == SOLVER_MULTIGRID:
            rn = 0.0
            for k in range(n):
                rn += R[k] * R[k]
            target = max(fpar[FP_ETA] * np.sqrt(rn), 0.1 * fpar[FP_TOL] * out[O_QREF] / np.sqrt(n))
            kits = gmres(mg.MGL, mg.MGI, mg.MGA, mg.MGW, mg.DLU, mg.PIV, mg.KRY, mg.HES, R, dp, target,
                         ipar[I_KRYLOV_MAX])
            if kits < 0:  # stalled: SuperLU from now on
                for k in range(n):
                    R[k] = -R[k]
                ipar[I_SOLVER] = SOLVER_SUPERLU
                ipar[I_RESUME] = 1
                return NEED_FACTORS
            ipar[I_KRYLOV] += kits
        else:
            lu_solve(lu.LUI, lu.Li, lu.Lx, lu.Ui, lu.Ux, lu.Ud, R, dp, work)
        P = C[C_P]
        for i in range(nx):
            for j in range(ny):
                P[i + 1, j + 1] += dp[i * ny + j]
        fill_centre_ghosts(P, flags, RULES[RULE_P], C[C_PFIX], nx, ny)
        update_density(C, fpar[FP_COMP], fpar[FP_RHOC], fpar[FP_PREF])
        it += 1
        ipar[I_ITER] = it


@njit(cache=True, error_model="numpy")
def step(resume, dt, state, eps_new, bu, bv, su, sv, qu, qv, modes, fields, bnd, system, lu, band, mg, fpar, ipar,
         out):
    """One gas step of ``dt`` [s] in one call: ``start_step`` (not when ``resume``: the call after the
    caller made the SuperLU factors that the previous one asked for), ``iterate`` and, when the step
    succeeded, ``end_step`` (the state at t + dt written into ``state``).

    ``state``, ``fields``, ``bnd``, ``system``, ``lu``, ``band``, ``mg``: the arrays of ``StateArrays``,
    ``Fields``, ``Boundaries``, ``PressureSystem``, ``LUFactors``, ``BandFactors``, ``Multigrid``
    (``_layout.py``) as plain tuples in the order of their fields, named here: Numba types a plain
    tuple argument in compiled code, a named tuple through Python, which costs about twice as much
    per array at every call.

    Returns BAD_VOIDAGE or BAD_BETA (an input out of range; nothing done), NEED_FACTORS (call again
    with ``resume`` after factorising ``MAT[M_DATA]``), or the status of ``iterate``. The state is
    written unless the status is NOT_FINITE or the mass residual ended above ``fpar[FP_SQRT_TOL]``:
    a failed step leaves it as it was at t.
    """
    state, fields, bnd = StateArrays(*state), Fields(*fields), Boundaries(*bnd)
    system, lu, band, mg = PressureSystem(*system), LUFactors(*lu), BandFactors(*band), Multigrid(*mg)
    if not resume:
        status = start_step(dt, state, eps_new, bu, bv, su, sv, qu, qv, modes, fields, bnd, fpar, ipar, out)
        if status != INPUT_OK:
            return status
    status = iterate(fields, bnd, system, lu, band, mg, fpar, ipar, out)
    if status == NEED_FACTORS:
        return status
    if not (status == NOT_FINITE or out[O_REL] > fpar[FP_SQRT_TOL]):
        end_step(state, eps_new, fields, fpar[FP_PREF])
    return status
