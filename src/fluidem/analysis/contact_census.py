"""Contact numbers of a particle snapshot under the readings of Sun et al. 2007's definition, and by region.

Sun 2007 §4: "The bulk coordination number is defined as the average number of contacting neighbors of a
particle" (Fig 5); N_c of a particle "is defined as the number of contacting neighbors of one particle"; the
multicontact ratio is "the ratio of particles in multicontacts to the total number of particles in contact"
(Fig 11), a particle in multicontact when N_c > 1. The text leaves open what makes two particles "contacting"
and whether a wall is a neighbour. The readings here, from positions and velocities alone (a snapshot of
``particles.h5``):

- ``overlap``: particle pairs with overlap δ = a_i + a_j − r_ij > 0, walls not neighbours (the run's own
  ``coordination`` probe, ``analysis.fluidised.contact_numbers``);
- ``force``: pairs with δ > 0 whose normal force pushes them apart, F_n = k_n δ − η_n v_ij·n_ij > 0
  (Sun 2007 eq. 21 with f = 1, n_ij from j to i, v_ij = v_i − v_j): a contact that carries a repulsive
  contact force (a separating pair whose dashpot outweighs its spring pulls and is left out);
- ``walls``: ``overlap`` plus one for each wall plane of an axis-aligned box a particle overlaps.

Orchestration over arrays (scipy's k-d tree for the pairs, ``numpy.bincount`` for the counts).
"""
from __future__ import annotations

import math

import numpy as np
from scipy.spatial import cKDTree


def touching_pairs(position, radius):
    """(i, j, overlap [m]) of the particle pairs i < j with overlap δ = a_i + a_j − |r_i − r_j| > 0 (Sun 2007
    eq. 17); ``position`` (N, 3) [m], ``radius`` (N,) [m]."""
    pos = np.asarray(position, float)
    rad = np.asarray(radius, float)
    if pos.shape[0] < 2:
        empty = np.zeros(0, dtype=np.int64)
        return empty, empty, np.zeros(0)
    pairs = cKDTree(pos).query_pairs(2.0 * float(rad.max()), output_type="ndarray")
    i, j = pairs[:, 0].astype(np.int64), pairs[:, 1].astype(np.int64)
    overlap = rad[i] + rad[j] - np.linalg.norm(pos[i] - pos[j], axis=1)
    keep = overlap > 0.0
    return i[keep], j[keep], overlap[keep]


def normal_force(position, velocity, i, j, overlap, stiffness, damping):
    """Signed normal force of each pair [N], positive repulsive: F_n = k_n δ − η_n (v_i − v_j)·n_ij, n_ij the
    unit vector from j to i (Sun 2007 eq. 21, linear spring–dashpot, f = 1)."""
    pos = np.asarray(position, float)
    vel = np.asarray(velocity, float)
    d = pos[i] - pos[j]
    n = d / np.linalg.norm(d, axis=1)[:, None]
    vn = np.einsum("ck,ck->c", vel[i] - vel[j], n)
    return stiffness * np.asarray(overlap, float) - damping * vn


def box_wall_contacts(position, radius, lower, upper, axes=(0, 1)):
    """Walls each particle overlaps, (N,) int: one for each plane x_a = lower[a] and x_a = upper[a], a in
    ``axes``, that lies closer to its centre than its radius."""
    pos = np.asarray(position, float)
    rad = np.asarray(radius, float)
    count = np.zeros(pos.shape[0], dtype=np.int64)
    for a in axes:  # two planes per axis
        count += (pos[:, a] - lower[a] < rad).astype(np.int64) + (upper[a] - pos[:, a] < rad).astype(np.int64)
    return count


def contact_numbers(n, i, j):
    """N_c of each of ``n`` particles, (n,) int: the number of listed pairs (i, j) it belongs to."""
    return (np.bincount(np.asarray(i, np.int64), minlength=n)
            + np.bincount(np.asarray(j, np.int64), minlength=n)).astype(np.int64)


def bulk(nc) -> tuple[float, float]:
    """(bulk coordination number: the mean of N_c over all particles (Sun 2007 Fig 5); multicontact ratio:
    particles with N_c > 1 over particles with N_c ≥ 1 (Fig 11), NaN when none touch)."""
    nc = np.asarray(nc)
    if nc.size == 0:
        return math.nan, math.nan
    touching = int(np.count_nonzero(nc >= 1))
    return float(nc.mean()), (float(np.count_nonzero(nc >= 2) / touching) if touching else math.nan)


def census(position, velocity, radius, stiffness, damping, lower, upper, axes=(0, 1)) -> dict[str, np.ndarray]:
    """N_c of every particle, (N,) int, under each reading of the module docstring: ``overlap``, ``force``
    (``stiffness`` k_n [N/m], ``damping`` η_n [N s/m] of the particle pairs) and ``walls`` (the box from
    ``lower`` to ``upper`` [m] along ``axes``)."""
    n = np.asarray(position).shape[0]
    i, j, ov = touching_pairs(position, radius)
    pushing = normal_force(position, velocity, i, j, ov, stiffness, damping) > 0.0
    nc = contact_numbers(n, i, j)
    return {"overlap": nc,
            "force": contact_numbers(n, i[pushing], j[pushing]),
            "walls": nc + box_wall_contacts(position, radius, lower, upper, axes)}
