"""Cases of a few spheres in a box with periodic sides, read from a particle CSV, for the periodic tests."""
from __future__ import annotations

import numpy as np

from fluidem.particles.contact import contact_models

DIAMETER = 4e-3  # [m], as tests/conftest.py
DENSITY = 2500.0  # [kg/m^3]


def law(model: str = "linear_spring_dashpot") -> dict:
    """A registered model's example law with restitution 0.9 and friction 0.3 (the tests' defaults)."""
    return {"model": model, "restitution": 0.9, "friction": 0.3, **contact_models.get(model).example}


def periodic_case_dict(path, pos, vel=None, *, upper, periodic, dimensions=3, contact=None,
                       gravity=(0.0, 0.0, 0.0), **box) -> dict:
    """Case dict of spheres of DIAMETER at ``pos`` (written to the CSV ``path``) in the box [0, upper]
    periodic along ``periodic``; ``box``: more keys of the box wall."""
    pos = np.atleast_2d(np.asarray(pos, float))
    n = pos.shape[0]
    vel = np.zeros((n, 3)) if vel is None else np.atleast_2d(np.asarray(vel, float))
    with open(path, "w") as f:
        f.write("x,y,z,diameter,vx,vy,vz\n")
        for p, v in zip(pos, vel):
            f.write(",".join(repr(float(c)) for c in (*p, DIAMETER, *v)) + "\n")
    return {
        "name": "periodic", "gravity": list(gravity),
        "particles": {"dimensions": dimensions,
                      "species": [{"name": "p", "diameter": DIAMETER, "density": DENSITY, "count": n}],
                      "contact": contact or law(), "placement": {"method": "file", "file": str(path)}},
        "walls": [{"name": "box", "kind": "box", "lower": [0.0, 0.0, 0.0], "upper": list(upper),
                   "periodic": list(periodic), **box}],
        "time": {"end": 1.0},
    }
