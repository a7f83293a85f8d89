"""Energy error of the hoomans-pour case (Hoomans 1996 §5.1, eq. 51) against DT for both force steps.

    python benchmarks/hardsphere_energy_error.py                       # the tables of docs/gallery.md, ~2 min
    python benchmarks/hardsphere_energy_error.py --count 100 --until 0.6 --times 0.1,0.3,0.4,0.5,0.6
    python benchmarks/hardsphere_energy_error.py --count 50 --until 0.05 --times 0.05 --dts 1e-4   # seconds

Runs the built-in ``hoomans-pour`` case (500 spheres of 4 mm, e = 0.9, μ = 0.3, no collapse remedy) with
``particles.force_step`` "hoomans" and "split" and each DT of ``--dts``, and prints the signed relative
error (E_kin + E_pot + E_rot + E_dsp − E_0) / E_0 at each of ``--times`` (potential energy relative to the
floor, as summary.json's ``energy_error_rel``, which is its magnitude at the end of the run), and beside it

* the free-fall offset of Hoomans' step, ½ Σ m g·DT (v − v_0) / E_0, which the split step does not have;
* the work of the floor ½ M g² DT (t − t_rest) / E_0 on a bed at rest since t_rest (each floor collision
  changes the energy by (1 + e) m g y_mid, y_mid the gap at mid-step on the straight path; in a bed at rest
  the bottom spheres meet the floor at the start of each step, y_mid = v' DT/2, and the floor's impulses add
  up to the bed's weight M g DT per step). ``--count`` fewer spheres (a shallower bed that rests sooner) and
  ``--until`` longer show that term.

Times nothing: it measures an error, not speed.
"""
from __future__ import annotations

import argparse

import numpy as np

from fluidem.case import load_case
from fluidem.particles.hardsphere import HardSphereEngine


def run(force_step: str, dt: float, count: int, times: list[float]) -> list[dict]:
    """Signed relative energy error and its parts at each of ``times`` [s]."""
    over = {"particles.force_step": force_step, "time.dt": dt}
    if count:
        over["particles.species.0.count"] = count
    eng = HardSphereEngine(load_case("hoomans-pour", over))
    eng.check_initial_overlaps()
    st = eng.state
    e0 = eng.energies()["total_J"]
    v0 = st.velocity.copy()
    rows = []
    for t in times:
        eng.advance(round(t / dt) - eng.steps)
        e = eng.energies()
        offset = 0.5 * dt * float(np.sum(st.mass[:, None] * (st.velocity - v0) * eng.gravity)) * -1.0
        rows.append({"t": eng.time, "error": (e["total_J"] - e0) / e0,
                     "offset": offset / e0 if force_step == "hoomans" else 0.0,
                     "kinetic": e["kinetic_J"] / e0, "collisions": eng.collisions})
    return rows


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dts", default="1e-4,5e-5,2.5e-5", help="force steps DT [s], comma-separated")
    ap.add_argument("--count", type=int, default=0, help="spheres (default: the case's 500)")
    ap.add_argument("--until", type=float, default=0.12, help="[s] simulated")
    ap.add_argument("--times", default="0.05,0.12", help="[s] where the error is printed")
    a = ap.parse_args(argv)
    times = [float(x) for x in a.times.split(",") if float(x) <= a.until + 1e-12]
    print(f"{'force_step':10s} {'DT [s]':>8s} {'t [s]':>6s} {'error':>10s} {'offset':>10s} {'error-offset':>12s} "
          f"{'E_kin/E_0':>9s} {'collisions':>11s}")
    for dt in (float(x) for x in a.dts.split(",")):
        for step in ("hoomans", "split"):
            for r in run(step, dt, a.count, times):
                print(f"{step:10s} {dt:8.2g} {r['t']:6.3f} {r['error']:10.3e} {r['offset']:10.3e} "
                      f"{r['error'] - r['offset']:12.3e} {r['kinetic']:9.2e} {r['collisions']:11d}")


if __name__ == "__main__":
    main()
