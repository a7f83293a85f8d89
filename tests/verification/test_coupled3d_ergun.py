"""Through the 3D coupled path, a frozen packed bed gives Ergun's pressure drop (required: within 2 %).

The 2D test (tests/verification/test_coupled_ergun.py) on a 3D grid with gravity and the flow along z:
particles sit on a cubic lattice, 4 × 4 × 4 per gas cell and none cut by a cell face, so every bed cell
has the same voidage with either 3D mapping; they are never moved (the coupling's gas steps run, the DEM
steps do not). Each gas step goes the whole coupled way: particles → voidage (the mapping under test),
each particle's K_p with the ``hoomans1996`` law (Ergun's β of Hoomans eq. 45 for ε < 0.8) deposited on
the faces, the gas solve with the paired pressure voidage, gas → particle forces. In steady plug flow
eq. 43 reduces to

    −dp/dz − ρ g = β U/ε² = 150 (1−ε)²/ε³ μU/d² + 1.75 (1−ε)/ε³ ρU²/d   (Ergun),

U superficial. The expected voidage is computed here from the lattice, independently of the mapping code:
ε = 1 − 64 V_p / dx³. The 2 % is the 2D test's requirement; plug flow through uniform cells is an exact
discrete solution, so what is left is the gas solver's tolerance (measured: 3e-12 at 0.2 m/s, 2e-14 at 3 m/s,
both mappings alike).
"""
import math

import numpy as np
import pytest

from fluidem.case import validate_case
from fluidem.simulation import Simulation

D = 2.4e-3  # particle diameter [m]
PITCH = 2.5e-3  # lattice pitch [m]: 4 per 10 mm cell along each axis, 0.05 mm clear of its faces
CELL = 0.01
NX, NY, NZ, BED_LAYERS = 2, 2, 8, 4
MU, RHO, G = 1.8e-5, 1.2, 9.81


def lattice():
    xs = np.arange(NX * 4) * PITCH + 0.5 * PITCH
    ys = np.arange(NY * 4) * PITCH + 0.5 * PITCH
    zs = np.arange(BED_LAYERS * 4) * PITCH + 0.5 * PITCH
    x, y, z = np.meshgrid(xs, ys, zs, indexing="ij")
    return np.column_stack([x.ravel(), y.ravel(), z.ravel()])


def ergun_gradient(eps, superficial):
    return (150.0 * (1 - eps) ** 2 / eps**3 * MU * superficial / D**2
            + 1.75 * (1 - eps) / eps**3 * RHO * superficial**2 / D)


def frozen_bed(write_particles, superficial, method, exchange="particle"):
    pos = lattice()
    path = write_particles(pos, D)
    case = validate_case({
        "name": "frozen-bed-3d",
        "gravity": [0.0, 0.0, -G],
        "particles": {
            "dimensions": 3,
            "species": [{"diameter": D, "density": 2500.0, "count": pos.shape[0]}],
            "contact": {"model": "linear_spring_dashpot", "stiffness": 1e3, "restitution": 0.9},
            "placement": {"method": "file", "file": str(path)},
        },
        "time": {"end": 1.0},
        "gas": {
            "dt": 2e-4,
            "grid": {"cells": [NX, NY, NZ], "size": [NX * CELL, NY * CELL, NZ * CELL]},
            "properties": {"viscosity": MU, "density": RHO},
            "initial_velocity": [0.0, 0.0, superficial],
            "boundaries": {"left": {"kind": "free_slip"}, "right": {"kind": "free_slip"},
                           "bottom": {"kind": "free_slip"}, "top": {"kind": "free_slip"},
                           "front": {"kind": "inflow", "superficial": superficial, "voidage": 1.0},
                           "back": {"kind": "pressure_outlet"}},
        },
        "coupling": {"drag": "hoomans1996", "voidage": {"method": method}, "momentum_exchange": exchange},
    })
    sim = Simulation(case)
    for _ in range(300):  # gas steps only: the particles stay where they are
        sim.gas.gas_step()
    return sim


@pytest.mark.parametrize("method", ["centroid", "volume"])
@pytest.mark.parametrize("superficial", [0.2, 1.0, 3.0])
def test_frozen_packed_bed_gives_ergun(write_particles, superficial, method):
    check_ergun(frozen_bed(write_particles, superficial, method), superficial)


@pytest.mark.parametrize("superficial", [0.2, 1.0, 3.0])
def test_frozen_packed_bed_gives_ergun_with_the_cell_exchange(write_particles, superficial):
    """``momentum_exchange = "cell"``: β of each bed cell from its voidage and slip (Sun 2007 eq. 33), averaged
    onto the faces; between two bed cells the face takes the same β, so the interior layers give Ergun alike."""
    check_ergun(frozen_bed(write_particles, superficial, "volume", exchange="cell"), superficial)


def check_ergun(sim, superficial):
    gas, grid = sim.gas, sim.gas.grid
    eps = 1.0 - 64 * math.pi / 6.0 * D**3 / CELL**3
    bed = gas.state.voidage[:, :, :BED_LAYERS]
    assert np.abs(bed - eps).max() < 1e-12, "the lattice fills every bed cell alike"
    assert eps < 0.8  # the Ergun branch of hoomans1996
    assert sim.state.velocity.max() == 0.0  # frozen
    k0, k1 = 1, BED_LAYERS - 2  # interior bed layers, away from the inlet and the bed surface
    dp = gas.state.p[:, :, k0] - gas.state.p[:, :, k1]
    frictional = dp / ((k1 - k0) * grid.dz) - RHO * G
    err = np.abs(frictional / ergun_gradient(eps, superficial) - 1.0).max()
    assert err < 0.02, err
