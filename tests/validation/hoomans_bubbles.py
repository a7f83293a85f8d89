"""Bubbles of the Hoomans 1996 Table 2 bed by time, and its u_mf from a slow sweep (diagnostic, docs/gallery.md).

    python tests/validation/hoomans_bubbles.py bubbles RUN [RUN ...]     # by 0.1 s: rows with a bubble, largest
    python tests/validation/hoomans_bubbles.py sweep RUN                  # Δp, heights, bubbles by superficial velocity

``bubbles``: for each 0.1 s of a run, the fraction of the probes.csv rows (every 1 ms) with a bubble
(``bubble_area_m2`` > 0, ``analysis.fluidised.bubble_area``) and the largest bubble [cm²].

``sweep``: a run of ``hoomans-tsuji`` whose bottom is one superficial-velocity table, e.g. the rising sweep
(the lattice falls without gas for 0.5 s, as Hoomans §4.1, then 0 → 3 m/s over 2.5 s)::

    fluidem run hoomans-tsuji --until 3 --out runs/umf-up --set output.snapshot_interval=0.05 \\
        --set 'gas.boundaries.bottom={ kind = "inflow", voidage = 0.4, superficial = { table = [[0.0, 0.0], [0.5, 0.0], [3.0, 3.0]] } }'

It prints u_mf of ``analysis.fluidised.minimum_fluidisation`` (the gas's bed pressure drop, minus the gas
weight, against the inflow's superficial velocity; a falling sweep is read backwards), and by 0.2 m/s of
superficial velocity: Δp / (W/A), mean particle height, bed surface, rows with a bubble and the largest;
then the eq-49 voidage of the cell rows 1-4 (2-10 cm) of the bed at rest. W/A = 3550 Pa.
"""
import math
import sys
import tomllib
from pathlib import Path

import numpy as np

from fluidem.analysis.fluidised import minimum_fluidisation, read_probes
from fluidem.io import read_gas_fields


def bubbles(run: str, step: float = 0.1) -> str:
    c = read_probes(Path(run) / "probes.csv")
    t, a = c["time_s"], c["bubble_area_m2"]
    cells = []
    for lo in np.arange(0.0, t[-1] - 1e-9, step):
        m = (t > lo + 1e-9) & (t <= lo + step + 1e-9)
        cells.append(f"{(a[m] > 0).mean():.2f}/{a[m].max() * 1e4:.0f}")
    return f"{Path(run).name}: " + " ".join(cells)


def sweep(run: str) -> None:
    bottom = tomllib.loads((Path(run) / "case.toml").read_text())["gas"]["boundaries"]["bottom"]
    tab = np.array(bottom["segments"][0]["superficial"]["table"], float)
    c = read_probes(Path(run) / "probes.csv")
    t = c["time_s"]
    u_all = np.interp(t, tab[:, 0], tab[:, 1])
    rho, g = 101325.0 * 28.8e-3 / (8.314 * 293.0), 9.81  # the ideal gas at the reference pressure
    weight = 2400 * math.pi / 6 * 0.004**3 * 2700.0 * g / (0.15 * 0.004)
    rising = tab[-1, 1] > tab[0, 1]
    # the ramp starts at the last point of the lowest value (rising) or at the highest value (falling)
    start = tab[np.flatnonzero(tab[:, 1] == tab[:, 1].min())[-1], 0] if rising else tab[np.argmax(tab[:, 1]), 0]
    sel = t > start + 1e-9
    order = slice(None) if rising else slice(None, None, -1)
    u = u_all[sel][order]
    dp = (c["pressure_drop_bed_Pa"] - rho * g * 0.5)[sel][order]
    h, s, ba = (c[k][sel][order] for k in ("mean_particle_height_m", "bed_surface_height_m", "bubble_area_m2"))
    res = minimum_fluidisation(u, dp, weight)
    print(f"{run}: W/A = {weight:.0f} Pa; u_mf (Ergun-form fit of the fixed branch meets W/A) = {res['umf']:.2f} m/s; "
          f"plateau {res['plateau_Pa'] / weight:.3f} W/A")
    for lo in np.arange(0.0, u.max() - 1e-9, 0.2):
        m = (u > lo) & (u <= lo + 0.2)
        if m.any():
            print(f"  U {lo:.1f}-{lo + 0.2:.1f} m/s: dp/(W/A) {dp[m].mean() / weight:.3f}, mean height "
                  f"{h[m].mean() * 1e3:.1f} mm, surface {s[m].mean() * 1e3:.0f} mm, rows with a bubble "
                  f"{(ba[m] > 0).mean():.2f}, largest {ba[m].max() * 1e4:.0f} cm2")
    gas = read_gas_fields(run, ["voidage"])
    rest = start if rising else t[-1]
    k = int(np.argmin(abs(gas["time"] - rest)))
    e = gas["voidage"][k]
    print(f"  eq-49 voidage of rows 1-4 at {gas['time'][k]:.2f} s: {e[:, 1:5].mean():.3f} "
          f"(inner 11 columns {e[2:-2, 1:5].mean():.3f})")


if __name__ == "__main__":
    what, runs = sys.argv[1], sys.argv[2:]
    for r in runs:
        print(bubbles(r)) if what == "bubbles" else sweep(r)
