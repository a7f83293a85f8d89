"""Collisions per second of the hard-sphere engine on one core: 2400 spheres poured into a 2D box.

The bed of Hoomans et al. 1996 Table 2 without gas: 2400 aluminium spheres of 4 mm in a
box 0.15 m wide and 0.5 m high, e = e_w = 0.9, μ = μ_w = 0.3, DT = 1e-4 s, gravity −9.81
m/s², TC collapse remedy t_c = 1e-5 s (the default). The particles start at random, at
rest, and fall into a dense bed. The figure reported is collisions per CPU second over
the measuring window. The window starts once the bed has begun to form (after
``--warmup`` seconds of simulated time) and ends at ``--until`` or after ``--budget`` CPU
seconds. Compile time is excluded.

    NUMBA_NUM_THREADS=1 python benchmarks/hardsphere_collisions.py [--until 0.45] [--budget 60]

Measured on the shared 2-vCPU development machine (Intel Xeon VM, other jobs running),
from t = 0.25 to 0.45 s: 5.6e7 collisions in 23 CPU s, i.e. 2.4e6 collisions/s (the
former engine, a binary heap with branchy predictions: 52–58 CPU s, 1.0–1.1e6/s, in the
same session; both give the same collisions, bit for bit). Single chunks vary by ±20 %
with the machine's load. The settled bed takes 30–45 thousand collisions per step,
1.19 events per collision (stale predictions and list rebuilds included).
With ``--collapse-time 0`` the settling bed reaches 1.7 million collisions per step at
t = 0.17 s, and the event limit stops it at t = 0.18 s (see contact/hard_sphere.py).

``--coupled`` times the engine inside the built-in ``hoomans-orifice`` case instead (the
same bed with gas, one engine call per gas step; defaults --warmup 0.5 --until 0.7, the
first 0.2 s of the jet). There the gas keeps the bed fluidised: only about 700 (jet) to
1900 (start-up at u_mf) collisions per step, so the per-step work (every particle's
prediction after the force kick, list rebuilds, the call) dominates: 0.7 ms per step,
1.0e6 collisions per engine CPU second, against 1.8 ms and 0.4e6/s for the former engine.

The engine is serial, so NUMBA_NUM_THREADS only keeps stray parallel kernels (placement)
on one core. CPU time rather than wall time is measured because the machine is shared.
"""
from __future__ import annotations

import argparse
import os
import time

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

from fluidem.case import load_case, validate_case
from fluidem.particles.hardsphere import HardSphereEngine


def bed_case(n=2400, width=0.15, height=0.5, e=0.9, mu=0.3, collapse_time=1e-5, dt=1e-4, seed=1996):
    return validate_case({
        "name": "hs-bench", "gravity": [0.0, -9.81, 0.0],
        "particles": {
            "dimensions": 2,
            "species": [{"name": "aluminium", "diameter": 4e-3, "density": 2700.0, "count": n}],
            "contact": {"model": "hard_sphere", "restitution": e, "friction": mu, "collapse_time": collapse_time},
            "placement": {"method": "random", "seed": seed},
        },
        "walls": [{"name": "box", "kind": "box", "lower": [0.0, 0.0, 0.0], "upper": [width, height, 4e-3]}],
        "time": {"end": 1.0, "dt": dt},
    })


def coupled(until, warmup):
    """Engine CPU time per step and collisions per engine CPU second inside the hoomans-orifice case."""
    import tempfile

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
        t0 = time.process_time()
        sim.run()
        total = time.process_time() - t0
    n, cpu = max(acc["steps"], 1), acc["cpu"]
    rate = acc["collisions"] / cpu if cpu > 0 else float("nan")
    print(f"hoomans-orifice from t = {warmup:g} to {eng.time:.3f} s: {acc['steps']} steps, "
          f"{acc['collisions'] / n:.0f} collisions/step, {acc['rebuilds'] / n:.3f} list rebuilds/step; engine "
          f"{1e3 * cpu / n:.3f} ms CPU/step = {rate:.3g} collisions/s (one core); whole run {total:.1f} s CPU "
          f"(gas, coupling and compilation included)")
    return rate


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--until", type=float, default=None, help="simulated time to stop at [s] (0.45; coupled 0.7)")
    ap.add_argument("--warmup", type=float, default=None, help="simulated time before measuring [s] (0.25; "
                                                                  "coupled 0.5)")
    ap.add_argument("--budget", type=float, default=60.0, help="CPU seconds of measuring at most")
    ap.add_argument("--restitution", type=float, default=0.9)
    ap.add_argument("--friction", type=float, default=0.3)
    ap.add_argument("--collapse-time", type=float, default=1e-5, help="TC remedy t_c [s] (0: off)")
    ap.add_argument("--chunk", type=int, default=10, help="steps per compiled call")
    ap.add_argument("--coupled", action="store_true", help="time the engine inside the hoomans-orifice case")
    args = ap.parse_args(argv)
    if args.coupled:
        return coupled(0.7 if args.until is None else args.until, 0.5 if args.warmup is None else args.warmup)
    args.until = 0.45 if args.until is None else args.until
    args.warmup = 0.25 if args.warmup is None else args.warmup

    eng = HardSphereEngine(bed_case(e=args.restitution, mu=args.friction, collapse_time=args.collapse_time))
    eng.check_initial_overlaps()
    t0 = time.process_time()
    eng.advance(1)  # compile (or load the cache)
    print(f"particles {eng.state.n}, DT {eng.dt:g} s, skin {eng.skin:.3g} m; first step (compile) "
          f"{time.process_time() - t0:.1f} s CPU")
    print(f"{'t [s]':>7} {'collisions':>12} {'coll/step':>10} {'events/coll':>11} {'rebuilds':>8} "
          f"{'coll/s (CPU)':>13}")
    warm_steps = round(args.warmup / eng.dt)
    end_steps = round(args.until / eng.dt)
    measured_c = 0
    measured_cpu = 0.0
    calls = 0
    while eng.steps < end_steps:
        c0, ev0 = eng.collisions, eng.events
        p0 = time.process_time()
        eng.advance(min(args.chunk, end_steps - eng.steps))
        cpu = time.process_time() - p0
        dc = eng.collisions - c0
        if eng.steps > warm_steps:
            measured_c += dc
            measured_cpu += cpu
        calls += 1
        if calls % 10 == 0 or eng.steps >= end_steps:
            print(f"{eng.time:7.3f} {eng.collisions:12d} {dc / args.chunk:10.0f} {(eng.events - ev0) / max(dc, 1):11.3f} "
                  f"{eng.rebuilds:8d} {dc / cpu if cpu > 0 else 0:13.3g}", flush=True)
        if measured_cpu > args.budget:
            break
    rate = measured_c / measured_cpu if measured_cpu > 0 else float("nan")
    e = eng.energies()
    print(f"\nmeasured from t = {args.warmup:g} s to t = {eng.time:.3f} s: {measured_c} collisions in "
          f"{measured_cpu:.1f} CPU s = {rate:.3g} collisions/s (one core)")
    print(f"kinetic energy {e['kinetic_J']:.3g} J, dissipated {e['dissipated_J']:.3g} J, "
          f"wall collisions {eng.wall_collisions}, sticking {eng.sticking_collisions}, remedy {eng.remedy_count}")
    return rate


if __name__ == "__main__":
    main()
