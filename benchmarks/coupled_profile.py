"""Where the wall time of a coupled run goes: DEM, gas solve, map, cell β, interpolation + drag.

    python benchmarks/coupled_profile.py [--case tsuji-jet] [--until 0.2] [--repeat 3]
                                         [--set coupling.drag_update=frozen ...]
                                         [--from runs/tsuji/restart.h5] [--jacobian-reuse 0.03]

``--from`` starts each timed run from a checkpoint of the same case (a developed, bubbling
bed instead of the settling start); ``--until`` then counts from the checkpoint's time.

Builds ``Simulation(load_case(case))`` (no run directory, no observers), warms the compiled
kernels up with a short run of a copy, then times ``Simulation.run(until=…)`` of a fresh one.
Each component is timed with ``time.perf_counter`` by wrapping the bound methods of that one
simulation's objects (instance attributes; nothing global is patched; ``fluidem.bench.profile_coupled``,
which ``fluidem bench`` uses too):

    DEM             engine.advance
    gas solve       gas.solver.advance
    map             gas._map            (particles → voidage, solids velocity)
    beta            gas.cell_beta       (Sun 2007 eq. 33; "cell" and "cell_beta" exchanges)
    deposit         gas._deposit        (K_p and face sums of the "particle" exchange)
    forces          gas.set_particle_forces (Hoomans 1996 eqs 40-41 interpolation, drag, −V_p ∇p,
                    and the swap into the engine's external and total forces)
    other           the rest of run(): the step loop, chunking, checks

Numbers are from a shared 2-vCPU machine: repeat (``--repeat``) and read the minimum.
"""
from __future__ import annotations

import argparse
import json
from pathlib import Path

import fluidem as fd
from fluidem.gas import _solver_kernels as K

from fluidem.bench import COUPLED_COMPONENTS as COMPONENTS
from fluidem.bench import profile_coupled


def _parse_sets(items):
    out = {}
    for s in items or []:
        k, _, v = s.partition("=")
        try:
            out[k] = json.loads(v)
        except json.JSONDecodeError:
            out[k] = v
    return out


def profile(case, until: float, start=None, jacobian_reuse=None) -> dict:
    sim = fd.Simulation(case)
    if start is not None:
        sim.load_checkpoint(start)
        until = sim.time + until
    solver = sim.gas.solver
    if jacobian_reuse is not None:  # GasSolver's argument; not a case key
        solver.jacobian_reuse = jacobian_reuse
        solver._fpar[K.F_REUSE] = jacobian_reuse
    f0, steps0 = solver.factorisations, sim.gas.gas_steps
    corrections = []
    advance = solver.advance

    def counted(*args, **kw):
        info = advance(*args, **kw)
        corrections.append(info.iterations)
        return info

    solver.advance = counted
    row = profile_coupled(sim, until)
    steps = max(sim.gas.gas_steps - steps0, 1)
    row["factorisations_per_step"] = (solver.factorisations - f0) / steps
    row["corrections_per_step"] = sum(corrections) / steps
    return row


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--case", default="tsuji-jet")
    ap.add_argument("--until", type=float, default=0.2, help="simulated seconds [s]")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--set", action="append", help="case override key=value (as `fluidem run --set`)")
    ap.add_argument("--json", help="write the rows as JSON")
    ap.add_argument("--from", dest="start", type=Path, help="checkpoint (restart.h5) of the same case to start from")
    ap.add_argument("--jacobian-reuse", type=float, default=None,
                    help="the gas solver's jacobian_reuse (default its own, 0.01): factors kept while the matrix "
                         "changes less than this")
    a = ap.parse_args()
    case = fd.load_case(a.case)
    sets = _parse_sets(a.set)
    if sets:
        case = case.with_overrides(sets)
    fd.Simulation(case).run(until=min(a.until, 20 * case.gas.dt))  # compile / load the caches
    rows = [profile(case, a.until, a.start, a.jacobian_reuse) for _ in range(a.repeat)]
    keys = [k for k, _, _ in COMPONENTS] + ["other", "total"]
    n = rows[0]["gas_steps"]
    print(f"case {a.case}, {a.until} s from {a.start or 'the start'}, {n} gas steps, overrides {sets or 'none'}; fluidem {fd.__file__}")
    print(f"{'component':12s} " + " ".join(f"{'run ' + str(r + 1):>9s}" for r in range(len(rows)))
          + f" {'min':>9s} {'ms/gas step':>12s}")
    for k in keys:
        vals = [r[k] for r in rows]
        print(f"{k:12s} " + " ".join(f"{v:9.3f}" for v in vals) + f" {min(vals):9.3f} {1e3 * min(vals) / n:12.4f}")
    print("calls: " + ", ".join(f"{k} {v}" for k, v in rows[0]["calls"].items()))
    print(f"gas solver: {rows[0]['factorisations_per_step']:.3f} factorisations and "
          f"{rows[0]['corrections_per_step']:.2f} Newton corrections per gas step")
    if a.json:
        with open(a.json, "w") as f:
            json.dump({"case": a.case, "until": a.until, "overrides": sets, "rows": rows}, f, indent=2)


if __name__ == "__main__":
    main()
