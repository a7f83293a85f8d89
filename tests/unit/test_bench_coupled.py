"""``fluidem bench``'s coupled rows: counts that follow from the case, parts that lie within the wall time
they were measured in, and rates recomputed from the counts."""
from __future__ import annotations

import math
import time

from fluidem.bench import time_coupled
from fluidem.case import load_case


def test_coupled_timing_row():
    case = load_case("tsuji-jet-background")
    until = 0.004
    t0 = time.perf_counter()
    r = time_coupled("tsuji-jet-background", until=until, warmup=0.002, threads=1)
    outside = time.perf_counter() - t0
    # counts the case fixes: gas steps of DT in the window, 14 DEM sub-steps a gas step (the case's comment), particles
    gas_steps = round(until / case.gas.dt)
    assert gas_steps == 20 and r["gas_steps"] == gas_steps and r["substeps"] == 14
    assert r["n_particles"] == sum(s.count for s in case.particles.species) == 2400 and r["threads"] == 1
    assert math.isclose(r["sim_seconds"], until, rel_tol=1e-9)
    # the timed window lies inside the call (warm-up, set-up and compilation included there)
    assert 0.0 < r["wall_s"] < outside
    parts = r["ms_per_gas_step_parts"]
    assert set(parts) == {"DEM", "gas solve", "map", "beta", "deposit", "forces", "other"}
    # each wrapped method is a disjoint part of the step: nested or double-counted timers would exceed the whole
    assert parts["other"] >= 0.0
    assert sum(v for k, v in parts.items() if k != "other") <= r["ms_per_gas_step"]
    # what the "particle" exchange calls every gas step, and what it never calls (cell β)
    assert case.coupling.momentum_exchange == "particle"
    assert min(parts["DEM"], parts["gas solve"], parts["map"], parts["deposit"], parts["forces"]) > 0.0
    assert parts["beta"] == 0.0
    assert 0.0 < parts["DEM"] / r["ms_per_gas_step"] < 1.0
    # rates and extrapolations recomputed from the counts and the measured wall time
    assert math.isclose(r["ms_per_gas_step"], 1e3 * r["wall_s"] / gas_steps, rel_tol=1e-12)
    assert math.isclose(r["particle_steps_per_s"], 2400 * gas_steps * 14 / r["wall_s"], rel_tol=1e-12)
    assert math.isclose(r["minutes_for_20_s"], r["ms_per_gas_step"] * 1e-3 * (20.0 / case.gas.dt) / 60, rel_tol=1e-9)
    # the neighbour lists' share of the DEM: rebuilds x one rebuild, a part of the DEM time
    assert (r["dem_neighbours_ms_per_gas_step"] == 0.0) == (r["neighbour_rebuilds"] == 0)
    assert r["dem_neighbours_ms_per_gas_step"] <= parts["DEM"]


def test_bench_refuses_a_coupled_window_that_is_not_positive(capsys):
    from fluidem.cli import main

    assert main(["bench", "--sizes", "", "--no-gas", "--coupled-until", "0"]) == 2
    assert "--coupled-until = 0.0: must be a positive number" in capsys.readouterr().err


def test_hard_sphere_timing_row():
    """The hoomans-orifice row counts the collisions of its window: the same number as a separate run of
    the case between the same times (collisions start at about 5 ms, when the lattice has fallen together)."""
    from fluidem.bench import time_hard_sphere
    from fluidem.simulation import Simulation

    warmup, until = 0.01, 0.005
    r = time_hard_sphere("hoomans-orifice", warmup=warmup, until=until)
    case = load_case("hoomans-orifice")
    steps = round(until / case.gas.dt)
    assert steps == 50 and r["steps"] == steps and r["n_particles"] == 2400

    sim = Simulation(case)
    sim.run(until=warmup)
    before = sim.engine.collisions
    sim.run(until=warmup + until)
    assert r["collisions"] == sim.engine.collisions - before > 0

    assert math.isclose(r["collisions_per_step"], r["collisions"] / steps, rel_tol=1e-12)
    assert math.isclose(r["collisions_per_s"], r["collisions"] / r["wall_s"], rel_tol=1e-12)
    assert 0.0 < r["engine_ms_per_step"] < r["ms_per_step"]  # the engine is a part of the whole step
    assert math.isclose(r["ms_per_step"], 1e3 * r["wall_s"] / steps, rel_tol=1e-12)
    assert math.isclose(r["engine_collisions_per_s"] * r["engine_ms_per_step"] * 1e-3 * steps, r["collisions"],
                        rel_tol=1e-9)


def test_bench_refuses_a_hard_sphere_window_that_is_not_positive(capsys):
    from fluidem.cli import main

    assert main(["bench", "--sizes", "", "--no-gas", "--no-coupled", "--hard-until", "-1"]) == 2
    assert "--hard-until = -1.0: must be a positive number" in capsys.readouterr().err


def test_coupled_3d_timing_row():
    """The 3D coupled row (``bubbling-3d``): the gas steps the window holds, its parts within the wall time,
    the "particle" exchange's parts all timed."""
    case = load_case("bubbling-3d")
    until = 0.002
    r = time_coupled("bubbling-3d", until=until, warmup=0.001, threads=1)
    assert r["gas_steps"] == round(until / case.gas.dt) == 20
    assert r["n_particles"] == 9240
    parts = r["ms_per_gas_step_parts"]
    assert parts["other"] >= 0.0 and parts["beta"] == 0.0
    assert min(parts["DEM"], parts["gas solve"], parts["map"], parts["deposit"], parts["forces"]) > 0.0
    assert math.isclose(r["particle_steps_per_s"], 9240 * r["gas_steps"] * r["substeps"] / r["wall_s"], rel_tol=1e-12)
