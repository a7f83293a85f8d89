"""CUDA kernels of the soft-sphere step: contact and wall forces, and the velocity-Verlet kicks and drift.

The GPU sibling of ``_softsphere_kernels``, one thread per particle. ``pair_and_wall_forces`` walks the
particle's row of the full list (``_neighbours_cuda``) and its walls and writes its own force, torque and
springs only: each contact is evaluated from both ends (the law is odd in the normal and the relative
velocity, so the two ends get equal and opposite forces to the last bit), and nothing needs atomics.
The law is the CPU's own code (``contact._dispatch_cuda``: ``_dispatch.contact_force`` and the registry's
switch over models, compiled from their Python source), as is the walls' motion (``wall_state``).

The step is the CPU's (``_softsphere_kernels.advance``) in separate passes, since a thread cannot move its
particle while others still read it::

    kick_drift(kicks=1, drift)          v += F/m dt/2, ω += T/I dt/2; x += v dt (Sun 2007 eqs 15-16)
    [list rebuild if any particle moved more than skin/2]
    pair_and_wall_forces                eqs 17-24; walls; gravity; external force − c v
    kick_drift(kicks=2, drift)          the closing half kick, the next step's half kick and drift
    ...
    kick_drift(kicks=1, no drift)       the last step's closing half kick

with the same expressions (two half kicks are two additions), so the results are the CPU's to round-off
(sums taken in another order).
"""
import math

from numba import cuda

from . import _softsphere_kernels as K
from .contact._dispatch_cuda import cached_kernel, contact_force, device_function

THREADS = 128  # threads per block of the per-particle kernels

wall_state = device_function(K.wall_state)  # wall reference point and velocity at time t


@cuda.jit(device=True)
def _row(table, a, b):
    """Row (a, b) of a packed contact table as a tuple of its 8 slots (``contact/base.py``)."""
    return (table[a, b, 0], table[a, b, 1], table[a, b, 2], table[a, b, 3], table[a, b, 4], table[a, b, 5],
            table[a, b, 6], table[a, b, 7])


@cached_kernel
def pair_and_wall_forces(pos, vel, omega, radius, mass, species, pp, nbr, count, hist, pw, wall_motion, wall_point0,
                         wall_normal, nw, wall_hist, wall_touch, gravity, ext_force, ext_damping, has_ext, dim2, t, dt,
                         update, force, torque):
    """Total force and torque on each particle at time t: contacts of its row, walls, gravity, external.

    Contacts (Sun 2007 eqs 17-24; lever arms a_i r/(a_i + a_j) as the CPU's ``_pair_kernels._law``): a listed
    pair touches when r² < (a_i + a_j)²; the spring of a pair that does not touch is reset. Walls: planes of
    infinite mass, the first ``nw`` rows of the wall tables, as the CPU's ``_gather_body``; ``wall_hist``
    (W, 3, N) their springs, ``wall_touch`` (W, N) uint8 1 where a spring is set. The external force is ext_force − c v at the current velocity (``has_ext``
    False: not read). In 2D (``dim2``) F_z and T_x, T_y are zero. ``update`` False leaves the springs as
    they are (force evaluation for analysis)."""
    i = cuda.grid(1)
    if i >= pos.shape[0]:
        return
    xi = pos[i, 0]
    yi = pos[i, 1]
    zi = pos[i, 2]
    vxi = vel[i, 0]
    vyi = vel[i, 1]
    vzi = vel[i, 2]
    wxi = omega[i, 0]
    wyi = omega[i, 1]
    wzi = omega[i, 2]
    ai = radius[i]
    mi = mass[i]
    si = species[i]
    fx = 0.0
    fy = 0.0
    fz = 0.0
    cx = 0.0
    cy = 0.0
    cz = 0.0
    for k in range(count[i]):
        j = nbr[k, i]
        rx = xi - pos[j, 0]
        ry = yi - pos[j, 1]
        rz = zi - pos[j, 2]
        aj = radius[j]
        cut = ai + aj
        r2 = rx * rx + ry * ry + rz * rz
        if not r2 < cut * cut:
            if (hist[0, k, i] != 0.0) or (hist[1, k, i] != 0.0) or (hist[2, k, i] != 0.0):  # the contact ended
                hist[0, k, i] = 0.0
                hist[1, k, i] = 0.0
                hist[2, k, i] = 0.0
            continue
        r = math.sqrt(r2)
        inv_r = 1.0 / r
        nx = rx * inv_r
        ny = ry * inv_r
        nz = rz * inv_r
        mj = mass[j]
        m_eff = mi * mj / (mi + mj)
        r_eff = ai * aj / (ai + aj)
        lever = r / cut
        fn, ftx, fty, ftz, hx, hy, hz = contact_force(
            _row(pp, si, species[j]), cut - r, nx, ny, nz, vxi - vel[j, 0], vyi - vel[j, 1], vzi - vel[j, 2],
            (ai * wxi + aj * omega[j, 0]) * lever, (ai * wyi + aj * omega[j, 1]) * lever,
            (ai * wzi + aj * omega[j, 2]) * lever, m_eff, r_eff, dt, hist[0, k, i], hist[1, k, i], hist[2, k, i],
            update)
        fx += fn * nx + ftx
        fy += fn * ny + fty
        fz += fn * nz + ftz
        cx += -(ny * ftz - nz * fty) * lever
        cy += -(nz * ftx - nx * ftz) * lever
        cz += -(nx * fty - ny * ftx) * lever
        hist[0, k, i] = hx
        hist[1, k, i] = hy
        hist[2, k, i] = hz
    for w in range(nw):
        px, py, pz, wvx, wvy, wvz = wall_state(wall_motion, wall_point0, w, t)
        nx = wall_normal[w, 0]
        ny = wall_normal[w, 1]
        nz = wall_normal[w, 2]
        overlap = ai - ((xi - px) * nx + (yi - py) * ny + (zi - pz) * nz)
        if overlap <= 0.0:
            if update and wall_touch[w, i] != 0:  # the wall contact ended: its spring is reset
                wall_hist[w, 0, i] = 0.0
                wall_hist[w, 1, i] = 0.0
                wall_hist[w, 2, i] = 0.0
                wall_touch[w, i] = 0
            continue
        fn, ftx, fty, ftz, hx, hy, hz = contact_force(
            _row(pw, si, w), overlap, nx, ny, nz, vxi - wvx, vyi - wvy, vzi - wvz, ai * wxi, ai * wyi, ai * wzi, mi,
            ai, dt, wall_hist[w, 0, i], wall_hist[w, 1, i], wall_hist[w, 2, i], update)
        if update:
            wall_hist[w, 0, i] = hx
            wall_hist[w, 1, i] = hy
            wall_hist[w, 2, i] = hz
            wall_touch[w, i] = 1
        fx += fn * nx + ftx
        fy += fn * ny + fty
        fz += fn * nz + ftz
        cx -= ny * ftz - nz * fty
        cy -= nz * ftx - nx * ftz
        cz -= nx * fty - ny * ftx
    tx = mi * gravity[0]
    ty = mi * gravity[1]
    tz = mi * gravity[2]
    if has_ext:
        c = ext_damping[i]
        tx += ext_force[i, 0] - c * vxi
        ty += ext_force[i, 1] - c * vyi
        tz += ext_force[i, 2] - c * vzi
    tx += fx
    ty += fy
    tz += fz
    if dim2:
        tz = 0.0
        cx = 0.0
        cy = 0.0
    force[i, 0] = tx
    force[i, 1] = ty
    force[i, 2] = tz
    torque[i, 0] = ai * cx
    torque[i, 1] = ai * cy
    torque[i, 2] = ai * cz


@cached_kernel
def kick_drift(pos, vel, omega, force, torque, inv_mass, inv_inertia, dt, kicks, drift, ref_pos, limit2, moved):
    """``kicks`` half kicks v += F/m dt/2, ω += T/I dt/2 (each a separate addition, as the CPU's fused pass),
    then, if ``drift``, x += v dt and moved[0] = 1 where a particle is more than sqrt(limit2) from
    ``ref_pos`` (its place at the last list build)."""
    i = cuda.grid(1)
    if i >= pos.shape[0]:
        return
    half = 0.5 * dt
    im = inv_mass[i]
    ii = inv_inertia[i]
    ax = half * force[i, 0] * im
    ay = half * force[i, 1] * im
    az = half * force[i, 2] * im
    bx = half * torque[i, 0] * ii
    by = half * torque[i, 1] * ii
    bz = half * torque[i, 2] * ii
    vx = vel[i, 0] + ax
    vy = vel[i, 1] + ay
    vz = vel[i, 2] + az
    wx = omega[i, 0] + bx
    wy = omega[i, 1] + by
    wz = omega[i, 2] + bz
    if kicks == 2:
        vx += ax
        vy += ay
        vz += az
        wx += bx
        wy += by
        wz += bz
    vel[i, 0] = vx
    vel[i, 1] = vy
    vel[i, 2] = vz
    omega[i, 0] = wx
    omega[i, 1] = wy
    omega[i, 2] = wz
    if drift:
        px = pos[i, 0] + dt * vx
        py = pos[i, 1] + dt * vy
        pz = pos[i, 2] + dt * vz
        pos[i, 0] = px
        pos[i, 1] = py
        pos[i, 2] = pz
        dx = px - ref_pos[i, 0]
        dy = py - ref_pos[i, 1]
        dz = pz - ref_pos[i, 2]
        if dx * dx + dy * dy + dz * dz > limit2:
            moved[0] = 1


@cached_kernel
def all_finite(pos, bad):
    """bad[0] = 1 if any position is not finite."""
    i = cuda.grid(1)
    if i >= pos.shape[0]:
        return
    if not (math.isfinite(pos[i, 0]) and math.isfinite(pos[i, 1]) and math.isfinite(pos[i, 2])):
        bad[0] = 1
