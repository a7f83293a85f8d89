"""Contacts against time: coordination number and contact counts, and the bulk coordination number with the
multicontact ratio (Sun et al. 2007 Figs 5 and 11)."""
from __future__ import annotations

import numpy as np

from ...errors import CaseError
from .. import style
from ..run import RunData, Unavailable
from ._shared import PlotOptions, averaging_window, figure, trace_axes


@figure("contacts", "coordination number and number of contacts against time (Sun et al. 2007)",
        lacks=lambda run: run.lacks_probes("coordination", "contacts", "wall_contacts", any_of=True))
def draw_contacts(run: RunData, options: PlotOptions):
    p = run.probes
    t = p["time_s"]
    rows = [["coordination"]] if "coordination" in p else []
    counts = [c for c in ("contacts", "wall_contacts") if c in p]
    if counts:
        rows.append(counts)
    fig, axes = trace_axes(len(rows))
    for ax, cols in zip(axes, rows):
        for c in cols:
            ax.plot(t, p[c], label=style.label(c).split(" [")[0])
        ax.set_ylabel(style.label(cols[0]) if len(cols) == 1 else "contacts [–]")
        if len(cols) > 1:
            ax.legend(loc="best")
    axes[0].set_title("contacts")
    return fig


def _summary_window(run: RunData) -> tuple[float, float] | None:
    """The window of the time averages in summary.json (``averages_window_s``), or None."""
    w = (run.summary or {}).get("averages_window_s")
    try:
        t0, t1 = (float(x) for x in w)
    except (TypeError, ValueError):
        return None
    return (t0, t1) if np.isfinite(t0) and np.isfinite(t1) and t0 < t1 else None


MULTICONTACT_COLUMNS = ("coordination", "multicontact_ratio")


@figure("multicontact", "bulk coordination number (mean N_c) and multicontact ratio (particles with N_c > 1 over "
                        "those with N_c ≥ 1) against time, with their means over the averaging window "
                        "(Sun et al. 2007 Figs 5 and 11)",
        lacks=lambda run: run.lacks_probes(*MULTICONTACT_COLUMNS))
def draw_multicontact(run: RunData, options: PlotOptions):
    p = run.probes
    t = p["time_s"]
    ok = np.isfinite(t)
    if not ok.any():
        raise Unavailable("probes.csv has no finite times")
    window = options.window or _summary_window(run)
    try:
        t0, t1, mask = averaging_window(t[ok], window, what="probe row")
    except CaseError as err:
        raise Unavailable(str(err)) from None
    fig, axes = trace_axes(2)
    titles = ("bulk coordination number", "multicontact ratio")
    for ax, col, title in zip(axes, MULTICONTACT_COLUMNS, titles):
        y = p[col][ok]
        ax.plot(t[ok], y, label=style.label(col).split(" [")[0])
        ax.axvspan(t0, t1, color="0.5", alpha=0.12, lw=0)
        vals = y[mask][np.isfinite(y[mask])]
        if vals.size:
            mean = float(vals.mean())
            ax.hlines(mean, t0, t1, colors="k", linestyles="--", lw=1.2,
                      label=f"mean over {t0:.3g}–{t1:.3g} s: {mean:.3g}")
        ax.set_ylabel(style.label(col))
        ax.set_title(title)
        ax.legend(loc="best")
    return fig
