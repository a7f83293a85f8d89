"""Compiled kernels of the gas solver: ghost values from cell flags, explicit momentum terms,
momentum prediction with the continuity residual, pressure-correction matrix, correction.

Arrays are the solver's padded arrays (``grid.py``): centre arrays ``(nx + 2, ny + 2)``
with cell (i, j) at ``[i + 1, j + 1]``; ``U`` ``(nx + 5, ny + 4)`` with x-face (i, j)
at ``[i + 2, j + 2]``; ``V`` ``(nx + 4, ny + 5)`` with y-face (i, j) at ``[i + 2, j + 2]``.
Boundary behaviour comes only from the integer cell flags (Hoomans 1996 Table 1) and
the face kinds derived from them at set-up.

Symbols inside kernels: ``E`` voidage ε, ``RHO`` gas density ρ_g, ``P`` pressure,
``G``/``H`` mass flux densities (ερ)_donor u, (ερ)_donor v [kg m^-2 s^-1], ``beta``
the interphase momentum-transfer coefficient β [kg m^-3 s^-1].
"""
import numpy as np
from numba import njit

from ._operators import face_value, normal_stresses_at_centre, shear_stress_at_corner

# cell flags (grid.py)
FREE_SLIP, NO_SLIP, INFLOW, PRESSURE, OUTFLOW, PERIODIC = 2, 3, 4, 5, 6, 8
# face kinds: momentum solved / value fixed (wall, inflow) / continuous outflow / periodic duplicate of face 0
SOLVED, FIXED, OUTFLOW_FACE, COPY = 0, 1, 2, 3
# ghost rules of centre scalars, chosen per flag: zero gradient / prescribed value / periodic wrap
R_NONE, R_COPY, R_FIXED, R_WRAP = 0, 1, 2, 3


# ---------------------------------------------------------------------------- ghosts
@njit(cache=True, error_model="numpy")
def fill_centre_ghosts(q, flags, rule, fixed, nx, ny):
    """Boundary-cell values of a centre scalar from the flags: ``rule[flag]`` is R_COPY
    (adjacent interior value), R_FIXED (``fixed`` at that cell) or R_WRAP (opposite side).
    Corners: the opposite corner cell when both sides are periodic, else the mean of the
    two boundary cells beside them."""
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
    both = flags[0, 1] == PERIODIC and flags[1, 0] == PERIODIC
    if both:
        q[0, 0] = q[nx, ny]
        q[nx + 1, 0] = q[1, ny]
        q[0, ny + 1] = q[nx, 1]
        q[nx + 1, ny + 1] = q[1, 1]
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


# ---------------------------------------------------------------------------- explicit terms
@njit(cache=True, error_model="numpy")
def mass_fluxes(U, V, E, RHO, G, H, flags, nx, ny):
    """G = (ερ)_donor u on x-faces and H = (ερ)_donor v on y-faces [kg m^-2 s^-1]
    (donor-cell ερ, Kuipers et al. 1992), ghosts filled like velocities."""
    for i in range(nx + 1):
        for j in range(ny):
            w = U[i + 2, j + 2]
            if w >= 0.0:
                G[i + 2, j + 2] = E[i, j + 1] * RHO[i, j + 1] * w
            else:
                G[i + 2, j + 2] = E[i + 1, j + 1] * RHO[i + 1, j + 1] * w
    for i in range(nx):
        for j in range(ny + 1):
            w = V[i + 2, j + 2]
            if w >= 0.0:
                H[i + 2, j + 2] = E[i + 1, j] * RHO[i + 1, j] * w
            else:
                H[i + 2, j + 2] = E[i + 1, j + 1] * RHO[i + 1, j + 1] * w
    fill_face_ghosts(G, H, flags, nx, ny)


@njit(cache=True, error_model="numpy")
def explicit_momentum(U, V, G, H, E, mu, dx, dy, scheme, ukind, vkind, exu, exv, nx, ny):
    """Explicit part of the momentum balance (Hoomans 1996 eq. 43) on every solved face [N m^-3]:
    exu = −[∇·(ερ u u) − u ∇·(ερ u)] − ∇·(ε τ_g), the convection in advective form (donor
    mass fluxes, face values by ``scheme``) and the viscous stress of eq. 48 (λ_g = 0)."""
    for i in range(nx + 1):
        for j in range(ny):
            if ukind[i, j] != 0:
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
            if vkind[i, j] != 0:
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


# ---------------------------------------------------------------------------- one iteration
@njit(cache=True, error_model="numpy")
def predict_residual(U, V, P, RHO, E, ro_old, u_old, v_old, exu, exv, beta_u, beta_v, rhs_u, rhs_v,
                     ukind, vkind, ufix, vfix, ubnd, vbnd, wout_u, wout_v, row_of, flags,
                     gx, gy, dt, dx, dy, area_x, area_y, vol, Du, Dv, R, nx, ny):
    """Face velocities from the momentum balance at the current pressure, then the cell
    continuity residuals (Hoomans 1996 eqs 42-43).

    Momentum on a solved face, implicit in pressure and drag (Kuipers et al. 1992)::

        (ερ)_f (u - u_old)/dt = exu - ε_f ∂p/∂x - β (u - u_s) + (ερ)_f g_x + source
        u = û - D ∂p/∂x,   D = ε_f / ((ερ)_f/dt + β)

    with ``rhs_u = β u_s + source``. Continuity residual of cell c [kg/s]::

        R_c = V [(ερ)_c - (ερ)_c,old]/dt + Σ_faces A (ερ)_donor u_out

    Outflow faces carry ``wout`` × the outflow that closes the mass balance. Returns
    (Σ|R|, reference flow, inflow, outflow, accumulation, mass, courant).
    """
    # momentum on solved faces; fixed faces take their values
    for i in range(nx + 1):
        for j in range(ny):
            k = ukind[i, j]
            if k == SOLVED:
                ef = 0.5 * (E[i, j + 1] + E[i + 1, j + 1])
                m = ef * 0.5 * (RHO[i, j + 1] + RHO[i + 1, j + 1])
                a = m / dt + beta_u[i, j]
                uh = (m * u_old[i, j] / dt + exu[i, j] + m * gx + rhs_u[i, j]) / a
                d = ef / a
                Du[i, j] = d
                U[i + 2, j + 2] = uh - d * (P[i + 1, j + 1] - P[i, j + 1]) / dx
            elif k == FIXED:
                Du[i, j] = 0.0
                U[i + 2, j + 2] = ufix[i, j]
            else:
                Du[i, j] = 0.0
    for i in range(nx):
        for j in range(ny + 1):
            k = vkind[i, j]
            if k == SOLVED:
                ef = 0.5 * (E[i + 1, j] + E[i + 1, j + 1])
                m = ef * 0.5 * (RHO[i + 1, j] + RHO[i + 1, j + 1])
                a = m / dt + beta_v[i, j]
                vh = (m * v_old[i, j] / dt + exv[i, j] + m * gy + rhs_v[i, j]) / a
                d = ef / a
                Dv[i, j] = d
                V[i + 2, j + 2] = vh - d * (P[i + 1, j + 1] - P[i + 1, j]) / dy
            elif k == FIXED:
                Dv[i, j] = 0.0
                V[i + 2, j + 2] = vfix[i, j]
            else:
                Dv[i, j] = 0.0
    # accumulation
    acc = 0.0
    acc_abs = 0.0
    mass = 0.0
    for i in range(nx):
        for j in range(ny):
            er = E[i + 1, j + 1] * RHO[i + 1, j + 1]
            a = vol * (er - ro_old[i, j]) / dt
            R[i * ny + j] = a
            acc += a
            acc_abs += abs(a)
            mass += vol * er
    # fluxes through every face except outflow faces and periodic duplicates
    inflow = 0.0
    outflow = 0.0
    net_in = 0.0
    has_outflow = False
    for i in range(nx + 1):
        for j in range(ny):
            k = ukind[i, j]
            if k == COPY:
                continue
            if k == OUTFLOW_FACE:
                has_outflow = True
                continue
            w = U[i + 2, j + 2]
            if w >= 0.0:
                f = area_x * E[i, j + 1] * RHO[i, j + 1] * w
            else:
                f = area_x * E[i + 1, j + 1] * RHO[i + 1, j + 1] * w
            rl = row_of[i, j + 1]
            rr = row_of[i + 1, j + 1]
            if rl >= 0:
                R[rl] += f
            if rr >= 0:
                R[rr] -= f
            s = ubnd[i, j]
            if s != 0:
                fin = s * f
                net_in += fin
                if fin > 0.0:
                    inflow += fin
                else:
                    outflow -= fin
    for i in range(nx):
        for j in range(ny + 1):
            k = vkind[i, j]
            if k == COPY:
                continue
            if k == OUTFLOW_FACE:
                has_outflow = True
                continue
            w = V[i + 2, j + 2]
            if w >= 0.0:
                f = area_y * E[i + 1, j] * RHO[i + 1, j] * w
            else:
                f = area_y * E[i + 1, j + 1] * RHO[i + 1, j + 1] * w
            rb = row_of[i + 1, j]
            rt = row_of[i + 1, j + 1]
            if rb >= 0:
                R[rb] += f
            if rt >= 0:
                R[rt] -= f
            s = vbnd[i, j]
            if s != 0:
                fin = s * f
                net_in += fin
                if fin > 0.0:
                    inflow += fin
                else:
                    outflow -= fin
    # continuous outflow: the faces share the outflow that closes the balance
    if has_outflow:
        need = net_in - acc
        for i in range(nx + 1):
            for j in range(ny):
                if ukind[i, j] != OUTFLOW_FACE:
                    continue
                s = ubnd[i, j]
                fout = wout_u[i, j] * need
                c = i if s < 0 else i + 1  # interior cell (padded column)
                f = -s * fout  # flux along +x
                U[i + 2, j + 2] = f / (area_x * E[c, j + 1] * RHO[c, j + 1])
                rl = row_of[i, j + 1]
                rr = row_of[i + 1, j + 1]
                if rl >= 0:
                    R[rl] += f
                if rr >= 0:
                    R[rr] -= f
                if fout > 0.0:
                    outflow += fout
                else:
                    inflow -= fout
        for i in range(nx):
            for j in range(ny + 1):
                if vkind[i, j] != OUTFLOW_FACE:
                    continue
                s = vbnd[i, j]
                fout = wout_v[i, j] * need
                c = j if s < 0 else j + 1
                f = -s * fout
                V[i + 2, j + 2] = f / (area_y * E[i + 1, c] * RHO[i + 1, c])
                rb = row_of[i + 1, j]
                rt = row_of[i + 1, j + 1]
                if rb >= 0:
                    R[rb] += f
                if rt >= 0:
                    R[rt] -= f
                if fout > 0.0:
                    outflow += fout
                else:
                    inflow -= fout
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
    qref = inflow + outflow + acc_abs + 1e-4 * mass / dt
    return res, qref, inflow, outflow, acc, mass, umax * dt / dx + vmax * dt / dy


# ---------------------------------------------------------------------------- pressure correction
@njit(cache=True, error_model="numpy")
def assemble_pressure(data, diag_pos, upos, vpos, U, V, E, RHO, Du, Dv, ukind, vkind, comp,
                      dt, dx, dy, area_x, area_y, vol, pin_pos, pin_diag, nx, ny):
    """Matrix of the pressure correction p' (CSC ``data`` of a fixed pattern): the Newton
    derivative of the continuity residuals R_c with respect to the cell pressures.

    Terms: compressibility ε V comp / dt on the diagonal (comp = M/(RT), 0 for constant
    density; Hoomans 1996 eq. 44), A (ερ)_donor D / h between the two cells of each
    solved face, and A ε_donor u comp from the donor density of every face with flow.
    ``upos[i, j]`` holds the positions of (row L, col L), (row L, col R), (row R, col L),
    (row R, col R), −1 where a row or column does not exist. ``pin_pos``: positions of
    a row replaced by p' = 0 (constant-density gas without a pressure boundary).
    """
    data[:] = 0.0
    if comp != 0.0:
        for i in range(nx):
            for j in range(ny):
                data[diag_pos[i * ny + j]] += comp * E[i + 1, j + 1] * vol / dt
    for i in range(nx + 1):
        for j in range(ny):
            k = ukind[i, j]
            if k == COPY or k == OUTFLOW_FACE:
                continue
            w = U[i + 2, j + 2]
            if w >= 0.0:
                er = E[i, j + 1] * RHO[i, j + 1]
                t = area_x * E[i, j + 1] * w * comp
            else:
                er = E[i + 1, j + 1] * RHO[i + 1, j + 1]
                t = area_x * E[i + 1, j + 1] * w * comp
            c = area_x * er * Du[i, j] / dx
            p_ll, p_lr, p_rl, p_rr = upos[i, j, 0], upos[i, j, 1], upos[i, j, 2], upos[i, j, 3]
            # flux out of L: +c p'_L - c p'_R + t p'_donor ; out of R: the negative
            if p_ll >= 0:
                data[p_ll] += c + (t if w >= 0.0 else 0.0)
            if p_lr >= 0:
                data[p_lr] += -c + (t if w < 0.0 else 0.0)
            if p_rl >= 0:
                data[p_rl] += -c - (t if w >= 0.0 else 0.0)
            if p_rr >= 0:
                data[p_rr] += c - (t if w < 0.0 else 0.0)
    for i in range(nx):
        for j in range(ny + 1):
            k = vkind[i, j]
            if k == COPY or k == OUTFLOW_FACE:
                continue
            w = V[i + 2, j + 2]
            if w >= 0.0:
                er = E[i + 1, j] * RHO[i + 1, j]
                t = area_y * E[i + 1, j] * w * comp
            else:
                er = E[i + 1, j + 1] * RHO[i + 1, j + 1]
                t = area_y * E[i + 1, j + 1] * w * comp
            c = area_y * er * Dv[i, j] / dy
            p_bb, p_bt, p_tb, p_tt = vpos[i, j, 0], vpos[i, j, 1], vpos[i, j, 2], vpos[i, j, 3]
            if p_bb >= 0:
                data[p_bb] += c + (t if w >= 0.0 else 0.0)
            if p_bt >= 0:
                data[p_bt] += -c + (t if w < 0.0 else 0.0)
            if p_tb >= 0:
                data[p_tb] += -c - (t if w >= 0.0 else 0.0)
            if p_tt >= 0:
                data[p_tt] += c - (t if w < 0.0 else 0.0)
    if pin_diag >= 0:
        for p in pin_pos:
            data[p] = 0.0
        data[pin_diag] = 1.0


@njit(cache=True, error_model="numpy")
def apply_correction(P, RHO, dp, flags, prule, pfix, rho_factor, rho_const, nx, ny):
    """p += p' in the interior, boundary-cell pressures from the flags, and the density:
    ρ = p M/(RT) (Hoomans 1996 eq. 44; ``rho_factor`` = M/(RT)) or the constant ``rho_const``."""
    for i in range(nx):
        for j in range(ny):
            P[i + 1, j + 1] += dp[i * ny + j]
    fill_centre_ghosts(P, flags, prule, pfix, nx, ny)
    update_density(P, RHO, rho_factor, rho_const)


@njit(cache=True, error_model="numpy")
def update_density(P, RHO, rho_factor, rho_const):
    """ρ = p M/(RT) everywhere (Hoomans 1996 eq. 44), or the constant density when rho_factor is 0."""
    if rho_factor != 0.0:
        for i in range(P.shape[0]):
            for j in range(P.shape[1]):
                RHO[i, j] = rho_factor * P[i, j]
    else:
        RHO[:, :] = rho_const


@njit(cache=True, error_model="numpy")
def lu_solve(Lp, Li, Lx, Up, Ui, Ux, Ud, perm_r, perm_c, b, x, w):
    """x = A^-1 b from SuperLU factors Pr A Pc = L U: L strictly lower (unit diagonal), U strictly
    upper plus its diagonal Ud, both CSC; w[perm_r] = b, then x = (U^-1 L^-1 w)[perm_c]."""
    n = b.size
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


# fpar / ipar slots of ``iterate``
F_GX, F_GY, F_DT, F_DX, F_DY, F_AX, F_AY, F_VOL, F_COMP, F_RHOC, F_TOL, F_REUSE, F_SLOW = range(13)
I_NX, I_NY, I_MAXIT, I_PIN, I_HAVE_LU, I_ITER, I_CHECKED, I_REFACTORED, I_RESUME = range(9)
# out slots
O_RES, O_QREF, O_IN, O_OUT, O_ACC, O_MASS, O_COURANT, O_REL, O_PREV = range(9)
# iterate status
CONVERGED, NEED_FACTORS, MAX_ITERATIONS, NOT_FINITE = 0, 1, 2, 3


@njit(cache=True, error_model="numpy")
def iterate(U, V, P, RHO, E, ro_old, u_old, v_old, exu, exv, beta_u, beta_v, rhs_u, rhs_v,
            ukind, vkind, ufix, vfix, ubnd, vbnd, wout_u, wout_v, row_of, flags, prule, pfix,
            Du, Dv, R, dp, data, lu_data, diag_pos, upos, vpos, pin_pos,
            Lp, Li, Lx, Up, Ui, Ux, Ud, perm_r, perm_c, work, fpar, ipar, out):
    """Pressure-correction (Newton) iterations of one time step until the mass residual is below
    ``fpar[F_TOL]``.

    Each iteration: momentum prediction and continuity residual (``predict_residual``), then
    p' from the factorised pressure matrix and p += p'. The factors are those of an earlier
    matrix while it stays within ``F_REUSE`` (max norm) of the current one; when it does not,
    or an iteration reduces the residual by less than ``F_SLOW``, the kernel returns
    NEED_FACTORS with the current matrix in ``data``; the caller factorises it and calls again
    (``I_RESUME`` then skips straight to the solve). Returns CONVERGED, MAX_ITERATIONS or
    NOT_FINITE otherwise; the step's diagnostics are in ``out``.
    """
    gx, gy, dt, dx, dy = fpar[F_GX], fpar[F_GY], fpar[F_DT], fpar[F_DX], fpar[F_DY]
    area_x, area_y, vol, comp, rho_c = fpar[F_AX], fpar[F_AY], fpar[F_VOL], fpar[F_COMP], fpar[F_RHOC]
    nx, ny, max_it, pin_diag = ipar[I_NX], ipar[I_NY], ipar[I_MAXIT], ipar[I_PIN]
    n = nx * ny
    it = ipar[I_ITER]
    prev = out[O_PREV]
    while True:
        if ipar[I_RESUME] == 0:
            res, qref, fin, fout, acc, mass, courant = predict_residual(
                U, V, P, RHO, E, ro_old, u_old, v_old, exu, exv, beta_u, beta_v, rhs_u, rhs_v, ukind, vkind,
                ufix, vfix, ubnd, vbnd, wout_u, wout_v, row_of, flags, gx, gy, dt, dx, dy, area_x, area_y, vol,
                Du, Dv, R, nx, ny)
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
                assemble_pressure(data, diag_pos, upos, vpos, U, V, E, RHO, Du, Dv, ukind, vkind, comp, dt, dx, dy,
                                  area_x, area_y, vol, pin_pos, pin_diag, nx, ny)
                if ipar[I_HAVE_LU] == 0:
                    need = True
                else:
                    dmax = 0.0
                    amax = 0.0
                    for k in range(data.size):
                        dmax = max(dmax, abs(data[k] - lu_data[k]))
                        amax = max(amax, abs(lu_data[k]))
                    need = dmax > fpar[F_REUSE] * amax
            elif rel > fpar[F_SLOW] * prev and ipar[I_REFACTORED] == 0:
                assemble_pressure(data, diag_pos, upos, vpos, U, V, E, RHO, Du, Dv, ukind, vkind, comp, dt, dx, dy,
                                  area_x, area_y, vol, pin_pos, pin_diag, nx, ny)
                need = True
            if need:
                ipar[I_REFACTORED] = 1
                ipar[I_RESUME] = 1
                out[O_PREV] = rel
                return NEED_FACTORS
        ipar[I_RESUME] = 0
        prev = out[O_REL]
        out[O_PREV] = prev
        for k in range(n):
            R[k] = -R[k]
        if pin_diag >= 0:
            R[0] = 0.0
        lu_solve(Lp, Li, Lx, Up, Ui, Ux, Ud, perm_r, perm_c, R, dp, work)
        apply_correction(P, RHO, dp, flags, prule, pfix, comp, rho_c, nx, ny)
        it += 1
        ipar[I_ITER] = it


@njit(cache=True, error_model="numpy")
def begin_step(U, V, P, RHO, E, G, H, flags, prule, pfix_old, erule, efix, rho_factor, rho_const, mu, dx, dy,
               scheme, ukind, vkind, exu, exv, nx, ny):
    """Ghosts of the old state, its donor mass fluxes and the explicit momentum terms."""
    fill_centre_ghosts(P, flags, prule, pfix_old, nx, ny)
    fill_centre_ghosts(E, flags, erule, efix, nx, ny)
    update_density(P, RHO, rho_factor, rho_const)
    fill_face_ghosts(U, V, flags, nx, ny)
    mass_fluxes(U, V, E, RHO, G, H, flags, nx, ny)
    explicit_momentum(U, V, G, H, E, mu, dx, dy, scheme, ukind, vkind, exu, exv, nx, ny)


@njit(cache=True, error_model="numpy")
def end_of_step_ghosts(P, RHO, E, flags, prule, pfix, erule, efix, rho_factor, rho_const, nx, ny):
    """Boundary cells of the new voidage and of the pressure at t + dt, and the density."""
    fill_centre_ghosts(E, flags, erule, efix, nx, ny)
    fill_centre_ghosts(P, flags, prule, pfix, nx, ny)
    update_density(P, RHO, rho_factor, rho_const)
