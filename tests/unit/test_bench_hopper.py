"""``fluidem bench``'s hopper row: counts that follow from the case and a rate recomputed from them."""
from __future__ import annotations

import math

from fluidem.bench import time_hopper
from fluidem.case import load_case
from fluidem.cli import main


def test_hopper_timing_row():
    case = load_case("hopper-3d")
    r = time_hopper("hopper-3d", warmup=0.002, until=0.002, threads=1)
    n = sum(s.count for s in case.particles.species)
    # nothing reaches the outlet plane 5 cm below the bed within 4 ms: every step counts all the particles
    assert r["n_particles"] == r["n_at_start"] == r["n_at_end"] == n == 3000 and r["threads"] == 1
    assert abs(r["steps"] - 0.002 / r["dt_s"]) <= 1.0  # the window in steps of the case's dt (about 9 µs)
    assert math.isclose(r["particle_steps_per_s"], n * r["steps"] / r["wall_s"], rel_tol=1e-12)


def test_bench_refuses_a_hopper_window_that_is_not_positive(capsys):
    assert main(["bench", "--sizes", "", "--no-gas", "--no-coupled", "--no-hard-sphere", "--hopper-until", "0"]) == 2
    assert "--hopper-until = 0.0: must be a positive number" in capsys.readouterr().err
