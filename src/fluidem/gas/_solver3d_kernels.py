"""Compiled kernels of the 3D gas solver: ghost values from cell flags, explicit momentum terms,
momentum prediction with the continuity residual, the pressure-correction matrix and its update.

The same discretisation as the 2D kernels (``_solver_kernels.py``, Hoomans 1996 eqs 42-48 after
Kuipers et al. 1992), written once for the three directions: a face quantity of axis ``a`` lives in
slot ``a`` of a stack (``_layout3d.py``), and a kernel loops over ``a`` with the unit offsets
``unit(a)`` or, on a boundary layer, with ``at(a, p, s, t)``, the (x, y, z) index of the point ``p``
along ``a``, ``s`` along ``(a + 1) % 3`` and ``t`` along ``(a + 2) % 3``.

Arrays are padded (``grid.py``): centre arrays ``(nx + 2, ny + 2, nz + 2)`` with cell (i, j, k) at
``[i + 1, j + 1, k + 1]``; the velocity and mass-flux stacks ``W``, ``Q`` ``(3, nx + 5, ny + 5, nz + 5)``
with face (i, j, k) of axis a at ``[a, i + 2, j + 2, k + 2]``; face stacks ``F[slot, a]`` and kinds
``K[slot, a]`` ``(nx + 1, ny + 1, nz + 1)`` without ghosts, each axis using its leading
``(nx + (a == 0), ny + (a == 1), nz + (a == 2))`` entries. Boundary behaviour comes only from the
integer cell flags (Hoomans 1996 Table 1) and the face kinds derived from them at set-up.

Symbols inside kernels: ``E`` voidage ε, ``RHO`` gas density ρ_g, ``P`` pressure relative to p_ref,
``Q`` mass flux densities (ερ)_f w [kg m^-2 s^-1], ``beta`` the interphase coefficient β
[kg m^-3 s^-1], ``S`` the normal stresses of ε τ_g at centres, ``T`` its shear stresses on the cell
edges: ``T[c]`` the (a, b) component, a = (c + 1) % 3, b = (c + 2) % 3, on the edges along axis c,
indexed by their face lines along a and b and their cell along c.
"""
import math

import numpy as np
from numba import literal_unroll, njit, prange

from ._layout3d import (
    C_E,
    C_EFIX,
    C_P,
    C_PFIX,
    C_PFIX_OLD,
    C_RHO,
    C_RO_OLD,
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
    FP_A,
    FP_COMP,
    FP_DT,
    FP_G,
    FP_H,
    FP_MU,
    FP_PREF,
    FP_RHOC,
    FP_VOL,
    I_N,
    I_PIN,
    I_SCHEME,
    I_THREADS,
    K_KIND,
    K_SIGN,
    O_ACC,
    O_IN,
    O_MASS,
    O_OUT,
    O_QREF,
    O_RES,
    OUTFLOW_FACE,
    R_COPY,
    R_FIXED,
    R_WRAP,
    RULE_E,
    RULE_P,
    SOLVED,
)
from ._multigrid3d_kernels import gmres, mg_setup
from ._operators import face_value
from ._solver_kernels import (  # ghost velocities per flag, shared with 2D
    _normal,
    _tangential,
)
from .grid import PERIODIC

AXES = (0, 1, 2)  # literal_unroll(AXES): a loop over the axes compiled once per axis

MASS_FLOOR = 1e-4  # share of (gas mass / dt) in the reference flow of the mass residual (as in 2D)

# The passes over the grid run on Numba's threads when ``threads`` (ipar[I_THREADS], the solver's count of
# Numba threads in use) is above 1: each ``*_threads`` kernel gives one x plane (or line) per work item to
# its ``*_planes`` body, which otherwise runs once over all planes as a serial call (no parallel launch on
# one thread). Each face, cell or edge is computed by the same code either way, and every sum (mass,
# flows, residual norms) stays one serial loop in grid order, so the results are bitwise the same on
# any number of threads.


@njit(cache=True, inline="always")
def at(a, p, s, t):
    """(x, y, z) index of the point ``p`` along axis ``a``, ``s`` along (a + 1) % 3, ``t`` along (a + 2) % 3."""
    if a == 0:
        return p, s, t
    if a == 1:
        return t, p, s
    return s, t, p


@njit(cache=True, inline="always")
def unit(a):
    """(1, 0, 0), (0, 1, 0) or (0, 0, 1): the unit offset of axis ``a``."""
    return int(a == 0), int(a == 1), int(a == 2)


# ---------------------------------------------------------------------------- step inputs
@njit(cache=True, error_model="numpy")
def unit_interval(x):
    """Whether every value of ``x`` (any shape) lies in (0, 1] (a NaN does not)."""
    for v in x.flat:
        if not (v > 0.0 and v <= 1.0):
            return False
    return True


@njit(cache=True, error_model="numpy")
def load_beta(F, a, b):
    """F[F_BETA, a] = β [kg m^-3 s^-1] on the faces of axis ``a`` (``b`` a face array of that axis); returns
    False, the faces before it written, at the first value that is not finite and ≥ 0."""
    for i in range(b.shape[0]):
        for j in range(b.shape[1]):
            for k in range(b.shape[2]):
                x = b[i, j, k]
                if not (math.isfinite(x) and x >= 0.0):
                    return False
                F[F_BETA, a, i, j, k] = x
    return True


@njit(cache=True, error_model="numpy")
def load_momentum_sources(F, a, us, source, n0, n1, n2):
    """F[F_RHS, a] = β u_s + source [N/m^3] on the (n0, n1, n2) faces of axis ``a``, summed from 0 in that
    order: ``us`` the solids velocity [m/s] (an empty array: no β u_s term), β from F[F_BETA, a], and
    ``source`` the explicit momentum source (empty: none)."""
    has_us = us.size > 0
    has_source = source.size > 0
    for i in range(n0):
        for j in range(n1):
            for k in range(n2):
                r = 0.0
                if has_us:
                    r += F[F_BETA, a, i, j, k] * us[i, j, k]
                if has_source:
                    r += source[i, j, k]
                F[F_RHS, a, i, j, k] = r


@njit(cache=True, error_model="numpy")
def _load_axis(F, a, b, us, source, n0, n1, n2):
    """``load_beta`` and then ``load_momentum_sources`` on the faces of axis ``a`` (``b`` empty: β is not
    loaded, F[F_BETA, a] stays as it is); returns False at the first β that is not finite and ≥ 0."""
    if b.size > 0 and not load_beta(F, a, b):
        return False
    load_momentum_sources(F, a, us, source, n0, n1, n2)
    return True


@njit(cache=True, error_model="numpy")
def load_face_inputs(F, b0, b1, b2, u0, u1, u2, s0, s1, s2, shapes):
    """``_load_axis`` of the three axes in one call: β (b*), the solids velocity (u*) and the momentum source
    (s*) on the x-, y- and z-faces, each an empty array where absent; ``shapes`` (3, 3) the face shapes.
    Returns the first axis with a β out of range (not finite or < 0), or −1."""
    if not _load_axis(F, np.int64(0), b0, u0, s0, shapes[0, 0], shapes[0, 1], shapes[0, 2]):
        return 0
    if not _load_axis(F, np.int64(1), b1, u1, s1, shapes[1, 0], shapes[1, 1], shapes[1, 2]):
        return 1
    if not _load_axis(F, np.int64(2), b2, u2, s2, shapes[2, 0], shapes[2, 1], shapes[2, 2]):
        return 2
    return -1


@njit(cache=True, error_model="numpy")
def unit_interval3(e0, e1, e2):
    """The first of the three arrays with a value outside (0, 1] (``unit_interval``), or −1."""
    if not unit_interval(e0):
        return 0
    if not unit_interval(e1):
        return 1
    if not unit_interval(e2):
        return 2
    return -1


@njit(cache=True, error_model="numpy", inline="always")
def _load_face(F, field, a, e):
    """F[field, a] = e on the faces of axis a (e of that axis's face shape)."""
    for i in range(e.shape[0]):
        for j in range(e.shape[1]):
            for k in range(e.shape[2]):
                F[field, a, i, j, k] = e[i, j, k]


@njit(cache=True, error_model="numpy")
def load_faces(F, field, e0, e1, e2):
    """F[field, a] = e_a on the faces of each axis a (e_a of that axis's face shape)."""
    _load_face(F, field, np.int64(0), e0)
    _load_face(F, field, np.int64(1), e1)
    _load_face(F, field, np.int64(2), e2)


# ---------------------------------------------------------------------------- ghosts
@njit(cache=True, error_model="numpy")
def fill_centre_ghosts(q, flags, rule, fixed, nx, ny, nz):
    """Boundary-cell values of a centre scalar from the flags: ``rule[flag]`` is R_COPY (adjacent
    interior value), R_FIXED (``fixed`` at that cell) or R_WRAP (opposite side). The cells on the
    ring's edges and corners (no condition of their own): wrapped along a periodic axis, else the
    mean of the two (three) ring cells beside them, as the 2D corners. q, flags and fixed: C-contiguous
    arrays of the padded shape (nx + 2, ny + 2, nz + 2)."""
    N = (nx, ny, nz)
    for a in range(3):
        _centre_face_ghosts(q, flags, rule, fixed, a, nx, ny, nz)
    per = (flags[0, 1, 1] == PERIODIC, flags[1, 0, 1] == PERIODIC, flags[1, 1, 0] == PERIODIC)
    for c in range(3):  # edges along axis c
        a, b = (c + 1) % 3, (c + 2) % 3
        na, nb = N[a], N[b]
        for ha in range(2):
            pa, ia, wa = (na + 1, na, 1) if ha else (0, 1, na)  # ghost, inward, wrapped
            for hb in range(2):
                pb, ib, wb = (nb + 1, nb, 1) if hb else (0, 1, nb)
                for pc in range(1, N[c] + 1):
                    g = at(c, pc, pa, pb)
                    if per[a]:
                        q[g] = q[at(c, pc, wa, pb)]
                    elif per[b]:
                        q[g] = q[at(c, pc, pa, wb)]
                    else:
                        q[g] = 0.5 * (q[at(c, pc, ia, pb)] + q[at(c, pc, pa, ib)])
    for hx in range(2):
        px, ix, wx = (nx + 1, nx, 1) if hx else (0, 1, nx)
        for hy in range(2):
            py, iy, wy = (ny + 1, ny, 1) if hy else (0, 1, ny)
            for hz in range(2):
                pz, iz, wz = (nz + 1, nz, 1) if hz else (0, 1, nz)
                if per[0]:
                    q[px, py, pz] = q[wx, py, pz]
                elif per[1]:
                    q[px, py, pz] = q[px, wy, pz]
                elif per[2]:
                    q[px, py, pz] = q[px, py, wz]
                else:
                    q[px, py, pz] = (q[ix, py, pz] + q[px, iy, pz] + q[px, py, iz]) / 3.0


@njit(cache=True, error_model="numpy")
def _centre_face_ghosts(q, flags, rule, fixed, a, nx, ny, nz):
    """The boundary cells of ``fill_centre_ghosts`` on the two faces normal to axis ``a`` (not their edges),
    addressed by flat offsets in q, flags and fixed (strides of the axes a, e1, e2): the same values as with
    (x, y, z) indices, each read from interior cells only, without a branch on the axis per cell."""
    N = (nx, ny, nz)
    Q = q.ravel()  # views: the arrays are C-contiguous
    G = flags.ravel()
    X = fixed.ravel()
    st = (q.shape[1] * q.shape[2], q.shape[2], 1)
    e1, e2 = (a + 1) % 3, (a + 2) % 3
    n, sd, s1, s2 = N[a], st[a], st[e1], st[e2]
    for s in range(1, N[e1] + 1):
        for t in range(1, N[e2] + 1):
            b = s * s1 + t * s2
            lo, hi = b, b + (n + 1) * sd
            r = rule[G[lo]]
            if r == R_COPY:
                Q[lo] = Q[b + sd]
            elif r == R_FIXED:
                Q[lo] = X[lo]
            elif r == R_WRAP:
                Q[lo] = Q[b + n * sd]
            r = rule[G[hi]]
            if r == R_COPY:
                Q[hi] = Q[b + n * sd]
            elif r == R_FIXED:
                Q[hi] = X[hi]
            elif r == R_WRAP:
                Q[hi] = Q[b + sd]


@njit(cache=True, error_model="numpy")
def fill_face_ghosts(W, flags, nx, ny, nz, threads):
    """Ghost faces of a face-vector stack (velocity or mass flux) from the flags: for each direction a,
    the tangential ghost layers along the other two axes, then the normal ghost layers along a (and
    the periodic duplicate face n_a = face 0), each over the whole padded extent of the other axes
    (ghost velocity per flag: ``_tangential``, ``_normal`` of the 2D kernels). The three passes one after
    the other (the later ones read the ghost layers of the earlier); within a pass a line ``s`` writes only
    its own ghost faces and reads only faces of its own line that the pass does not write, so the lines
    of the three directions go to Numba's threads (``_face_ghost_threads``)."""
    if threads > 1:
        for q in range(3):
            _face_ghost_threads(W, flags, q, nx, ny, nz)
    else:
        m = max(nx, max(ny, nz)) + 5
        for a in range(3):
            for q in range(3):
                _face_ghost_lines(W, flags, a, q, np.int64(0), m, nx, ny, nz)


@njit(cache=True, error_model="numpy", parallel=True)
def _face_ghost_threads(W, flags, q, nx, ny, nz):
    """Pass ``q`` of ``fill_face_ghosts``, one line of one direction per work item."""
    m = max(nx, max(ny, nz)) + 5
    for ip in prange(3 * m):
        p = np.int64(ip)  # signed: Numba's prange index is unsigned, and unsigned + signed is a float
        a = p // m
        s = p - a * m
        _face_ghost_lines(W, flags, a, q, s, s + 1, nx, ny, nz)


@njit(cache=True, error_model="numpy")
def _face_ghost_lines(W, flags, a, q, s0, s1, nx, ny, nz):
    """Pass ``q`` of ``fill_face_ghosts`` for direction ``a``, lines s0 <= s < s1. The faces are addressed by
    their flat offsets in ``W[a]`` and ``flags`` (strides of the axes d, e1, e2 of the pass) and the wrapped
    source rows of a periodic side are taken once per pass: the same values written in the same order as
    with (x, y, z) indices, without a branch on the axis and an integer division per face. W and flags are
    the solver's own C-contiguous arrays (``W[a].ravel()`` is then a view)."""
    N = (nx, ny, nz)
    Wa = W[a]
    Wf = Wa.ravel()  # a view: W[a] is contiguous
    Ff = flags.ravel()
    d = (a + 1 + q) % 3  # the tangential axes first, the normal axis a last
    e1, e2 = (d + 1) % 3, (d + 2) % 3
    n = N[d]
    ws = (Wa.shape[1] * Wa.shape[2], Wa.shape[2], 1)
    fs = (flags.shape[1] * flags.shape[2], flags.shape[2], 1)
    sd, se1, se2 = ws[d], ws[e1], ws[e2]
    fd, fe1, fe2 = fs[d], fs[e1], fs[e2]
    ext1 = N[e1] + 4 + (1 if e1 == a else 0)
    ext2 = N[e2] + 4 + (1 if e2 == a else 0)
    lo1, lo2 = (2 + (n - 1) % n) * sd, (2 + (n - 2) % n) * sd  # wrapped rows of the low ghosts, k = 1, 2
    th1, th2 = 2 * sd, (2 + 1 % n) * sd  # of the high tangential ghosts: 2 + (k - 1) % n
    nh1, nh2 = (2 + 1 % n) * sd, (2 + 2 % n) * sd  # of the high normal ghosts: 2 + k % n
    m1, m2 = N[e1] - 1, N[e2] - 1
    for s in range(max(s0, 0), min(s1, ext1)):
        cs = min(max(s - 2, 0), m1) + 1
        for t in range(ext2):
            ct = min(max(t - 2, 0), m2) + 1
            b = s * se1 + t * se2
            fb = cs * fe1 + ct * fe2
            flo = Ff[fb]
            fhi = Ff[fb + (n + 1) * fd]
            if d != a:  # k = 1 low and high, then k = 2 (which may read a k = 1 ghost when n = 1)
                Wf[b + sd] = _tangential(flo, Wf[b + 2 * sd], Wf[b + lo1])
                Wf[b + (n + 2) * sd] = _tangential(fhi, Wf[b + (n + 1) * sd], Wf[b + th1])
                Wf[b] = _tangential(flo, Wf[b + 3 * sd], Wf[b + lo2])
                Wf[b + (n + 3) * sd] = _tangential(fhi, Wf[b + n * sd], Wf[b + th2])
            else:
                if fhi == PERIODIC:
                    Wf[b + (n + 2) * sd] = Wf[b + 2 * sd]
                Wf[b + sd] = _normal(flo, Wf[b + 2 * sd], Wf[b + 3 * sd], Wf[b + lo1])
                Wf[b + (n + 3) * sd] = _normal(fhi, Wf[b + (n + 2) * sd], Wf[b + (n + 1) * sd], Wf[b + nh1])
                Wf[b] = _normal(flo, Wf[b + 2 * sd], Wf[b + 4 * sd], Wf[b + lo2])
                Wf[b + (n + 4) * sd] = _normal(fhi, Wf[b + (n + 2) * sd], Wf[b + n * sd], Wf[b + nh2])


# ---------------------------------------------------------------------------- centre values
@njit(cache=True, error_model="numpy")
def update_density(C, rho_factor, rho_const, p_ref, threads):
    """ρ = (p' + p_ref) M/(RT) everywhere (Hoomans 1996 eq. 44; C[C_P] is the pressure relative to
    p_ref), or the constant density when rho_factor is 0."""
    if threads > 1:
        _density_threads(C, rho_factor, rho_const, p_ref)
    else:
        _density_planes(np.int64(0), C.shape[1], C, rho_factor, rho_const, p_ref)


@njit(cache=True, error_model="numpy", parallel=True)
def _density_threads(C, rho_factor, rho_const, p_ref):
    for ip in prange(C.shape[1]):
        i = np.int64(ip)  # signed: Numba's prange index is unsigned, and unsigned + signed is a float
        _density_planes(i, i + 1, C, rho_factor, rho_const, p_ref)


@njit(cache=True, error_model="numpy")
def _density_planes(i0, i1, C, rho_factor, rho_const, p_ref):
    """``update_density`` on the padded x planes i0 <= i < i1."""
    P, RHO = C[C_P], C[C_RHO]
    for i in range(max(i0, 0), i1):
        for j in range(P.shape[1]):
            for k in range(P.shape[2]):
                RHO[i, j, k] = rho_factor * (P[i, j, k] + p_ref) if rho_factor != 0.0 else rho_const


@njit(cache=True, error_model="numpy")
def boundary_cells(C, pfix, flags, RULES, fpar, ipar):
    """Boundary cells of voidage and pressure (prescribed values from ``pfix``) from the flags, then the
    density everywhere."""
    nx, ny, nz = ipar[I_N], ipar[I_N + 1], ipar[I_N + 2]
    fill_centre_ghosts(C[C_E], flags, RULES[RULE_E], C[C_EFIX], nx, ny, nz)
    fill_centre_ghosts(C[C_P], flags, RULES[RULE_P], pfix, nx, ny, nz)
    update_density(C, fpar[FP_COMP], fpar[FP_RHOC], fpar[FP_PREF], ipar[I_THREADS])


@njit(cache=True, error_model="numpy", inline="always")
def face_voidage(E, l0, l1, l2, r0, r1, r2, kind, sign):
    """ε on the face between padded cells l and r: the mean, or on a fixed boundary face the boundary
    cell's (sign > 0: the boundary cell is on the low side), as in 2D."""
    if kind == FIXED:
        return E[l0, l1, l2] if sign > 0 else E[r0, r1, r2]
    return 0.5 * (E[l0, l1, l2] + E[r0, r1, r2])


@njit(cache=True, error_model="numpy")
def mass_fluxes(W, Q, C, K, flags, nx, ny, nz, threads):
    """Q = (ερ)_f w on the faces of every direction [kg m^-2 s^-1], ghosts filled like velocities."""
    if threads > 1:
        _mass_flux_threads(W, Q, C, K, nx, ny, nz)
    else:
        _mass_flux_planes(np.int64(0), nx + 1, W, Q, C, K, nx, ny, nz)
    fill_face_ghosts(Q, flags, nx, ny, nz, threads)


@njit(cache=True, error_model="numpy", parallel=True)
def _mass_flux_threads(W, Q, C, K, nx, ny, nz):
    for ip in prange(nx + 1):
        i = np.int64(ip)  # signed: Numba's prange index is unsigned, and unsigned + signed is a float
        _mass_flux_planes(i, i + 1, W, Q, C, K, nx, ny, nz)


@njit(cache=True, error_model="numpy")
def _mass_flux_planes(i0, i1, W, Q, C, K, nx, ny, nz):
    """The faces of ``mass_fluxes`` with x index i0 <= i < i1."""
    E, RHO = C[C_E], C[C_RHO]
    for a in range(3):
        ex, ey, ez = unit(a)
        kind, sign = K[K_KIND, a], K[K_SIGN, a]
        for i in range(max(i0, 0), min(i1, nx + ex)):
            for j in range(ny + ey):
                for k in range(nz + ez):
                    ef = face_voidage(E, i + 1 - ex, j + 1 - ey, k + 1 - ez, i + 1, j + 1, k + 1, kind[i, j, k],
                                      sign[i, j, k])
                    rf = 0.5 * (RHO[i + 1 - ex, j + 1 - ey, k + 1 - ez] + RHO[i + 1, j + 1, k + 1])
                    Q[a, i + 2, j + 2, k + 2] = ef * rf * W[a, i + 2, j + 2, k + 2]


# ---------------------------------------------------------------------------- explicit terms
@njit(cache=True, error_model="numpy")
def stresses(W, E, mu, hx, hy, hz, S, T, nx, ny, nz, threads):
    """The stresses of ε τ_g (Hoomans 1996 eq. 48, λ_g = 0; the sign of the stress on the gas) that
    ``explicit_momentum`` differences: S[d] = ε μ (2 ∂w_d/∂x_d − 2/3 ∇·u) at the cells −1..n_d along d
    (the others interior), and on every cell edge T[c] = ε_e μ (∂w_a/∂x_b + ∂w_b/∂x_a), ε_e the mean of
    the four cells around the edge."""
    if threads > 1:
        _stress_threads(W, E, mu, hx, hy, hz, S, T, nx, ny, nz)
    else:
        _stress_planes(np.int64(-1), nx + 1, W, E, mu, hx, hy, hz, S, T, nx, ny, nz)


@njit(cache=True, error_model="numpy", parallel=True)
def _stress_threads(W, E, mu, hx, hy, hz, S, T, nx, ny, nz):
    for ip in prange(nx + 2):
        i = np.int64(ip) - 1  # signed: Numba's prange index is unsigned, and unsigned + signed is a float
        _stress_planes(i, i + 1, W, E, mu, hx, hy, hz, S, T, nx, ny, nz)


@njit(cache=True, error_model="numpy")
def _stress_planes(i0, i1, W, E, mu, hx, hy, hz, S, T, nx, ny, nz):
    """``stresses`` at the points with x index i0 <= i < i1 (normal stresses from −1, edges from 0)."""
    ihx, ihy, ihz = 1.0 / hx, 1.0 / hy, 1.0 / hz
    for d in literal_unroll(AXES):  # one compiled loop per axis: the index tuples of at() fold
        ex, ey, ez = unit(d)
        for i in range(max(i0, -ex), min(i1, nx + ex)):
            for j in range(-ey, ny + ey):
                for k in range(-ez, nz + ez):
                    du = (W[0, i + 3, j + 2, k + 2] - W[0, i + 2, j + 2, k + 2]) * ihx
                    dv = (W[1, i + 2, j + 3, k + 2] - W[1, i + 2, j + 2, k + 2]) * ihy
                    dw = (W[2, i + 2, j + 2, k + 3] - W[2, i + 2, j + 2, k + 2]) * ihz
                    own = du if d == 0 else (dv if d == 1 else dw)
                    third = (2.0 / 3.0) * (du + dv + dw)
                    S[d, i + 1, j + 1, k + 1] = E[i + 1, j + 1, k + 1] * mu * (2.0 * own - third)
    N = (nx, ny, nz)
    ih = (ihx, ihy, ihz)
    for c in literal_unroll(AXES):
        a, b = (c + 1) % 3, (c + 2) % 3
        # the x index of the edge (pc, pa, pb) is pc (c = 0), pb (c = 1) or pa (c = 2)
        x0, x1 = max(i0, 0), min(i1, nx + (c != 0))
        for pc in range(x0 if c == 0 else 0, x1 if c == 0 else N[c]):
            for pa in range(x0 if c == 2 else 0, x1 if c == 2 else N[a] + 1):
                for pb in range(x0 if c == 1 else 0, x1 if c == 1 else N[b] + 1):
                    dadb = (W[a][at(c, pc + 2, pa + 2, pb + 2)] - W[a][at(c, pc + 2, pa + 2, pb + 1)]) * ih[b]
                    dbda = (W[b][at(c, pc + 2, pa + 2, pb + 2)] - W[b][at(c, pc + 2, pa + 1, pb + 2)]) * ih[a]
                    ec = 0.25 * (E[at(c, pc + 1, pa, pb)] + E[at(c, pc + 1, pa + 1, pb)]
                                 + E[at(c, pc + 1, pa, pb + 1)] + E[at(c, pc + 1, pa + 1, pb + 1)])
                    T[c][at(c, pc, pa, pb)] = ec * mu * (dadb + dbda)


@njit(cache=True, error_model="numpy")
def explicit_momentum(W, Q, C, K, F, S, T, fpar, ipar):
    """Explicit part of the momentum balance (Hoomans 1996 eq. 43) on every solved face [N m^-3]:
    F[F_EX] = −[∇·(ερ w u) − w ∇·(ερ u)] − ∇·(ε τ_g), the convection in advective form (the mass fluxes Q
    of the continuity equation, averaged onto the faces of the face's control volume; face velocities
    upwind or TVD, ``_operators.face_value``) and the viscous stress of eq. 48 (``stresses``)."""
    nx, ny, nz, scheme, threads = ipar[I_N], ipar[I_N + 1], ipar[I_N + 2], ipar[I_SCHEME], ipar[I_THREADS]
    hx, hy, hz = fpar[FP_H], fpar[FP_H + 1], fpar[FP_H + 2]
    stresses(W, C[C_E], fpar[FP_MU], hx, hy, hz, S, T, nx, ny, nz, threads)
    if threads > 1:
        _explicit_threads(W, Q, K, F, S, T, hx, hy, hz, scheme, nx, ny, nz)
    else:
        _explicit_planes(np.int64(0), nx + 1, W, Q, K, F, S, T, hx, hy, hz, scheme, nx, ny, nz)


@njit(cache=True, error_model="numpy", parallel=True)
def _explicit_threads(W, Q, K, F, S, T, hx, hy, hz, scheme, nx, ny, nz):
    for ip in prange(nx + 1):
        i = np.int64(ip)  # signed: Numba's prange index is unsigned, and unsigned + signed is a float
        _explicit_planes(i, i + 1, W, Q, K, F, S, T, hx, hy, hz, scheme, nx, ny, nz)


@njit(cache=True, error_model="numpy")
def _explicit_planes(i0, i1, W, Q, K, F, S, T, hx, hy, hz, scheme, nx, ny, nz):
    """``explicit_momentum`` on the faces with x index i0 <= i < i1."""
    ih = (1.0 / hx, 1.0 / hy, 1.0 / hz)
    for a in range(3):
        ax, ay, az = unit(a)
        kind, EX = K[K_KIND, a], F[F_EX, a]
        for i in range(max(i0, 0), min(i1, nx + ax)):
            for j in range(ny + ay):
                for k in range(nz + az):
                    if kind[i, j, k] != SOLVED:
                        EX[i, j, k] = 0.0
                        continue
                    I, J, L = i + 2, j + 2, k + 2
                    wp = W[a, I, J, L]
                    adv = 0.0
                    visc = 0.0
                    for d in literal_unroll(AXES):  # the offsets of d fold: 3.5x faster than a loop
                        dx, dy, dz = unit(d)
                        if d == a:
                            fp = 0.5 * (Q[a, I, J, L] + Q[a, I + dx, J + dy, L + dz])
                            fm = 0.5 * (Q[a, I - dx, J - dy, L - dz] + Q[a, I, J, L])
                            visc += (S[a, i + 1, j + 1, k + 1] - S[a, i + 1 - dx, j + 1 - dy, k + 1 - dz]) * ih[a]
                        else:
                            fp = 0.5 * (Q[d, I - ax + dx, J - ay + dy, L - az + dz] + Q[d, I + dx, J + dy, L + dz])
                            fm = 0.5 * (Q[d, I - ax, J - ay, L - az] + Q[d, I, J, L])
                            c = 3 - a - d
                            visc += (T[c, i + dx, j + dy, k + dz] - T[c, i, j, k]) * ih[d]
                        wpp = face_value(fp, W[a, I - dx, J - dy, L - dz], wp, W[a, I + dx, J + dy, L + dz],
                                         W[a, I + 2 * dx, J + 2 * dy, L + 2 * dz], scheme)
                        wm = face_value(fm, W[a, I - 2 * dx, J - 2 * dy, L - 2 * dz], W[a, I - dx, J - dy, L - dz],
                                        wp, W[a, I + dx, J + dy, L + dz], scheme)
                        adv += (fp * (wpp - wp) - fm * (wm - wp)) * ih[d]
                    EX[i, j, k] = -adv + visc


@njit(cache=True, error_model="numpy")
def _outflow_shares(F, K, C, fpar, total, nx, ny, nz, threads):
    """Outward mass flux through the interior face next to each continuous-outflow face, at t (zero
    normal gradient), into F[F_WOUT]; adds them to ``total`` = [sum, sum of |.|, area] (in face order, serial)."""
    if threads > 1:
        _outflow_flow_threads(F, K, C, fpar, nx, ny, nz)
    else:
        _outflow_flow_planes(np.int64(0), nx + 1, F, K, C, fpar, nx, ny, nz)
    for a in range(3):
        ex, ey, ez = unit(a)
        area = fpar[FP_A + a]
        kind, share = K[K_KIND, a], F[F_WOUT, a]
        for i in range(nx + ex):
            for j in range(ny + ey):
                for k in range(nz + ez):
                    if kind[i, j, k] == OUTFLOW_FACE:
                        f = share[i, j, k]
                        total[0] += f
                        total[1] += abs(f)
                        total[2] += area


@njit(cache=True, error_model="numpy", parallel=True)
def _outflow_flow_threads(F, K, C, fpar, nx, ny, nz):
    for ip in prange(nx + 1):
        i = np.int64(ip)  # signed: Numba's prange index is unsigned, and unsigned + signed is a float
        _outflow_flow_planes(i, i + 1, F, K, C, fpar, nx, ny, nz)


@njit(cache=True, error_model="numpy")
def _outflow_flow_planes(i0, i1, F, K, C, fpar, nx, ny, nz):
    """The outward flux of each continuous-outflow face (0 on the other faces) into F[F_WOUT], faces with x
    index i0 <= i < i1."""
    RHO, E = C[C_RHO], C[C_E]
    for a in range(3):
        ex, ey, ez = unit(a)
        area = fpar[FP_A + a]
        kind, sign, old, share = K[K_KIND, a], K[K_SIGN, a], F[F_OLD, a], F[F_WOUT, a]
        for i in range(max(i0, 0), min(i1, nx + ex)):
            for j in range(ny + ey):
                for k in range(nz + ez):
                    if kind[i, j, k] != OUTFLOW_FACE:
                        share[i, j, k] = 0.0
                        continue
                    s = sign[i, j, k]
                    w = old[i + s * ex, j + s * ey, k + s * ez]
                    if s > 0:  # the interior cell
                        c0, c1, c2 = i + 1, j + 1, k + 1
                    else:
                        c0, c1, c2 = i + 1 - ex, j + 1 - ey, k + 1 - ez
                    share[i, j, k] = -s * w * E[c0, c1, c2] * RHO[c0, c1, c2] * area


@njit(cache=True, error_model="numpy")
def _normalise_shares(F, K, fpar, total):
    by_flow = total[0] > 1e-9 * total[1] and total[0] > 0.0
    for a in range(3):
        kind, share = K[K_KIND, a], F[F_WOUT, a]
        area = fpar[FP_A + a]
        for i in range(share.shape[0]):
            for j in range(share.shape[1]):
                for k in range(share.shape[2]):
                    if kind[i, j, k] == OUTFLOW_FACE:
                        share[i, j, k] = share[i, j, k] / total[0] if by_flow else area / total[2]


@njit(cache=True, error_model="numpy")
def _face_constants(C, F, K, fpar, idt, nx, ny, nz, threads):
    """Per step: ε_f at t + dt (``face_voidage``) and the pressure term's ε_p,f = ε_f, X1 = w_old/dt + g,
    X2 = explicit terms + β u_s + source."""
    if threads > 1:
        _face_constant_threads(C, F, K, fpar, idt, nx, ny, nz)
    else:
        _face_constant_planes(np.int64(0), nx + 1, C, F, K, fpar, idt, nx, ny, nz)


@njit(cache=True, error_model="numpy", parallel=True)
def _face_constant_threads(C, F, K, fpar, idt, nx, ny, nz):
    for ip in prange(nx + 1):
        i = np.int64(ip)  # signed: Numba's prange index is unsigned, and unsigned + signed is a float
        _face_constant_planes(i, i + 1, C, F, K, fpar, idt, nx, ny, nz)


@njit(cache=True, error_model="numpy")
def _face_constant_planes(i0, i1, C, F, K, fpar, idt, nx, ny, nz):
    """``_face_constants`` on the faces with x index i0 <= i < i1."""
    E = C[C_E]
    for a in range(3):
        ex, ey, ez = unit(a)
        g = fpar[FP_G + a]
        kind, sign = K[K_KIND, a], K[K_SIGN, a]
        EF, X1, X2, old, exp_, rhs, EP = (F[F_EF, a], F[F_X1, a], F[F_X2, a], F[F_OLD, a], F[F_EX, a], F[F_RHS, a],
                                          F[F_EP, a])
        for i in range(max(i0, 0), min(i1, nx + ex)):
            for j in range(ny + ey):
                for k in range(nz + ez):
                    ef = face_voidage(E, i + 1 - ex, j + 1 - ey, k + 1 - ez, i + 1, j + 1, k + 1, kind[i, j, k],
                                      sign[i, j, k])
                    EF[i, j, k] = ef
                    EP[i, j, k] = ef
                    X1[i, j, k] = old[i, j, k] * idt + g
                    X2[i, j, k] = exp_[i, j, k] + rhs[i, j, k]


@njit(cache=True, error_model="numpy", parallel=True)
def _load_threads(p, rho, u, v, w, eps_old, W, C, F, p_ref, nx):
    for ip in prange(nx + 1):
        i = np.int64(ip)  # signed: Numba's prange index is unsigned, and unsigned + signed is a float
        _load_planes(i, i + 1, p, rho, u, v, w, eps_old, W, C, F, p_ref)


@njit(cache=True, error_model="numpy")
def _load_planes(i0, i1, p, rho, u, v, w, eps_old, W, C, F, p_ref):
    """The state at t into C (p − p_ref, ε, ερ), W and F[F_OLD], x planes i0 <= i < i1."""
    P, E, RO = C[C_P], C[C_E], C[C_RO_OLD]
    for i in range(max(i0, 0), min(i1, p.shape[0])):
        for j in range(p.shape[1]):
            for k in range(p.shape[2]):
                P[i + 1, j + 1, k + 1] = p[i, j, k] - p_ref
                E[i + 1, j + 1, k + 1] = eps_old[i, j, k]
                RO[i + 1, j + 1, k + 1] = eps_old[i, j, k] * rho[i, j, k]
    for a in range(3):
        src = u if a == 0 else (v if a == 1 else w)
        old = F[F_OLD, a]
        for i in range(max(i0, 0), min(i1, src.shape[0])):
            for j in range(src.shape[1]):
                for k in range(src.shape[2]):
                    W[a, i + 2, j + 2, k + 2] = src[i, j, k]
                    old[i, j, k] = src[i, j, k]


@njit(cache=True, error_model="numpy", parallel=True)
def _voidage_threads(eps, C, nx):
    for ip in prange(nx):
        i = np.int64(ip)  # signed: Numba's prange index is unsigned, and unsigned + signed is a float
        _voidage_planes(i, i + 1, eps, C)


@njit(cache=True, error_model="numpy")
def _voidage_planes(i0, i1, eps, C):
    """ε into the interior cells of C[C_E], x planes i0 <= i < i1."""
    E = C[C_E]
    for i in range(max(i0, 0), i1):
        for j in range(eps.shape[1]):
            for k in range(eps.shape[2]):
                E[i + 1, j + 1, k + 1] = eps[i, j, k]


@njit(cache=True, error_model="numpy")
def begin_step(p, rho, u, v, w, eps_old, eps_new, W, Q, C, F, K, S, T, flags, RULES, fpar, ipar):
    """Load the state at t (p absolute [Pa], rho, u, v, w, voidage), fill its ghosts, its mass fluxes and the
    explicit momentum terms F[F_EX]; the shares of the continuous outflow; then the new voidage
    ``eps_new`` and the boundary cells at t + dt, and the per-step face constants. F[F_BETA] and F[F_RHS]
    must hold this step's β and β u_s + source on every face."""
    nx, ny, nz, threads = ipar[I_N], ipar[I_N + 1], ipar[I_N + 2], ipar[I_THREADS]
    p_ref = fpar[FP_PREF]
    if threads > 1:
        _load_threads(p, rho, u, v, w, eps_old, W, C, F, p_ref, nx)
    else:
        _load_planes(np.int64(0), nx + 1, p, rho, u, v, w, eps_old, W, C, F, p_ref)
    boundary_cells(C, C[C_PFIX_OLD], flags, RULES, fpar, ipar)
    fill_face_ghosts(W, flags, nx, ny, nz, threads)
    mass_fluxes(W, Q, C, K, flags, nx, ny, nz, threads)
    explicit_momentum(W, Q, C, K, F, S, T, fpar, ipar)
    total = np.zeros(3)
    _outflow_shares(F, K, C, fpar, total, nx, ny, nz, threads)
    if total[2] > 0.0:
        _normalise_shares(F, K, fpar, total)
    if threads > 1:
        _voidage_threads(eps_new, C, nx)
    else:
        _voidage_planes(np.int64(0), nx, eps_new, C)
    boundary_cells(C, C[C_PFIX], flags, RULES, fpar, ipar)
    _face_constants(C, F, K, fpar, 1.0 / fpar[FP_DT], nx, ny, nz, threads)


@njit(cache=True, error_model="numpy")
def end_step(p, rho, u, v, w, eps, eps_new, W, C, flags, fpar, ipar):
    """Fill the ghost (and periodic duplicate) faces, then write the fields at t + dt into the state arrays
    (p as absolute pressure, ε = eps_new)."""
    nx, ny, nz, threads = ipar[I_N], ipar[I_N + 1], ipar[I_N + 2], ipar[I_THREADS]
    fill_face_ghosts(W, flags, nx, ny, nz, threads)
    if threads > 1:
        _store_threads(p, rho, u, v, w, eps, eps_new, W, C, fpar[FP_PREF], nx)
    else:
        _store_planes(np.int64(0), nx + 1, p, rho, u, v, w, eps, eps_new, W, C, fpar[FP_PREF])


@njit(cache=True, error_model="numpy", parallel=True)
def _store_threads(p, rho, u, v, w, eps, eps_new, W, C, p_ref, nx):
    for ip in prange(nx + 1):
        i = np.int64(ip)  # signed: Numba's prange index is unsigned, and unsigned + signed is a float
        _store_planes(i, i + 1, p, rho, u, v, w, eps, eps_new, W, C, p_ref)


@njit(cache=True, error_model="numpy")
def _store_planes(i0, i1, p, rho, u, v, w, eps, eps_new, W, C, p_ref):
    """The fields at t + dt into the state arrays (``end_step``), x planes i0 <= i < i1."""
    P, RHO = C[C_P], C[C_RHO]
    for i in range(max(i0, 0), min(i1, p.shape[0])):
        for j in range(p.shape[1]):
            for k in range(p.shape[2]):
                p[i, j, k] = P[i + 1, j + 1, k + 1] + p_ref
                rho[i, j, k] = RHO[i + 1, j + 1, k + 1]
                eps[i, j, k] = eps_new[i, j, k]
    for a in range(3):
        dst = u if a == 0 else (v if a == 1 else w)
        for i in range(max(i0, 0), min(i1, dst.shape[0])):
            for j in range(dst.shape[1]):
                for k in range(dst.shape[2]):
                    dst[i, j, k] = W[a, i + 2, j + 2, k + 2]


# ---------------------------------------------------------------------------- one iteration
@njit(cache=True, error_model="numpy")
def _face_fluxes(W, C, F, K, fpar, nx, ny, nz, threads):
    """Momentum of every face at the current pressure and the mass fluxes A (ερ)_f w [kg/s] into F[F_FLUX]:
    0 on outflow faces (``_outflow`` adds theirs), periodic duplicates those of face 0. Solved faces::

        (ερ)_f (w - w_old)/dt = ex - ε_f ∂p/∂x_a - β (w - w_s) + (ερ)_f g_a + source
        w = (m X1 + X2 - ε_p,f ∂p/∂x_a) / (m/dt + β),   m = ε_f ρ_f

    Returns whether there are outflow faces."""
    if threads > 1:
        has_outflow = _face_flux_threads(W, C, F, K, fpar, nx, ny, nz) > 0
    else:
        has_outflow = _face_flux_planes(np.int64(0), nx + 1, W, C, F, K, fpar, nx, ny, nz)
    for a in range(3):
        kind, FL = K[K_KIND, a], F[F_FLUX, a]
        na = nx if a == 0 else (ny if a == 1 else nz)
        nb, nc = (ny, nz) if a == 0 else ((nz, nx) if a == 1 else (nx, ny))
        for s in range(nb):
            for t in range(nc):
                g = at(a, na, s, t)
                if kind[g] == COPY:
                    FL[g] = FL[at(a, 0, s, t)]
    return has_outflow


@njit(cache=True, error_model="numpy", parallel=True)
def _face_flux_threads(W, C, F, K, fpar, nx, ny, nz):
    n_outflow = 0
    for ip in prange(nx + 1):
        i = np.int64(ip)  # signed: Numba's prange index is unsigned, and unsigned + signed is a float
        n_outflow += 1 if _face_flux_planes(i, i + 1, W, C, F, K, fpar, nx, ny, nz) else 0
    return n_outflow


@njit(cache=True, error_model="numpy")
def _face_flux_planes(i0, i1, W, C, F, K, fpar, nx, ny, nz):
    """``_face_fluxes`` on the faces with x index i0 <= i < i1 (not the periodic duplicates); returns whether
    there are outflow faces among them (a flag, not a count: a counter in the loop halves its speed)."""
    P, RHO = C[C_P], C[C_RHO]
    idt = 1.0 / fpar[FP_DT]
    has_outflow = False
    for a in range(3):
        ex, ey, ez = unit(a)
        ih = 1.0 / fpar[FP_H + a]
        area = fpar[FP_A + a]
        kind = K[K_KIND, a]
        EF, X1, X2, beta, fix, FL, EP = (F[F_EF, a], F[F_X1, a], F[F_X2, a], F[F_BETA, a], F[F_FIX, a], F[F_FLUX, a],
                                         F[F_EP, a])
        for i in range(max(i0, 0), min(i1, nx + ex)):
            for j in range(ny + ey):
                for k in range(nz + ez):
                    kk = kind[i, j, k]
                    l0, l1, l2 = i + 1 - ex, j + 1 - ey, k + 1 - ez
                    rf = 0.5 * (RHO[l0, l1, l2] + RHO[i + 1, j + 1, k + 1])
                    if kk == SOLVED:
                        ef = EF[i, j, k]
                        m = ef * rf
                        w = (m * X1[i, j, k] + X2[i, j, k]
                             - EP[i, j, k] * (P[i + 1, j + 1, k + 1] - P[l0, l1, l2]) * ih) / (m * idt + beta[i, j, k])
                        W[a, i + 2, j + 2, k + 2] = w
                        FL[i, j, k] = area * ef * rf * w
                    elif kk == FIXED:
                        w = fix[i, j, k]
                        W[a, i + 2, j + 2, k + 2] = w
                        FL[i, j, k] = area * EF[i, j, k] * rf * w
                    elif kk == OUTFLOW_FACE:
                        FL[i, j, k] = 0.0
                        has_outflow = True
    return has_outflow


@njit(cache=True, error_model="numpy")
def _boundary_flows(F, K, nx, ny, nz):
    """(inflow, outflow, net inflow) [kg/s] through the boundary faces (F[F_FLUX]), outflow faces apart."""
    inflow = 0.0
    outflow = 0.0
    net_in = 0.0
    N = (nx, ny, nz)
    for a in range(3):
        kind, sign, FL = K[K_KIND, a], K[K_SIGN, a], F[F_FLUX, a]
        for hi in range(2):
            p = N[a] if hi else 0
            for s in range(N[(a + 1) % 3]):
                for t in range(N[(a + 2) % 3]):
                    g = at(a, p, s, t)
                    sg = sign[g]
                    kk = kind[g]
                    if sg == 0 or kk == COPY or kk == OUTFLOW_FACE:
                        continue
                    fin = sg * FL[g]
                    net_in += fin
                    if fin > 0.0:
                        inflow += fin
                    else:
                        outflow -= fin
    return inflow, outflow, net_in


@njit(cache=True, error_model="numpy")
def _outflow(W, C, F, K, row_of, R, fpar, need, nx, ny, nz):
    """Continuous-outflow faces carry their share F[F_WOUT] of the outflow ``need`` [kg/s]; their velocity
    follows from the interior cell's ε ρ. Returns (in, out)."""
    RHO, E = C[C_RHO], C[C_E]
    inflow = 0.0
    outflow = 0.0
    for a in range(3):
        ex, ey, ez = unit(a)
        area = fpar[FP_A + a]
        kind, sign, share = K[K_KIND, a], K[K_SIGN, a], F[F_WOUT, a]
        for i in range(nx + ex):
            for j in range(ny + ey):
                for k in range(nz + ez):
                    if kind[i, j, k] != OUTFLOW_FACE:
                        continue
                    s = sign[i, j, k]
                    fout = share[i, j, k] * need
                    l0, l1, l2 = i + 1 - ex, j + 1 - ey, k + 1 - ez
                    if s < 0:
                        c0, c1, c2 = l0, l1, l2
                    else:
                        c0, c1, c2 = i + 1, j + 1, k + 1
                    f = -s * fout  # flux along +x_a
                    W[a, i + 2, j + 2, k + 2] = f / (area * E[c0, c1, c2] * RHO[c0, c1, c2])
                    rl = row_of[l0, l1, l2]
                    rr = row_of[i + 1, j + 1, k + 1]
                    if rl >= 0:
                        R[rl] += f
                    if rr >= 0:
                        R[rr] -= f
                    if fout > 0.0:
                        outflow += fout
                    else:
                        inflow -= fout
    return inflow, outflow


@njit(cache=True, error_model="numpy", parallel=True)
def _residual_threads(C, F, R, vdt, nx, ny, nz):
    for ip in prange(nx):
        i = np.int64(ip)  # signed: Numba's prange index is unsigned, and unsigned + signed is a float
        _residual_planes(i, i + 1, C, F, R, vdt, ny, nz)


@njit(cache=True, error_model="numpy")
def _residual_planes(i0, i1, C, F, R, vdt, ny, nz):
    """The cell continuity residuals of ``predict_residual`` (without outflow faces), x planes i0 <= i < i1."""
    E, RHO, RO = C[C_E], C[C_RHO], C[C_RO_OLD]
    FLX, FLY, FLZ = F[F_FLUX, 0], F[F_FLUX, 1], F[F_FLUX, 2]
    for i in range(max(i0, 0), i1):
        for j in range(ny):
            for k in range(nz):
                er = E[i + 1, j + 1, k + 1] * RHO[i + 1, j + 1, k + 1]
                a = vdt * (er - RO[i + 1, j + 1, k + 1])
                R[(i * ny + j) * nz + k] = a + ((FLX[i + 1, j, k] - FLX[i, j, k]) + (FLY[i, j + 1, k] - FLY[i, j, k])
                                                + (FLZ[i, j, k + 1] - FLZ[i, j, k]))


@njit(cache=True, error_model="numpy")
def predict_residual(W, C, F, K, row_of, R, fpar, ipar, out):
    """Face velocities from the momentum balance at the current pressure (``_face_fluxes``), then the cell
    continuity residuals (Hoomans 1996 eq. 42) [kg/s]::

        R_c = V [(ερ)_c - (ερ)_c,old]/dt + Σ_faces A (ερ)_f w_out

    row (i ny + j) nz + k for cell (i, j, k). Outflow faces carry F[F_WOUT] × the outflow that closes the
    mass balance. Writes Σ|R|, the reference flow, inflow, outflow, accumulation and mass into ``out``
    and returns the mass residual Σ|R| / reference flow."""
    nx, ny, nz = ipar[I_N], ipar[I_N + 1], ipar[I_N + 2]
    idt = 1.0 / fpar[FP_DT]
    vol = fpar[FP_VOL]
    RHO, E, RO = C[C_RHO], C[C_E], C[C_RO_OLD]
    threads = ipar[I_THREADS]
    has_outflow = _face_fluxes(W, C, F, K, fpar, nx, ny, nz, threads)
    vdt = vol * idt
    if threads > 1:
        _residual_threads(C, F, R, vdt, nx, ny, nz)
    else:
        _residual_planes(np.int64(0), nx, C, F, R, vdt, ny, nz)
    acc = 0.0
    acc_abs = 0.0
    mass = 0.0
    for i in range(nx):  # the sums in cell order, serial: the same on any number of threads
        for j in range(ny):
            for k in range(nz):
                er = E[i + 1, j + 1, k + 1] * RHO[i + 1, j + 1, k + 1]
                a = vdt * (er - RO[i + 1, j + 1, k + 1])
                acc += a
                acc_abs += abs(a)
                mass += er
    mass *= vol
    inflow, outflow, net = _boundary_flows(F, K, nx, ny, nz)
    if has_outflow:
        a_in, a_out = _outflow(W, C, F, K, row_of, R, fpar, net - acc, nx, ny, nz)
        inflow += a_in
        outflow += a_out
    res = 0.0
    for q in range(R.size):
        res += abs(R[q])
    qref = inflow + outflow + acc_abs + MASS_FLOOR * mass * idt
    out[O_RES], out[O_QREF], out[O_IN], out[O_OUT], out[O_ACC], out[O_MASS] = res, qref, inflow, outflow, acc, mass
    return res / qref if qref > 0.0 else 0.0


@njit(cache=True, error_model="numpy")
def courant_number(W, fpar, ipar):
    """Σ_a max|w_a| dt/h_a over the faces [-]."""
    nx, ny, nz = ipar[I_N], ipar[I_N + 1], ipar[I_N + 2]
    total = 0.0
    for a in range(3):
        ex, ey, ez = unit(a)
        m = 0.0
        for i in range(nx + ex):
            for j in range(ny + ey):
                for k in range(nz + ez):
                    m = max(m, abs(W[a, i + 2, j + 2, k + 2]))
        total += m * fpar[FP_DT] / fpar[FP_H + a]
    return total


# ---------------------------------------------------------------------------- pressure correction
@njit(cache=True, error_model="numpy")
def assemble_pressure(data, diag_pos, pos, pin_pos, W, C, F, K, fpar, ipar):
    """Matrix of the pressure correction p' (CSC ``data`` on a fixed pattern): the Newton derivative
    (Jacobian) of the continuity residuals with respect to the cell pressures, as in 2D
    (``_solver_kernels.assemble_pressure``): ε V comp/dt on the diagonal, A (ερ)_f D / h between the two
    cells of each solved face (D = ε_p,f / ((ερ)_f/dt + β)), and the derivatives through the face density
    of the flux and of the inertia of the face momentum. ``pos[a, i, j, k]`` holds the positions of (row L,
    col L), (row L, col R), (row R, col L), (row R, col R) of face (i, j, k) of axis a, −1 where a row or
    column does not exist; ``pin_pos``: the entries of row 0, replaced by p'_0 = 0 when the level is pinned."""
    nx, ny, nz, pin_diag = ipar[I_N], ipar[I_N + 1], ipar[I_N + 2], ipar[I_PIN]
    comp, dt, vol = fpar[FP_COMP], fpar[FP_DT], fpar[FP_VOL]
    idt = 1.0 / dt
    E, RHO = C[C_E], C[C_RHO]
    for q in range(data.size):
        data[q] = 0.0
    if comp != 0.0:
        for i in range(nx):
            for j in range(ny):
                for k in range(nz):
                    data[diag_pos[(i * ny + j) * nz + k]] += comp * E[i + 1, j + 1, k + 1] * vol * idt
    half_comp = 0.5 * comp
    for a in range(3):
        ex, ey, ez = unit(a)
        area = fpar[FP_A + a]
        ih = 1.0 / fpar[FP_H + a]
        kind, EF, beta, X1, EP = K[K_KIND, a], F[F_EF, a], F[F_BETA, a], F[F_X1, a], F[F_EP, a]
        for i in range(nx + ex):
            for j in range(ny + ey):
                for k in range(nz + ez):
                    kk = kind[i, j, k]
                    if kk == COPY or kk == OUTFLOW_FACE:
                        continue
                    w = W[a, i + 2, j + 2, k + 2]
                    ef = EF[i, j, k]
                    rf = 0.5 * (RHO[i + 1 - ex, j + 1 - ey, k + 1 - ez] + RHO[i + 1, j + 1, k + 1])
                    base = area * ef * rf
                    acoef = ef * rf * idt + beta[i, j, k]
                    d = EP[i, j, k] / acoef if kk == SOLVED else 0.0
                    c = base * d * ih
                    t = area * ef * w * half_comp
                    if kk == SOLVED and comp != 0.0:
                        t += base * (ef / acoef) * half_comp * (X1[i, j, k] - w * idt)
                    p_ll, p_lr, p_rl, p_rr = pos[a, i, j, k, 0], pos[a, i, j, k, 1], pos[a, i, j, k, 2], pos[a, i, j, k, 3]
                    if p_ll >= 0:
                        data[p_ll] += c + t
                    if p_lr >= 0:
                        data[p_lr] += t - c
                    if p_rl >= 0:
                        data[p_rl] -= c + t
                    if p_rr >= 0:
                        data[p_rr] += c - t
    if pin_diag >= 0:
        for q in pin_pos:
            data[q] = 0.0
        data[pin_diag] = 1.0


@njit(cache=True, error_model="numpy", parallel=True)
def _correction_threads(C, dp, nx, ny, nz):
    for ip in prange(nx):
        i = np.int64(ip)  # signed: Numba's prange index is unsigned, and unsigned + signed is a float
        _correction_planes(i, i + 1, C, dp, ny, nz)


@njit(cache=True, error_model="numpy")
def _correction_planes(i0, i1, C, dp, ny, nz):
    """p += p' in the interior cells of the x planes i0 <= i < i1 (``correct_pressure``)."""
    P = C[C_P]
    for i in range(max(i0, 0), i1):
        for j in range(ny):
            for k in range(nz):
                P[i + 1, j + 1, k + 1] += dp[(i * ny + j) * nz + k]


@njit(cache=True, error_model="numpy")
def correct_pressure(C, dp, flags, RULES, fpar, ipar):
    """p += p' in every cell (p'_row of cell (i, j, k) at (i ny + j) nz + k), then the boundary cells of
    the pressure and the density everywhere."""
    nx, ny, nz = ipar[I_N], ipar[I_N + 1], ipar[I_N + 2]
    P, threads = C[C_P], ipar[I_THREADS]
    if threads > 1:
        _correction_threads(C, dp, nx, ny, nz)
    else:
        _correction_planes(np.int64(0), nx, C, dp, ny, nz)
    fill_centre_ghosts(P, flags, RULES[RULE_P], C[C_PFIX], nx, ny, nz)
    update_density(C, fpar[FP_COMP], fpar[FP_RHOC], fpar[FP_PREF], threads)


@njit(cache=True, error_model="numpy")
def newton_multigrid(W, C, F, K, row_of, R, fpar, ipar, out, data, diag_pos, pos, pin_pos, flags, RULES, ell, MGL, MGI,
                     MGA, MGS, MGW, DLU, PIV, KRY, HES, rhs, dp, pinned, tolerance, max_iterations, reduction,
                     floor_factor, krylov_max, counts, chord):
    """The Newton iterations of a gas step on the multigrid path, in one compiled call: the continuity residual
    (``predict_residual``) until it is at most ``tolerance`` (or not finite, or after ``max_iterations``), each
    iteration solving J p' = −R by GMRES to max(``reduction`` ‖R‖₂, ``floor_factor`` × the reference flow / √n),
    then ``correct_pressure``. The first iteration of the step assembles the Jacobian (``assemble_pressure``) and
    makes its hierarchy (``_multigrid3d_kernels.mg_setup``). A later one keeps the last hierarchy, and with it
    the last Jacobian as GMRES's matrix (a chord step of the inexact Newton method), where the last correction
    cut the residual to at most ``chord`` times what it was (0: never); it assembles again where the reduction
    was weaker or GMRES on the kept matrix does not converge. The residual, and so the convergence test, is
    always the current one. ``pinned``: row 0 is the pressure level's (its right-hand side 0). ``counts``
    [hierarchies, GMRES iterations] are added to. Returns (iterations, mass residual, failed): ``failed`` where
    the hierarchy could not be made or GMRES stalled on a fresh one in the iteration reached, whose right-hand
    side is then in ``rhs`` and Jacobian in ``data`` (the caller goes on with SuperLU)."""
    n = R.size
    it = 0
    prev = math.inf
    kept = False  # a hierarchy of this step is set up
    while True:
        rel = predict_residual(W, C, F, K, row_of, R, fpar, ipar, out)
        if not math.isfinite(rel) or rel <= tolerance or it >= max_iterations:
            return it, rel, False
        for q in range(n):
            rhs[q] = -R[q]
        if pinned:
            rhs[0] = 0.0
        target = max(reduction * math.sqrt(np.dot(rhs, rhs)), floor_factor * out[O_QREF] / math.sqrt(n))
        kits = -1
        if kept and rel <= chord * prev:
            kits = gmres(MGL, MGI, MGA, MGS, MGW, DLU, PIV, KRY, HES, rhs, dp, target, krylov_max)
            if kits >= 0:
                counts[1] += kits
        if kits < 0:
            assemble_pressure(data, diag_pos, pos, pin_pos, W, C, F, K, fpar, ipar)
            if not mg_setup(data, ell, MGL, MGI, MGA, MGS, MGW, DLU, PIV):
                return it, rel, True
            counts[0] += 1
            kept = True
            kits = gmres(MGL, MGI, MGA, MGS, MGW, DLU, PIV, KRY, HES, rhs, dp, target, krylov_max)
            if kits < 0:
                return it, rel, True
            counts[1] += kits
        correct_pressure(C, dp, flags, RULES, fpar, ipar)
        prev = rel
        it += 1
