"""``bubbling-3d`` beside ``bubbling-pseudo2d`` (the same bed, the gas on a 2D grid): the table of docs/gallery.md.

    python tests/validation/bubbling_pseudo2d.py RUN_3D RUN_2D [--from 0.2] [--to 0.6]

Each RUN is a run directory of ``fluidem run bubbling-3d`` or ``bubbling-pseudo2d`` (``--until 0.6``). Over the
window [from, to] of each run: the bed pressure drop of probes.csv (``pressure_drop_bed_Pa``, inlet to outlet)
against W/A, W the particles' weight less the gas's buoyancy (ρ_g ≈ 1.2 kg/m³, 0.1 %) and A the column's
44 × 10 mm cross-section; the bed surface (``bed_surface_height_m``) and the mean centre height
(``mean_particle_height_m``), mean ± standard deviation over the probe samples; and the time-averaged
solids fraction φ(y) over height from the particle snapshots: each sphere's section π (R² − (y − y_c)²) at
levels 0.1 mm apart (``analysis.fluidised.solids_profile``) over the column's cross-section, averaged over
6 mm bins and over the snapshots in the window. The profile comes from the particles alone, so the two
grids' voidage mappings ("volume" in 3D, "area_volume" in 2D) do not enter it.
"""
import argparse
import math
from pathlib import Path

import h5py
import numpy as np

from fluidem.analysis.fluidised import solids_profile
from fluidem.io.probes_csv import read_probes

G, WIDTH, DEPTH = 9.81, 0.044, 0.010  # [m/s²], [m]
STEP, BIN, TOP = 1e-4, 6e-3, 0.12  # profile level spacing, bin height, column height [m]


def weight_over_area(d=0.0012, rho=1000.0, n=9240, rho_gas=1.2) -> float:
    return n * math.pi / 6.0 * d**3 * (rho - rho_gas) * G / (WIDTH * DEPTH)


def probe_stats(run: Path, t0: float, t1: float) -> dict:
    p = read_probes(run)
    t = np.asarray(p["time_s"], float)
    sel = (t >= t0 - 1e-9) & (t <= t1 + 1e-9)
    out = {"samples": int(sel.sum()), "until": float(t.max())}
    for key in ("pressure_drop_bed_Pa", "bed_surface_height_m", "mean_particle_height_m"):
        v = np.asarray(p[key], float)[sel]
        out[key] = (float(v.mean()), float(v.std()))
    return out


def profile(run: Path, t0: float, t1: float) -> tuple[np.ndarray, int]:
    """φ averaged over 6 mm bins from the floor to the top, and the number of snapshots in the window."""
    nbins = int(round(TOP / BIN))
    per_bin = int(round(BIN / STEP))
    acc = np.zeros(nbins)
    count = 0
    with h5py.File(run / "particles.h5", "r") as f:
        for name in sorted(f["snapshots"]):
            s = f["snapshots"][name]
            t = float(s.attrs["time"])
            if not t0 - 1e-9 <= t <= t1 + 1e-9:
                continue
            pos, d = s["position"][()], s["diameter"][()]
            phi = solids_profile(pos[:, 1], 0.5 * d, False, STEP) / (WIDTH * DEPTH)
            phi = np.pad(phi, (0, max(0, nbins * per_bin - phi.size)))[:nbins * per_bin]
            acc += phi.reshape(nbins, per_bin).mean(axis=1)
            count += 1
    return acc / max(count, 1), count


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs=2, type=Path, help="the bubbling-3d run, then the bubbling-pseudo2d run")
    ap.add_argument("--from", dest="t0", type=float, default=0.2)
    ap.add_argument("--to", dest="t1", type=float, default=0.6)
    args = ap.parse_args(argv)
    wa = weight_over_area()
    stats = [probe_stats(r, args.t0, args.t1) for r in args.runs]
    profiles = [profile(r, args.t0, args.t1) for r in args.runs]
    print(f"window {args.t0:g}-{args.t1:g} s; W/A = {wa:.1f} Pa")
    print("| quantity | bubbling-3d (3D gas, 15 x 40 x 3) | bubbling-pseudo2d (2D gas, 15 x 40) |")
    print("| --- | --- | --- |")
    dp = [s["pressure_drop_bed_Pa"] for s in stats]
    print("| Δp bed [Pa], mean ± std | " + " | ".join(f"{m:.1f} ± {e:.1f}" for m, e in dp) + " |")
    print("| Δp / (W/A) | " + " | ".join(f"{m / wa:.3f}" for m, _ in dp) + " |")
    for key, label in (("bed_surface_height_m", "bed surface [mm]"), ("mean_particle_height_m", "mean centre height [mm]")):
        print(f"| {label}, mean ± std | " + " | ".join(f"{1e3 * s[key][0]:.1f} ± {1e3 * s[key][1]:.1f}"
                                                     for s in stats) + " |")
    print("| probe samples / snapshots | " + " | ".join(f"{s['samples']} / {p[1]}" for s, p in zip(stats, profiles))
          + " |")
    print()
    print("| height [mm] | φ bubbling-3d | φ bubbling-pseudo2d |")
    print("| --- | --- | --- |")
    a, b = profiles[0][0], profiles[1][0]
    for k in range(a.size):
        if a[k] < 1e-3 and b[k] < 1e-3:
            break
        print(f"| {1e3 * k * BIN:.0f}–{1e3 * (k + 1) * BIN:.0f} | {a[k]:.3f} | {b[k]:.3f} |")


if __name__ == "__main__":
    main()
