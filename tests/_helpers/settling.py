"""A lone sphere settling in still gas: the case of tests/verification/test_coupled_settling.py.

A 100 µm glass-like sphere in air, released near the top of a 2D gas box (3 × 30 cells,
0.03 × 0.3 m) of 1 m depth, so that its drag hardly moves the gas.
"""
from __future__ import annotations

D, RHO_P, MU, G = 100e-6, 2500.0, 1.8e-5, 9.81  # [m], [kg/m^3], [Pa s], [m/s^2]
X0, Y0 = 0.015, 0.28  # [m] release point


def settling_case(drag="hoomans1996", density=1.2, pressure_gradient_force=True, end=0.4, **coupling):
    """Case dictionary of the settling sphere.

    Parameters
    ----------
    drag : str
        Registered drag law.
    density : float or None
        Constant gas density [kg/m^3]; None for the ideal gas (Hoomans 1996 eq. 44).
    pressure_gradient_force : bool
        Whether the particle feels −V_p ∇p.
    end : float
        Simulated time [s].
    **coupling
        Further ``[coupling]`` keys.
    """
    return {
        "name": "settling",
        "gravity": [0.0, -G, 0.0],
        "particles": {
            "dimensions": 2,
            "species": [{"diameter": D, "density": RHO_P, "count": 1}],
            "contact": {"model": "linear_spring_dashpot", "stiffness": 1e-3, "restitution": 0.9},
            "placement": {"method": "random", "region_lower": [X0 - 1e-4, Y0 - 1e-4, 0.0],
                          "region_upper": [X0 + 1e-4, Y0 + 1e-4, 0.0]},
        },
        "time": {"end": end},
        "gas": {
            "dt": 1e-3,
            "grid": {"cells": [3, 30], "size": [0.03, 0.3], "depth": 1.0},
            "properties": {"viscosity": MU} | ({"density": density} if density is not None else {}),
            "boundaries": {"left": {"kind": "wall"}, "right": {"kind": "wall"}, "bottom": {"kind": "wall"},
                           "top": {"kind": "pressure_outlet"}},
        },
        "coupling": {"drag": drag, "pressure_gradient_force": pressure_gradient_force} | coupling,
    }
