"""The flotsam/jetsam chart of Di Renzo & Di Maio 2012 (Figs 1 and 2), with binary systems placed on it.

Not a figure of a run: ``draw_segregation_chart(results)`` takes ``SegregationResult`` objects
(``fluidem.analysis.segregation``) and returns a two-panel Figure. Left, the chapter's Fig 1: the
equilibrium lines of eq. 19 in the plane of d = D_1/D_2 and s = rho_2/rho_1 at several compositions
x_1, the two segregation regions labelled with their flotsam. Right, the plane of Fig 2: d_bar =
D_bar/D_2 and s_bar = rho_2/rho_bar, where eq. 18 is one line for every composition. Each system is
drawn with the symbols of Fig 2 (open circle: the larger species is flotsam; filled: the smaller;
cross: mixed), in the chapter's labelling (species 1 the smaller; a system given the other way round
is relabelled, x_1 with it), with its own composition's line dashed in its colour on the left.
"""
from __future__ import annotations

import numpy as np

from ...analysis.segregation import (
    CHART_COMPOSITIONS,
    FIG1_VOIDAGE,
    SegregationResult,
    equilibrium_density_ratio,
    equilibrium_mean_density_ratio,
    segregation_criterion,
)
from ...errors import CaseError
from .. import style

CHART_SIZE_IN = (10.0, 4.6)
COMPOSITION_GREYS = ("#C8C8C8", "#A0A0A0", "#787878", "#505050", "#282828")  # light: little species 1


def chart_convention(result: SegregationResult) -> tuple[SegregationResult, bool]:
    """``result`` with species 1 the smaller (the denser at equal size), as the chapter labels them;
    and whether the species were swapped to get there (x_1 becomes 1 - x_1)."""
    (d1, d2), (r1, r2) = result.diameters, result.densities
    if d1 < d2 or (d1 == d2 and r1 >= r2):
        return result, False
    return segregation_criterion((d2, d1), (r2, r1), 1.0 - result.composition, result.voidage,
                                 viscosity=result.viscosity, gravity=result.gravity,
                                 tolerance=result.tolerance), True


def _marker(result: SegregationResult, colour: str) -> dict:
    """Fig 2's symbols, for a result in the chart's labelling."""
    if result.flotsam == "mixed":
        return dict(marker="x", color=colour, markersize=8, markeredgewidth=2.0, linestyle="none")
    filled = result.flotsam == 1  # species 1 = the smaller
    return dict(marker="o", markersize=8, markeredgewidth=1.6, markeredgecolor=colour,
                markerfacecolor=colour if filled else "white", linestyle="none")


def _verdict(result: SegregationResult) -> str:
    if result.flotsam == "mixed":
        return "mixed"
    return f"flotsam {result.flotsam} ({'smaller' if result.flotsam == 1 else 'larger'})"


def draw_segregation_chart(results=(), voidage: float | None = None, compositions=CHART_COMPOSITIONS):
    """The segregation chart (Di Renzo & Di Maio 2012 Figs 1-2, eqs 18-19) with ``results`` on it.

    Parameters
    ----------
    results : SegregationResult objects to place on the chart (any number, all at the chart's voidage).
    voidage : ε of the equilibrium lines; default the results' voidage, else 0.4 (Fig 1's caption).
    compositions : x_1 of the lines drawn on the left panel (the chapter's Fig 1 does not state its
        own; default 0.1, 0.3, 0.5, 0.7, 0.9).

    Returns a ``matplotlib.figure.Figure``; build and save it inside ``style.context()``.
    """
    results = list(results)
    for i, r in enumerate(results):
        if not isinstance(r, SegregationResult):
            raise CaseError(f"results[{i}] = {r!r}: give SegregationResult objects (segregation_criterion)")
    if voidage is None:
        voidage = results[0].voidage if results else FIG1_VOIDAGE
    eps = float(voidage)
    for i, r in enumerate(results):
        if r.voidage != eps:
            raise CaseError(f"results[{i}].voidage = {r.voidage!r}: every system on the chart needs the chart's "
                            f"voidage, {eps!r}")
    compositions = [float(x) for x in compositions]
    equilibrium_density_ratio(1.0, 0.5, eps)  # checks the voidage: CaseError naming it
    for x in compositions:
        equilibrium_density_ratio(1.0, x, eps)  # checks each composition

    charted = [chart_convention(r) for r in results]
    fig = style.new_figure(*CHART_SIZE_IN)
    ax, axm = fig.subplots(1, 2)
    d = np.linspace(1e-3, 1.0, 400)

    greys = COMPOSITION_GREYS if len(compositions) <= len(COMPOSITION_GREYS) else None
    for k, x in enumerate(sorted(compositions)):
        grey = greys[k] if greys else str(0.75 - 0.6 * k / max(1, len(compositions) - 1))
        s = equilibrium_density_ratio(d, x, eps)
        ax.plot(d, s, color=grey, lw=1.6)
        ax.annotate(f"$x_1$ = {x:g}", (d[0], s[0]), xytext=(3, 3), textcoords="offset points", fontsize=7,
                    color="#404040", bbox=dict(facecolor="white", edgecolor="none", pad=0.4, alpha=0.8))

    s_top = max([1.0] + [r.density_ratio for r, _ in charted])
    sbar_top = max([1.0] + [r.mean_density_ratio for r, _ in charted])
    db = np.linspace(0.0, 1.0, 50)
    axm.plot(db, equilibrium_mean_density_ratio(np.maximum(db, 1e-12), eps), color="#282828", lw=1.6)
    axm.annotate(r"$\bar s = 1-\varepsilon+\varepsilon\bar d$", (0.35, 1.0 - eps + 0.35 * eps), xytext=(-12, 10),
                 textcoords="offset points", rotation=0, fontsize=8, color="#282828", ha="center")

    for i, (r, swapped) in enumerate(charted):
        colour = style.LINE_COLOURS[i % len(style.LINE_COLOURS)]
        if not any(abs(r.composition - x) < 1e-12 for x in compositions):
            ax.plot(d, equilibrium_density_ratio(d, r.composition, eps), color=colour, lw=1.0, ls="--")
        tag = f"{i + 1}"
        label = (f"system {tag}: $x_1$ = {r.composition:.3g}, {_verdict(r)}"
                 + (" (species relabelled: 1 = smaller)" if swapped else ""))
        ax.plot([r.size_ratio], [r.density_ratio], **_marker(r, colour), label=label)
        axm.plot([r.mean_size_ratio], [r.mean_density_ratio], **_marker(r, colour))
        for a, (px, py) in ((ax, (r.size_ratio, r.density_ratio)), (axm, (r.mean_size_ratio, r.mean_density_ratio))):
            a.annotate(tag, (px, py), xytext=(6, 4), textcoords="offset points", fontsize=8, color=colour)

    box = dict(boxstyle="round,pad=0.3", facecolor="white", edgecolor="#909090", linewidth=0.6)
    for a in (ax, axm):
        a.text(0.03, 0.97, "species 1 (smaller, denser)\nis flotsam", transform=a.transAxes, ha="left", va="top",
               fontsize=8, bbox=box)
        a.text(0.97, 0.03, "species 2 (larger, lighter)\nis flotsam", transform=a.transAxes, ha="right",
               va="bottom", fontsize=8, bbox=box)
    ax.set_xlim(0.0, 1.03)
    ax.set_ylim(0.0, 1.05 * s_top)
    ax.set_xlabel(r"size ratio $d = D_1/D_2$ [–]")
    ax.set_ylabel(r"density ratio $s = \rho_2/\rho_1$ [–]")
    ax.set_title(f"equilibrium lines, eq. 19 (ε = {eps:g}; Di Renzo & Di Maio 2012 Fig. 1)")
    axm.set_xlim(0.0, 1.03)
    axm.set_ylim(0.0, 1.05 * sbar_top)
    axm.set_xlabel(r"mean size ratio $\bar d = \bar D/D_2$ [–]")
    axm.set_ylabel(r"mean density ratio $\bar s = \rho_2/\bar\rho$ [–]")
    axm.set_title(f"one line for every composition, eq. 18 (ε = {eps:g}; Fig. 2)")

    from matplotlib.lines import Line2D

    if results:
        handles, _ = ax.get_legend_handles_labels()
        symbols = [Line2D([], [], **_marker(_Flotsam(2), "#303030"), label="larger species is flotsam"),
                   Line2D([], [], **_marker(_Flotsam(1), "#303030"), label="smaller species is flotsam"),
                   Line2D([], [], **_marker(_Flotsam("mixed"), "#303030"), label="mixed (on its line)")]
        fig.legend(handles=handles + symbols, loc="outside lower center", ncol=2, fontsize=7)
    return fig


class _Flotsam:
    """A stand-in with only ``flotsam``, for the legend's symbols."""

    def __init__(self, flotsam):
        self.flotsam = flotsam
