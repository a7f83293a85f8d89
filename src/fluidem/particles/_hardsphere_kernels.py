"""Compiled event-driven hard-sphere dynamics (Hoomans et al. 1996, §2.3–2.5, Fig. 3).

``advance`` runs many force steps DT in one call. Each step: every velocity gets
(g + F/m) DT (eqs 33–34); then the binary collisions inside the step are processed
in time order with free flight in between (eq. 32), each by eqs 10–29.

Event scheme (all inside one step; nothing is predicted past its end):

* every particle keeps its own clock ``t_loc``: its stored position is the one at
  that time; a collision moves only its two particles (delayed states), so one
  event costs O(log N), not O(N) as Hoomans' "move" routine;
* each particle has one predicted event (earliest of: a collision with a
  neighbour, eq. 30; a collision with a wall plane, eq. 31 for any plane; leaving
  its skin sphere) and a binary min-heap orders the particles by it;
* a collision bumps both particles' collision counters; a predicted collision
  stores its partner's counter and is re-predicted when popped if that changed
  (lazy invalidation, as in Hoomans' "reset lists" but without scanning);
* the neighbour list is a full Verlet list with cut-off R_i + R_j + skin around
  reference positions; a particle leaving the sphere of radius skin/2 around its
  reference position is an event that rebuilds the list, so no pair can touch
  without being listed: no collision is ever missed;
* round-off: an approaching pair at or below contact distance, or a particle at
  or behind a wall moving into it, collides at once (time 0), so no overlap grows.

Inelastic collapse: the TC model (Luding & McNamara 1998, see
``contact/hard_sphere.py``) makes a collision elastic and frictionless when either
particle collided less than t_c before. A limit on events per step stops any
runaway that remains with a status code instead of a hang.

Speed: the helpers called for every event take no arrays they could keep, so they are
compiled with ``_nrt=False`` (Numba's switch for reference counting). Otherwise every
call increments and decrements the count of each array argument, atomically. Those
atomic operations took 30 % of the time, and the settled 2400-sphere bed ran at
0.7 million collisions per second instead of 1.2 million (one core of this machine).
Nothing in those helpers allocates, and that is what the switch requires.
"""
import math

import numpy as np
from numba import njit

from ._neighbours_kernels import _bin, _cell_grid

# predicted-event codes in ev_part: >= 0 partner particle, then:
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
# collision classes
NO_COLLISION, SLIDING, STICKING = 0, 1, 2

# packed contact rows (contact/hard_sphere.py)
SLOT_RESTITUTION, SLOT_COLLAPSE_TIME, SLOT_FRICTION = 1, 2, 7

SKIN_MARGIN = 1.0 - 1e-9  # the skin event fires a hair before the displacement reaches skin/2


# ---------------------------------------------------------------- neighbour list
@njit(cache=True, error_model="numpy")
def build_neighbours(pos, radius, skin, dim2):
    """Full Verlet list (CSR, both directions) of all pairs closer than R_i + R_j + skin.

    Returns (start (N+1,) int64, neighbours (P,) int32). Cell binning with cells at
    least 2 R_max + skin wide, so only the 3^d surrounding cells are searched.
    """
    n = pos.shape[0]
    start = np.zeros(n + 1, dtype=np.int64)
    if n == 0:
        return start, np.empty(0, dtype=np.int32)
    lo, inv, ncell = _cell_grid(pos, radius, skin, dim2)  # cells >= 2 R_max + skin, as the soft engine's
    cell, cstart, members = _bin(pos, lo, inv, ncell)
    nbr = np.empty(0, dtype=np.int32)
    for phase in range(2):  # 0: count, 1: write
        for i in range(n):
            c = cell[i]
            cz = c % ncell[2]
            cy = (c // ncell[2]) % ncell[1]
            cx = c // (ncell[2] * ncell[1])
            k = 0
            for x in range(max(cx - 1, 0), min(cx + 2, ncell[0])):
                for y in range(max(cy - 1, 0), min(cy + 2, ncell[1])):
                    for z in range(max(cz - 1, 0), min(cz + 2, ncell[2])):
                        cc = (x * ncell[1] + y) * ncell[2] + z
                        for m in range(cstart[cc], cstart[cc + 1]):
                            j = members[m]
                            if j == i:
                                continue
                            rx = pos[i, 0] - pos[j, 0]
                            ry = pos[i, 1] - pos[j, 1]
                            rz = pos[i, 2] - pos[j, 2]
                            cut = radius[i] + radius[j] + skin
                            if rx * rx + ry * ry + rz * rz < cut * cut:
                                if phase == 1:
                                    nbr[start[i] + k] = j
                                k += 1
            if phase == 0:
                start[i + 1] = k
        if phase == 0:
            for i in range(n):
                start[i + 1] += start[i]
            nbr = np.empty(start[n], dtype=np.int32)
    return start, nbr


# ---------------------------------------------------------------- collision law
@njit(cache=True, error_model="numpy", _nrt=False)
def impulse(nx, ny, nz, ux, uy, uz, inv_ma, inv_mb, ka, kb, e, mu):
    """Impulse on body a of a binary collision (Hoomans 1996 eqs 10–29, slip as a vector).

    n : unit normal from b to a; u : velocity of a's contact point relative to b's
    (u·n < 0 approaching); inv_m : 1/m [1/kg] (0 for a wall); k = R²/I [1/kg] (0 for a wall).

    Returns (P_n, P_t (3), E_n, E_t, kind): normal impulse magnitude along n [N s],
    tangential impulse on a [N s], energy dissipated by each part [J], and the class:
    SLIDING (eq. 24), STICKING (eq. 25) or NO_COLLISION when u·n >= 0.
    """
    c0 = ux * nx + uy * ny + uz * nz  # compression velocity C_0, eq. 14 (spin adds nothing along n)
    if c0 >= 0.0:  # not approaching (round-off after the prediction): no impulse
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, NO_COLLISION
    sx = ux - c0 * nx  # initial slip S_0, eq. 11 as a vector in the tangent plane
    sy = uy - c0 * ny
    sz = uz - c0 * nz
    b2 = inv_ma + inv_mb  # eq. 15
    b1 = b2 + ka + kb  # eq. 12
    pn = -(1.0 + e) * c0 / b2  # eq. 22
    en = c0 * c0 / (2.0 * b2) * (1.0 - e * e)  # eq. 23
    s = math.sqrt(sx * sx + sy * sy + sz * sz)
    if s >= mu * b1 * pn:  # sliding, eq. 24
        if s > 0.0:
            f = -mu * pn / s  # eq. 26: P_t = −μ P_n ŝ
            ptx = f * sx
            pty = f * sy
            ptz = f * sz
        else:
            ptx = 0.0
            pty = 0.0
            ptz = 0.0
        et = -mu * (1.0 + e) * c0 / b2 * (s + mu * b1 * (1.0 + e) * c0 / (2.0 * b2))  # eq. 27
        return pn, ptx, pty, ptz, en, et, SLIDING
    # sticking, eq. 25: the slip ends at zero
    ptx = -sx / b1  # eq. 28
    pty = -sy / b1
    ptz = -sz / b1
    et = s * s / (2.0 * b1)  # eq. 29
    return pn, ptx, pty, ptz, en, et, STICKING


@njit(cache=True, error_model="numpy", _nrt=False)
def collide_pair(a, b, pos, vel, omega, radius, inv_mass, inv_inertia, e, mu):
    """Apply the collision of particles a and b (both at the same time); returns (E_n, E_t, class)."""
    rx = pos[a, 0] - pos[b, 0]
    ry = pos[a, 1] - pos[b, 1]
    rz = pos[a, 2] - pos[b, 2]
    inv_r = 1.0 / math.sqrt(rx * rx + ry * ry + rz * rz)
    nx = rx * inv_r
    ny = ry * inv_r
    nz = rz * inv_r
    ra = radius[a]
    rb = radius[b]
    wx = ra * omega[a, 0] + rb * omega[b, 0]
    wy = ra * omega[a, 1] + rb * omega[b, 1]
    wz = ra * omega[a, 2] + rb * omega[b, 2]
    # contact-point velocity of a relative to b: v_a − v_b − (R_a ω_a + R_b ω_b) × n  (eqs 8–9, 11, 14)
    ux = vel[a, 0] - vel[b, 0] - (wy * nz - wz * ny)
    uy = vel[a, 1] - vel[b, 1] - (wz * nx - wx * nz)
    uz = vel[a, 2] - vel[b, 2] - (wx * ny - wy * nx)
    ima = inv_mass[a]
    imb = inv_mass[b]
    ka = ra * ra * inv_inertia[a]
    kb = rb * rb * inv_inertia[b]
    pn, ptx, pty, ptz, en, et, kind = impulse(nx, ny, nz, ux, uy, uz, ima, imb, ka, kb, e, mu)
    if kind == NO_COLLISION:
        return 0.0, 0.0, kind
    jx = pn * nx + ptx
    jy = pn * ny + pty
    jz = pn * nz + ptz
    vel[a, 0] += jx * ima  # eqs 1–2
    vel[a, 1] += jy * ima
    vel[a, 2] += jz * ima
    vel[b, 0] -= jx * imb  # eqs 4–5
    vel[b, 1] -= jy * imb
    vel[b, 2] -= jz * imb
    # n × P_t; the torques about the centres are −R_a n × P_t on a and −R_b n × P_t on b (eqs 3, 6)
    cx = ny * ptz - nz * pty
    cy = nz * ptx - nx * ptz
    cz = nx * pty - ny * ptx
    fa = -ra * inv_inertia[a]
    fb = -rb * inv_inertia[b]
    omega[a, 0] += fa * cx
    omega[a, 1] += fa * cy
    omega[a, 2] += fa * cz
    omega[b, 0] += fb * cx
    omega[b, 1] += fb * cy
    omega[b, 2] += fb * cz
    return en, et, kind


@njit(cache=True, error_model="numpy", _nrt=False)
def collide_wall(a, nx, ny, nz, vel, omega, radius, inv_mass, inv_inertia, e, mu):
    """Collision of particle a with a static wall of inward normal n (infinite mass, Hoomans §2.3)."""
    ra = radius[a]
    wx = ra * omega[a, 0]
    wy = ra * omega[a, 1]
    wz = ra * omega[a, 2]
    ux = vel[a, 0] - (wy * nz - wz * ny)
    uy = vel[a, 1] - (wz * nx - wx * nz)
    uz = vel[a, 2] - (wx * ny - wy * nx)
    ima = inv_mass[a]
    ka = ra * ra * inv_inertia[a]
    pn, ptx, pty, ptz, en, et, kind = impulse(nx, ny, nz, ux, uy, uz, ima, 0.0, ka, 0.0, e, mu)
    if kind == NO_COLLISION:
        return 0.0, 0.0, kind
    vel[a, 0] += (pn * nx + ptx) * ima
    vel[a, 1] += (pn * ny + pty) * ima
    vel[a, 2] += (pn * nz + ptz) * ima
    fa = -ra * inv_inertia[a]
    omega[a, 0] += fa * (ny * ptz - nz * pty)
    omega[a, 1] += fa * (nz * ptx - nx * ptz)
    omega[a, 2] += fa * (nx * pty - ny * ptx)
    return en, et, kind


# ---------------------------------------------------------------- binary heap (indexed, one entry per particle)
@njit(cache=True, error_model="numpy", _nrt=False)
def _sift_up(k, heap, hkey, hpos):
    item = heap[k]
    key = hkey[k]
    while k > 0:
        parent = (k - 1) >> 1
        if hkey[parent] <= key:
            break
        q = heap[parent]
        heap[k] = q
        hkey[k] = hkey[parent]
        hpos[q] = k
        k = parent
    heap[k] = item
    hkey[k] = key
    hpos[item] = k


@njit(cache=True, error_model="numpy", _nrt=False)
def _sift_down(k, n, heap, hkey, hpos):
    item = heap[k]
    key = hkey[k]
    while True:
        c = 2 * k + 1
        if c >= n:
            break
        if c + 1 < n and hkey[c + 1] < hkey[c]:
            c += 1
        if hkey[c] >= key:
            break
        q = heap[c]
        heap[k] = q
        hkey[k] = hkey[c]
        hpos[q] = k
        k = c
    heap[k] = item
    hkey[k] = key
    hpos[item] = k


@njit(cache=True, error_model="numpy", _nrt=False)
def _heap_update(i, key, heap, hkey, hpos):
    k = hpos[i]
    old = hkey[k]
    hkey[k] = key
    if key < old:
        _sift_up(k, heap, hkey, hpos)
    elif key > old:
        _sift_down(k, heap.shape[0], heap, hkey, hpos)


@njit(cache=True, error_model="numpy", _nrt=False)
def _heapify(ev_time, heap, hkey, hpos):
    n = heap.shape[0]
    for i in range(n):
        heap[i] = i
        hkey[i] = ev_time[i]
        hpos[i] = i
    for k in range(n // 2 - 1, -1, -1):
        _sift_down(k, n, heap, hkey, hpos)


# ---------------------------------------------------------------- event prediction
@njit(cache=True, error_model="numpy", _nrt=False)
def _predict(i, t, t_end, pos, vel, t_loc, radius, nbr_start, nbr, wall_point, wall_normal, ref_pos, half_skin,
             ncoll, ev_time, ev_part, ev_cnt):
    """Earliest event of particle i after time t and before t_end (else none), stored in ev_*."""
    dti = t - t_loc[i]
    xi = pos[i, 0] + vel[i, 0] * dti  # eq. 32 up to time t
    yi = pos[i, 1] + vel[i, 1] * dti
    zi = pos[i, 2] + vel[i, 2] * dti
    vxi = vel[i, 0]
    vyi = vel[i, 1]
    vzi = vel[i, 2]
    ri = radius[i]
    best = t_end
    part = NO_EVENT
    cnt = 0
    # wall planes: Hoomans eq. 31 for any plane, gap h = (x − p)·n − R closed at speed −v·n
    for w in range(wall_normal.shape[0]):
        nx = wall_normal[w, 0]
        ny = wall_normal[w, 1]
        nz = wall_normal[w, 2]
        vn = vxi * nx + vyi * ny + vzi * nz
        if vn < 0.0:
            h = (xi - wall_point[w, 0]) * nx + (yi - wall_point[w, 1]) * ny + (zi - wall_point[w, 2]) * nz - ri
            tw = t if h <= 0.0 else t + h / -vn  # at or behind the wall: collide now (round-off guard)
            if tw < best:
                best = tw
                part = WALL_EVENT0 - w
    # neighbours: Hoomans eq. 30 in the cancellation-free form c / (−b + sqrt(b² − v² c))
    for p in range(nbr_start[i], nbr_start[i + 1]):
        j = nbr[p]
        dtj = t - t_loc[j]
        vx = vxi - vel[j, 0]
        vy = vyi - vel[j, 1]
        vz = vzi - vel[j, 2]
        rx = xi - (pos[j, 0] + vel[j, 0] * dtj)
        ry = yi - (pos[j, 1] + vel[j, 1] * dtj)
        rz = zi - (pos[j, 2] + vel[j, 2] * dtj)
        b = rx * vx + ry * vy + rz * vz
        if b >= 0.0:  # moving apart (Hoomans, after eq. 30)
            continue
        sig = ri + radius[j]
        c = rx * rx + ry * ry + rz * rz - sig * sig
        if c <= 0.0:  # at or inside contact distance and approaching: collide now (round-off guard)
            tc = t
        else:
            if c >= -2.0 * b * (best - t):  # the root is at least c / (−2b): it cannot beat the best event
                continue
            v2 = vx * vx + vy * vy + vz * vz
            disc = b * b - v2 * c
            if disc < 0.0:
                continue
            tc = t + c / (-b + math.sqrt(disc))
        if tc < best:
            best = tc
            part = j
            cnt = ncoll[j]
    # leaving the skin sphere |x − x_ref| = skin/2 invalidates the neighbour list
    dx = xi - ref_pos[i, 0]
    dy = yi - ref_pos[i, 1]
    dz = zi - ref_pos[i, 2]
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
    ev_time[i] = best
    ev_part[i] = part
    ev_cnt[i] = cnt


@njit(cache=True, error_model="numpy", _nrt=False)
def _move(i, t, pos, vel, t_loc):
    """Free flight of particle i up to time t (Hoomans eq. 32)."""
    dt = t - t_loc[i]
    pos[i, 0] += vel[i, 0] * dt
    pos[i, 1] += vel[i, 1] * dt
    pos[i, 2] += vel[i, 2] * dt
    t_loc[i] = t


@njit(cache=True, error_model="numpy", _nrt=False)
def _sync(t, pos, vel, t_loc):
    for i in range(pos.shape[0]):
        _move(i, t, pos, vel, t_loc)


@njit(cache=True, error_model="numpy", _nrt=False)
def _predict_all(t, t_end, pos, vel, t_loc, radius, nbr_start, nbr, wall_point, wall_normal, ref_pos, half_skin,
                 ncoll, ev_time, ev_part, ev_cnt, heap, hkey, hpos):
    for i in range(pos.shape[0]):
        _predict(i, t, t_end, pos, vel, t_loc, radius, nbr_start, nbr, wall_point, wall_normal, ref_pos, half_skin,
                 ncoll, ev_time, ev_part, ev_cnt)
    _heapify(ev_time, heap, hkey, hpos)


@njit(cache=True, error_model="numpy", _nrt=False)
def _repredict(i, j, t, t_end, pos, vel, t_loc, radius, nbr_start, nbr, wall_point, wall_normal, ref_pos, half_skin,
               ncoll, ev_time, ev_part, ev_cnt, heap, hkey, hpos):
    """New events for particle i (and j if j >= 0) from time t, and their places in the heap."""
    _predict(i, t, t_end, pos, vel, t_loc, radius, nbr_start, nbr, wall_point, wall_normal, ref_pos, half_skin,
             ncoll, ev_time, ev_part, ev_cnt)
    _heap_update(i, ev_time[i], heap, hkey, hpos)
    if j >= 0:
        _predict(j, t, t_end, pos, vel, t_loc, radius, nbr_start, nbr, wall_point, wall_normal, ref_pos, half_skin,
                 ncoll, ev_time, ev_part, ev_cnt)
        _heap_update(j, ev_time[j], heap, hkey, hpos)


@njit(cache=True, error_model="numpy", _nrt=False)
def _book(i, j, code, tabs, en, et, kind, remedy, last_coll, ncoll, counters, energy, log):
    """Counters, dissipated energy, TC clocks and the optional log after a collision of i with j (or wall code)."""
    last_coll[i] = tabs
    ncoll[i] += 1
    if j >= 0:
        last_coll[j] = tabs
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
@njit(cache=True, error_model="numpy")
def advance(pos, vel, omega, radius, inv_mass, inv_inertia, species, pp, pw, wall_point, wall_normal, gravity,
            ext_force, dim2, nbr_start, nbr, ref_pos, skin, last_coll, step0, dt, nsteps, max_events, counters,
            energy, log, info):
    """Run ``nsteps`` force steps of length ``dt`` (Hoomans 1996 Fig. 3 per step).

    Parameters (arrays are updated in place)
    ----------
    pos, vel, omega : (N, 3) float64 [m, m/s, rad/s]
    radius, inv_mass, inv_inertia : (N,) float64 [m, 1/kg, 1/(kg m²)]
    species : (N,) int64; pp : (S, S, 8), pw : (S, W, 8) packed hard-sphere rows
    wall_point, wall_normal : (W, 3) static wall planes (inward normals)
    gravity : (3,) [m/s²]; ext_force : (N, 3) [N], constant over a step (the gas force)
    nbr_start, nbr : full neighbour list of ``ref_pos`` (N, 3) with cut-off R_i + R_j + skin
    last_coll : (N,) absolute time of each particle's last collision [s] (TC model)
    step0 : index of the first step (absolute time of step s is (step0 + s) dt)
    max_events : events per step after which the call stops with status TOO_MANY_EVENTS
    counters : (N_COUNTERS,) int64, energy : (N_ENERGIES,) float64, cumulative
    log : (L, 5) float64; the first L collisions after counters[C_LOGGED] = 0 are recorded as
        (absolute time, a, b or WALL_EVENT0 − w, E_n, E_t)
    info : (3,) float64, on failure (step index, time in step, events)

    Returns (nbr_start, nbr, status); status OK or TOO_MANY_EVENTS (the state is then
    mid-step and the caller restores its copy).
    """
    n = pos.shape[0]
    t_loc = np.zeros(n)
    ev_time = np.empty(n)
    ev_part = np.empty(n, dtype=np.int64)
    ev_cnt = np.empty(n, dtype=np.int64)
    ncoll = np.zeros(n, dtype=np.int64)
    heap = np.empty(n, dtype=np.int64)
    hkey = np.empty(n)
    hpos = np.empty(n, dtype=np.int64)
    half_skin = 0.5 * skin * SKIN_MARGIN
    gx = gravity[0]
    gy = gravity[1]
    gz = gravity[2]
    for s in range(nsteps):
        t_abs0 = (step0 + s) * dt
        # force step: v = v* + (g + F/m) DT, Hoomans eqs 33–34
        for i in range(n):
            im = inv_mass[i]
            vel[i, 0] += (gx + ext_force[i, 0] * im) * dt
            vel[i, 1] += (gy + ext_force[i, 1] * im) * dt
            if not dim2:
                vel[i, 2] += (gz + ext_force[i, 2] * im) * dt
            t_loc[i] = 0.0
        _predict_all(0.0, dt, pos, vel, t_loc, radius, nbr_start, nbr, wall_point, wall_normal, ref_pos, half_skin,
                     ncoll, ev_time, ev_part, ev_cnt, heap, hkey, hpos)
        events = 0
        while n > 0:
            i = heap[0]
            t = hkey[0]
            if not t < dt:  # the next event lies beyond the step (or there is none)
                break
            events += 1
            if events > max_events:
                info[0] = s
                info[1] = t
                info[2] = events
                counters[C_EVENTS] += events
                return nbr_start, nbr, TOO_MANY_EVENTS
            p = ev_part[i]
            if p == SKIN_EVENT:
                # a particle reached skin/2 from its reference position: all to time t, new list
                _sync(t, pos, vel, t_loc)
                nbr_start, nbr = build_neighbours(pos, radius, skin, dim2)
                for k in range(n):  # (an explicit loop: a slice assignment costs seconds of compile time)
                    ref_pos[k, 0] = pos[k, 0]
                    ref_pos[k, 1] = pos[k, 1]
                    ref_pos[k, 2] = pos[k, 2]
                counters[C_REBUILDS] += 1
                _predict_all(t, dt, pos, vel, t_loc, radius, nbr_start, nbr, wall_point, wall_normal, ref_pos,
                             half_skin, ncoll, ev_time, ev_part, ev_cnt, heap, hkey, hpos)
                continue
            if p >= 0 and ncoll[p] != ev_cnt[i]:  # the partner collided since the prediction: predict again
                counters[C_STALE] += 1
                _repredict(i, -1, t, dt, pos, vel, t_loc, radius, nbr_start, nbr, wall_point, wall_normal, ref_pos,
                           half_skin, ncoll, ev_time, ev_part, ev_cnt, heap, hkey, hpos)
                continue
            tabs = t_abs0 + t
            _move(i, t, pos, vel, t_loc)
            w = -1
            # scalars, not a row view: a view costs two atomic reference-count updates
            if p >= 0:
                j = p
                _move(j, t, pos, vel, t_loc)
                si = species[i]
                sj = species[j]
                tcol = pp[si, sj, SLOT_COLLAPSE_TIME]
                e = pp[si, sj, SLOT_RESTITUTION]
                mu = pp[si, sj, SLOT_FRICTION]
                remedy = tabs - last_coll[i] < tcol or tabs - last_coll[j] < tcol
            else:
                j = -1
                w = WALL_EVENT0 - p
                si = species[i]
                tcol = pw[si, w, SLOT_COLLAPSE_TIME]
                e = pw[si, w, SLOT_RESTITUTION]
                mu = pw[si, w, SLOT_FRICTION]
                remedy = tabs - last_coll[i] < tcol
            if remedy and (e < 1.0 or mu > 0.0):
                e = 1.0  # TC model (Luding & McNamara 1998): elastic and frictionless
                mu = 0.0
            else:
                remedy = False
            if j >= 0:
                en, et, kind = collide_pair(i, j, pos, vel, omega, radius, inv_mass, inv_inertia, e, mu)
            else:
                en, et, kind = collide_wall(i, wall_normal[w, 0], wall_normal[w, 1], wall_normal[w, 2], vel, omega,
                                            radius, inv_mass, inv_inertia, e, mu)
            if kind != NO_COLLISION:
                _book(i, j, p, tabs, en, et, kind, remedy, last_coll, ncoll, counters, energy, log)
            # new predictions for the particle(s) whose velocity changed ("reset lists" of Fig. 3)
            _repredict(i, j, t, dt, pos, vel, t_loc, radius, nbr_start, nbr, wall_point, wall_normal, ref_pos,
                       half_skin, ncoll, ev_time, ev_part, ev_cnt, heap, hkey, hpos)
        counters[C_EVENTS] += events
        _sync(dt, pos, vel, t_loc)  # free flight to the end of the step
    return nbr_start, nbr, OK
