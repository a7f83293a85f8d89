"""Renumbering the particles in cell order (``neighbours.reorder_interval``) changes nothing but speed.

The soft-sphere engine may renumber its particles in slab and cell order at a list rebuild
(``_softsphere_kernels.reorder``): every per-particle array is permuted alike, the list and its
tangential history renamed, ``state.ids`` follows the particles, the coupling's per-particle arrays
follow through ``reorder_listeners`` and snapshots list the particles by id. These tests check each
of those against a run that is never renumbered, and that the renumbering depends on step numbers only
(the same result in any chunks, on any number of threads, and after a resume).
"""
import math

import h5py
import numba
import numpy as np
import pytest

from fluidem.case import validate_case
from fluidem.particles import _neighbours_kernels as NK
from fluidem.particles.softsphere import SoftSphereEngine
from fluidem.simulation import Simulation

from _helpers.neighbours import random_packing


def by_id(state, name):
    """Rows of a state array in the order of the particles' ids."""
    return getattr(state, name)[np.argsort(state.ids)]


@pytest.mark.parametrize("dim2", [True, False])
def test_cell_order_puts_every_slab_in_one_run(dim2):
    """After renumbering by ``cell_order`` the list's slabs hold consecutive particles 0, 1, 2, …
    (build_pairs lists a slab's members ascending): the order is by slab, and it is a permutation."""
    pos, radius = random_packing(3, 800, dim2)
    skin = 0.3 * radius.max()
    order = NK.cell_order(pos, radius, skin, dim2)
    assert np.array_equal(np.sort(order), np.arange(pos.shape[0]))
    assert not np.array_equal(order, np.arange(pos.shape[0]))  # the random packing was not in that order
    _, _, slab_start, members = NK.build_pairs(pos[order], radius[order], skin, dim2)
    assert slab_start.size > 3
    assert np.array_equal(members, np.arange(pos.shape[0]))


def test_renumbered_list_keeps_every_pair_and_its_history():
    rng = np.random.default_rng(5)
    pos, radius = random_packing(4, 600, False)
    rs, partner, _, _ = NK.build_pairs(pos, radius, 0.4 * radius.max(), False)
    hist = rng.normal(size=(partner.size, 3))
    new_index = rng.permutation(pos.shape[0]).astype(np.int64)
    rs2, partner2, hist2 = NK.renumber_pairs(rs, partner, hist, new_index)
    owner = np.repeat(np.arange(pos.shape[0]), np.diff(rs))
    owner2 = np.repeat(np.arange(pos.shape[0]), np.diff(rs2))
    before = {(int(new_index[i]), int(new_index[j])): tuple(h) for i, j, h in zip(owner, partner, hist)}
    after = {(int(i), int(j)): tuple(h) for i, j, h in zip(owner2, partner2, hist2)}
    assert after == before
    for i in range(pos.shape[0]):  # rows ascending (renumber_pairs sorts them; the next rebuild puts touching pairs first)
        assert np.all(np.diff(partner2[rs2[i]:rs2[i + 1]]) > 0)


def frictional_bed(tiny_bed_case, reorder, model="hertz_mindlin"):
    case = tiny_bed_case(n=150, model=model, restitution=0.5, friction=0.5)
    d = case.particles.species[0].diameter
    return case.with_overrides({"neighbours.skin": 0.05 * d, "neighbours.reorder_interval": reorder,
                                "particles.placement.velocity": [0.3, 0.2, -0.5]}), d


@pytest.mark.parametrize("model", ["linear_spring_dashpot", "hertz_mindlin"])
def test_renumbering_does_not_change_the_dynamics(tiny_bed_case, model):
    """A frictional bed hitting the floor, renumbered every 50 steps (at the next rebuild) against the
    same bed never renumbered: each particle, found by its id, ends where it does there. The sums of
    forces are taken in another order, so the runs differ by round-off, amplified by the collisions about
    tenfold per 250 steps (test_neighbours: ~1e-12 d after 2000 steps, 1e-9 d after 3000, so 2000 here); a
    pair or spring that lost its history, or a force applied to the wrong particle, gives differences of
    order d and of the spins themselves."""
    case, d = frictional_bed(tiny_bed_case, 0, model)
    plain = SoftSphereEngine(case)
    plain.advance(2000)
    case, _ = frictional_bed(tiny_bed_case, 50, model)
    sorted_ = SoftSphereEngine(case)
    sorted_.advance(2000)
    assert plain.reorders == 0 and sorted_.reorders > 20
    assert not np.array_equal(sorted_.state.ids, np.arange(150))
    assert np.array_equal(np.sort(sorted_.state.ids), np.arange(150))
    spin = np.abs(plain.state.omega).max()
    assert spin > 10.0  # friction has spun the particles up [rad/s]
    assert np.abs(by_id(sorted_.state, "position") - plain.state.position).max() < 1e-10 * d
    assert np.abs(by_id(sorted_.state, "omega") - plain.state.omega).max() < 1e-8 * spin
    for name in ("radius", "mass", "inertia", "species"):
        assert np.array_equal(by_id(sorted_.state, name), getattr(plain.state, name))
    # each particle's wall springs moved with it (the box walls carry history too)
    order = np.argsort(sorted_.state.ids)
    assert np.abs(sorted_.wall_hist[order] - plain.wall_hist).max() < 1e-6 * np.abs(plain.wall_hist).max()


def test_particles_are_renumbered_at_set_up(tiny_bed_case):
    """With renumbering on, the engine starts in cell order (the placed bed is not): the same particles
    (by id: positions bitwise, the set-up forces to round-off), numbered so that cell_order is the identity."""
    case, d = frictional_bed(tiny_bed_case, 0)
    plain = SoftSphereEngine(case)
    case, _ = frictional_bed(tiny_bed_case, 50)
    sorted_ = SoftSphereEngine(case)
    st = sorted_.state
    assert not np.array_equal(st.ids, np.arange(150)) and sorted_.reorders == 0 and sorted_.steps == 0
    for name in ("position", "velocity", "radius", "mass"):
        assert np.array_equal(by_id(st, name), getattr(plain.state, name))
    np.testing.assert_allclose(by_id(st, "force"), plain.state.force, rtol=0, atol=1e-12 * np.abs(plain.state.force).max())
    assert np.array_equal(NK.cell_order(st.position, st.radius, sorted_.skin, sorted_.dim2), np.arange(150))
    assert not np.array_equal(NK.cell_order(plain.state.position, plain.state.radius, plain.skin, plain.dim2),
                              np.arange(150))


def test_renumbering_is_the_same_in_any_chunks_and_on_any_threads(tiny_bed_case):
    """Renumbering happens at the first rebuild ``reorder_interval`` steps after the last one, whatever
    the calls: one call of 1500 steps and calls of 7 end bitwise alike; so do 1 and 2 threads."""
    case, _ = frictional_bed(tiny_bed_case, 40)
    before = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        one = SoftSphereEngine(case)
        one.advance(1500)
        chunked = SoftSphereEngine(case)
        for _ in range(1500 // 7):
            chunked.advance(7)
        chunked.advance(1500 % 7)
        runs = [one, chunked]
        if numba.config.NUMBA_NUM_THREADS >= 2:
            numba.set_num_threads(2)
            two = SoftSphereEngine(case)
            two.advance(1500)
            runs.append(two)
    finally:
        numba.set_num_threads(before)
    assert one.reorders > 10
    for other in runs[1:]:
        assert other.reorders == one.reorders
        for name in ("position", "velocity", "omega", "ids"):
            assert np.array_equal(getattr(other.state, name), getattr(one.state, name)), name


def test_resumed_renumbered_run_is_bitwise_the_uninterrupted_one(tiny_bed_case, stopped_and_resumed):
    case, _ = frictional_bed(tiny_bed_case, 40)
    case = case.with_overrides({"time.end": 0.002, "output.checkpoint_interval": 0.001})
    whole, first, again = stopped_and_resumed(case, 0.0011)
    assert first.engine.reorders > 0 and again.engine.reorders > first.engine.reorders
    assert again.engine.reorders == whole.engine.reorders
    for name in ("position", "velocity", "omega", "ids"):
        assert np.array_equal(getattr(again.state, name), getattr(whole.state, name)), name


def test_snapshots_list_the_particles_by_id(tiny_bed_case, tmp_path):
    from fluidem.io.snapshots import ParticleWriter

    case, _ = frictional_bed(tiny_bed_case, 40)
    sim = Simulation(case)
    sim.advance(1000)
    assert sim.engine.reorders > 0 and not np.array_equal(sim.state.ids, np.arange(sim.state.n))
    ParticleWriter(tmp_path, extra_fields={"radius_by_row": lambda s: s.state.radius})(sim)
    with h5py.File(tmp_path / "particles.h5") as f:
        snap = f["snapshots"]["000000"]
        assert np.array_equal(snap["id"][()], np.arange(sim.state.n))
        for name in ("position", "velocity", "omega"):
            assert np.array_equal(snap[name][()], by_id(sim.state, name)), name
        assert np.array_equal(snap["radius_by_row"][()], by_id(sim.state, "radius"))


def coupled_polydisperse_bed(reorder):
    """Two sizes in a small 2D gas-fluidised bed, so that the coupling's per-particle volumes differ."""
    return validate_case({
        "name": "coupled-reorder",
        "particles": {
            "dimensions": 2,
            "species": [{"name": "small", "diameter": 2e-3, "density": 2500.0, "count": 150},
                        {"name": "large", "diameter": 3e-3, "density": 2500.0, "count": 100}],
            "contact": {"model": "linear_spring_dashpot", "stiffness": 800.0, "restitution": 0.9, "friction": 0.3},
            "placement": {"method": "random", "region_lower": [0.0, 0.0, 0.0015], "region_upper": [0.04, 0.06, 0.0015],
                          "seed": 11},
        },
        "walls": [{"name": "column", "kind": "box", "lower": [0.0, 0.0, 0.0], "upper": [0.04, 0.12, 0.003]}],
        "neighbours": {"reorder_interval": reorder, "skin": 1e-4},  # thin: frequent rebuilds
        "time": {"end": 0.02},
        "gas": {"dt": 2e-4, "grid": {"cells": [4, 12], "size": [0.04, 0.12], "depth": 0.003},
                "boundaries": {"left": {"kind": "wall"}, "right": {"kind": "wall"},
                               "bottom": {"kind": "inflow", "segments": [{"superficial": 1.2}]},
                               "top": {"kind": "pressure_outlet"}}},
        "coupling": {"drag": "gidaspow", "pressure_gradient_force": True},
    })


def test_coupling_follows_the_renumbering():
    """Gas-fluidised polydisperse bed: the coupling's particle volumes and K_p (``_reorder``) are renumbered
    with the particles, so each particle, by id, ends where it does in the run never renumbered. The force
    sums per cell are taken in another order, hence round-off differences, which the gas solve (tolerance
    1e-10) and the collisions amplify over 100 gas steps; a volume or K_p left on the wrong particle
    changes its drag by a third or more."""
    plain = Simulation(coupled_polydisperse_bed(0))
    plain.run()
    sorted_ = Simulation(coupled_polydisperse_bed(30))
    sorted_.run()
    assert sorted_.engine.reorders > 3
    st = sorted_.state
    np.testing.assert_array_equal(sorted_.gas.volume, math.pi / 6.0 * (2.0 * st.radius) ** 3)
    speed = np.abs(plain.state.velocity).max()
    assert speed > 0.01  # the particles fall and the gas acts [m/s]
    assert np.abs(by_id(st, "position") - plain.state.position).max() < 1e-9
    assert np.abs(by_id(st, "velocity") - plain.state.velocity).max() < 1e-6 * speed


def test_checkpoint_of_a_renumbered_coupled_bed_loads_into_a_fresh_simulation(tmp_path):
    """A fresh Simulation (particles numbered as placed) loading the checkpoint of a renumbered polydisperse
    bed takes the checkpoint's numbering everywhere, the coupling's particle volumes included, and goes
    on exactly as the run that wrote it."""
    case = coupled_polydisperse_bed(30)
    first = Simulation(case)
    first.run(until=0.01)
    assert first.engine.reorders > 0 and not np.array_equal(first.state.ids, np.arange(first.state.n))
    first.save_checkpoint(tmp_path / "restart.h5")
    fresh = Simulation(case)
    fresh.load_checkpoint(tmp_path / "restart.h5")
    np.testing.assert_array_equal(fresh.state.ids, first.state.ids)
    np.testing.assert_array_equal(fresh.gas.volume, math.pi / 6.0 * (2.0 * fresh.state.radius) ** 3)
    first.run(until=0.012)
    fresh.run(until=0.012)
    assert np.abs(fresh.state.position - first.state.position).max() < 1e-12
