"""The spout of a ``spouted-3d`` run by time: jet penetration, fountain, bed surface and bed pressure drop.

    fluidem run spouted-3d --until 0.4 --out runs/spout --threads 1 -q --set output.snapshot_interval=0.05
    python tests/validation/spout_3d.py runs/spout [--from 0.2]

For each gas-field snapshot (``gas.h5``):

- jet penetration: the height of the top of the connected run of cells with voidage above 0.8 (the bubble
  threshold of ``analysis.fluidised``) that starts at the bottom in the layer's cells over the nozzle (the cells
  whose centre lies within the nozzle's radius + half a cell of its axis; the layer counts if any of them is
  above 0.8). It reaches the bed surface when the jet breaks through: a spout;
- fountain: the highest particle centre within 2 nozzle radii of the axis (particle snapshot of the same time);
- bed surface: ``analysis.fluidised.bed_surface_height`` of all the particles.

Then the mean bed pressure drop (``probes.csv`` ``pressure_drop_bed_Pa``, minus the gas weight over the
column) from ``--from`` to the end against the bed's buoyant weight over area W/A.
"""
import argparse
import math
import tomllib
from pathlib import Path

import numpy as np

from fluidem.analysis.fluidised import BUBBLE_VOIDAGE, bed_surface_height
from fluidem.io import read_gas_fields
from fluidem.io.probes_csv import read_probes
from fluidem.io.snapshots import iter_snapshots

RHO_GAS = 101325.0 * 28.8e-3 / (8.314 * 293.0)  # [kg/m^3] the ideal gas at the reference pressure


def jet_penetration(eps, x, z, centre, radius, dy, threshold=BUBBLE_VOIDAGE) -> float:
    """Height [m] of the top of the run of layers, from the bottom, whose cells over the nozzle hold ε > threshold."""
    hx, hz = x[1] - x[0], z[1] - z[0]
    X, Z = np.meshgrid(x, z, indexing="ij")
    over = np.hypot(X - centre[0], Z - centre[1]) <= radius + 0.5 * max(hx, hz)
    open_layer = (np.moveaxis(eps, 1, 2)[over] > threshold).any(axis=0)  # (ny,)
    n = int(np.argmin(open_layer)) if not open_layer.all() else open_layer.size
    return n * dy


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("run")
    ap.add_argument("--from", dest="start", type=float, default=0.2, help="start of the Δp window [s]")
    a = ap.parse_args(argv)
    run = Path(a.run)
    case = tomllib.loads((run / "case.toml").read_text())
    bottom = case["gas"]["boundaries"]["bottom"]
    nozzle = bottom["patches"][0]
    centre, radius = nozzle["centre"], nozzle["radius"]
    sp = case["particles"]["species"][0]
    size = case["gas"]["grid"]["size"]
    area = size[0] * size[2]
    weight = sp["count"] * math.pi / 6 * sp["diameter"] ** 3 * (sp["density"] - RHO_GAS) * 9.81 / area

    gas = read_gas_fields(run, ["voidage"])
    dy = gas["y_faces"][1] - gas["y_faces"][0]
    snaps = {round(t, 6): s for t, s in iter_snapshots(run / "particles.h5", fields=["position", "diameter"])}
    print(f"{run}: nozzle r = {radius * 1e3:.1f} mm at ({centre[0] * 1e3:.0f}, {centre[1] * 1e3:.0f}) mm; "
          f"W/A = {weight:.1f} Pa")
    print(f"{'t [s]':>6s} {'jet top [mm]':>12s} {'fountain [mm]':>13s} {'bed surface [mm]':>16s}")
    for k, t in enumerate(gas["time"]):
        jet = jet_penetration(gas["voidage"][k], gas["x"], gas["z"], centre, radius, dy)
        s = snaps.get(round(float(t), 6))
        if s is None:
            continue
        pos, r = s["position"], 0.5 * s["diameter"]
        near = np.hypot(pos[:, 0] - centre[0], pos[:, 2] - centre[1]) < 2 * radius
        fountain = pos[near, 1].max() if near.any() else math.nan
        surface = bed_surface_height(pos[:, 1], r, False)
        print(f"{t:6.3f} {jet * 1e3:12.1f} {fountain * 1e3:13.1f} {surface * 1e3:16.1f}")
    p = read_probes(run / "probes.csv")
    sel = p["time_s"] >= a.start - 1e-9
    dp = p["pressure_drop_bed_Pa"][sel] - RHO_GAS * 9.81 * size[1]
    print(f"bed Δp over {a.start:g}-{p['time_s'][-1]:g} s: {dp.mean():.1f} ± {dp.std():.1f} Pa = "
          f"{dp.mean() / weight:.3f} W/A")


if __name__ == "__main__":
    main()
