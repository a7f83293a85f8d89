"""The 3D coupling kernels (_voidage3d_kernels, _paired3d_kernels) give bitwise (==) the same numbers on one
thread and on two, and the same as the plain serial sums they replace: each sphere's exact volume in each cell
(as ``_volume_range`` gives it for that sphere alone, itself ``sphere_box_volume`` of the cell to round-off)
added in particle order, each particle's centre cell, K_p and face
sums, and the gas force per particle. Random packings with spheres straddling cell faces, edges and corners
and poking through the domain's sides, on walled and on periodic axes; more particles than one work chunk
(``CHUNK``) so that the parallel passes run. The sums onto the grid run in x slabs, one per thread, each
walking all particles in order: the slab split is crossed by many spheres and, on a periodic x axis, by
wrapped ones, and the slab passes are checked for every number of slabs up to one per x plane."""
from __future__ import annotations

import math

import numba
import numpy as np
import pytest

from fluidem.coupling import _paired3d_kernels as P3
from fluidem.coupling import _voidage3d_kernels as VK3
from fluidem.coupling._voidage_kernels import cell_index

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


def box_volume_cells(pos, r, periodic):
    """Each sphere's exact volume in each cell it overlaps by ``sphere_box_volume`` of the cell's box: a dict
    {(i, j, k) wrapped: V} per sphere (the cells with V > 0)."""
    nx, ny, nz = CELLS
    out = []
    for p in range(pos.shape[0]):
        rng_ = []
        for a in range(3):
            d, n = SPACING[a], CELLS[a]
            lo, hi = int(math.floor((pos[p, a] - r[p]) / d)), int(math.floor((pos[p, a] + r[p]) / d))
            if not periodic[a]:
                lo, hi = min(max(lo, 0), n - 1), min(max(hi, 0), n - 1)
            rng_.append((lo, hi))
        (a0, a1), (b0, b1), (c0, c1) = rng_
        cells = {}
        if a0 == a1 and b0 == b1 and c0 == c1:
            cells[(a0 % nx, b0 % ny, c0 % nz)] = 4.0 / 3.0 * math.pi * r[p] * r[p] * r[p]
        else:
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
                            c = (i % nx, j % ny, k % nz)
                            cells[c] = cells.get(c, 0.0) + v
        out.append(cells)
    return out


def sphere_cells(pos, r, periodic):
    """Each sphere's cells and volumes as ``_volume_range`` gives them for that sphere alone (a list of
    ((i, j, k), V) per sphere, in its order; ``sphere_box_volume`` per cell where it has none: count −1)."""
    nodes, stride = VK3._volume_layout(r, *SPACING, *CELLS, *periodic)
    work = np.empty(stride)
    out = []
    for p in range(pos.shape[0]):
        VK3._volume_range(0, 1, pos[p:p + 1], r[p:p + 1], np.ones(1), *SPACING, *CELLS, *periodic, nodes, stride,
                          work)
        m = int(work[nodes])
        if m < 0:
            out.append(list(box_volume_cells(pos[p:p + 1], r[p:p + 1], periodic)[0].items()))
            continue
        out.append([((int(work[nodes + 1 + 4 * q]), int(work[nodes + 2 + 4 * q]), int(work[nodes + 3 + 4 * q])),
                     work[nodes + 4 + 4 * q]) for q in range(m)])
    return out


def reference_volume(pos, r, vel, periodic):
    """The volume map as one plain serial pass: each sphere's cell volumes (``sphere_cells``, each sphere
    alone) added to the cells in particle order."""
    out = [np.zeros(CELLS) for _ in range(4)]
    for p, cells in enumerate(sphere_cells(pos, r, periodic)):
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
    """The parallel deposit == the cells of each sphere alone added in particle order, on 1 and 2 threads, with
    an owned scratch, a scratch allocated inside (None) and one too short (allocated inside too)."""
    pos, r, vel = packing()
    ref = reference_volume(pos, r, vel, periodic)
    stride = VK3.volume_stride(r, *SPACING, *CELLS, *periodic)
    assert stride == 27 + 1 + 4 * 8  # spheres under one cell across: at most 2 cells, 3 nodes, per axis
    for threads in (1, 2):
        for work in (np.empty(N * stride), None, np.empty(3)):
            got = with_threads(threads, volume_map, pos, r, vel, periodic, work)
            for a in range(4):
                assert np.array_equal(got[a], ref[a]), (threads, a)
    straddling = sum(1 for p in range(N) if np.any(np.floor((pos[p] - r[p]) / SPACING) !=
                                                   np.floor((pos[p] + r[p]) / SPACING)))
    assert straddling > N // 2  # the test is about spheres cut by cell faces


@pytest.mark.parametrize("periodic", PERIODIC)
@pytest.mark.parametrize("dmax", [1.8e-3, 6.0e-3])
def test_cell_volumes_of_each_sphere_are_the_box_volumes(periodic, dmax):
    """Each sphere's cell volumes (at most one face per axis inside it: the volumes beyond the faces combined;
    more: the node values) are ``sphere_box_volume`` of each cell's box to round-off (1e-14 of the sphere) and
    add up to the sphere."""
    pos, r, vel = packing(seed=9 if dmax > 2e-3 else 5, dmax=dmax)
    got, ref = sphere_cells(pos, r, periodic), box_volume_cells(pos, r, periodic)
    for p in range(N):
        vp = 4.0 / 3.0 * math.pi * r[p] ** 3
        cells = {}
        for c, v in got[p]:
            cells[c] = cells.get(c, 0.0) + v
        for c in set(cells) | set(ref[p]):
            assert abs(cells.get(c, 0.0) - ref[p].get(c, 0.0)) <= 1e-14 * vp, (p, c)
        assert sum(cells.values()) == pytest.approx(vp, rel=1e-13)


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
                                   0.1, 0.1, 0.1, 2, 0.3, *out, np.empty(N * 60))
        return clipped, out

    c1, one = with_threads(1, run)
    c2, two = with_threads(2, run)
    assert c1 == c2
    for a in range(4):
        assert np.array_equal(one[a], two[a])


def gas_fields(seed=8):
    """Random gas velocities on the faces, voidage in [0.4, 0.95], density and pressure at the centres."""
    rng = np.random.default_rng(seed)
    nx, ny, nz = CELLS
    u = rng.normal(0.5, 0.4, (nx + 1, ny, nz))
    v = rng.normal(1.0, 0.4, (nx, ny + 1, nz))
    w = rng.normal(-0.2, 0.4, (nx, ny, nz + 1))
    eps = rng.uniform(0.4, 0.95, CELLS)
    rho = rng.uniform(1.1, 1.3, CELLS)
    p = rng.normal(0.0, 50.0, CELLS)
    return u, v, w, eps, rho, p


def face_sums_reference(pos, vel, vol, kp, periodic, fold, ok=None):
    """A_f, B_f of the three face directions, Σ K_p of each cell and Σ_p w_pf V_p (∇p weights), added in particle
    order with the weights of ``_paired3d_kernels._axis``, written out in Python: the serial pass of ``deposit3d``
    (a particle with ok[q] False adds its V_p only)."""
    nx, ny, nz = CELLS
    shapes = [(nx + 1, ny, nz), (nx, ny + 1, nz), (nx, ny, nz + 1)]
    A = [np.zeros(s) for s in shapes]
    B = [np.zeros(s) for s in shapes]
    E = [np.zeros(s) for s in shapes]
    KC = np.zeros(CELLS)

    def add(F, i, a, j, b, k, c, q):
        for s in range(2):
            for t in range(2):
                for r in range(2):
                    F[i[s], j[t], k[r]] += a[s] * b[t] * c[r] * q

    for q in range(pos.shape[0]):
        ax = [P3._axis(pos[q, m], 1.0 / SPACING[m], CELLS[m], periodic[m], fold) for m in range(3)]
        g = [P3._face_axis(pos[q, m], 1.0 / SPACING[m], CELLS[m], periodic[m], True) for m in range(3)]
        cn = [(a[0], a[1]) for a in ax]
        cw = [(a[2], a[3]) for a in ax]
        fn = [(a[4], a[5]) for a in ax]
        fw = [(a[6], a[7]) for a in ax]
        gn = [(a[0], a[1]) for a in g]
        gw = [(a[2], a[3]) for a in g]
        add(E[0], gn[0], gw[0], cn[1], cw[1], cn[2], cw[2], vol[q])
        add(E[1], cn[0], cw[0], gn[1], gw[1], cn[2], cw[2], vol[q])
        add(E[2], cn[0], cw[0], cn[1], cw[1], gn[2], gw[2], vol[q])
        if ok is not None and not ok[q]:
            continue
        k = kp[q]
        cell = tuple(min(max(int(pos[q, m] * (1.0 / SPACING[m])), 0), CELLS[m] - 1) for m in range(3))
        KC[cell] += k
        for m in range(3):
            nodes = [fn[a] if a == m else cn[a] for a in range(3)]
            wts = [fw[a] if a == m else cw[a] for a in range(3)]
            add(A[m], nodes[0], wts[0], nodes[1], wts[1], nodes[2], wts[2], k)
            add(B[m], nodes[0], wts[0], nodes[1], wts[1], nodes[2], wts[2], k * vel[q, m])
    return A, B, KC, E


@pytest.mark.parametrize("periodic", PERIODIC)
@pytest.mark.parametrize("fold", [True, False])
@pytest.mark.parametrize("pair", [True, False])
def test_deposit3d_and_forces_equal_the_serial_sums(periodic, fold, pair):
    """K_p of the whole set (parallel chunks) == K_p of each particle alone; the face sums, cell sums and pressure
    voidage (``pair``; untouched without) == the sums in particle order; the forces (plain and split) == each
    particle's alone; on 1 and 2 threads, with owned scratch and with scratch allocated inside."""
    from fluidem.coupling.drag import drag_laws
    from fluidem.coupling.exchange3d import face_volumes3d

    pos, r, vel = packing(seed=12)
    size = np.array(CELLS) * np.array(SPACING)
    pos = np.ascontiguousarray(np.clip(pos, 0.0, size))  # centres in the box: the kernels clamp outside ones
    vol = 4.0 / 3.0 * math.pi * r**3
    u, v, w, eps, rho, p = gas_fields()
    law = drag_laws.get("gidaspow")().pack()
    mu, mv = 1.8e-5, 0.3
    inv_dbar = np.zeros((0, 0, 0))
    VF = face_volumes3d(CELLS, periodic, float(np.prod(SPACING)))
    shapes = [f.shape for f in VF]

    def kp_alone():
        kp, valid = np.empty(N), np.empty(N, np.bool_)
        for q in range(N):
            P3.kp3d(law, pos[q:q + 1], vel[q:q + 1], r[q:q + 1], vol[q:q + 1], u, v, w, eps, rho, mu, inv_dbar,
                    *SPACING, mv, *periodic, fold, kp[q:q + 1], valid[q:q + 1])
        assert valid.all()
        return kp

    def deposit(scratch):
        kp = np.empty(N)
        sums = [np.empty(s) for s in shapes for _ in range(2)]
        KC = np.empty(CELLS)
        coef = [np.empty(s) for s in shapes for _ in range(2)]
        E = [np.full(s, 7.0) for s in shapes]
        extra = (np.empty(N, np.bool_),) if scratch else ()
        bad = P3.deposit3d(law, pos, vel, r, vol, u, v, w, eps, rho, mu, inv_dbar, *SPACING, mv, *periodic, fold, kp,
                           *sums, KC, *VF, *coef, pair, *E, *extra)
        assert bad == 0
        return kp, sums, KC, coef, E

    kp_ref = kp_alone()
    A, B, KC_ref, E_ref = face_sums_reference(pos, vel, vol, kp_ref, periodic, fold)
    runs = [with_threads(t, deposit, s) for t in (1, 2) for s in (True, False)]
    for kp, sums, KC, coef, E in runs:
        assert np.array_equal(kp, kp_ref)
        assert np.array_equal(KC, KC_ref)
        for m in range(3):
            assert np.array_equal(sums[2 * m], A[m]) and np.array_equal(sums[2 * m + 1], B[m])
            assert np.array_equal(coef[2 * m], A[m] / VF[m])
            assert np.array_equal(coef[2 * m + 1], np.where(A[m] > 0.0, B[m] / np.where(A[m] > 0, A[m], 1.0), 0.0))
            if pair:
                assert np.array_equal(E[m], np.maximum(1.0 - E_ref[m] / VF[m], mv))
            else:
                assert np.all(E[m] == 7.0)

    def forces(split):
        out, total = np.zeros((N, 3)), np.ones((N, 3))
        damp = np.full(N, 0.5)
        if split:
            P3.particle_forces_split3d(pos, vel, vol, kp_ref, u, v, w, p, *SPACING, *periodic, fold, True, out, damp,
                                       total)
        else:
            P3.particle_forces3d(pos, vel, vol, kp_ref, u, v, w, p, *SPACING, *periodic, fold, True, out, total)
        return out, total, damp

    for split in (False, True):
        ref = [np.zeros((N, 3)), np.ones((N, 3)), np.full(N, 0.5)]
        for q in range(N):
            s = slice(q, q + 1)
            if split:
                P3.particle_forces_split3d(pos[s], vel[s], vol[s], kp_ref[s], u, v, w, p, *SPACING, *periodic, fold,
                                           True, ref[0][s], ref[2][s], ref[1][s])
            else:
                P3.particle_forces3d(pos[s], vel[s], vol[s], kp_ref[s], u, v, w, p, *SPACING, *periodic, fold, True,
                                     ref[0][s], ref[1][s])
        for t in (1, 2):
            got = with_threads(t, forces, split)
            for a in range(3):
                assert np.array_equal(got[a], ref[a]), (split, t, a)


def slab_partitions(nx):
    """Numbers of x slabs to try: one (the serial pass), two, three and one per x plane."""
    return sorted({1, min(2, nx), min(3, nx), nx})


def touched_x_cells(pos, r, periodic_x):
    """The wrapped x cells each sphere overlaps (its cell range along x, ``_voidage3d_kernels._cell_range``)."""
    nx, d = CELLS[0], SPACING[0]
    out = []
    for p in range(pos.shape[0]):
        lo, hi = int(math.floor((pos[p, 0] - r[p]) / d)), int(math.floor((pos[p, 0] + r[p]) / d))
        if not periodic_x:
            lo, hi = min(max(lo, 0), nx - 1), min(max(hi, 0), nx - 1)
        out.append({i % nx for i in range(lo, hi + 1)})
    return out


@pytest.mark.parametrize("nx", [1, 2, 5, 6, 15])
def test_slabs_hold_every_x_index_once(nx):
    """The x slabs of m = 1 … nx hold each cell and face index 0 … nx exactly once, in order."""
    for m in range(1, nx + 1):
        got = []
        for s in range(m):
            lo, hi = VK3.slab_bounds(s, m, nx)
            assert hi > lo
            got += list(range(lo, hi))
        assert got == list(range(nx + 1)), m


@pytest.mark.parametrize("periodic", PERIODIC)
def test_volume_and_centroid_sums_in_any_number_of_slabs(periodic):
    """The slab passes of the voidage map, run one after the other for 1, 2, 3 and one slab per x plane, == the
    serial sums; the packing has many spheres across the two-slab split and, with periodic x, across the
    domain's x side (cell nx − 1 and cell 0, in different slabs)."""
    pos, r, vel = packing(seed=7)
    nx = CELLS[0]
    touched = touched_x_cells(pos, r, periodic[0])
    split = VK3.slab_bounds(1, 2, nx)[0]
    assert sum(1 for t in touched if split - 1 in t and split in t) > 50
    if periodic[0]:
        assert sum(1 for t in touched if 0 in t and nx - 1 in t) > 50
    ref = reference_volume(pos, r, vel, periodic)
    nodes, stride = VK3._volume_layout(r, *SPACING, *CELLS, *periodic)
    work = np.empty(N * stride)
    scale = np.ones(N)
    VK3._volume_range(0, N, pos, r, scale, *SPACING, *CELLS, *periodic, nodes, stride, work)
    w = 4.0 / 3.0 * math.pi * r**3
    cells = np.empty(N)
    VK3._centroid_range(0, N, pos, *SPACING, *CELLS, cells)
    cref = [np.zeros(CELLS) for _ in range(4)]
    for p in range(N):
        c = tuple(cell_index(pos[p, a], 1.0 / SPACING[a], CELLS[a]) for a in range(3))
        cref[0][c] += w[p]
        for a in range(3):
            cref[a + 1][c] += w[p] * vel[p, a]
    ones = [np.zeros(CELLS) for _ in range(4)]  # the number-weighted sums by centres, in particle order
    for p in range(N):
        c = tuple(cell_index(pos[p, a], 1.0 / SPACING[a], CELLS[a]) for a in range(3))
        ones[0][c] += 1.0
        for a in range(3):
            ones[a + 1][c] += 1.0 * vel[p, a]
    none = [np.empty((0, 0, 0))] * 4
    for m in slab_partitions(nx):
        out = [np.zeros(CELLS) for _ in range(4)]
        cout = [np.zeros(CELLS) for _ in range(4)]
        bit = VK3.slab_bits(m, nx)
        slabs = np.empty(N, np.int64)
        VK3._volume_slabs(0, N, pos, r, SPACING[0], nx, periodic[0], bit, slabs, False)
        single = (slabs & (slabs - 1)) == 0  # all its cells in one slab
        assert single.all() == (m == 1) and (single.any() or m > 2), m
        for s in range(m):
            lo, hi = VK3.slab_bounds(s, m, nx)
            VK3._volume_add(lo, hi, bit[lo], slabs, pos, r, scale, vel, *SPACING, *periodic, nodes, stride, work, *out,
                            *none)
            VK3._centroid_add(lo, hi, N, w, vel, cells, *cout)
        for a in range(4):
            assert np.array_equal(out[a], ref[a]), (m, a)
            assert np.array_equal(cout[a], cref[a]), (m, a)
        # the volumes and the number-weighted centre sums in one pass (the map of a "volume" method with
        # "number" weighting)
        VK3._volume_slabs(0, N, pos, r, SPACING[0], nx, periodic[0], bit, slabs, True)
        vol, both = np.zeros(CELLS), [np.zeros(CELLS) for _ in range(4)]
        for s in range(m):
            lo, hi = VK3.slab_bounds(s, m, nx)
            VK3._volume_add(lo, hi, bit[lo], slabs, pos, r, scale, vel, *SPACING, *periodic, nodes, stride, work, vol,
                            *none[:3], *both)
        assert np.array_equal(vol, ref[0]), m
        for a in range(4):
            assert np.array_equal(both[a], ones[a]), (m, a)


@pytest.mark.parametrize("periodic", PERIODIC)
@pytest.mark.parametrize("pair", [True, False])
def test_face_sums_in_any_number_of_slabs(periodic, pair):
    """The slab passes of the face deposit (``_paired3d_kernels._face_sums_slab`` with each particle's slabs of
    ``_face_slabs``), one after the other for 1, 2, 3 and one slab per x plane, == the sums in particle order,
    with a tenth of the particles out of drag range (V_p deposited, no K_p); face nx (walls) in the last slab,
    wrapped faces (periodic) in the first; particles inside one slab and straddling two both present."""
    pos, r, vel = packing(seed=13)
    size = np.array(CELLS) * np.array(SPACING)
    pos = np.ascontiguousarray(np.clip(pos, 0.0, size))
    vol = 4.0 / 3.0 * math.pi * r**3
    rng = np.random.default_rng(3)
    kp = rng.uniform(1e-5, 1e-3, N)
    ok = rng.uniform(size=N) > 0.1
    nx, ny, nz = CELLS
    shapes = [(nx + 1, ny, nz), (nx, ny + 1, nz), (nx, ny, nz + 1)]
    inv = [1.0 / d for d in SPACING]
    for fold in (True, False):
        A, B, KC_ref, E_ref = face_sums_reference(pos, vel, vol, kp, periodic, fold, ok)
        for m in slab_partitions(nx):
            AB = [np.zeros(s) for s in shapes for _ in range(2)]
            KC = np.zeros(CELLS)
            E = [np.zeros(s) for s in shapes]
            slabs = np.empty(N, np.int64)
            bit = VK3.slab_bits(m, nx)
            P3._face_slabs(0, N, pos, ok, inv[0], nx, periodic[0], fold, pair, bit, slabs)
            single = (slabs & (slabs - 1)) == 0  # one bit: the particle's nodes all in one slab
            assert single.all() == (m == 1) and (single.any() or m > 2), m
            for s in range(m):
                lo, hi = VK3.slab_bounds(s, m, nx)
                P3._face_sums_slab(s, lo, hi, slabs, pos, vel, vol, kp, ok, *inv, *periodic, fold, pair, *AB, KC, *E)
            assert np.array_equal(KC, KC_ref), (fold, m)
            for a in range(3):
                assert np.array_equal(AB[2 * a], A[a]) and np.array_equal(AB[2 * a + 1], B[a]), (fold, m, a)
                assert np.array_equal(E[a], E_ref[a] if pair else np.zeros(shapes[a])), (fold, m, a)
            if not periodic[0] and not fold:
                assert A[0][nx].any()  # the wall face nx, held by the last slab


def test_slab_of_is_the_slab_whose_bounds_hold_the_index():
    for nx in (1, 2, 5, 15, 64):
        for m in range(1, min(nx, 63) + 1):
            for s in range(m):
                lo, hi = VK3.slab_bounds(s, m, nx)
                assert all(VK3.slab_of(i, m, nx) == s for i in range(lo, hi)), (nx, m, s)


def test_volume_deposit_without_velocity_sums():
    """Velocity arrays of size 0: the same volumes, bitwise, on 1 and 2 threads (the map of number-weighted
    velocities takes its weights from the centres)."""
    periodic = (True, False, True)
    pos, r, vel = packing(seed=3)
    ref = reference_volume(pos, r, vel, periodic)[0]
    none = np.empty((0, 0, 0))
    for threads in (1, 2):
        out = np.zeros(CELLS)
        with_threads(threads, VK3.volume_deposit, pos, r, np.ones(N), vel, *SPACING, *periodic, out, none, none, none)
        assert np.array_equal(out, ref)
