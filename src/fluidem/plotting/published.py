"""Published numbers of the seed cases, keyed by built-in case name, for the report's
"quantity | published | this run" table.

One entry per number or outcome a reference publishes (transcribed from /reference via
SEED-CASES.md). ``summary_key`` names the ``summary.json`` key holding this run's value
(the first of ``summary_key`` and ``fallback_keys`` present); None means the run does not
measure it yet (the table says so). Time averages name ``window_key``, so the table says
over which window this run's mean was taken (Sun's are over 5–10 s). Yes/no outcomes
(a bubble forms) give ``yes_no`` texts; ``case_keys`` adds the case settings the published
outcome depends on (the restitution and friction of Hoomans' ideal and non-ideal
particles). A new built-in case adds its rows here under its case name; nothing else
changes.
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
    fallback_keys: tuple[str, ...] = ()  # other summary keys of the same quantity, tried in order
    window_key: str | None = None  # summary key of the [t0, t1] window of a time average
    window_text: str = "mean over"  # how this run's value relates to that window
    yes_no: tuple[str, str] | None = None  # texts for a true / false summary value
    case_keys: tuple[tuple[str, str], ...] = ()  # (symbol, dotted case key) shown beside this run's value
    details: tuple[tuple[str, str, float, str], ...] = ()  # (label, summary key, scale, unit) shown after a yes
    see: str = ""  # where the run shows it when no summary key measures it (e.g. a figure)

    def _value(self, summary: dict | None):
        for key in (self.summary_key, *self.fallback_keys):
            if key is not None and key in (summary or {}):
                return summary[key]
        return None

    def this_run(self, summary: dict | None, case: dict | None = None) -> str:
        """This run's value formatted like the published one, or why there is none."""
        if self.summary_key is None:
            return "not measured yet" + (f"; see {self.see}" if self.see else "")
        value = self._value(summary)
        settings = _settings(case, self.case_keys)
        if self.yes_no is not None and isinstance(value, (bool, int)) and value in (0, 1):
            text = self.yes_no[0 if value else 1]
            shown = [f"{lab} {summary[k] * sc:.3g} {unit}".rstrip() for lab, k, sc, unit in self.details
                     if value and _finite_number(summary.get(k))]
            return text + (f", {', '.join(shown)}" if shown else "") + settings
        if self.yes_no is not None and isinstance(value, str) and value.strip():
            return value.strip() + settings
        if not isinstance(value, (int, float)) or isinstance(value, bool) or not math.isfinite(value):
            return self.when_missing
        text = f"{value * self.scale:.{self.digits}g}" + (f" {self.unit}" if self.unit else "")
        if self.low is not None and self.high is not None:
            inside = self.low <= value <= self.high
            text += " (inside the published range)" if inside else " (outside the published range)"
        window = (summary or {}).get(self.window_key) if self.window_key else None
        if isinstance(window, (list, tuple)) and len(window) == 2 and all(
                isinstance(w, (int, float)) and not isinstance(w, bool) for w in window):
            text += f" ({self.window_text} {window[0]:.3g}–{window[1]:.3g} s)"
        return text + settings

    def published_text(self) -> str:
        main = f"{self.published} ({self.source})"
        return "; ".join([main, *self.others])


_HOOMANS_POUR_PACKING = {
    "quantity": "packing fraction of the settled bed (area fraction, 2D)", "published": "0.832 ± 0.010",
    "source": "Hoomans et al. 1996 §5.1", "summary_key": "packing_fraction", "digits": 3, "low": 0.822,
    "high": 0.842, "others": ("0.80 (Hogue & Newland)", "0.805 (Rosato et al.)")}
_ENERGY_ERROR = {"quantity": "energy conservation error", "published": "0.005 %",
                 "source": "Hoomans et al. 1996 §5.1, hard spheres, DT = 1e-4 s", "summary_key": "energy_error_rel",
                 "scale": 100.0, "unit": "%", "digits": 2}
_IDEALITY = (("e", "particles.contact.restitution"), ("μ", "particles.contact.friction"))  # Hoomans' ideal: e = 1, μ = 0
_BUBBLE_KEYS = {"summary_key": "bubble_detected", "fallback_keys": ("bubble",), "yes_no": ("bubble", "no bubble"),
                "when_missing": "—", "case_keys": _IDEALITY,  # summary.json keys: analysis/fluidised.py
                "details": (("largest", "bubble_max_area_m2", 1e4, "cm²"),)}
_SUN_AVERAGE = {"window_key": "averages_window_s"}  # Sun's numbers are 5–10 s means

# Sun et al. 2007 central jet: the published values of both readings of its inflow (tsuji-jet, tsuji-jet-background)
_SUN_JET = (
    PublishedValue("bulk coordination number", "about 1.2", "Sun et al. 2007 Fig 5, central jet",
                   summary_key="coordination_number_avg", **_SUN_AVERAGE),
    PublishedValue("multicontact ratio", "above 0.6 most of the time", "Sun et al. 2007 Fig 11, central jet",
                   summary_key="multicontact_ratio_avg", **_SUN_AVERAGE),
    PublishedValue("dominant frequency of the pressure drop 20 cm above the inlet",
                   "Fig 3 (not given numerically)", "Sun et al. 2007, central jet",
                   summary_key="pressure_20cm_dominant_frequency_Hz", unit="Hz", digits=3,
                   window_text="power spectrum over", **_SUN_AVERAGE),
    PublishedValue("largest contact force / drag (cell means; this run: the largest cell's, averaged over time)", "up to 100",
                   "Sun et al. 2007 Fig 7, corners beside the jet",
                   summary_key="contact_drag_ratio_max_avg", digits=3, when_missing="not measured; see the forces figure",
                   **_SUN_AVERAGE),
)

PUBLISHED: dict[str, tuple[PublishedValue, ...]] = {
    # Hoomans et al. 1996 §5.1 with soft spheres: the packing compares; the energy error does not
    # (contacts dissipate by design)
    "pour": (
        PublishedValue(**_HOOMANS_POUR_PACKING),
        PublishedValue(**_ENERGY_ERROR, when_missing="n/a for soft spheres (contacts dissipate by design)"),
    ),
    # Hoomans et al. 1996, hard spheres (2D)
    "hoomans-pour": (
        PublishedValue(**_HOOMANS_POUR_PACKING),
        PublishedValue(**_ENERGY_ERROR),
    ),
    "hoomans-tsuji": (
        PublishedValue("bubble above the jet (Tsuji's set-up, jet 2.6 m/s superficial)",
                       "no bubble; the voidage just above the jet slightly raised",
                       "Hoomans et al. 1996 §5.2 (confirmed by their experiment with 4 mm beads)", **_BUBBLE_KEYS),
    ),
    "hoomans-orifice": (
        PublishedValue("bubble at the orifice (jet 10 u_mf)",
                       "bubble (turning into a slug) for non-ideal particles, e = e_w = 0.9, μ = μ_w = 0.3; "
                       "none for ideal particles, e = 1, μ = 0",
                       "Hoomans et al. 1996 §5.3.1, Figs 10–11", **_BUBBLE_KEYS),
    ),
    "hoomans-slug": (
        PublishedValue("bubbles / slugs from homogeneous inflow (1.75 u_mf)",
                       "slugs and bubbles for non-ideal particles, e = e_w = 0.9, μ = μ_w = 0.3; none (homogeneous "
                       "expansion) for ideal particles, e = 1, μ = 0",
                       "Hoomans et al. 1996 §5.3.2, Figs 12–13", **_BUBBLE_KEYS),
    ),
    "hoomans-experiment": (
        PublishedValue("bubble at the orifice (200 ms pulse, 5 u_mf)", "a bubble forms at the orifice",
                       "Hoomans et al. 1996 §5.4, Fig 15 (experiment and simulation)",
                       others=("simulated bubble larger than the experiment's, with satellite bubbles ahead of it",),
                       **_BUBBLE_KEYS),
    ),
    # Sun et al. 2007 (soft spheres, 2D, one layer): the built-in cases tsuji-jet (and tsuji-jet-background, the
    # same bed with the rest of the bottom at u_mf) and goldschmidt.
    # Sun's numbers are means over 5-10 s; summary.json holds this run's means over that window
    # (or over the second half of a shorter run, which the table says).
    "tsuji-jet": _SUN_JET,
    "tsuji-jet-background": _SUN_JET,
    "goldschmidt": (
        PublishedValue("mean particle height", "8.9 cm (TF-DEM, cell-averaged drag)",
                       "Sun et al. 2007 Fig 9, uniform inflow, 5–10 s",
                       others=("9.1 cm (TF-DEM, per-particle drag)", "9.16 cm (two-fluid model)",
                               "11.4 cm (experiment, Goldschmidt et al.)"),
                       summary_key="mean_particle_height_avg_m", scale=100.0, unit="cm", digits=3, **_SUN_AVERAGE),
        PublishedValue("bulk coordination number", "about 0.5", "Sun et al. 2007 Fig 5, uniform inflow",
                       summary_key="coordination_number_avg", **_SUN_AVERAGE),
        PublishedValue("multicontact ratio", "about 0.3", "Sun et al. 2007 Fig 11, uniform inflow",
                       summary_key="multicontact_ratio_avg", **_SUN_AVERAGE),
        PublishedValue("largest contact force / drag (cell means; this run: the largest cell's, averaged over time)", "at most 15",
                       "Sun et al. 2007 Fig 12, uniform inflow",
                       summary_key="contact_drag_ratio_max_avg", digits=3, when_missing="not measured; see the forces figure",
                       **_SUN_AVERAGE),
    ),
}


def _finite_number(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)


def _settings(case: dict | None, keys: tuple[tuple[str, str], ...]) -> str:
    """' (this run: e = 0.9, μ = 0.3)' from the dotted ``keys`` of ``case``; '' when none is there."""
    shown = []
    for symbol, dotted in keys:
        node = case
        for part in dotted.split("."):
            node = node.get(part) if isinstance(node, dict) else None
        if isinstance(node, (int, float)) and not isinstance(node, bool):
            shown.append(f"{symbol} = {node:g}")
    return f" (this run: {', '.join(shown)})" if shown else ""


def comparison_rows(case_name: str, summary: dict | None, case: dict | None = None) -> list[tuple[str, str, str]]:
    """(quantity, published, this run) rows for a built-in case; [] for other cases. ``case`` (the run's
    case.toml as a dict) adds the settings an outcome depends on."""
    return [(v.quantity, v.published_text(), v.this_run(summary, case)) for v in PUBLISHED.get(case_name, ())]
