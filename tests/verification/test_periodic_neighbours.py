"""Neighbour lists of boxes with periodic sides against an O(N²) nearest-image enumeration.

``build_pairs_periodic`` must list every pair whose nearest images are closer than a_i + a_j + skin exactly
once and no other, on random packings in 2D and 3D with one, two and three periodic axes (both sides
evaluate the same floating-point expressions, ``nearest_image`` of x_i − x_j, so the sets are equal, not
close). The pair loops run even slabs, then odd ones, in parallel: every pair must join its owner's slab
to the same slab or the next one round the seam, which is checked too.
"""
from __future__ import annotations

import numpy as np
import pytest
from numba import njit

from fluidem.particles._neighbours_kernels import build_pairs_periodic, contacts_first_periodic, nearest_image



@njit(error_model="numpy")
def brute_force_periodic(pos, radius, skin, period):
    """All pairs i < j with |r_ij| < a_i + a_j + skin, r_ij by nearest image on the periodic axes, O(N²)."""
    n = pos.shape[0]
    out = []
    for i in range(n):
        for j in range(i + 1, n):
            rx = nearest_image(pos[i, 0] - pos[j, 0], period[0])
            ry = nearest_image(pos[i, 1] - pos[j, 1], period[1])
            rz = nearest_image(pos[i, 2] - pos[j, 2], period[2])
            cut = radius[i] + radius[j] + skin
            if rx * rx + ry * ry + rz * rz < cut * cut:
                out.append((i, j))
    return out


def periodic_packing(seed, n, dim2, axes, narrow=None, solid_fraction=0.3):
    """Random polydisperse centres (overlaps allowed, radii 0.5-1.5 mm) uniform in a box [lo, lo + L) not at
    the origin, periodic along ``axes``; ``narrow``: that axis 2.1 cut-offs long (two cells, searched whole).
    Returns (pos, radius, period, lo)."""
    rng = np.random.default_rng(seed)
    radius = 1e-3 * rng.uniform(0.5, 1.5, n)
    if dim2:
        side = np.sqrt(np.sum(np.pi * radius**2) / solid_fraction)
        size = np.array([side, side, 0.0])
    else:
        side = np.cbrt(np.sum(4 / 3 * np.pi * radius**3) / solid_fraction)
        size = np.array([side, side, side])
    if narrow is not None:
        d = "xyz".index(narrow)
        size[d] = 2.1 * (2 * radius.max() + 0.4e-3)
        size[(d + 1) % (2 if dim2 else 3)] *= side / size[d]
    lo = -0.3 * size
    pos = lo + rng.uniform(0.0, 1.0, (n, 3)) * size
    if dim2:
        pos[:, 2] = 0.25e-3
        lo[2] = 0.25e-3
    period = np.zeros(3)
    for ax in axes:
        period["xyz".index(ax)] = size["xyz".index(ax)]
    return pos, radius, period, lo


def listed_pairs(row_start, partner):
    rows = np.repeat(np.arange(row_start.shape[0] - 1), np.diff(row_start))
    pairs = set(zip(np.minimum(rows, partner).tolist(), np.maximum(rows, partner).tolist()))
    assert len(pairs) == partner.shape[0], "a pair is listed twice"
    return pairs


CASES = [  # (dim2, periodic axes, narrow axis)
    (True, "x", None), (True, "y", None), (True, "xy", None), (True, "x", "x"),
    (False, "x", None), (False, "z", None), (False, "xy", None), (False, "xz", None), (False, "xyz", None),
    (False, "xyz", "y"),
]


@pytest.mark.parametrize("dim2, axes, narrow", CASES)
@pytest.mark.parametrize("seed", [1, 2])
def test_periodic_list_equals_nearest_image_brute_force(dim2, axes, narrow, seed):
    n = 700 if dim2 else 900
    pos, radius, period, lo = periodic_packing(seed, n, dim2, axes, narrow)
    skin = 0.4e-3
    assert np.all((pos >= lo) & (pos < lo + np.where(period > 0, period, np.inf)))
    row_start, partner, slab_start, slab_members = build_pairs_periodic(pos, radius, skin, dim2, period, lo)
    assert row_start[0] == 0 and row_start[-1] == partner.shape[0]
    found = listed_pairs(row_start, partner)
    expected = {(int(i), int(j)) for i, j in brute_force_periodic(pos, radius, skin, period)}
    assert found == expected, f"missing {sorted(expected - found)[:5]}, extra {sorted(found - expected)[:5]}"
    # pairs across a seam are there (else the test would not test the periodic search)
    wrap = 0
    for i, j in expected:
        r = pos[i] - pos[j]
        wrap += bool(np.any(np.abs(r[period > 0]) > 0.5 * period[period > 0]))
    assert wrap > 0
    owner = np.repeat(np.arange(n), np.diff(row_start))
    for i in range(n):  # rows ascending
        assert np.all(np.diff(partner[row_start[i]:row_start[i + 1]]) > 0)
    nslab = slab_start.shape[0] - 1
    assert np.array_equal(np.sort(slab_members), np.arange(n))
    slab = np.empty(n, np.int64)
    for s in range(nslab):
        slab[slab_members[slab_start[s]:slab_start[s + 1]]] = s
    step = (slab[partner] - slab[owner]) % nslab if nslab > 2 else slab[partner] - slab[owner]
    assert np.all((step == 0) | (step == 1)), "a pair spans non-adjacent slabs or is owned by the wrong end"
    if nslab > 2:
        assert nslab % 2 == 0 or nslab == 1


def test_contacts_first_by_nearest_image():
    """The touching pairs (by nearest image) come first in each row, with their springs."""
    pos, radius, period, lo = periodic_packing(3, 800, False, "xyz")
    row_start, partner, _, _ = build_pairs_periodic(pos, radius, 0.4e-3, False, period, lo)
    hist = np.zeros((partner.shape[0], 3))
    hist[:, 0] = partner  # a label that must travel with its pair
    contacts_first_periodic(pos, radius, row_start, partner, hist, period)
    assert np.array_equal(hist[:, 0], partner)
    for i in range(pos.shape[0]):
        row = partner[row_start[i]:row_start[i + 1]]
        r = np.array([[nearest_image(pos[i, d] - pos[j, d], period[d]) for d in range(3)] for j in row])
        touch = (np.sum(r * r, axis=1) < (radius[i] + radius[row]) ** 2) if row.size else np.zeros(0, bool)
        assert not np.any(np.diff(touch.astype(int)) > 0), "a touching pair after a non-touching one"
