"""Where the weight of the u_mf-sweep bed goes when fluidised (diagnostic for test_umf_sweep.py).

The sweep case held at 0.4 m/s (2.1 u_mf) after settling, in the sweep's first, smaller bed
(2000 spheres, 20 × 5 diameters, 5 × 15 cells: the figures quoted in test_umf_sweep.py; the
test itself now sweeps a 60 × 10 d bed); over 0.35-0.65 s it prints the
bed pressure drop over W/A and the gas force on the particles (drag + −V_p∇p) over their
weight m g; the difference from 1 is what rests on the bottom wall.

    python tests/validation/umf_budget.py [INFLOW_VOIDAGE] [MOMENTUM_EXCHANGE]
"""
import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
import test_umf_sweep as T  # noqa: E402

from fluidem.analysis.fluidised import pressure_drop  # noqa: E402
from fluidem.case import validate_case  # noqa: E402
from fluidem.simulation import Simulation  # noqa: E402


def main(eps_in=1.0, exchange="particle", u=0.4, end=0.65, start=0.35):
    T.N, T.W, T.DEPTH = 2000, 20 * T.D, 5 * T.D  # the 20 x 5 d bed (5 x 15 cells of 4 d)
    c = T.sweep_case().model_dump(mode="json", exclude_none=True)
    bottom = c["gas"]["boundaries"]["bottom"]
    bottom["voidage"] = eps_in
    bottom["superficial"] = {"table": [[0.0, 0.0], [T.T_SETTLE, 0.0], [T.T_SETTLE + 0.1, u], [10.0, u]]}
    c["coupling"]["momentum_exchange"] = exchange
    c["time"]["end"] = end
    sim = Simulation(validate_case(c))
    chunk = int(round(0.005 / sim.dt))
    st = sim.state
    weight = float(np.sum(st.mass)) * T.G
    wa = T.N * math.pi / 6 * T.D**3 * (T.RHO_P - T.RHO) * T.G / (T.W * T.DEPTH)
    dp, fg = [], []
    while sim.time < end - 1e-9:
        sim.step_once(chunk)
        if sim.time > start:
            dp.append(pressure_drop(sim.gas.grid, sim.gas.state.p, T.H) - T.RHO * T.G * T.H)
            fg.append(float(sim.engine.ext_force[:, 1].sum()))
    print(f"inflow voidage {eps_in}, exchange {exchange}, {u} m/s: bed pressure drop / (W/A) = "
          f"{np.mean(dp) / wa:.4f}; gas force on particles / m g = {np.mean(fg) / weight:.4f}")


if __name__ == "__main__":
    main(float(sys.argv[1]) if len(sys.argv) > 1 else 1.0, sys.argv[2] if len(sys.argv) > 2 else "particle")
