"""Grid → particle interpolation (coupling/interpolation, Hoomans 1996 eqs 40-41) on the staggered grid:
linear and constant fields reproduced to round-off everywhere including the wall strips, weights sum to 1,
pressure gradients exact for linear and quadratic pressure."""
from __future__ import annotations

import numpy as np
import pytest

from fluidem.coupling import interpolation as I
from fluidem.gas.grid import StaggeredGrid
from fluidem.gas.solver import GasState

GRID = StaggeredGrid(cells=(7, 5), size=(0.07, 0.1), depth=0.004)


def positions(n=500, seed=3):
    """Random points plus the four corners, points on the walls and in the half-cell wall strips."""
    rng = np.random.default_rng(seed)
    lx, ly = GRID.size
    pts = [rng.uniform(0, lx, n), rng.uniform(0, ly, n)]
    special = np.array([[0, 0], [lx, 0], [0, ly], [lx, ly], [0.2 * GRID.dx, 0.5 * ly], [lx - 0.1 * GRID.dx, 0.3 * ly],
                        [0.4 * lx, 0.1 * GRID.dy], [0.6 * lx, ly - 0.3 * GRID.dy], [GRID.dx, GRID.dy]])
    xy = np.vstack([np.column_stack(pts), special])
    return np.column_stack([xy, np.zeros(len(xy))])


def field(location, f):
    X, Y = {"centre": GRID.centres(),
            "x_face": np.meshgrid(GRID.x_faces, GRID.y_centres, indexing="ij"),
            "y_face": np.meshgrid(GRID.x_centres, GRID.y_faces, indexing="ij")}[location]
    return f(X, Y)


LINEAR = lambda x, y: 3.0 + 20.0 * x - 7.0 * y


@pytest.mark.parametrize("location", I.LOCATIONS)
def test_linear_fields_reproduced(location):
    """a + b x + c y at every point (walls, corners, wall strips) to 1e-13 relative with 'linear' boundaries."""
    pos = positions()
    got = I.interpolate(GRID, field(location, LINEAR), pos, location, "linear")
    np.testing.assert_allclose(got, LINEAR(pos[:, 0], pos[:, 1]), rtol=1e-13, atol=0)


@pytest.mark.parametrize("location", I.LOCATIONS)
@pytest.mark.parametrize("boundary", ["linear", "copy"])
def test_constant_fields_reproduced(location, boundary):
    pos = positions()
    got = I.interpolate(GRID, field(location, lambda x, y: np.full_like(x, 2.5)), pos, location, boundary)
    np.testing.assert_allclose(got, 2.5, rtol=1e-15)


@pytest.mark.parametrize("location", I.LOCATIONS)
def test_weights_sum_to_one_and_reproduce_interpolate(location):
    pos = positions()
    index, w = I.weights(GRID, pos, location)
    np.testing.assert_allclose(w.sum(axis=1), 1.0, rtol=0, atol=1e-15)
    assert np.all(w >= 0.0)
    ext = I.extend(GRID, field(location, LINEAR), location, "linear")
    i, j = index[:, 0], index[:, 1]
    manual = w[:, 0] * ext[i, j] + w[:, 1] * ext[i + 1, j] + w[:, 2] * ext[i + 1, j + 1] + w[:, 3] * ext[i, j + 1]
    np.testing.assert_allclose(manual, I.interpolate(GRID, field(location, LINEAR), pos, location), rtol=1e-14)


def test_wall_value_is_used_at_the_wall():
    """u on x-faces with 0 on bottom and top (no-slip tangential velocity): 0 on those walls, linear between
    the wall and the first row of faces."""
    u = field("x_face", lambda x, y: np.ones_like(x))
    pos = np.array([[0.03, 0.0, 0], [0.03, GRID.size[1], 0], [0.03, 0.25 * GRID.dy, 0]])
    got = I.interpolate(GRID, u, pos, "x_face", {"bottom": 0.0, "top": 0.0})
    np.testing.assert_allclose(got, [0.0, 0.0, 0.5], rtol=1e-15)


def test_pressure_gradient_linear_and_quadratic():
    """Linear p: constant gradient at every particle to 1e-12. Quadratic p(y) = p0 − a y²: centred differences
    are exact at faces and the wall faces are extrapolated linearly, so −2 a y is reproduced to 1e-9."""
    pos = positions()
    p = field("centre", lambda x, y: 1e5 + 300.0 * x - 9000.0 * y)
    gx, gy = I.pressure_gradient(GRID, p)
    np.testing.assert_allclose(I.interpolate(GRID, gx, pos, "x_face"), 300.0, rtol=1e-9)
    np.testing.assert_allclose(I.interpolate(GRID, gy, pos, "y_face"), -9000.0, rtol=1e-9)
    q = field("centre", lambda x, y: 1e5 - 4e4 * y**2)
    gx, gy = I.pressure_gradient(GRID, q, "linear")
    np.testing.assert_allclose(I.interpolate(GRID, gy, pos, "y_face"), -8e4 * pos[:, 1], rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(gx, 0.0, atol=1e-9)


def test_pressure_gradient_across_a_periodic_side():
    """Periodic x: both side faces take the difference of the two edge cells the side joins (a cosine over the
    width: its centred difference there), the y side faces still copy their interior neighbours."""
    width = GRID.nx * GRID.dx
    q = field("centre", lambda x, y: 1e5 + 50.0 * np.cos(2 * np.pi * x / width) - 9000.0 * y)
    gx, gy = I.pressure_gradient(GRID, q, "copy", (True, False))
    side = (q[0] - q[-1]) / GRID.dx
    np.testing.assert_array_equal(gx[0], side)
    np.testing.assert_array_equal(gx[-1], side)
    xf = GRID.dx * np.arange(GRID.nx + 1)  # centred difference of the cosine at each face, x = 0 ≡ width
    want = -50.0 * 2 * np.pi / width * np.sin(2 * np.pi * xf / width) * np.sinc(GRID.dx / width)
    np.testing.assert_allclose(gx[:, 0], want, atol=1e-9 * 50.0 / GRID.dx)
    np.testing.assert_allclose(gy, -9000.0, rtol=1e-9)


def test_sample_gas_state():
    pos = positions(50)
    st = GasState(p=field("centre", lambda x, y: 1e5 - 100 * y), rho=np.ones(GRID.shape),
                  u=field("x_face", LINEAR), v=field("y_face", lambda x, y: 2 * x + y),
                  voidage=np.full(GRID.shape, 0.45))
    s = I.sample_gas(GRID, st, pos)
    np.testing.assert_allclose(s["u"], LINEAR(pos[:, 0], pos[:, 1]), rtol=1e-13)
    np.testing.assert_allclose(s["v"], 2 * pos[:, 0] + pos[:, 1], rtol=1e-13, atol=1e-15)
    np.testing.assert_allclose(s["voidage"], 0.45, rtol=1e-15)
    np.testing.assert_allclose(s["dpdy"], -100.0, rtol=1e-9)
    np.testing.assert_allclose(s["p"], 1e5 - 100 * pos[:, 1], rtol=1e-14)
