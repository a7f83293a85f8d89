"""Compiled contact statistics (read-only): contacts over the Verlet list, forces of the particles on the walls."""
import numpy as np
from numba import njit

from ..particles._neighbours_kernels import nearest_image
from ..particles._softsphere_kernels import wall_contact, walls_now

NO_PERIOD = np.zeros(3)  # ``period`` of a box without periodic sides


@njit(cache=True, error_model="numpy")
def contact_counts(pos, radius, row_start, partner, period):
    """(contacts per particle (N,) int64, number of contacts, largest overlap / diameter [-]). ``period`` (3,):
    the box length along each periodic axis, 0 elsewhere; offsets by nearest image there
    (``_neighbours_kernels.nearest_image``, which leaves an offset along a non-periodic axis as it is)."""
    n = pos.shape[0]
    per = np.zeros(n, dtype=np.int64)
    total = 0
    worst = 0.0
    for i in range(n):
        for p in range(row_start[i], row_start[i + 1]):
            j = partner[p]
            r2 = 0.0
            for d in range(3):
                r2 += nearest_image(pos[i, d] - pos[j, d], period[d]) ** 2
            cut = radius[i] + radius[j]
            if r2 < cut * cut:
                per[i] += 1
                per[j] += 1
                total += 1
                ov = (cut - np.sqrt(r2)) / (2.0 * min(radius[i], radius[j]))
                if ov > worst:
                    worst = ov
    return per, total, worst


@njit(cache=True, error_model="numpy")
def wall_totals(pos, vel, omega, radius, mass, species, pw, motion, point0, normal, wall_hist, t, dt):
    """Force of the particles on each wall plane at time ``t`` [s], (W, 3) [N]: minus the sum of the
    wall contact forces (``particles._softsphere_kernels.wall_contact``) on the particles touching it."""
    nw = normal.shape[0]
    out = np.zeros((nw, 3))
    now = walls_now(motion, point0, t)
    for i in range(pos.shape[0]):
        for w in range(nw):
            ov, fx, fy, fz, _, _, _ = wall_contact(i, w, pos, vel, omega, radius, mass, species, pw, now,
                                                   normal, wall_hist, dt, False)
            if ov > 0.0:
                out[w, 0] -= fx  # force of the particles on the wall
                out[w, 1] -= fy
                out[w, 2] -= fz
    return out
