"""Particle → grid mapping on a 3D grid (coupling/voidage, _voidage3d_kernels): the exact sphere ∩ box volume
against closed forms and a bounding raster, exact conservation of the solids volume (centroid and volume
methods, periodic and walled axes), smoothing that keeps the total and has the stated width, solids-velocity
averages (Sun 2007 eqs 34-35, Hoomans 1996 eq. 50)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from fluidem.coupling import voidage as V
from fluidem.coupling._voidage3d_kernels import corner_volume, octant_volume, sphere_box_volume
from fluidem.gas.grid import StaggeredGrid

D = 4e-3
INF = math.inf


@pytest.fixture
def grid():
    return StaggeredGrid(cells=(5, 6, 4), size=(0.025, 0.036, 0.02))  # dx 5 mm, dy 6 mm, dz 5 mm


def random_spheres(grid, n=60, seed=3, inside=True):
    """Centres at random (inside: every sphere within the box), some on cell faces, edges and corners."""
    rng = np.random.default_rng(seed)
    d = rng.uniform(0.5, 1.0, n) * D
    r = 0.5 * d
    lo = r[:, None] if inside else np.zeros((n, 1))
    hi = np.array(grid.size)[None, :] - lo
    pos = rng.uniform(lo, hi)
    dx = np.array(grid.spacing)
    pos[:10] = np.round(pos[:10] / dx) * dx  # on cell corners
    pos[:10] = np.clip(pos[:10], lo[:10], hi[:10])
    pos[10:20, 0] = np.round(pos[10:20, 0] / dx[0]) * dx[0]  # on an x face
    pos[10:20, 0] = np.clip(pos[10:20, 0], lo[10:20, 0], hi[10:20, 0])
    return pos, d


def test_closed_forms():
    """Whole sphere, hemisphere, a cap, an octant and a quarter: the closed forms to 1e-14 relative."""
    r = 0.7
    full = 4.0 / 3.0 * math.pi * r**3
    assert sphere_box_volume(0, 0, 0, r, -INF, INF, -INF, INF, -INF, INF) == pytest.approx(full, rel=1e-14)
    assert sphere_box_volume(0, 0, 0, r, -1, 1, -1, 1, -1, 1) == pytest.approx(full, rel=1e-14)
    assert sphere_box_volume(0, 0, 0, r, 0, INF, -INF, INF, -INF, INF) == pytest.approx(full / 2, rel=1e-14)
    h = 0.3
    cap = math.pi * (r - h) ** 2 * (2 * r + h) / 3.0
    assert sphere_box_volume(0, 0, 0, r, -INF, INF, h, INF, -INF, INF) == pytest.approx(cap, rel=1e-14)
    assert sphere_box_volume(0, 0, 0, r, -INF, INF, -INF, -h, -INF, INF) == pytest.approx(cap, rel=1e-14)
    assert corner_volume(0.0, 0.0, 0.0, r) == pytest.approx(full / 8, rel=1e-14)
    assert sphere_box_volume(0, 0, 0, r, 0, 5, 0, 5, -5, 5) == pytest.approx(full / 4, rel=1e-14)
    # symmetric in the axes
    a, b, c = 0.11, -0.23, 0.31
    vals = [corner_volume(*p, r) for p in ((a, b, c), (b, c, a), (c, a, b), (b, a, c))]
    assert max(vals) - min(vals) < 1e-15 * full


def test_octant_volume_against_quadrature():
    """octant_volume(a, b, c) = ∫∫ (√(r² − x² − y²) − c) dy dx over x > a, y > b, x² + y² < r² − c², by SciPy's
    adaptive quadrature (an evaluation independent of the closed form and of its sums of arctangents) to 1e-11
    of the sphere: random bounds; c = 0 (the closed form's upper end alone); a = 0 and a = b = 0 (where the
    summed angles meet their edge cases); bounds just inside the rim; bounds of 1e-6 r."""
    dblquad = pytest.importorskip("scipy.integrate").dblquad
    r = 0.7
    full = 4.0 / 3.0 * math.pi * r**3
    rng = np.random.default_rng(11)
    cases = [(0.0, 0.0, 0.0), (0.0, 0.0, 0.3), (0.0, 0.25, 0.0), (0.0, 0.25, 0.4), (0.3, 0.3, 0.3),
             (1e-6 * r, 2e-6 * r, 1e-6 * r)]
    while len(cases) < 30:
        a, b, c = rng.uniform(0.0, r, 3)
        if len(cases) % 3 == 0:
            c = 0.0
        if len(cases) % 5 == 0:  # just inside the rim
            scale = 0.99 * r / math.sqrt(a * a + b * b + c * c)
            a, b, c = a * scale, b * scale, c * scale
        if a * a + b * b + c * c < r * r:
            cases.append((a, b, c))
    for a, b, c in cases:
        h = r * r - c * c
        ref, err = dblquad(lambda y, x: math.sqrt(max(r * r - x * x - y * y, 0.0)) - c, a, math.sqrt(h - b * b),
                           lambda x: b, lambda x: math.sqrt(max(h - x * x, b * b)), epsabs=1e-14 * full, epsrel=1e-13)
        assert err < 1e-12 * full
        got = octant_volume(a, b, c, r)
        assert abs(got - ref) < 1e-11 * full, (a, b, c, got, ref)
        assert corner_volume(a, b, c, r) == got
    assert octant_volume(0.5, 0.5, 0.0, r) == 0.0  # a² + b² ≥ r²: nothing of the sphere


def test_sphere_box_volume_within_a_bounding_raster():
    """Random spheres cut by random boxes: the exact volume lies between the volume of the raster cells
    (60³ over the box) that lie wholly inside the sphere and that plus the cells the sphere's surface may
    cross (centre within half a cell diagonal of it): a bound, not a statistical tolerance. The bracket is
    about 5 % of the piece; the closed form also lands within 0.5 % of its midpoint."""
    rng = np.random.default_rng(7)
    m = 60
    for _ in range(25):
        r = rng.uniform(0.3, 1.0)
        c = rng.uniform(-0.5, 0.5, 3)
        lo = rng.uniform(-1.2, 0.3, 3)
        hi = lo + rng.uniform(0.2, 1.5, 3)
        h = (hi - lo) / m
        axes = [lo[k] + (np.arange(m) + 0.5) * h[k] for k in range(3)]
        X, Y, Z = np.meshgrid(*axes, indexing="ij")
        dist = np.sqrt((X - c[0]) ** 2 + (Y - c[1]) ** 2 + (Z - c[2]) ** 2)
        half = 0.5 * np.linalg.norm(h)
        cell = h.prod()
        inner = np.count_nonzero(dist + half <= r) * cell
        maybe = np.count_nonzero((dist - half < r) & (dist + half > r)) * cell
        v = sphere_box_volume(c[0], c[1], c[2], r, lo[0], hi[0], lo[1], hi[1], lo[2], hi[2])
        assert inner - 1e-15 <= v <= inner + maybe + 1e-15
        if v > 0.05 * r**3:
            raster = np.count_nonzero(dist < r) * cell
            assert v == pytest.approx(raster, rel=0.02)


@pytest.mark.parametrize("method", ["centroid", "volume"])
def test_solids_volume_conserved(grid, method):
    """Σ (1 − ε) V_cell = Σ V_p to round-off, spheres inside the box and cut by cell faces."""
    pos, d = random_spheres(grid)
    frac = V.solids_fraction(grid, pos, d, method)
    assert frac.shape == grid.shape
    total = math.pi / 6.0 * np.sum(d**3)
    assert np.sum(frac) * grid.cell_volume == pytest.approx(total, rel=1e-13)


def test_volume_method_periodic_and_poking_out(grid):
    """Spheres through the domain's sides: wrapped on periodic axes, kept in the edge cells of walled ones;
    Σ kept to round-off either way, and a sphere centred on the periodic side x = 0 splits evenly between
    the first and the last cell."""
    pos, d = random_spheres(grid, inside=False, seed=11)
    total = math.pi / 6.0 * np.sum(d**3)
    for periodic in ((False, False, False), (True, False, True), (True, True, True)):
        frac = V.solids_fraction(grid, pos, d, "volume", periodic=periodic)
        assert np.sum(frac) * grid.cell_volume == pytest.approx(total, rel=1e-13)
    one = np.array([[0.0, 0.5 * grid.dy, 0.5 * grid.dz]])
    frac = V.solids_fraction(grid, one, D, "volume", periodic=(True, False, False))
    assert frac[0, 0, 0] == pytest.approx(frac[-1, 0, 0], rel=1e-13)
    assert (frac[0, 0, 0] + frac[-1, 0, 0]) * grid.cell_volume == pytest.approx(math.pi / 6 * D**3, rel=1e-14)


def test_centroid_puts_the_volume_in_the_centre_cell(grid):
    pos = np.array([[0.0126, 0.0071, 0.0149]])
    frac = V.solids_fraction(grid, pos, D, "centroid")
    assert frac[2, 1, 2] * grid.cell_volume == pytest.approx(math.pi / 6 * D**3, rel=1e-15)
    assert np.count_nonzero(frac) == 1


def test_volume_method_splits_a_sphere_on_a_corner_in_eight(grid):
    pos = np.array([[grid.dx, grid.dy, grid.dz]])
    frac = V.solids_fraction(grid, pos, D, "volume")
    eighth = math.pi / 6 * D**3 / 8 / grid.cell_volume
    assert np.allclose(frac[:2, :2, :2], eighth, rtol=1e-13, atol=0)


def test_smoothing_conserves_and_has_the_stated_width():
    """A spike far from the sides: Σ kept to 1e-14 and its variance along each axis is width² (each
    explicit step adds exactly 2 D Δt); near walls and across periodic sides Σ is kept too."""
    g = StaggeredGrid(cells=(21, 21, 21), size=(0.021, 0.021, 0.021))
    f = np.zeros(g.shape)
    f[10, 10, 10] = 1.0
    width = 0.0015
    s = V.smooth(g, f, width)
    assert s.sum() == pytest.approx(1.0, rel=1e-14)
    for c in g.centres():
        mean = np.sum(s * c)
        assert np.sum(s * (c - mean) ** 2) == pytest.approx(width**2, rel=1e-10)
    f = np.zeros(g.shape)
    f[0, 20, 3] = 1.0
    for periodic in (None, (True, False, True)):
        s = V.smooth(g, f, 0.004, periodic=periodic)
        assert s.sum() == pytest.approx(1.0, rel=1e-13)
    s = V.smooth(g, f, 0.004, periodic=(True, False, False))
    assert s[-1, 20, 3] > 0.0  # across the periodic side x = 0


def test_mapping_smoothing_keeps_the_solids_volume(grid):
    pos, d = random_spheres(grid)
    smap = V.VoidageMapping(method="volume", smoothing_width=0.006, minimum_voidage=0.01).map(grid, pos, d)
    total = math.pi / 6.0 * np.sum(d**3)
    assert np.sum(1.0 - smap.voidage) * grid.cell_volume == pytest.approx(total, rel=1e-13)
    assert smap.solids_w is not None and smap.solids_w.shape == grid.shape


def test_solids_velocity_number_and_volume_average(grid):
    """A small and a large sphere in one cell: number mean (Hoomans 1996 eq. 50) and volume mean (Sun 2007
    eq. 35) of their velocities, all three components."""
    pos = np.array([[0.0121, 0.0081, 0.0121], [0.0129, 0.0089, 0.0129]])
    d = np.array([1e-3, 2e-3])
    vel = np.array([[1.0, 2.0, 3.0], [-1.0, 0.0, 1.0]])
    un, vn, wn = V.solids_velocity(grid, pos, d, vel, "number")
    assert (un[2, 1, 2], vn[2, 1, 2], wn[2, 1, 2]) == pytest.approx((0.0, 1.0, 2.0))
    uv, vv, wv = V.solids_velocity(grid, pos, d, vel, "volume")
    w = d**3 / np.sum(d**3)
    assert (uv[2, 1, 2], vv[2, 1, 2], wv[2, 1, 2]) == pytest.approx(tuple(w @ vel))


def test_methods_refused_on_the_wrong_grid(grid):
    pos = np.array([[0.01, 0.01, 0.01]])
    for method in ("area", "area_volume"):
        with pytest.raises(ValueError, match="on a 3D grid allowed are 'centroid' and 'volume'"):
            V.VoidageMapping(method=method).map(grid, pos, D)
    g2 = StaggeredGrid(cells=(4, 4), size=(0.02, 0.02), depth=D)
    with pytest.raises(ValueError, match="needs a 3D grid"):
        V.VoidageMapping(method="volume").map(g2, pos, D)


def test_sauter_inverse_of_the_cells(grid):
    """1/D̄ = Σ V_p/d_p / Σ V_p of the centres in each cell (DEM book 2012 eq. 10); empty cells take the bed's."""
    pos, d = random_spheres(grid, seed=5)
    inv = V.sauter_inverse(grid, pos, d)
    idx = tuple(np.clip((pos[:, a] / grid.spacing[a]).astype(int), 0, grid.cells[a] - 1) for a in range(3))
    vol = d**3
    num, den = np.zeros(grid.shape), np.zeros(grid.shape)
    np.add.at(num, idx, vol / d)
    np.add.at(den, idx, vol)
    bed = np.sum(vol / d) / np.sum(vol)
    expected = np.where(den > 0, num / np.where(den > 0, den, 1.0), bed)
    np.testing.assert_allclose(inv, expected, rtol=1e-13)
