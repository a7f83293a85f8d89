"""Where the weight of the u_mf-sweep bed goes when fluidised (diagnostic for test_umf_sweep.py).

The sweep case (``_helpers.umf_sweep``) held at 0.4 m/s (2.1 u_mf) after settling, in a smaller bed
than the test's (2000 spheres, 20 × 5 diameters, 5 × 15 cells: the first row of figures quoted in
test_umf_sweep.py; ``--wide`` runs the test's 60 × 10 d bed); over 0.35-0.65 s it prints the
bed pressure drop over W/A, the gas force on the particles (drag + −V_p∇p) over their
weight m g, and the bottom wall's force over m g (sampled every gas step, as the floor's
load comes in impacts): the last two add up to 1 less the particles' mean acceleration.
``--profile`` also prints the gas force over m g in layers of one diameter.

    python tests/validation/umf_budget.py [INFLOW_VOIDAGE] [MOMENTUM_EXCHANGE] [U] [--profile]
        [--exchange-faces] [--no-pairing] [--centre] [--wide] [--frozen] [--3d]

Options: ``--exchange-faces`` (``coupling.boundary_faces = "exchange"``), ``--no-pairing``
(``coupling.pressure_pairing = false``), ``--centre`` (the pressure drop from the first row of centres
instead of the inlet pressure extrapolated from the first two rows), ``--wide`` (the test's own 60 × 10 d
bed of 12,000 spheres instead of the 20 × 5 d one), ``--3d`` (the 3D gas grid's bed of
test_umf_sweep_3d.py: 5120 spheres, 16 × 16 d with periodic sides, 4 × 15 × 4 cells), ``--frozen``
(``drag_update = "frozen"``). The last figure printed is the drag and pressure force the gas gave up
(``GasCoupling.exchange_balance``; the pressure part only with pairing).

Measured (``python tests/validation/umf_budget.py 1.0 particle [U] [options]``, 0.4 m/s unless given;
Δp / (W/A), gas force / m g, floor / m g (share of gas steps with the floor touched), given up by the
gas / m g):

    defaults (fold, pairing)                 0.974, 0.974, 0.026 (71 %), 0.974
    --centre                                 0.859 (the first interior faces' half cell left out)
    --frozen                                 0.974, 0.974, 0.026 (63 %), 0.974
    --no-pairing                             0.957, 0.968, 0.031 (78 %)
    --exchange-faces                         0.971, 0.939, 0.056 (96 %), 0.916
    inflow voidage 0.4 (``0.4 particle``)    0.971, 0.974, 0.025 (66 %), 0.974
    0.3 --wide                               0.968, 0.968, 0.028 (87 %), 0.968
    0.35 --3d                                0.976, 0.975, 0.027 (46 %), 0.975
    --3d                                     0.963, 0.962, 0.037 (48 %), 0.962

With the defaults the budget closes: the gas gives up what the particles gain and Δp × A is that force;
the floor's 2.5-3 % is what keeps the plateau below W/A, the load of particles falling back onto it in
this slugging bed. The 3D-grid bed's budget closes as well (gas force + floor = 1.002 and 0.999 m g at
0.35 and 0.4 m/s): its floor carries 2.7 % and 3.7 % of the weight, touched in about half of the gas steps,
and by height (``--profile`` at 0.35 m/s) the gas pushes the lowest 9 d at 1.05-1.18 × their weight and the
top layers (16-24 d) at 0.35-0.91, as in the 2D-grid bed (test_umf_sweep_3d.py adds the floor's load to
its plateau). Without pairing the gas's −ε∇p (mapped ε) gives up less pressure force than the particles
gain; with the exchanged boundary faces the particles above the inflow hand 2 % of the drag to the inflow and more of the bed rests on the floor (and the extrapolated inlet pressure, which belongs to
the folded faces' control volumes, no longer matches what the gas carries). With both (boundary faces
exchanged, pressure unpaired): Δp / (W/A) 0.952-0.953, gas force 0.933-0.934 m g, floor 0.060-0.062 m g
(touched in 75 % of the gas steps); by height (``--profile``) 0.87 and 0.94 in the two lowest diameters
(the gas there is interpolated towards the inflow face's slower superficial velocity), 1.12-1.15 at
3-6 d, and 0.35-0.89 in the top layers (17-25 d): the bed slugs, the plug thrown up falls back onto the
floor. The folded faces' sums are divided by their own control volume of 1.5 cells
(``coupling.exchange.face_volumes``); divided by V_cell, β comes out 1.5× and the pressure voidage clips
at the minimum in a packed bed: the lowest particles are pushed at 1.2× their weight and tsuji-jet-background's
bed stands 5 cm higher (0.240 against 0.186 m over 5-10 s).
"""
import math
import sys
from pathlib import Path

import numpy as np

from fluidem.analysis.fluidised import pressure_drop
from fluidem.analysis.probes import wall_forces
from fluidem.case import validate_case
from fluidem.simulation import Simulation

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tests/, for _helpers
from _helpers import umf_sweep as T  # noqa: E402


def from_first_centre(grid, p, height):
    """Pressure drop from the first row of cell centres (width-averaged) to ``height`` (``--centre``)."""
    from fluidem.analysis.fluidised import pressure_at_heights

    return float(np.asarray(p).mean(axis=0)[0] - pressure_at_heights(grid, p, [height])[0])


def main(eps_in=1.0, exchange="particle", u=0.4, end=0.65, start=0.35, profile=False, faces="fold", pairing=True,
         wide=False, update="substep", three_d=False):
    if three_d:  # the 3D-grid sweep's bed of test_umf_sweep_3d.py: 16 x 16 d, periodic sides, 4 x 15 x 4 cells
        from test_umf_sweep_3d import N3, SIDE, sweep_case_3d

        n, w, depth = N3, SIDE, SIDE
        case = sweep_case_3d()
    else:
        n, w, depth = (T.N, T.W, T.DEPTH) if wide else (2000, 20 * T.D, 5 * T.D)  # the 20 x 5 d bed: 5 x 15 cells
        case = T.sweep_case(n, w, depth)
    c = case.model_dump(mode="json", exclude_none=True)
    bottom = c["gas"]["boundaries"]["bottom"]
    bottom["voidage"] = eps_in
    bottom.pop("segments", None)  # the sweep's ramp, replaced by a ramp to u held from T_SETTLE + 0.1 s
    bottom["superficial"] = {"table": [[0.0, 0.0], [T.T_SETTLE, 0.0], [T.T_SETTLE + 0.1, u], [10.0, u]]}
    c["coupling"]["momentum_exchange"] = exchange
    c["coupling"]["boundary_faces"] = faces
    c["coupling"]["pressure_pairing"] = pairing
    c["coupling"]["drag_update"] = update
    c["time"]["end"] = end
    sim = Simulation(validate_case(c))
    chunk = int(round(0.005 / sim.dt))
    st = sim.state
    weight = float(np.sum(st.mass)) * T.G
    wa = n * math.pi / 6 * T.D**3 * (T.RHO_P - T.RHO) * T.G / (w * depth)
    eng = sim.engine
    mg = st.mass * T.G
    layers = np.zeros((2, 60))  # Σ gas force, Σ m g per one-diameter layer
    dp, fg, floor, gas_side = [], [], [], []
    while sim.time < end - 1e-9:
        sim.advance(chunk if sim.time <= start else sim.gas.substeps)  # every gas step in the window
        if sim.time > start:
            dp.append(pressure_drop(sim.gas.grid, sim.gas.state.p, T.H) - T.RHO * T.G * T.H)
            f = eng.external_force()[:, 1]
            fg.append(float(f.sum()))
            b = sim.gas.exchange_balance()  # what the gas gave up in the step: drag, pressure force (y)
            gas_side.append(float(b["gas"][1] - b.get("pressure_gas", [0.0, 0.0])[1]))
            floor.append(-float(wall_forces(eng)["box.ymin"][1]))
            k = np.clip((st.position[:, 1] / T.D).astype(int), 0, layers.shape[1] - 1)
            layers[0] += np.bincount(k, f, layers.shape[1])
            layers[1] += np.bincount(k, mg, layers.shape[1])
    touched = np.mean(np.array(floor) > 0)
    print(f"inflow voidage {eps_in}, exchange {exchange}, boundary_faces {faces}, pressure_pairing {pairing}, "
          f"{u} m/s: bed pressure drop / (W/A) = {np.mean(dp) / wa:.4f}; "
          f"gas force on particles / m g = {np.mean(fg) / weight:.4f}; "
          f"bottom wall / m g = {np.mean(floor) / weight:.4f} (touched in {touched:.0%} of the gas steps); "
          f"drag + pressure force the gas gave up / m g = {np.mean(gas_side) / weight:.4f}")
    if profile:
        for k in np.flatnonzero(layers[1]):
            print(f"  {k:2d}-{k + 1:2d} d: gas force / m g = {layers[0, k] / layers[1, k]:.3f}")


if __name__ == "__main__":
    if "--help" in sys.argv or "-h" in sys.argv:
        print(__doc__)
        sys.exit(0)
    if "--centre" in sys.argv:
        pressure_drop = from_first_centre  # noqa: F811 (main reads the module's name)
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    main(float(args[0]) if args else 1.0, args[1] if len(args) > 1 else "particle",
         float(args[2]) if len(args) > 2 else 0.4, profile="--profile" in sys.argv,
         faces="exchange" if "--exchange-faces" in sys.argv else "fold", pairing="--no-pairing" not in sys.argv,
         wide="--wide" in sys.argv, update="frozen" if "--frozen" in sys.argv else "substep",
         three_d="--3d" in sys.argv)
