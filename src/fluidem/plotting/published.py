"""Published numbers of the seed cases, keyed by built-in case name, for the report's
"quantity | published | this run" table.

One entry per number a reference publishes (transcribed from /reference via
SEED-CASES.md). ``summary_key`` names the ``summary.json`` key holding this run's value;
None means the run does not measure it yet (the table says so). A new built-in case
adds its rows here under its case name; nothing else changes.
"""
from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class PublishedValue:
    quantity: str
    published: str  # as the paper states it, uncertainty included
    source: str  # reference and section/figure/table
    summary_key: str | None = None  # where this run's value is in summary.json
    scale: float = 1.0  # this run's value × scale is shown (e.g. 100 for %)
    unit: str = ""  # unit of the shown value
    digits: int = 3  # significant digits of the shown value
    others: tuple[str, ...] = ()  # other published values of the same quantity
    when_missing: str = "not measured by this run"
    low: float | None = None  # published range in summary units (shown values inside it are marked)
    high: float | None = None

    def this_run(self, summary: dict | None) -> str:
        """This run's value formatted like the published one, or why there is none."""
        if self.summary_key is None:
            return "not measured yet"
        value = (summary or {}).get(self.summary_key)
        if not isinstance(value, (int, float)) or isinstance(value, bool) or not math.isfinite(value):
            return self.when_missing
        text = f"{value * self.scale:.{self.digits}g}" + (f" {self.unit}" if self.unit else "")
        if self.low is not None and self.high is not None:
            inside = self.low <= value <= self.high
            text += " (inside the published range)" if inside else " (outside the published range)"
        return text

    def published_text(self) -> str:
        main = f"{self.published} ({self.source})"
        return "; ".join([main, *self.others])


PUBLISHED: dict[str, tuple[PublishedValue, ...]] = {
    "pour": (
        PublishedValue(
            "packing fraction of the settled bed (area fraction, 2D)", "0.832 ± 0.010",
            "Hoomans et al. 1996 §5.1", summary_key="packing_fraction", digits=3, low=0.822, high=0.842,
            others=("0.80 (Hogue & Newland)", "0.805 (Rosato et al.)")),
        PublishedValue(
            "energy conservation error", "0.005 %", "Hoomans et al. 1996 §5.1, hard spheres, DT = 1e-4 s",
            summary_key="energy_error_rel", scale=100.0, unit="%", digits=2,
            when_missing="n/a for soft spheres (contacts dissipate by design)"),
    ),
    # Sun et al. 2007 (soft spheres, 2D): the built-in cases tsuji-jet and goldschmidt.
    # Sun's numbers are averages over 5-10 s: give them a summary_key once the run reports
    # such an average (the final instantaneous value is not comparable).
    "tsuji-jet": (
        PublishedValue("bulk coordination number", "about 1.2", "Sun et al. 2007, central jet, 5–10 s"),
        PublishedValue("multicontact ratio", "above 0.6 most of the time", "Sun et al. 2007, central jet"),
        PublishedValue("largest contact force / drag", "up to 100", "Sun et al. 2007, corners beside the jet"),
    ),
    "goldschmidt": (
        PublishedValue("mean particle height, 5–10 s", "8.9 cm (TF-DEM, cell-averaged drag)",
                       "Sun et al. 2007, uniform inflow",
                       others=("9.1 cm (per-particle drag)", "9.16 cm (two-fluid model)", "11.4 cm (experiment)")),
        PublishedValue("bulk coordination number", "about 0.5", "Sun et al. 2007, uniform inflow, 5–10 s"),
        PublishedValue("multicontact ratio", "about 0.3", "Sun et al. 2007, uniform inflow"),
        PublishedValue("largest contact force / drag", "at most 15", "Sun et al. 2007, uniform inflow"),
    ),
}


def comparison_rows(case_name: str, summary: dict | None) -> list[tuple[str, str, str]]:
    """(quantity, published, this run) rows for a built-in case; [] for other cases."""
    return [(v.quantity, v.published_text(), v.this_run(summary)) for v in PUBLISHED.get(case_name, ())]
