"""Periodic sides of a box wall (``walls.periodic``): case checks, wrapping with image counts, refusals.

A particle leaving through a periodic side re-enters through the opposite one with the same velocity; its
unwrapped position, position + image · L, continues the straight line it was on (checked to round-off of
the coordinates). Bad input names the keys involved.
"""
from __future__ import annotations

import copy

import numpy as np
import pytest

from fluidem.case import read_case_data, validate_case
from fluidem.errors import CaseError
from fluidem.particles.softsphere import SoftSphereEngine
from fluidem.particles.softsphere_gpu import gpu_refusals

from _helpers.periodic import periodic_case_dict

D = 4e-3


def box(upper, periodic, **kw):
    return {"name": "box", "kind": "box", "lower": [0.0, 0.0, 0.0], "upper": list(upper), "periodic": periodic, **kw}


def error_of(data) -> str:
    with pytest.raises(CaseError) as info:
        validate_case(data)
    return str(info.value)


@pytest.fixture
def base(tmp_path):
    """A case dict of a few particles in a 3D box periodic along x (no gravity), or with ``walls``."""

    def make(pos, vel=None, walls=None, dimensions=3, gravity=(0.0, 0.0, 0.0)):
        data = periodic_case_dict(tmp_path / "p.csv", pos, vel, upper=(10 * D,) * 3, periodic=["x"],
                                  dimensions=dimensions, gravity=gravity)
        if walls is not None:
            data["walls"] = walls
        return data

    return make


def test_periodic_needs_a_box(base):
    data = base([[5 * D] * 3])
    data["walls"] = [{"name": "floor", "kind": "plane", "point": [0, 0, 0], "normal": [0, 0, 1], "periodic": ["x"]}]
    msg = error_of(data)
    assert "periodic" in msg and "box" in msg and "floor" in msg


def test_periodic_axis_named_twice(base):
    msg = error_of(base([[5 * D] * 3], walls=[box((10 * D,) * 3, ["x", "x"])]))
    assert "twice" in msg and "['x', 'x']" in msg


def test_periodic_unknown_axis_is_refused(base):
    msg = error_of(base([[5 * D] * 3], walls=[box((10 * D,) * 3, ["w"])]))
    assert "periodic" in msg and "'x'" in msg


def test_periodic_z_in_2d_is_refused(base):
    data = base([[5 * D, 5 * D, 0.5 * D]], walls=[box((10 * D, 10 * D, D), ["x", "z"])], dimensions=2)
    msg = error_of(data)
    assert "walls.0.periodic" in msg and "particles.dimensions = 2" in msg and "x, y" in msg


def test_periodic_box_must_be_the_only_box(base):
    walls = [box((10 * D,) * 3, ["x"]), {"name": "inner", "kind": "box", "lower": [0, 0, 0], "upper": [D, D, D]}]
    msg = error_of(base([[5 * D] * 3], walls=walls))
    assert "walls.0.periodic" in msg and "walls.1 ('inner')" in msg


def test_periodic_open_top_on_the_same_axis(base):
    msg = error_of(base([[5 * D] * 3], walls=[box((10 * D,) * 3, ["z"], open_top=True)], gravity=(0, 0, -9.81)))
    assert "walls.0.periodic" in msg and "open_top" in msg


def test_periodic_box_may_not_move(base):
    w = box((10 * D,) * 3, ["x"], motion={"kind": "constant_velocity", "velocity": [0, 0, 0.1]})
    msg = error_of(base([[5 * D] * 3], walls=[w]))
    assert "periodic" in msg and "motion" in msg


def test_gas_sides_must_be_periodic_too():
    data = read_case_data("tsuji-jet")
    data["walls"][0]["periodic"] = ["x"]
    msg = error_of(copy.deepcopy(data))
    assert "walls.0.periodic" in msg and "gas.boundaries.left" in msg and "'wall'" in msg
    data["gas"]["boundaries"]["left"] = {"kind": "periodic"}
    data["gas"]["boundaries"]["right"] = {"kind": "periodic"}
    case = validate_case(copy.deepcopy(data))
    assert case.walls[0].periodic == ["x"]
    data["walls"][0]["upper"][0] = 0.1  # narrower than the gas grid along the periodic axis
    msg = error_of(data)
    assert "walls.0.periodic" in msg and "gas.grid.size" in msg


def test_box_planes_of_a_periodic_axis_are_gone(base):
    eng = SoftSphereEngine(validate_case(base([[5 * D] * 3], walls=[box((10 * D, 12 * D, 14 * D), ["x", "z"])])))
    assert eng.walls.names == ["box.ymin", "box.ymax"]
    assert eng.period.tolist() == [10 * D, 0.0, 14 * D] and eng.periodic


def test_a_box_too_short_for_the_cut_off_is_refused(base):
    with pytest.raises(CaseError, match=r"periodic along y .* below twice the neighbour cut-off"):
        SoftSphereEngine(validate_case(base([[D, D, D]], walls=[box((10 * D, 2.2 * D, 10 * D), ["y"])])))


def test_the_gpu_engine_refuses_periodic_sides(base):
    case = validate_case(base([[5 * D] * 3]))
    assert any("walls.0.periodic = ['x']" in r for r in gpu_refusals(case))


@pytest.mark.parametrize("axis", [0, 1, 2])
@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_crossing_keeps_the_velocity_and_the_unwrapped_path(base, axis, sign):
    """One free particle crosses a periodic side several times: its velocity stays bit for bit, its image
    count steps by ±1 at each crossing, and position + image · L is x0 + v t to round-off of the
    coordinates (the drift adds v dt each step, 1e-12 of L over a few thousand steps)."""
    L = 10 * D
    v = np.array([0.3, -0.2, 0.25])
    v[axis] = sign * 2.0
    x0 = np.array([5 * D, 5 * D, 5 * D])
    walls = [box((L, L, L), ["x", "y", "z"])]
    eng = SoftSphereEngine(validate_case(base([x0, [5 * D, 5 * D, 5 * D + 2.5 * D]], [v, v], walls=walls)))
    steps = 0
    crossings = 0
    last = 0
    while crossings < 3:
        eng.advance(97)
        steps += 97
        st = eng.state
        assert np.array_equal(st.velocity[0], v)
        assert 0.0 <= st.position[0, axis] <= L
        crossings = abs(int(st.image[0, axis]))
        assert np.all((st.position[0] >= 0.0) & (st.position[0] <= L))
        assert abs(int(st.image[0, axis]) - last) <= 1
        last = int(st.image[0, axis])
        unwrapped = st.position[0] + st.image[0] * eng.period
        assert np.allclose(unwrapped, x0 + v * steps * eng.dt, rtol=0.0, atol=1e-12 * L)
    assert np.sign(last) == sign
    # the other particle moved alongside, never touching: no forces
    assert np.array_equal(eng.state.velocity[1], v)


def test_placement_in_a_periodic_box_has_no_overlap_across_the_sides(contact_law):
    """Random and lattice fills of a fully periodic box: no two particles overlap by nearest image."""
    for method in ("random", "lattice"):
        data = {
            "name": "fill", "gravity": [0.0, 0.0, 0.0],
            "particles": {"dimensions": 3,
                          "species": [{"name": "p", "diameter": D, "density": 2500.0, "count": 300}],
                          "contact": contact_law("linear_spring_dashpot"),
                          "placement": {"method": method, "seed": 3}},
            "walls": [box((8 * D, 8 * D, 8 * D), ["x", "y", "z"])], "time": {"end": 0.01},
        }
        eng = SoftSphereEngine(validate_case(data))
        eng.check_initial_overlaps(tolerance=0.0)
        r = eng.minimum_image(eng.state.position[:, None, :] - eng.state.position[None, :, :])
        dist = np.linalg.norm(r, axis=2) + np.eye(300) * 1.0
        assert dist.min() >= D * (1 - 1e-12)


def test_contact_probe_counts_a_contact_across_the_side(base):
    """Two spheres overlapping by 10 µm across the x side: one contact, by nearest image."""
    from fluidem.analysis.fluidised import contact_numbers
    from fluidem.analysis.probes import contacts

    L = 10 * D
    eng = SoftSphereEngine(validate_case(base([[0.5 * D - 5e-6, 5 * D, 5 * D], [L - 0.5 * D + 5e-6, 5 * D, 5 * D]])))
    got = contacts(eng)
    assert got["contacts"] == 1
    assert got["max_overlap_rel"] == pytest.approx(10e-6 / D, rel=1e-6)
    assert contact_numbers(eng).tolist() == [1, 1]


def test_image_counts_follow_the_particles_through_renumbering(tmp_path):
    """Particles renumbered in cell order every few steps (neighbours.reorder_interval) carry their image
    counts: by id, position + image · L is x0 + v t for a lattice drifting as a whole (no contacts)."""
    L = 10 * D
    idx = np.arange(27)
    x0 = np.column_stack([idx % 3, idx // 3 % 3, idx // 9]) * 3.0 * D + 0.5 * D
    v = np.array([1.3, -0.7, 0.4])
    data = periodic_case_dict(tmp_path / "p.csv", x0, np.tile(v, (27, 1)), upper=(L, L, L), periodic=["x", "y", "z"])
    data["neighbours"] = {"reorder_interval": 5}
    eng = SoftSphereEngine(validate_case(data))
    for _ in range(20):
        eng.advance(53)
    st = eng.state
    assert eng.reorders > 0 and not np.array_equal(st.ids, idx)
    assert np.abs(st.image).sum() >= 9  # a layer has crossed a side
    unwrapped = st.position + st.image * eng.period
    assert np.allclose(unwrapped, x0[st.ids] + v * eng.steps * eng.dt, rtol=0.0, atol=1e-12 * L)
