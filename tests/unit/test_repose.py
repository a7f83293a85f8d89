"""The dynamic angle of repose (``analysis.repose``) of synthetic beds whose free surface is a plane at a
known angle, and the drum a case holds."""
from __future__ import annotations

import math

import numpy as np
import pytest

from fluidem.analysis.repose import Drum, drum_of, repose_angle
from fluidem.case import validate_case

R, L, D = 0.05, 0.04, 0.004  # drum radius and length, particle diameter [m]


def _bed(angle_deg, n=400000, seed=3, axis=(0.0, 1.0, 0.0), gravity=(0.0, 0.0, -9.81)):
    """Centres filling a drum (axis along y, gravity −z) below the plane z = tan(angle) x − 0.01 m."""
    rng = np.random.default_rng(seed)
    p = rng.uniform([-R, 0.0, -R], [R, L, R], (n, 3))
    inside = p[:, 0] ** 2 + p[:, 2] ** 2 < (R - D / 2) ** 2
    below = p[:, 2] < math.tan(math.radians(angle_deg)) * p[:, 0] - 0.01
    p = p[inside & below]
    return p, np.full(len(p), D / 2)


@pytest.mark.parametrize("angle", [0.0, 12.0, 30.0, -38.0, 50.0])
def test_angle_of_a_plane_surface(angle):
    """Each bin's highest centre lies below the plane by a random gap (under 0.5 mm among the ~1e5 centres
    here), which tilts the line fitted over 50 mm by 0.1° at most for these beds; 0.5° leaves room for that."""
    pos, rad = _bed(angle)
    drum = Drum.of((0.0, 0.0, 0.0), (0.0, 1.0, 0.0), R, L, (0.0, 0.0, -9.81))
    assert repose_angle(pos, rad, drum) == pytest.approx(abs(angle), abs=0.5)


def test_the_frame_follows_the_drum_axis_and_gravity():
    """The same bed turned so that the drum axis is x and gravity −y gives the same angle."""
    pos, rad = _bed(25.0)
    turned = np.column_stack([pos[:, 1], pos[:, 2], -pos[:, 0]])  # (x, y, z) -> (y, z, -x): axis y -> x, up z -> y
    drum = Drum.of((0.0, 0.0, 0.0), (1.0, 0.0, 0.0), R, L, (0.0, -9.81, 0.0))
    assert repose_angle(turned, rad, drum) == pytest.approx(25.0, abs=0.5)


def test_end_plates_are_left_out_and_empty_beds_have_no_angle():
    pos, rad = _bed(20.0)
    drum = Drum.of((0.0, 0.0, 0.0), (0.0, 1.0, 0.0), R, L, (0.0, 0.0, -9.81))
    # a heap against an end plate (within two diameters of it) does not change the angle
    heap = np.column_stack([np.linspace(-0.02, 0.02, 30), np.full(30, 0.003), np.full(30, 0.03)])
    both = np.vstack([pos, heap])
    assert repose_angle(both, np.full(len(both), D / 2), drum) == pytest.approx(20.0, abs=0.5)
    assert math.isnan(repose_angle(np.zeros((0, 3)), np.zeros(0), drum))


def _case(walls, gravity=(0.0, 0.0, -9.81)):
    return validate_case({
        "gravity": list(gravity),
        "particles": {"species": [{"diameter": D, "density": 2500.0, "count": 10}],
                      "contact": {"model": "linear_spring_dashpot", "stiffness": 2e3, "restitution": 0.5,
                                  "friction": 0.5},
                      "placement": {"region_lower": [-0.01, 0.01, -0.01], "region_upper": [0.01, 0.03, 0.01]}},
        "walls": walls, "time": {"end": 0.01}})


def test_drum_of_a_case():
    rot = {"kind": "rotation", "axis_point": [0.0, 0.0, 0.0], "axis": [0.0, -2.0, 0.0], "angular_velocity": 1.0}
    shell = {"name": "shell", "kind": "cylinder", "point": [0.0, 0.0, 0.0], "axis": [0.0, 1.0, 0.0], "radius": R,
             "length": L}
    drum = drum_of(_case([{**shell, "motion": rot}]))
    assert drum is not None and drum.radius == R and drum.length == L
    np.testing.assert_allclose(drum.up, [0.0, 0.0, 1.0])
    assert drum_of(_case([shell])) is None  # at rest: not a drum
    assert drum_of(_case([{**shell, "motion": {**rot, "axis_point": [0.01, 0.0, 0.0]}}])) is None  # off its axis
    assert drum_of(_case([{**shell, "motion": rot}], gravity=(0.0, -9.81, 0.0))) is None  # axis along gravity


def test_an_adhesive_law_takes_its_non_adhesive_base_at_the_walls():
    """hertz_mindlin_jkr particles may meet the walls with hertz_mindlin (wall shapes take no adhesive law);
    other mixtures of models stay refused, naming both."""
    from fluidem.errors import CaseError

    hm = {"model": "hertz_mindlin", "youngs_modulus": 1e7, "restitution": 0.5, "friction": 0.5}
    jkr = {**hm, "model": "hertz_mindlin_jkr", "surface_energy": 0.1}
    lsd = {"model": "linear_spring_dashpot", "stiffness": 2e3, "restitution": 0.5, "friction": 0.5}

    def case(contact, wall):
        return validate_case({
            "gravity": [0.0, 0.0, -9.81],
            "particles": {"species": [{"diameter": D, "density": 2500.0, "count": 1}], "contact": contact,
                          "wall_contact": wall},
            "walls": [{"kind": "box", "lower": [0, 0, 0], "upper": [0.02, 0.02, 0.02]}], "time": {"end": 0.01}})

    assert case(jkr, hm).particles.wall_contact.model == "hertz_mindlin"
    for contact, wall in ((hm, jkr), (hm, lsd), (jkr, lsd)):
        with pytest.raises(CaseError, match=f"wall_contact.model = '{wall['model']}' and contact.model = "
                                            f"'{contact['model']}'"):
            case(contact, wall)
