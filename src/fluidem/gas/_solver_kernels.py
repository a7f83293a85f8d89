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
"""
import numpy as np
from numba import njit

from ._operators import face_value, normal_stresses_at_centre, shear_stress_at_corner
from .grid import FREE_SLIP, INFLOW, NO_SLIP, PERIODIC  # cell flags, Hoomans 1996 Table 1

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
# The solver keeps its arrays in a few stacks (fewer kernel arguments compile much faster).
# C  (7, nx + 2, ny + 2) centre arrays with one ring of boundary cells: gauge pressure, density,
# voidage, prescribed gauge pressure at t + dt and at t, fixed voidage, (ερ) at t
C_P, C_RHO, C_E, C_PFIX, C_PFIX_OLD, C_EFIX, C_RO_OLD = 0, 1, 2, 3, 4, 5, 6
# FU (7, nx + 1, ny), FV (7, nx, ny + 1) face arrays without ghosts:
F_OLD, F_EX, F_BETA, F_RHS, F_FIX, F_WOUT, F_D = 0, 1, 2, 3, 4, 5, 6
# (velocity at t, explicit terms, β, β u_s + source, fixed value, outflow share, D = ε_f / a)
# KU (2, nx + 1, ny), KV (2, nx, ny + 1) int8: face kind and inward sign (+1 / -1 on boundary faces, else 0)
K_KIND, K_SIGN = 0, 1
# RULES (2, 9): ghost rule per flag for the pressure (row 0) and the voidage (row 1)
RULE_P, RULE_E = 0, 1
# VEC (3, nx ny): continuity residual R [kg/s], pressure correction p' [Pa], work
V_R, V_DP, V_WORK = 0, 1, 2
# MAT (2, nnz): pressure matrix data (CSC), and the data of the matrix last factorised
M_DATA, M_FACTORED = 0, 1
# LUI (4, n + 1): L column pointers, U column pointers, perm_r, perm_c (SuperLU factors)
L_LP, L_UP, L_PERM_R, L_PERM_C = 0, 1, 2, 3
# fpar / ipar / out slots
(F_GX, F_GY, F_DT, F_DX, F_DY, F_AX, F_AY, F_VOL, F_COMP, F_RHOC, F_TOL, F_REUSE, F_SLOW, F_PREF,
 F_MU) = range(15)
(I_NX, I_NY, I_MAXIT, I_PIN, I_HAVE_LU, I_ITER, I_CHECKED, I_REFACTORED, I_RESUME, I_SCHEME, I_BANDED, I_BW,
 I_NFACT) = range(13)
O_RES, O_QREF, O_IN, O_OUT, O_ACC, O_MASS, O_COURANT, O_REL, O_PREV = range(9)
# iterate status
CONVERGED, NEED_FACTORS, MAX_ITERATIONS, NOT_FINITE = 0, 1, 2, 3
MASS_FLOOR = 1e-4  # share of (gas mass / dt) in the reference flow of the mass residual


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
    for i in range(P.shape[0]):
        for j in range(P.shape[1]):
            RHO[i, j] = rho_factor * (P[i, j] + p_ref) if rho_factor != 0.0 else rho_const


@njit(cache=True, error_model="numpy")
def boundary_cells(C, pfix, flags, RULES, fpar, ipar):
    """Boundary cells of voidage and pressure (prescribed values from ``pfix``) from the flags,
    then the density everywhere."""
    nx, ny = ipar[I_NX], ipar[I_NY]
    fill_centre_ghosts(C[C_E], flags, RULES[RULE_E], C[C_EFIX], nx, ny)
    fill_centre_ghosts(C[C_P], flags, RULES[RULE_P], pfix, nx, ny)
    update_density(C, fpar[F_COMP], fpar[F_RHOC], fpar[F_PREF])


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
def explicit_momentum(U, V, G, H, E, mu, dx, dy, scheme, ukind, vkind, exu, exv, nx, ny):
    """Explicit part of the momentum balance (Hoomans 1996 eq. 43) on every solved face [N m^-3]:
    exu = −[∇·(ερ u u) − u ∇·(ερ u)] − ∇·(ε τ_g), the convection in advective form (the mass
    fluxes G, H of the continuity equation; face velocities by ``scheme``) and the viscous
    stress of eq. 48 (λ_g = 0)."""
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
            adv = (fe * (ue - up) - fw * (uw - up)) / dx + (fn * (un - up) - fs * (us - up)) / dy
            sxx_l, _ = normal_stresses_at_centre(U, V, E, mu, dx, dy, i - 1, j)
            sxx_r, _ = normal_stresses_at_centre(U, V, E, mu, dx, dy, i, j)
            tn = shear_stress_at_corner(U, V, E, mu, dx, dy, i, j + 1)
            ts = shear_stress_at_corner(U, V, E, mu, dx, dy, i, j)
            exu[i, j] = -adv + (sxx_r - sxx_l) / dx + (tn - ts) / dy
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
            adv = (fn * (vn - vp) - fs * (vs - vp)) / dy + (fe * (ve - vp) - fw * (vw - vp)) / dx
            _, syy_s = normal_stresses_at_centre(U, V, E, mu, dx, dy, i, j - 1)
            _, syy_n = normal_stresses_at_centre(U, V, E, mu, dx, dy, i, j)
            te = shear_stress_at_corner(U, V, E, mu, dx, dy, i + 1, j)
            tw = shear_stress_at_corner(U, V, E, mu, dx, dy, i, j)
            exv[i, j] = -adv + (syy_n - syy_s) / dy + (te - tw) / dx


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
def begin_step(p, rho, u, v, eps_old, eps_new, U, V, G, H, C, FU, FV, KU, KV, flags, RULES, fpar, ipar):
    """Load the state at t (p, rho, u, v, eps_old; p as gauge pressure), fill its ghosts, its
    mass fluxes and the explicit momentum terms FU[F_EX], FV[F_EX]; the shares of the
    continuous outflow; then the new voidage and the boundary cells at t + dt."""
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
                      KV[K_KIND], FU[F_EX], FV[F_EX], nx, ny)
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


@njit(cache=True, error_model="numpy")
def finite_nonnegative(a, b):
    """True when every value of the 2D arrays a and b is finite and >= 0."""
    for q in (a, b):
        for i in range(q.shape[0]):
            for j in range(q.shape[1]):
                x = q[i, j]
                if not (x >= 0.0 and x < np.inf):
                    return False
    return True


@njit(cache=True, error_model="numpy")
def end_step(p, rho, u, v, U, V, C, p_ref):
    """Write the fields at t + dt back into the state arrays (p as absolute pressure)."""
    nx, ny = p.shape
    P, RHO = C[C_P], C[C_RHO]
    for i in range(nx):
        for j in range(ny):
            p[i, j] = P[i + 1, j + 1] + p_ref
            rho[i, j] = RHO[i + 1, j + 1]
    copy_from(u, U)
    copy_from(v, V)


# ---------------------------------------------------------------------------- one iteration
@njit(cache=True, error_model="numpy")
def _predict(W, C, F, K, gravity, dt, h):
    """Momentum on the faces of one direction (x-faces: W = U, F = FU; y-faces: V, FV)."""
    P, RHO, E = C[C_P], C[C_RHO], C[C_E]
    kind = K[K_KIND]
    old, ex, beta, rhs, fix, D = F[F_OLD], F[F_EX], F[F_BETA], F[F_RHS], F[F_FIX], F[F_D]
    da, db = face_axis(P, K)
    for i in range(kind.shape[0]):
        for j in range(kind.shape[1]):
            k = kind[i, j]
            if k == SOLVED:
                la, lb, ra, rb = i + 1 - da, j + 1 - db, i + 1, j + 1
                ef = 0.5 * (E[la, lb] + E[ra, rb])
                m = ef * 0.5 * (RHO[la, lb] + RHO[ra, rb])
                a = m / dt + beta[i, j]
                d = ef / a
                D[i, j] = d
                W[i + 2, j + 2] = (m * old[i, j] / dt + ex[i, j] + m * gravity + rhs[i, j]) / a \
                    - d * (P[ra, rb] - P[la, lb]) / h
            elif k == FIXED:
                D[i, j] = 0.0
                W[i + 2, j + 2] = fix[i, j]
            else:
                D[i, j] = 0.0


@njit(cache=True, error_model="numpy")
def _fluxes(W, C, K, row_of, R, area):
    """Add the mass flux A (ερ)_f w of every face of one direction, except outflow faces and
    periodic duplicates, to the residuals of the cells either side. Returns (inflow, outflow,
    net inflow, has outflow faces) through the boundary faces of this direction [kg/s]."""
    RHO, E = C[C_RHO], C[C_E]
    kind, sign = K[K_KIND], K[K_SIGN]
    inflow = 0.0
    outflow = 0.0
    net_in = 0.0
    has_outflow = False
    da, db = face_axis(E, K)
    for i in range(kind.shape[0]):
        for j in range(kind.shape[1]):
            k = kind[i, j]
            if k == COPY:
                continue
            if k == OUTFLOW_FACE:
                has_outflow = True
                continue
            la, lb, ra, rb = i + 1 - da, j + 1 - db, i + 1, j + 1
            w = W[i + 2, j + 2]
            f = area * face_voidage(E, la, lb, ra, rb, k, sign[i, j]) * 0.5 * (RHO[la, lb] + RHO[ra, rb]) * w
            rl = row_of[la, lb]
            rr = row_of[ra, rb]
            if rl >= 0:
                R[rl] += f
            if rr >= 0:
                R[rr] -= f
            s = sign[i, j]
            if s != 0:
                fin = s * f
                net_in += fin
                if fin > 0.0:
                    inflow += fin
                else:
                    outflow -= fin
    return inflow, outflow, net_in, has_outflow


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
def predict_residual(U, V, C, FU, FV, KU, KV, row_of, flags, R, fpar, ipar):
    """Face velocities from the momentum balance at the current pressure, then the cell
    continuity residuals (Hoomans 1996 eqs 42-43).

    Momentum on a solved face, implicit in pressure and drag (Kuipers et al. 1992)::

        (ερ)_f (u - u_old)/dt = ex - ε_f ∂p/∂x - β (u - u_s) + (ερ)_f g_x + source
        u = û - D ∂p/∂x,   D = ε_f / ((ερ)_f/dt + β)

    with ``F_RHS = β u_s + source``. Continuity residual of cell c [kg/s]::

        R_c = V [(ερ)_c - (ερ)_c,old]/dt + Σ_faces A (ερ)_f u_out

    Outflow faces carry F_WOUT × the outflow that closes the mass balance. Returns
    (Σ|R|, reference flow, inflow, outflow, accumulation, mass, Courant number).
    """
    nx, ny = ipar[I_NX], ipar[I_NY]
    dt, dx, dy, vol = fpar[F_DT], fpar[F_DX], fpar[F_DY], fpar[F_VOL]
    _predict(U, C, FU, KU, fpar[F_GX], dt, dx)
    _predict(V, C, FV, KV, fpar[F_GY], dt, dy)
    RHO, E, RO = C[C_RHO], C[C_E], C[C_RO_OLD]
    acc = 0.0
    acc_abs = 0.0
    mass = 0.0
    for i in range(nx):
        for j in range(ny):
            er = E[i + 1, j + 1] * RHO[i + 1, j + 1]
            a = vol * (er - RO[i + 1, j + 1]) / dt
            R[i * ny + j] = a
            acc += a
            acc_abs += abs(a)
            mass += vol * er
    in_x, out_x, net_x, of_x = _fluxes(U, C, KU, row_of, R, fpar[F_AX])
    in_y, out_y, net_y, of_y = _fluxes(V, C, KV, row_of, R, fpar[F_AY])
    inflow = in_x + in_y
    outflow = out_x + out_y
    if of_x or of_y:
        need = net_x + net_y - acc
        a, b = _outflow(U, C, FU, KU, row_of, R, fpar[F_AX], need)
        c, d = _outflow(V, C, FV, KV, row_of, R, fpar[F_AY], need)
        inflow += a + c
        outflow += b + d
    fill_face_ghosts(U, V, flags, nx, ny)
    res = 0.0
    for k in range(nx * ny):
        res += abs(R[k])
    umax = 0.0
    for i in range(nx + 1):
        for j in range(ny):
            umax = max(umax, abs(U[i + 2, j + 2]))
    vmax = 0.0
    for i in range(nx):
        for j in range(ny + 1):
            vmax = max(vmax, abs(V[i + 2, j + 2]))
    qref = inflow + outflow + acc_abs + MASS_FLOOR * mass / dt
    return res, qref, inflow, outflow, acc, mass, umax * dt / dx + vmax * dt / dy


# ---------------------------------------------------------------------------- pressure correction
@njit(cache=True, error_model="numpy")
def _assemble_faces(data, pos, W, C, F, K, area, h, comp):
    """Face terms of the pressure matrix for one direction (see ``assemble_pressure``)."""
    RHO, E = C[C_RHO], C[C_E]
    kind, sign, D = K[K_KIND], K[K_SIGN], F[F_D]
    da, db = face_axis(E, K)
    for i in range(kind.shape[0]):
        for j in range(kind.shape[1]):
            k = kind[i, j]
            if k == COPY or k == OUTFLOW_FACE:
                continue
            la, lb, ra, rb = i + 1 - da, j + 1 - db, i + 1, j + 1
            w = W[i + 2, j + 2]
            ef = face_voidage(E, la, lb, ra, rb, k, sign[i, j])
            c = area * ef * 0.5 * (RHO[la, lb] + RHO[ra, rb]) * D[i, j] / h
            t = 0.5 * area * ef * w * comp  # d(flux)/dp of either cell through ρ_f = (ρ_L + ρ_R)/2
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
    derivative of the continuity residuals R_c with respect to the cell pressures.

    Terms: compressibility ε V comp / dt on the diagonal (comp = M/(RT), 0 for constant
    density; Hoomans 1996 eq. 44), A (ερ)_f D / h between the two cells of each solved
    face, and A ε_f u comp / 2 per cell from the face density (ρ_L + ρ_R)/2 of every face
    with flow.
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
    _assemble_faces(data, upos, U, C, FU, KU, fpar[F_AX], fpar[F_DX], comp)
    _assemble_faces(data, vpos, V, C, FV, KV, fpar[F_AY], fpar[F_DY], comp)
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


@njit(cache=True, error_model="numpy")
def band_factor(data, indices, indptr, order, bw, B):
    """LU factors, without pivoting, of the CSC matrix (data, indices, indptr) with rows and
    columns renumbered by ``order`` into a band of half-width ``bw``: B (n, 2 bw + 1) with
    B[i, j − i + bw] = A[i, j]; L below the diagonal (unit diagonal), U on and above.

    Safe without pivoting because the pressure matrix is diagonally dominant; returns the
    smallest |pivot| relative to the largest |diagonal| so that the caller can check.
    """
    n = B.shape[0]
    for i in range(n):
        for j in range(B.shape[1]):
            B[i, j] = 0.0
    for col in range(n):
        c = order[col]
        for q in range(indptr[col], indptr[col + 1]):
            r = order[indices[q]]
            B[r, c - r + bw] += data[q]
    dmax = 0.0
    for i in range(n):
        dmax = max(dmax, abs(B[i, bw]))
    pmin = np.inf
    for k in range(n):
        piv = B[k, bw]
        pmin = min(pmin, abs(piv))
        if piv == 0.0:
            return 0.0
        last = min(k + bw, n - 1)
        for i in range(k + 1, last + 1):
            lik = B[i, k - i + bw]
            if lik == 0.0:
                continue
            lik /= piv
            B[i, k - i + bw] = lik
            for j in range(k + 1, last + 1):
                B[i, j - i + bw] -= lik * B[k, j - k + bw]
    return pmin / dmax if dmax > 0.0 else 0.0


@njit(cache=True, error_model="numpy")
def band_solve(B, order, bw, b, x, w):
    """x = A^-1 b with the band factors of ``band_factor``."""
    n = B.shape[0]
    for k in range(n):
        w[order[k]] = b[k]
    for i in range(n):
        acc = w[i]
        for k in range(max(0, i - bw), i):
            acc -= B[i, k - i + bw] * w[k]
        w[i] = acc
    for i in range(n - 1, -1, -1):
        acc = w[i]
        for j in range(i + 1, min(i + bw, n - 1) + 1):
            acc -= B[i, j - i + bw] * w[j]
        w[i] = acc / B[i, bw]
    for k in range(n):
        x[k] = w[order[k]]


@njit(cache=True, error_model="numpy")
def iterate(U, V, C, FU, FV, KU, KV, row_of, flags, RULES, VEC, MAT, diag_pos, upos, vpos, pin_pos,
            LUI, Li, Lx, Ui, Ux, Ud, B, order, csc_indices, csc_indptr, fpar, ipar, out):
    """Pressure-correction (Newton) iterations of one time step until the mass residual is below
    ``fpar[F_TOL]``.

    Each iteration: momentum prediction and continuity residual (``predict_residual``), then
    p' from the factorised pressure matrix and p += p'. The factors are those of an earlier
    matrix while it stays within ``F_REUSE`` (max norm) of the current one; when it does not,
    or an iteration reduces the residual by less than ``F_SLOW``, the matrix is factorised
    again: here, as a band (``band_factor``, ``ipar[I_BANDED]``), or else by the caller with
    SuperLU: the kernel returns NEED_FACTORS with the current matrix in ``MAT[M_DATA]`` and is
    called again (``I_RESUME`` then skips straight to the solve). Otherwise it returns
    CONVERGED, MAX_ITERATIONS or NOT_FINITE; the step's diagnostics are in ``out``.
    """
    nx, ny, max_it, pin_diag = ipar[I_NX], ipar[I_NY], ipar[I_MAXIT], ipar[I_PIN]
    R, dp, work = VEC[V_R], VEC[V_DP], VEC[V_WORK]
    data, factored = MAT[M_DATA], MAT[M_FACTORED]
    n = nx * ny
    it = ipar[I_ITER]
    while True:
        if ipar[I_RESUME] == 0:
            res, qref, fin, fout, acc, mass, courant = predict_residual(U, V, C, FU, FV, KU, KV, row_of, flags, R,
                                                                        fpar, ipar)
            rel = res / qref if qref > 0.0 else 0.0
            out[O_RES], out[O_QREF], out[O_IN], out[O_OUT] = res, qref, fin, fout
            out[O_ACC], out[O_MASS], out[O_COURANT], out[O_REL] = acc, mass, courant, rel
            ipar[I_ITER] = it
            if not np.isfinite(rel):
                return NOT_FINITE
            if rel <= fpar[F_TOL]:
                return CONVERGED
            if it >= max_it:
                return MAX_ITERATIONS
            need = False
            if ipar[I_CHECKED] == 0:
                ipar[I_CHECKED] = 1
                assemble_pressure(data, diag_pos, upos, vpos, pin_pos, U, V, C, FU, FV, KU, KV, fpar, ipar)
                if ipar[I_HAVE_LU] == 0:
                    need = True
                else:
                    dmax = 0.0
                    amax = 0.0
                    for k in range(data.size):
                        dmax = max(dmax, abs(data[k] - factored[k]))
                        amax = max(amax, abs(factored[k]))
                    need = dmax > fpar[F_REUSE] * amax
            elif rel > fpar[F_SLOW] * out[O_PREV] and ipar[I_REFACTORED] == 0:
                assemble_pressure(data, diag_pos, upos, vpos, pin_pos, U, V, C, FU, FV, KU, KV, fpar, ipar)
                need = True
            if need:
                ipar[I_REFACTORED] = 1
                if ipar[I_BANDED] == 1 and band_factor(data, csc_indices, csc_indptr, order, ipar[I_BW], B) > 1e-12:
                    for k in range(data.size):
                        factored[k] = data[k]
                    ipar[I_HAVE_LU] = 1
                    ipar[I_NFACT] += 1
                else:  # SuperLU, by the caller (from now on, if the band had a poor pivot)
                    ipar[I_BANDED] = 0
                    ipar[I_RESUME] = 1
                    return NEED_FACTORS
        ipar[I_RESUME] = 0
        out[O_PREV] = out[O_REL]
        for k in range(n):
            R[k] = -R[k]
        if pin_diag >= 0:
            R[0] = 0.0
        if ipar[I_BANDED] == 1:
            band_solve(B, order, ipar[I_BW], R, dp, work)
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
