"""Segregation of a bed of several species against time: each species' mean height, the segregation index
and Lacey's mixing index (``analysis.mixing``), from probes.csv."""
from __future__ import annotations

from ..run import RunData
from ._shared import PlotOptions, figure, trace_axes


def _height_columns(run: RunData) -> list[str]:
    return [c for c in run.probe_columns() if c.startswith("height_") and c.endswith("_m")]


def _lacks_mixing(run: RunData) -> str | None:
    why = run.lacks_probes("segregation_index")
    if why is not None:
        return f"{why} (a bed of one species has no segregation index)"
    return None


def _several_species(run: RunData) -> bool:
    try:
        return len(run.species_names) > 1
    except Exception:  # noqa: BLE001 - no readable case: let ``lacks`` say what is missing
        return True


@figure("segregation", "mean height of each species and the segregation and Lacey mixing indices against time",
        lacks=_lacks_mixing, applies=_several_species)
def draw_segregation(run: RunData, options: PlotOptions):
    p = run.probes
    t = p["time_s"]
    fig, (top, bottom) = trace_axes(2)
    for c in _height_columns(run):
        top.plot(t, p[c], label=c[len("height_"):-len("_m")])
    top.set_ylabel("mean height [m]")
    top.set_title("species heights")
    top.legend(loc="best")
    names = [c[len("height_"):-len("_m")] for c in _height_columns(run)]
    label = f"segregation index 2(h_a − h_b)/(h_a + h_b), a = {names[0]}, b = {names[1]}" if len(names) > 1 \
        else "segregation index"
    bottom.plot(t, p["segregation_index"], label=label)
    if "lacey_index" in p:
        bottom.plot(t, p["lacey_index"], label="Lacey mixing index (0 segregated, 1 random)")
    bottom.axhline(0.0, color="0.6", lw=0.8)
    bottom.set_ylabel("index [-]")
    bottom.legend(loc="best", fontsize="small")
    return fig
