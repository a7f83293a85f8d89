"""The ideal Table 2 bed (Hoomans 1996 §5.3.1) with its background at the model's own u_mf (docs/gallery.md).

Hoomans' background, 4.5 m/s interstitial (1.8 m/s superficial), is his u_mf (Wen & Yu); this model's
bed is lifted from about 1.0 m/s superficial (the slow sweep of ``hoomans_bubbles.py sweep``). These runs
put the ideal bed (e = e_w = 1, μ = μ_w = 0) at the model's own minimum fluidisation instead, with and
without the 45 m/s orifice jet from T0 = 0.5 s::

    B='{ kind = "inflow", voidage = 0.4, segments = [{ interstitial = 2.5 }, { interstitial = { pulse = 45.0, start = 0.5, duration = 10.0, otherwise = 2.5 }, start = 0.07, end = 0.08 }] }'
    fluidem run hoomans-orifice --out runs/ideal-bg25-jet --set particles.contact.restitution=1.0 \\
        --set particles.contact.friction=0.0 --set "gas.boundaries.bottom=$B"
    fluidem run hoomans-orifice --out runs/ideal-bg25 --set particles.contact.restitution=1.0 \\
        --set particles.contact.friction=0.0 \\
        --set 'gas.boundaries.bottom={ kind = "inflow", voidage = 0.4, interstitial = 2.5 }'
    python tests/validation/hoomans_background.py runs/ideal-bg25-jet runs/ideal-bg25

For each run it prints the measures of test_hoomans1996.py (gas snapshots every 10 ms from T0: bubbles, a
4-connected region of ≥ 3 cells of ε > 0.8 apart from the freeboard; slugs, a chord of 0.8 of the width;
the largest bubble), the probe rows (every 1 ms) with a bubble and the largest in 0.3-0.5 s and from T0,
the mean particle height over T0 − 0.2 s to T0 and from T0, and the gauge pressure 20 cm up from T0
(standard deviation, peak-to-peak), and whether the first bubble from T0 sits on the orifice (the
central column's lowest two rows, as test_hoomans1996.py) and when the first slug comes.
"""
import sys
from pathlib import Path

import numpy as np

import fluidem as fd
from fluidem.analysis import fluidised as F
from fluidem.io import read_gas_fields

T0 = 0.5  # [s] the jet onset of the case


def measure(run: str) -> str:
    out = Path(run)
    grid = fd.load_case(out / "case.toml").gas.grid.build()
    gas = read_gas_fields(out, ["voidage"])
    t, eps = gas["time"], gas["voidage"]
    area = np.array([F.bubble_area(grid, e) for e in eps])
    slug = np.array([F.slug_detected(grid, e) for e in eps])
    late = t >= T0 - 1e-9
    c = F.read_probes(out / "probes.csv")
    pt, pa, h = c["time_s"], c["bubble_area_m2"], c["mean_particle_height_m"]
    p20 = c["pressure_20cm_gauge_Pa"][pt >= T0 - 1e-9]

    def rows(lo, hi):
        m = (pt > lo + 1e-9) & (pt <= hi + 1e-9)
        return f"{int((pa[m] > 0).sum())}/{int(m.sum())}, {pa[m].max() * 1e4:.0f} cm2"

    before = (pt >= T0 - 0.2 - 1e-9) & (pt < T0 - 1e-9)
    first = ""
    onset = np.flatnonzero(late & (area > 0))
    if onset.size:  # the first bubble from T0: does it sit on the orifice (the central column, lowest two rows)?
        mask = F.bubble_regions(grid, eps[onset[0]])[0]
        on = bool(mask[grid.nx // 2, :2].any())
        slugs = np.flatnonzero(late & slug)
        first = (f"; first bubble at T0{t[onset[0]] - T0:+.2f} s, {'on' if on else 'not on'} the orifice"
                 + (f", first slug at T0{t[slugs[0]] - T0:+.2f} s" if slugs.size else ""))
    return (f"{out.name}: mean height T0-0.2..T0 {h[before].mean() * 1e3:.1f} mm, from T0 "
            f"{h[pt >= T0 - 1e-9].mean() * 1e3:.1f} mm; probe rows with a bubble 0.3-0.5 s {rows(0.3, T0)}, "
            f"from T0 {rows(T0, pt[-1])}; snapshots from T0 with a bubble {int((area[late] > 0).sum())}, a slug "
            f"{int(slug[late].sum())} (of {int(late.sum())}), largest {area[late].max() * 1e4:.0f} cm2; "
            f"p20 gauge from T0: std {p20.std():.0f} Pa, peak-to-peak {np.ptp(p20):.0f} Pa{first}")


if __name__ == "__main__":
    if len(sys.argv) < 2 or sys.argv[1] in ("-h", "--help"):
        print(__doc__)
        sys.exit(0)
    for r in sys.argv[1:]:
        print(measure(r))
