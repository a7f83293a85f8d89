"""Gas pressure at probes against time and its power spectrum with the dominant frequency (Hoomans et al. 1996
Figs 11 and 13; Sun et al. 2007 Fig 3): the probes.csv columns of pressures, else the gas field 0.2 m above the
bottom centre. The spectrum is ``analysis.spectrum.power_spectrum``, the one the summary's frequencies come from."""
from __future__ import annotations

import numpy as np

from ...analysis.fluidised import PRESSURE_PROBE_HEIGHT
from ...analysis.spectrum import MIN_SAMPLES, power_spectrum
from .. import style
from ..run import RunData
from ._shared import PlotOptions, figure


def _pressure_columns(run: RunData) -> list[str]:
    """probes.csv columns holding pressures: names starting with ``pressure`` or ending ``_Pa``."""
    return [c for c in run.probe_columns() if c.startswith("pressure") or c.endswith("_Pa")]


def _lacks_pressure(run: RunData) -> str | None:
    probe_why = run.lacks_probes()
    if probe_why is None and _pressure_columns(run):
        return None
    gas_why = run.lacks_gas("p")
    if gas_why is None:
        if len(run.gas_times) >= 2:
            return None
        gas_why = f"gas.h5 has {len(run.gas_times)} snapshot; a trace needs 2"
    probe_why = probe_why or "probes.csv has no pressure columns (pressure*, *_Pa)"
    return f"{probe_why}, and {gas_why}"


def pressure_probe_cell(x_centres: np.ndarray, y_centres: np.ndarray, dy: float,
                        height: float = PRESSURE_PROBE_HEIGHT) -> tuple[int, int]:
    """(i, j) of the cell at the bottom centre's x holding ``height`` [m] (the top row if the domain is lower)."""
    x_mid = 0.5 * (x_centres[0] + x_centres[-1])
    i = int(np.argmin(np.abs(x_centres - x_mid)))
    bottom = y_centres[0] - 0.5 * dy
    j = int(np.clip(np.floor((height - bottom) / dy), 0, len(y_centres) - 1))
    return i, j


def _pressure_traces(run: RunData) -> tuple[list[tuple[str, np.ndarray, np.ndarray]], str, str]:
    """(label, time [s], pressure [Pa]) per trace, the y label, and where the traces come from."""
    if run.lacks_probes() is None and _pressure_columns(run):
        p = run.probes
        traces = [(style.label(c).split(" [")[0], p["time_s"], p[c]) for c in _pressure_columns(run)]
        return traces, "pressure [Pa]", "probes.csv"
    g = run.gas
    dy = float(g["y_faces"][1] - g["y_faces"][0])
    i, j = pressure_probe_cell(g["x"], g["y"], dy)
    p_ref = float(run.case.get("gas", {}).get("properties", {}).get("reference_pressure", 101325.0))
    label = f"cell centre x = {g['x'][i]:.3g} m, y = {g['y'][j]:.3g} m"
    return [(label, g["time"], g["p"][:, i, j] - p_ref)], f"p − {p_ref:.6g} Pa [Pa]", "gas.h5"


@figure("pressure", "gas pressure at probes against time and its power spectrum with the dominant frequency "
                    "(Hoomans et al. 1996 Figs 11 and 13; Sun et al. 2007 Fig 3)",
        lacks=_lacks_pressure)
def draw_pressure(run: RunData, options: PlotOptions):
    traces, ylabel, source = _pressure_traces(run)
    w, h = style.TRACE_SIZE_IN
    fig = style.new_figure(w, 1.75 * h)
    ax, ax_f = fig.subplots(2, 1, squeeze=True)
    for k, (label, t, y) in enumerate(traces):
        colour = style.LINE_COLOURS[k % len(style.LINE_COLOURS)]
        ax.plot(t, y, color=colour, label=label)
        spec = power_spectrum(t, y)
        if spec is None:
            continue
        f, psd, dominant = spec
        if not np.isfinite(dominant):  # a constant signal: no peak
            ax_f.plot(f, psd, color=colour, label=f"{label}: no peak")
            continue
        ax_f.plot(f, psd, color=colour, label=f"{label}: dominant {dominant:.3g} Hz")
        ax_f.axvline(dominant, color=colour, ls="--", lw=0.9)
        peak = float(psd[1:].max())
        ax_f.annotate(f"{dominant:.3g} Hz", (dominant, peak), xytext=(4, 2), textcoords="offset points",
                      color=colour, fontsize=style.RC["legend.fontsize"])
    ax.set_xlabel(style.label("time_s"))
    ax.set_ylabel(ylabel)
    ax.set_title(f"pressure ({source})")
    if len(traces) > 1 or source == "gas.h5":
        ax.legend(loc="best")
    ax_f.set_xlabel(style.label("frequency_Hz"))
    ax_f.set_ylabel("power spectral density [Pa²/Hz]")
    ax_f.set_title("power spectrum of the fluctuations")
    if ax_f.lines:
        positive = [ln.get_ydata() for ln in ax_f.lines if len(np.atleast_1d(ln.get_ydata())) > 2]
        if positive and all(np.nanmax(v) > 0 for v in positive):
            ax_f.set_yscale("log")
        ax_f.legend(loc="best")
    else:
        ax_f.text(0.5, 0.5, f"too few samples for a spectrum ({MIN_SAMPLES} needed)", transform=ax_f.transAxes,
                  ha="center", va="center")
    return fig
