"""Compiled soft-sphere DEM: forces and velocity-Verlet sub-steps (Sun 2007 eqs 15–24).

``advance`` runs many DEM steps in one call: half kick, drift, Verlet-list check
and rebuild, forces, half kick. Pair forces are computed once per pair into
per-pair buffers and gathered per particle (no write races, thread-count
independent sums).
"""
import math

import numpy as np
from numba import njit, prange

from ._neighbours_kernels import build_pairs, carry_history
from .contact._dispatch import contact_force

# wall motion kinds (walls.py builds the table)
STATIC, CONSTANT_VELOCITY, OSCILLATING = 0, 1, 2


@njit(cache=True)
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


@njit(cache=True, parallel=True)
def pair_forces(pos, vel, omega, radius, mass, species, pp, row_start, partner, hist, dt, update,
                pair_f, pair_c):
    """Per-pair contact force on i (pair_f) and −n × F_t (pair_c, torque per unit lever arm)."""
    n = pos.shape[0]
    for i in prange(n):
        for p in range(row_start[i], row_start[i + 1]):
            j = partner[p]
            rx = pos[i, 0] - pos[j, 0]
            ry = pos[i, 1] - pos[j, 1]
            rz = pos[i, 2] - pos[j, 2]
            r2 = rx * rx + ry * ry + rz * rz
            cut = radius[i] + radius[j]
            if r2 >= cut * cut:
                hist[p, 0] = 0.0
                hist[p, 1] = 0.0
                hist[p, 2] = 0.0
                pair_f[p, 0] = 0.0
                pair_f[p, 1] = 0.0
                pair_f[p, 2] = 0.0
                pair_c[p, 0] = 0.0
                pair_c[p, 1] = 0.0
                pair_c[p, 2] = 0.0
                continue
            r = math.sqrt(r2)
            nx = rx / r
            ny = ry / r
            nz = rz / r
            m_eff = mass[i] * mass[j] / (mass[i] + mass[j])
            r_eff = radius[i] * radius[j] / (radius[i] + radius[j])
            wx = radius[i] * omega[i, 0] + radius[j] * omega[j, 0]
            wy = radius[i] * omega[i, 1] + radius[j] * omega[j, 1]
            wz = radius[i] * omega[i, 2] + radius[j] * omega[j, 2]
            fn, ftx, fty, ftz, hx, hy, hz = contact_force(
                pp[species[i], species[j]], cut - r, nx, ny, nz,
                vel[i, 0] - vel[j, 0], vel[i, 1] - vel[j, 1], vel[i, 2] - vel[j, 2],
                wx, wy, wz, m_eff, r_eff, dt, hist[p, 0], hist[p, 1], hist[p, 2], update)
            hist[p, 0] = hx
            hist[p, 1] = hy
            hist[p, 2] = hz
            pair_f[p, 0] = fn * nx + ftx
            pair_f[p, 1] = fn * ny + fty
            pair_f[p, 2] = fn * nz + ftz
            # torque on i: (−a_i n) × F_t = a_i (−n × F_t); on j: (a_j n) × (−F_t) = a_j (−n × F_t)  (Sun 2007 eq. 24)
            pair_c[p, 0] = -(ny * ftz - nz * fty)
            pair_c[p, 1] = -(nz * ftx - nx * ftz)
            pair_c[p, 2] = -(nx * fty - ny * ftx)


@njit(cache=True)
def wall_contact(i, w, pos, vel, omega, radius, mass, species, pw, wall_motion, wall_point0, wall_normal,
                 wall_hist, t, dt, update):
    """(overlap, fx, fy, fz, tx, ty, tz) of particle i on wall w (a plane; infinite mass)."""
    px, py, pz, wvx, wvy, wvz = wall_state(wall_motion, wall_point0, w, t)
    nx, ny, nz = wall_normal[w, 0], wall_normal[w, 1], wall_normal[w, 2]
    gap = (pos[i, 0] - px) * nx + (pos[i, 1] - py) * ny + (pos[i, 2] - pz) * nz
    overlap = radius[i] - gap
    if overlap <= 0.0:
        if update:
            wall_hist[i, w, 0] = 0.0
            wall_hist[i, w, 1] = 0.0
            wall_hist[i, w, 2] = 0.0
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    a = radius[i]
    fn, ftx, fty, ftz, hx, hy, hz = contact_force(
        pw[species[i], w], overlap, nx, ny, nz,
        vel[i, 0] - wvx, vel[i, 1] - wvy, vel[i, 2] - wvz,
        a * omega[i, 0], a * omega[i, 1], a * omega[i, 2], mass[i], a, dt,
        wall_hist[i, w, 0], wall_hist[i, w, 1], wall_hist[i, w, 2], update)
    if update:
        wall_hist[i, w, 0] = hx
        wall_hist[i, w, 1] = hy
        wall_hist[i, w, 2] = hz
    tqx = -a * (ny * ftz - nz * fty)
    tqy = -a * (nz * ftx - nx * ftz)
    tqz = -a * (nx * fty - ny * ftx)
    return overlap, fn * nx + ftx, fn * ny + fty, fn * nz + ftz, tqx, tqy, tqz


@njit(cache=True, parallel=True)
def gather_forces(pos, vel, omega, radius, mass, species, pw, wall_motion, wall_point0, wall_normal,
                  wall_hist, gravity, ext_force, dim2, row_start, partner, trans_start, trans_pair,
                  pair_f, pair_c, t, dt, force, torque):
    """Total force and torque per particle: contacts (gathered), walls, gravity, external force."""
    n = pos.shape[0]
    nw = wall_normal.shape[0]
    for i in prange(n):
        fx = mass[i] * gravity[0] + ext_force[i, 0]
        fy = mass[i] * gravity[1] + ext_force[i, 1]
        fz = mass[i] * gravity[2] + ext_force[i, 2]
        cx = 0.0
        cy = 0.0
        cz = 0.0
        for p in range(row_start[i], row_start[i + 1]):
            fx += pair_f[p, 0]
            fy += pair_f[p, 1]
            fz += pair_f[p, 2]
            cx += pair_c[p, 0]
            cy += pair_c[p, 1]
            cz += pair_c[p, 2]
        for q in range(trans_start[i], trans_start[i + 1]):
            p = trans_pair[q]
            fx -= pair_f[p, 0]
            fy -= pair_f[p, 1]
            fz -= pair_f[p, 2]
            cx += pair_c[p, 0]
            cy += pair_c[p, 1]
            cz += pair_c[p, 2]
        a = radius[i]
        tx = a * cx
        ty = a * cy
        tz = a * cz
        for w in range(nw):
            ov, wfx, wfy, wfz, wtx, wty, wtz = wall_contact(
                i, w, pos, vel, omega, radius, mass, species, pw, wall_motion, wall_point0, wall_normal,
                wall_hist, t, dt, True)
            if ov > 0.0:
                fx += wfx
                fy += wfy
                fz += wfz
                tx += wtx
                ty += wty
                tz += wtz
        if dim2:
            fz = 0.0
            tx = 0.0
            ty = 0.0
        force[i, 0] = fx
        force[i, 1] = fy
        force[i, 2] = fz
        torque[i, 0] = tx
        torque[i, 1] = ty
        torque[i, 2] = tz


@njit(cache=True, parallel=True)
def _kick(vel, omega, force, torque, inv_mass, inv_inertia, half_dt):
    n = vel.shape[0]
    for i in prange(n):
        for d in range(3):
            vel[i, d] += half_dt * force[i, d] * inv_mass[i]
            omega[i, d] += half_dt * torque[i, d] * inv_inertia[i]


@njit(cache=True, parallel=True)
def _drift(pos, vel, dt, ref_pos, limit2):
    """Move particles; return how many moved more than sqrt(limit2) since the last list build."""
    n = pos.shape[0]
    moved = 0
    for i in prange(n):
        d2 = 0.0
        for d in range(3):
            pos[i, d] += dt * vel[i, d]
            dd = pos[i, d] - ref_pos[i, d]
            d2 += dd * dd
        if d2 > limit2:
            moved += 1
    return moved


@njit(cache=True)
def rebuild(pos, radius, skin, dim2, row_start, partner, hist, ref_pos):
    """New Verlet list around the current positions, history carried over."""
    new_start, new_partner, trans_start, trans_pair = build_pairs(pos, radius, skin, dim2)
    new_hist = carry_history(row_start, partner, hist, new_start, new_partner)
    ref_pos[:, :] = pos
    return new_start, new_partner, new_hist, trans_start, trans_pair


@njit(cache=True)
def compute_forces(pos, vel, omega, radius, mass, species, pp, pw, wall_motion, wall_point0, wall_normal,
                   wall_hist, gravity, ext_force, dim2, row_start, partner, hist, trans_start, trans_pair,
                   pair_f, pair_c, t, dt, update, force, torque):
    pair_forces(pos, vel, omega, radius, mass, species, pp, row_start, partner, hist, dt, update, pair_f, pair_c)
    gather_forces(pos, vel, omega, radius, mass, species, pw, wall_motion, wall_point0, wall_normal,
                  wall_hist, gravity, ext_force, dim2, row_start, partner, trans_start, trans_pair,
                  pair_f, pair_c, t, dt, force, torque)


@njit(cache=True)
def advance(pos, vel, omega, force, torque, radius, mass, inv_mass, inv_inertia, species, pp, pw,
            wall_motion, wall_point0, wall_normal, wall_hist, gravity, ext_force, dim2,
            row_start, partner, hist, trans_start, trans_pair, ref_pos, skin, step0, dt, nsteps):
    """Run ``nsteps`` velocity-Verlet DEM steps from step ``step0`` (time step0 * dt).

    Order of one step::

        v += F/m dt/2, ω += T/I dt/2          (Sun 2007 eqs 15-16, half kick)
        x += v dt                              (drift)
        rebuild the Verlet list if any particle moved more than skin/2
        F, T at the new positions             (eqs 17-24; walls; gravity; external force)
        v += F/m dt/2, ω += T/I dt/2          (half kick)

    The list arrays change size on rebuild, so they are returned with the rebuild count.
    """
    half = 0.5 * dt
    limit2 = (0.5 * skin) ** 2
    npairs = partner.shape[0]
    pair_f = np.zeros((npairs, 3))
    pair_c = np.zeros((npairs, 3))
    rebuilds = 0
    for s in range(nsteps):
        t = (step0 + s + 1) * dt
        _kick(vel, omega, force, torque, inv_mass, inv_inertia, half)
        moved = _drift(pos, vel, dt, ref_pos, limit2)
        if moved > 0:
            row_start, partner, hist, trans_start, trans_pair = rebuild(
                pos, radius, skin, dim2, row_start, partner, hist, ref_pos)
            rebuilds += 1
            if partner.shape[0] != pair_f.shape[0]:
                pair_f = np.zeros((partner.shape[0], 3))
                pair_c = np.zeros((partner.shape[0], 3))
        compute_forces(pos, vel, omega, radius, mass, species, pp, pw, wall_motion, wall_point0, wall_normal,
                       wall_hist, gravity, ext_force, dim2, row_start, partner, hist, trans_start, trans_pair,
                       pair_f, pair_c, t, dt, True, force, torque)
        _kick(vel, omega, force, torque, inv_mass, inv_inertia, half)
    return row_start, partner, hist, trans_start, trans_pair, rebuilds
