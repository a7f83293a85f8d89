"""Collisions per CPU second of the hard-sphere engine on one core: 2400 spheres settling, or inside hoomans-orifice.

    NUMBA_NUM_THREADS=1 python benchmarks/hardsphere_collisions.py [--until 0.45] [--budget 20] [--repeat 3]
    NUMBA_NUM_THREADS=1 python benchmarks/hardsphere_collisions.py --coupled [--warmup 0.5] [--until 0.7]
    python benchmarks/hardsphere_collisions.py --warmup 0.01 --until 0.02 --repeat 1          # a quick check

Settling (the default): the bed of Hoomans et al. 1996 Table 2 without gas: 2400 aluminium spheres of
4 mm in a 2D box 0.15 m wide and 0.5 m high, e = e_w = 0.9, μ = μ_w = 0.3, DT = 1e-4 s, gravity −9.81
m/s², TC collapse remedy t_c = 1e-5 s (the default; ``--collapse-time 0`` turns it off). The particles
start at random, at rest, and fall into a dense bed. Measured: collisions per CPU second over a
window that starts once the bed has begun to form (after ``--warmup`` seconds of simulated time,
default 0.25 s) and ends at ``--until`` (0.45 s) or after ``--budget`` CPU seconds.

``--coupled``: the engine inside the built-in ``hoomans-orifice`` case (the same bed with gas and
Hoomans' own coupling, one engine call per gas step; default window 0.5–0.7 s, the first 0.2 s of the
jet): collisions per CPU second of the engine calls alone, and the engine's CPU milliseconds per step.

Each round is one fresh run (``--repeat`` rounds); compilation is excluded. The engine is serial, so
NUMBA_NUM_THREADS only keeps stray parallel kernels (placement) on one core. CPU time rather than wall
time is measured because the machine is shared.
"""
from __future__ import annotations

import argparse
import os
import tempfile
import time

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

from fluidem.case import load_case, validate_case  # noqa: E402
from fluidem.particles.hardsphere import HardSphereEngine  # noqa: E402

import harness  # noqa: E402  benchmarks/harness.py: this script's folder is first on sys.path


def bed_case(n=2400, width=0.15, height=0.5, e=0.9, mu=0.3, collapse_time=1e-5, dt=1e-4, seed=1996):
    """The settling bed: n spheres of 4 mm at random in a width × height 2D box [m]."""
    return validate_case({
        "name": "hs-bench", "gravity": [0.0, -9.81, 0.0],
        "particles": {
            "dimensions": 2,
            "force_step": "hoomans",  # the step these figures were measured with (the same trajectories as "split")
            "species": [{"name": "aluminium", "diameter": 4e-3, "density": 2700.0, "count": n}],
            "contact": {"model": "hard_sphere", "restitution": e, "friction": mu, "collapse_time": collapse_time},
            "placement": {"method": "random", "seed": seed},
        },
        "walls": [{"name": "box", "kind": "box", "lower": [0.0, 0.0, 0.0], "upper": [width, height, 4e-3]}],
        "time": {"end": 1.0, "dt": dt},
    })


def settling(until: float, warmup: float, budget: float, chunk: int, restitution: float, friction: float,
             collapse_time: float) -> dict:
    """One settling run: collisions per CPU second (``value``) over the window, and its counts."""
    eng = HardSphereEngine(bed_case(e=restitution, mu=friction, collapse_time=collapse_time))
    eng.check_initial_overlaps()
    eng.advance(1)  # compile (or load the cache); before the window
    warm_steps, end_steps = round(warmup / eng.dt), round(until / eng.dt)
    collisions, events, cpu, steps = 0, 0, 0.0, 0
    while eng.steps < end_steps and cpu <= budget:
        c0, ev0, p0 = eng.collisions, eng.events, time.process_time()
        k = min(chunk, end_steps - eng.steps)
        if eng.steps < warm_steps:  # the window starts at a call's start
            k = min(k, warm_steps - eng.steps)
        eng.advance(k)
        dt_cpu = time.process_time() - p0
        if eng.steps > warm_steps:  # the call lies in the window
            collisions += eng.collisions - c0
            events += eng.events - ev0
            cpu += dt_cpu
            steps += k
    return {"value": collisions / cpu if cpu > 0 else None, "collisions": collisions, "cpu_s": cpu, "steps": steps,
            "collisions_per_step": collisions / max(steps, 1), "events_per_collision": events / max(collisions, 1),
            "end_time_s": eng.time, "rebuilds": eng.rebuilds, "remedy": eng.remedy_count}


def coupled(until: float, warmup: float) -> dict:
    """One run of hoomans-orifice to ``until``: engine collisions per CPU second (``value``) after ``warmup``."""
    from fluidem.simulation import Simulation

    case = load_case("hoomans-orifice", {"time.end": until, "output.snapshot_interval": 10.0,
                                         "output.probe_interval": 10.0, "output.checkpoint_interval": 10.0})
    with tempfile.TemporaryDirectory() as out:
        sim = Simulation(case, out_dir=out)
        eng = sim.engine
        acc = {"cpu": 0.0, "collisions": 0, "steps": 0, "rebuilds": 0}
        advance = eng.advance

        def timed(nsteps):
            c0, r0, p0 = eng.collisions, eng.rebuilds, time.process_time()
            advance(nsteps)
            if eng.time > warmup:
                acc["cpu"] += time.process_time() - p0
                acc["collisions"] += eng.collisions - c0
                acc["rebuilds"] += eng.rebuilds - r0
                acc["steps"] += nsteps

        eng.advance = timed
        sim.run()
    n, cpu = max(acc["steps"], 1), acc["cpu"]
    return {"value": acc["collisions"] / cpu if cpu > 0 else None, "collisions": acc["collisions"], "cpu_s": cpu,
            "steps": acc["steps"], "collisions_per_step": acc["collisions"] / n,
            "rebuilds_per_step": acc["rebuilds"] / n, "engine_ms_per_step": 1e3 * cpu / n, "end_time_s": eng.time}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--until", type=float, default=None, help="simulated time to stop at [s] (0.45; coupled 0.7)")
    ap.add_argument("--warmup", type=float, default=None,
                    help="simulated time before the window [s] (0.25; coupled 0.5)")
    ap.add_argument("--budget", type=float, default=60.0, help="CPU seconds of the window at most (settling)")
    ap.add_argument("--restitution", type=float, default=0.9)
    ap.add_argument("--friction", type=float, default=0.3)
    ap.add_argument("--collapse-time", type=float, default=1e-5, help="TC remedy t_c [s] (0: off)")
    ap.add_argument("--chunk", type=int, default=10, help="steps per compiled call (settling)")
    ap.add_argument("--coupled", action="store_true", help="time the engine inside the hoomans-orifice case")
    harness.add_options(ap, repeat=1)
    a = ap.parse_args(argv)
    if a.coupled:
        until, warmup = (0.7 if a.until is None else a.until), (0.5 if a.warmup is None else a.warmup)

        def measure():
            return coupled(until, warmup)
        title = f"hoomans-orifice, engine calls from t = {warmup:g} to {until:g} s"
        columns = {"collisions_per_step": "collisions per step", "rebuilds_per_step": "list rebuilds per step",
                   "engine_ms_per_step": "engine CPU ms per step"}
    else:
        until, warmup = (0.45 if a.until is None else a.until), (0.25 if a.warmup is None else a.warmup)

        def measure():
            return settling(until, warmup, a.budget, a.chunk, a.restitution, a.friction, a.collapse_time)
        title = f"2400 spheres settling, from t = {warmup:g} to at most {until:g} s ({a.budget:g} CPU s at most)"
        columns = {"collisions_per_step": "collisions per step", "events_per_collision": "events per collision",
                   "end_time_s": "window's end [s]"}

    def progress(k, got):
        r = got["collisions"]
        print(f"round {k + 1}: {r['collisions']} collisions in {r['cpu_s']:.2f} CPU s over {r['steps']} steps: "
              f"{r['value'] or 0:.3g} collisions/s", flush=True)

    rounds = harness.run_rounds({"collisions": measure}, a.repeat, unit="collisions per CPU second", progress=progress)
    print(f"\n{title}, one core, {a.repeat} round(s)")
    rows = [["collisions per CPU second", *_row(rounds, None)]] + [[label, *_row(rounds, c)]
                                                                  for c, label in columns.items()]
    print(harness.format_table(["", "rounds", "min", "median", "max"], rows))
    harness.write_json(a.json, {"collisions": rounds}, coupled=a.coupled, until_s=until, warmup_s=warmup)
    return 0


def _row(rounds, key):
    s = rounds.stats("collisions", key)
    return [s["n"], s["min"], s["median"], s["max"]]


if __name__ == "__main__":
    raise SystemExit(main())
