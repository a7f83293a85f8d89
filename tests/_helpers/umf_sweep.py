"""The u_mf sweep bed of tests/validation/test_umf_sweep.py (also run by tests/validation/umf_budget.py).

Frictionless 0.5 mm glass spheres in a 3D box on a 2D gas grid of 4 × 4 diameter cells; after
``T_SETTLE`` of settling the inflow's superficial velocity rises linearly to ``U_MAX`` over ``T_SWEEP``.
"""
from __future__ import annotations

from fluidem.case import validate_case

D, RHO_P, MU, RHO, G = 0.5e-3, 2500.0, 1.8e-5, 1.2, 9.81  # [m], [kg/m^3], [Pa s], [kg/m^3], [m/s^2]
N, W, DEPTH, H = 12000, 60 * D, 10 * D, 60 * D  # particles; bed width, depth and box height [m]
T_SETTLE, T_SWEEP, U_MAX = 0.15, 1.0, 0.5  # [s], [s], [m/s]


def sweep_case(n=N, width=W, depth=DEPTH):
    """The validated sweep case of ``n`` spheres in a box ``width`` × ``H`` × ``depth`` [m]."""
    return validate_case({
        "name": "umf-sweep", "gravity": [0.0, -G, 0.0],
        "particles": {
            "dimensions": 3, "species": [{"diameter": D, "density": RHO_P, "count": n}],
            "contact": {"model": "linear_spring_dashpot", "stiffness": 20.0, "restitution": 0.5, "friction": 0.0},
            "placement": {"method": "random", "region_lower": [0, 0, 0], "region_upper": [width, H, depth], "seed": 1},
        },
        "walls": [{"name": "box", "kind": "box", "lower": [0, 0, 0], "upper": [width, H, depth]}],
        "time": {"end": T_SETTLE + T_SWEEP, "dt_fraction": 0.05},
        "gas": {
            "dt": 2e-4, "grid": {"cells": [round(width / (4 * D)), 15], "size": [width, H], "depth": depth},
            "properties": {"viscosity": MU, "density": RHO},
            "boundaries": {"left": {"kind": "free_slip"}, "right": {"kind": "free_slip"},
                           "bottom": {"kind": "inflow", "voidage": 1.0, "superficial": {
                               "table": [[0.0, 0.0], [T_SETTLE, 0.0], [T_SETTLE + T_SWEEP, U_MAX]]}},
                           "top": {"kind": "pressure_outlet"}},
        },
        "coupling": {"drag": "gidaspow"},
    })
