"""Milliseconds per step of the 3D gas solver (``GasSolver.advance`` on a 3D grid alone), 1e4 to 1e6 cells.

    python benchmarks/gas3d_step.py                                   # 20x25x20, 40x60x40 (1e4, 1e5 cells)
    python benchmarks/gas3d_step.py --grids 100x100x100 --repeat 1 --seconds 1 --warmup 2     # 1e6 cells
    python benchmarks/gas3d_step.py --grids 20x25x20 --linear-solver multigrid,superlu --repeat 3
    python benchmarks/gas3d_step.py --grids 10x12x10 --seconds 0.2 --repeat 1                 # a quick check
    python benchmarks/gas3d_step.py --grids 20x25x20,40x60x40 --matrices 6 --repeat 3        # against pyamg
    python benchmarks/gas3d_step.py --grids 20x25x20,40x60x40,100x100x100 --kernels 2 --seconds 3 --warmup 3
                                                                  # the step's kernels, GMRES's parts

Problem ``NXxNYxNZ``: a 3D bubbling bed, 0.2 m x 0.4 m x 0.2 m (y up), ideal gas, inflow at the bottom
through influx cells of voidage 0.4: 0.6 m/s superficial background and a central circular jet of
radius 1 cm at 20 m/s interstitial; a pressure outlet on top, no-slip walls on the four other sides; a bed
of voidage 0.42 below 0.15 m with a surface wave and a rising bubble (the voidage moves every step), and
Ergun's β (Hoomans 1996 eq. 45, d_p = 2 mm) from the gas every step where the voidage is below 0.8;
dt = min(1e-4 s, 0.5 h_min / 20 m/s).

``--linear-solver``: the ``GasSolver`` option ("auto", the default choice, "multigrid" or "superlu"); a
comma-separated list makes them the variants of each grid's rounds. Each round, for each grid, times every
solver once on a fresh solver: ``--warmup`` steps are not timed, then ``advance`` alone for ``--seconds``
(at least 3 steps). Printed per grid and solver: wall milliseconds per step (min, median, max over the
rounds), the median CPU milliseconds and CPU microseconds per cell, pressure corrections and GMRES iterations
per step.

``--matrices K``: instead of whole steps, the linear solvers alone on the same matrices. The bed runs
``--warmup`` steps, then the matrix and right-hand side of the first pressure correction of each of the next
steps are kept (K of them, ``keeping_corrections``; with pyamg installed, else fluidem's row alone); each is
solved to the target that ``GasSolver`` sets (``KRYLOV_REDUCTION_3D`` of the
right-hand side's norm, or the absolute floor) by (a) fluidem's GMRES with the aggregation W-cycle
(``_multigrid3d_kernels``: hierarchy made anew for every matrix, as the solver does at each step's first
correction) and (b) pyamg's smoothed
aggregation (``smoothed_aggregation_solver``, its defaults: symmetric Gauss-Seidel, one V-cycle as
preconditioner) inside SciPy's GMRES and BiCGStab (restart 30), with the pyamg hierarchy made for every
matrix ("setup+solve") and, a lower bound for a scheme that would keep it, made once for the first of the K
matrices and reused for all ("one setup for all").
Printed per grid and solver: CPU microseconds per cell and solve (median over the rounds, each round
all K matrices), iterations per solve, and the largest ||b - A x|| / target (<= 1: each reached its target).

``--kernels K``: where a step's time goes, one round. The bed (multigrid) runs ``--warmup`` steps, then
``--seconds`` of steps with every kernel call of ``GasSolver3D.advance`` timed (``_solver3d_kernels``:
begin_step, newton_multigrid, courant_number, end_step; the Newton loop, with its residuals, Jacobian,
hierarchy, GMRES solves and corrections, is one compiled call): CPU µs per cell and call, calls per step, µs
per cell and step ("whole step": ``advance``; the rest of it is Python). Then the first pressure corrections
of the next K steps are kept (``keeping_corrections``, untimed) and replayed (repeated for at least 1 CPU
second, after one untimed pass): ``mg_setup`` per call, and GMRES split per iteration: ``mg_cycle`` alone as many times
as GMRES iterated, ``mg_matvec`` once more (the products, and the true residual's), the Krylov part (the
rest: Gram-Schmidt, the updates of x), and the cycle level by level ("down": the sweeps before the coarse
correction and the restriction, one pass; "up": the prolongation and the sweeps after it; Python drives
the level loop there, which adds a few µs per call to the small levels).
"""
from __future__ import annotations

import argparse
import contextlib
import inspect
import math
import time

import harness  # benchmarks/harness.py: this script's folder is first on sys.path
import numpy as np


def bed_problem(nx: int, ny: int, nz: int, linear_solver: str = "auto"):
    """The 3D bubbling bed on an nx x ny x nz grid: (solver, state, step_args, dt)."""
    from fluidem.gas import (
        Circle,
        GasProperties,
        GasSolver,
        Inflow,
        PressureOutlet,
        StaggeredGrid,
        Wall,
    )

    L, H = 0.2, 0.4
    grid = StaggeredGrid(cells=(nx, ny, nz), size=(L, H, L))
    props = GasProperties()
    bcs = {s: Wall() for s in grid.sides}
    bcs.update(top=PressureOutlet(), bottom=Inflow(
        superficial=0.6, voidage=0.4, patches=[Circle(centre=(0.5 * L, 0.5 * L), radius=0.01, interstitial=20.0)]))
    solver = GasSolver(grid, props, bcs, linear_solver=linear_solver)
    X, Y, Z = grid.centres()
    d_p, mu = 2e-3, props.viscosity

    def voidage_at(t):
        surface = 0.15 + 0.01 * np.sin(2 * np.pi * (X / L - t / 0.2)) * np.cos(2 * np.pi * Z / L)
        bed = 0.42 + 0.58 / (1.0 + np.exp(-(Y - surface) / 0.01))
        r = np.sqrt((X - 0.5 * L) ** 2 + (Y - (0.03 + 0.5 * t) % 0.12) ** 2 + (Z - 0.5 * L) ** 2)
        return np.clip(bed + 0.45 / (1.0 + np.exp((r - 0.02) / 0.005)), 0.42, 1.0)

    def step_args(st, t, dt):
        eps = voidage_at(t + dt)
        uc = 0.5 * (st.u[1:] + st.u[:-1])
        vc = 0.5 * (st.v[:, 1:] + st.v[:, :-1])
        wc = 0.5 * (st.w[:, :, 1:] + st.w[:, :, :-1])
        slip = np.sqrt(uc**2 + vc**2 + wc**2)
        ergun = 150.0 * (1 - eps) ** 2 / eps * mu / d_p**2 + 1.75 * (1 - eps) * st.rho / d_p * slip  # eq. 45
        return {"voidage": eps, "beta": np.where(eps < 0.8, ergun, 0.0), "solids_u": 0.0, "solids_v": 0.0,
                "solids_w": 0.0}

    state = solver.initial_state(voidage=voidage_at(0.0))
    dt = min(1e-4, 0.5 * min(grid.spacing) / 20.0)
    return solver, state, step_args, dt


def time_one(grid: str, seconds: float, warmup: int, linear_solver: str = "auto") -> dict:
    """A fresh solver on ``grid`` ("NXxNYxNZ"): wall ms per step (``value``) and the other figures of one timing."""
    nx, ny, nz = (int(k) for k in grid.split("x"))
    solver, state, step_args, dt = bed_problem(nx, ny, nz, linear_solver)
    t = 0.0
    for _ in range(warmup):
        solver.advance(state, dt, t, **step_args(state, t, dt))
        t += dt
    n = its = 0
    elapsed = cpu = 0.0
    kry0 = solver.krylov_iterations
    wall0 = time.perf_counter()
    while (time.perf_counter() - wall0 < seconds or n < 3) and n < 100000:
        kw = step_args(state, t, dt)  # the coupling's work, not timed
        c0, t0 = time.process_time(), time.perf_counter()
        info = solver.advance(state, dt, t, **kw)
        elapsed += time.perf_counter() - t0
        cpu += time.process_time() - c0
        t += dt
        n += 1
        its += info.iterations
    return {"value": 1e3 * elapsed / n, "cpu_ms": 1e3 * cpu / n, "steps": n, "iterations_per_step": its / n,
            "krylov_per_step": (solver.krylov_iterations - kry0) / n, "solver": solver.linear_solver,
            "cells": nx * ny * nz}


@contextlib.contextmanager
def keeping_corrections(kept: list, count: int):
    """While inside, the first pressure correction of each step of a 3D ``GasSolver`` on the multigrid path is
    appended to ``kept`` as (matrix data, right-hand side, target), until ``count`` are kept.

    The Newton iterations run in one compiled call (``_solver3d_kernels.newton_multigrid``), so the correction is
    taken around that call: its first residual is evaluated beforehand with the same arrays (``predict_residual``
    sets the face velocities and the residuals from the pressure alone, so the call repeats it to the same bits),
    its right-hand side (−R, row 0 zero where the pressure level is pinned) and GMRES target (as the loop computes
    it) kept, and the Jacobian it assembled read back afterwards from ``data``: the loop's first iteration
    assembles it and makes the hierarchy, and later iterations of the step keep it (chord steps) unless GMRES
    fails on it. A step that converged without a correction, or assembled more than once, is not kept."""
    from fluidem.gas import solver3d as S3

    K3 = S3.K3
    newton = K3.newton_multigrid
    names = list(inspect.signature(newton.py_func).parameters)

    def kept_first(*args):
        a = dict(zip(names, args))
        if len(kept) >= count:
            return newton(*args)
        rel = K3.predict_residual(a["W"], a["C"], a["F"], a["K"], a["row_of"], a["R"], a["fpar"], a["ipar"], a["out"])
        b = -a["R"]
        if a["pinned"]:
            b[0] = 0.0
        target = max(a["reduction"] * float(np.linalg.norm(b)),
                     a["floor_factor"] * float(a["out"][K3.O_QREF]) / math.sqrt(b.size))
        made = int(a["counts"][0])
        result = newton(*args)
        if rel > a["tolerance"] and int(a["counts"][0]) == made + 1:
            kept.append((a["data"].copy(), b, target))
        return result

    K3.newton_multigrid = kept_first
    try:
        yield kept
    finally:
        K3.newton_multigrid = newton


def capture(grid: str, warmup: int, count: int) -> tuple[list, np.ndarray, np.ndarray, object]:
    """The bed on ``grid`` run ``warmup`` steps, then until ``count`` pressure corrections were kept
    (``keeping_corrections``): their (matrix data, right-hand side, target), the CSC pattern and the solver's
    multigrid arrays."""
    nx, ny, nz = (int(k) for k in grid.split("x"))
    solver, state, step_args, dt = bed_problem(nx, ny, nz, "multigrid")
    t = 0.0
    for _ in range(warmup):
        solver.advance(state, dt, t, **step_args(state, t, dt))
        t += dt
    kept, _ = keep_next(grid, solver, state, step_args, dt, t, count)
    return kept, solver._indices, solver._indptr, solver._mg


def keep_next(grid: str, solver, state, step_args, dt: float, t: float, count: int) -> tuple[list, float]:
    """The bed's next steps from time ``t`` until ``count`` pressure corrections were kept
    (``keeping_corrections``): (the kept corrections, the time reached)."""
    kept = []
    with keeping_corrections(kept, count):
        for _ in range(100 * count):  # a step without a kept correction is rare; give up rather than loop on
            if len(kept) >= count:
                break
            solver.advance(state, dt, t, **step_args(state, t, dt))
            t += dt
    if len(kept) < count:
        raise RuntimeError(f"{grid}: {len(kept)} of {count} pressure corrections kept in {100 * count} steps")
    return kept, t


def solve_matrices(grid: str, warmup: int, count: int, repeat: int) -> list[list]:
    """Rows of the ``--matrices`` table for ``grid`` (without pyamg installed, fluidem's row alone)."""
    try:
        import pyamg
    except ImportError:
        pyamg = None
        print("pyamg is not installed: its rows are left out (pip install pyamg)")
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla

    from fluidem.gas import _multigrid3d_kernels as MK
    from fluidem.gas.solver import KRYLOV_MAX

    kept, indices, indptr, mg = capture(grid, warmup, count)
    n = kept[0][1].size
    x = np.zeros(n)

    def ours():
        its, xs = 0, []
        for data, b, target in kept:
            MK.mg_setup(data, mg.ell, mg.MGL, mg.MGI, mg.MGA, mg.MGS, mg.MGW, mg.DLU, mg.PIV)
            its += MK.gmres(mg.MGL, mg.MGI, mg.MGA, mg.MGS, mg.MGW, mg.DLU, mg.PIV, mg.KRY, mg.HES, b, x, target,
                            KRYLOV_MAX)
            xs.append(x.copy())
        return its, xs

    def amg(method, reuse):
        its, xs, ml = 0, [], None
        for data, b, target in kept:
            A = sp.csr_matrix(sp.csc_matrix((data, indices, indptr), shape=(n, n)))
            if ml is None or not reuse:
                ml = pyamg.smoothed_aggregation_solver(A)
            calls = [0]

            def cb(_):
                calls[0] += 1

            M = ml.aspreconditioner(cycle="V")
            rtol = target / np.linalg.norm(b)
            if method == "gmres":
                y, _ = spla.gmres(A, b, rtol=rtol, atol=0.0, restart=30, maxiter=10, M=M, callback=cb,
                                  callback_type="pr_norm")
            else:
                y, _ = spla.bicgstab(A, b, rtol=rtol, atol=0.0, maxiter=300, M=M, callback=cb)
            its += calls[0]
            xs.append(y)
        return its, xs

    variants = {"fluidem multigrid + GMRES": lambda: ours()}
    if pyamg is not None:
        variants.update({"pyamg SA + GMRES, setup+solve": lambda: amg("gmres", False),
                         "pyamg SA + BiCGStab, setup+solve": lambda: amg("bicgstab", False),
                         "pyamg SA + GMRES, one setup for all": lambda: amg("gmres", True),
                         "pyamg SA + BiCGStab, one setup for all": lambda: amg("bicgstab", True)})
    times = {k: [] for k in variants}
    result = {}
    for r in range(repeat):
        for name in harness.round_order(list(variants), r):
            c0 = time.process_time()
            result[name] = variants[name]()
            times[name].append(time.process_time() - c0)
    worst = {}
    for name, (_, xs) in result.items():  # ||b - A x|| / target, outside the timing
        worst[name] = max(np.linalg.norm(b - sp.csc_matrix((data, indices, indptr), shape=(n, n)) @ y) / target
                          for (data, b, target), y in zip(kept, xs))
    return [[grid, n, name, 1e6 * float(np.median(times[name])) / (n * count), result[name][0] / count,
             worst[name]] for name in variants]


def kernel_split(grid: str, seconds: float, warmup: int, count: int) -> list[list]:
    """Rows of the ``--kernels`` table for ``grid``: CPU µs per cell of each kernel call of a step, then of
    ``mg_setup`` and the parts of ``MK.gmres`` replayed on ``count`` pressure corrections kept afterwards."""
    from fluidem.gas import _multigrid3d_kernels as MK
    from fluidem.gas import solver3d as S3
    from fluidem.gas.solver import KRYLOV_MAX

    nx, ny, nz = (int(k) for k in grid.split("x"))
    n = nx * ny * nz
    solver, state, step_args, dt = bed_problem(nx, ny, nz, "multigrid")
    t = 0.0
    for _ in range(warmup):
        solver.advance(state, dt, t, **step_args(state, t, dt))
        t += dt
    cpu, calls, saved = {}, {}, []

    def wrap(mod, name):
        f = getattr(mod, name)
        saved.append((mod, name, f))

        def timed_call(*args):
            c0 = time.process_time()
            r = f(*args)
            cpu[name] = cpu.get(name, 0.0) + time.process_time() - c0
            calls[name] = calls.get(name, 0) + 1
            return r

        setattr(mod, name, timed_call)

    # the kernels ``advance`` calls on the multigrid path; the Newton loop (residuals, the Jacobian, the hierarchy,
    # GMRES, the corrections) is one compiled call
    for name in ("begin_step", "newton_multigrid", "courant_number", "end_step"):
        wrap(S3.K3, name)
    steps, whole = 0, 0.0
    try:
        wall0 = time.perf_counter()
        while time.perf_counter() - wall0 < seconds or steps < 3:
            kw = step_args(state, t, dt)
            c0 = time.process_time()
            solver.advance(state, dt, t, **kw)
            whole += time.process_time() - c0
            t += dt
            steps += 1
    finally:
        for mod, name, f in saved:
            setattr(mod, name, f)
    rows = [[grid, n, "whole step", 1e6 * whole / (n * steps), 1.0, 1e6 * whole / (n * steps)]]
    for name in sorted(cpu, key=lambda k: -cpu[k]):
        rows.append([grid, n, name, 1e6 * cpu[name] / (n * calls[name]), calls[name] / steps,
                     1e6 * cpu[name] / (n * steps)])
    kept, t = keep_next(grid, solver, state, step_args, dt, t, count)  # the next steps, untimed
    # GMRES replayed: the whole solve, then its iterations' cycles and matrix products alone
    mg = solver._mg
    x = np.zeros(n)
    levels = mg.MGL.shape[1] - 1
    def replay(part):
        its_all = 0
        for data, b, target in kept:
            c0 = time.process_time()
            MK.mg_setup(data, mg.ell, mg.MGL, mg.MGI, mg.MGA, mg.MGS, mg.MGW, mg.DLU, mg.PIV)
            part["mg_setup"] = part.get("mg_setup", 0.0) + time.process_time() - c0
            c0 = time.process_time()
            its = MK.gmres(mg.MGL, mg.MGI, mg.MGA, mg.MGS, mg.MGW, mg.DLU, mg.PIV, mg.KRY, mg.HES, b, x, target,
                           KRYLOV_MAX)
            part["gmres"] = part.get("gmres", 0.0) + time.process_time() - c0
            its_all += its
            v, z = b / np.linalg.norm(b), np.zeros(n)
            c0 = time.process_time()
            for _ in range(its):
                MK.mg_cycle(mg.MGL, mg.MGI, mg.MGA, mg.MGS, mg.MGW, mg.DLU, mg.PIV, v, z)
            part["cycle"] = part.get("cycle", 0.0) + time.process_time() - c0
            c0 = time.process_time()
            for _ in range(its + 1):  # the iterations' products and the true residual's
                MK.mg_matvec(mg.MGL, mg.MGI, mg.MGA, z, v)
            part["matvec"] = part.get("matvec", 0.0) + time.process_time() - c0
            v = b / np.linalg.norm(b)
            for _ in range(its):  # the cycle level by level (mg_cycle's loop driven from here)
                _cycle_by_level(MK, mg, v, z, part)
        return its_all

    replay({})  # untimed: compiles, and brings the arrays in
    part, its_all, passes = {}, 0, 0
    while passes < 2 or part["gmres"] < 1.0:
        its_all += replay(part)
        passes += 1
    part["krylov"] = part["gmres"] - part["cycle"] - part["matvec"]
    k = max(its_all, 1)
    rows.append([grid, n, "mg_setup replayed", 1e6 * part["mg_setup"] / (n * passes * len(kept)), "per call", None])
    rows.append([grid, n, f"gmres replayed ({its_all / (passes * len(kept)):.1f} it/solve)", 1e6 * part["gmres"] / (n * k), "per it",
                 None])
    for name in ["cycle", "matvec", "krylov"] + [f"level {l} {w}" for l in range(levels)
                                                   for w in ("down", "up", "coarsest")]:
        if name in part:
            rows.append([grid, n, "  " + name, 1e6 * part[name] / (n * k), "per it", None])
    return rows


def _cycle_by_level(MK, mg, b, x, part):
    """``MK.mg_cycle`` with its loop in Python, each level's pass timed into ``part`` (CPU s)."""
    MGL, MGI, MGW = mg.MGL, mg.MGI, mg.MGW
    levels = MGL.shape[1] - 1
    X, B, visits = MGW[MK.MG_X], MGW[MK.MG_B], [0] * (levels + 1)
    top = levels - 1
    l, down = 0, True

    def run(key, f, *args):
        c0 = time.process_time()
        f(*args)
        part[key] = part.get(key, 0.0) + time.process_time() - c0

    while True:
        if down:
            if l == top:
                run(f"level {l} coarsest", MK._mg_coarsest, MGL, mg.DLU, mg.PIV, X, B)
                down = False
                continue
            wrap = MGL[1, l] > 1 and MGI[MGL[0, l], MK.MGI_NB] >= 0
            if l == 0:
                run("level 0 down", MK._mg_presmooth_restrict, MGL, MGI, mg.MGS, x, b, B, l, wrap, True)
            else:
                run(f"level {l} down", MK._mg_presmooth_restrict, MGL, MGI, mg.MGS, X, B, B, l, wrap, visits[l] == 0)
            l += 1
            visits[l] = 0
        else:
            if l == 0:
                break
            visits[l] += 1
            if l < top and visits[l] < MK.CYCLES and 4 * (MGL[0, l + 1] - MGL[0, l]) <= MGL[0, l] - MGL[0, l - 1]:
                down = True
                continue
            l -= 1
            wrap = MGL[1, l] > 1 and MGI[MGL[0, l], MK.MGI_NB] >= 0
            run(f"level {l} up", MK._mg_prolong_postsmooth, MGL, MGI, mg.MGS, x if l == 0 else X, b if l == 0 else B,
                X, l, wrap)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--grids", default="20x25x20,40x60x40")
    ap.add_argument("--seconds", type=float, default=2.0, help="timed wall seconds of each solver in each round")
    ap.add_argument("--warmup", type=int, default=10, help="untimed steps of a fresh solver")
    ap.add_argument("--linear-solver", default="auto",
                    help="GasSolver linear_solver: auto, multigrid, superlu; a comma-separated list times each")
    ap.add_argument("--matrices", type=int, default=0,
                    help="time the linear solvers alone (fluidem's, pyamg's) on this many pressure corrections")
    harness.add_options(ap, repeat=3)
    ap.add_argument("--kernels", type=int, default=0,
                    help="CPU µs per cell of each kernel of a step, and of GMRES's parts on this many corrections")
    a = ap.parse_args(argv)
    import fluidem

    print(f"fluidem from {fluidem.__file__}")
    if a.kernels:
        rows = []
        for grid in [g for g in a.grids.split(",") if g]:
            rows += kernel_split(grid, a.seconds, a.warmup, a.kernels)
        print(harness.format_table(["grid", "cells", "kernel", "cpu us/cell/call", "calls/step", "cpu us/cell/step"],
                                   rows))
        return 0
    if a.matrices:
        rows = []
        for grid in [g for g in a.grids.split(",") if g]:
            rows += solve_matrices(grid, a.warmup, a.matrices, a.repeat)
        print(harness.format_table(["grid", "cells", "linear solver", "cpu us/cell/solve", "it/solve",
                                    "max |r|/target"], rows))
        return 0
    solvers = [s for s in a.linear_solver.split(",") if s]
    measurements, rows, ratio_lines = {}, [], []
    for grid in [g for g in a.grids.split(",") if g]:
        variants = {s: (lambda s=s, g=grid: time_one(g, a.seconds, a.warmup, s)) for s in solvers}
        rounds = harness.run_rounds(variants, a.repeat, unit="ms")
        measurements[grid] = rounds
        for s in solvers:
            w = rounds.stats(s)
            ex = rounds.extras[s][0]
            rows.append([grid, ex["cells"], ex["solver"], w["n"], w["min"], w["median"], w["max"],
                         rounds.stats(s, "cpu_ms")["median"], 1e3 * rounds.stats(s, "cpu_ms")["median"] / ex["cells"],
                         rounds.stats(s, "iterations_per_step")["median"],
                         rounds.stats(s, "krylov_per_step")["median"], int(sum(e["steps"] for e in rounds.extras[s]))])
        ratio_lines += [f"{grid}: " + rounds.ratio_line(s, solvers[0]) for s in solvers[1:]]
    print(harness.format_table(["grid", "cells", "solver", "rounds", "wall ms/step min", "median", "max", "cpu ms/step",
                                "cpu us/cell", "it/step", "gmres/step", "steps"], rows))
    for line in ratio_lines:
        print(line)
    harness.write_json(a.json, measurements, seconds=a.seconds, warmup=a.warmup, linear_solvers=solvers)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
