"""Compiled kernels of the gas solver: ghost values from cell flags, explicit momentum terms,
momentum prediction with the continuity residual, pressure-correction matrix, correction.

Arrays are the solver's padded arrays (``grid.py``): centre arrays ``(nx + 2, ny + 2)``
with cell (i, j) at ``[i + 1, j + 1]``; ``U`` ``(nx + 5, ny + 4)`` with x-face (i, j)
at ``[i + 2, j + 2]``; ``V`` ``(nx + 4, ny + 5)`` with y-face (i, j) at ``[i + 2, j + 2]``.
Boundary behaviour comes only from the integer cell flags (Hoomans 1996 Table 1) and
the face kinds derived from them at set-up. The solver keeps most arrays in a few stacks
(``C``, ``FU``, ``FV``, ...; slots named below): fewer kernel arguments compile faster.

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
from face fluxes (no read-after-write through memory), the band solve works on blocks of
cells (dense mat-vecs, one dependent step per block), divisions by dx, dy are multiplications.
"""
import numpy as np
from numba import njit

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

# face kinds: momentum solved / value fixed (wall, inflow) / continuous outflow / periodic duplicate of face 0
SOLVED, FIXED, OUTFLOW_FACE, COPY = 0, 1, 2, 3
# ghost rules of centre scalars, chosen per flag: zero gradient / prescribed value / periodic wrap
R_NONE, R_COPY, R_FIXED, R_WRAP = 0, 1, 2, 3


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


# ---------------------------------------------------------------------------- stacked work arrays
# The solver keeps its arrays in a few stacks (fewer kernel arguments compile faster and dispatch faster).
# C  (9, nx + 2, ny + 2) centre arrays with one ring of boundary cells: gauge pressure, density,
# voidage, prescribed gauge pressure at t + dt and at t, fixed voidage, (ερ) at t, and the
# normal stresses σ_xx, σ_yy of ε τ_g at t (work of ``explicit_momentum``)
C_P, C_RHO, C_E, C_PFIX, C_PFIX_OLD, C_EFIX, C_RO_OLD, C_SXX, C_SYY = range(9)
N_C = 9
# FU (10, nx + 1, ny), FV (10, nx, ny + 1) face arrays without ghosts:
F_OLD, F_EX, F_BETA, F_RHS, F_FIX, F_WOUT, F_FLUX, F_EF, F_X1, F_X2, F_EP = range(11)
N_F = 11
# (velocity at t, explicit terms, β, β u_s + source, fixed value, outflow share, mass flux A (ερ)_f w
#  along +x / +y [kg/s], face voidage ε_f at t + dt, u_old/dt + g, explicit terms + β u_s + source,
#  the voidage ε_p,f of the pressure term −ε_p,f ∂p/∂x: ε_f, or the step input ``pressure_voidage``)
# KU (2, nx + 1, ny), KV (2, nx, ny + 1) int8: face kind and inward sign (+1 / -1 on boundary faces, else 0)
K_KIND, K_SIGN = 0, 1
# RULES (2, 9): ghost rule per flag for the pressure (row 0) and the voidage (row 1)
RULE_P, RULE_E = 0, 1
# VEC (5, nx ny): continuity residual R [kg/s], pressure correction p' [Pa], work vectors
V_R, V_DP, V_WORK, V_WORK2, V_ROW = range(5)
N_VEC = 6  # V_ROW: two rows
# MAT (2, nnz): pressure matrix data (CSC), and the data of the matrix last factorised
M_DATA, M_FACTORED = 0, 1
# LUI (4, n + 1): L column pointers, U column pointers, perm_r, perm_c (SuperLU factors)
L_LP, L_UP, L_PERM_R, L_PERM_C = 0, 1, 2, 3
# fpar / ipar / out slots
(F_GX, F_GY, F_DT, F_DX, F_DY, F_AX, F_AY, F_VOL, F_COMP, F_RHOC, F_TOL, F_REUSE, F_SLOW, F_PREF,
 F_MU, F_ETA) = range(16)
N_FPAR = 16
(I_NX, I_NY, I_MAXIT, I_PIN, I_HAVE_LU, I_ITER, I_CHECKED, I_REFACTORED, I_RESUME, I_SCHEME, I_SOLVER, I_BW,
 I_NFACT, I_LEVELS, I_KRYLOV, I_KRYLOV_MAX, I_RESTART, I_PX, I_PY, I_BLOCKS, I_PRESSURE_VOIDAGE) = range(21)
N_IPAR = 21
O_RES, O_QREF, O_IN, O_OUT, O_ACC, O_MASS, O_COURANT, O_REL, O_PREV = range(9)
# linear solvers of the pressure correction (ipar[I_SOLVER])
SOLVER_SUPERLU, SOLVER_BAND, SOLVER_MULTIGRID = 0, 1, 2
# iterate status
CONVERGED, NEED_FACTORS, MAX_ITERATIONS, NOT_FINITE = 0, 1, 2, 3
MASS_FLOOR = 1e-4  # share of (gas mass / dt) in the reference flow of the mass residual
BLOCK_REUSE = 0.3  # band: blocks whose rows changed by less than this share of F_REUSE keep their factors
# modes of the step inputs (begin_step's ``modes``): not given / a number (at [0, 0]) / cell centres / faces
IN_NONE, IN_SCALAR, IN_CENTRE, IN_FACE = 0, 1, 2, 3
IN_VOIDAGE, IN_BETA, IN_SOLIDS_U, IN_SOLIDS_V, IN_SOURCE_U, IN_SOURCE_V = range(6)
# begin_step status
INPUT_OK, BAD_VOIDAGE, BAD_BETA = 0, 1, 2


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
    update_density(C, fpar[F_COMP], fpar[F_RHOC], fpar[F_PREF])


# ---------------------------------------------------------------------------- step inputs
@njit(cache=True, error_model="numpy")
def _to_faces(mode, q, periodic, axis, out):
    """Face values ``out`` of an input given as a number (q[0, 0]), at centres or on faces."""
    if mode == IN_SCALAR:
        x = q[0, 0]
        for i in range(out.shape[0]):
            for j in range(out.shape[1]):
                out[i, j] = x
    elif mode == IN_CENTRE:
        if axis == 0:
            centre_to_x_faces(q, periodic, out)
        else:
            centre_to_y_faces(q, periodic, out)
    elif mode == IN_FACE:
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
    if mode == IN_NONE:
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
    if modes[IN_VOIDAGE] != IN_NONE:
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
    if bmode != IN_NONE:
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
def begin_step(p, rho, u, v, eps_old, eps_new, U, V, G, H, C, FU, FV, KU, KV, flags, RULES, fpar, ipar, TAU):
    """Load the state at t (p, rho, u, v, eps_old; p as gauge pressure), fill its ghosts, its
    mass fluxes and the explicit momentum terms FU[F_EX], FV[F_EX]; the shares of the
    continuous outflow; then the new voidage (``eps_new``, (nx, ny)) and the boundary cells at
    t + dt, and the per-step face constants. FU/FV[F_BETA] and [F_RHS] must hold this step's
    β and β u_s + source (``load_inputs``)."""
    nx, ny = ipar[I_NX], ipar[I_NY]
    p_ref = fpar[F_PREF]
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
    explicit_momentum(U, V, G, H, E, fpar[F_MU], fpar[F_DX], fpar[F_DY], ipar[I_SCHEME], KU[K_KIND],
                      KV[K_KIND], FU[F_EX], FV[F_EX], nx, ny, C[C_SXX], C[C_SYY], TAU)
    total = np.zeros(3)
    _outflow_shares(FU, KU, C, fpar[F_AX], total)
    _outflow_shares(FV, KV, C, fpar[F_AY], total)
    if total[2] > 0.0:
        _normalise_shares(FU, KU, fpar[F_AX], total)
        _normalise_shares(FV, KV, fpar[F_AY], total)
    for i in range(nx):
        for j in range(ny):
            E[i + 1, j + 1] = eps_new[i, j]
    boundary_cells(C, C[C_PFIX], flags, RULES, fpar, ipar)
    idt = 1.0 / fpar[F_DT]
    given = ipar[I_PRESSURE_VOIDAGE] != 0
    _face_constants(C, FU, KU, fpar[F_GX], idt, given)
    _face_constants(C, FV, KV, fpar[F_GY], idt, given)


@njit(cache=True, error_model="numpy")
def start_step(dt, p, rho, u, v, eps_old, eps_new, bu, bv, su, sv, qu, qv, modes, U, V, G, H, C, FU, FV, KU, KV,
               flags, RULES, fpar, ipar, out, TAU):
    """``load_inputs`` (returns its status when an input is out of range), then ``begin_step`` for
    a step of ``dt``, and the counters of ``iterate`` reset: one call per step."""
    status = load_inputs(eps_new, bu, bv, su, sv, qu, qv, modes, FU, FV, ipar[I_PX] != 0, ipar[I_PY] != 0)
    if status != INPUT_OK:
        return status
    fpar[F_DT] = dt
    begin_step(p, rho, u, v, eps_old, eps_new, U, V, G, H, C, FU, FV, KU, KV, flags, RULES, fpar, ipar, TAU)
    ipar[I_ITER] = 0
    ipar[I_CHECKED] = 0
    ipar[I_REFACTORED] = 0
    ipar[I_RESUME] = 0
    out[O_PREV] = np.inf
    return INPUT_OK


@njit(cache=True, error_model="numpy")
def end_step(p, rho, u, v, U, V, C, p_ref, eps, eps_new):
    """Write the fields at t + dt back into the state arrays (p as absolute pressure, ε = eps_new)."""
    nx, ny = p.shape
    P, RHO = C[C_P], C[C_RHO]
    for i in range(nx):
        for j in range(ny):
            p[i, j] = P[i + 1, j + 1] + p_ref
            rho[i, j] = RHO[i + 1, j + 1]
            eps[i, j] = eps_new[i, j]
    copy_from(u, U)
    copy_from(v, V)


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
    dt, vol = fpar[F_DT], fpar[F_VOL]
    idt = 1.0 / dt
    RHO, E, RO = C[C_RHO], C[C_E], C[C_RO_OLD]
    of_x = _face_fluxes(U, C, FU, KU, idt, 1.0 / fpar[F_DX], fpar[F_AX])
    of_y = _face_fluxes(V, C, FV, KV, idt, 1.0 / fpar[F_DY], fpar[F_AY])
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
        a, b = _outflow(U, C, FU, KU, row_of, R, fpar[F_AX], need)
        c, d = _outflow(V, C, FV, KV, row_of, R, fpar[F_AY], need)
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
    dt = fpar[F_DT]
    return umax * dt / fpar[F_DX] + vmax * dt / fpar[F_DY]


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
    comp, dt, vol = fpar[F_COMP], fpar[F_DT], fpar[F_VOL]
    E = C[C_E]
    for k in range(data.size):
        data[k] = 0.0
    if comp != 0.0:
        for i in range(nx):
            for j in range(ny):
                data[diag_pos[i * ny + j]] += comp * E[i + 1, j + 1] * vol / dt
    _assemble_faces(data, upos, U, C, FU, KU, fpar[F_AX], fpar[F_DX], comp, 1.0 / dt)
    _assemble_faces(data, vpos, V, C, FV, KV, fpar[F_AY], fpar[F_DY], comp, 1.0 / dt)
    if pin_diag >= 0:
        for p in pin_pos:
            data[p] = 0.0
        data[pin_diag] = 1.0


@njit(cache=True, error_model="numpy")
def lu_solve(LUI, Li, Lx, Ui, Ux, Ud, b, x, w):
    """x = A^-1 b from SuperLU factors Pr A Pc = L U: L strictly lower (unit diagonal), U strictly
    upper plus its diagonal Ud, both CSC; w[perm_r] = b, then x = (U^-1 L^-1 w)[perm_c]."""
    n = b.size
    Lp, Up, perm_r, perm_c = LUI[L_LP], LUI[L_UP], LUI[L_PERM_R], LUI[L_PERM_C]
    for i in range(n):
        w[perm_r[i]] = b[i]
    for j in range(n):
        wj = w[j]
        if wj != 0.0:
            for k in range(Lp[j], Lp[j + 1]):
                w[Li[k]] -= Lx[k] * wj
    for j in range(n - 1, -1, -1):
        wj = w[j] / Ud[j]
        w[j] = wj
        if wj != 0.0:
            for k in range(Up[j], Up[j + 1]):
                w[Ui[k]] -= Ux[k] * wj
    for i in range(n):
        x[i] = w[perm_c[i]]


# ---------------------------------------------------------------------------- block-tridiagonal LU ("band")
# With the unknowns numbered along one grid direction first (m = its number of cells, the band
# half-width), the 5-point matrix is block tridiagonal: nb = n / m dense diagonal blocks D_j (m × m,
# tridiagonal, plus corners for a periodic direction) and diagonal couplings lo_j, up_j to the
# blocks before and after. Block LU: S_0 = D_0, S_j = D_j - diag(lo_j) S_{j-1}^-1 diag(up_{j-1});
# the inverses S_j^-1 are kept, so that a solve is 2 nb dense mat-vecs (one dependent step per
# block instead of one per unknown):
#     y_j = S_j^-1 (b_j - lo_j ∘ y_{j-1}),   x_j = y_j - S_j^-1 (up_j ∘ x_{j+1})
# BINV (nb, m, m) holds S_j^-1 transposed (BINV[j, c, r] = (S_j^-1)[r, c]); BLU (2, nb, m) lo and up.
@njit(cache=True, error_model="numpy")
def _invert_in_place(A, rows):
    """A^-1 in place by Gauss-Jordan elimination without pivoting (A diagonally dominant), the
    pivots taken two at a time so that every other row is updated in one pass; ``rows`` (2, ≥ m)
    is work. Returns the smallest |pivot|, 0 if one vanished.

    A may have more columns than rows (m × mp, mp ≥ m), the extra ones zero: they stay zero, and the
    row operations run over mp columns, a multiple of the vector width (``GasSolver`` pads the band
    blocks so): 45 blocks of 15 × 15 take 108 µs, of 16 × 16 97 µs, the real entries the same bits.
    Written with two-index subscripts only: a row view ``A[r]`` in the loops cost an atomic
    reference-count increment and decrement each (120 per 15 × 15 block), a fifth of the time
    (137 → 108 µs, the same bits); unsigned indices spare the wrap-around code."""
    m = A.shape[0]
    mp = A.shape[1]
    pmin = np.inf
    k = 0
    while k < m:
        two = k + 1 < m
        for q in range(2 if two else 1):  # eliminate inside the pair of rows k, k + 1
            kk = UI(k + q)
            piv = A[kk, kk]
            pmin = min(pmin, abs(piv))
            if piv == 0.0:
                return 0.0
            inv = 1.0 / piv
            A[kk, kk] = 1.0
            for c in range(mp):
                A[kk, UI(c)] *= inv
            if two:
                ko = UI(k + 1 - q)
                f = A[ko, kk]
                A[ko, kk] = 0.0
                for c in range(mp):
                    A[ko, UI(c)] -= f * A[kk, UI(c)]
        uk = UI(k)
        if not two:  # the last pivot alone, on the rows above it
            for c in range(mp):
                rows[UI(0), UI(c)] = A[uk, UI(c)]
            for r in range(k):
                ur = UI(r)
                f = A[ur, uk]
                if f != 0.0:
                    A[ur, uk] = 0.0
                    for c in range(mp):
                        A[ur, UI(c)] -= f * rows[UI(0), UI(c)]
            break
        uk1 = UI(k + 1)
        for c in range(mp):
            rows[UI(0), UI(c)] = A[uk, UI(c)]
            rows[UI(1), UI(c)] = A[uk1, UI(c)]
        for r in range(m):
            if r == k or r == k + 1:
                continue
            ur = UI(r)
            f0 = A[ur, uk]
            f1 = A[ur, uk1]
            A[ur, uk] = 0.0
            A[ur, uk1] = 0.0
            for c in range(mp):
                A[ur, UI(c)] -= f0 * rows[UI(0), UI(c)] + f1 * rows[UI(1), UI(c)]
        k += 2
    return pmin


@njit(cache=True, error_model="numpy")
def band_factor(data, indices, indptr, place, BINV, BLU, rows, j0):
    """Block-tridiagonal LU (see above) of the CSC matrix (data, indices, indptr) with rows and
    columns renumbered by the band numbering ``order`` of ``band_solve``, given as ``place`` (2, n) int64:
    order // m and order % m (the block of each unknown and its place in it, made once by ``GasSolver``),
    from block ``j0`` on (the blocks before it keep their
    factors: the recursion runs in block order); ``row`` is work (≥ m). Without pivoting, as the
    pressure matrix is diagonally dominant; returns the smallest |pivot| relative to the largest
    |diagonal| so that the caller can check (0 when the matrix is not block tridiagonal in this
    numbering)."""
    nb, m = BINV.shape[0], BINV.shape[1]
    n = nb * m
    lo, up = BLU[0], BLU[1]
    for jb in range(j0, nb):
        for a in range(m):
            lo[jb, a] = 0.0
            up[jb, a] = 0.0
            for b in range(BINV.shape[2]):  # with the padding columns (``_invert_in_place``)
                BINV[jb, a, b] = 0.0
    blk, at = place[0], place[1]  # block of each unknown and its place in it (a division per matrix entry
    # here took 33 µs of a tsuji-jet factorisation)
    for col in range(n):
        jc = blk[col]
        ic = at[col]
        for q in range(indptr[col], indptr[col + 1]):
            rk = indices[q]
            jr = blk[rk]
            if jr < j0:
                continue
            ir = at[rk]
            if jr == jc:
                BINV[jr, ic, ir] += data[q]  # the transposed block: inv(Sᵀ) = inv(S)ᵀ
            elif jc == jr - 1 and ic == ir:
                lo[jr, ir] += data[q]
            elif jc == jr + 1 and ic == ir:
                up[jr, ir] += data[q]
            else:
                return 0.0
    dmax = 0.0
    for jb in range(j0, nb):
        for a in range(m):
            dmax = max(dmax, abs(BINV[jb, a, a]))
    pmin = np.inf
    for jb in range(j0, nb):
        St = BINV[jb]
        if jb > 0:  # Sᵀ[b, a] -= up_{j-1}[b] (S_{j-1}^-1)ᵀ[b, a] lo_j[a]
            Pt = BINV[jb - 1]
            for b in range(m):
                ub = up[jb - 1, b]
                if ub != 0.0:
                    for a in range(m):
                        St[b, a] -= ub * Pt[b, a] * lo[jb, a]
        pmin = min(pmin, _invert_in_place(St, rows))
        if pmin == 0.0:
            return 0.0
    return pmin / dmax if dmax > 0.0 else 0.0


@njit(cache=True, error_model="numpy")
def _block_matvec(T, v, y):
    """y = Tᵀ v (T an inverse block stored transposed, m × mp with zero padding columns: y has mp
    entries, the last mp − m zero), two columns per pass."""
    m = T.shape[0]
    mp = T.shape[1]
    for a in range(mp):
        y[a] = 0.0
    c = 0
    while c + 1 < m:  # two-index subscripts: no row views (``_invert_in_place``)
        v0, v1 = v[c], v[c + 1]
        uc, uc1 = UI(c), UI(c + 1)
        for a in range(mp):
            y[UI(a)] += T[uc, UI(a)] * v0 + T[uc1, UI(a)] * v1
        c += 2
    if c < m:
        vc = v[c]
        uc = UI(c)
        for a in range(mp):
            y[UI(a)] += T[uc, UI(a)] * vc


@njit(cache=True, error_model="numpy")
def band_solve(BINV, BLU, order, b, x, w, v, y):
    """x = A^-1 b with the factors of ``band_factor``; w (n), v (≥ m) and y (≥ mp, the padded block
    width) are work."""
    nb, m = BINV.shape[0], BINV.shape[1]
    n = nb * m
    lo, up = BLU[0], BLU[1]
    for k in range(n):  # unsigned indices: no wrap-around code
        w[UI(order[UI(k)])] = b[UI(k)]
    for jb in range(nb):
        base = UI(jb * m)
        if jb > 0:
            for a in range(m):
                v[UI(a)] = w[base + UI(a)] - lo[UI(jb), UI(a)] * w[base - UI(m) + UI(a)]
        else:
            for a in range(m):
                v[UI(a)] = w[base + UI(a)]
        _block_matvec(BINV[jb], v, y)
        for a in range(m):
            w[base + UI(a)] = y[UI(a)]
    for jb in range(nb - 2, -1, -1):
        base = UI(jb * m)
        for c in range(m):
            v[UI(c)] = up[UI(jb), UI(c)] * w[base + UI(m) + UI(c)]
        _block_matvec(BINV[jb], v, y)
        for a in range(m):
            w[base + UI(a)] -= y[UI(a)]
    for k in range(n):
        x[UI(k)] = w[UI(order[UI(k)])]


# ---------------------------------------------------------------------------- multigrid-preconditioned GMRES
# For grids too large for the band: restarted GMRES, right-preconditioned by one V-cycle of an
# aggregation multigrid on the grid's own hierarchy (2 × 2 cells per coarse cell, piecewise-constant
# prolongation P, coarse matrices Pᵀ A P, which stay 5-point, with their couplings halved (see
# ``_mg_level_matrix``); symmetric Gauss-Seidel smoothing (a forward and a backward sweep) before
# and after the coarse correction; dense LU on the coarsest level).
# Layout, all levels concatenated (level l holds cells MGL[0, l] .. MGL[0, l + 1] - 1):
#   MGL (3, levels + 1) int64: cell offsets, and the grid size (a, b) of each level (cell i b + j)
#   MGI (N, 9) int64: per cell its 4 neighbours (-x, +x, -y, +y; local index, -1 none),
#       the Galerkin target of each of those 4 entries in MGA (flat index (row) * 5 + slot,
#       slot 0 the diagonal; -1 none), and the coarse cell (local index) of this cell
#   MGA (N, 5): matrix rows (diagonal, then the 4 neighbour coefficients)
#   MGW (4, N): x, b, r, 1 / diagonal
#   DLU (m, m) + PIV (m): dense LU of the coarsest level, partial pivoting
#   KRY (2 (restart + 1), n): GMRES basis V and preconditioned vectors Z
#   HES (restart + 4, restart + 1): Hessenberg matrix, then rows of Givens cosines, sines, rhs
MG_X, MG_B, MG_R, MG_IDIAG = 0, 1, 2, 3
MGI_NB, MGI_GAL, MGI_AGG = 0, 4, 8


@njit(cache=True, error_model="numpy")
def _mg_level_matrix(MGL, MGI, MGA, MGW, l):
    """Coarse matrix of level l + 1 from that of level l (also 1 / diagonal of level l + 1)."""
    o0, o1, o2 = MGL[0, l], MGL[0, l + 1], MGL[0, l + 2]
    flat = MGA.reshape(MGA.size)
    for g in range(o1, o2):
        for s in range(5):
            MGA[g, s] = 0.0
    for g in range(o0, o1):
        flat[(o1 + MGI[g, MGI_AGG]) * 5] += MGA[g, 0]
        for d in range(4):
            t = MGI[g, MGI_GAL + d]
            if t >= 0:
                flat[t] += MGA[g, 1 + d]
    # Pᵀ A P doubles the couplings of a diffusion operator against those of its discretisation on the
    # coarse grid (two fine faces per coarse face, same ratio area / distance) while its row sums (the
    # compressibility, the boundaries) are right: halve the couplings, keep the row sums
    for g in range(o1, o2):
        rs = MGA[g, 0] + MGA[g, 1] + MGA[g, 2] + MGA[g, 3] + MGA[g, 4]
        MGA[g, 0] = 0.5 * (MGA[g, 0] + rs)
        for d in range(1, 5):
            MGA[g, d] *= 0.5
    for g in range(o1, o2):
        MGW[MG_IDIAG, g] = 1.0 / MGA[g, 0]


@njit(cache=True, error_model="numpy")
def mg_setup(data, csc_ell, MGL, MGI, MGA, MGW, DLU, PIV):
    """The multigrid hierarchy of the CSC matrix ``data`` (its entries go to MGA rows by
    ``csc_ell``: flat index cell * 5 + slot); returns False if a diagonal or the coarsest LU is singular."""
    levels = MGL.shape[1] - 1
    n0 = MGL[0, 1]
    flat = MGA.reshape(MGA.size)
    for g in range(n0):
        for s in range(5):
            MGA[g, s] = 0.0
    for q in range(data.size):
        flat[csc_ell[q]] += data[q]
    for g in range(n0):
        if MGA[g, 0] == 0.0:
            return False
        MGW[MG_IDIAG, g] = 1.0 / MGA[g, 0]
    for l in range(levels - 1):
        _mg_level_matrix(MGL, MGI, MGA, MGW, l)
    # dense LU (partial pivoting) of the coarsest level
    oc = MGL[0, levels - 1]
    m = MGL[0, levels] - oc
    for i in range(m):
        for j in range(m):
            DLU[i, j] = 0.0
    for i in range(m):
        g = oc + i
        DLU[i, i] += MGA[g, 0]
        for d in range(4):
            c = MGI[g, MGI_NB + d]
            if c >= 0:
                DLU[i, c] += MGA[g, 1 + d]
    for k in range(m):
        p = k
        big = abs(DLU[k, k])
        for i in range(k + 1, m):
            if abs(DLU[i, k]) > big:
                big = abs(DLU[i, k])
                p = i
        PIV[k] = p
        if big == 0.0:
            return False
        if p != k:
            for j in range(m):
                tmp = DLU[k, j]
                DLU[k, j] = DLU[p, j]
                DLU[p, j] = tmp
        inv = 1.0 / DLU[k, k]
        for i in range(k + 1, m):
            lik = DLU[i, k] * inv
            DLU[i, k] = lik
            if lik != 0.0:
                for j in range(k + 1, m):
                    DLU[i, j] -= lik * DLU[k, j]
    return True


@njit(cache=True, error_model="numpy", inline="always")
def _mg_row(MGI, MGA, X, o0, b, g, edge):
    """Σ_d A[g, d] x[neighbour d] of cell g (local neighbours from MGI on the edges of the level's
    grid, else g ∓ b, g ∓ 1)."""
    if edge:
        s = 0.0
        for d in range(4):
            c = MGI[g, MGI_NB + d]
            if c >= 0:
                s += MGA[g, 1 + d] * X[o0 + c]
        return s
    return MGA[g, 1] * X[g - b] + MGA[g, 2] * X[g + b] + MGA[g, 3] * X[g - 1] + MGA[g, 4] * X[g + 1]


@njit(cache=True, error_model="numpy")
def _mg_gauss_seidel(MGL, MGI, MGA, MGW, l, forward):
    """One Gauss-Seidel sweep of level l (cells in index order, forward or backward)."""
    X, B, IDG = MGW[MG_X], MGW[MG_B], MGW[MG_IDIAG]
    o0, a, b = MGL[0, l], MGL[1, l], MGL[2, l]
    for ii in range(a):
        i = ii if forward else a - 1 - ii
        edge_i = i == 0 or i == a - 1
        for jj in range(b):
            j = jj if forward else b - 1 - jj
            g = o0 + i * b + j
            X[g] = (B[g] - _mg_row(MGI, MGA, X, o0, b, g, edge_i or j == 0 or j == b - 1)) * IDG[g]


@njit(cache=True, error_model="numpy")
def _mg_restrict_residual(MGL, MGI, MGA, MGW, l):
    """b of level l + 1 = Pᵀ (b - A x) of level l."""
    X, B = MGW[MG_X], MGW[MG_B]
    o0, a, b = MGL[0, l], MGL[1, l], MGL[2, l]
    o1, o2 = MGL[0, l + 1], MGL[0, l + 2]
    for g in range(o1, o2):
        B[g] = 0.0
    for i in range(a):
        edge_i = i == 0 or i == a - 1
        for j in range(b):
            g = o0 + i * b + j
            r = B[g] - MGA[g, 0] * X[g] - _mg_row(MGI, MGA, X, o0, b, g, edge_i or j == 0 or j == b - 1)
            B[o1 + MGI[g, MGI_AGG]] += r


@njit(cache=True, error_model="numpy")
def mg_vcycle(MGL, MGI, MGA, MGW, DLU, PIV, b, x):
    """x ≈ A^-1 b by one V-cycle (a fixed linear operator: the preconditioner of ``gmres``)."""
    levels = MGL.shape[1] - 1
    X, B = MGW[MG_X], MGW[MG_B]
    n0 = MGL[0, 1]
    for g in range(n0):
        B[g] = b[g]
    for l in range(levels - 1):
        o0, o1 = MGL[0, l], MGL[0, l + 1]
        for g in range(o0, o1):
            X[g] = 0.0
        _mg_gauss_seidel(MGL, MGI, MGA, MGW, l, True)
        _mg_gauss_seidel(MGL, MGI, MGA, MGW, l, False)
        _mg_restrict_residual(MGL, MGI, MGA, MGW, l)
    oc = MGL[0, levels - 1]
    m = MGL[0, levels] - oc
    for i in range(m):  # coarsest: forward / back substitution with the pivots
        X[oc + i] = B[oc + i]
    for k in range(m):
        p = PIV[k]
        if p != k:
            tmp = X[oc + k]
            X[oc + k] = X[oc + p]
            X[oc + p] = tmp
        xk = X[oc + k]
        for i in range(k + 1, m):
            X[oc + i] -= DLU[i, k] * xk
    for k in range(m - 1, -1, -1):
        s = X[oc + k]
        for j in range(k + 1, m):
            s -= DLU[k, j] * X[oc + j]
        X[oc + k] = s / DLU[k, k]
    for l in range(levels - 2, -1, -1):
        o0, o1 = MGL[0, l], MGL[0, l + 1]
        for g in range(o0, o1):
            X[g] += X[o1 + MGI[g, MGI_AGG]]
        _mg_gauss_seidel(MGL, MGI, MGA, MGW, l, False)
        _mg_gauss_seidel(MGL, MGI, MGA, MGW, l, True)
    for g in range(n0):
        x[g] = X[g]


@njit(cache=True, error_model="numpy")
def mg_matvec(MGL, MGI, MGA, x, y):
    """y = A x with the finest level of the hierarchy."""
    a, b = MGL[1, 0], MGL[2, 0]
    for i in range(a):
        edge_i = i == 0 or i == a - 1
        for j in range(b):
            g = i * b + j
            y[g] = MGA[g, 0] * x[g] + _mg_row(MGI, MGA, x, 0, b, g, edge_i or j == 0 or j == b - 1)


@njit(cache=True, error_model="numpy")
def gmres(MGL, MGI, MGA, MGW, DLU, PIV, KRY, HES, b, x, target, max_iter):
    """x ≈ A^-1 b by restarted GMRES with the V-cycle as right preconditioner, from x = 0, until
    ||b - A x||_2 <= target. Returns the iterations made, or -1 when ``max_iter`` were not enough."""
    n = b.size
    m = HES.shape[1] - 1
    Vb = KRY[: m + 1]
    Zb = KRY[m + 1:]
    Hh = HES[: m + 1]
    cs, sn, gv = HES[m + 1], HES[m + 2], HES[m + 3]
    for i in range(n):
        x[i] = 0.0
    r = Vb[0]
    for i in range(n):
        r[i] = b[i]
    its = 0
    while True:
        beta = 0.0
        for i in range(n):
            beta += r[i] * r[i]
        beta = np.sqrt(beta)
        if beta <= target:
            return its
        if its >= max_iter:
            return -1
        v0 = Vb[0]
        for i in range(n):
            v0[i] = r[i] / beta
        for k in range(m + 1):
            gv[k] = 0.0
        gv[0] = beta
        k_used = 0
        for k in range(m):
            mg_vcycle(MGL, MGI, MGA, MGW, DLU, PIV, Vb[k], Zb[k])
            w = Vb[k + 1]
            mg_matvec(MGL, MGI, MGA, Zb[k], w)
            for jj in range(k + 1):  # modified Gram-Schmidt
                vj = Vb[jj]
                hsum = 0.0
                for i in range(n):
                    hsum += w[i] * vj[i]
                Hh[jj, k] = hsum
                for i in range(n):
                    w[i] -= hsum * vj[i]
            hn = 0.0
            for i in range(n):
                hn += w[i] * w[i]
            hn = np.sqrt(hn)
            Hh[k + 1, k] = hn
            if hn > 0.0:
                for i in range(n):
                    w[i] /= hn
            for jj in range(k):  # earlier rotations
                h0, h1 = Hh[jj, k], Hh[jj + 1, k]
                Hh[jj, k] = cs[jj] * h0 + sn[jj] * h1
                Hh[jj + 1, k] = -sn[jj] * h0 + cs[jj] * h1
            h0, h1 = Hh[k, k], Hh[k + 1, k]
            den = np.sqrt(h0 * h0 + h1 * h1)
            if den == 0.0:
                cs[k], sn[k] = 1.0, 0.0
            else:
                cs[k], sn[k] = h0 / den, h1 / den
            Hh[k, k] = den
            Hh[k + 1, k] = 0.0
            gv[k + 1] = -sn[k] * gv[k]
            gv[k] = cs[k] * gv[k]
            its += 1
            k_used = k + 1
            if abs(gv[k + 1]) <= target or its >= max_iter or hn == 0.0:
                break
        # y = H^-1 g, x += Z y
        for jj in range(k_used - 1, -1, -1):
            s = gv[jj]
            for q in range(jj + 1, k_used):
                s -= Hh[jj, q] * gv[q]
            gv[jj] = s / Hh[jj, jj]
        for jj in range(k_used):
            z = Zb[jj]
            y = gv[jj]
            for i in range(n):
                x[i] += y * z[i]
        # true residual for the restart test
        mg_matvec(MGL, MGI, MGA, x, r)
        for i in range(n):
            r[i] = b[i] - r[i]


# ---------------------------------------------------------------------------- the iterations of a step
@njit(cache=True, error_model="numpy")
def iterate(U, V, C, FU, FV, KU, KV, row_of, flags, RULES, VEC, MAT, diag_pos, upos, vpos, pin_pos,
            LUI, Li, Lx, Ui, Ux, Ud, BAND, BLU, order, band_place, csc_indices, csc_indptr, csc_block, csc_ell,
            MGL, MGI, MGA, MGW, DLU, PIV, KRY, HES, fpar, ipar, out):
    """Pressure-correction (Newton) iterations of one time step until the mass residual is below
    ``fpar[F_TOL]``.

    Each iteration: momentum prediction and continuity residual (``predict_residual``), then
    p' from the pressure matrix (the Jacobian of the residuals) and p += p'. Band and SuperLU:
    the factors are those of an earlier matrix while no entry of the current one differs from it
    by more than ``F_REUSE`` times its largest entry; when one does, or an iteration reduces the
    residual by less than ``F_SLOW``, the matrix is factorised again: here as a band
    (``band_factor``; after a change of the step's matrix from the first block whose rows
    changed by more than BLOCK_REUSE × F_REUSE), or else by the caller with SuperLU: the kernel
    returns NEED_FACTORS with the current matrix in ``MAT[M_DATA]`` and is called again
    (``I_RESUME`` then skips straight to the solve). Multigrid: the matrix and its hierarchy
    are made again on every iteration (Newton); each p' comes from GMRES to a residual ``F_ETA``
    times that of the iteration (no smaller than a tenth of the step's tolerance); if GMRES
    stalls, or the hierarchy cannot be made, the solver falls back to SuperLU. Returns
    CONVERGED, MAX_ITERATIONS or NOT_FINITE, with the ghost faces filled and the step's
    diagnostics in ``out``.
    """
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
            elif rel <= fpar[F_TOL]:
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
                    tol = fpar[F_REUSE] * amax
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
                                j0 = min(j0, csc_block[k])
            elif solver == SOLVER_MULTIGRID or (rel > fpar[F_SLOW] * out[O_PREV] and ipar[I_REFACTORED] == 0):
                # multigrid: a new Jacobian every iteration (Newton), its hierarchy costs little
                assemble_pressure(data, diag_pos, upos, vpos, pin_pos, U, V, C, FU, FV, KU, KV, fpar, ipar)
                need = True
            if need:
                ipar[I_REFACTORED] = 1
                if solver == SOLVER_BAND and band_factor(data, csc_indices, csc_indptr, band_place, BAND, BLU,
                                                         VEC[V_ROW:V_ROW + 2], j0) > 1e-12:
                    for k in range(data.size):
                        if csc_block[k] >= j0:
                            factored[k] = data[k]
                    ipar[I_HAVE_LU] = 1
                    ipar[I_NFACT] += 1
                    ipar[I_BLOCKS] += BAND.shape[0] - j0
                elif solver == SOLVER_MULTIGRID and mg_setup(data, csc_ell, MGL, MGI, MGA, MGW, DLU, PIV):
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
            target = max(fpar[F_ETA] * np.sqrt(rn), 0.1 * fpar[F_TOL] * out[O_QREF] / np.sqrt(n))
            kits = gmres(MGL, MGI, MGA, MGW, DLU, PIV, KRY, HES, R, dp, target, ipar[I_KRYLOV_MAX])
            if kits < 0:  # stalled: SuperLU from now on
                for k in range(n):
                    R[k] = -R[k]
                ipar[I_SOLVER] = SOLVER_SUPERLU
                ipar[I_RESUME] = 1
                return NEED_FACTORS
            ipar[I_KRYLOV] += kits
        else:
            lu_solve(LUI, Li, Lx, Ui, Ux, Ud, R, dp, work)
        P = C[C_P]
        for i in range(nx):
            for j in range(ny):
                P[i + 1, j + 1] += dp[i * ny + j]
        fill_centre_ghosts(P, flags, RULES[RULE_P], C[C_PFIX], nx, ny)
        update_density(C, fpar[F_COMP], fpar[F_RHOC], fpar[F_PREF])
        it += 1
        ipar[I_ITER] = it
