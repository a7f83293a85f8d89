"""Milliseconds per gas step (``GasSolver.advance`` alone) on the standard grids.

    python benchmarks/gas_step.py                       # 15x25, 15x45 (tsuji-jet), 39x60, 150x300
    python benchmarks/gas_step.py --grids 15x45 --repeat 5 --seconds 2
    python benchmarks/gas_step.py --grids 39x60,150x300 --linear-solver multigrid,pyamg   # one row per solver
    PYTHONPATH=/path/to/other/src python benchmarks/gas_step.py    # another checkout, for before/after

Problems:

* ``NXxNY``: the Hoomans 1996 orifice bed of ``fluidem.gas.solver._bench_problem`` (0.15 m x 0.5 m,
  ideal gas, 45 m/s jet, bed of voidage 0.4 in the lower 0.2 m, Ergun's beta recomputed from the
  gas every step, moving voidage: a surface wave and a rising bubble), dt = min(1e-4, 0.5 min(dx, dy) / 45).
* ``15x45``: the built-in coupled case ``tsuji-jet`` (``load_case("tsuji-jet").gas.build(...)``:
  0.15 m x 0.9 m, 39 m/s jet, ideal gas, DT = 1e-4 s) with a bubbling-bed voidage (bed to 0.22 m,
  a surface wave and a rising bubble) and Gidaspow's beta from the gas every step, with a solids
  velocity field, as the coupling hands them over.

``--linear-solver``: the ``GasSolver`` option ("auto", the default choice, or "band", "multigrid",
"superlu", "pyamg"); a comma-separated list times each in turn on the same problem. pyamg's
Krylov loop uses NumPy's BLAS: on a small shared machine run it with OPENBLAS_NUM_THREADS=1.

Each row: the first 20 steps are not timed; then ``advance`` alone is timed for ``--seconds``;
repeated ``--repeat`` times on a fresh solver; the median is reported (the machine is shared).
Two clocks: wall time (``perf_counter``) and this process's CPU time (``process_time``), which
other people's jobs on a shared machine disturb less.
"""
from __future__ import annotations

import argparse
import statistics
import time

import numpy as np


def tsuji_problem(linear_solver="auto"):
    from fluidem.case import load_case

    case = load_case("tsuji-jet")
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


def bench_problem(nx, ny, linear_solver="auto"):
    from fluidem.gas.solver import _bench_problem

    solver, state, beta_of, voidage_at = _bench_problem(nx, ny, linear_solver=linear_solver)
    dt = min(1e-4, 0.5 * min(solver.grid.dx, solver.grid.dy) / 45.0)

    def step_args(st, t, dt):
        return {"voidage": voidage_at(t + dt), "beta": beta_of(st), "solids_u": 0.0, "solids_v": 0.0}

    return solver, state, step_args, dt


def time_one(name, seconds, linear_solver="auto"):
    nx, ny = (int(k) for k in name.split("x"))
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
    return {"ms": 1e3 * elapsed / n, "cpu": 1e3 * cpu / n, "steps": n, "it": its / n,
            "lu": (solver.factorisations - fac0) / n, "solver": solver.linear_solver}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--grids", default="15x25,15x45,39x60,150x300")
    ap.add_argument("--seconds", type=float, default=2.0)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--linear-solver", default="auto",
                    help="GasSolver linear_solver: auto, band, multigrid, superlu, pyamg; a comma-separated list "
                         "times each (e.g. multigrid,pyamg)")
    args = ap.parse_args(argv)
    import fluidem

    print(f"fluidem from {fluidem.__file__}")
    print(f"{'grid':>8} {'solver':>9} {'wall ms/step':>12} {'(min':>8} {'max)':>8} {'cpu ms/step':>11} "
          f"{'it/step':>8} {'fact/step':>9} {'steps':>7}")
    for name in args.grids.split(","):
        for linear_solver in args.linear_solver.split(","):
            runs = [time_one(name, args.seconds, linear_solver) for _ in range(args.repeat)]
            ms = [r["ms"] for r in runs]
            r = runs[0]
            label = name + ("*" if name == "15x45" else "")
            print(f"{label:>8} {r['solver']:>9} {statistics.median(ms):12.4f} {min(ms):8.4f} {max(ms):8.4f} "
                  f"{statistics.median(x['cpu'] for x in runs):11.4f} {statistics.median(x['it'] for x in runs):8.2f} "
                  f"{statistics.median(x['lu'] for x in runs):9.3f} {sum(x['steps'] for x in runs):7d}", flush=True)
    print("* tsuji-jet (built-in case), bubbling-bed voidage and beta; medians over --repeat runs")


if __name__ == "__main__":
    main()
