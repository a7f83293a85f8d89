"""Compiled soft-sphere DEM: forces and velocity-Verlet sub-steps (Sun 2007 eqs 15–24).

``advance`` runs many DEM steps in one call: half kick, drift, Verlet-list check
and rebuild, forces, half kick. Pair forces are computed once per pair and added
straight into per-particle sums, slab by slab in two phases (see
``_neighbours_kernels``), so there are no write races and the sums do not depend
on the number of threads.

The contact law runs vectorised over chunks of contacts (``_pair_kernels``, called by
``pair_forces``). The per-particle loops (``_gather_range``) and those of ``_pair_kernels``
index with unsigned integers (``U``): with a signed index Numba adds wrap-around code for negative
values to every ``a[k]``, which LLVM cannot drop in these loops (the former scalar pair loop, one
thread, bitwise the same sums: tsuji-jet-background bed at 1.5 s 139 → 100 µs per step, the 10k 3D bench bed
2.28 → 1.92 ms).
"""
import math

import numpy as np
from numba import njit, prange

from ._pair_kernels import chunk_run, make_work
from ._neighbours_kernels import (build_pairs, build_pairs_periodic, carry_history, cell_order, contacts_first,
                                  contacts_first_periodic, renumber_pairs)
from .contact._dispatch import contact_force, contact_force_full
from .contact.base import N_SLOTS, ROLLING_HISTORY, SLOT_EXTENDED, SLOT_ROLLING_FRICTION
from ._shape_kernels import bodies_kick_drift, bodies_step, body_loads, has_bodies, shape_forces, shape_step

U = np.uintp  # unsigned array index: no wrap-around code (module docstring)
assert N_SLOTS == 12, "_law reads the first 8 slots of a packed contact row, _law_full all 12"

# wall motion kinds (walls.py builds the table)
STATIC, CONSTANT_VELOCITY, OSCILLATING = 0, 1, 2


@njit(cache=True, error_model="numpy", inline="always")
def wall_state(motion, point0, w, t):
    """Position of the reference point and velocity of wall w at time t."""
    kind = int(motion[w, 0])
    px, py, pz = point0[w, 0], point0[w, 1], point0[w, 2]
    if kind == CONSTANT_VELOCITY:
        vx, vy, vz = motion[w, 1], motion[w, 2], motion[w, 3]
        return px + vx * t, py + vy * t, pz + vz * t, vx, vy, vz
    if kind == OSCILLATING:
        om = 2.0 * math.pi * motion[w, 4]
        s = math.sin(om * t + motion[w, 5])
        c = math.cos(om * t + motion[w, 5]) * om
        return (px + motion[w, 1] * s, py + motion[w, 2] * s, pz + motion[w, 3] * s,
                motion[w, 1] * c, motion[w, 2] * c, motion[w, 3] * c)
    return px, py, pz, 0.0, 0.0, 0.0


@njit(cache=True, error_model="numpy", inline="always")
def _law(table, a, b):
    """Row (a, b) of a packed contact table as a tuple of scalars.

    ``table[a, b]`` would create an array view, and each view costs an atomic reference-count
    increment and decrement (two out-of-line calls) per contact; a tuple of scalars costs nothing."""
    return (table[a, b, U(0)], table[a, b, U(1)], table[a, b, U(2)], table[a, b, U(3)], table[a, b, U(4)], table[a, b, U(5)],
            table[a, b, U(6)], table[a, b, U(7)])


@njit(cache=True, error_model="numpy", inline="always")
def _law_full(table, a, b):
    """Row (a, b) with all its slots (rolling friction, adhesion), for ``contact_force_full``."""
    return (table[a, b, U(0)], table[a, b, U(1)], table[a, b, U(2)], table[a, b, U(3)], table[a, b, U(4)], table[a, b, U(5)],
            table[a, b, U(6)], table[a, b, U(7)], table[a, b, U(8)], table[a, b, U(9)], table[a, b, U(10)],
            table[a, b, U(11)])


@njit(cache=True, error_model="numpy")
def extended(table):
    """True if a row of a packed contact table has rolling friction or an adhesive law: its contacts then go
    through ``contact_force_full``."""
    ext = False
    for a in range(table.shape[0]):
        for b in range(table.shape[1]):
            ext |= (table[a, b, SLOT_ROLLING_FRICTION] != 0.0) | (table[a, b, SLOT_EXTENDED] != 0.0)
    return ext


@njit(cache=True, error_model="numpy")
def any_nonzero(ext_force, ext_damping):
    """True if any external force or drag coefficient is not zero. Stops at the first one (in a coupled run
    the first particle's), where ``np.any(ext_force != 0)`` made and scanned a temporary N × 3 array at each
    ``advance`` call."""
    for i in range(ext_force.shape[0]):
        if (ext_force[i, 0] != 0.0) | (ext_force[i, 1] != 0.0) | (ext_force[i, 2] != 0.0) | (ext_damping[i] != 0.0):
            return True
    return False


@njit(cache=True, error_model="numpy")
def is_flat(pos, vel, omega, hist):
    """True if every particle has the same z, v_z = 0, ω_x = ω_y = 0 and every spring h_z = 0 (a flat 2D bed:
    the pair forces and the force pass may leave out the z terms, exact zeros there). Counts without early
    exits, which the compiler vectorises (a call per gas step of a coupled run)."""
    n = pos.shape[0]
    if n == 0:
        return False
    z0 = pos[0, 2]
    off = 0
    for i in range(n):
        off += (pos[i, 2] != z0) + (vel[i, 2] != 0.0) + (omega[i, 0] != 0.0) + (omega[i, 1] != 0.0)
    for p in range(hist.shape[0]):
        off += hist[p, 2] != 0.0
    return off == 0


PAIR_WEIGHT = 1.5  # cost of a listed pair against that of a particle's own pass (gather), for thread_blocks
# (measured for the former scalar pair loop; the chunked one keeps the 100,000-sphere bed's two blocks within 3 %)


@njit(cache=True, error_model="numpy")
def thread_blocks(row_start, slab_start, slab_members, nthreads):
    """Split the slabs into ``nthreads`` contiguous blocks of about equal work: (nthreads + 1,) slab bounds.

    Work of a slab: PAIR_WEIGHT per listed pair in its members' rows plus 1 per member (the
    force-gathering pass). Thread k takes the slabs of block k in the pair loop (both parities)
    and the particles slab_start[block[k]] … slab_start[block[k + 1]] − 1 of the numbering in the
    gathering pass: in slab order (``reorder``) those are the same particles, so each thread keeps
    its particles' data in its own core's cache from pass to pass and step to step. Dealing
    slabs round-robin (and particles in fixed chunks) instead moved that data between the cores
    at every pass: 2 threads took 160 µs for the pair loop of the 2400-particle tsuji-jet-background bed
    against 117 µs on one. Any split gives the same sums (``pair_forces``)."""
    nslab = slab_start.shape[0] - 1
    block = np.empty(nthreads + 1, dtype=np.int64)
    block[0] = 0
    block[nthreads] = nslab
    if nthreads == 1:
        return block
    n = row_start.shape[0] - 1
    total = PAIR_WEIGHT * (row_start[n] - row_start[0]) + n
    acc = 0.0
    k = 1
    for s in range(nslab):
        for m in range(slab_start[s], slab_start[s + 1]):
            i = slab_members[m]
            acc += PAIR_WEIGHT * (row_start[i + 1] - row_start[i]) + 1.0
        while k < nthreads and acc >= total * k / nthreads:
            block[k] = s + 1
            k += 1
    while k < nthreads:
        block[k] = nslab
        k += 1
    return block


@njit(cache=True, error_model="numpy", parallel=True)
def _chunk_forces_parallel(state, pp, lists, hist, dt, update, sum_f, sum_c, block, flat, work, period, laws):
    """Phase 0 runs the even slabs, phase 1 the odd ones; thread k the slabs of its block (``thread_blocks``),
    with row k of the work arrays."""
    nthreads = block.shape[0] - 1
    for phase in range(2):
        for k in prange(nthreads):
            chunk_run(block[k] + (block[k] + phase) % 2, block[k + 1], flat, state, pp, lists, hist, dt, update,
                      sum_f, sum_c, work, np.int64(k), period, laws)


@njit(cache=True, error_model="numpy")
def _chunk_forces(state, pp, lists, hist, dt, update, sum_f, sum_c, block, flat, work, period, laws):
    """The contacts of all slabs: the even ones, then the odd ones (see ``pair_forces``)."""
    if block.shape[0] > 2:
        _chunk_forces_parallel(state, pp, lists, hist, dt, update, sum_f, sum_c, block, flat, work, period, laws)
        return
    nslab = lists[2].shape[0] - 1
    for phase in range(2):
        chunk_run(phase, nslab, flat, state, pp, lists, hist, dt, update, sum_f, sum_c, work, np.int64(0), period,
                  laws)


@njit(cache=True, error_model="numpy")
def pair_forces(pos, vel, omega, radius, mass, species, pp, row_start, partner, slab_start, slab_members, hist,
                dt, update, sum_f, sum_c, block, flat=None, work=None, period=None, laws=True):
    """Add the contact force sums (sum_f) and Σ −n × F_t (sum_c, torque per unit lever arm) per particle.

    sum_f and sum_c must be zero on entry (gather_forces leaves them so). The contact law runs vectorised
    over chunks of contacts (``_pair_kernels``). Slabs of one parity run in parallel: the pairs of slab s
    touch only slabs s and s + 1. ``block``: the slab blocks of the threads (``thread_blocks``); with one
    block the slabs run in the same order without a parallel region. Every particle gets its terms in the
    same order either way (bitwise the same sums).
    ``flat``: None, or True for a flat 2D bed (``is_flat``), whose sum_f z and sum_c x, y are left as they are
    (False is refused: the variant is chosen by None or not when this is compiled, see ``chunk_run``).
    ``work``: ``_pair_kernels.make_work`` for this list and at least len(block) − 1 threads (made here if
    None or too small).
    ``period``: (3,) the box length along each periodic axis, 0 elsewhere (None: no periodic side); centre
    offsets are then taken by nearest image, with a list from ``build_pairs_periodic``.
    ``laws``: None where no contact law of the run has rolling friction or adhesion (``extended``), which
    leaves the extended law out of the compilation (``_pair_kernels.chunk_run``); else any value.
    """
    if flat is not None:
        if not flat:
            raise ValueError("pair_forces: flat must be None (a bed that is not flat) or True (a flat 2D bed)")
    state = (pos, vel, omega, radius, mass, species)
    lists = (row_start, partner, slab_start, slab_members)
    nthreads = block.shape[0] - 1
    if work is None:
        _chunk_forces(state, pp, lists, hist, dt, update, sum_f, sum_c, block, flat,
                      make_work(pp, row_start, hist, slab_start, slab_members, nthreads), period, laws)
    elif work[0].shape[0] < nthreads:
        _chunk_forces(state, pp, lists, hist, dt, update, sum_f, sum_c, block, flat,
                      make_work(pp, row_start, hist, slab_start, slab_members, nthreads), period, laws)
    else:
        _chunk_forces(state, pp, lists, hist, dt, update, sum_f, sum_c, block, flat, work, period, laws)


@njit(cache=True, error_model="numpy")
def walls_now(motion, point0, t):
    """(W, 6) table of each wall's reference point and velocity at time t."""
    nw = point0.shape[0]
    out = np.empty((nw, 6))
    for w in range(nw):
        px, py, pz, vx, vy, vz = wall_state(motion, point0, w, t)
        out[w, 0] = px
        out[w, 1] = py
        out[w, 2] = pz
        out[w, 3] = vx
        out[w, 4] = vy
        out[w, 5] = vz
    return out


@njit(cache=True, error_model="numpy")
def wall_axes(wall_normal):
    """(W,) int64: k where wall w's normal is ±e_k (a box side), else −1.

    For such a wall the gap n·(x − p) is ±(x_k − p_k), computed so in _gather_range: the same
    number as the full dot product (the other two terms are zero), at a fraction of the cost
    (gather_forces of the tsuji-jet-background bed: 58 → 45 µs per step with its four box sides)."""
    nw = wall_normal.shape[0]
    axis = np.full(nw, -1, dtype=np.int64)
    for w in range(nw):
        for k in range(3):
            if (abs(wall_normal[w, k]) == 1.0) & (wall_normal[w, (k + 1) % 3] == 0.0) & (wall_normal[w, (k + 2) % 3] == 0.0):
                axis[w] = k
    return axis


@njit(cache=True, error_model="numpy", inline="always")
def wall_contact(i, w, pos, vel, omega, radius, mass, species, pw, wall_now, wall_normal, wall_hist, dt, update):
    """(overlap, fx, fy, fz, tx, ty, tz) of particle i on wall w (a plane; infinite mass).

    For analysis (``analysis.probes``); the stepping loop has the same code inline in _gather_range (there
    the plain ``contact_force`` serves tables without rolling friction or adhesion, with the same numbers)."""
    px, py, pz = wall_now[w, 0], wall_now[w, 1], wall_now[w, 2]
    wvx, wvy, wvz = wall_now[w, 3], wall_now[w, 4], wall_now[w, 5]
    nx, ny, nz = wall_normal[w, 0], wall_normal[w, 1], wall_normal[w, 2]
    wide = wall_hist.shape[2] > 3
    rolling = wall_hist.shape[2] > ROLLING_HISTORY
    gap = (pos[i, 0] - px) * nx + (pos[i, 1] - py) * ny + (pos[i, 2] - pz) * nz
    overlap = radius[i] - gap
    if overlap <= -(wall_hist[i, w, 3] if wide else 0.0):
        if update:
            wall_hist[i, w, :] = 0.0
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    a = radius[i]
    g0 = wall_hist[i, w, ROLLING_HISTORY] if rolling else 0.0
    g1 = wall_hist[i, w, ROLLING_HISTORY + 1] if rolling else 0.0
    g2 = wall_hist[i, w, ROLLING_HISTORY + 2] if rolling else 0.0
    fn, ftx, fty, ftz, hx, hy, hz, reach, mx, my, mz, gx, gy, gz = contact_force_full(
        _law_full(pw, species[i], w), overlap, nx, ny, nz, vel[i, 0] - wvx, vel[i, 1] - wvy, vel[i, 2] - wvz,
        a * omega[i, 0], a * omega[i, 1], a * omega[i, 2], omega[i, 0], omega[i, 1], omega[i, 2], mass[i], a,
        1.4 * mass[i] * a * a, dt, wall_hist[i, w, 0], wall_hist[i, w, 1], wall_hist[i, w, 2], g0, g1, g2, update)
    if update:
        wall_hist[i, w, 0] = hx
        wall_hist[i, w, 1] = hy
        wall_hist[i, w, 2] = hz
        if wide:
            wall_hist[i, w, 3] = reach
        if rolling:
            wall_hist[i, w, ROLLING_HISTORY] = gx
            wall_hist[i, w, ROLLING_HISTORY + 1] = gy
            wall_hist[i, w, ROLLING_HISTORY + 2] = gz
    return (overlap, fn * nx + ftx, fn * ny + fty, fn * nz + ftz, -a * (ny * ftz - nz * fty) + mx,
            -a * (nz * ftx - nx * ftz) + my, -a * (nx * fty - ny * ftx) + mz)


@njit(cache=True, error_model="numpy", inline="always")
def _gather_body(flat, lo, hi, pos, vel, omega, radius, mass, species, pw, walls, gravity, ext_force, ext_damping,
                 has_ext, dim2, sum_f, sum_c, dt, force, torque, inv_mass, inv_inertia, mode, ref_pos, limit2, laws):
    """gather_forces for particles lo..hi−1 (serial code; the parallel driver splits the range).

    ``flat`` (a constant where inlined: ``_gather_range`` False, ``_gather_range_flat`` True): a flat 2D bed
    (``is_flat``, ``dim2``): z positions, v_z, ω_x, ω_y stay as they are (their updates add exact zeros)
    and sum_f z, sum_c x, y are not read (the flat pair forces leave them zero).
    ``walls``: (wall_now, wall_normal, wall_axis, wall_hist, wall_touch, near_count, near_wall) in one tuple, as a
    call of more than 30 arguments is compiled by Python as f(*args), which Numba cannot inline.
    ``laws``: None where no contact law of the run has rolling friction or adhesion, which leaves
    ``contact_force_full`` out of the compilation (as ``pair_forces``'s); else any value."""
    wall_now, wall_normal, wall_axis, wall_hist, wall_touch, near_count, near_wall = walls
    # rolling friction or an adhesive law at some wall: contact_force_full; an adhesive one keeps each contact's
    # pull-off distance in wall_hist[i, w, 3] while it lasts (0 before it forms), as for pairs
    wext = extended(pw)
    wwide = wall_hist.shape[2] > 3
    wroll = wall_hist.shape[2] > ROLLING_HISTORY  # an epsd wall law's rolling spring, columns 4-6
    half = 0.5 * dt
    moved = 0
    update = mode > 0
    # walls first, for the particles that can reach one (near_walls: few), into the sums: force, and −n × F_t per
    # unit lever arm (the lever is the radius) as for pairs. Kept out of the main loop below, whose inner loop
    # over walls and its branches made it 2.5 times slower than it is without them (tsuji-jet-background bed)
    for i_ in range(lo, hi):
        i = U(i_)
        nq = near_count[i]
        if nq == 0:
            continue
        a = radius[i]
        xi = pos[i, U(0)]
        yi = pos[i, U(1)]
        zi = pos[i, U(2)]  # read in the flat case too: a wall may face z (never reached in a flat bed)
        for q in range(nq):  # the walls particle i can reach before the next list rebuild (near_walls)
            w = U(near_wall[i, U(q)])
            nx = wall_normal[w, U(0)]
            ny = wall_normal[w, U(1)]
            nz = wall_normal[w, U(2)]
            k = wall_axis[w]
            if k == 0:  # a box side: n·(x − p) with the two zero terms left out (wall_axes)
                gap = (xi - wall_now[w, U(0)]) * nx
            elif k == 1:
                gap = (yi - wall_now[w, U(1)]) * ny
            elif k == 2:
                gap = (zi - wall_now[w, U(2)]) * nz
            else:
                gap = (xi - wall_now[w, U(0)]) * nx + (yi - wall_now[w, U(1)]) * ny + (zi - wall_now[w, U(2)]) * nz
            overlap = a - gap
            if overlap <= -(wall_hist[i, w, U(3)] if wwide else 0.0):
                # the spring of a wall contact that ended is reset; wall_touch[i, w] False means it is zero
                # already, which spares reading wall_hist (N × W × 3) for every particle and wall each step
                if update and wall_touch[i, w]:
                    wall_hist[i, w, U(0)] = 0.0
                    wall_hist[i, w, U(1)] = 0.0
                    wall_hist[i, w, U(2)] = 0.0
                    if wwide:
                        for e in range(3, wall_hist.shape[2]):
                            wall_hist[i, w, U(e)] = 0.0
                    wall_touch[i, w] = False
                continue
            if laws is not None:
                if wext:
                    g0 = wall_hist[i, w, U(ROLLING_HISTORY)] if wroll else 0.0
                    g1 = wall_hist[i, w, U(ROLLING_HISTORY + 1)] if wroll else 0.0
                    g2 = wall_hist[i, w, U(ROLLING_HISTORY + 2)] if wroll else 0.0
                    fn, ftx, fty, ftz, hx, hy, hz, reach, mx, my, mz, gx, gy, gz = contact_force_full(
                        _law_full(pw, U(species[i]), w), overlap, nx, ny, nz,
                        vel[i, U(0)] - wall_now[w, U(3)], vel[i, U(1)] - wall_now[w, U(4)],
                        (0.0 if flat else vel[i, U(2)]) - wall_now[w, U(5)],
                        0.0 if flat else a * omega[i, U(0)], 0.0 if flat else a * omega[i, U(1)], a * omega[i, U(2)],
                        0.0 if flat else omega[i, U(0)], 0.0 if flat else omega[i, U(1)], omega[i, U(2)], mass[i], a,
                        1.4 * mass[i] * a * a, dt, wall_hist[i, w, U(0)], wall_hist[i, w, U(1)], wall_hist[i, w, U(2)],
                        g0, g1, g2, update)
                    if update:
                        wall_hist[i, w, U(0)] = hx
                        wall_hist[i, w, U(1)] = hy
                        wall_hist[i, w, U(2)] = hz
                        if wwide:
                            wall_hist[i, w, U(3)] = reach
                        if wroll:
                            wall_hist[i, w, U(ROLLING_HISTORY)] = gx
                            wall_hist[i, w, U(ROLLING_HISTORY + 1)] = gy
                            wall_hist[i, w, U(ROLLING_HISTORY + 2)] = gz
                        wall_touch[i, w] = True
                    # the rolling torque per unit lever (the radius a), as the sums hold it
                    sum_f[i, U(0)] += fn * nx + ftx
                    sum_f[i, U(1)] += fn * ny + fty
                    sum_c[i, U(2)] -= nx * fty - ny * ftx - mz / a
                    if not flat:
                        sum_f[i, U(2)] += fn * nz + ftz
                        sum_c[i, U(0)] -= ny * ftz - nz * fty - mx / a
                        sum_c[i, U(1)] -= nz * ftx - nx * ftz - my / a
                    continue
            # wall_contact written out (an inlined helper taking arrays made Numba copy array references: an
            # atomic reference-count increment and decrement per particle and wall)
            fn, ftx, fty, ftz, hx, hy, hz = contact_force(
                _law(pw, U(species[i]), w), overlap, nx, ny, nz,
                vel[i, U(0)] - wall_now[w, U(3)], vel[i, U(1)] - wall_now[w, U(4)],
                (0.0 if flat else vel[i, U(2)]) - wall_now[w, U(5)],
                0.0 if flat else a * omega[i, U(0)], 0.0 if flat else a * omega[i, U(1)], a * omega[i, U(2)], mass[i], a,
                dt, wall_hist[i, w, U(0)], wall_hist[i, w, U(1)], wall_hist[i, w, U(2)], update)
            if update:
                wall_hist[i, w, U(0)] = hx
                wall_hist[i, w, U(1)] = hy
                wall_hist[i, w, U(2)] = hz
                wall_touch[i, w] = True
            sum_f[i, U(0)] += fn * nx + ftx
            sum_f[i, U(1)] += fn * ny + fty
            sum_c[i, U(2)] -= nx * fty - ny * ftx
            if not flat:
                sum_f[i, U(2)] += fn * nz + ftz
                sum_c[i, U(0)] -= ny * ftz - nz * fty
                sum_c[i, U(1)] -= nz * ftx - nx * ftz
    for i_ in range(lo, hi):
        i = U(i_)
        # external force: a fixed part and a linear drag −c v at the current velocity (the gas's drag
        # coefficient K_p when the coupling updates the particle's own velocity every sub-step)
        fx = mass[i] * gravity[0]
        fy = mass[i] * gravity[1]
        fz = 0.0 if flat else mass[i] * gravity[2]
        if has_ext:  # else both are zero (no gas): not read, 4 of the pass's ~40 numbers a particle
            c = ext_damping[i]
            fx += ext_force[i, U(0)] - c * vel[i, U(0)]
            fy += ext_force[i, U(1)] - c * vel[i, U(1)]
            if not flat:
                fz += ext_force[i, U(2)] - c * vel[i, U(2)]
        fx += sum_f[i, U(0)]
        fy += sum_f[i, U(1)]
        cz = sum_c[i, U(2)]
        # leave the sums zero for the next pair_forces (saves a separate clearing pass)
        sum_f[i, U(0)] = 0.0
        sum_f[i, U(1)] = 0.0
        sum_c[i, U(2)] = 0.0
        if flat:
            cx = 0.0
            cy = 0.0
        else:
            fz += sum_f[i, U(2)]
            cx = sum_c[i, U(0)]
            cy = sum_c[i, U(1)]
            sum_f[i, U(2)] = 0.0
            sum_c[i, U(0)] = 0.0
            sum_c[i, U(1)] = 0.0
        a = radius[i]
        tx = a * cx
        ty = a * cy
        tz = a * cz
        if dim2:
            fz = 0.0
            tx = 0.0
            ty = 0.0
        if mode < 2:  # mode 2: the next step's pass writes them before anything reads them
            force[i, U(0)] = fx
            force[i, U(1)] = fy
            force[i, U(2)] = fz
            torque[i, U(0)] = tx
            torque[i, U(1)] = ty
            torque[i, U(2)] = tz
        if mode >= 1:
            # in registers (re-reading force and vel from memory after each store chained the updates through
            # store-to-load forwarding: 23 % slower); the two half kicks stay two additions, bitwise as separate passes
            im = inv_mass[i]
            ii = inv_inertia[i]
            ax = half * fx * im
            ay = half * fy * im
            az = half * fz * im
            bx = half * tx * ii
            by = half * ty * ii
            bz = half * tz * ii
            vx = vel[i, U(0)] + ax
            vy = vel[i, U(1)] + ay
            vz = 0.0 if flat else vel[i, U(2)] + az
            wx = 0.0 if flat else omega[i, U(0)] + bx
            wy = 0.0 if flat else omega[i, U(1)] + by
            wz = omega[i, U(2)] + bz
            if mode == 2:
                vx += ax
                vy += ay
                vz += az
                wx += bx
                wy += by
                wz += bz
                px = pos[i, U(0)] + dt * vx
                py = pos[i, U(1)] + dt * vy
                pos[i, U(0)] = px
                pos[i, U(1)] = py
                if flat:
                    dz = 0.0
                else:
                    pz = pos[i, U(2)] + dt * vz
                    pos[i, U(2)] = pz
                    dz = pz - ref_pos[i, U(2)]
                dx = px - ref_pos[i, U(0)]
                dy = py - ref_pos[i, U(1)]
                moved += dx * dx + dy * dy + dz * dz > limit2
            vel[i, U(0)] = vx
            vel[i, U(1)] = vy
            omega[i, U(2)] = wz
            if not flat:
                vel[i, U(2)] = vz
                omega[i, U(0)] = wx
                omega[i, U(1)] = wy
    return moved


@njit(cache=True, error_model="numpy")
def _gather_range(lo, hi, pos, vel, omega, radius, mass, species, pw, wall_now, wall_normal, wall_axis, wall_hist, wall_touch,
                  near_count, near_wall, gravity, ext_force, ext_damping, has_ext, dim2, sum_f, sum_c, dt, force, torque,
                  inv_mass, inv_inertia, mode, ref_pos, limit2, laws):
    """``_gather_body``, general."""
    walls = (wall_now, wall_normal, wall_axis, wall_hist, wall_touch, near_count, near_wall)
    return _gather_body(False, lo, hi, pos, vel, omega, radius, mass, species, pw, walls, gravity, ext_force, ext_damping,
                        has_ext, dim2, sum_f, sum_c, dt, force, torque, inv_mass, inv_inertia, mode, ref_pos, limit2,
                        laws)


@njit(cache=True, error_model="numpy")
def _gather_range_flat(lo, hi, pos, vel, omega, radius, mass, species, pw, wall_now, wall_normal, wall_axis, wall_hist,
                       wall_touch, near_count, near_wall, gravity, ext_force, ext_damping, has_ext, dim2, sum_f, sum_c, dt,
                       force, torque, inv_mass, inv_inertia, mode, ref_pos, limit2, laws):
    """``_gather_body`` of a flat 2D bed."""
    walls = (wall_now, wall_normal, wall_axis, wall_hist, wall_touch, near_count, near_wall)
    return _gather_body(True, lo, hi, pos, vel, omega, radius, mass, species, pw, walls, gravity, ext_force, ext_damping,
                        has_ext, dim2, sum_f, sum_c, dt, force, torque, inv_mass, inv_inertia, mode, ref_pos, limit2,
                        laws)


@njit(cache=True, error_model="numpy")
def touching_walls(wall_hist):
    """(N, W) bool: where the wall spring wall_hist[i, w] is not zero (derived, not state)."""
    n, nw = wall_hist.shape[0], wall_hist.shape[1]
    out = np.zeros((n, nw), dtype=np.bool_)
    for i in range(n):
        for w in range(nw):
            out[i, w] = (wall_hist[i, w, 0] != 0.0) | (wall_hist[i, w, 1] != 0.0) | (wall_hist[i, w, 2] != 0.0)
            for e in range(3, wall_hist.shape[2]):
                out[i, w] |= wall_hist[i, w, e] != 0.0
    return out


@njit(cache=True, error_model="numpy")
def near_walls(ref_pos, radius, wall_motion, wall_point0, wall_normal, skin, dim2, wall_hist, wall_touch, near_count,
               near_wall, first=None):
    """Fill near_count (N,) and near_wall (N, W) with the walls each particle can touch before the next list
    rebuild (row i: near_wall[i, :near_count[i]]), and wall_touch (N, W): True where the wall spring
    wall_hist[i, w] is not zero. The engine keeps the three from rebuild to rebuild (also across calls).

    Between rebuilds no particle is more than skin/2 from its place at the last one (``ref_pos``), so a
    static wall whose gap n·(x_ref − p) exceeds a + skin cannot be reached (in 2D, where centres move in
    the x-y plane only, a + skin |n_xy|: the front and back walls of a one-layer bed at exactly one
    radius are never touched); a moving wall always can.
    Most particles of a bed touch no wall: checking only these (ascending w, as before) spared the
    gather pass five of its six box sides per particle (10,000-sphere bench bed: 0.47 → 0.17 ms of
    wall checks per step measured with none at all). A particle whose wall spring is still set on a wall
    out of reach left that contact earlier: its spring is reset here (the per-step check did it then).
    ``first``: the threads' particle ranges (as for ``gather_forces``; None or two entries: one thread).
    Each particle's rows are its own: the same result on any split.
    """
    nw = wall_normal.shape[0]
    moving = np.empty(nw, dtype=np.bool_)
    reach = np.empty(nw)
    for w in range(nw):
        moving[w] = int(wall_motion[w, 0]) != STATIC
        reach[w] = skin * math.sqrt(wall_normal[w, 0] ** 2 + wall_normal[w, 1] ** 2) if dim2 else skin
    if first is not None and first.shape[0] > 2:
        _near_parallel(first, ref_pos, radius, wall_point0, wall_normal, moving, reach, wall_hist, wall_touch,
                       near_count, near_wall)
    else:
        _near_range(np.int64(0), ref_pos.shape[0], ref_pos, radius, wall_point0, wall_normal, moving, reach, wall_hist,
                    wall_touch, near_count, near_wall)


@njit(cache=True, error_model="numpy", parallel=True)
def _near_parallel(first, ref_pos, radius, wall_point0, wall_normal, moving, reach, wall_hist, wall_touch, near_count,
                   near_wall):
    for k in prange(first.shape[0] - 1):
        _near_range(first[k], first[k + 1], ref_pos, radius, wall_point0, wall_normal, moving, reach, wall_hist,
                    wall_touch, near_count, near_wall)


@njit(cache=True, error_model="numpy")
def _near_range(lo, hi, ref_pos, radius, wall_point0, wall_normal, moving, reach, wall_hist, wall_touch, near_count,
                near_wall):
    """``near_walls`` for particles lo..hi−1."""
    nw = wall_normal.shape[0]
    wide = wall_hist.shape[2] > 3  # an adhesive wall law's column of formed contacts
    for i_ in range(lo, hi):
        i = U(i_)
        x = ref_pos[i, U(0)]
        y = ref_pos[i, U(1)]
        z = ref_pos[i, U(2)]
        a = radius[i]
        c = 0
        for w_ in range(nw):
            w = U(w_)
            gap = ((x - wall_point0[w, U(0)]) * wall_normal[w, U(0)] + (y - wall_point0[w, U(1)]) * wall_normal[w, U(1)]
                   + (z - wall_point0[w, U(2)]) * wall_normal[w, U(2)])
            touch = (wall_hist[i, w, U(0)] != 0.0) | (wall_hist[i, w, U(1)] != 0.0) | (wall_hist[i, w, U(2)] != 0.0)
            for e in range(3, wall_hist.shape[2]):
                touch |= wall_hist[i, w, U(e)] != 0.0
            if moving[w] or gap < a + reach[w]:
                near_wall[i, U(c)] = w
                c += 1
            elif touch:
                wall_hist[i, w, U(0)] = 0.0
                wall_hist[i, w, U(1)] = 0.0
                wall_hist[i, w, U(2)] = 0.0
                if wide:
                    for e in range(3, wall_hist.shape[2]):
                        wall_hist[i, w, U(e)] = 0.0
                touch = False
            wall_touch[i, w] = touch
        near_count[i] = c


@njit(cache=True, error_model="numpy")
def all_walls(n, nw):
    """near_walls' arrays listing every wall for every particle (forces evaluated outside ``advance``)."""
    near_wall = np.empty((n, nw), dtype=np.int64)
    for i in range(n):
        for w in range(nw):
            near_wall[i, w] = w
    return np.full(n, nw, dtype=np.int64), near_wall


@njit(cache=True, error_model="numpy", parallel=True)
def _gather_parallel(pos, vel, omega, radius, mass, species, pw, wall_now, wall_normal, wall_axis, wall_hist, wall_touch,
                     near_count, near_wall, gravity, ext_force, ext_damping, has_ext, dim2, sum_f, sum_c, dt, force, torque,
                     inv_mass, inv_inertia, mode, ref_pos, limit2, first, flat, laws):
    """Thread k gathers particles first[k] … first[k + 1] − 1."""
    moved = 0
    for k in prange(first.shape[0] - 1):
        if flat is not None:
            moved += _gather_range_flat(first[k], first[k + 1], pos, vel, omega, radius, mass, species, pw, wall_now,
                                        wall_normal, wall_axis, wall_hist, wall_touch, near_count, near_wall, gravity,
                                        ext_force, ext_damping, has_ext, dim2, sum_f, sum_c, dt, force, torque, inv_mass,
                                        inv_inertia, mode, ref_pos, limit2, laws)
        else:
            moved += _gather_range(first[k], first[k + 1], pos, vel, omega, radius, mass, species, pw, wall_now,
                                   wall_normal, wall_axis, wall_hist, wall_touch, near_count, near_wall, gravity,
                                   ext_force, ext_damping, has_ext, dim2, sum_f, sum_c, dt, force, torque, inv_mass,
                                   inv_inertia, mode, ref_pos, limit2, laws)
    return moved


@njit(cache=True, error_model="numpy")
def gather_forces(pos, vel, omega, radius, mass, species, pw, wall_motion, wall_point0, wall_normal, wall_axis,
                  wall_hist, wall_touch, near_count, near_wall, gravity, ext_force, ext_damping, has_ext, dim2, sum_f, sum_c,
                  t, dt, force, torque, inv_mass, inv_inertia, mode, ref_pos, limit2, first, flat=None, laws=True):
    """Total force and torque per particle: contact sums, walls, gravity, external force.

    ``mode`` fuses the integrator into the same pass (one memory sweep per step):
    0 forces only (wall history untouched); 1 forces + closing half kick; 2 forces + closing half kick +
    the next step's half kick and drift (``force`` and ``torque`` are then not stored: the next step's
    pass overwrites them unread). ``has_ext`` False: ext_force and ext_damping are zero (not read). Returns how many particles moved more
    than sqrt(limit2) from ``ref_pos`` (mode 2), else 0. Leaves sum_f and sum_c zero.
    ``wall_touch`` (N, W) bool: False where wall_hist[i, w] is zero (filled by near_walls); kept so.
    ``wall_axis``: ``wall_axes(wall_normal)``, made once by the caller (the walls' normals do not change).
    ``near_count``, ``near_wall``: the walls each particle is checked against (``near_walls``; all walls: ``all_walls``).
    ``first``: the particle ranges of the threads, slab_start[thread_blocks(…)] (0 and N: one thread, no
    parallel region). Each particle's arithmetic is the same on any number of threads.
    ``flat``: None, or True for a flat 2D bed (``is_flat`` and ``dim2``) after flat pair forces
    (``_gather_body``); chosen when this is compiled, as ``pair_forces``'s, and so is ``laws``.
    """
    wall_now = walls_now(wall_motion, wall_point0, t)
    n = pos.shape[0]
    if first.shape[0] > 2:
        return _gather_parallel(pos, vel, omega, radius, mass, species, pw, wall_now, wall_normal, wall_axis, wall_hist,
                                wall_touch, near_count, near_wall, gravity, ext_force, ext_damping, has_ext, dim2, sum_f,
                                sum_c, dt, force, torque, inv_mass, inv_inertia, mode, ref_pos, limit2, first, flat,
                                laws)
    if flat is not None:
        return _gather_range_flat(np.int64(0), n, pos, vel, omega, radius, mass, species, pw, wall_now, wall_normal,
                                  wall_axis, wall_hist, wall_touch, near_count, near_wall, gravity, ext_force,
                                  ext_damping, has_ext, dim2, sum_f, sum_c, dt, force, torque, inv_mass, inv_inertia,
                                  mode, ref_pos, limit2, laws)
    return _gather_range(np.int64(0), n, pos, vel, omega, radius, mass, species, pw, wall_now, wall_normal, wall_axis,
                         wall_hist, wall_touch, near_count, near_wall, gravity, ext_force, ext_damping, has_ext, dim2,
                         sum_f, sum_c, dt, force, torque, inv_mass, inv_inertia, mode, ref_pos, limit2, laws)


@njit(cache=True, error_model="numpy")
def _kick_drift(pos, vel, omega, force, torque, inv_mass, inv_inertia, dt, ref_pos, limit2):
    """Half kick then drift; returns how many particles moved more than sqrt(limit2) since the last build.
    (Once per ``advance`` call; the later steps' kicks and drifts are fused into gather_forces. Components
    written out with unsigned indices: a loop over them with signed ones took 25 µs for the 2400 particles
    of the tsuji-jet-background bed, now 5, and a coupled run calls advance every gas step.)"""
    n = pos.shape[0]
    half = 0.5 * dt
    moved = 0
    for i_ in range(n):
        i = U(i_)
        im = inv_mass[i]
        ii = inv_inertia[i]
        # the same expressions as the fused pass of gather_forces (bitwise: a run cut into calls differently)
        vx = vel[i, U(0)] + half * force[i, U(0)] * im
        vy = vel[i, U(1)] + half * force[i, U(1)] * im
        vz = vel[i, U(2)] + half * force[i, U(2)] * im
        vel[i, U(0)] = vx
        vel[i, U(1)] = vy
        vel[i, U(2)] = vz
        omega[i, U(0)] += half * torque[i, U(0)] * ii
        omega[i, U(1)] += half * torque[i, U(1)] * ii
        omega[i, U(2)] += half * torque[i, U(2)] * ii
        px = pos[i, U(0)] + dt * vx
        py = pos[i, U(1)] + dt * vy
        pz = pos[i, U(2)] + dt * vz
        pos[i, U(0)] = px
        pos[i, U(1)] = py
        pos[i, U(2)] = pz
        dx = px - ref_pos[i, U(0)]
        dy = py - ref_pos[i, U(1)]
        dz = pz - ref_pos[i, U(2)]
        moved += dx * dx + dy * dy + dz * dz > limit2
    return moved


@njit(cache=True, error_model="numpy")
def rebuild(pos, radius, skin, dim2, row_start, partner, hist, ref_pos):
    """New Verlet list around the current positions, history carried over, touching pairs first in each row
    (``contacts_first``)."""
    new_start, new_partner, slab_start, slab_members = build_pairs(pos, radius, skin, dim2, partner.shape[0])
    new_hist = carry_history(row_start, partner, hist, new_start, new_partner)
    contacts_first(pos, radius, new_start, new_partner, new_hist)
    ref_pos[:, :] = pos
    return new_start, new_partner, new_hist, slab_start, slab_members


@njit(cache=True, error_model="numpy")
def rebuild_periodic(pos, radius, skin, dim2, row_start, partner, hist, ref_pos, period, box_lo):
    """``rebuild`` for a box with periodic sides (``build_pairs_periodic``, ``contacts_first_periodic``): the
    history of a pair is carried over by the particles' numbers, so a contact keeps its spring across a
    wrap of either particle."""
    new_start, new_partner, slab_start, slab_members = build_pairs_periodic(pos, radius, skin, dim2, period, box_lo)
    new_hist = carry_history(row_start, partner, hist, new_start, new_partner)
    contacts_first_periodic(pos, radius, new_start, new_partner, new_hist, period)
    ref_pos[:, :] = pos
    return new_start, new_partner, new_hist, slab_start, slab_members


@njit(cache=True, error_model="numpy")
def wrap_positions(pos, ref_pos, image, period, box_lo):
    """Bring every centre back into the box along each periodic axis d (``period[d]`` = L_d > 0):
    x_d ← x_d − k L_d with k = floor((x_d − lo_d) / L_d), and image[i, d] += k, so that the unwrapped
    position x_d + image_d L_d is continuous. ``ref_pos`` (the centres at the last list build) moves by the
    same k L_d: the displacement since the build, which decides the next rebuild, is unchanged. The nearest
    image convention (Allen & Tildesley 1987 §1.5.3) then holds for the pair offsets."""
    n = pos.shape[0]
    for d in range(3):
        length = period[d]
        if length > 0.0:
            lo = box_lo[d]
            hi = lo + length
            for i in range(n):
                x = pos[i, d]
                if x >= hi or x < lo:
                    k = math.floor((x - lo) / length)
                    pos[i, d] = x - k * length
                    ref_pos[i, d] -= k * length
                    image[i, d] += np.int64(k)


@njit(cache=True, error_model="numpy")
def _permute(a, order):
    """a[k] = a[order[k]] along the first axis, in place (a 2D and C-contiguous)."""
    old = a.copy()
    for k in range(a.shape[0]):
        src = U(order[U(k)])
        for c in range(a.shape[1]):
            a[U(k), U(c)] = old[src, U(c)]


@njit(cache=True, error_model="numpy")
def reorder(pos, vel, omega, force, torque, radius, mass, inertia, inv_mass, inv_inertia, species, ids, ext_force,
            ext_damping, wall_hist, row_start, partner, hist, skin, dim2, image=None):
    """Renumber the particles in slab and cell order (``cell_order``): every per-particle array is permuted
    in place, the half list renamed (``renumber_pairs``; the caller rebuilds it). Returns (order, row_start,
    partner, hist): new particle k is former particle order[k]; ``ids`` keeps each particle's original number.

    Why: particles numbered at random (a random fill, or a bed after seconds of bubbling) make the pair loop
    read its partners all over memory and, on two threads, make threads working on different slabs write
    into the same cache lines of the force sums (false sharing). In slab order each thread writes its own
    run. Every array is permuted alike, so the physics is unchanged; sums of forces are taken in another
    order, so results differ from an unsorted run at round-off level (and are again the same for any
    number of threads). ``image`` (N, 3) int64, the periodic image counts (``wrap_positions``), is permuted
    alike where given."""
    n = pos.shape[0]
    order = cell_order(pos, radius, skin, dim2)
    new_index = np.empty(n, dtype=np.int64)
    for k in range(n):
        new_index[U(order[U(k)])] = k
    for a in (pos, vel, omega, force, torque, ext_force):
        _permute(a, order)
    for b in (radius, mass, inertia, inv_mass, inv_inertia, ext_damping):
        _permute(b.reshape((n, 1)), order)
    _permute(species.reshape((n, 1)), order)
    _permute(ids.reshape((n, 1)), order)
    if image is not None:
        _permute(image, order)
    _permute(wall_hist.reshape((n, wall_hist.shape[1] * wall_hist.shape[2])), order)
    row_start, partner, hist = renumber_pairs(row_start, partner, hist, new_index)
    return order, row_start, partner, hist


@njit(cache=True, error_model="numpy")
def compute_forces(pos, vel, omega, radius, mass, species, pp, pw, wall_motion, wall_point0, wall_normal,
                   wall_hist, gravity, ext_force, ext_damping, dim2, row_start, partner, hist, slab_start, slab_members,
                   t, dt, update, force, torque, nthreads, period, shapes, flat, laws):
    """Forces and torques at the current state (no integration; history updated only if ``update``).
    ``period`` (3,): the box length along each periodic axis, 0 elsewhere (None: no periodic side). ``shapes``:
    the wall shapes' arrays (``shapes.ShapeSet.kernel_arrays``; their near lists made anew; None: no shape).
    ``flat``: None, or True for a flat 2D bed (``compute_forces_flat``). ``laws``: None where no contact law has
    rolling friction or adhesion. The four choose what is compiled, as ``advance``'s.
    """
    sum_f = np.zeros_like(force)
    sum_c = np.zeros_like(force)
    block = thread_blocks(row_start, slab_start, slab_members, nthreads)
    pair_forces(pos, vel, omega, radius, mass, species, pp, row_start, partner, slab_start, slab_members, hist,
                dt, update, sum_f, sum_c, block, flat, make_work(pp, row_start, hist, slab_start, slab_members, nthreads),
                period, laws)
    if shapes is not None:
        shape_forces(shapes, pos, pos, vel, omega, radius, mass, species, species, np.bool_(True), np.int64(-1), t,
                     dt, update, flat is not None, sum_f, sum_c)
        if has_bodies(shapes):  # the free bodies' force and torque for their first half kick
            body_loads(shapes[3], shapes[18])
    near_count, near_wall = all_walls(pos.shape[0], wall_normal.shape[0])
    # has_ext and mode as run-time values, as advance passes them: a constant argument is a literal type to
    # Numba, which would compile gather_forces once more for it (and with it all it calls)
    has_ext = any_nonzero(ext_force, ext_damping)
    forces_only = np.zeros(1, dtype=np.int64)[0]  # mode 0, an int64 read at run time
    gather_forces(pos, vel, omega, radius, mass, species, pw, wall_motion, wall_point0, wall_normal,
                  wall_axes(wall_normal), wall_hist, touching_walls(wall_hist), near_count, near_wall, gravity, ext_force,
                  ext_damping, has_ext, dim2, sum_f, sum_c, t, dt, force, torque, mass, mass, forces_only, pos, 0.0,
                  slab_start[block], flat, laws)


@njit(cache=True, error_model="numpy")
def advance(pos, vel, omega, force, torque, radius, mass, inv_mass, inv_inertia, species, pp, pw,
            wall_motion, wall_point0, wall_normal, wall_hist, gravity, ext_force, ext_damping, dim2,
            row_start, partner, hist, slab_start, slab_members, ref_pos, skin, step0, dt, nsteps, nthreads,
            inertia, ids, reorder_interval, last_reorder, wall_touch, near_count, near_wall, period, box_lo, image,
            shapes, flat, laws):
    """Run ``nsteps`` velocity-Verlet DEM steps from step ``step0`` (time step0 * dt).

    Order of one step::

        v += F/m dt/2, ω += T/I dt/2          (Sun 2007 eqs 15-16, half kick)
        x += v dt                              (drift)
        wrap the centres into the box along its periodic axes (``wrap_positions``; none: nothing done)
    rebuild the Verlet list if any particle moved more than skin/2
        F, T at the new positions             (eqs 17-24; walls; gravity; external force)
        v += F/m dt/2, ω += T/I dt/2          (half kick)

    The closing half kick of one step, the opening half kick and the drift of the
    next are fused into the force-gathering pass; results are bitwise those of the
    separate passes, so chunking a run differently does not change it.
    The list arrays change size on rebuild, so they are returned with the rebuild count.
    ``nthreads`` > 1 selects the parallel force loops, in contiguous blocks of slabs (``thread_blocks``, made
    anew at each rebuild); the sums are the same.

    Reordering: at a rebuild at least ``reorder_interval`` steps (> 0) after step ``last_reorder``,
    the particles are renumbered in cell order first (``reorder``). Tied to rebuilds and step numbers
    only, so a run gives the same result however it is cut into calls. Also returns the step of the
    last reordering, the number of them in this call and their combined order (new k is former
    order[k]; empty if none).
    ``wall_touch``, ``near_count``, ``near_wall``: the walls within reach (``near_walls``), made anew at each
    rebuild; the caller keeps them between calls (made at set-up and after a restore).
    ``period`` (3,): the box length along each periodic axis, 0 elsewhere (None: no periodic side);
    ``box_lo`` (3,) the box's lower corner; ``image`` (N, 3) int64 the image counts, updated as particles
    wrap. With a periodic axis the list is ``build_pairs_periodic``'s and pair offsets are taken by nearest
    image.
    ``shapes``: the wall shapes' arrays (``shapes.ShapeSet.kernel_arrays``; None: no shape), their forces added
    once a step (``_shape_kernels.shape_step``); free bodies among them take the same half kicks and drift as
    the particles (``bodies_kick_drift`` at the start, ``bodies_step`` after each step's forces).
    ``flat``: None, or True for a flat 2D bed (``dim2`` and ``is_flat``; a flat bed stays flat: in 2D gather_forces
    zeroes F_z and T_x, T_y at every step).
    ``laws``: None where no contact law of the run (pairs or walls) has rolling friction or adhesion (no row of
    either table is ``extended``); else any value, the tables' flags then choosing as the run goes.

    ``period``, ``shapes``, ``flat`` and ``laws`` choose what is compiled, down to the slab and gather variants: Numba
    leaves out of a compilation a branch that an ``arg is None`` test rules out, with the kernels it calls,
    where the argument's type is None or a literal (``Literal[bool](True)``: a constant passed by another
    compiled function, ``advance_flat``), not where it is a run-time value (``bool``, an array), whose
    compilation keeps both branches. So a run of a flat 2D bed (``advance_flat``) or of a bed that is not
    flat (``flat`` None), without periodic sides, wall shapes or extended laws, compiles only the variants it
    uses (``benchmarks/compile_time.py``).
    """
    limit2 = (0.5 * skin) ** 2
    update = nsteps > 0  # a run-time True, as compute_forces passes it (a literal would compile pair_forces twice)
    sum_f = np.zeros_like(force)
    sum_c = np.zeros_like(force)
    rebuilds = 0
    reorders = 0
    combined = np.empty(0, dtype=np.int64)
    if nsteps <= 0:
        return row_start, partner, hist, slab_start, slab_members, rebuilds, last_reorder, 0, combined
    wall_axis = wall_axes(wall_normal)
    has_ext = any_nonzero(ext_force, ext_damping)
    moved = _kick_drift(pos, vel, omega, force, torque, inv_mass, inv_inertia, dt, ref_pos, limit2)
    bodies = False
    if shapes is not None:
        bodies = has_bodies(shapes)
        if bodies:
            bodies_kick_drift(shapes, dt)
    block = thread_blocks(row_start, slab_start, slab_members, nthreads)
    first = slab_start[block]
    work = make_work(pp, row_start, hist, slab_start, slab_members, nthreads)
    for s in range(nsteps):
        t = (step0 + s + 1) * dt
        if period is not None:
            wrap_positions(pos, ref_pos, image, period, box_lo)
        if moved > 0:
            if reorder_interval > 0 and step0 + s - last_reorder >= reorder_interval:
                order, row_start, partner, hist = reorder(
                    pos, vel, omega, force, torque, radius, mass, inertia, inv_mass, inv_inertia, species, ids,
                    ext_force, ext_damping, wall_hist, row_start, partner, hist, skin, dim2, image)
                combined = order if combined.shape[0] == 0 else combined[order]
                last_reorder = step0 + s
                reorders += 1
            if period is not None:
                row_start, partner, hist, slab_start, slab_members = rebuild_periodic(
                    pos, radius, skin, dim2, row_start, partner, hist, ref_pos, period, box_lo)
            else:
                row_start, partner, hist, slab_start, slab_members = rebuild(
                    pos, radius, skin, dim2, row_start, partner, hist, ref_pos)
            block = thread_blocks(row_start, slab_start, slab_members, nthreads)
            first = slab_start[block]
            work = make_work(pp, row_start, hist, slab_start, slab_members, nthreads)
            near_walls(ref_pos, radius, wall_motion, wall_point0, wall_normal, skin, dim2, wall_hist, wall_touch,
                       near_count, near_wall, first)
            rebuilds += 1
        pair_forces(pos, vel, omega, radius, mass, species, pp, row_start, partner, slab_start, slab_members, hist,
                    dt, update, sum_f, sum_c, block, flat, work, period, laws)
        if shapes is not None:
            shape_step(shapes, pos, ref_pos, vel, omega, radius, mass, species, ids, moved > 0, last_reorder, t, dt,
                       update, flat is not None, sum_f, sum_c)
        mode = 2 if s < nsteps - 1 else 1
        moved = gather_forces(pos, vel, omega, radius, mass, species, pw, wall_motion, wall_point0, wall_normal,
                              wall_axis, wall_hist, wall_touch, near_count, near_wall, gravity, ext_force, ext_damping,
                              has_ext, dim2, sum_f, sum_c, t, dt, force, torque, inv_mass, inv_inertia, mode, ref_pos, limit2,
                              first, flat, laws)
        if shapes is not None:
            if bodies:  # the free bodies' kicks and drift, as the particles' in gather_forces
                bodies_step(shapes, dt, mode)
    return row_start, partner, hist, slab_start, slab_members, rebuilds, last_reorder, reorders, combined


@njit(cache=True, error_model="numpy")
def advance_flat(pos, vel, omega, force, torque, radius, mass, inv_mass, inv_inertia, species, pp, pw,
                 wall_motion, wall_point0, wall_normal, wall_hist, gravity, ext_force, ext_damping, dim2,
                 row_start, partner, hist, slab_start, slab_members, ref_pos, skin, step0, dt, nsteps, nthreads,
                 inertia, ids, reorder_interval, last_reorder, wall_touch, near_count, near_wall, period, box_lo, image,
                 shapes, laws):
    """``advance`` of a flat 2D bed: ``flat`` passed as a constant, so that it is compiled without the
    variants of beds that are not flat."""
    return advance(pos, vel, omega, force, torque, radius, mass, inv_mass, inv_inertia, species, pp, pw,
                   wall_motion, wall_point0, wall_normal, wall_hist, gravity, ext_force, ext_damping, dim2,
                   row_start, partner, hist, slab_start, slab_members, ref_pos, skin, step0, dt, nsteps, nthreads,
                   inertia, ids, reorder_interval, last_reorder, wall_touch, near_count, near_wall, period, box_lo,
                   image, shapes, True, laws)


@njit(cache=True, error_model="numpy")
def compute_forces_flat(pos, vel, omega, radius, mass, species, pp, pw, wall_motion, wall_point0, wall_normal,
                        wall_hist, gravity, ext_force, ext_damping, dim2, row_start, partner, hist, slab_start,
                        slab_members, t, dt, update, force, torque, nthreads, period, shapes, laws):
    """``compute_forces`` of a flat 2D bed (as ``advance_flat``)."""
    compute_forces(pos, vel, omega, radius, mass, species, pp, pw, wall_motion, wall_point0, wall_normal,
                   wall_hist, gravity, ext_force, ext_damping, dim2, row_start, partner, hist, slab_start, slab_members,
                   t, dt, update, force, torque, nthreads, period, shapes, True, laws)
