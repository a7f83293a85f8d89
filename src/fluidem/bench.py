"""``fluidem bench``: throughput on standard problems, printed as a table.

Problems
--------
dense bed   The peer benchmark of shared/PEERS.md: monodisperse spheres d = 4 mm,
            ρ = 2700 kg/m³, Hertz–Mindlin with tangential history (E = 5 MPa, ν = 0.3,
            e = 0.9, μ = 0.3 for particles and walls), dt = 1e-5 s, skin 1 mm, in a
            closed box, loaded settled and at rest. The settled beds are made once by
            this engine (lattice → settle → quench) and cached.
pour        The built-in 2D ``pour`` case (500 particles), stepping from its start.
hopper      The built-in ``hopper-3d`` case (3000 spheres of 4 mm, linear spring–dashpot, an STL cone of
            192 triangles, an outlet plane) discharging: its first ``hopper_warmup`` seconds (the bed
            collapses and the flow through the orifice sets in) are run untimed, then ``hopper_until``
            seconds of the discharge are timed, outlet removals included; particle-steps per second
            over the particles present at each step, next to the dense bed's rows of the same run.
coupled     The built-in ``tsuji-jet-background`` case (Sun 2007: 2400 soft spheres, 15 × 45 gas cells,
            DT = 2e-4 s, 14 DEM sub-steps) including the gas, from its start for ``coupled_until``
            simulated seconds after a short warm-up that compiles: particle-steps per second,
            ms per gas step split into DEM, gas solve, map, deposit, forces and the rest (of the
            DEM, the neighbour lists' share estimated as rebuilds × one rebuild timed after the
            run: the sub-steps run in one compiled call), and the wall time that 20 s at this pace
            would take (the case's length; the target is 3 minutes on 2 cores).
coupled 3D  The built-in ``bubbling-3d`` case (9240 spheres of 1.2 mm, 15 × 40 × 3 gas cells, exact
            sphere-in-cell voidage) the same way, for min(``coupled_until``, 0.02) simulated seconds (its
            DEM step is 7 times shorter: a window as long as the 2D row's would take minutes), with the
            gas side's share of the gas step (map, gas solve, deposit, forces; the target: at most 30 %
            on 2 cores, benchmarks/README.md).
hard spheres The built-in ``hoomans-orifice`` case (Hoomans 1996 Table 2: 2400 hard spheres, 15 × 25
            gas cells, DT = 1e-4 s) including the gas: its 0.5 s start-up at the u_mf background is run
            untimed (``hard_warmup``), then ``hard_until`` seconds of the 45 m/s jet are timed:
            collisions per second of the whole run and of the engine alone (the target: 2e6 per
            second on one core), collisions and milliseconds per step. The engine is serial.
GPU         ``--device gpu``: the dense bed of 100,000, 1,000,000 and 10,000,000 spheres (tiles of the
            10,000 bed) on the GPU engine (``particles/softsphere_gpu.py``), the only rows then run.
gas step    One gas-phase step on the 15 × 25, 39 × 60 and 150 × 300 grids
            (``gas_step_benchmark``: Hoomans 1996 orifice bed), with the
            pressure-correction solver ``gas_linear_solver`` ("auto", or e.g. "band"; for
            solvers side by side see ``benchmarks/gas_step.py --linear-solver band,multigrid``).

Only the stepping loop is timed. Results are particle-steps per second.
"""
from __future__ import annotations

import json
import math
import os
import sys
import time
from pathlib import Path

import numpy as np

DIAMETER = 4e-3
DENSITY = 2700.0
DT = 1e-5
SKIN = 1e-3


def cache_dir() -> Path:
    d = Path(os.environ.get("FLUIDEM_CACHE", Path.home() / ".cache" / "fluidem")) / "bench"
    d.mkdir(parents=True, exist_ok=True)
    return d


def box_side(n: int) -> float:
    """Box width [m]: 0.08 m for 10,000 spheres (PEERS.md), area scaled to keep beds about 9–15 cm high."""
    if n <= 10000:
        return 0.08 * (n / 10000) ** (1 / 3)
    return 0.08 * (n / 10000) ** 0.4


def bed_case(n: int, side: float, height: float, restitution: float = 0.9, placement=None):
    from .case import validate_case

    data = {
        "name": f"dense-bed-{n}",
        "description": "PEERS.md dense-bed benchmark",
        "particles": {
            "dimensions": 3,
            "species": [{"name": "glass", "diameter": DIAMETER, "density": DENSITY, "count": n}],
            "contact": {"model": "hertz_mindlin", "youngs_modulus": 5e6, "poisson_ratio": 0.3,
                        "restitution": restitution, "friction": 0.3},
            "placement": placement or {"method": "lattice", "spacing": 1.1, "perturbation": 0.02,
                                       "region_lower": [0.0, 0.0, 0.0], "region_upper": [side, side, height]},
        },
        "walls": [{"name": "box", "kind": "box", "lower": [0.0, 0.0, 0.0], "upper": [side, side, height]}],
        "time": {"end": 1.0, "dt": DT},
        "neighbours": {"skin": SKIN},
    }
    return validate_case(data)


def settled_bed(n: int, verbose: bool = True) -> Path:
    """Path of the settled bed of n spheres (npz: position, diameter, box_lower, box_upper).

    The 10,000-sphere bed ships with the package (made by ``_settle`` below). Multiples
    of 10,000 are tiles of it side by side (the inner walls removed), so that the
    100,000 bed has the same packing and contacts without an hour of settling. Other
    sizes are settled once and cached.
    """
    from importlib import resources

    shipped = Path(str(resources.files("fluidem") / "data" / f"bed_{n}.npz"))
    if shipped.exists():
        return shipped
    path = cache_dir() / f"bed_{n}.npz"
    if path.exists():
        return path
    if n > 10000 and n % 10000 == 0:
        _tile(settled_bed(10000), n // 10000, path)
        return path
    return _settle(n, path, verbose)


def _tile(base: Path, copies: int, path: Path) -> None:
    a = max(k for k in range(1, int(copies**0.5) + 1) if copies % k == 0)
    b = copies // a
    bed = np.load(base)
    side = bed["box_upper"] - bed["box_lower"]
    pos = np.concatenate([bed["position"] + np.array([ix * side[0], iy * side[1], 0.0])
                          for ix in range(a) for iy in range(b)])
    np.savez_compressed(path, position=pos, diameter=np.tile(bed["diameter"], copies),
                        box_lower=bed["box_lower"], box_upper=bed["box_lower"] + side * np.array([a, b, 1.0]))


def _settle(n: int, path: Path, verbose: bool) -> Path:
    """Settle n spheres from a loose lattice under gravity, quench, save (slow: minutes per 10,000)."""
    from .particles.softsphere import SoftSphereEngine

    side = box_side(n)
    per_layer = int(side / (1.1 * DIAMETER)) ** 2
    height = (n / per_layer + 2) * 1.1 * DIAMETER
    case = bed_case(n, side, height, restitution=0.3)
    eng = SoftSphereEngine(case)
    if verbose:
        print(f"fluidem bench: settling a bed of {n} spheres once (cached in {path}) ...", file=sys.stderr, flush=True)
    t0 = time.perf_counter()
    # settle: fall and damp; quench velocities every 0.02 s after the collapse
    for k in range(40):
        eng.advance(2000)
        ke = 0.5 * np.sum(eng.state.mass[:, None] * eng.state.velocity**2)
        if k >= 10:
            eng.state.velocity[:] = 0.0
            eng.state.omega[:] = 0.0
        if verbose:
            print(f"  t = {eng.time:.2f} s  kinetic energy {ke:.3e} J  ({time.perf_counter() - t0:.0f} s)",
                  file=sys.stderr, flush=True)
        if k >= 20 and ke < 1e-9 * n:
            break
    st = eng.state
    top = float(np.max(st.position[:, 2] + st.radius))
    np.savez_compressed(path, position=st.position, diameter=2 * st.radius, box_lower=np.zeros(3),
             box_upper=np.array([side, side, top + 2 * DIAMETER]))
    return path


def load_bed_engine(n: int, device: str = "cpu"):
    """The soft-sphere engine of the settled dense bed of n spheres (``device`` "gpu": the GPU engine)."""
    from .particles.softsphere import SoftSphereEngine
    from .state import ParticleState

    bed = np.load(settled_bed(n))
    lo, hi = bed["box_lower"], bed["box_upper"]
    case = bed_case(n, float(hi[0] - lo[0]), float(hi[2] - lo[2]))
    case.walls[0].upper = tuple(float(x) for x in hi)
    st = ParticleState.create(bed["position"], np.zeros_like(bed["position"]), bed["diameter"],
                              np.zeros(n, np.int64), np.array([DENSITY]))
    if device == "gpu":
        from .particles.softsphere_gpu import SoftSphereGPUEngine

        return SoftSphereGPUEngine(case.with_overrides({"device": "gpu"}), state=st)
    return SoftSphereEngine(case, state=st)


def time_engine(eng, steps: int, target_seconds: float = 5.0) -> tuple[int, float]:
    eng.advance(20)  # compile / warm caches
    if steps <= 0:
        t0 = time.perf_counter()
        eng.advance(50)
        per = (time.perf_counter() - t0) / 50
        steps = max(50, int(target_seconds / max(per, 1e-9)))
    t0 = time.perf_counter()
    eng.advance(steps)
    return steps, time.perf_counter() - t0


COUPLED_3D_UNTIL = 0.02  # [s] the longest window of the 3D coupled row

# where a coupled gas step's wall time goes: (name, owner, bound method) of one simulation's objects
COUPLED_COMPONENTS = (("DEM", "engine", "advance"), ("gas solve", "solver", "advance"), ("map", "gas", "_map"),
                      ("beta", "gas", "cell_beta"), ("deposit", "gas", "_deposit"),
                      ("forces", "gas", "set_particle_forces"))


def _wrap(obj, name, key, acc, calls):
    """Time every call of ``obj.name`` into acc[key] (an instance attribute: nothing global is patched)."""
    fn = getattr(obj, name)

    def timed(*args, **kwargs):
        t0 = time.perf_counter()
        try:
            return fn(*args, **kwargs)
        finally:
            acc[key] += time.perf_counter() - t0
            calls[key] += 1

    setattr(obj, name, timed)


def profile_coupled(sim, until: float) -> dict:
    """Run ``sim`` (a coupled Simulation) to ``until`` timing its parts; returns seconds per part, the
    rest ("other"), the total and the gas steps taken."""
    from collections import defaultdict

    acc, calls = defaultdict(float), defaultdict(int)
    owners = {"engine": sim.engine, "gas": sim.gas, "solver": sim.gas.solver}
    for key, owner, name in COUPLED_COMPONENTS:
        _wrap(owners[owner], name, key, acc, calls)
    steps0 = sim.gas.gas_steps
    t0 = time.perf_counter()
    sim.run(until=until)
    total = time.perf_counter() - t0
    row = {k: acc[k] for k, _, _ in COUPLED_COMPONENTS}
    row["other"] = total - sum(row.values())
    row["total"] = total
    row["gas_steps"] = sim.gas.gas_steps - steps0
    row["calls"] = dict(calls)
    return row


def time_coupled(case_name: str = "tsuji-jet-background", until: float = 0.25, warmup: float = 0.01,
                 threads: int | None = None) -> dict:
    """Coupled throughput of a built-in case from its start (see the module docstring)."""
    from .case import load_case
    from .simulation import Simulation

    case = load_case(case_name)
    if threads is not None:
        case = case.with_overrides({"threads": threads})
    sim = Simulation(case)
    sim.run(until=warmup)  # compiles (or loads the caches)
    t_start, rebuilds0 = sim.time, sim.engine.rebuilds
    parts = profile_coupled(sim, t_start + until)
    n = sim.state.n
    dem_steps = parts["gas_steps"] * sim.gas.substeps
    per_step = parts["total"] / max(parts["gas_steps"], 1)
    rebuilds = sim.engine.rebuilds - rebuilds0
    return {"problem": f"coupled {case_name}", "n_particles": n, "threads": sim.threads,
            "sim_seconds": sim.time - t_start, "wall_s": parts["total"], "gas_steps": parts["gas_steps"],
            "substeps": sim.gas.substeps, "particle_steps_per_s": n * dem_steps / parts["total"],
            "ms_per_gas_step": 1e3 * per_step,
            "ms_per_gas_step_parts": {k: 1e3 * parts[k] / max(parts["gas_steps"], 1)
                                      for k in [c[0] for c in COUPLED_COMPONENTS] + ["other"]},
            "minutes_for_20_s": per_step * round(20.0 / sim.gas.gas_dt) / 60.0,
            "neighbour_rebuilds": rebuilds,
            "dem_neighbours_ms_per_gas_step": 1e3 * rebuilds * time_rebuild(sim.engine) / max(parts["gas_steps"], 1)}


def time_hopper(case_name: str = "hopper-3d", warmup: float = 0.25, until: float = 0.05,
                threads: int | None = None) -> dict:
    """Particle-steps per second of a discharging hopper over ``until`` simulated seconds after ``warmup``
    (see the module docstring); the count of each step is that of the particles present then."""
    from .analysis.probes import contacts
    from .case import load_case
    from .simulation import Simulation

    case = load_case(case_name)
    if threads is not None:
        case = case.with_overrides({"threads": threads})
    sim = Simulation(case)
    sim.run(until=warmup)  # compiles (or loads the caches) and sets the flow going; not timed
    steps0, psteps0, n0 = sim.steps, sim.particle_steps, sim.state.n
    t0 = time.perf_counter()
    sim.run(until=warmup + until)
    wall = time.perf_counter() - t0
    steps, psteps = sim.steps - steps0, sim.particle_steps - psteps0
    return {"problem": f"hopper {case_name}", "n_particles": int(round(psteps / max(steps, 1))), "threads": sim.threads,
            "steps": steps, "wall_s": wall, "particle_steps_per_s": psteps / wall,
            "contacts_per_particle": contacts(sim.engine)["coordination"], "n_at_start": n0, "n_at_end": sim.state.n,
            "dt_s": sim.dt}


def time_rebuild(eng, repeat: int = 5) -> float:
    """Seconds one Verlet-list rebuild (build and history carry-over) of a soft-sphere engine takes at its
    current positions (least of ``repeat``); the engine is left as it was. The DEM sub-steps of a gas step run
    in one compiled call, so the list's share of them is estimated as rebuilds × this."""
    from .particles import _softsphere_kernels as K

    st, best = eng.state, math.inf
    for _ in range(repeat):
        ref = eng.ref_pos.copy()
        t0 = time.perf_counter()
        K.rebuild(st.position, st.radius, eng.skin, eng.dim2, eng.row_start, eng.partner, eng.hist, ref)
        best = min(best, time.perf_counter() - t0)
    return best


def time_hard_sphere(case_name: str = "hoomans-orifice", warmup: float = 0.5, until: float = 0.1) -> dict:
    """Collisions per second of a coupled hard-sphere case over ``until`` simulated seconds after ``warmup``."""
    from .case import load_case
    from .simulation import Simulation

    sim = Simulation(load_case(case_name))
    sim.run(until=warmup)  # compiles (or loads the caches); the start-up is not timed
    eng = sim.engine
    t_start, c0, s0 = sim.time, eng.collisions, eng.steps
    parts = profile_coupled(sim, t_start + until)
    coll, steps = eng.collisions - c0, max(eng.steps - s0, 1)
    return {"problem": f"hard spheres {case_name}", "n_particles": sim.state.n, "threads": 1,
            "sim_seconds": sim.time - t_start, "wall_s": parts["total"], "steps": eng.steps - s0,
            "collisions": coll, "collisions_per_step": coll / steps,
            "collisions_per_s": coll / parts["total"], "engine_collisions_per_s": coll / parts["DEM"],
            "ms_per_step": 1e3 * parts["total"] / steps, "engine_ms_per_step": 1e3 * parts["DEM"] / steps}


def gas_step_benchmark(grids=((15, 25), (39, 60), (150, 300)), seconds: float = 2.0, convection: str = "upwind",
                       moving_bed: tuple[bool, ...] = (False, True), verbose: bool = False,
                       linear_solver: str = "auto") -> list[dict]:
    """Wall time of one gas step on standard grids; rows for ``fluidem bench``.

    The problem is the Hoomans 1996 single-orifice bed of ``gas_bench_problem`` (Table 2
    geometry 0.15 m × 0.5 m, scaled to each grid), with Ergun's β recomputed from the gas
    velocity every step, as a coupled run would. ``moving_bed``: whether the bed's voidage also
    changes every step (a surface wave and a rising bubble, 0.5 m/s), which changes the pressure
    matrix as particles do. The time step is Hoomans' DT = 1e-4 s, or less where the jet would
    cross more than half the smaller cell side in a step (explicit convection):
    dt = min(1e-4, 0.5 min(dx, dy) / 45 m/s). The first 20 steps (compilation, start-up
    transient) are not timed; then ``advance`` alone is timed for about ``seconds`` per row.
    ``linear_solver``: the ``GasSolver`` option (e.g. "band" against "multigrid").

    Returns
    -------
    list of dict
        One row per grid and bed: problem, grid, cells, dt_s [s], linear_solver, steps,
        ms_per_step [ms], iterations_per_step (pressure corrections), factorisations_per_step.
    """
    rows = []
    for nx, ny in grids:
        for moving in moving_bed:
            solver, state, beta_of, voidage_at = gas_bench_problem(nx, ny, convection, linear_solver)
            t, dt = 0.0, min(1e-4, 0.5 * min(solver.grid.dx, solver.grid.dy) / 45.0)
            for _ in range(20):
                solver.advance(state, dt, t, voidage=voidage_at(t + dt) if moving else None, beta=beta_of(state),
                               solids_u=0.0, solids_v=0.0)
                t += dt
            n, its, fac0, elapsed, wall0 = 0, 0, solver.factorisations, 0.0, time.perf_counter()
            while (time.perf_counter() - wall0 < seconds or n < 3) and n < 100000:
                beta = beta_of(state)  # the coupling's work, not timed
                eps = voidage_at(t + dt) if moving else None
                t0 = time.perf_counter()
                info = solver.advance(state, dt, t, voidage=eps, beta=beta, solids_u=0.0, solids_v=0.0)
                elapsed += time.perf_counter() - t0
                t += dt
                n += 1
                its += info.iterations
            row = {"problem": f"gas step, jet bed, {'moving' if moving else 'fixed'} voidage ({convection})",
                   "grid": f"{nx}x{ny}", "cells": nx * ny, "dt_s": dt, "linear_solver": solver.linear_solver,
                   "steps": n, "ms_per_step": 1e3 * elapsed / n,
                   "iterations_per_step": its / n, "factorisations_per_step": (solver.factorisations - fac0) / n}
            rows.append(row)
            if verbose:
                print(f"{row['grid']:>8} {'moving' if moving else 'fixed ':6} dt {dt:.2g} s {row['linear_solver']:>7}"
                      f"  {row['ms_per_step']:9.3f} ms/step  {row['iterations_per_step']:.2f} it/step  "
                      f"{row['factorisations_per_step']:.3f} LU/step", flush=True)
    return rows


def gas_bench_problem(nx: int, ny: int, convection: str = "upwind", linear_solver: str = "auto"):
    """The gas benchmark bed on an nx × ny grid: ``(solver, state, beta_of, voidage_at)``.

    Hoomans 1996 single-orifice bed (Table 2 geometry, 0.15 m × 0.5 m, depth 4 mm): ideal gas,
    a 1 cm jet of 45 m/s interstitial in the middle of the bottom (0.07–0.08 m) and 4.5 m/s elsewhere through influx
    cells of voidage 0.4, no-slip side walls, a pressure outlet at 101325 Pa on top, a bed of
    voidage 0.4 below 0.2 m. ``beta_of(state)``: Ergun's β [kg/(m³ s)] (Hoomans 1996 eq. 45,
    d_p = 4 mm) from the gas's cell-centred speed where the voidage is below 0.8, else 0.
    ``voidage_at(t)``: a moving bed at time t [s] (a surface wave and a bubble rising at 0.5 m/s).
    """
    from .gas import GasProperties, GasSolver, GasState, Inflow, PressureOutlet, Segment, StaggeredGrid, Wall

    grid = StaggeredGrid(cells=(nx, ny), size=(0.15, 0.5), depth=0.004)
    props = GasProperties()
    bcs = {"left": Wall(), "right": Wall(), "top": PressureOutlet(pressure=101325.0),
           "bottom": Inflow(segments=(Segment(interstitial=4.5), Segment(interstitial=45.0, start=0.07, end=0.08)),
                            voidage=0.4)}
    solver = GasSolver(grid, props, bcs, convection=convection, linear_solver=linear_solver)
    X, Y = grid.centres()
    state = solver.initial_state(voidage=np.where(Y < 0.2, 0.4, 1.0))
    d_p = 4e-3
    mu = props.viscosity

    def beta_of(st: GasState) -> np.ndarray:
        uc = 0.5 * (st.u[1:] + st.u[:-1])
        vc = 0.5 * (st.v[:, 1:] + st.v[:, :-1])
        slip = np.hypot(uc, vc)
        e = st.voidage
        # Hoomans 1996 eq. 45 (Ergun) in the bed; no particles above it
        b = 150.0 * (1 - e) ** 2 / e * mu / d_p**2 + 1.75 * (1 - e) * st.rho / d_p * slip
        return np.where(e < 0.8, b, 0.0)

    def voidage_at(t: float) -> np.ndarray:
        surface = 0.2 + 0.01 * np.sin(2 * np.pi * (X / 0.15 - t / 0.2))
        bed = 0.4 + 0.6 / (1.0 + np.exp(-(Y - surface) / 0.01))
        r = np.hypot(X - 0.075, Y - (0.05 + 0.5 * t) % 0.15)
        return np.clip(bed + 0.4 / (1.0 + np.exp((r - 0.02) / 0.005)), 0.4, 1.0)

    return solver, state, beta_of, voidage_at


GPU_SIZES = "100000,1000000,10000000"  # the dense-bed sizes of ``fluidem bench --device gpu``


def gpu_name() -> str:
    """The name of the GPU numba.cuda uses ("CUDA simulator" under NUMBA_ENABLE_CUDASIM)."""
    from numba import cuda

    try:
        name = cuda.get_current_device().name
        return name.decode() if isinstance(name, bytes) else str(name)
    except Exception:  # noqa: BLE001 - the simulator's device has no name
        return "CUDA simulator" if cuda.is_available() else "none"


def run_gpu_bench(sizes=GPU_SIZES, steps: int = 0, as_json: str | None = None) -> list[dict]:
    """The dense-bed rows on the GPU engine (``fluidem bench --device gpu``): particle-steps per second of
    the settled Hertz–Mindlin bed of each size, the set-up (bed, renumbering, upload, first list) timed
    apart. A size that fails (no GPU memory left, say) gets a row with its error and the next one runs."""
    import gc

    from .analysis.probes import contacts
    from .particles.softsphere_gpu import cuda_available

    if not cuda_available():
        from .errors import CaseError

        raise CaseError("bench --device gpu: no CUDA GPU is available (numba.cuda.is_available() is False)")
    device = gpu_name()
    rows = []
    print(f"{'problem':26s} {'N':>9s} {'device':>22s} {'steps':>7s} {'wall s':>8s} {'particle-steps/s':>17s} "
          f"{'contacts/particle':>18s} {'set-up s':>9s}", flush=True)
    for n in [int(float(s)) for s in str(sizes).split(",") if s]:
        row = {"problem": "dense bed 3D hertz (GPU)", "n_particles": n, "device": device}
        try:
            t0 = time.perf_counter()
            eng = load_bed_engine(n, device="gpu")
            row["setup_s"] = time.perf_counter() - t0
            nsteps, wall = time_engine(eng, steps)
            row.update(steps=nsteps, wall_s=wall, particle_steps_per_s=n * nsteps / wall,
                       contacts_per_particle=contacts(eng)["coordination"], rebuilds=eng.rebuilds,
                       partners_per_row=eng._row_length)
            print(f"{row['problem']:26s} {n:9d} {device[:22]:>22s} {nsteps:7d} {wall:8.2f} "
                  f"{row['particle_steps_per_s']:17.3e} {row['contacts_per_particle']:18.2f} {row['setup_s']:9.1f}",
                  flush=True)
        except Exception as err:  # noqa: BLE001 - one size's failure is a row of the table
            row["error"] = f"{type(err).__name__}: {err}"
            print(f"{row['problem']:26s} {n:9d} {device[:22]:>22s} failed: {row['error']}", flush=True)
        rows.append(row)
        eng = None
        gc.collect()
    if as_json:
        Path(as_json).write_text(json.dumps(rows, indent=2) + "\n")
    return rows


def run_bench(sizes=None, threads="1,2", steps: int = 0, as_json: str | None = None,
              gas: bool = True, gas_linear_solver: str = "auto", coupled: bool = True,
              coupled_until: float = 0.25, hard_sphere: bool = True, hard_warmup: float = 0.5,
              hard_until: float = 0.1, device: str = "cpu", hopper: bool = True, hopper_warmup: float = 0.25,
              hopper_until: float = 0.05) -> list[dict]:
    """Every problem of the module docstring on the CPU; ``device = "gpu"``: the dense-bed rows on the GPU
    only (``run_gpu_bench``; sizes default ``GPU_SIZES``)."""
    if device == "gpu":
        return run_gpu_bench(sizes or GPU_SIZES, steps, as_json)
    import numba

    from .analysis.probes import contacts
    from .case import load_case
    from .particles.softsphere import SoftSphereEngine

    sizes = [int(s) for s in str(sizes or "10000,100000").split(",") if s]
    threads = [int(t) for t in str(threads).split(",") if t]
    rows = []
    for n in sizes:
        for t in threads:
            numba.set_num_threads(min(t, numba.config.NUMBA_NUM_THREADS))
            eng = load_bed_engine(n)
            nsteps, wall = time_engine(eng, steps)
            c = contacts(eng)
            rows.append({"problem": "dense bed 3D hertz", "n_particles": n, "threads": t, "steps": nsteps,
                         "wall_s": wall, "particle_steps_per_s": n * nsteps / wall,
                         "contacts_per_particle": c["coordination"]})
            _print_row(rows[-1], header=len(rows) == 1)
    for t in threads:
        numba.set_num_threads(min(t, numba.config.NUMBA_NUM_THREADS))
        eng = SoftSphereEngine(load_case("pour"))
        nsteps, wall = time_engine(eng, steps, 3.0)
        rows.append({"problem": "pour 2D linear", "n_particles": eng.state.n, "threads": t, "steps": nsteps,
                     "wall_s": wall, "particle_steps_per_s": eng.state.n * nsteps / wall,
                     "contacts_per_particle": contacts(eng)["coordination"]})
        _print_row(rows[-1], header=not rows[:-1])
    if hopper:
        for t in threads:
            rows.append(time_hopper("hopper-3d", warmup=hopper_warmup, until=hopper_until, threads=t))
            _print_row(rows[-1], header=False)
    if coupled:
        print(f"\n{'coupled (gas included)':28s} {'N':>6s} {'threads':>7s} {'sim s':>6s} {'wall s':>7s} "
              f"{'particle-steps/s':>17s} {'ms/gas step':>11s} {'20 s takes':>10s}")
        for name, t in [(n, t) for n in ("tsuji-jet-background", "bubbling-3d") for t in threads]:
            r = time_coupled(name, until=coupled_until if name != "bubbling-3d" else min(coupled_until, COUPLED_3D_UNTIL),
                             threads=t)
            rows.append(r)
            print(f"{r['problem']:28s} {r['n_particles']:6d} {r['threads']:7d} {r['sim_seconds']:6.2f} "
                  f"{r['wall_s']:7.2f} {r['particle_steps_per_s']:17.3e} {r['ms_per_gas_step']:11.3f} "
                  f"{r['minutes_for_20_s']:8.1f} min", flush=True)
            print("    ms per gas step: " + ", ".join(f"{k} {v:.3f}" for k, v in r["ms_per_gas_step_parts"].items()
                                                     if k != "beta" or v > 0)
                  + f"; of the DEM, neighbour lists about {r['dem_neighbours_ms_per_gas_step']:.3f} "
                  f"({r['neighbour_rebuilds']} rebuilds), contacts and integration the rest", flush=True)
            if name == "bubbling-3d":
                parts = r["ms_per_gas_step_parts"]
                gas_side = sum(v for k, v in parts.items() if k not in ("DEM", "other"))
                print(f"    gas side (map, gas solve, deposit, forces) {100.0 * gas_side / r['ms_per_gas_step']:.1f} % "
                      "of the gas step (target: at most 30 % on 2 cores)", flush=True)
    if hard_sphere:
        r = time_hard_sphere("hoomans-orifice", warmup=hard_warmup, until=hard_until)
        rows.append(r)
        print(f"\n{'hard spheres (gas included)':28s} {'N':>6s} {'sim s':>6s} {'wall s':>7s} {'coll/step':>9s} "
              f"{'collisions/s':>13s} {'engine coll/s':>13s} {'ms/step':>8s} {'engine ms':>9s}")
        print(f"{r['problem']:28s} {r['n_particles']:6d} {r['sim_seconds']:6.2f} {r['wall_s']:7.2f} "
              f"{r['collisions_per_step']:9.0f} {r['collisions_per_s']:13.3e} {r['engine_collisions_per_s']:13.3e} "
              f"{r['ms_per_step']:8.3f} {r['engine_ms_per_step']:9.3f}", flush=True)
    if gas:
        print(f"\n{'gas step':42s} {'grid':>8s} {'dt s':>8s} {'solver':>9s} {'ms/step':>8s} {'iterations':>10s}")
        for r in gas_step_benchmark(linear_solver=gas_linear_solver):
            rows.append(r)
            print(f"{r['problem']:42s} {r['grid']:>8s} {r['dt_s']:8.1e} {r['linear_solver']:>9s} "
                  f"{r['ms_per_step']:8.3f} {r['iterations_per_step']:10.2f}", flush=True)
    if as_json:
        Path(as_json).write_text(json.dumps(rows, indent=2) + "\n")
    return rows


def _print_row(r: dict, header: bool) -> None:
    if header:
        print(f"{'problem':22s} {'N':>8s} {'threads':>7s} {'steps':>7s} {'wall s':>8s} {'particle-steps/s':>17s} {'contacts/particle':>18s}")
    print(f"{r['problem']:22s} {r['n_particles']:8d} {r['threads']:7d} {r['steps']:7d} {r['wall_s']:8.2f} "
          f"{r['particle_steps_per_s']:17.3e} {r['contacts_per_particle']:18.2f}", flush=True)
