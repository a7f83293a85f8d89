"""Compiled event-driven hard-sphere dynamics (Hoomans et al. 1996, §2.3–2.5, Fig. 3).

``advance`` runs many force steps DT in one call. Each step: every velocity gets
(g + F/m) DT (eqs 33–34), all of it before the collisions (Hoomans) or half before and
half after them (split, see ``hardsphere``); the binary collisions inside the step are
processed in time order with free flight in between (eq. 32), each by eqs 10–29.

Event scheme (all inside one step; nothing is predicted past its end):

* every particle keeps its own clock: its stored position is the one at that
  time; a collision moves only its two particles (delayed states), so one event
  costs O(log N), not O(N) as Hoomans' "move" routine;
* each particle has one predicted event (earliest of: a collision with a
  neighbour, eq. 30; a collision with a wall plane, eq. 31 for any plane; leaving
  its skin sphere), and a tournament tree over the particles orders them by it;
* a collision bumps both particles' collision counters; a predicted collision
  stores its partner's counter and is re-predicted when popped if that changed
  (lazy invalidation, as in Hoomans' "reset lists" but without scanning);
* the neighbour list is a full Verlet list with cut-off R_i + R_j + skin around
  reference positions; a particle leaving the sphere of radius skin/2 around its
  reference position is an event that rebuilds the list, so no pair can touch
  without being listed: no collision is ever missed. For the same reason a
  particle whose reference position is more than skin/2 (plus R) from every wall
  cannot touch a wall before its list is rebuilt, and its walls are not tested;
* round-off: an approaching pair at or below contact distance, or a particle at
  or behind a wall moving into it, collides at once (time 0), so no overlap grows;
* periodic box sides: the list is built by nearest image, and a pair's offset is
  x_i − x_j plus its image shift, −L round((x_ref,i − x_ref,j) / L) from the reference
  positions (``_image_shift``), in prediction and collision alike. Positions are
  wrapped into the box only at list rebuilds, so the shift holds until the next one.
  Without periodic sides the shift is never computed (a loop-invariant branch): the
  same numbers as before.

Inelastic collapse: the TC model (Luding & McNamara 1998, see
``contact/hard_sphere.py``) makes a collision elastic and frictionless when either
particle collided less than t_c before. A limit on events per step stops any
runaway that remains with a status code instead of a hang.

Speed (benchmarks/hardsphere_collisions.py, one core): the event loop ``_events`` is
compiled with ``_nrt=False`` (Numba's switch for reference counting) and its helpers
are inlined into it (``inline="always"``), so no event pays for calls or for the
atomic reference-count updates of array arguments; it allocates nothing, which is
what the switch requires, and returns to ``advance`` for a list rebuild. What a
prediction reads of a neighbour is one 64-byte row of a flat array (``P``: position,
velocity, clock, radius), indexed through unsigned integers so that no negative-index
wrap-around code is emitted. The neighbour tests are written without data-dependent
branches, and so is the queue (a tournament tree instead of a binary heap); planar
(2D) motion skips the z terms, which are exact zeros there, and particles away from
the walls skip the walls. The work arrays live in the engine between calls
(``workspace``), and a call leaves the state untouched when it fails, so the engine
keeps no copy. The results are those of the former engine (binary heap, branchy
predictions, 1.0–1.1e6 collisions/s on the settled bed) bit for bit; this one does
2.4–2.7e6/s there, and a step of the coupled hoomans-orifice case in 0.7 ms instead
of 1.4–1.8 ms.
"""
import math

import numpy as np
from numba import njit

from ._neighbours_kernels import _csr_of_pairs, build_pairs, build_pairs_periodic
from .contact.base import SLOT_FRICTION
from .contact.hard_sphere import NO_COLLISION, SLOT_COLLAPSE_TIME, SLOT_RESTITUTION, STICKING, impulse

# predicted-event codes in ev[:, 0]: >= 0 partner particle, then:
NO_EVENT = -1
SKIN_EVENT = -2
WALL_EVENT0 = -3  # wall w is coded WALL_EVENT0 - w

# counters (int64 array) slots
C_COLLISIONS, C_WALL_COLLISIONS, C_REMEDY, C_REBUILDS, C_EVENTS, C_STALE, C_STICKING, C_LOGGED = range(8)
N_COUNTERS = 8
# energy (float64 array) slots: dissipated by the normal (eq. 23) and tangential (eqs 27, 29) impulses [J]
E_NORMAL, E_TANGENTIAL = 0, 1
N_ENERGIES = 2
# status
OK, TOO_MANY_EVENTS = 0, 1

SKIN_MARGIN = 1.0 - 1e-9  # the skin event fires a hair before the displacement reaches skin/2

# P (8 N,) flat, particle i at P[8 i:8 i + 8], one 64-byte cache line: what predicting an event reads of a
# neighbour: position at the particle's own clock, velocity, clock, radius
P_X, P_Y, P_Z, P_VX, P_VY, P_VZ, P_T, P_R = range(8)
P_ROW = 8
# Q (N, 8): what a collision reads besides P: spin, 1/m, 1/I, absolute time of the last collision (TC model)
Q_WX, Q_WY, Q_WZ, Q_IM, Q_II, Q_LAST = range(6)
# R (4 N,) flat, particle i at R[4 i:4 i + 4]: reference position of the neighbour list (the centre of the skin
# sphere) and 1.0 where the particle may reach a wall before it leaves that sphere (see _set_reference), else 0.0
R_X, R_Y, R_Z, R_NEAR = range(4)
R_ROW = 4
# wall table rows (see _wall_table): inward normal, a point, event code (as a float)
W_NX, W_NY, W_NZ, W_PX, W_PY, W_PZ, W_CODE = range(7)
# why _events returns
EV_END, EV_SKIN, EV_LIMIT = 0, 1, 2


# ---------------------------------------------------------------- neighbour list
@njit(cache=True, error_model="numpy")
def build_neighbours(pos, radius, skin, dim2):
    """Full Verlet list (CSR, both directions) of all pairs closer than R_i + R_j + skin.

    Returns (start (N+1,) int64, neighbours (P,) int32), each row ascending. The pairs are those of the
    soft-sphere engine's search (``_neighbours_kernels.build_pairs``: each pair once, found cell run by
    cell run), entered in both directions and put in rows by the same stable counting sort: 210–220 µs a
    build on the hoomans-orifice bed (2400 spheres in one layer; the search 150 of them), against 380–390 µs
    for the former search here (each particle's 3^d cells in turn, every pair from both ends).
    """
    n = pos.shape[0]
    if n == 0:
        return np.zeros(1, dtype=np.int64), np.empty(0, dtype=np.int32)
    row_start, partner, _, _ = build_pairs(pos, radius, skin, dim2, np.int64(0))
    return _full_list(n, row_start, partner)


@njit(cache=True, error_model="numpy")
def build_neighbours_periodic(pos, radius, skin, dim2, period, box_lo):
    """``build_neighbours`` in a box with periodic sides: all pairs closer than R_i + R_j + skin between
    nearest images (``_neighbours_kernels.build_pairs_periodic``; positions inside the box on the periodic axes,
    lengths ``period`` (3,) [m], 0 on the others, lower corner ``box_lo``)."""
    n = pos.shape[0]
    if n == 0:
        return np.zeros(1, dtype=np.int64), np.empty(0, dtype=np.int32)
    row_start, partner, _, _ = build_pairs_periodic(pos, radius, skin, dim2, period, box_lo)
    return _full_list(n, row_start, partner)


@njit(cache=True, error_model="numpy")
def _full_list(n, row_start, partner):
    """The half list (CSR by owner) entered in both directions, rows ascending (a stable counting sort)."""
    m = partner.shape[0]
    both = np.empty((1, 2 * m), dtype=np.int64)
    k = 0
    for i in range(n):
        for p in range(row_start[i], row_start[i + 1]):
            j = np.int64(partner[p])
            both[0, k] = (np.int64(i) << 32) | j
            both[0, k + 1] = (j << 32) | i
            k += 2
    return _csr_of_pairs(n, both, np.full(1, 2 * m, dtype=np.int64))


@njit(cache=True, error_model="numpy")
def upper_half(start, nbr):
    """The entries j > i of each row i of a full neighbour list, in the row's order: (start (N+1,) uint64,
    neighbours uint32), what ``_predict_all`` walks (each pair once, without a data-dependent skip)."""
    n = start.shape[0] - 1
    up_start = np.zeros(n + 1, dtype=np.uint64)
    for i in range(n):
        k = 0
        for p in range(start[i], start[i + 1]):
            k += nbr[p] > i
        up_start[i + 1] = up_start[i] + k
    up = np.empty(up_start[n] + 1, dtype=np.uint32)  # + 1: the slot written after the last kept entry
    k = 0
    for i in range(n):
        for p in range(start[i], start[i + 1]):
            j = nbr[p]
            up[k] = j
            k += j > i
    return up_start, up[:k]


# ---------------------------------------------------------------- packed per-particle records
@njit(cache=True, error_model="numpy")
def set_forces(mass, gravity, ext_force, force, torque):
    """force = m g + ext_force (the finite forces of eq. 34), torque = 0 (none between collisions)."""
    for i in range(mass.shape[0]):
        for d in range(3):
            force[i, d] = mass[i] * gravity[d] + ext_force[i, d]
            torque[i, d] = 0.0


@njit(cache=True, error_model="numpy", _nrt=False, inline="always")
def _move(i, t, P):
    """Free flight of particle i up to time t (Hoomans eq. 32)."""
    o = P_ROW * i
    dt = t - P[o + P_T]
    P[o + P_X] += P[o + P_VX] * dt
    P[o + P_Y] += P[o + P_VY] * dt
    P[o + P_Z] += P[o + P_VZ] * dt
    P[o + P_T] = t


@njit(cache=True, error_model="numpy", _nrt=False, inline="always")
def _image_shift(ra, rb, length):
    """The image shift s = −L round((x_ref,a − x_ref,b) / L) [m] of a pair along an axis of period L > 0
    (0 for L = 0): from the reference positions of the neighbour list, so constant between list builds (no
    position is wrapped in between) and the nearest image of the build (Allen & Tildesley 1987 eq. 1.9).
    x_a − x_b + s is then the pair's offset whichever side of the seam either particle has reached."""
    return -length * math.floor((ra - rb) / length + 0.5) if length > 0.0 else 0.0


@njit(cache=True, error_model="numpy", _nrt=False, inline="always")
def _collide_pair(a, b, P, Q, e, mu, R, per, lx, ly, lz):
    """Apply the collision of particles a and b (both at the same time); returns (E_n, E_t, class).
    ``per``: a box with periodic sides of lengths (lx, ly, lz) [m] (0: not periodic), the offset then taken
    with the pair's image shift (``_image_shift``)."""
    oa = P_ROW * a
    ob = P_ROW * b
    rx = P[oa + P_X] - P[ob + P_X]
    ry = P[oa + P_Y] - P[ob + P_Y]
    rz = P[oa + P_Z] - P[ob + P_Z]
    if per:
        qa = R_ROW * a
        qb = R_ROW * b
        rx += _image_shift(R[qa + R_X], R[qb + R_X], lx)
        ry += _image_shift(R[qa + R_Y], R[qb + R_Y], ly)
        rz += _image_shift(R[qa + R_Z], R[qb + R_Z], lz)
    inv_r = 1.0 / math.sqrt(rx * rx + ry * ry + rz * rz)
    nx = rx * inv_r
    ny = ry * inv_r
    nz = rz * inv_r
    ra = P[oa + P_R]
    rb = P[ob + P_R]
    wx = ra * Q[a, Q_WX] + rb * Q[b, Q_WX]
    wy = ra * Q[a, Q_WY] + rb * Q[b, Q_WY]
    wz = ra * Q[a, Q_WZ] + rb * Q[b, Q_WZ]
    # contact-point velocity of a relative to b: v_a − v_b − (R_a ω_a + R_b ω_b) × n  (eqs 8–9, 11, 14)
    ux = P[oa + P_VX] - P[ob + P_VX] - (wy * nz - wz * ny)
    uy = P[oa + P_VY] - P[ob + P_VY] - (wz * nx - wx * nz)
    uz = P[oa + P_VZ] - P[ob + P_VZ] - (wx * ny - wy * nx)
    ima = Q[a, Q_IM]
    imb = Q[b, Q_IM]
    iia = Q[a, Q_II]
    iib = Q[b, Q_II]
    ka = ra * ra * iia
    kb = rb * rb * iib
    pn, ptx, pty, ptz, en, et, kind = impulse(nx, ny, nz, ux, uy, uz, ima, imb, ka, kb, e, mu)
    if kind == NO_COLLISION:
        return 0.0, 0.0, kind
    jx = pn * nx + ptx
    jy = pn * ny + pty
    jz = pn * nz + ptz
    P[oa + P_VX] += jx * ima  # eqs 1–2
    P[oa + P_VY] += jy * ima
    P[oa + P_VZ] += jz * ima
    P[ob + P_VX] -= jx * imb  # eqs 4–5
    P[ob + P_VY] -= jy * imb
    P[ob + P_VZ] -= jz * imb
    # n × P_t; the torques about the centres are −R_a n × P_t on a and −R_b n × P_t on b (eqs 3, 6)
    cx = ny * ptz - nz * pty
    cy = nz * ptx - nx * ptz
    cz = nx * pty - ny * ptx
    fa = -ra * iia
    fb = -rb * iib
    Q[a, Q_WX] += fa * cx
    Q[a, Q_WY] += fa * cy
    Q[a, Q_WZ] += fa * cz
    Q[b, Q_WX] += fb * cx
    Q[b, Q_WY] += fb * cy
    Q[b, Q_WZ] += fb * cz
    return en, et, kind


@njit(cache=True, error_model="numpy", _nrt=False, inline="always")
def _collide_wall(a, nx, ny, nz, P, Q, e, mu):
    """Collision of particle a with a static wall of inward normal n (infinite mass, Hoomans §2.3)."""
    oa = P_ROW * a
    ra = P[oa + P_R]
    wx = ra * Q[a, Q_WX]
    wy = ra * Q[a, Q_WY]
    wz = ra * Q[a, Q_WZ]
    ux = P[oa + P_VX] - (wy * nz - wz * ny)
    uy = P[oa + P_VY] - (wz * nx - wx * nz)
    uz = P[oa + P_VZ] - (wx * ny - wy * nx)
    ima = Q[a, Q_IM]
    iia = Q[a, Q_II]
    ka = ra * ra * iia
    pn, ptx, pty, ptz, en, et, kind = impulse(nx, ny, nz, ux, uy, uz, ima, 0.0, ka, 0.0, e, mu)
    if kind == NO_COLLISION:
        return 0.0, 0.0, kind
    P[oa + P_VX] += (pn * nx + ptx) * ima
    P[oa + P_VY] += (pn * ny + pty) * ima
    P[oa + P_VZ] += (pn * nz + ptz) * ima
    fa = -ra * iia
    Q[a, Q_WX] += fa * (ny * ptz - nz * pty)
    Q[a, Q_WY] += fa * (nz * ptx - nx * ptz)
    Q[a, Q_WZ] += fa * (nx * pty - ny * ptx)
    return en, et, kind


# ---------------------------------------------------------------- event queue: a tournament tree over the particles
# T (4L,), L a power of two >= N: node k is (T[2k], T[2k + 1]) = (time, particle index as a float). Leaf L + i
# holds particle i's event; each inner node the earlier of its two children, so the root (node 1) is the next
# event. Changing one particle's time rewrites the log2 L nodes on its leaf's path to the root, each the earlier
# of the path value and the sibling: compiled to a minimum and a masked move, without the data-dependent
# branches of a binary heap's sift (one badly predicted branch per level). On a tie the value coming up the
# path stays: the order of simultaneous events is a deterministic function of the history.
@njit(cache=True, error_model="numpy", _nrt=False, inline="always")
def _queue_set(i, key, T, L):
    k = L + i
    idx = T[2 * k + 1]
    T[2 * k] = key
    while k > 1:
        s = k ^ 1
        sk = T[2 * s]
        si = T[2 * s + 1]
        take = sk < key
        key = sk if take else key
        idx = si if take else idx
        k >>= 1
        T[2 * k] = key
        T[2 * k + 1] = idx


@njit(cache=True, error_model="numpy", _nrt=False)
def _queue_build(ev_time, T, L):
    n = ev_time.shape[0]
    for i in range(L):
        T[2 * (L + i)] = ev_time[i] if i < n else np.inf
        T[2 * (L + i) + 1] = i
    for k in range(L - 1, 0, -1):
        a = 2 * k
        if T[2 * a + 2] < T[2 * a]:
            a += 1
        T[2 * k] = T[2 * a]
        T[2 * k + 1] = T[2 * a + 1]


# ---------------------------------------------------------------- event prediction
# Neighbours: Hoomans eq. 30 in the cancellation-free form t_c = c / (−b + sqrt(b² − v² c)) with b = r·v,
# c = r² − σ², for the pairs that approach (b < 0, Hoomans after eq. 30); a pair at or inside contact distance
# (c <= 0) and approaching collides at once (the round-off guard), and a root can beat the best event only if
# c < −2b (best − t) (the root is at least c / (−2b)). Written without branches: every candidate's root is
# computed, then masked. Which neighbours approach is a coin toss in a dense bed, and the mispredicted branches
# cost more than the square roots and divisions they save. The partner index travels as a float so that every
# choice is a masked move of a float register. p0, p1 (uint64) and nbr (uint32) are unsigned: no wrap-around.
@njit(cache=True, error_model="numpy", _nrt=False, inline="always")
def _pair_time(rx, ry, rz, vx, vy, vz, sig, t, horizon):
    """Collision time of a pair at separation r = x_i − x_j, relative velocity v and contact distance σ
    (eq. 30 in the form above), or inf when the pair does not approach or its root lies beyond
    ``horizon`` (a time span; the pruning bound). Scalars only, no branches."""
    b = rx * vx + ry * vy + rz * vz
    c = rx * rx + ry * ry + rz * rz - sig * sig
    v2 = vx * vx + vy * vy + vz * vz
    disc = b * b - v2 * c
    root = c / (-b + math.sqrt(max(disc, 0.0)))
    hit = (b < 0.0) & ((c <= 0.0) | ((c < -2.0 * b * horizon) & (disc >= 0.0)))
    tc = t if c <= 0.0 else t + root
    return tc if hit else np.inf


@njit(cache=True, error_model="numpy", _nrt=False, inline="always")
def _scan(t, xi, yi, zi, vxi, vyi, vzi, ri, best, partf, P, p0, p1, nbr, sync, planar, R, i, per, lx, ly, lz):
    """Earliest collision of a particle at (x, v, R)_i with its neighbours nbr[p0:p1] if before ``best``:
    returns the new (best, partner as a float). ``sync``: every particle's clock is t, so the stored positions
    are those at t (the same numbers as moving them by zero). ``planar`` (see ``_load``): the z terms, all
    exactly zero then, are not read (the same numbers result). ``per``: periodic sides of lengths (lx, ly, lz),
    the offsets taken with each pair's image shift (``_image_shift``; i is the particle, R the reference rows)."""
    for p in range(p0, p1):
        j = nbr[p]
        o = P_ROW * j
        vxj = P[o + P_VX]
        vyj = P[o + P_VY]
        vx = vxi - vxj
        vy = vyi - vyj
        if sync:
            rx = xi - P[o + P_X]
            ry = yi - P[o + P_Y]
        else:
            dtj = t - P[o + P_T]
            rx = xi - (P[o + P_X] + vxj * dtj)
            ry = yi - (P[o + P_Y] + vyj * dtj)
        if planar:
            vz = 0.0
            rz = 0.0
        else:
            vzj = P[o + P_VZ]
            vz = vzi - vzj
            rz = zi - P[o + P_Z] if sync else zi - (P[o + P_Z] + vzj * (t - P[o + P_T]))
        if per:
            qi = R_ROW * i
            qj = R_ROW * j
            rx += _image_shift(R[qi + R_X], R[qj + R_X], lx)
            ry += _image_shift(R[qi + R_Y], R[qj + R_Y], ly)
            if not planar:
                rz += _image_shift(R[qi + R_Z], R[qj + R_Z], lz)
        tc = _pair_time(rx, ry, rz, vx, vy, vz, ri + P[o + P_R], t, best - t)
        better = tc < best
        best = tc if better else best
        partf = float(j) if better else partf
    return best, partf


@njit(cache=True, error_model="numpy", _nrt=False, inline="always")
def _wall_event(i, t, xi, yi, zi, vxi, vyi, vzi, ri, best, partf, walls, R):
    """Earliest wall collision of particle i (Hoomans eq. 31) before ``best``: (best, code as a float).

    Any plane, gap h = (x − p)·n − R closed at speed −v·n. Only for a particle near a wall: the others
    leave their skin sphere (an earlier event) before they can touch one."""
    if R[R_ROW * i + R_NEAR] != 0.0:
        for w in range(walls.shape[0]):
            nx = walls[w, W_NX]
            ny = walls[w, W_NY]
            nz = walls[w, W_NZ]
            vn = vxi * nx + vyi * ny + vzi * nz
            if vn < 0.0:
                h = (xi - walls[w, W_PX]) * nx + (yi - walls[w, W_PY]) * ny + (zi - walls[w, W_PZ]) * nz - ri
                tw = t if h <= 0.0 else t + h / -vn  # at or behind the wall: collide now (round-off guard)
                if tw < best:
                    best = tw
                    partf = walls[w, W_CODE]
    return best, partf


@njit(cache=True, error_model="numpy", _nrt=False, inline="always")
def _finish_event(i, t, xi, yi, zi, vxi, vyi, vzi, best, partf, R, half_skin, ncoll, ev):
    """The skin event (leaving the skin sphere |x − x_ref| = skin/2 invalidates the neighbour list) if it
    comes before ``best``; stores (partner, its collision counter) in ev[i]; returns the time (inf: none)."""
    part = int(partf)
    cnt = ncoll[part] if part >= 0 else 0
    dx = xi - R[R_ROW * i + R_X]
    dy = yi - R[R_ROW * i + R_Y]
    dz = zi - R[R_ROW * i + R_Z]
    v2 = vxi * vxi + vyi * vyi + vzi * vzi
    d2 = dx * dx + dy * dy + dz * dz
    span = best - t
    q2 = 0.25 * half_skin * half_skin
    if v2 > 0.0 and not (d2 <= q2 and v2 * span * span <= q2):  # else |d| + |v| span <= skin/2: no event
        c = d2 - half_skin * half_skin
        if c >= 0.0:
            ts = t
        else:
            b = dx * vxi + dy * vyi + dz * vzi
            ts = t + (-b + math.sqrt(b * b - v2 * c)) / v2
        if ts < best:
            best = ts
            part = SKIN_EVENT
    if part == NO_EVENT:
        best = np.inf
    ev[i, 0] = part
    ev[i, 1] = cnt
    return best


@njit(cache=True, error_model="numpy", _nrt=False, inline="always")
def _predict(i, t, t_end, P, nbr_start, nbr, walls, R, half_skin, ncoll, ev, planar, sync, per, lx, ly, lz):
    """Earliest event of particle i (uint32) after time t and before t_end (else none): stores (partner, its
    collision counter) in ev[i] and returns the time (inf for none). ``planar``: see ``_load``; ``sync``
    (a constant): every particle's clock is t."""
    o = P_ROW * i
    vxi = P[o + P_VX]
    vyi = P[o + P_VY]
    vzi = P[o + P_VZ]
    if sync:
        xi = P[o + P_X]
        yi = P[o + P_Y]
        zi = P[o + P_Z]
    else:
        dti = t - P[o + P_T]
        xi = P[o + P_X] + vxi * dti  # eq. 32 up to time t
        yi = P[o + P_Y] + vyi * dti
        zi = P[o + P_Z] + vzi * dti
    ri = P[o + P_R]
    best, partf = _wall_event(i, t, xi, yi, zi, vxi, vyi, vzi, ri, t_end, float(NO_EVENT), walls, R)
    # neighbours: Hoomans eq. 30
    best, partf = _scan(t, xi, yi, zi, vxi, vyi, vzi, ri, best, partf, P, nbr_start[i], nbr_start[i + 1], nbr,
                        sync, planar, R, i, per, lx, ly, lz)
    return _finish_event(i, t, xi, yi, zi, vxi, vyi, vzi, best, partf, R, half_skin, ncoll, ev)


@njit(cache=True, error_model="numpy", _nrt=False)
def _predict_all(t, t_end, P, up_start, up, walls, R, half_skin, ncoll, ev, ev_time, T, L, planar, partf, per, lx, ly,
                 lz):
    """Events of all particles, all with their clocks at t (the start of a step or a list rebuild).

    Each pair is solved once, from its lower index (``up_start, up``: the upper half of the neighbour list,
    ``upper_half``), and offered to both particles: eq. 30 gives the same time for (i, j) and (j, i) (r and v
    only change sign). The pruning bound of ``_scan`` is the step's end here, as the partner's best is not
    known yet. ``partf`` (N,): scratch. Equal times go to the first offer: walls, then the partners in the
    order the pairs are met.

    Unlike ``_scan``, this loop branches on the cheap test that a root may lie inside the step, and solves
    eq. 30 only then: at the start of a step the pairs that collide before its end are few and the branch
    is well predicted (hoomans-orifice jet: about 420 collisions per step among 6,200 listed pairs)."""
    n = ev_time.shape[0]
    for i in range(n):
        o = P_ROW * i
        best, pf = _wall_event(i, t, P[o + P_X], P[o + P_Y], P[o + P_Z], P[o + P_VX], P[o + P_VY], P[o + P_VZ],
                               P[o + P_R], t_end, float(NO_EVENT), walls, R)
        ev_time[i] = best
        partf[i] = pf
    for i in range(n):
        o = P_ROW * i
        xi = P[o + P_X]
        yi = P[o + P_Y]
        zi = P[o + P_Z]
        vxi = P[o + P_VX]
        vyi = P[o + P_VY]
        vzi = P[o + P_VZ]
        ri = P[o + P_R]
        best = ev_time[i]
        pf = partf[i]
        fi = float(i)
        span = t_end - t
        for p in range(up_start[i], up_start[i + 1]):
            j = up[p]
            q = P_ROW * j
            vx = vxi - P[q + P_VX]
            vy = vyi - P[q + P_VY]
            rx = xi - P[q + P_X]
            ry = yi - P[q + P_Y]
            if planar:
                vz = 0.0
                rz = 0.0
            else:
                vz = vzi - P[q + P_VZ]
                rz = zi - P[q + P_Z]
            if per:  # the pair's image shift (_image_shift)
                qi = R_ROW * i
                qj = R_ROW * j
                rx += _image_shift(R[qi + R_X], R[qj + R_X], lx)
                ry += _image_shift(R[qi + R_Y], R[qj + R_Y], ly)
                if not planar:
                    rz += _image_shift(R[qi + R_Z], R[qj + R_Z], lz)
            b = rx * vx + ry * vy + rz * vz
            sig = ri + P[q + P_R]
            c = rx * rx + ry * ry + rz * rz - sig * sig
            if (b < 0.0) & ((c <= 0.0) | (c < -2.0 * b * span)):  # else no root inside the step (_pair_time)
                tc = _pair_time(rx, ry, rz, vx, vy, vz, sig, t, span)
                if tc < best:
                    best = tc
                    pf = float(j)
                if tc < ev_time[j]:
                    ev_time[j] = tc
                    partf[j] = fi
        ev_time[i] = best
        partf[i] = pf
    for i in range(n):
        o = P_ROW * i
        ev_time[i] = _finish_event(i, t, P[o + P_X], P[o + P_Y], P[o + P_Z], P[o + P_VX], P[o + P_VY], P[o + P_VZ],
                                   ev_time[i], partf[i], R, half_skin, ncoll, ev)
    _queue_build(ev_time, T, L)


# ---------------------------------------------------------------- set-up helpers
@njit(cache=True, error_model="numpy", _nrt=False)
def _load(pos, vel, omega, radius, inv_mass, inv_inertia, last_coll, wall_normal, dim2, P, Q, ncoll):
    """Fill P, Q and ncoll from the state and return ``planar``.

    planar: the motion stays exactly in the plane z = const, in a 2D case with all particles at the same z,
    no z velocity, spins along z only, and every wall normal either in the plane or along z. Pair and wall
    impulses then have no z component and change the spin about z only (eqs 1–6), so this holds for the whole
    call: the z terms of eq. 30 are exact zeros, and walls along z are never hit (v·n = 0).
    """
    n = pos.shape[0]
    nw = wall_normal.shape[0]
    planar = dim2
    for w in range(nw):
        if wall_normal[w, 2] != 0.0 and (wall_normal[w, 0] != 0.0 or wall_normal[w, 1] != 0.0):
            planar = False
    z0 = pos[0, 2] if n > 0 else 0.0
    for i in range(n):
        o = P_ROW * i
        P[o + P_X] = pos[i, 0]
        P[o + P_Y] = pos[i, 1]
        P[o + P_Z] = pos[i, 2]
        P[o + P_VX] = vel[i, 0]
        P[o + P_VY] = vel[i, 1]
        P[o + P_VZ] = vel[i, 2]
        P[o + P_T] = 0.0
        P[o + P_R] = radius[i]
        Q[i, Q_WX] = omega[i, 0]
        Q[i, Q_WY] = omega[i, 1]
        Q[i, Q_WZ] = omega[i, 2]
        Q[i, Q_IM] = inv_mass[i]
        Q[i, Q_II] = inv_inertia[i]
        Q[i, Q_LAST] = last_coll[i]
        ncoll[i] = 0
    if planar:
        off = 0
        for i in range(n):
            off += (pos[i, 2] != z0) | (vel[i, 2] != 0.0) | (omega[i, 0] != 0.0) | (omega[i, 1] != 0.0)
        planar = off == 0
    return planar


@njit(cache=True, error_model="numpy")
def _wall_table(wall_point, wall_normal, planar):
    """(W', 7) rows (normal, point, event code as a float) of the walls a particle can hit: all of them, or for
    planar motion (see ``_load``) those with a normal in the plane (v·n = 0 for the others)."""
    nw = wall_normal.shape[0]
    keep = 0
    for w in range(nw):
        if not (planar and wall_normal[w, 0] == 0.0 and wall_normal[w, 1] == 0.0):
            keep += 1
    walls = np.empty((keep, 7))
    k = 0
    for w in range(nw):
        if not (planar and wall_normal[w, 0] == 0.0 and wall_normal[w, 1] == 0.0):
            for d in range(3):
                walls[k, W_NX + d] = wall_normal[w, d]
                walls[k, W_PX + d] = wall_point[w, d]
            walls[k, W_CODE] = WALL_EVENT0 - w
            k += 1
    return walls


@njit(cache=True, error_model="numpy", _nrt=False)
def _set_reference(ref, radius, walls, skin, R, near):
    """R (see R_X) from the reference positions ``ref`` (N, 3): a particle stays within skin/2 of its reference
    position until its skin event, so it can touch a wall before then only if its reference gap
    (x_ref − p)·n − R to that wall is at most skin/2 (with a relative margin of 1e-6 that round-off cannot
    bridge). ``near`` (N,): scratch."""
    reach = 0.5 * skin * (1.0 + 1e-6)
    n = ref.shape[0]
    for i in range(n):
        R[R_ROW * i + R_X] = ref[i, 0]
        R[R_ROW * i + R_Y] = ref[i, 1]
        R[R_ROW * i + R_Z] = ref[i, 2]
        near[i] = 0.0
    for w in range(walls.shape[0]):
        nx = walls[w, W_NX]
        ny = walls[w, W_NY]
        nz = walls[w, W_NZ]
        px = walls[w, W_PX]
        py = walls[w, W_PY]
        pz = walls[w, W_PZ]
        for i in range(n):
            gap = ((R[R_ROW * i + R_X] - px) * nx + (R[R_ROW * i + R_Y] - py) * ny + (R[R_ROW * i + R_Z] - pz) * nz
                   - radius[i])
            near[i] = max(near[i], 0.0 if gap > reach else 1.0)  # (a NaN counts as near)
    for i in range(n):
        R[R_ROW * i + R_NEAR] = near[i]


@njit(cache=True, error_model="numpy", _nrt=False, inline="always")
def _book(i, j, code, tabs, en, et, kind, remedy, Q, ncoll, counters, energy, log):
    """Counters, dissipated energy, TC clocks and the optional log after a collision of i with j (or wall code)."""
    Q[i, Q_LAST] = tabs
    ncoll[i] += 1
    if j >= 0:
        Q[j, Q_LAST] = tabs
        ncoll[j] += 1
    else:
        counters[C_WALL_COLLISIONS] += 1
    counters[C_COLLISIONS] += 1
    if kind == STICKING:
        counters[C_STICKING] += 1
    if remedy:
        counters[C_REMEDY] += 1
    energy[E_NORMAL] += en
    energy[E_TANGENTIAL] += et
    k = counters[C_LOGGED]
    if k < log.shape[0]:
        log[k, 0] = tabs
        log[k, 1] = i
        log[k, 2] = code
        log[k, 3] = en
        log[k, 4] = et
        counters[C_LOGGED] += 1


# ---------------------------------------------------------------- the step loop
@njit(cache=True, error_model="numpy", _nrt=False)
def _events(t_abs0, dt, P, Q, species, pp, pw, walls, wall_normal, nbr_start, nbr, R, half_skin, ncoll, ev, T, L,
            planar, events, max_events, counters, energy, log, per, lx, ly, lz):
    """Process the events of one step in time order until the step ends, a particle leaves its skin sphere
    or the event limit is passed; returns (reason, time of the last event, events so far in the step).

    Compiled without reference counting, with its helpers inlined: nothing here allocates.
    """
    while L > 0:
        t = T[2]
        if not t < dt:  # the next event lies beyond the step (or there is none)
            return EV_END, t, events
        i = np.uint32(T[3])
        events += 1
        if events > max_events:
            return EV_LIMIT, t, events
        p = ev[i, 0]
        if p == SKIN_EVENT:  # a particle reached skin/2 from its reference position: the caller rebuilds
            return EV_SKIN, t, events
        j = i  # the other particle whose velocity changes, i if none
        if p >= 0 and ncoll[p] != ev[i, 1]:  # the partner collided since the prediction: predict again
            counters[C_STALE] += 1
        else:
            tabs = t_abs0 + t
            _move(i, t, P)
            si = species[i]
            if p >= 0:
                j = np.uint32(p)
                w = 0
                _move(j, t, P)
                sj = species[j]
                tcol = pp[si, sj, SLOT_COLLAPSE_TIME]
                e = pp[si, sj, SLOT_RESTITUTION]
                mu = pp[si, sj, SLOT_FRICTION]
                remedy = tabs - Q[i, Q_LAST] < tcol or tabs - Q[j, Q_LAST] < tcol
            else:
                w = WALL_EVENT0 - p
                tcol = pw[si, w, SLOT_COLLAPSE_TIME]
                e = pw[si, w, SLOT_RESTITUTION]
                mu = pw[si, w, SLOT_FRICTION]
                remedy = tabs - Q[i, Q_LAST] < tcol
            if remedy and (e < 1.0 or mu > 0.0):
                e = 1.0  # TC model (Luding & McNamara 1998): elastic and frictionless
                mu = 0.0
            else:
                remedy = False
            if p >= 0:
                en, et, kind = _collide_pair(i, j, P, Q, e, mu, R, per, lx, ly, lz)
            else:
                en, et, kind = _collide_wall(i, wall_normal[w, 0], wall_normal[w, 1], wall_normal[w, 2], P, Q, e, mu)
            if kind != NO_COLLISION:
                _book(i, p, p, tabs, en, et, kind, remedy, Q, ncoll, counters, energy, log)
        # new predictions for i, then j ("reset lists" of Fig. 3); one call site, so one inlined copy
        k = i
        while True:
            _queue_set(k, _predict(k, t, dt, P, nbr_start, nbr, walls, R, half_skin, ncoll, ev, planar, False, per,
                                   lx, ly, lz), T, L)
            if k == j:
                break
            k = j
    return EV_END, dt, events


@njit(cache=True, error_model="numpy", _nrt=False)
def _wrap(k, P, period, box_lo, image_step):
    """Particle k back into the box along each periodic axis d (L_d = ``period[d]`` > 0): x_d ← x_d − m L_d with
    m = floor((x_d − lo_d) / L_d), image_step[k, d] += m (as ``_softsphere_kernels.wrap_positions``)."""
    for d in range(3):
        length = period[d]
        if length > 0.0:
            x = P[P_ROW * k + P_X + d]
            lo = box_lo[d]
            if x >= lo + length or x < lo:
                m = math.floor((x - lo) / length)
                P[P_ROW * k + P_X + d] = x - m * length
                image_step[k, d] += np.int64(m)


@njit(cache=True, error_model="numpy", _nrt=False)
def _kick(n, P, Q, gx, gy, gz, ext_force, h, dim2):
    """v += (g + F/m) h for every particle (Hoomans eqs 33–34 with the impulse of a time h [s]); 2D: no z."""
    for i in range(n):
        o = P_ROW * i
        im = Q[i, Q_IM]
        P[o + P_VX] += (gx + ext_force[i, 0] * im) * h
        P[o + P_VY] += (gy + ext_force[i, 1] * im) * h
        if not dim2:
            P[o + P_VZ] += (gz + ext_force[i, 2] * im) * h


@njit(cache=True, error_model="numpy")
def advance(pos, vel, omega, radius, inv_mass, inv_inertia, species, pp, pw, wall_point, wall_normal, gravity,
            ext_force, dim2, nbr_start, nbr, up_start, up, ref_pos, skin, last_coll, step0, dt, nsteps, max_events,
            counters, energy, log, info, work, split, period, box_lo, image_step):
    """Run ``nsteps`` force steps of length ``dt`` (Hoomans 1996 Fig. 3 per step).

    ``split`` False: Hoomans' force step, v += (g + F/m) DT (eqs 33–34), then the collisions of the step in
    time order with straight flight between them (eqs 30–32). ``split`` True: the same collision sequence
    between two half kicks, v += (g + F/m) DT/2 before it and after it (a kick–drift–kick, Strang splitting
    of the external force from the collisions): free fall is then exact and the step time-reversible.

    Parameters
    ----------
    pos, vel, omega : (N, 3) float64 [m, m/s, rad/s]
    radius, inv_mass, inv_inertia : (N,) float64 [m, 1/kg, 1/(kg m²)]
    species : (N,) int64; pp : (S, S, 8), pw : (S, W, 8) packed hard-sphere rows
    wall_point, wall_normal : (W, 3) static wall planes (inward normals)
    gravity : (3,) [m/s²]; ext_force : (N, 3) [N], constant over a step (the gas force)
    nbr_start, nbr : full neighbour list of ``ref_pos`` (N, 3) with cut-off R_i + R_j + skin
    up_start, up : its upper half, ``upper_half(nbr_start, nbr)``
    last_coll : (N,) absolute time of each particle's last collision [s] (TC model)
    step0 : index of the first step (absolute time of step s is (step0 + s) dt)
    max_events : events per step after which the call stops with status TOO_MANY_EVENTS
    counters : (N_COUNTERS,) int64, energy : (N_ENERGIES,) float64, cumulative
    log : (L, 5) float64; the first L collisions after counters[C_LOGGED] = 0 are recorded as
        (absolute time, a, b or WALL_EVENT0 − w, E_n, E_t)
    info : (3,) float64, on failure (step index, time in step, events)
    work : ``hardsphere.workspace(N)``
    split : bool, the split force step (above) instead of Hoomans'
    period : (3,) box length along each periodic axis [m], 0 along the others; box_lo (3,) its lower corner.
        Pairs meet across a periodic side by their image shift (``_image_shift``). Positions are wrapped into
        the box at each list rebuild only (x ← x − k L, ``_wrap``), so between rebuilds a particle is outside
        the box by at most skin/2, and each rebuild adds k to ``image_step`` (N, 3) int64 (the caller adds it
        to the image counts when the call succeeds). None: no periodic side (Numba then compiles no
        periodic list build: an ``arg is None`` test is decided from the argument's type)

    Returns (nbr_start, nbr, up_start, up, status); status OK or TOO_MANY_EVENTS. On OK, pos, vel, omega,
    ref_pos and last_coll hold the new state; on TOO_MANY_EVENTS they are left as they were
    (counters, energy and the returned lists are then mid-step: the caller keeps its copies).
    """
    P, Q, R, ev, ev_time, ncoll, T, X, F, M = work
    n = pos.shape[0]
    L = T.shape[0] // 4
    planar = _load(pos, vel, omega, radius, inv_mass, inv_inertia, last_coll, wall_normal, dim2, P, Q, ncoll)
    walls = _wall_table(wall_point, wall_normal, planar)
    if not (M[0] == 1 and M[1] == planar):  # else R is that of ref_pos already (see workspace)
        _set_reference(ref_pos, radius, walls, skin, R, ev_time)
    M[0] = 0  # R may change below; valid again once the state is written back
    half_skin = 0.5 * skin * SKIN_MARGIN
    gx = gravity[0]
    gy = gravity[1]
    gz = gravity[2]
    status = OK
    rebuilt = False
    # unsigned views of the neighbour list (the same bits: all entries are >= 0)
    nbr_start_u = nbr_start.view(np.uint64)
    nbr_u = nbr.view(np.uint32)
    kick = 0.5 * dt if split else dt  # the force impulse before the collisions, per unit acceleration
    if period is None:  # decided when compiled (see ``period`` above)
        lx = ly = lz = 0.0
    else:
        lx = period[0]
        ly = period[1]
        lz = period[2]
    per = lx > 0.0 or ly > 0.0 or lz > 0.0
    for s in range(nsteps):
        t_abs0 = (step0 + s) * dt
        # force step: v = v* + (g + F/m) DT before the collisions (Hoomans eqs 33–34), or its first half (split)
        _kick(n, P, Q, gx, gy, gz, ext_force, kick, dim2)
        for i in range(n):
            P[P_ROW * i + P_T] = 0.0
        _predict_all(0.0, dt, P, up_start, up, walls, R, half_skin, ncoll, ev, ev_time, T, L, planar, F, per, lx,
                     ly, lz)
        events = np.int64(0)
        t = 0.0
        while n > 0:
            reason, t, events = _events(t_abs0, dt, P, Q, species, pp, pw, walls, wall_normal, nbr_start_u, nbr_u, R,
                                        half_skin, ncoll, ev, T, L, planar, events, max_events, counters, energy, log, per,
                                        lx, ly, lz)
            if reason != EV_SKIN:
                break
            # a particle reached skin/2 from its reference position: all to time t, new list around X
            for k in range(n):
                _move(k, t, P)
                if period is not None:
                    if per:
                        _wrap(k, P, period, box_lo, image_step)
                X[k, 0] = P[P_ROW * k + P_X]
                X[k, 1] = P[P_ROW * k + P_Y]
                X[k, 2] = P[P_ROW * k + P_Z]
            if period is None:
                nbr_start, nbr = build_neighbours(X, radius, skin, dim2)
            elif per:
                nbr_start, nbr = build_neighbours_periodic(X, radius, skin, dim2, period, box_lo)
            else:
                nbr_start, nbr = build_neighbours(X, radius, skin, dim2)
            nbr_start_u = nbr_start.view(np.uint64)
            nbr_u = nbr.view(np.uint32)
            up_start, up = upper_half(nbr_start, nbr)
            _set_reference(X, radius, walls, skin, R, ev_time)
            counters[C_REBUILDS] += 1
            rebuilt = True
            _predict_all(t, dt, P, up_start, up, walls, R, half_skin, ncoll, ev, ev_time, T, L, planar, F, per, lx, ly,
                         lz)
        counters[C_EVENTS] += events
        if reason == EV_LIMIT:
            info[0] = s
            info[1] = t
            info[2] = events
            return nbr_start, nbr, up_start, up, TOO_MANY_EVENTS
        for i in range(n):  # free flight to the end of the step
            _move(i, dt, P)
        if split:  # the second half of the force impulse, after the collisions
            _kick(n, P, Q, gx, gy, gz, ext_force, kick, dim2)
    for i in range(n):
        o = P_ROW * i
        pos[i, 0] = P[o + P_X]
        pos[i, 1] = P[o + P_Y]
        pos[i, 2] = P[o + P_Z]
        vel[i, 0] = P[o + P_VX]
        vel[i, 1] = P[o + P_VY]
        vel[i, 2] = P[o + P_VZ]
        omega[i, 0] = Q[i, Q_WX]
        omega[i, 1] = Q[i, Q_WY]
        omega[i, 2] = Q[i, Q_WZ]
        last_coll[i] = Q[i, Q_LAST]
    if rebuilt:
        for i in range(n):
            ref_pos[i, 0] = R[R_ROW * i + R_X]
            ref_pos[i, 1] = R[R_ROW * i + R_Y]
            ref_pos[i, 2] = R[R_ROW * i + R_Z]
    M[0] = 1
    M[1] = planar
    return nbr_start, nbr, up_start, up, status
