"""Milliseconds per gas step (``GasSolver.advance`` alone) on the standard grids, linear solvers side by side.

    python benchmarks/gas_step.py                                   # 15x25, 15x45 (tsuji-jet-background), 39x60, 150x300
    python benchmarks/gas_step.py --grids 15x45 --repeat 5 --seconds 2
    python benchmarks/gas_step.py --grids 39x60,75x150,150x300 --linear-solver band,multigrid,superlu --repeat 3
    python benchmarks/gas_step.py --grids 15x25 --seconds 0.2 --repeat 1       # a quick check

Problems:

* ``NXxNY``: the Hoomans 1996 orifice bed of ``fluidem.bench.gas_bench_problem`` (0.15 m x 0.5 m, ideal
  gas, 45 m/s jet, bed of voidage 0.4 in the lower 0.2 m, Ergun's β recomputed from the gas every step,
  moving voidage: a surface wave and a rising bubble), dt = min(1e-4, 0.5 min(dx, dy) / 45 m/s).
* ``15x45``: the built-in coupled case ``tsuji-jet-background`` (``load_case("tsuji-jet-background").gas.build(...)``: 0.15 m x
  0.9 m, 39 m/s jet, ideal gas, dt = 1e-4 s) with a bubbling-bed voidage (bed to 0.22 m, a surface wave
  and a rising bubble) and Gidaspow's β from the gas every step, with a solids velocity field, as the
  coupling hands them over.

``--linear-solver``: the ``GasSolver`` option ("auto", the default choice, or "band", "multigrid",
"superlu"); a comma-separated list makes them the variants of each grid's rounds. SuperLU calls
NumPy's BLAS: on a small shared machine run it with OPENBLAS_NUM_THREADS=1.

Each round, for each grid, times every solver once on a fresh solver: the first 20 steps are not timed,
then ``advance`` alone for ``--seconds``. Two clocks: wall time (``perf_counter``) and this process's CPU
time (``process_time``), which other jobs on a shared machine disturb less. Printed per grid and solver:
wall milliseconds per step (min, median, max over the rounds), the median CPU milliseconds, pressure
corrections and factorisations per step; with several solvers, the median of the per-round ratios of
each to the first.
"""
from __future__ import annotations

import argparse
import time

import numpy as np

import harness  # benchmarks/harness.py: this script's folder is first on sys.path


def tsuji_problem(linear_solver: str = "auto"):
    """The tsuji-jet-background case's gas solver with a bubbling-bed voidage; (solver, state, step_args, dt)."""
    from fluidem.case import load_case

    case = load_case("tsuji-jet-background")
    case.gas.linear_solver = linear_solver
    solver = case.gas.build(case.gravity)
    grid = solver.grid
    X, Y = grid.centres()
    mu = solver.props.viscosity
    d_p = 4e-3

    def voidage_at(t):
        surface = 0.22 + 0.015 * np.sin(2 * np.pi * (X / 0.15 - t / 0.25))
        bed = 0.42 + 0.58 / (1.0 + np.exp(-(Y - surface) / 0.01))
        r = np.hypot(X - 0.075, Y - (0.04 + 0.6 * t) % 0.18)
        return np.clip(bed + 0.45 / (1.0 + np.exp((r - 0.025) / 0.006)), 0.42, 1.0)

    def beta_of(st, eps):
        uc = 0.5 * (st.u[1:] + st.u[:-1])
        vc = 0.5 * (st.v[:, 1:] + st.v[:, :-1])
        slip = np.hypot(uc, vc)
        e = eps
        # Gidaspow: Ergun below voidage 0.8 (Hoomans 1996 eq. 45), Wen-Yu above
        ergun = 150.0 * (1 - e) ** 2 / e * mu / d_p**2 + 1.75 * (1 - e) * st.rho / d_p * slip
        re = np.maximum(e * st.rho * slip * d_p / mu, 1e-12)
        cd = np.where(re < 1000.0, 24.0 / re * (1 + 0.15 * re**0.687), 0.44)
        wen_yu = 0.75 * cd * e * (1 - e) * st.rho * slip / d_p * e**-2.65
        return np.where(e < 0.8, ergun, np.where(e < 0.999, wen_yu, 0.0))

    state = solver.initial_state(voidage=voidage_at(0.0), velocity=(0.0, 1.8))
    vs = 0.05 * np.sin(2 * np.pi * X / 0.15) * (Y < 0.25)

    def step_args(st, t, dt):
        eps = voidage_at(t + dt)
        return {"voidage": eps, "beta": beta_of(st, eps), "solids_u": vs, "solids_v": -vs}

    return solver, state, step_args, 1e-4


def bench_problem(nx: int, ny: int, linear_solver: str = "auto"):
    """The orifice bed of ``fluidem.bench.gas_bench_problem`` with a moving voidage; (solver, state, step_args, dt)."""
    from fluidem.bench import gas_bench_problem

    solver, state, beta_of, voidage_at = gas_bench_problem(nx, ny, linear_solver=linear_solver)
    dt = min(1e-4, 0.5 * min(solver.grid.dx, solver.grid.dy) / 45.0)

    def step_args(st, t, dt):
        return {"voidage": voidage_at(t + dt), "beta": beta_of(st), "solids_u": 0.0, "solids_v": 0.0}

    return solver, state, step_args, dt


def time_one(grid: str, seconds: float, linear_solver: str = "auto") -> dict:
    """A fresh solver on ``grid`` ("NXxNY"): wall ms per step (``value``) and the other figures of one timing."""
    nx, ny = (int(k) for k in grid.split("x"))
    solver, state, step_args, dt = (tsuji_problem(linear_solver) if (nx, ny) == (15, 45)
                                    else bench_problem(nx, ny, linear_solver))
    t = 0.0
    for _ in range(20):
        solver.advance(state, dt, t, **step_args(state, t, dt))
        t += dt
    n = its = 0
    elapsed = cpu = 0.0
    fac0 = solver.factorisations
    wall0 = time.perf_counter()
    while (time.perf_counter() - wall0 < seconds or n < 3) and n < 200000:
        kw = step_args(state, t, dt)  # the coupling's work, not timed
        c0, t0 = time.process_time(), time.perf_counter()
        info = solver.advance(state, dt, t, **kw)
        elapsed += time.perf_counter() - t0
        cpu += time.process_time() - c0
        t += dt
        n += 1
        its += info.iterations
    return {"value": 1e3 * elapsed / n, "cpu_ms": 1e3 * cpu / n, "steps": n, "iterations_per_step": its / n,
            "factorisations_per_step": (solver.factorisations - fac0) / n, "solver": solver.linear_solver}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--grids", default="15x25,15x45,39x60,150x300")
    ap.add_argument("--seconds", type=float, default=2.0, help="timed wall seconds of each solver in each round")
    ap.add_argument("--linear-solver", default="auto",
                    help="GasSolver linear_solver: auto, band, multigrid, superlu; a comma-separated list "
                         "times each (e.g. band,multigrid)")
    harness.add_options(ap, repeat=3)
    a = ap.parse_args(argv)
    import fluidem

    print(f"fluidem from {fluidem.__file__}")
    solvers = [s for s in a.linear_solver.split(",") if s]
    measurements, rows, ratio_lines = {}, [], []
    for grid in [g for g in a.grids.split(",") if g]:
        variants = {s: (lambda s=s, g=grid: time_one(g, a.seconds, s)) for s in solvers}
        rounds = harness.run_rounds(variants, a.repeat, unit="ms")
        measurements[grid] = rounds
        for s in solvers:
            w = rounds.stats(s)
            ex = rounds.extras[s][0]
            rows.append([grid + ("*" if grid == "15x45" else ""), ex["solver"], w["n"], w["min"], w["median"], w["max"],
                         rounds.stats(s, "cpu_ms")["median"], rounds.stats(s, "iterations_per_step")["median"],
                         rounds.stats(s, "factorisations_per_step")["median"],
                         int(sum(e["steps"] for e in rounds.extras[s]))])
        ratio_lines += [f"{grid}: " + rounds.ratio_line(s, solvers[0]) for s in solvers[1:]]
    print(harness.format_table(["grid", "solver", "rounds", "wall ms/step min", "median", "max", "cpu ms/step",
                                "it/step", "fact/step", "steps"], rows))
    for line in ratio_lines:
        print(line)
    print("* tsuji-jet-background (built-in case), bubbling-bed voidage and beta; cpu, it/step, fact/step: medians of the rounds")
    harness.write_json(a.json, measurements, seconds=a.seconds, linear_solvers=solvers)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
