"""Where the wall time of a coupled gas step goes: DEM, gas solve, map, cell β, deposit, forces.

    fluidem run tsuji-jet-background --out runs/tj20                    # a developed bed (20 s) to start from
    NUMBA_NUM_THREADS=2 python benchmarks/coupled_profile.py --from runs/tj20/restart.h5 --until 0.2 --repeat 3
    python benchmarks/coupled_profile.py --case hoomans-orifice --until 0.01 --repeat 1 [--set key=value ...]

Each round builds ``Simulation(load_case(case))`` (no run directory, no observers), loads the
checkpoint of ``--from`` if given (a developed, bubbling bed instead of the settling start; ``--until``
then counts from its time), and times ``Simulation.run`` for ``--until`` simulated seconds; a short
untimed run first compiles the kernels or loads their caches. Each component is timed with
``time.perf_counter`` by wrapping the bound methods of that one simulation's objects
(``fluidem.bench.profile_coupled``, which ``fluidem bench`` uses too; nothing global is patched):

    DEM             engine.advance
    gas solve       gas.solver.advance
    map             gas._map            (particles → voidage, solids velocity)
    beta            gas.cell_beta       (Sun 2007 eq. 33; "cell" and "cell_beta" exchanges)
    deposit         gas._deposit        (K_p and face sums of the "particle" exchange)
    forces          gas.set_particle_forces (Hoomans 1996 eqs 40-41 interpolation, drag, −V_p ∇p,
                    and the swap into the engine's external and total forces)
    other           the rest of run(): the step loop, chunking, checks

Printed: milliseconds per gas step of each component, min, median and max over the rounds, the gas
side's share of the gas step (map, beta, gas solve, deposit and forces over the total, per round), and
the gas solver's factorisations and Newton corrections per gas step. On a shared machine read the
minimum; the shares, both parts timed in the same round, drift less than the times.
"""
from __future__ import annotations

import argparse
import json
from pathlib import Path

import fluidem as fd
from fluidem.bench import COUPLED_COMPONENTS, profile_coupled

import harness  # benchmarks/harness.py: this script's folder is first on sys.path

KEYS = [k for k, _, _ in COUPLED_COMPONENTS] + ["other", "total"]


def parse_sets(items) -> dict:
    """``key=value`` overrides as ``fluidem run --set`` takes them (values read as JSON where they parse)."""
    out = {}
    for s in items or []:
        k, _, v = s.partition("=")
        try:
            out[k] = json.loads(v)
        except json.JSONDecodeError:
            out[k] = v
    return out


def profile(case, until: float, start: Path | None = None) -> dict:
    """One timed run: milliseconds per gas step of each component (``value``: the whole step)."""
    sim = fd.Simulation(case)
    if start is not None:
        sim.load_checkpoint(start)
    solver = sim.gas.solver
    f0, steps0 = solver.factorisations, sim.gas.gas_steps
    corrections = []
    advance = solver.advance

    def counted(*args, **kw):
        info = advance(*args, **kw)
        corrections.append(info.iterations)
        return info

    solver.advance = counted
    row = profile_coupled(sim, sim.time + until)
    steps = max(sim.gas.gas_steps - steps0, 1)
    out = {k: 1e3 * row[k] / steps for k in KEYS}
    gas_side = sum(out[k] for k in KEYS if k not in ("DEM", "other", "total"))
    out["gas_side_share"] = 100.0 * gas_side / out["total"] if out["total"] > 0.0 else 0.0
    out.update(value=out["total"], gas_steps=row["gas_steps"],
               factorisations_per_step=(solver.factorisations - f0) / steps,
               corrections_per_step=sum(corrections) / steps, calls=row["calls"])
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--case", default="tsuji-jet-background", help="built-in case name or case file")
    ap.add_argument("--until", type=float, default=0.2, help="simulated seconds timed in each round [s]")
    ap.add_argument("--set", action="append", metavar="KEY=VALUE", help="case override (as `fluidem run --set`)")
    ap.add_argument("--from", dest="start", type=Path, help="checkpoint (restart.h5) of the same case to start from")
    harness.add_options(ap, repeat=3)
    a = ap.parse_args(argv)
    case = fd.load_case(a.case)
    sets = parse_sets(a.set)
    if sets:
        case = case.with_overrides(sets)
    fd.Simulation(case).run(until=min(a.until, 20 * case.gas.dt))  # compile / load the caches
    rounds = harness.run_rounds({"profile": lambda: profile(case, a.until, a.start)}, a.repeat, unit="ms")
    first = rounds.extras["profile"][0]
    print(f"case {a.case}, {a.until:g} s from {a.start or 'the start'}, {first['gas_steps']} gas steps a round, "
          f"{a.repeat} rounds, overrides {sets or 'none'}; fluidem {fd.__file__}")
    rows = []
    for k in KEYS:
        s = rounds.stats("profile", k)
        rows.append([k, s["min"], s["median"], s["max"]])
    print(harness.format_table(["ms per gas step", "min", "median", "max"], rows))
    share = rounds.stats("profile", "gas_side_share")
    print(f"gas side (map, beta, gas solve, deposit, forces): {share['min']:.1f} / {share['median']:.1f} / "
          f"{share['max']:.1f} % of the gas step (min / median / max)")
    print("calls: " + ", ".join(f"{k} {v}" for k, v in first["calls"].items()))
    print(f"gas solver: {rounds.stats('profile', 'factorisations_per_step')['median']:.3f} factorisations and "
          f"{rounds.stats('profile', 'corrections_per_step')['median']:.2f} Newton corrections per gas step (median)")
    harness.write_json(a.json, {"profile": rounds}, case=a.case, until_s=a.until, overrides=sets,
                       start=str(a.start) if a.start else None)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
