"""Compiled kernels of the momentum-paired exchange (``exchange.py``, ``momentum_exchange``).

``particle`` mode (Sun 2007's drag "from each particle's own velocity", eq. 29, made
equal and opposite):

``deposit``          before the gas step: each particle's drag coefficient
                     K_p = β/(1 − ε_p) V_p [kg/s] at its interpolated ε_p and slip, and the
                     face sums A_f = Σ_p w_pf K_p, B_f = Σ_p w_pf K_p v_p with the weights w_pf
                     that interpolate the gas velocity to the particle (Hoomans 1996 eqs 40-41).
                     The gas then takes β_f = A_f / V_f and u_s,f = B_f / A_f, implicitly.
``particle_forces``  after the gas step: F_p = K_p (Σ_f w_pf u_f − v_p) − V_p ∇p_p.

Because Σ_f w_pf = 1 for every particle, Σ_f V_f β_f (u_f − u_s,f) = Σ_p K_p (u_p − v_p):
the gas loses exactly the momentum the particles gain, whatever the weights. Weights that
reach a boundary node of the extended grid are folded back onto real nodes so they stay
non-negative: the nearest node ("copy") at a wall, half to each of the two wrapped nodes on a
periodic side (which is exact linear interpolation across it). Along the face axis of a
non-periodic side, ``fold`` (``coupling.boundary_faces = "fold"``, the default) moves the
boundary face's weight onto the first interior face: the gas solves no momentum on a wall or
inflow face, and the half cell along it has no control volume of its own, so the first interior
face's stands for it (as it does for ∇p, ``_face_gradient``). Without ``fold`` the drag deposited
on such a face is momentum exchanged with that boundary: near an inflow, weight of the bed that
the gas pressure does not carry (the u_mf sweep of tests/validation/test_umf_sweep.py: plateau −4.6 % of W/A).

``deposit`` (and ``pressure_voidage`` for the other exchanges) also gives the gas the voidage of
its pressure term, ε_p,f = 1 − Σ_p w_pf V_p / V_f with the weights of the particles' ∇p, so
that the −V_p ∇p of the particles (Sun 2007 eq. 28) and the gas's −ε_p,f ∇p add up to −V_f ∇p
on every face: the pressure force is exchanged as exactly as the drag (``coupling.pressure_pairing``).

``cell`` mode (Sun 2007's cell-averaged drag shared by the particles of the cell):

``cell_faces``      β and β u_s of the cells averaged onto faces (ghost cells count 0, so that
                    every face carries half of each neighbouring cell's coefficient);
``cell_forces``     D_c = β_c V_c (u_c − u_s,c), u_c the mean of the cell's two faces, shared by
                    the particles whose centre lies in the cell in proportion to V_p.

Σ_faces V (β_f u_f − (β u_s)_f) = Σ_c D_c exactly (each face is half of two cells).

Array indices in the per-particle loops are cast to unsigned (``U``): Numba adds wrap-around code
for negative values to every access with a signed index (tsuji-jet-background bed at 1.5 s, one thread,
bitwise the same results: ``deposit`` 245 → 209 µs, ``particle_forces_split`` 204 → 158 µs).

``deposit`` computes every K_p first (the interpolation and the drag law, most of its work), then
adds them into the face sums in one serial pass in particle order. With more than one thread
(``parallel`` True) the first pass, and ``particle_forces_split``, run in chunks of particles on all
threads: each number is computed as on one thread, so the results are bitwise the same for any
number of threads.
"""
import math

import numpy as np
from numba import njit, prange

U = np.uintp  # unsigned array index: no wrap-around code (module docstring)
CHUNK = 256  # particles per work item of the parallel variants (``parallel`` True)

from ._exchange_kernels import _cell, _drag_arguments_valid, store_force
from .drag._dispatch import beta_per_solids


@njit(cache=True, inline="always")
def _face_gradient(p, i, j, n, inv_d, periodic, axis):
    """∂p/∂x (axis 0) on x-face (i, j) or ∂p/∂y (axis 1) on y-face (j, i) [Pa/m]: the centred
    difference of the two cells; across a periodic side the wrapped cells; a wall face copies
    its nearest interior face (``interpolation.pressure_gradient(boundary="copy")``)."""
    if n < 2:
        return 0.0
    if i == 0 or i == n:
        if periodic:
            a, b = n - 1, 0
        elif i == 0:
            a, b = 0, 1
        else:
            a, b = n - 2, n - 1
    else:
        a, b = i - 1, i
    if axis == 0:
        return (p[U(b), U(j)] - p[U(a), U(j)]) * inv_d
    return (p[U(j), U(b)] - p[U(j), U(a)]) * inv_d


@njit(cache=True, inline="always")
def _centre_axis(x, inv_d, n, periodic):
    """(k0, k1, w0, w1): the two cell-centre nodes of one axis around coordinate x and their
    weights (Hoomans 1996 eq. 41 in 1D), centres at (k + ½) d, k = 0 … n − 1.

    The nodes are extended by one on each wall (x = 0 and x = n d) whose weight is folded back:
    onto the nearest centre, or on a periodic axis half onto each of the two centres the side
    joins (exact linear interpolation across it). x is clamped to [0, n d]; w0 + w1 = 1.
    Scalars, not arrays: the kernels keep them in registers (3× faster than small arrays).
    """
    s = x * inv_d
    if not s > 0.0:  # below the domain or NaN
        s = 0.0
    if s > n:
        s = float(n)
    if n == 1:
        return 0, 0, 1.0, 0.0
    if s < 0.5:  # between the wall node and centre 0
        if periodic:
            t = 2.0 * s
            return 0, n - 1, 0.5 + 0.5 * t, 0.5 - 0.5 * t
        return 0, 0, 1.0, 0.0
    if s > n - 0.5:  # between centre n − 1 and the wall node
        if periodic:
            t = 2.0 * (s - (n - 0.5))
            return n - 1, 0, 1.0 - 0.5 * t, 0.5 * t
        return n - 1, n - 1, 1.0, 0.0
    k = int(math.floor(s - 0.5))
    if k > n - 2:
        k = n - 2
    t = s - 0.5 - k
    return k, k + 1, 1.0 - t, t


@njit(cache=True, inline="always")
def _face_axis(x, inv_d, n, periodic, fold):
    """(k0, k1, w0, w1) as ``_centre_axis`` for nodes at the faces k d, k = 0 … n (on a periodic
    axis face n is face 0).

    ``fold`` (a non-periodic axis of at least two cells): the weight of a boundary face (0 or n,
    which the gas does not solve, or at a pressure outlet solves without particles) goes to the first
    interior face (1 or n − 1), so a particle in the half cell along the boundary takes the gas
    velocity of that face and hands its drag to the gas there; the half cell has no momentum
    control volume of its own, so the first interior one stands for it. This is also how ∇p is
    interpolated in either case (``_face_gradient`` copies the interior face onto the boundary one).
    """
    s = x * inv_d
    if not s > 0.0:
        s = 0.0
    if s > n:
        s = float(n)
    k = int(math.floor(s))
    if k > n - 1:
        k = n - 1
    if fold and not periodic and n >= 2:
        if k == 0:
            return 1, 1, 1.0, 0.0
        if k == n - 1:
            return n - 1, n - 1, 1.0, 0.0
    t = s - k
    k1 = k + 1
    if periodic and k1 == n:
        k1 = 0
    return k, k1, 1.0 - t, t


@njit(cache=True, inline="always")
def _stencil(x, y, idx, idy, nx, ny, px, py, fold):
    """The nodes and weights around (x, y) on both axes: centres along x, faces along x, centres along
    y, faces along y (``_centre_axis``, ``_face_axis`` with ``fold``), 16 scalars."""
    ci0, ci1, cw0, cw1 = _centre_axis(x, idx, nx, px)
    fi0, fi1, fw0, fw1 = _face_axis(x, idx, nx, px, fold)
    cj0, cj1, cv0, cv1 = _centre_axis(y, idy, ny, py)
    fj0, fj1, fv0, fv1 = _face_axis(y, idy, ny, py, fold)
    return ci0, ci1, cw0, cw1, fi0, fi1, fw0, fw1, cj0, cj1, cv0, cv1, fj0, fj1, fv0, fv1


@njit(cache=True, inline="always")
def _mean(f, i0, i1, a0, a1, j0, j1, b0, b1):
    """Σ a_i b_j f[i, j] over the two nodes of each axis."""
    return a0 * (b0 * f[U(i0), U(j0)] + b1 * f[U(i0), U(j1)]) + a1 * (b0 * f[U(i1), U(j0)] + b1 * f[U(i1), U(j1)])


@njit(cache=True, inline="always")
def _gradient_at(p, fi0, fi1, fw0, fw1, cj0, cj1, cv0, cv1, ci0, ci1, cw0, cw1, fj0, fj1, fv0, fv1,
                 nx, ny, idx, idy, px, py):
    """(∂p/∂x, ∂p/∂y) at a particle: the face gradients (``_face_gradient``) interpolated like the
    velocity on their faces."""
    gx = (fw0 * (cv0 * _face_gradient(p, fi0, cj0, nx, idx, px, 0) + cv1 * _face_gradient(p, fi0, cj1, nx, idx, px, 0))
          + fw1 * (cv0 * _face_gradient(p, fi1, cj0, nx, idx, px, 0)
                   + cv1 * _face_gradient(p, fi1, cj1, nx, idx, px, 0)))
    gy = (fv0 * (cw0 * _face_gradient(p, fj0, ci0, ny, idy, py, 1) + cw1 * _face_gradient(p, fj0, ci1, ny, idy, py, 1))
          + fv1 * (cw0 * _face_gradient(p, fj1, ci0, ny, idy, py, 1)
                   + cw1 * _face_gradient(p, fj1, ci1, ny, idy, py, 1)))
    return gx, gy


@njit(cache=True, inline="always")
def _scatter(A, B, i0, i1, a0, a1, j0, j1, b0, b1, k, vel):
    """A[i, j] += a_i b_j k and B[i, j] += a_i b_j k vel over the two nodes of each axis (no branches:
    an inlined helper with array arguments and branches costs Numba reference counting)."""
    w = a0 * b0 * k
    A[U(i0), U(j0)] += w
    B[U(i0), U(j0)] += w * vel
    w = a0 * b1 * k
    A[U(i0), U(j1)] += w
    B[U(i0), U(j1)] += w * vel
    w = a1 * b0 * k
    A[U(i1), U(j0)] += w
    B[U(i1), U(j0)] += w * vel
    w = a1 * b1 * k
    A[U(i1), U(j1)] += w
    B[U(i1), U(j1)] += w * vel


@njit(cache=True, error_model="numpy")
def deposit(law, position, velocity, radius, volume, u, v, voidage, rho, mu, inv_dbar, dx, dy, min_voidage, px, py, kp,
            AU, BU, AV, BV, KC, vol, VU, VV, beta_u, su, beta_v, sv, fold, EU, EV, parallel=False):
    """K_p and the face sums of the ``particle`` mode (module docstring); returns the number of
    particles whose drag arguments are out of range (their K_p is NaN, nothing deposited).

    position, velocity : (N, 3); radius, volume, kp : (N,); u, AU, BU : (nx + 1, ny);
    v, AV, BV : (nx, ny + 1); voidage (ε at the end of the gas step, clipped to
    [min_voidage, 1] at the particle), rho, KC : (nx, ny). A*, B* are overwritten; KC[i, j] becomes
    Σ K_p over the particles whose centre lies in cell (i, j) (for output: Sun 2007 eq. 33's cell β
    times V_cell). What the gas takes: beta_u = AU / V_f, su = BU / AU (0 where AU = 0), and the same on
    the y-faces, with V_f = vol (V_cell) or, with ``fold`` (boundary faces folded, ``_face_axis``), the
    face volumes VU (nx + 1, ny), VV (nx, ny + 1) of ``exchange.face_volumes``.

    EU (nx + 1, ny), EV (nx, ny + 1), or both (0, 0) for none: the pressure term's face voidage
    (``pressure_voidage``), deposited in the same pass. inv_dbar (nx, ny): 1/D̄ of each cell's mixture
    [1/m] (``voidage.sauter_inverse``), interpolated to each particle as ε is, for the polydisperse
    drag (``drag._dispatch.beta_per_solids``); (0, 0) for a monodisperse bed (y = 1).
    """
    nx, ny = voidage.shape
    idx, idy = 1.0 / dx, 1.0 / dy
    AU[:, :] = 0.0
    BU[:, :] = 0.0
    AV[:, :] = 0.0
    BV[:, :] = 0.0
    KC[:, :] = 0.0
    n = position.shape[0]
    valid = np.empty(n, dtype=np.bool_)
    if parallel and n > CHUNK:
        bad = _kp_parallel(law, position, velocity, radius, volume, u, v, voidage, rho, mu, inv_dbar, idx, idy,
                           min_voidage,
                           px, py, fold, kp, valid)
    else:
        bad = _kp_range(np.int64(0), n, law, position, velocity, radius, volume, u, v, voidage, rho, mu, inv_dbar, idx,
                        idy, min_voidage, px, py, fold, kp, valid)
    solids = EU.shape[0] > 0
    if solids:
        EU[:, :] = 0.0
        EV[:, :] = 0.0
    for q_ in range(n):  # the face sums, in particle order
        q = U(q_)
        x = position[q, U(0)]
        y = position[q, U(1)]
        (ci0, ci1, cw0, cw1, fi0, fi1, fw0, fw1, cj0, cj1, cv0, cv1, fj0, fj1, fv0,
         fv1) = _stencil(x, y, idx, idy, nx, ny, px, py, fold)
        if solids:  # V_p on the faces of its ∇p interpolation (always folded: ``_face_gradient``)
            if fold:
                _add(EU, fi0, fi1, fw0, fw1, cj0, cj1, cv0, cv1, volume[q])
                _add(EV, ci0, ci1, cw0, cw1, fj0, fj1, fv0, fv1, volume[q])
            else:
                gi0, gi1, gw0, gw1 = _face_axis(x, idx, nx, px, True)
                gj0, gj1, gv0, gv1 = _face_axis(y, idy, ny, py, True)
                _add(EU, gi0, gi1, gw0, gw1, cj0, cj1, cv0, cv1, volume[q])
                _add(EV, ci0, ci1, cw0, cw1, gj0, gj1, gv0, gv1, volume[q])
        if not valid[q]:
            continue
        ic = min(max(int(x / dx), 0), nx - 1)
        jc = min(max(int(y / dy), 0), ny - 1)
        k = kp[q]
        KC[U(ic), U(jc)] += k
        _scatter(AU, BU, fi0, fi1, fw0, fw1, cj0, cj1, cv0, cv1, k, velocity[q, U(0)])
        _scatter(AV, BV, ci0, ci1, cw0, cw1, fj0, fj1, fv0, fv1, k, velocity[q, U(1)])
    _face_coefficients(AU, BU, vol, VU, fold, beta_u, su)
    _face_coefficients(AV, BV, vol, VV, fold, beta_v, sv)
    if solids:
        _face_voidage(EU, VU, min_voidage)
        _face_voidage(EV, VV, min_voidage)
    return bad


@njit(cache=True, error_model="numpy")
def _kp_range(lo, hi, law, position, velocity, radius, volume, u, v, voidage, rho, mu, inv_dbar, idx, idy, min_voidage,
              px, py, fold, kp, valid):
    """kp[q] of ``deposit`` for particles lo..hi−1, valid[q] whether its drag arguments are in range (else
    kp[q] = NaN); returns the number out of range."""
    nx, ny = voidage.shape
    three = velocity.shape[1] > 2
    mixture = inv_dbar.shape[0] > 0
    bad = 0
    for q_ in range(lo, hi):
        q = U(q_)
        x = position[q, U(0)]
        y = position[q, U(1)]
        (ci0, ci1, cw0, cw1, fi0, fi1, fw0, fw1, cj0, cj1, cv0, cv1, fj0, fj1, fv0,
         fv1) = _stencil(x, y, idx, idy, nx, ny, px, py, fold)
        eps = _mean(voidage, ci0, ci1, cw0, cw1, cj0, cj1, cv0, cv1)
        rg = _mean(rho, ci0, ci1, cw0, cw1, cj0, cj1, cv0, cv1)
        if eps < min_voidage:
            eps = min_voidage
        elif eps > 1.0:
            eps = 1.0
        wx = _mean(u, fi0, fi1, fw0, fw1, cj0, cj1, cv0, cv1) - velocity[q, U(0)]
        wy = _mean(v, ci0, ci1, cw0, cw1, fj0, fj1, fv0, fv1) - velocity[q, U(1)]
        wz = -velocity[q, U(2)] if three else 0.0
        slip = math.sqrt(wx * wx + wy * wy + wz * wz)
        d = 2.0 * radius[q]
        ok = _drag_arguments_valid(eps, slip, d, rg, mu)
        valid[q] = ok
        if not ok:
            bad += 1
            kp[q] = math.nan
            continue
        # y = d/D̄ (DEM book 2012 eq. 11) with 1/D̄ interpolated as ε is; 1 for a monodisperse bed
        yq = d * _mean(inv_dbar, ci0, ci1, cw0, cw1, cj0, cj1, cv0, cv1) if mixture else 1.0
        kp[q] = beta_per_solids(law, eps, slip, d, rg, mu, yq) * volume[q]
    return bad


@njit(cache=True, error_model="numpy", parallel=True)
def _kp_parallel(law, position, velocity, radius, volume, u, v, voidage, rho, mu, inv_dbar, idx, idy, min_voidage, px,
                 py, fold, kp, valid):
    n = position.shape[0]
    bad = 0
    for c in prange((n + CHUNK - 1) // CHUNK):
        bad += _kp_range(c * CHUNK, min(n, (c + 1) * CHUNK), law, position, velocity, radius, volume, u, v, voidage,
                         rho, mu, inv_dbar, idx, idy, min_voidage, px, py, fold, kp, valid)
    return bad


@njit(cache=True, error_model="numpy")
def _face_coefficients(A, B, vol, VF, per_face, beta, solids):
    """beta = A / V_f (VF[i, j] if ``per_face``, else vol), solids = B / A (0 where A = 0): the face β and
    u_s the gas takes."""
    for i in range(A.shape[0]):
        for j in range(A.shape[1]):
            a = A[i, j]
            beta[i, j] = a / (VF[i, j] if per_face else vol)
            solids[i, j] = B[i, j] / a if a > 0.0 else 0.0


@njit(cache=True, inline="always")
def _add(E, i0, i1, a0, a1, j0, j1, b0, b1, k):
    """E[i, j] += a_i b_j k over the two nodes of each axis."""
    E[U(i0), U(j0)] += a0 * b0 * k
    E[U(i0), U(j1)] += a0 * b1 * k
    E[U(i1), U(j0)] += a1 * b0 * k
    E[U(i1), U(j1)] += a1 * b1 * k


@njit(cache=True, error_model="numpy")
def _face_voidage(E, VF, min_voidage):
    """E (the particle volume on each face) → max(1 − E / V_f, min_voidage): ``pressure_voidage``."""
    for i in range(E.shape[0]):
        for j in range(E.shape[1]):
            E[i, j] = max(1.0 - E[i, j] / VF[i, j], min_voidage)


@njit(cache=True, error_model="numpy")
def pressure_voidage(position, volume, dx, dy, px, py, VU, VV, min_voidage, EU, EV):
    """The voidage of the gas's pressure term −ε_p,f ∂p/∂x that pairs the particles' −V_p ∇p_p:
    ε_p,f = 1 − Σ_p w_pf V_p / V_f with the weights w_pf by which ∇p is interpolated to particle p
    (``_gradient_at``: boundary faces folded) and the face volumes V_f of ``exchange.face_volumes`` (VU, VV),
    clipped below at ``min_voidage``.

    Then Σ_f (1 − ε_p,f) V_f ∂p/∂x|_f = Σ_p V_p ∂p/∂x|_p: the gas (−ε_p,f ∇p) and the particles
    (−V_p ∇p, Sun 2007 eq. 28) together feel −∇p V_f on each face, as the mixture must, so the
    pressure force is exchanged as drag is (Newton's third law), wherever no face is clipped.
    The mean of the mapped cell voidages (the gas's ε_f elsewhere) agrees with it only up to the
    mapping, and at an inflow face not at all (a bed on an inflow lost part of its weight there).
    EU (nx + 1, ny), EV (nx, ny + 1) are overwritten."""
    nx, ny = EU.shape[0] - 1, EU.shape[1]
    idx, idy = 1.0 / dx, 1.0 / dy
    EU[:, :] = 0.0
    EV[:, :] = 0.0
    for q_ in range(position.shape[0]):
        q = U(q_)
        (ci0, ci1, cw0, cw1, fi0, fi1, fw0, fw1, cj0, cj1, cv0, cv1, fj0, fj1, fv0,
         fv1) = _stencil(position[q, U(0)], position[q, U(1)], idx, idy, nx, ny, px, py, True)
        _add(EU, fi0, fi1, fw0, fw1, cj0, cj1, cv0, cv1, volume[q])
        _add(EV, ci0, ci1, cw0, cw1, fj0, fj1, fv0, fv1, volume[q])
    _face_voidage(EU, VU, min_voidage)
    _face_voidage(EV, VV, min_voidage)


@njit(cache=True, inline="always")
def _gas_at(x, y, u, v, p, idx, idy, nx, ny, px, py, fold, velocity, pressure):
    """Gas velocity (u, v) and ∇p at (x, y), interpolated with the weights of ``deposit`` (the velocity
    from its faces, ∇p by ``_gradient_at``); 0.0 for what is not asked (``velocity``, ``pressure``)."""
    (ci0, ci1, cw0, cw1, fi0, fi1, fw0, fw1, cj0, cj1, cv0, cv1, fj0, fj1, fv0,
     fv1) = _stencil(x, y, idx, idy, nx, ny, px, py, fold)
    ug = 0.0
    vg = 0.0
    gx = 0.0
    gy = 0.0
    if velocity:
        ug = _mean(u, fi0, fi1, fw0, fw1, cj0, cj1, cv0, cv1)
        vg = _mean(v, ci0, ci1, cw0, cw1, fj0, fj1, fv0, fv1)
    if pressure:
        gx, gy = _gradient_at(p, fi0, fi1, fw0, fw1, cj0, cj1, cv0, cv1, ci0, ci1, cw0, cw1, fj0, fj1, fv0, fv1,
                              nx, ny, idx, idy, px, py)
    return ug, vg, gx, gy


@njit(cache=True, error_model="numpy")
def particle_forces(position, velocity, volume, kp, u, v, p, dx, dy, px, py, fold, pressure_force, dim2, out, total):
    """out[q] = K_q (u_q − v_q) − V_q ∇p_q [N] (Sun 2007 eqs 28-29) with the weights of ``deposit``.

    ∇p at the particle: the face gradients (``_face_gradient``) interpolated like the velocity on
    their face. ``total`` (N, 3) follows the change of ``out`` (see ``_exchange_kernels.gas_forces``)
    or is (0, 3). z component 0 if ``dim2``; in 3D the gas has no z velocity, so F_z = −K v_z.
    """
    nx, ny = p.shape
    idx, idy = 1.0 / dx, 1.0 / dy
    three = velocity.shape[1] > 2
    follow = total.shape[0] > 0
    for q_ in range(position.shape[0]):
        q = U(q_)
        ug, vg, gx, gy = _gas_at(position[q, U(0)], position[q, U(1)], u, v, p, idx, idy, nx, ny, px, py, fold, True,
                                 pressure_force)
        k = kp[q]
        fx = k * (ug - velocity[q, U(0)])
        fy = k * (vg - velocity[q, U(1)])
        fz = -k * velocity[q, U(2)] if three else 0.0
        if pressure_force:  # −V_p ∇p, Sun eq. 28
            fx -= volume[q] * gx
            fy -= volume[q] * gy
        if dim2:
            fz = 0.0
        store_force(out, total, q, fx, fy, fz, follow)


@njit(cache=True, error_model="numpy")
def _split_range(lo, hi, position, velocity, volume, kp, u, v, p, idx, idy, px, py, fold, pressure_force, dim2, ext,
                 damp, total):
    """``particle_forces_split`` for particles lo..hi−1."""
    nx, ny = p.shape
    three = velocity.shape[1] > 2
    for q_ in range(lo, hi):
        q = U(q_)
        ug, vg, gx, gy = _gas_at(position[q, U(0)], position[q, U(1)], u, v, p, idx, idy, nx, ny, px, py, fold, True,
                                 pressure_force)
        k = kp[q]
        ax = k * ug
        ay = k * vg
        if pressure_force:  # −V_p ∇p, Sun eq. 28
            ax -= volume[q] * gx
            ay -= volume[q] * gy
        vx = velocity[q, U(0)]
        vy = velocity[q, U(1)]
        vz = velocity[q, U(2)] if three else 0.0
        c = damp[q]
        total[q, U(0)] += (ax - k * vx) - (ext[q, U(0)] - c * vx)
        total[q, U(1)] += (ay - k * vy) - (ext[q, U(1)] - c * vy)
        if not dim2:
            total[q, U(2)] += (0.0 - k * vz) - (ext[q, U(2)] - c * vz)
        ext[q, U(0)] = ax
        ext[q, U(1)] = ay
        ext[q, U(2)] = 0.0
        damp[q] = k


@njit(cache=True, error_model="numpy", parallel=True)
def _split_parallel(position, velocity, volume, kp, u, v, p, idx, idy, px, py, fold, pressure_force, dim2, ext, damp,
                    total):
    n = position.shape[0]
    for c in prange((n + CHUNK - 1) // CHUNK):
        _split_range(c * CHUNK, min(n, (c + 1) * CHUNK), position, velocity, volume, kp, u, v, p, idx, idy, px, py,
                     fold, pressure_force, dim2, ext, damp, total)


@njit(cache=True, error_model="numpy")
def particle_forces_split(position, velocity, volume, kp, u, v, p, dx, dy, px, py, fold, pressure_force, dim2, ext,
                          damp, total, parallel=False):
    """``particle_forces`` split for a drag that follows the particle's own velocity (``drag_update =
    "substep"``): the fixed part ext[q] = K_q u_q − V_q ∇p_q and the coefficient damp[q] = K_q, so that
    the engine evaluates ext − K v at every sub-step's velocity (Sun 2007 eq. 29 with u_q held from the
    step). ``total`` (N, 3) follows the change of the force at the current velocity:
    += (ext_new − K_new v) − (ext_old − K_old v). z of ext is 0 (the gas has no z velocity).
    ``parallel``: chunks of particles on all threads (each particle's numbers as on one)."""
    n = position.shape[0]
    if parallel and n > CHUNK:
        _split_parallel(position, velocity, volume, kp, u, v, p, 1.0 / dx, 1.0 / dy, px, py, fold, pressure_force,
                        dim2, ext, damp, total)
    else:
        _split_range(np.int64(0), n, position, velocity, volume, kp, u, v, p, 1.0 / dx, 1.0 / dy, px, py, fold,
                     pressure_force, dim2, ext, damp, total)


@njit(cache=True, inline="always")
def _faces_of_axis(beta, solids, periodic, bf, sf):
    """``cell_faces`` along axis 0 of beta (nx, ny) → faces (nx + 1, ny); the y-faces are this on
    the transposed arrays."""
    n, m = beta.shape
    for j in range(m):
        for i in range(n + 1):
            a, b = i - 1, i
            if periodic and (i == 0 or i == n):
                a, b = n - 1, 0
            ba = beta[a, j] if a >= 0 else 0.0
            bb = beta[b, j] if b < n else 0.0
            ma = ba * solids[a, j] if a >= 0 else 0.0
            mb = bb * solids[b, j] if b < n else 0.0
            bf[i, j] = 0.5 * (ba + bb)
            sf[i, j] = (ma + mb) / (ba + bb) if ba + bb > 0.0 else 0.0


@njit(cache=True, error_model="numpy")
def cell_faces(beta, solids_u, solids_v, px, py, bu, su, bv, sv):
    """Face β (bu, bv) and solids velocity (su, sv) of the ``cell`` mode from the cell β and u_s:
    β_f = (β_a + β_b)/2 and u_s,f = (β_a u_s,a + β_b u_s,b)/(β_a + β_b) (0 where β_f = 0), a ghost
    cell counting β = 0 and a periodic side joining its two edge cells (face n = face 0)."""
    _faces_of_axis(beta, solids_u, px, bu, su)
    _faces_of_axis(beta.T, solids_v.T, py, bv.T, sv.T)


@njit(cache=True, inline="always", error_model="numpy")
def cell_force(x, y, vq, i, j, solids, beta, solids_u, solids_v, u, v, p, idx, idy, cell_volume, px, py,
               pressure_force):
    """(F_x, F_y) of ``cell_forces`` for a particle of volume vq centred at (x, y) in cell (i, j), ``solids``
    Σ V_r of the cell's particles: its share V_q/Σ V_r of the cell's drag β V_c (u_c − u_s,c), minus V_q ∇p_q."""
    nx, ny = beta.shape
    share = vq / solids[i, j] * beta[i, j] * cell_volume
    fx = share * (0.5 * (u[i, j] + u[i + 1, j]) - solids_u[i, j])
    fy = share * (0.5 * (v[i, j] + v[i, j + 1]) - solids_v[i, j])
    if pressure_force:
        _, _, gx, gy = _gas_at(x, y, u, v, p, idx, idy, nx, ny, px, py, True, False, True)
        fx -= vq * gx
        fy -= vq * gy
    return fx, fy


@njit(cache=True, error_model="numpy")
def cell_forces(position, velocity, volume, beta, solids_u, solids_v, u, v, p, dx, dy, cell_volume, px, py,
                pressure_force, dim2, out, total):
    """out[q] = (V_q / Σ_{r in c} V_r) β_c V_c (u_c − u_s,c) − V_q ∇p_q [N] for the cell c of q's centre
    (Sun 2007's cell-averaged drag shared in the cell; u_c the mean of the cell's two faces),
    ∇p_q as in ``particle_forces``. ``total`` as there."""
    nx, ny = beta.shape
    solids = np.zeros((nx, ny))
    n = position.shape[0]
    cell = np.empty((n, 2), np.int64)
    for q in range(n):
        i = _cell(position[q, 0], dx, nx)
        j = _cell(position[q, 1], dy, ny)
        cell[q, 0] = i
        cell[q, 1] = j
        solids[i, j] += volume[q]
    idx, idy = 1.0 / dx, 1.0 / dy
    follow = total.shape[0] > 0
    for q in range(n):
        fx, fy = cell_force(position[q, 0], position[q, 1], volume[q], cell[q, 0], cell[q, 1], solids, beta, solids_u,
                            solids_v, u, v, p, idx, idy, cell_volume, px, py, pressure_force)
        store_force(out, total, q, fx, fy, 0.0, follow)
