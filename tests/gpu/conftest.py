"""The GPU engine against the CPU engine: run where numba.cuda works in this process.

That is on a machine with an NVIDIA GPU (``python3 -m pytest tests/gpu``: the kernels run for real), or under
the CUDA simulator (``NUMBA_ENABLE_CUDASIM=1`` set before Numba is imported: the kernels run as Python,
thread by thread). The simulator must be chosen before Numba is imported, and the suite's own conftest
imports it first, so in the ordinary ``python3 -m pytest`` run these tests are skipped in-process and
``tests/unit/test_gpu_device.py`` runs this folder in a subprocess under the simulator.

Factories
---------
packing_case(model, n=..., dimensions=3, seed=..., **kw)   (case, state): a jittered lattice pressed against
                                                           the walls of a box, random velocities and spins
"""
from __future__ import annotations

import numpy as np
import pytest

from fluidem.case import validate_case
from fluidem.state import ParticleState


DIAMETER = 4e-3  # [m]
DENSITY = 2500.0  # [kg/m^3]
LAWS = {
    "hertz_mindlin": {"model": "hertz_mindlin", "youngs_modulus": 5e6, "poisson_ratio": 0.3, "restitution": 0.8,
                      "friction": 0.4},
    "linear_spring_dashpot": {"model": "linear_spring_dashpot", "stiffness": 2e3, "restitution": 0.8,
                              "friction": 0.4},
}


def make_packing(model: str, n: int = 120, dimensions: int = 3, seed: int = 3, speed: float = 0.5,
                 spin: float = 50.0, two_species: bool = True, moving_wall: bool = False, pitch: float = 0.97,
                 margin: float = 0.48, **time):
    """(case, state): n spheres on a lattice of ``pitch`` d (0.97: neighbours overlap by 3 %), jittered, in a
    box ``margin`` d from the outer centres (0.48: the walls cut into the outer layer); two sizes in two species with a per-pair override (the contact
    tables are per species pair); gravity; random velocities [m/s] and spins [rad/s]."""
    rng = np.random.default_rng(seed)
    pitch = pitch * DIAMETER
    per = int(np.ceil(n ** (1.0 / dimensions)))
    idx = np.array(np.meshgrid(*[np.arange(per)] * dimensions, indexing="ij")).reshape(dimensions, -1).T[:n]
    pos = np.zeros((n, 3))
    pos[:, :dimensions] = (idx + 0.5) * pitch + margin * DIAMETER
    pos[:, :dimensions] += rng.uniform(-0.02, 0.02, (n, dimensions)) * DIAMETER
    upper = pos.max(axis=0) + margin * DIAMETER
    if dimensions == 2:
        pos[:, 2] = 0.5 * DIAMETER
        upper[2] = DIAMETER
    species = (np.arange(n) % 2) if two_species else np.zeros(n, np.int64)
    diam = np.where(species == 1, 0.9 * DIAMETER, DIAMETER)
    vel = rng.normal(0.0, speed, (n, 3))
    omega = rng.normal(0.0, spin, (n, 3))
    if dimensions == 2:
        vel[:, 2] = 0.0
        omega[:, :2] = 0.0
    law = dict(LAWS[model])
    box = {"name": "box", "kind": "box", "lower": [0.0, 0.0, 0.0], "upper": upper.tolist()}
    if moving_wall:
        box["motion"] = {"kind": "oscillation", "amplitude": [0.0, 0.0, 2e-4], "frequency": 50.0}
    data = {
        "name": "gpu-packing",
        "gravity": [0.0, -9.81, 0.0] if dimensions == 2 else [0.0, 0.0, -9.81],
        "particles": {
            "dimensions": dimensions,
            "species": [{"name": "a", "diameter": DIAMETER, "density": DENSITY, "count": int(np.sum(species == 0))},
                        {"name": "b", "diameter": 0.9 * DIAMETER, "density": 1.2 * DENSITY,
                         "count": int(np.sum(species == 1))}] if two_species else
            [{"name": "a", "diameter": DIAMETER, "density": DENSITY, "count": n}],
            "contact": law,
            "pairs": [{"species": ["a", "b"], "restitution": 0.6, "friction": 0.2}] if two_species else [],
            "placement": {"method": "lattice"},
        },
        "walls": [box],
        "time": {"end": 1.0, "dt": 2e-6, **time},
        "neighbours": {"skin": 0.1 * DIAMETER},
    }
    case = validate_case(data)
    dens = np.array([s.density for s in case.particles.species])
    state = ParticleState.create(pos, vel, diam, species.astype(np.int64), dens)
    state.omega[...] = omega
    return case, state


def copy_state(state: ParticleState) -> ParticleState:
    return ParticleState(**{k: np.array(v) for k, v in state.arrays().items()})


@pytest.fixture
def packing_case():
    """``packing_case(model, n=..., dimensions=3, ...)`` -> (case, state) (``make_packing``)."""
    return make_packing


@pytest.fixture
def clone():
    """``clone(state)`` -> an independent copy of a ``ParticleState``."""
    return copy_state
