"""A lone sphere settling in still gas on a 3D grid: the case of tests/verification/test_coupled3d_settling.py.

The 100 µm glass-like sphere of ``settling.py`` released in a 3D gas box of 3 × 3 × 30 cells, 0.3 × 0.3 m
across and 0.3 m along gravity (cells 0.1 × 0.1 × 0.01 m, solids fraction ~5e-9 in the particle's cell, so
that its drag hardly moves the gas), gravity along the grid axis ``axis``.
"""
from __future__ import annotations

from .settling import D, G, MU, RHO_P

WIDTH, HEIGHT = 0.3, 0.3  # [m]


def settling3d_case(drag="hoomans1996", density=1.2, pressure_gradient_force=True, end=0.4, axis=2, **coupling):
    """Case dictionary of the settling sphere on a 3D grid, gravity along −``axis`` (0, 1 or 2)."""
    cells = [3, 3, 3]
    size = [WIDTH, WIDTH, WIDTH]
    cells[axis], size[axis] = 30, HEIGHT
    centre = [0.5 * WIDTH] * 3
    centre[axis] = HEIGHT - 0.02
    lo = [c - 1e-4 for c in centre]
    hi = [c + 1e-4 for c in centre]
    gravity = [0.0, 0.0, 0.0]
    gravity[axis] = -G
    sides = (("left", "right"), ("bottom", "top"), ("front", "back"))
    boundaries = {s: {"kind": "wall"} for pair in sides for s in pair}
    boundaries[sides[axis][1]] = {"kind": "pressure_outlet"}
    return {
        "name": "settling-3d",
        "gravity": gravity,
        "particles": {
            "dimensions": 3,
            "species": [{"diameter": D, "density": RHO_P, "count": 1}],
            "contact": {"model": "linear_spring_dashpot", "stiffness": 1e-3, "restitution": 0.9},
            "placement": {"method": "random", "region_lower": lo, "region_upper": hi},
        },
        "time": {"end": end},
        "gas": {
            "dt": 1e-3,
            "grid": {"cells": cells, "size": size},
            "properties": {"viscosity": MU} | ({"density": density} if density is not None else {}),
            "boundaries": boundaries,
            "initial_velocity": [0.0, 0.0, 0.0],
        },
        "coupling": {"drag": drag, "pressure_gradient_force": pressure_gradient_force} | coupling,
    }
