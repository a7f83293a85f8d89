"""A 3D bubbling bed run (``bubbling-3d-large``) against W/A and Darton et al. (1977): pressure drop, bed height,
pressure spectrum, bubble sizes and time-averaged solids-fraction maps.

    fluidem run bubbling-3d-large --until 2 --out runs/bed3d --threads 2 -q
    python tests/validation/bed3d_report.py runs/bed3d [--from 0.5] [--out DIR]

Over the window from ``--from`` to the last probe (a run still going is read as far as it has written):

- bed pressure drop: the mean of ``probes.csv`` ``pressure_drop_bed_Pa`` (inlet minus outlet, width-averaged)
  less the gas weight over the column, ρ_g g H_column, against the bed's buoyant weight over the cross-section,
  W/A = N (π/6) d³ (ρ_p − ρ_g) g / A;
- bed height: mean ± standard deviation of ``bed_surface_height_m`` (``analysis.fluidised.bed_surface_height``);
- pressure spectrum: ``analysis.spectrum.power_spectrum`` of the bed pressure drop, its dominant frequency and
  highest peaks;
- bubbles: in each gas snapshot, the bubbles of ``analysis.fluidised.bubble_regions`` (6-connected cells with
  ε > 0.8 not open to the freeboard), each as the sphere of its volume, D_eq = (6 V / π)^(1/3), at its centroid's
  height h; their mean in bands of height against Darton et al. (1977, Trans. IChemE 55, 274) for a porous-plate
  distributor (h₀ = 0, an ideal uniform inflow as the case's):

      D_b = 0.54 (U − u_mf)^0.4 (h + h₀)^0.8 g^−0.2,

  u_mf of Wen & Yu (``analysis.fluidised.wen_yu_umf``). Bubbles of a few cells of ~3 d are read to about a layer of
  cells: ±30 % in volume, ±10 % in D_eq;
- solids-fraction maps (PNG, ``--out``, default RUN/bed3d): the time mean of 1 − ε of the gas snapshots, seen from
  the front (averaged over the depth) and in a horizontal slice at half the mean bed height.
"""
from __future__ import annotations

import argparse
import math
import tomllib
from pathlib import Path

import numpy as np

from fluidem.analysis.fluidised import bubble_regions, wen_yu_umf
from fluidem.analysis.spectrum import power_spectrum, spectral_peaks
from fluidem.case import load_case
from fluidem.io import read_gas_fields
from fluidem.io.probes_csv import read_probes

G = 9.81  # [m/s²]


def darton_diameter(h, excess, h0: float = 0.0, g: float = G):
    """Bubble diameter [m] at height ``h`` [m] above the distributor, Darton et al. (1977):
    D_b = 0.54 (U − u_mf)^0.4 (h + h₀)^0.8 g^−0.2; ``excess`` U − u_mf [m/s], h₀ = 0 for a porous plate."""
    return 0.54 * excess**0.4 * (np.asarray(h, float) + h0) ** 0.8 * g**-0.2


def bed_numbers(run: Path) -> dict:
    """The case's numbers the comparison needs: W/A [Pa], U and u_mf [m/s], gas density, column size."""
    case = load_case(run / "case.toml")
    gas = case.gas
    rho_g = gas.properties.density
    if rho_g is None:  # the ideal gas at the reference pressure and temperature
        p = gas.properties
        rho_g = p.reference_pressure * p.molar_mass / (8.314462618 * p.temperature)
    size = gas.grid.size
    area = size[0] * size[2]
    weight = sum(s.count * math.pi / 6.0 * s.diameter**3 * (s.density - rho_g) for s in case.particles.species)
    sp = case.particles.species[0]
    raw = tomllib.loads((run / "case.toml").read_text())
    bottom = raw["gas"]["boundaries"]["bottom"]  # the saved case gives the inflow as segments
    superficial = float(bottom["superficial"] if "superficial" in bottom else bottom["segments"][0]["superficial"])
    return {"case": case, "rho_g": rho_g, "height": size[1], "area": area, "w_over_a": weight * G / area,
            "U": superficial, "umf": wen_yu_umf(sp.diameter, sp.density, rho_g, gas.properties.viscosity),
            "diameter": sp.diameter}


def pressure_and_height(run: Path, start: float, nums: dict) -> dict:
    """Window means of the bed pressure drop and bed height, and the pressure drop's spectrum."""
    p = read_probes(run / "probes.csv")
    t = p["time_s"]
    sel = t >= start - 1e-9
    if sel.sum() < 2:
        raise SystemExit(f"{run}: fewer than 2 probe samples after {start} s (last {t[-1]:.3f} s)")
    dp = p["pressure_drop_bed_Pa"][sel] - nums["rho_g"] * G * nums["height"]
    h = p["bed_surface_height_m"][sel]
    spec = power_spectrum(t[sel], dp)
    peaks, heights = spectral_peaks(t[sel], dp)
    return {"t0": float(t[sel][0]), "t1": float(t[sel][-1]), "samples": int(sel.sum()),
            "dp_mean": float(dp.mean()), "dp_std": float(dp.std()), "h_mean": float(h.mean()),
            "h_std": float(h.std()), "spectrum": spec, "peaks": peaks, "peak_heights": heights}


def bubble_sizes(run: Path, start: float, nums: dict):
    """(D_eq [m], centroid height [m], time [s]) of every bubble in the gas snapshots from ``start`` on."""
    g = read_gas_fields(run, ["voidage"])
    grid = nums["case"].gas.build(nums["case"].gravity).grid
    dx, dy, dz = (np.diff(g["x_faces"])[0], np.diff(g["y_faces"])[0], np.diff(g["z_faces"])[0])
    y = g["y"]
    rows = []
    for k in np.flatnonzero(g["time"] >= start - 1e-9):
        for mask in bubble_regions(grid, g["voidage"][k]):
            volume = mask.sum() * dx * dy * dz
            height = float(y[np.nonzero(mask)[1]].mean())
            rows.append(((6.0 * volume / math.pi) ** (1.0 / 3.0), height, float(g["time"][k])))
    return np.array(rows).reshape(-1, 3), g


def solids_maps(g: dict, start: float, slice_height: float, out: Path) -> Path:
    """Front view (mean over the depth) and a horizontal slice of the time-mean solids fraction, as PNG."""
    from fluidem.plotting import style

    sel = g["time"] >= start - 1e-9
    phi = np.nanmean(1.0 - g["voidage"][sel], axis=0)  # (nx, ny, nz)
    front = phi.mean(axis=2)
    j = int(np.clip(np.searchsorted(g["y_faces"], slice_height) - 1, 0, phi.shape[1] - 1))
    vmax = max(float(np.nanmax(phi)), 1e-3)
    with style.context():
        fig = style.new_figure(7.0, 5.0)
        ax1, ax2 = fig.subplots(1, 2, gridspec_kw={"width_ratios": [1.0, 1.3]})
        m = ax1.pcolormesh(g["x_faces"] * 1e3, g["y_faces"] * 1e3, front.T, cmap=style.SOLIDS_COLOURMAP,
                           vmin=0.0, vmax=vmax, shading="flat", rasterized=True)
        ax1.set_aspect("equal")
        ax1.set_xlabel("x [mm]")
        ax1.set_ylabel("height [mm]")
        ax1.axhline(g["y_faces"][j] * 1e3, color="k", lw=0.6, ls="--")
        ax1.axhline(g["y_faces"][j + 1] * 1e3, color="k", lw=0.6, ls="--")
        ax1.set_title("front, mean over the depth")
        ax2.pcolormesh(g["x_faces"] * 1e3, g["z_faces"] * 1e3, phi[:, j, :].T, cmap=style.SOLIDS_COLOURMAP,
                       vmin=0.0, vmax=vmax, shading="flat", rasterized=True)
        ax2.set_aspect("equal")
        ax2.set_xlabel("x [mm]")
        ax2.set_ylabel("z [mm]")
        ax2.set_title(f"slice {g['y_faces'][j] * 1e3:.0f}-{g['y_faces'][j + 1] * 1e3:.0f} mm high")
        fig.colorbar(m, ax=[ax1, ax2], label="mean solids fraction [-]", shrink=0.8)
        n = int(sel.sum())
        fig.suptitle(f"mean over t = {g['time'][sel][0]:.2f}-{g['time'][sel][-1]:.2f} s ({n} gas snapshots)")
        out.mkdir(parents=True, exist_ok=True)
        return style.save(fig, out / "solids_fraction", ["png"])[0]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("run")
    ap.add_argument("--from", dest="start", type=float, default=0.5, help="start of the averaging window [s]")
    ap.add_argument("--out", default=None, help="folder of the PNG maps (default RUN/bed3d)")
    a = ap.parse_args(argv)
    run = Path(a.run)
    nums = bed_numbers(run)
    ph = pressure_and_height(run, a.start, nums)
    print(f"{run}: window {ph['t0']:.3f}-{ph['t1']:.3f} s, {ph['samples']} probe samples")
    print(f"bed pressure drop: {ph['dp_mean']:.1f} ± {ph['dp_std']:.1f} Pa; W/A = {nums['w_over_a']:.1f} Pa; "
          f"ratio {ph['dp_mean'] / nums['w_over_a']:.3f}")
    print(f"bed height (bed_surface_height_m): {ph['h_mean'] * 1e3:.1f} ± {ph['h_std'] * 1e3:.1f} mm")
    spec = ph["spectrum"]
    if spec is None:
        print("pressure spectrum: too few samples")
    else:
        peaks = ", ".join(f"{f:.2f} Hz ({h:.2f})" for f, h in zip(ph["peaks"], ph["peak_heights"]))
        print(f"pressure spectrum: dominant {spec.dominant:.2f} Hz (resolution {spec.frequency[1]:.2f} Hz); "
              f"peaks {peaks}")
    excess = nums["U"] - nums["umf"]
    print(f"U = {nums['U']:.3f} m/s, u_mf (Wen & Yu) = {nums['umf']:.3f} m/s, U - u_mf = {excess:.3f} m/s")
    bubbles, g = bubble_sizes(run, a.start, nums)
    if bubbles.shape[0] == 0:
        print("bubbles: none detected in the window")
    else:
        top = ph["h_mean"]
        edges = np.linspace(0.0, top, 5)
        print(f"bubbles: {bubbles.shape[0]} in {np.unique(bubbles[:, 2]).size} gas snapshots; by centroid height:")
        print(f"{'h [mm]':>12s} {'count':>6s} {'D_eq [mm]':>14s} {'Darton [mm]':>12s} {'ratio':>6s}")
        for lo, hi in zip(edges[:-1], edges[1:]):
            s = (bubbles[:, 1] >= lo) & (bubbles[:, 1] < hi)
            if not s.any():
                continue
            d = bubbles[s, 0]
            dd = float(np.mean(darton_diameter(bubbles[s, 1], excess)))
            print(f"{lo * 1e3:5.0f}-{hi * 1e3:<5.0f} {s.sum():6d} {d.mean() * 1e3:7.1f} ± {d.std() * 1e3:4.1f} "
                  f"{dd * 1e3:12.1f} {d.mean() / dd:6.2f}")
        mid = (bubbles[:, 1] >= 0.25 * top) & (bubbles[:, 1] < 0.75 * top)
        if mid.any():
            ratio = bubbles[mid, 0].mean() / float(np.mean(darton_diameter(bubbles[mid, 1], excess)))
            print(f"bubbles between 1/4 and 3/4 of the bed height: mean D_eq / Darton = {ratio:.2f}")
    png = solids_maps(g, a.start, 0.5 * ph["h_mean"], Path(a.out) if a.out else run / "bed3d")
    print(f"solids-fraction maps: {png}")


if __name__ == "__main__":
    main()
