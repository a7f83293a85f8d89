"""Inflow patches on a side of a 3D gas grid: circles and rectangles with their own velocity and time dependence.

Faces are assigned by exact area: each boundary face takes the fraction of its area inside the patch (for
a circle the exact area of the circle–rectangle intersection, ``patches.circle_rectangle_area``), so the
mass flow through a circle within the side is ρ ε u π r² to round-off (1e-12 relative is asserted), however
the circle meets the grid, and the raster's area error is nil; without it (whole faces in or out by their
centres) a 1.3-cell radius would be off by 10 % or more.
"""
import math

import numpy as np
import pytest

from fluidem.errors import CaseError
from fluidem.gas import (
    Circle,
    GasProperties,
    GasSolver,
    Inflow,
    PressureOutlet,
    Pulse,
    Rectangle,
    StaggeredGrid,
    Wall,
)
from fluidem.gas.boundaries.patches import circle_rectangle_area


@pytest.mark.parametrize("box", [(-1.0, 1.0, -1.0, 1.0), (0.0, 1.0, 0.0, 1.0), (0.1, 0.3, -0.2, 0.45),
                                 (0.3, 0.4, 0.3, 0.4), (0.6, 0.9, -0.1, 0.2)])
def test_circle_rectangle_area_against_a_fine_quadrature(box):
    x0, x1, y0, y1 = box
    r = 0.5
    x = np.linspace(x0, x1, 400001)  # the chord's square-root ends: error ~ (dx)^1.5
    h = np.sqrt(np.maximum(r * r - x * x, 0.0))
    chord = np.clip(np.minimum(y1, h) - np.maximum(y0, -h), 0.0, None)
    reference = np.trapezoid(chord, x)
    assert circle_rectangle_area(x0, x1, y0, y1, r) == pytest.approx(reference, rel=1e-5, abs=1e-9)


def bed(patches, background=None, density=1.2):
    grid = StaggeredGrid(cells=(10, 8, 12), size=(0.1, 0.08, 0.12))
    inflow = Inflow(patches=patches, voidage=0.4, **({} if background is None else {"superficial": background}))
    bcs = {s: Wall() for s in grid.sides}
    bcs.update(bottom=inflow, top=PressureOutlet())
    return grid, GasSolver(grid, GasProperties(density=density), bcs)


@pytest.mark.parametrize("centre, radius", [((0.05, 0.06), 0.013), ((0.0437, 0.0711), 0.0229), ((0.05, 0.06), 0.004)])
def test_circular_patch_mass_flow_is_rho_eps_u_pi_r2(centre, radius):
    u, rho, eps = 12.0, 1.2, 0.4
    grid, solver = bed([Circle(centre=centre, radius=radius, interstitial=u)], density=rho)
    state = solver.initial_state(pressure=1e5)
    info = solver.advance(state, 1e-4, 0.0)
    assert info.converged
    exact = rho * eps * u * math.pi * radius**2
    assert info.inflow_rate == pytest.approx(exact, rel=1e-12)
    # the face velocities: u on faces inside, 0 far outside, the covered fraction across the rim
    v0 = state.v[:, 0, :]
    assert v0.min() == 0.0 and v0.max() <= u * (1.0 + 1e-14)
    if radius > 2.0 * grid.dx:
        assert v0.max() == pytest.approx(u, rel=1e-14)
    assert (v0 * grid.area_y).sum() == pytest.approx(u * math.pi * radius**2, rel=1e-12)


def test_rectangles_and_circles_with_a_background_and_time_dependence():
    """A distributor: 0.2 m/s superficial background, a central jet and two nozzles pulsed in turn."""
    eps = 0.4
    jet = Circle(centre=(0.05, 0.06), radius=0.01, interstitial=10.0)
    nozzle1 = Rectangle(start=(0.01, 0.01), end=(0.025, 0.03), interstitial=Pulse(4.0, start=0.0, duration=2e-4))
    nozzle2 = Circle(centre=(0.08, 0.02), radius=0.006, superficial=Pulse(2.0, start=2e-4, duration=1.0))
    grid, solver = bed([jet, nozzle1, nozzle2], background=0.2)
    state = solver.initial_state(pressure=1e5)
    side = grid.size[0] * grid.size[2]
    a_jet, a_1, a_2 = jet.area(), nozzle1.area(), nozzle2.area()
    flows = []
    for k in range(4):
        info = solver.advance(state, 1e-4, k * 1e-4)
        flows.append(info.inflow_rate)
    rho = 1.2
    background = 0.2 / eps * (side - a_jet - a_1 - a_2)  # [m^3/s] of interstitial velocity × area
    first = rho * eps * (background + 10.0 * a_jet + 4.0 * a_1)
    later = rho * eps * (background + 10.0 * a_jet + 2.0 / eps * a_2)
    assert flows[0] == pytest.approx(first, rel=1e-12)  # velocities at the step's end, t + dt = 1e-4
    assert flows[2] == pytest.approx(later, rel=1e-12)


def test_patches_refused_where_they_do_not_belong():
    with pytest.raises(CaseError, match="overlap"):
        Inflow(patches=[Circle(centre=(0.05, 0.05), radius=0.02, interstitial=1.0),
                        Rectangle(start=(0.06, 0.0), end=(0.08, 0.1), interstitial=1.0)])
    with pytest.raises(CaseError, match="covers no part"):
        bed([Circle(centre=(0.5, 0.5), radius=0.01, interstitial=1.0)])
    grid = StaggeredGrid(cells=(4, 4), size=(0.1, 0.1), depth=0.01)
    with pytest.raises(CaseError, match="need a 3D grid"):
        GasSolver(grid, GasProperties(), {"left": Wall(), "right": Wall(), "top": PressureOutlet(),
                                          "bottom": Inflow(patches=[Circle(centre=(0.05, 0.0), radius=0.01,
                                                                           interstitial=1.0)])})
