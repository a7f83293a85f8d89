"""Particle → grid mapping (coupling/voidage): exact conservation, exact corner split, eq. 49, clipping,
smoothing, solids-velocity averages (Sun 2007 eqs 34-35, Hoomans 1996 §3.4, eqs 49-50)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from fluidem.coupling import voidage as V
from fluidem.coupling._voidage_kernels import disc_rect_area
from fluidem.gas.grid import StaggeredGrid

D = 4e-3


def straddling(grid, n=40, seed=1):
    """Particles on cell edges, corners and at random, all discs inside the domain."""
    rng = np.random.default_rng(seed)
    xf, yf = grid.x_faces[1:-1], grid.y_faces[1:-1]
    corners = np.array([[x, y, 0.0] for x in xf[:3] for y in yf[:3]])
    edges = np.array([[xf[1], grid.y_centres[2] + 0.3 * grid.dy, 0.0], [grid.x_centres[1], yf[0] + 1e-4, 0.0]])
    r = 0.5 * D
    rand = np.column_stack([rng.uniform(r, grid.size[0] - r, n), rng.uniform(r, grid.size[1] - r, n), np.zeros(n)])
    pos = np.vstack([corners, edges, rand])
    return pos, rng.uniform(0.6, 1.0, len(pos)) * D


@pytest.fixture
def grid():
    return StaggeredGrid(cells=(6, 8), size=(0.03, 0.048), depth=D)  # dx = 5 mm, dy = 6 mm


def test_centroid_conserves_solids_volume(grid):
    """Σ (1−ε) V_cell = Σ V_p to 1e-12 relative (Sun 2007 eq. 34), depth = one diameter (Sun after eq. 35)."""
    pos, d = straddling(grid)
    frac = V.solids_fraction(grid, pos, d, "centroid")
    assert np.sum(frac) * grid.cell_volume == pytest.approx(np.sum(math.pi / 6 * d**3), rel=1e-12)


def test_centroid_single_particle_in_a_cell_of_depth_d():
    g = StaggeredGrid(cells=(3, 3), size=(3 * 4 * D, 3 * 4 * D), depth=D)
    frac = V.solids_fraction(g, [[6 * D, 6 * D, 0.0]], D, "centroid")
    assert frac[1, 1] == pytest.approx((math.pi / 6 * D**3) / (16 * D**3), rel=1e-15)
    assert np.count_nonzero(frac) == 1


def test_area_conserves_disc_area(grid):
    """Σ (1−ε_2D) dx dy = Σ π r² to 1e-12 relative, discs straddling edges and corners."""
    pos, d = straddling(grid)
    frac = V.solids_fraction(grid, pos, d, "area")
    assert np.sum(frac) * grid.dx * grid.dy == pytest.approx(np.sum(math.pi * d**2 / 4), rel=1e-12)


def test_area_volume_conserves_solids_volume(grid):
    pos, d = straddling(grid)
    frac = V.solids_fraction(grid, pos, d, "area_volume")
    assert np.sum(frac) * grid.cell_volume == pytest.approx(np.sum(math.pi / 6 * d**3), rel=1e-12)


def test_disc_on_a_corner_splits_in_four(grid):
    x, y = grid.x_faces[2], grid.y_faces[3]
    frac = V.solids_fraction(grid, [[x, y, 0.0]], D, "area") * grid.dx * grid.dy
    quarter = math.pi * D**2 / 16
    np.testing.assert_allclose(frac[1:3, 2:4], quarter, rtol=1e-14)
    assert np.count_nonzero(frac) == 4


def test_area_against_fine_raster():
    """Random discs (up to 2 cells wide) vs midpoint raster of 400 × 400 pixels per cell. A pixel is misjudged
    only if the circle crosses it (cell edges lie on pixel edges), so |error| ≤ 2π r · √2 h per disc
    (h = pixel size); asserted per cell against that bound summed over the discs touching it."""
    rng = np.random.default_rng(7)
    g = StaggeredGrid(cells=(3, 3), size=(0.03, 0.03), depth=1.0)
    n = 6
    r = rng.uniform(0.002, 0.01, n)
    pos = np.column_stack([rng.uniform(r, 0.03 - r), rng.uniform(r, 0.03 - r), np.zeros(n)])
    frac = V.solids_fraction(g, pos, 2 * r, "area") * g.dx * g.dy
    m = 400
    h = g.dx / m
    for i in range(3):
        for j in range(3):
            xs = i * g.dx + (np.arange(m) + 0.5) * h
            ys = j * g.dy + (np.arange(m) + 0.5) * h
            X, Y = np.meshgrid(xs, ys, indexing="ij")
            raster = sum(np.count_nonzero((X - px) ** 2 + (Y - py) ** 2 < rr**2) for (px, py, _), rr in zip(pos, r)) * h * h
            bound = sum(2 * math.pi * rr * math.sqrt(2) * h for rr in r)
            assert abs(frac[i, j] - raster) <= bound


def test_disc_rect_area_single_pieces():
    r = 1.0
    assert disc_rect_area(0.0, 0.0, r, -2.0, 2.0, -2.0, 2.0) == pytest.approx(math.pi, rel=1e-15)
    assert disc_rect_area(0.0, 0.0, r, 0.0, 2.0, -2.0, 2.0) == pytest.approx(math.pi / 2, rel=1e-15)
    # circular segment above y = 0.5: r² acos(0.5) − 0.5 sqrt(r² − 0.25)
    seg = math.acos(0.5) - 0.5 * math.sqrt(0.75)
    assert disc_rect_area(0.0, 0.0, r, -2.0, 2.0, 0.5, 2.0) == pytest.approx(seg, rel=1e-14)
    assert disc_rect_area(0.0, 0.0, r, 1.0, 2.0, -2.0, 2.0) == 0.0


def test_eq49_conversion():
    """Hoomans 1996 eq. 49: hexagonal 2D packing (1−ε = π/(2√3)) maps onto FCC (1−ε = π/(3√2)); other values
    against the formula to 1e-15."""
    e2 = 1 - math.pi / (2 * math.sqrt(3))
    assert V.voidage_3d_from_2d(e2) == pytest.approx(1 - math.pi / (3 * math.sqrt(2)), abs=1e-15)
    e = np.array([0.2, 0.5, 0.9, 1.0])
    np.testing.assert_allclose(V.voidage_3d_from_2d(e),
                               1 - 2 / np.sqrt(np.pi * np.sqrt(3)) * (1 - e) ** 1.5, rtol=1e-15)


def test_clipping_counts():
    e = np.array([[0.1, 0.5], [0.29, 0.3]])
    clipped, count = V.clip_voidage(e, 0.3)
    assert count == 2
    np.testing.assert_array_equal(clipped, [[0.3, 0.5], [0.3, 0.3]])
    g = StaggeredGrid(cells=(2, 1), size=(2 * D, D), depth=D)
    pos = np.array([[0.5 * D, 0.5 * D, 0], [0.5 * D, 0.5 * D, 0]])  # two spheres in one cube cell: 1−ε = π/3 > 1
    m = V.VoidageMapping(method="centroid", minimum_voidage=0.35).map(g, pos, D)
    assert m.clipped == 1 and m.voidage[0, 0] == 0.35 and m.voidage[1, 0] == 1.0


def test_smoothing_conserves_and_has_the_stated_width():
    """Spike far from walls: Σ kept to 1e-14, and its variance in x and y equals width² to 1e-12 (each explicit
    diffusion step adds exactly 2 D Δt)."""
    g = StaggeredGrid(cells=(41, 41), size=(0.041, 0.041), depth=1.0)
    f = np.zeros(g.shape)
    f[20, 20] = 1.0
    width = 0.003
    s = V.smooth(g, f, width)
    assert s.sum() == pytest.approx(1.0, rel=1e-14)
    X, Y = g.centres()
    for c in (X, Y):
        mean = np.sum(s * c)
        assert np.sum(s * (c - mean) ** 2) == pytest.approx(width**2, rel=1e-10)


def test_smoothing_near_walls_conserves(grid):
    pos, d = straddling(grid)
    frac = V.solids_fraction(grid, pos, d, "area_volume")
    s = V.smooth(grid, frac, 0.01)
    assert s.sum() == pytest.approx(frac.sum(), rel=1e-13)


def test_solids_velocity_number_and_volume_average():
    """Hoomans 1996 eq. 50 (number mean) vs Sun 2007 eq. 35 (volume mean) for a small and a large particle."""
    g = StaggeredGrid(cells=(2, 2), size=(0.02, 0.02), depth=D)
    pos = np.array([[0.002, 0.003, 0], [0.006, 0.004, 0], [0.015, 0.015, 0]])
    d = np.array([1e-3, 2e-3, 1e-3])
    vel = np.array([[1.0, -1.0, 0], [4.0, 2.0, 0], [0.5, 0.25, 0]])
    un, vn = V.solids_velocity(g, pos, d, vel, "number")
    assert (un[0, 0], vn[0, 0]) == pytest.approx((2.5, 0.5), rel=1e-15)
    uv, vv = V.solids_velocity(g, pos, d, vel, "volume")
    assert (uv[0, 0], vv[0, 0]) == pytest.approx(((1 + 8 * 4) / 9, (-1 + 8 * 2) / 9), rel=1e-14)
    assert (un[1, 1], vn[1, 1]) == (0.5, 0.25)
    assert un[1, 0] == 0.0 and un[0, 1] == 0.0  # empty cells


def test_mapping_options_are_validated():
    with pytest.raises(Exception):
        V.VoidageMapping(method="nearest")
    with pytest.raises(Exception):
        V.VoidageMapping(smoothing=1.0)
    g = StaggeredGrid(cells=(2, 2), size=(0.02, 0.02), depth=D)
    with pytest.raises(ValueError, match="eq. 49"):
        V.VoidageMapping(method="centroid", to_3d=True).map(g, [[0.01, 0.01, 0]], D)
    m = V.VoidageMapping(method="area", to_3d=True).map(g, [[0.01, 0.01, 0]], D)
    e2 = 1 - (math.pi * D**2 / 16) / 1e-4
    np.testing.assert_allclose(m.voidage, V.voidage_3d_from_2d(e2), rtol=1e-14)


def test_area_drops_discs_wholly_outside_the_grid():
    """A disc beyond a side of the grid, cut by a grid line out there, adds nothing: no cell inside gains area
    (a negative index would wrap to the far side) and nothing lands past the array's end."""
    from fluidem.coupling._voidage_kernels import area_deposit

    nx, ny, dx, dy = 4, 5, 0.01, 0.01
    r = 0.2 * dx
    # centres on the grid lines x = (nx + 1) dx, x = -dx, y = (ny + 1) dy, y = -dy, inside the other range
    px = np.array([(nx + 1) * dx, -dx, 0.5 * dx, 0.5 * dx])
    py = np.array([0.5 * dy, 0.5 * dy, (ny + 1) * dy, -dy])
    n = px.size
    big = np.zeros((nx + 4, ny + 4))  # the map is big[2:-2, 2:-2]: a stray write lands in the margin
    bvx, bvy = np.zeros_like(big), np.zeros_like(big)
    area_deposit(px, py, np.full(n, r), np.ones(n), np.ones(n), np.ones(n), dx, dy,
                 big[2:-2, 2:-2], bvx[2:-2, 2:-2], bvy[2:-2, 2:-2])
    assert not big.any() and not bvx.any() and not bvy.any()
