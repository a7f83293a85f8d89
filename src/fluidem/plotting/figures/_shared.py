"""What the figure modules share: the registry of figures, the plot options, time selection and axes.

A figure is a registered ``FigureSpec``: it says why a run cannot have it (``lacks(run) -> str |
None``, a one-line reason such as "the run has no probes.csv") and draws it (``draw(run, options) ->
Figure``). ``render`` walks the registry in order and yields a figure or the reason it was skipped.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from ...analysis.fluidised import averaging_window as sun_window
from ...errors import CaseError
from ...registry import Registry
from .. import style
from ..run import RunData, Unavailable

COLOR_MODES = ("height", "speed", "species", "nc")
DEFAULT_PANELS = 4


@dataclass
class PlotOptions:
    """Choices shared by the figures.

    times : snapshot times [s] to draw (nearest snapshot each); None: ``DEFAULT_PANELS``
        evenly spaced, first and last included. Used by the particle and voidage maps.
    color : "height" (band of initial height), "speed" (|v| [m/s]), "species" or "nc" (the
        particle's number of contacting particles N_c, classes 0, 1, 2, 3, ≥4; Sun et al.
        2007 Figs 6/10; needs the snapshots' ``contacts`` field).
    bands : number of initial-height bands.
    overlay : draw the particles over the gas voidage maps.
    window : (t0, t1) [s] of the time averages (gas-field maps, force maps, the mean lines of
        the multicontact figure); None: 5-10 s when the run covers it (Sun et al. 2007),
        else the second half of the run.
    """

    times: list[float] | None = None
    color: str = "height"
    bands: int = 6
    overlay: bool = True
    window: tuple[float, float] | None = None

    def __post_init__(self):
        if self.color not in COLOR_MODES:
            raise CaseError(f"--color {self.color!r}: allowed are {', '.join(COLOR_MODES)}")
        if int(self.bands) < 1:
            raise CaseError(f"--bands {self.bands}: give a whole number of at least 1")
        if self.window is not None:
            try:
                t0, t1 = (float(t) for t in self.window)
            except (TypeError, ValueError):
                raise CaseError(f"--window {self.window!r}: give two times in seconds, T0,T1") from None
            if not (np.isfinite(t0) and np.isfinite(t1) and t0 < t1):
                raise CaseError(f"--window {t0:g},{t1:g}: give finite times with T0 < T1 [s]")
            self.window = (t0, t1)


@dataclass(frozen=True)
class FigureSpec:
    name: str
    description: str
    lacks: Callable[[RunData], str | None]
    draw: Callable[[RunData, PlotOptions], object]
    stem: Callable[[PlotOptions], str] | None = None
    # whether the figure belongs to this kind of run at all (None: every run); one that does not is left out
    # without a note, unless asked for by name (``--only``)
    applies: Callable[[RunData], bool] | None = None

    def file_stem(self, options: PlotOptions) -> str:
        return self.stem(options) if self.stem else self.name


figures: Registry[FigureSpec] = Registry("figure")


def figure(name: str, description: str, lacks: Callable[[RunData], str | None], stem=None, applies=None):
    """Register the decorated ``draw(run, options) -> Figure`` as figure ``name``."""

    def deco(draw):
        figures.register(name)(FigureSpec(name, description, lacks, draw, stem, applies))
        return draw

    return deco


def parse_names(text: str | None) -> list[str] | None:
    """``"energy,contacts"`` → the names, checked against the registry (CaseError otherwise)."""
    if text is None:
        return None
    names = [n.strip() for n in str(text).split(",") if n.strip()]
    for n in names:
        if n not in figures:
            try:
                figures.get(n)
            except KeyError as err:
                raise CaseError(f"--only: {err.args[0]}") from None
    return names


def render(run: RunData, options: PlotOptions, only: list[str] | None = None):
    """Yield (spec, figure or None, reason or None) for every registered figure, in order."""
    for name, spec in figures.items():
        if only is not None and name not in only:
            continue
        if only is None and spec.applies is not None and not spec.applies(run):
            continue
        why = spec.lacks(run)
        if why is None:
            try:
                yield spec, spec.draw(run, options), None
                continue
            except Unavailable as err:
                why = str(err)
        yield spec, None, why


# ---------------------------------------------------------------- time selection
def parse_window(text: str | None) -> tuple[float, float] | None:
    """``"5,10"`` → (5.0, 10.0); CaseError unless two numbers T0 < T1."""
    if text is None:
        return None
    items = [t for t in str(text).split(",") if t.strip()]
    try:
        values = [float(t) for t in items]
    except ValueError:
        values = []
    if len(values) != 2:
        raise CaseError(f"--window {text!r}: give two times in seconds, e.g. --window 5,10")
    return values[0], values[1]


def parse_times(text: str | None) -> list[float] | None:
    """``"0,0.5,1"`` → [0.0, 0.5, 1.0]; CaseError naming an item that is not a number."""
    if text is None:
        return None
    out = []
    for item in str(text).split(","):
        if not item.strip():
            continue
        try:
            t = float(item)
        except ValueError:
            raise CaseError(f"--times {item.strip()!r}: not a number; give seconds separated by commas, "
                            f"e.g. --times 0,0.5,1.0") from None
        if not np.isfinite(t):
            raise CaseError(f"--times {item.strip()!r}: give finite times in seconds")
        out.append(t)
    if not out:
        raise CaseError(f"--times {text!r}: give at least one time in seconds")
    return out


def select_snapshots(available: np.ndarray, requested: list[float] | None,
                     count: int = DEFAULT_PANELS) -> list[int]:
    """Indices of the snapshots to draw.

    ``requested=None``: ``count`` evenly spaced, first and last included. Otherwise the
    nearest snapshot to each requested time, in the order given, without repeats; a time
    further than half a snapshot interval outside the run is a CaseError.
    """
    available = np.asarray(available, float)
    n = len(available)
    if requested is None:
        if n <= count:
            return list(range(n))
        return sorted({int(round(k)) for k in np.linspace(0, n - 1, count)})
    gaps = np.diff(available)
    tol = 0.5 * float(np.median(gaps)) if n > 1 else 0.0
    tol = max(tol, 1e-9 * max(abs(available[-1]), 1.0))
    out: list[int] = []
    for t in requested:
        if t < available[0] - tol or t > available[-1] + tol:
            raise CaseError(f"--times {t:g}: outside the snapshots of this run, which run from "
                            f"{available[0]:g} s to {available[-1]:g} s ({n} snapshots)")
        k = int(np.argmin(np.abs(available - t)))
        if k not in out:
            out.append(k)
    return out


def averaging_window(times: np.ndarray, requested: tuple[float, float] | None = None,
                     what: str = "gas-field snapshot") -> tuple[float, float, np.ndarray]:
    """(t0, t1, mask of ``times`` inside) of a time average over samples at ``times`` (sorted) [s].

    ``requested=None``: 5-10 s when the samples cover it (Sun et al. 2007 Figs 4/8/13),
    else the second half of the samples' span, as ``analysis.fluidised.averaging_window`` chooses
    it. A requested window with no sample in it is a CaseError naming ``what`` the samples are.
    """
    times = np.asarray(times, float)
    tol = 1e-9 * max(abs(times[-1]), 1.0)
    if requested is None:
        t0, t1 = sun_window(float(times[-1]), t_start=float(times[0]))
    else:
        t0, t1 = requested
    mask = (times >= t0 - tol) & (times <= t1 + tol)
    if not mask.any():
        raise CaseError(f"--window {t0:g},{t1:g}: no {what} in it; the {what}s run from "
                        f"{times[0]:g} s to {times[-1]:g} s ({len(times)} of them)")
    return float(t0), float(t1), mask


# ---------------------------------------------------------------- axes
def time_title(t: float) -> str:
    """A panel title for time ``t`` [s]: to the millisecond, three significant digits below 1 ms."""
    return f"t = {t:.3f} s" if abs(t) >= 1e-3 or t == 0 else f"t = {t:.3g} s"


def trace_axes(nrows: int = 1):
    """(figure, axes (nrows,)) of traces against time stacked over a shared time axis."""
    w, h = style.TRACE_SIZE_IN
    fig = style.new_figure(w, h if nrows == 1 else 0.6 * h * nrows + 0.6)
    axes = fig.subplots(nrows, 1, sharex=True, squeeze=False)[:, 0]
    axes[-1].set_xlabel(style.label("time_s"))
    return fig, axes


def map_axes(run: RunData, npanels: int, colourbar: bool = True):
    """A row of ``npanels`` map axes sized to the gas domain, the x–y plane of the grid."""
    g = run.gas
    fig, axes = map_grid(g["x_faces"], g["y_faces"], 1, npanels, 1.6 if colourbar else 0.7)
    return fig, axes[0]


def map_grid(xf, yf, nrows: int, ncols: int, extra_w: float = 1.6, extra_h: float = 0.8, ylim=None):
    """``nrows`` × ``ncols`` map axes over x faces ``xf`` and y faces ``yf`` [m] (y limited to ``ylim``):
    (figure, axes (nrows, ncols)); the x–y plane of the grid, equal aspect."""
    y0, y1 = (yf[0], yf[-1]) if ylim is None else ylim
    aspect = (xf[-1] - xf[0]) / (y1 - y0)
    panel_w = float(np.clip(style.PANEL_HEIGHT_IN * aspect, 1.4, 8.0))
    # "compressed": constrained layout for fixed-aspect panels (plain constrained layout narrows them
    # after placing their labels, which can push the y label off the edge)
    fig = style.new_figure(ncols * panel_w + extra_w, nrows * style.PANEL_HEIGHT_IN + extra_h, layout="compressed")
    axes = fig.subplots(nrows, ncols, sharex=True, sharey=True, squeeze=False)
    for (r, c), ax in np.ndenumerate(axes):
        ax.set_xlim(xf[0], xf[-1])
        ax.set_ylim(y0, y1)
        ax.set_aspect("equal")
        ax.grid(False)
        if r == nrows - 1:
            ax.set_xlabel("x [m]")
        if c == 0:
            ax.set_ylabel("y [m]")
    return fig, axes
