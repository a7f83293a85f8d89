"""Angle of repose of a small 2D heap with the ``epsd`` rolling model: it grows with μ_r.

300 discs (4 mm, μ = 0.5, linear law, k_n = 1e4 N/m, e = 0.3) poured from a column onto a floor and
settled for 1.2 s, as ``tests/verification/test_rolling_resistance.py::test_angle_of_repose_grows_with_rolling_friction``
does for ``cdt``; the flank slope is fitted by ``heap_angle``. Recorded (docs/physics/contact.md): 0.57° for
μ_r = 0, 3.25° for μ_r = 0.1 and 7.94° for μ_r = 0.3 (η_r = 0.3; cdt gives 8.5° at 0.3), about 5 min a
heap on one loaded core. Reference trend: Ai et al. (2011) §5 (Fig. 13), the angle of repose of a
heap grows with μ_r for model C and levels off at large μ_r.
"""
from __future__ import annotations

import pytest

from _helpers.heap import heap_angle

DIAMETER = 4e-3  # [m]
DENSITY = 2500.0  # [kg/m^3]
G = 9.81  # [m/s^2]

pytestmark = pytest.mark.validation


def _heap(mu_r):
    from fluidem.case import validate_case
    from fluidem.particles.softsphere import SoftSphereEngine

    case = validate_case({
        "name": "heap", "gravity": [0.0, -G, 0.0],
        "particles": {"dimensions": 2,
                      "species": [{"name": "p", "diameter": DIAMETER, "density": DENSITY, "count": 300}],
                      "contact": {"model": "linear_spring_dashpot", "stiffness": 1e4, "restitution": 0.3,
                                  "friction": 0.5, "rolling_friction": mu_r, "rolling_model": "epsd",
                                  "rolling_damping": 0.3 if mu_r > 0.0 else 0.0},
                      "placement": {"method": "random", "seed": 11, "region_lower": [-0.02, 0.004, 0.0],
                                    "region_upper": [0.02, 0.24, 0.0]}},
        "walls": [{"name": "floor", "kind": "plane", "point": [0.0, 0.0, 0.0], "normal": [0.0, 1.0, 0.0]}],
        "time": {"end": 1.2}})
    eng = SoftSphereEngine(case)
    eng.advance(int(1.2 / eng.dt))
    return heap_angle(eng.state.position, eng.state.radius)


def test_epsd_angle_of_repose_grows_with_rolling_friction():
    """Margin 5° between μ_r = 0 and 0.3 (the cdt test's): the flank fit of a heap this small scatters by a
    degree or two."""
    angles = {mu_r: _heap(mu_r) for mu_r in (0.0, 0.1, 0.3)}
    print("epsd angle of repose: " + ", ".join(f"mu_r = {k}: {v:.1f} deg" for k, v in angles.items()))
    assert angles[0.1] > angles[0.0]
    assert angles[0.3] > angles[0.0] + 5.0
