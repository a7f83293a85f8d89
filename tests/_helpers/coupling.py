"""Random particles and gas states over a staggered grid, and the voidage mappings the coupling tests run."""
from __future__ import annotations

import numpy as np

from fluidem.gas.solver import GasState

MAPPINGS = {
    "centroid-number": {"method": "centroid"},
    "centroid-volume": {"method": "centroid", "velocity_weighting": "volume", "minimum_voidage": 0.4},
    "area-number-3d-smoothed": {"method": "area", "to_3d": True, "smoothing_width": 0.012},
    "area-volume": {"method": "area", "velocity_weighting": "volume"},
    "area_volume-number": {"method": "area_volume", "minimum_voidage": 0.35},
    "area_volume-volume-smoothed": {"method": "area_volume", "velocity_weighting": "volume",
                                    "smoothing_width": 0.005},
}


def random_particles(grid, n, seed):
    """Polydisperse discs uniform over the domain and a little beyond it, plus centres on faces and walls."""
    rng = np.random.default_rng(seed)
    lx, ly = grid.size
    pos = np.column_stack([rng.uniform(-0.02 * lx, 1.02 * lx, n), rng.uniform(-0.01 * ly, 1.01 * ly, n),
                           rng.uniform(0.0, 0.004, n)])
    k = n // 8  # centres exactly on x- and y-faces (where trunc(x/dx) and floor(x/dx) may part) and walls
    pos[:k, 0] = rng.integers(0, grid.shape[0] + 1, k) * grid.dx
    pos[k:2 * k, 1] = rng.integers(0, grid.shape[1] + 1, k) * grid.dy
    pos[2 * k:2 * k + 4, :2] = [[0.0, 0.0], [lx, ly], [0.0, ly], [lx, 0.0]]
    radius = rng.choice([1.5e-3, 2e-3, 2.5e-3], n)  # few sizes: cells repeat diameters
    vel = rng.normal(0.0, 0.5, (n, 3))
    return pos, radius, vel


def random_gas(grid, seed):
    """A random gas state on ``grid``: pressure about 1.013e5 Pa, density, velocities and voidage spread wide."""
    rng = np.random.default_rng(seed)
    c, fu, fv = grid.shape, grid.u_shape, grid.v_shape
    return GasState(p=1.013e5 + rng.normal(0.0, 300.0, c), rho=rng.uniform(0.9, 1.5, c),
                    u=rng.normal(0.0, 1.5, fu), v=rng.normal(1.0, 3.0, fv), voidage=rng.uniform(0.2, 1.0, c))
