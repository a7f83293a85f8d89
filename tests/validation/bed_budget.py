"""Where a built-in coupled bed's weight goes (diagnostic; the u_mf sweep's own is ``umf_budget.py``).

Runs the case to 2 s, then samples every gas step over 2-3 s: the pressure drop over the whole column
times its cross-section (``analysis.fluidised.pressure_drop`` to the top, the gas's own weight ρ g H
included), the gas force on the particles (drag + −V_p∇p, at each sub-step's velocity), what the gas
gave up for it (``GasCoupling.exchange_balance``), each wall's push on the particles, and the rate of
change of the particles' momentum over the window, all over the particles' weight W = m g:
gas force + walls − 1 = d(Σ m v)/dt / W closes the budget.

    python tests/validation/bed_budget.py [case=NAME] [KEY=VALUE ...]   (overrides as ``fluidem run --set``)

Measured with the boundary faces folded and the pressure force paired (the defaults):

    tsuji-jet-background     Δp A / W 0.852, gas force 0.877, gas gave up 0.877; bottom 0.068, side walls 0.018;
                  d(Σ m v)/dt / W −0.038 (the bed's upward momentum fell over this window)
    goldschmidt   Δp A / W 0.996, gas force 0.993, gas gave up 0.993; bottom 0.0065, side walls 0.003;
                  d(Σ m v)/dt / W 0.002

In tsuji-jet-background the background gas is at u_mf, so part of the bed rests on the bottom; Δp A falls short of
the gas force by the jet's momentum flux, ρ u² over its cell (1.2 × 39² Pa over 1/15 of the width,
~3 % of W).
"""
import sys

import numpy as np

import fluidem as fd
from fluidem.analysis.fluidised import pressure_drop
from fluidem.analysis.probes import wall_forces
from fluidem.simulation import Simulation


def main(argv):
    over = dict(a.split("=", 1) for a in argv)
    over = {k: (v == "true" if v in ("true", "false") else v) for k, v in over.items()}
    name = over.pop("case", "tsuji-jet-background")
    sim = Simulation(fd.load_case(name).with_overrides(over))
    weight = float(sim.state.mass.sum()) * float(np.linalg.norm(sim.case.gravity))
    gd = sim.gas.grid
    area, height = gd.nx * gd.dx * gd.depth, gd.ny * gd.dy
    while sim.time < 2.0:
        sim.advance(sim.gas.substeps * 50)
    dp, force, gave, walls = [], [], [], {}
    t0, p0 = sim.time, float((sim.state.mass * sim.state.velocity[:, 1]).sum())
    while sim.time < 3.0:
        sim.advance(sim.gas.substeps)
        dp.append(pressure_drop(gd, sim.gas.state.p, height))
        force.append(float(sim.engine.external_force()[:, 1].sum()))
        b = sim.gas.exchange_balance()
        gave.append(float(b["gas"][1] - b.get("pressure_gas", [0.0, 0.0])[1]))
        for k, v in wall_forces(sim.engine).items():
            walls.setdefault(k, []).append(-float(v[1]))
    rate = (float((sim.state.mass * sim.state.velocity[:, 1]).sum()) - p0) / (sim.time - t0)
    print(f"{name} {over}: d(Σ m v)/dt / W = {rate / weight:.4f}, Δp A / W = {np.mean(dp) * area / weight:.4f}, "
          f"gas force / W = {np.mean(force) / weight:.4f}, gas gave up / W = {np.mean(gave) / weight:.4f}; walls / W: "
          + ", ".join(f"{k} {np.mean(v) / weight:.4f}" for k, v in walls.items()))


if __name__ == "__main__":
    if "--help" in sys.argv or "-h" in sys.argv:
        print(__doc__)
        sys.exit(0)
    main(sys.argv[1:])
