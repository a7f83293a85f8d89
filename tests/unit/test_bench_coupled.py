"""``fluidem bench``'s coupled timing: the parts it reports add up to the wall time it measured."""
from __future__ import annotations

import math

from fluidem.bench import time_coupled


def test_coupled_timing_row():
    r = time_coupled("tsuji-jet", until=0.004, warmup=0.002, threads=1)
    assert r["gas_steps"] == 20 and r["substeps"] == 14 and r["n_particles"] == 2400 and r["threads"] == 1
    parts = r["ms_per_gas_step_parts"]
    assert set(parts) == {"DEM", "gas solve", "map", "beta", "deposit", "forces", "other"}
    assert all(v >= 0.0 for k, v in parts.items() if k != "other")
    assert math.isclose(sum(parts.values()), r["ms_per_gas_step"], rel_tol=1e-9)
    assert parts["DEM"] > 0 and parts["gas solve"] > 0 and parts["deposit"] > 0 and parts["beta"] == 0.0
    assert math.isclose(r["particle_steps_per_s"], 2400 * 20 * 14 / r["wall_s"], rel_tol=1e-12)
    assert math.isclose(r["minutes_for_20_s"], r["ms_per_gas_step"] * 1e-3 * 100000 / 60, rel_tol=1e-12)
    # the neighbour lists' share of the DEM: rebuilds x one rebuild, part of the DEM time
    assert r["neighbour_rebuilds"] >= 0
    assert (r["dem_neighbours_ms_per_gas_step"] == 0.0) == (r["neighbour_rebuilds"] == 0)
    assert r["dem_neighbours_ms_per_gas_step"] <= parts["DEM"]


def test_bench_refuses_a_coupled_window_that_is_not_positive(capsys):
    from fluidem.cli import main

    assert main(["bench", "--sizes", "", "--no-gas", "--coupled-until", "0"]) == 2
    assert "--coupled-until = 0.0: must be a positive number" in capsys.readouterr().err


def test_hard_sphere_timing_row():
    """The hoomans-orifice row: collisions counted over the timed window, rates from the measured times."""
    from fluidem.bench import time_hard_sphere

    r = time_hard_sphere("hoomans-orifice", warmup=0.002, until=0.003)
    assert r["steps"] == 30 and r["n_particles"] == 2400 and r["threads"] == 1
    assert r["collisions"] >= 0 and math.isclose(r["collisions_per_step"], r["collisions"] / 30, rel_tol=1e-12)
    assert 0.0 < r["engine_ms_per_step"] < r["ms_per_step"]  # the engine is a part of the whole step
    assert math.isclose(r["collisions_per_s"], r["collisions"] / r["wall_s"], rel_tol=1e-12)
    assert r["engine_collisions_per_s"] >= r["collisions_per_s"]


def test_bench_refuses_a_hard_sphere_window_that_is_not_positive(capsys):
    from fluidem.cli import main

    assert main(["bench", "--sizes", "", "--no-gas", "--no-coupled", "--hard-until", "-1"]) == 2
    assert "--hard-until = -1.0: must be a positive number" in capsys.readouterr().err
