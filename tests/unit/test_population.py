"""Inlets and outlets (particles/population.py): schema, the insertion fill, the contact list kept across a
change of the particles, counts and masses, resume and the snapshots of a changing particle count."""
from __future__ import annotations

import math

import h5py
import numpy as np
import pytest

from fluidem import Simulation
from fluidem.case import validate_case
from fluidem.errors import CaseError
from fluidem.particles._population_kernels import drop_pairs, insert_fill

D, RHO = 2e-3, 2500.0


def feed_case(count=0, inlets=None, outlets=None, end=0.1, walls=None, dims=2, **species):
    depth = D
    return validate_case({
        "name": "feed",
        "particles": {"dimensions": dims, "species": [{"name": "glass", "diameter": D, "density": RHO, "count": count,
                                                       **species}],
                      "contact": {"model": "linear_spring_dashpot", "stiffness": 2000.0, "restitution": 0.5,
                                  "friction": 0.3},
                      "placement": {"region_lower": [0, 0, 0], "region_upper": [0.04, 0.03, depth]}},
        "walls": walls if walls is not None else [
            {"name": "box", "kind": "box", "lower": [0, 0, 0], "upper": [0.04, 0.1, depth], "open_top": True}],
        "inlets": inlets or [],
        "outlets": outlets or [],
        "time": {"end": end},
    })


INLET = {"name": "feed", "lower": [0.005, 0.07, 0.0], "upper": [0.035, 0.09, D], "rate": 2000.0, "interval": 0.01,
         "velocity": [0.0, -0.5, 0.0]}


# ------------------------------------------------------------------ schema
def test_rate_and_mass_rate_exclusive():
    with pytest.raises(CaseError, match="exactly one of rate"):
        feed_case(inlets=[{**INLET, "mass_rate": 1.0}])
    bad = dict(INLET)
    del bad["rate"]
    with pytest.raises(CaseError, match="exactly one of rate"):
        feed_case(inlets=[bad])


def test_empty_species_needs_an_inlet():
    with pytest.raises(CaseError, match=r"particles.species.0.count = 0.*no inlet"):
        feed_case(count=0)


def test_inlet_species_must_exist():
    with pytest.raises(CaseError, match=r"inlets.0.species = 'sand' is not one of \['glass'\]"):
        feed_case(count=5, inlets=[{**INLET, "species": "sand"}])


def test_hard_spheres_refuse_inlets():
    case = feed_case(inlets=[INLET]).model_dump()
    case["particles"]["contact"] = {"model": "hard_sphere", "restitution": 0.9, "friction": 0.3}
    case["particles"]["species"][0]["count"] = 10
    with pytest.raises(CaseError, match="inlets need a soft-sphere contact law"):
        validate_case(case)


def test_outlet_needs_its_geometry():
    with pytest.raises(CaseError, match="kind = 'plane' needs point and normal"):
        feed_case(count=5, outlets=[{"name": "out", "kind": "plane", "point": [0, 0, 0]}])
    with pytest.raises(CaseError, match="upper y = 0.0 must exceed lower y = 0.0"):
        feed_case(count=5, outlets=[{"name": "out", "kind": "box", "lower": [0, 0, 0], "upper": [1, 0, 1]}])


# ------------------------------------------------------------------ kernels
@pytest.mark.parametrize("dim2", [True, False])
def test_insert_fill_places_without_overlap(dim2):
    rng = np.random.default_rng(3)
    lo, hi = np.zeros(3), np.array([0.02, 0.02, 0.02])
    old = rng.uniform(0, 0.02, (40, 3))
    old_r = np.full(40, 5e-4)
    keep = np.ones(40, bool)  # old spheres may overlap each other; only the new ones are checked
    if dim2:
        old[:, 2] = 0.01
    r = rng.uniform(4e-4, 8e-4, 60)
    pos, placed = insert_fill(old, old_r, r, lo, hi, dim2, 0.01, 7, 500)
    assert placed == 60 and keep.all()
    pos = pos[:placed]
    assert np.all(pos - r[:, None] >= lo - 1e-15) and np.all(pos[:, :2] + r[:, None] <= hi[:2] + 1e-15)
    if dim2:
        assert np.all(pos[:, 2] == 0.01)
    d_new = np.linalg.norm(pos[:, None] - pos[None], axis=2) + np.eye(placed)
    assert np.all(d_new >= (r[:, None] + r[None]) * (1 - 1e-12) + np.eye(placed) * 0)
    d_old = np.linalg.norm(pos[:, None] - old[None], axis=2)
    assert np.all(d_old >= r[:, None] + old_r[None])


def test_insert_fill_stops_when_full():
    r = np.full(50, 0.004)  # at most 4 fit in a 1 cm square
    pos, placed = insert_fill(np.zeros((0, 3)), np.zeros(0), r, np.zeros(3), np.array([0.01, 0.01, 0.0]), True,
                              0.0, 1, 200)
    assert 1 <= placed <= 4


def test_drop_pairs_against_a_plain_loop():
    rng = np.random.default_rng(0)
    n = 30
    rows = [sorted(rng.choice(np.arange(i + 1, n), size=min(3, n - i - 1), replace=False)) if i < n - 1 else []
            for i in range(n)]
    row_start = np.zeros(n + 1, dtype=np.int64)
    row_start[1:] = np.cumsum([len(r) for r in rows])
    partner = np.array([j for r in rows for j in r], dtype=np.int32)
    hist = rng.normal(size=(partner.size, 4))
    keep = rng.random(n) > 0.3
    new_index = np.where(keep, np.cumsum(keep) - 1, -1)
    n_new = int(keep.sum()) + 5
    rs, pa, hi = drop_pairs(row_start, partner, hist, new_index, n_new)
    expect = [(new_index[i], new_index[j], tuple(hist[p])) for i in range(n) for p, j in
              zip(range(row_start[i], row_start[i + 1]), partner[row_start[i]:row_start[i + 1]])
              if keep[i] and keep[j]]
    got = [(a, int(pa[p]), tuple(hi[p])) for a in range(n_new) for p in range(rs[a], rs[a + 1])]
    assert got == expect and rs.shape == (n_new + 1,) and np.all(np.diff(rs) >= 0)


# ------------------------------------------------------------------ runs
def test_rate_inserts_its_count_and_species_sizes(tmp_path):
    case = feed_case(inlets=[{**INLET, "stop": 0.05}], end=0.06)
    s = Simulation(case, out_dir=tmp_path / "r").run()
    assert s["inlet_feed_count"] == 100 == s["n_particles"]  # 2000/s over 0.05 s
    assert s["inlet_feed_mass_kg"] == pytest.approx(100 * RHO * math.pi / 6 * D**3, rel=1e-12)


def test_mass_rate_carries_the_mass_within_one_particle(tmp_path):
    sizes = {"size_distribution": {"kind": "uniform", "min": 1.5e-3, "max": 2.5e-3}}
    inlet = {**INLET, "rate": None, "mass_rate": 0.02, "stop": 0.04}
    s = Simulation(feed_case(inlets=[inlet], end=0.05, **sizes), out_dir=tmp_path / "r").run()
    m_big = RHO * math.pi / 6 * 2.5e-3**3
    assert abs(s["inlet_feed_mass_kg"] - 0.02 * 0.04) <= m_big
    d = 2 * Simulation.resume(tmp_path / "r", until=0.06).state.radius
    assert d.min() >= 1.5e-3 and d.max() <= 2.5e-3 and d.std() > 0


def test_total_caps_the_insertion(tmp_path):
    s = Simulation(feed_case(inlets=[{**INLET, "total": 37}], end=0.05), out_dir=tmp_path / "r").run()
    assert s["inlet_feed_count"] == 37


def test_crowded_box_carries_the_rest(tmp_path, caplog):
    small = {**INLET, "lower": [0.015, 0.08, 0.0], "upper": [0.025, 0.09, D], "rate": 4000.0, "stop": 0.06}
    s = Simulation(feed_case(inlets=[small], end=0.3), out_dir=tmp_path / "r").run()
    assert "found room" in caplog.text
    assert s["inlet_feed_count"] == 240  # all of 4000/s × 0.06 s arrive, later than asked


def test_outlet_removes_and_books_what_it_removes(tmp_path):
    walls = [{"name": "left", "kind": "plane", "point": [0, 0, 0], "normal": [1, 0, 0]},
             {"name": "right", "kind": "plane", "point": [0.04, 0, 0], "normal": [-1, 0, 0]}]
    outlets = [{"name": "floor", "kind": "plane", "point": [0, 0.0, 0], "normal": [0, 1, 0]}]
    s = Simulation(feed_case(inlets=[{**INLET, "stop": 0.03}], outlets=outlets, walls=walls, end=0.25),
                   out_dir=tmp_path / "r").run()
    assert s["inlet_feed_count"] == 60 and s["outlet_floor_count"] == 60 and s["n_particles"] == 0
    assert s["outlet_floor_mass_kg"] == pytest.approx(s["inlet_feed_mass_kg"], rel=1e-12)


def test_resume_continues_bit_for_bit(tmp_path):
    walls = [{"name": "left", "kind": "plane", "point": [0, 0, 0], "normal": [1, 0, 0]},
             {"name": "right", "kind": "plane", "point": [0.04, 0, 0], "normal": [-1, 0, 0]},
             {"name": "floor", "kind": "plane", "point": [0, 0, 0], "normal": [0.3, 1, 0]}]
    outlets = [{"name": "side", "kind": "box", "lower": [0.0, -0.01, -1], "upper": [0.01, 0.01, 1]}]
    case = feed_case(inlets=[{**INLET, "stop": 0.08}], outlets=outlets, walls=walls, end=0.16)
    whole = Simulation(case, out_dir=tmp_path / "whole")
    a = whole.run()
    part = Simulation(case, out_dir=tmp_path / "part")
    part.run(until=0.07)
    b = Simulation.resume(tmp_path / "part").run()
    assert a["outlet_side_count"] > 0 and a["n_particles"] > 0
    for k in ("n_particles", "inlet_feed_count", "outlet_side_count", "outlet_side_mass_kg"):
        assert a[k] == b[k]
    with h5py.File(tmp_path / "whole" / "restart.h5") as f1, h5py.File(tmp_path / "part" / "restart.h5") as f2:
        for name in ("state/position", "state/velocity", "state/ids", "engine/hist"):
            assert np.array_equal(f1[name][...], f2[name][...]), name


def test_snapshots_index_each_count(tmp_path):
    Simulation(feed_case(inlets=[{**INLET, "stop": 0.05}], end=0.06), out_dir=tmp_path / "r").run()
    text = (tmp_path / "r" / "particles.xdmf").read_text()
    with h5py.File(tmp_path / "r" / "particles.h5") as f:
        counts = [f["snapshots"][k]["position"].shape[0] for k in sorted(f["snapshots"])]
    assert len(set(counts)) > 2
    import re

    assert [int(m) for m in re.findall(r'NumberOfElements="(\d+)"', text)] == counts


def test_added_particles_leave_resting_contacts_alone():
    """Adding particles far from a settled bed keeps every pair's tangential history and force."""
    case = feed_case(count=60, end=1.0)
    sim = Simulation(case)
    sim.advance(60000)  # 0.2 s: the bed has settled
    eng = sim.engine
    before_f = eng.state.force.copy()
    pairs = {(int(eng.state.ids[i]), int(eng.state.ids[eng.partner[p]])): eng.hist[p].copy()
             for i in range(eng.state.n) for p in range(eng.row_start[i], eng.row_start[i + 1])}
    from fluidem.state import ParticleState

    new = ParticleState.create(np.array([[0.02, 0.09, D / 2]]), np.zeros((1, 3)), np.array([D]),
                               np.zeros(1, dtype=np.int64), np.array([RHO]))
    new.ids = np.array([1000])
    eng.replace_particles(np.ones(eng.state.n, bool), new)
    assert np.array_equal(eng.state.force[:-1], before_f)
    assert np.array_equal(eng.state.force[-1], eng.state.mass[-1] * eng.gravity)
    after = {}
    for i in range(eng.state.n):
        for p in range(eng.row_start[i], eng.row_start[i + 1]):
            a, b = int(eng.state.ids[i]), int(eng.state.ids[eng.partner[p]])
            after[(a, b)] = eng.hist[p]
    for (a, b), h in pairs.items():
        if (a, b) in after:
            assert np.array_equal(after[(a, b)], h)
        elif (b, a) in after:
            assert np.array_equal(after[(b, a)][:3], -h[:3])
    touching = sum(1 for h in pairs.values() if np.any(h[:3] != 0))
    assert touching > 20


def test_gpu_engine_refuses_inlets():
    from fluidem.particles.softsphere_gpu import gpu_refusals

    assert any("[[inlets]]" in r for r in gpu_refusals(feed_case(inlets=[INLET])))


def test_coupled_run_maps_the_particles_that_arrive(tmp_path):
    """With a gas, particles inserted during the run enter the voidage map of the next gas step."""
    case = feed_case(inlets=[{**INLET, "stop": 0.02}], end=0.03).model_dump()
    case["gas"] = {"dt": 1e-4, "grid": {"cells": [4, 10], "size": [0.04, 0.1], "depth": D},
                   "boundaries": {"bottom": {"kind": "inflow", "superficial": 0.05}, "top": {"kind": "pressure_outlet"},
                                  "left": {"kind": "wall"}, "right": {"kind": "wall"}}}
    case["coupling"] = {"voidage": {"method": "centroid"}}
    sim = Simulation(validate_case(case), out_dir=tmp_path / "r")
    s = sim.run()
    assert s["n_particles"] == s["inlet_feed_count"] == 40
    sim.advance(sim.gas.substeps)  # one more gas step maps the particles there now
    gd = sim.gas.grid
    solids = float(((1.0 - sim.gas.last_map.voidage) * gd.dx * gd.dy * D).sum())
    assert solids == pytest.approx(float((4 / 3 * math.pi * sim.state.radius**3).sum()), rel=1e-9)


def test_inlet_beside_a_periodic_side_is_refused():
    walls = [{"name": "box", "kind": "box", "lower": [0, 0, 0], "upper": [0.04, 0.1, D], "periodic": ["x"]}]
    with pytest.raises(CaseError, match=r"inlets.0 \('feed'\).*periodic sides"):
        Simulation(feed_case(count=5, inlets=[{**INLET, "lower": [0.0, 0.07, 0.0]}], walls=walls))


def test_inlet_in_a_periodic_box_fills_without_overlap(tmp_path):
    walls = [{"name": "box", "kind": "box", "lower": [0, 0, 0], "upper": [0.04, 0.1, D], "periodic": ["x"]}]
    case = feed_case(count=20, inlets=[{**INLET, "stop": 0.03}], walls=walls, end=0.15)
    sim = Simulation(case, out_dir=tmp_path / "r")
    s = sim.run()
    assert s["n_particles"] == 20 + 60 and s["max_overlap_rel"] < 0.1


FUNNEL = [{"name": "funnel-left", "kind": "polyline", "points": [[0.0, 0.06], [0.015, 0.03]]},
          {"name": "funnel-right", "kind": "polyline", "points": [[0.025, 0.03], [0.04, 0.06]]},
          {"name": "left", "kind": "plane", "point": [0, 0, 0], "normal": [1, 0, 0]},
          {"name": "right", "kind": "plane", "point": [0.04, 0, 0], "normal": [-1, 0, 0]}]
BELOW = [{"name": "below", "kind": "plane", "point": [0.0, 0.0, 0.0], "normal": [0.0, 1.0, 0.0]}]


def test_hopper_of_segments_fed_and_emptied(tmp_path):
    """Inlet, wall shapes and outlet together: a 2D funnel of two segments fed from above and emptied below;
    the shape contact slots follow the particles through every insertion and removal, and counts balance."""
    case = feed_case(inlets=[{**INLET, "stop": 0.1, "rate": 800.0}], outlets=BELOW, walls=FUNNEL, end=0.3)
    a = Simulation(case, out_dir=tmp_path / "whole").run()
    assert a["inlet_feed_count"] == 80 == a["outlet_below_count"] + a["n_particles"]
    assert a["outlet_below_count"] > 40  # they leave through the gap


def test_hopper_of_segments_resumes_bit_for_bit(tmp_path):
    """The funnel started empty, stopped and resumed, ends as the run made in one go: the shapes' broad-phase
    cells are sized for the largest particle an inlet may bring, not for the (no) particles at the start."""
    case = feed_case(inlets=[{**INLET, "stop": 0.1, "rate": 800.0}], outlets=BELOW, walls=FUNNEL, end=0.16)
    a = Simulation(case, out_dir=tmp_path / "whole").run()
    part = Simulation(case, out_dir=tmp_path / "part")
    part.run(until=0.09)
    b = Simulation.resume(tmp_path / "part").run()
    assert a["n_particles"] == b["n_particles"] > 10
    with h5py.File(tmp_path / "whole" / "restart.h5") as f1, h5py.File(tmp_path / "part" / "restart.h5") as f2:
        for name in ("state/position", "state/velocity", "engine/shape_slot_hist", "engine/shape_slot_elem"):
            assert np.array_equal(f1[name][...], f2[name][...]), name
