"""A case with a 3D gas grid and 3D particles validates; what the 3D coupling cannot take is refused with the key,
the value and what is allowed."""
from __future__ import annotations

import copy

import pytest

from fluidem.case import validate_case
from fluidem.errors import CaseError

from _helpers.settling3d import settling3d_case


def test_a_3d_gas_grid_with_3d_particles_validates_with_gravity_along_any_axis():
    for axis in range(3):
        case = validate_case(settling3d_case(axis=axis))
        assert case.gas.grid.dimensions == 3 and case.coupling.momentum_exchange == "particle"


@pytest.mark.parametrize("exchange", ["cell", "cell_beta"])
def test_a_3d_gas_grid_takes_the_cell_exchanges(exchange):
    case = validate_case(changed(("coupling", "momentum_exchange"), exchange))
    assert case.gas.grid.dimensions == 3 and case.coupling.momentum_exchange == exchange


def changed(path, value, axis=2):
    data = copy.deepcopy(settling3d_case(axis=axis))
    *head, last = path
    d = data
    for k in head:
        d = d[k]
    d[last] = value
    return data


@pytest.mark.parametrize("path,value,message", [
    (("particles", "dimensions"), 2, "a 3D gas grid takes 3D particles"),
    (("gravity",), [0.0, -3.0, -9.0], "gravity must lie along one grid axis"),
    (("coupling", "voidage"), {"method": "area_volume"}, "on a 3D grid allowed are 'centroid' and 'volume'"),
    (("particles", "placement", "region_upper"), [0.15, 0.15, 0.35], "z from .* not within the gas grid"),
])
def test_what_the_3d_coupling_cannot_take_is_refused(path, value, message):
    two = path == ("particles", "dimensions")  # 2D particles: gravity along y, centres in one z plane
    data = changed(path, value, axis=1 if two else 2)
    if two:
        data["particles"]["placement"]["region_lower"][2] = data["particles"]["placement"]["region_upper"][2] = 0.1
    with pytest.raises(CaseError, match=message):
        validate_case(data)


def test_the_volume_mapping_needs_a_3d_grid():
    from _helpers.settling import settling_case

    data = settling_case()
    data["coupling"]["voidage"] = {"method": "volume"}
    with pytest.raises(CaseError, match="needs a 3D grid"):
        validate_case(data)
