"""A one-cell-deep 3D gas grid with free-slip front and back, coupled to spheres whose centres lie in its mid
plane, gives the 2D coupled result (a 2D grid of that depth, 2D particles) within the gas solver's tolerance.

Why it holds: the 2D path's cells have volume dx dy depth and the 3D path's dx dy dz with dz = depth, so the
centroid voidage is the same; with one cell along z the trilinear weights reduce to the bilinear ones (one
centre node, and the z-faces at the free-slip front and back, whose w = 0); ∂p/∂z is 0 with one cell; the
face control volumes are those of 2D along x and y. In-plane contacts give in-plane forces and torques about
z only. What differs is the pressure-correction solve (2D band LU, 3D GMRES with multigrid), each converged
to the mass tolerance 1e-10, and the order of some sums (round-off): the two runs drift apart at that level.
Measured over 25 gas steps (5 ms) of 24 spheres settling against an upflow: positions agree to 1e-17 m,
velocities to 1e-14 m/s, gas pressures to 1e-10 Pa and gas velocities to 1e-11 m/s; required 1e-9 m,
1e-6 m/s and 1e-6 Pa, orders above the solver tolerance's effect and orders below any modelling difference.
"""
import numpy as np
import pytest

from fluidem.case import validate_case
from fluidem.simulation import Simulation

D = 2e-3
NX, NY, CELL = 4, 10, 5e-3


def positions(n=24, seed=4):
    """Spheres in a loose layer near the bottom, apart from each other by at least 1.05 D."""
    rng = np.random.default_rng(seed)
    out = []
    while len(out) < n:
        p = np.array([rng.uniform(0.6 * D, NX * CELL - 0.6 * D), rng.uniform(0.6 * D, 0.02), 0.5 * D])
        if all(np.linalg.norm(p - q) > 1.05 * D for q in out):
            out.append(p)
    return np.array(out)


def case(write_particles, three, exchange="particle"):
    pos = positions()
    path = write_particles(pos, D)
    boundaries = {"left": {"kind": "wall"}, "right": {"kind": "wall"},
                  "bottom": {"kind": "inflow", "superficial": 1.2, "voidage": 1.0}, "top": {"kind": "pressure_outlet"}}
    grid = {"cells": [NX, NY], "size": [NX * CELL, NY * CELL], "depth": D}
    if three:
        boundaries |= {"front": {"kind": "free_slip"}, "back": {"kind": "free_slip"}}
        grid = {"cells": [NX, NY, 1], "size": [NX * CELL, NY * CELL, D]}
    return validate_case({
        "name": "equivalence",
        "gravity": [0.0, -9.81, 0.0],
        "particles": {"dimensions": 3 if three else 2,
                      "species": [{"diameter": D, "density": 2500.0, "count": pos.shape[0]}],
                      "contact": {"model": "linear_spring_dashpot", "stiffness": 500.0, "restitution": 0.9,
                                  "friction": 0.3},
                      "placement": {"method": "file", "file": str(path)}},
        "walls": [{"name": "box", "kind": "box", "lower": [0.0, 0.0, 0.0], "upper": [NX * CELL, NY * CELL, D]}],
        "time": {"end": 1.0},
        "gas": {"dt": 2e-4, "grid": grid, "properties": {"viscosity": 1.8e-5, "density": 1.2},
                "boundaries": boundaries, "initial_velocity": [0.0, 1.2] + ([0.0] if three else [])},
        "coupling": {"drag": "di_felice", "momentum_exchange": exchange},
    })


@pytest.mark.parametrize("exchange", ["particle", "cell"])
def test_one_cell_deep_3d_grid_gives_the_2d_coupled_result(write_particles, exchange):
    """"cell" as "particle": the cell β from the same cell voidage and slip (w = 0 and no z velocity in
    the mid plane), the same face averages along x and y, and the same share of the cell's drag per sphere."""
    sims = [Simulation(case(write_particles, three, exchange)) for three in (False, True)]
    assert sims[0].gas.substeps == sims[1].gas.substeps
    for sim in sims:
        sim.advance(25 * sim.gas.substeps)
    two, three = sims
    assert np.abs(three.state.position[:, 2] - 0.5 * D).max() == 0.0  # the spheres stay in the mid plane
    assert np.abs(three.state.position - two.state.position).max() < 1e-9
    assert np.abs(three.state.velocity - two.state.velocity).max() < 1e-6
    assert np.abs(two.state.velocity).max() > 0.01  # they moved
    assert np.abs(three.gas.state.p[:, :, 0] - two.gas.state.p).max() < 1e-6
    assert np.abs(three.gas.state.v[:, :, 0] - two.gas.state.v).max() < 1e-6
