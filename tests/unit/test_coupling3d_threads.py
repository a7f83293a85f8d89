"""The 3D coupling kernels (_voidage3d_kernels, _paired3d_kernels) give bitwise (==) the same numbers on one
thread and on two, and the same as the plain serial sums they replace: each sphere's exact volume in each cell
summed per cell by ``sphere_box_volume`` and added in particle order, each particle's centre cell, K_p and face
sums, and the gas force per particle. Random packings with spheres straddling cell faces, edges and corners
and poking through the domain's sides, on walled and on periodic axes; more particles than one work chunk
(``CHUNK``) so that the parallel passes run."""
from __future__ import annotations

import math

import numba
import numpy as np
import pytest

from fluidem.coupling import _paired3d_kernels as P3
from fluidem.coupling import _voidage3d_kernels as VK3
from fluidem.coupling._voidage_kernels import cell_index
from fluidem.coupling.drag import drag_laws

CELLS = (6, 5, 4)
SPACING = (2.0e-3, 2.4e-3, 2.2e-3)  # [m]
N = 700  # > 2 CHUNK: the parallel passes split the particles
PERIODIC = [(False, False, False), (True, False, True), (True, True, True)]


def packing(seed=5, dmax=1.8e-3):
    """N spheres (diameters 0.4–1 dmax) anywhere in the box and up to a radius beyond its sides; a fifth of
    the centres put on cell faces, edges and corners."""
    rng = np.random.default_rng(seed)
    size = np.array(CELLS) * np.array(SPACING)
    r = 0.5 * rng.uniform(0.4, 1.0, N) * dmax
    pos = rng.uniform(-r[:, None], size[None, :] + r[:, None])
    h = np.array(SPACING)
    m = N // 5
    pos[:m] = np.round(pos[:m] / h) * h  # on corners
    pos[m:2 * m, 1] = np.round(pos[m:2 * m, 1] / h[1]) * h[1]  # on a y face
    pos[2 * m:3 * m, :2] = np.round(pos[2 * m:3 * m, :2] / h[:2]) * h[:2]  # on a z edge
    vel = rng.normal(0.0, 0.3, (N, 3))
    return np.ascontiguousarray(pos), r, vel


def reference_volume(pos, r, vel, periodic):
    """Each sphere's exact volume in each cell it overlaps (``sphere_box_volume``), added to the cells in particle
    order: the serial deposit of the volume map before it kept node values."""
    nx, ny, nz = CELLS
    out = [np.zeros(CELLS) for _ in range(4)]
    for p in range(pos.shape[0]):
        rng_ = []
        for a in range(3):
            d, n = SPACING[a], CELLS[a]
            lo, hi = int(math.floor((pos[p, a] - r[p]) / d)), int(math.floor((pos[p, a] + r[p]) / d))
            if not periodic[a]:
                lo, hi = min(max(lo, 0), n - 1), min(max(hi, 0), n - 1)
            rng_.append((lo, hi))
        (a0, a1), (b0, b1), (c0, c1) = rng_
        if a0 == a1 and b0 == b1 and c0 == c1:
            v = 1.0 * 4.0 / 3.0 * math.pi * r[p] * r[p] * r[p]
            cells = [((a0 % nx, b0 % ny, c0 % nz), v)]
        else:
            cells = []
            for i in range(a0, a1 + 1):
                for j in range(b0, b1 + 1):
                    for k in range(c0, c1 + 1):
                        b = []
                        for a, m in enumerate((i, j, k)):
                            d, n = SPACING[a], CELLS[a]
                            lo, hi = m * d, (m + 1) * d
                            if not periodic[a]:
                                lo = -math.inf if m == 0 else lo
                                hi = math.inf if m == n - 1 else hi
                            b += [lo, hi]
                        v = VK3.sphere_box_volume(pos[p, 0], pos[p, 1], pos[p, 2], r[p], *b)
                        if v > 0.0:
                            cells.append(((i % nx, j % ny, k % nz), v * 1.0))
        for c, v in cells:
            out[0][c] += v
            for a in range(3):
                out[a + 1][c] += v * vel[p, a]
    return out


def with_threads(n, fn, *args):
    """fn(*args) with n Numba threads."""
    before = numba.get_num_threads()
    numba.set_num_threads(min(n, numba.config.NUMBA_NUM_THREADS))
    try:
        return fn(*args)
    finally:
        numba.set_num_threads(before)


def volume_map(pos, r, vel, periodic, work):
    out = [np.zeros(CELLS) for _ in range(4)]
    VK3.volume_deposit(pos, r, np.ones(pos.shape[0]), vel, *SPACING, *periodic, *out, work)
    return out


def centroid_map(pos, w, vel, work):
    out = [np.zeros(CELLS) for _ in range(4)]
    VK3.centroid_deposit3d(pos, w, vel, *SPACING, *out, work)
    return out


@pytest.mark.parametrize("periodic", PERIODIC)
def test_volume_deposit_equals_the_serial_sums(periodic):
    """Node values summed per cell == ``sphere_box_volume`` per cell, on 1 and 2 threads, with an owned scratch,
    a scratch allocated inside (None) and one too short (allocated inside too)."""
    pos, r, vel = packing()
    ref = reference_volume(pos, r, vel, periodic)
    stride = VK3.volume_stride(r, *SPACING, *CELLS, *periodic)
    assert stride == 27  # spheres under one cell across: at most 2 cells, 3 nodes, per axis
    for threads in (1, 2):
        for work in (np.empty(N * stride), None, np.empty(3)):
            got = with_threads(threads, volume_map, pos, r, vel, periodic, work)
            for a in range(4):
                assert np.array_equal(got[a], ref[a]), (threads, a)
    straddling = sum(1 for p in range(N) if np.any(np.floor((pos[p] - r[p]) / SPACING) !=
                                                   np.floor((pos[p] + r[p]) / SPACING)))
    assert straddling > N // 2  # the test is about spheres cut by cell faces


def test_volume_deposit_spheres_larger_than_a_cell():
    """Spheres spanning up to four cells per axis (stride from the largest) and, on a periodic axis, wrapping onto
    themselves: still == the serial sums, and Σ kept."""
    periodic = (True, False, True)
    pos, r, vel = packing(seed=9, dmax=6.0e-3)
    ref = reference_volume(pos, r, vel, periodic)
    for threads in (1, 2):
        got = with_threads(threads, volume_map, pos, r, vel, periodic, None)
        for a in range(4):
            assert np.array_equal(got[a], ref[a])
    assert got[0].sum() == pytest.approx(4.0 / 3.0 * math.pi * np.sum(r**3), rel=1e-13)


def test_centroid_deposit_equals_the_serial_sums():
    pos, r, vel = packing(seed=6)
    w = 4.0 / 3.0 * math.pi * r**3
    ref = [np.zeros(CELLS) for _ in range(4)]
    for p in range(N):
        c = tuple(cell_index(pos[p, a], 1.0 / SPACING[a], CELLS[a]) for a in range(3))
        ref[0][c] += w[p]
        for a in range(3):
            ref[a + 1][c] += w[p] * vel[p, a]
    for threads in (1, 2):
        for work in (np.empty(N), None):
            got = with_threads(threads, centroid_map, pos, w, vel, work)
            for a in range(4):
                assert np.array_equal(got[a], ref[a])


@pytest.mark.parametrize("method", [0, 3])
@pytest.mark.parametrize("weighting", [0, 1])
def test_map_solids3d_same_on_one_and_two_threads(method, weighting):
    """The whole map (deposit, smoothing, clipping, averages) == on 1 and 2 threads, periodic x and z."""
    pos, r, vel = packing(seed=4)
    vol = 4.0 / 3.0 * math.pi * r**3
    cell = float(np.prod(SPACING))

    def run():
        out = [np.empty(CELLS) for _ in range(4)]
        clipped = VK3.map_solids3d(method, weighting, pos, r, vol, vel, *SPACING, True, False, True, cell,
                                   0.1, 0.1, 0.1, 2, 0.3, *out, np.empty(N * 27))
        return clipped, out

    c1, one = with_threads(1, run)
    c2, two = with_threads(2, run)
    assert c1 == c2
    for a in range(4):
        assert np.array_equal(one[a], two[a])
