"""The mean particle height above the floor against time (Sun et al. 2007): from probes.csv, else the snapshots."""
from __future__ import annotations

import numpy as np

from .. import style
from ..run import RunData
from ._shared import PlotOptions, figure, trace_axes
from .snapshots import view_of

BED_HEIGHT_COLUMNS = ("mean_bed_height_m", "bed_height_m")


def _lacks_bed_height(run: RunData) -> str | None:
    if run.lacks_probes(*BED_HEIGHT_COLUMNS, any_of=True) is None:
        return None
    why = run.lacks_snapshots()
    if why is None and len(run.snapshot_times) < 2:
        why = "the run has a single snapshot"
    return None if why is None else f"no bed-height probe and {why}"


@figure("bed_height", "mean particle height above the floor against time (Sun et al. 2007)",
        lacks=_lacks_bed_height)
def draw_bed_height(run: RunData, options: PlotOptions):
    fig, (ax,) = trace_axes()
    if run.lacks_probes(*BED_HEIGHT_COLUMNS, any_of=True) is None:
        p = run.probes
        for c in BED_HEIGHT_COLUMNS:
            if c in p:
                ax.plot(p["time_s"], p[c], label=style.label(c).split(" [")[0] + " (probes)")
        ylabel = style.label(next(c for c in BED_HEIGHT_COLUMNS if c in p))
    else:
        first = run.snapshot(0)
        view = view_of(run, first)
        t, h = [], []
        for time, snap in run.iter_snapshots(("position",)):
            if "position" in snap and len(snap["position"]):
                t.append(time)
                h.append(float(np.mean(view.height(snap["position"]))))
        ax.plot(t, h, marker="o", ms=3, label="mean particle height (snapshots)")
        ylabel = "mean particle height [m]"
    ax.set_ylabel(ylabel)
    ax.set_title("bed height")
    ax.legend(loc="best")
    return fig
