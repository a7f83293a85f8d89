"""The figures of one run, each a registered ``FigureSpec``: what it needs and how it is drawn.

A spec says why a run cannot have the figure (``lacks(run) -> str | None``, a one-line
reason such as "the run has no probes.csv") and draws it (``draw(run, options) ->
Figure``). ``render`` walks the registry in order and yields a figure or the reason it
was skipped; ``plot_run`` writes them. A new quantity (gas voidage maps, pressure
probes, segregation indices) is one more decorated function here, nothing else.

Registered today: ``snapshots`` (particles at chosen times, Hoomans et al. 1996 Figs
8/10/12; coloured by N_c, Sun et al. 2007 Figs 6/10), ``energy`` (budget against time,
with the dissipated energy of hard-sphere runs, Hoomans Fig 9), ``contacts``
(coordination number and contacts, Sun et al. 2007), ``multicontact`` (bulk coordination
number and multicontact ratio, Sun Figs 5/11), ``bed_height`` (mean particle height, Sun 2007),
``pressure`` (pressure probes against time and their power spectrum with the dominant
frequency, Hoomans Figs 11/13 and Sun Fig 3: probe columns ``pressure*`` / ``*_Pa``, else
the gas field 0.2 m above the bottom centre), ``voidage`` (gas voidage maps at chosen
times with the particles over them, Hoomans Figs 10/12) and ``solids_fraction``
(time-averaged solids fraction map, Sun Figs 4/8/13) and ``forces`` (contact and gas
force per particle weight and their ratio on the gas grid, Sun Figs 7/12, from the
particle snapshots' ``contact_force`` and ``gas_force``). The gas figures read ``gas.h5``
(``fluidem.io.gas_fields``).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from ..errors import CaseError
from ..registry import Registry
from . import style
from .run import RunData, Unavailable

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

    def file_stem(self, options: PlotOptions) -> str:
        return self.stem(options) if self.stem else self.name


figures: Registry[FigureSpec] = Registry("figure")


def figure(name: str, description: str, lacks: Callable[[RunData], str | None], stem=None):
    """Register the decorated ``draw(run, options) -> Figure`` as figure ``name``."""

    def deco(draw):
        figures.register(name)(FigureSpec(name, description, lacks, draw, stem))
        return draw

    return deco


@dataclass
class PlotResult:
    written: list[Path] = field(default_factory=list)
    skipped: list[tuple[str, str]] = field(default_factory=list)  # (figure name, reason)


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
        why = spec.lacks(run)
        if why is None:
            try:
                yield spec, spec.draw(run, options), None
                continue
            except Unavailable as err:
                why = str(err)
        yield spec, None, why


def plot_run(run: RunData, out_dir: Path, options: PlotOptions | None = None, formats=("png",),
             only: list[str] | None = None) -> PlotResult:
    """Write every figure that applies to ``run`` into ``out_dir``; the others are listed as skipped."""
    options = options or PlotOptions()
    # bad --times / --window: an error before anything is written
    if options.times is not None and run.lacks_snapshots() is None:
        select_snapshots(run.snapshot_times, options.times)
    elif options.times is not None and run.lacks_gas() is None and (only is None or "voidage" in only):
        select_snapshots(run.gas_times, options.times)
    if options.window is not None and run.lacks_gas() is None and (only is None or "solids_fraction" in only):
        averaging_window(run.gas_times, options.window)
    if options.window is not None and (only is None or "forces" in only) and _lacks_forces(run) is None:
        averaging_window(run.snapshot_times, options.window, what="particle snapshot")
    if options.window is not None and (only is None or "multicontact" in only) \
            and run.lacks_probes(*MULTICONTACT_COLUMNS) is None:
        t = run.probes["time_s"]
        averaging_window(t[np.isfinite(t)], options.window, what="probe row")
    result = PlotResult()
    out_dir = Path(out_dir)
    with style.context():
        for spec, fig, why in render(run, options, only):
            if fig is None:
                result.skipped.append((spec.name, why))
                continue
            try:
                out_dir.mkdir(parents=True, exist_ok=True)
            except OSError as err:
                raise CaseError(f"--out {str(out_dir)!r}: cannot create the folder: {err.strerror or err}") from None
            result.written += style.save(fig, out_dir / spec.file_stem(options), list(formats))
    return result


# ---------------------------------------------------------------- snapshot selection
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


# ---------------------------------------------------------------- projection
@dataclass
class View:
    """How particle positions map onto a figure: the horizontal and vertical axes (0, 1, 2 for
    x, y, z), the depth axis projected away (3D only), and the drawing limits [m]."""

    horizontal: int
    vertical: int
    depth: int | None
    up_sign: float
    xlim: tuple[float, float]
    ylim: tuple[float, float]
    floor: float  # vertical coordinate of the floor [m] (lowest box bottom, else 0)
    walls: list[np.ndarray]  # polylines (k, 2) in figure coordinates [m]

    def project(self, position: np.ndarray) -> np.ndarray:
        """(N, 3) positions → (N, 2) figure coordinates [m]."""
        return np.column_stack([position[:, self.horizontal], self.up_sign * position[:, self.vertical]])

    def height(self, position: np.ndarray) -> np.ndarray:
        """Height above the floor [m], (N,)."""
        return self.up_sign * position[:, self.vertical] - self.floor

    @property
    def aspect(self) -> float:
        return (self.xlim[1] - self.xlim[0]) / (self.ylim[1] - self.ylim[0])

    def axis_label(self, k: int) -> str:
        name = "xyz"[k]
        return f"{'−' if (k == self.vertical and self.up_sign < 0) else ''}{name} [m]"


def view_of(run: RunData, first: dict | None = None) -> View:
    """The projection for ``run``: 2D runs are drawn in their x–y plane; 3D runs are projected
    onto the plane of gravity and the wider horizontal axis (the depth axis is dropped)."""
    g = run.gravity
    plane = [0, 1] if run.dimensions == 2 else [0, 1, 2]
    gp = np.array([abs(g[k]) for k in plane])
    vertical = plane[int(np.argmax(gp))] if gp.max() > 0 else plane[-1]
    up_sign = -1.0 if g[vertical] > 0 else 1.0
    rest = [k for k in plane if k != vertical]
    boxes = run.boxes()
    pos = first["position"] if first is not None else None
    diam = float(np.max(first["diameter"])) if first is not None and len(first["diameter"]) else 0.0
    depth = None
    if len(rest) == 1:
        horizontal = rest[0]
    else:
        if boxes:
            lo = np.min([b["lower"] for b in boxes], axis=0)
            hi = np.max([b["upper"] for b in boxes], axis=0)
            extent = hi - lo
        elif pos is not None and len(pos):
            extent = np.ptp(pos, axis=0)
        else:
            extent = np.ones(3)
        horizontal = rest[0] if extent[rest[0]] >= extent[rest[1]] else rest[1]
        depth = rest[1] if horizontal == rest[0] else rest[0]
    walls = []
    xs, ys = [], []
    floor = None
    for b in boxes:
        x0, x1 = b["lower"][horizontal], b["upper"][horizontal]
        y0, y1 = sorted((up_sign * b["lower"][vertical], up_sign * b["upper"][vertical]))
        pts = [(x0, y1), (x0, y0), (x1, y0), (x1, y1)]
        if not b["open_top"]:
            pts.append((x0, y1))
        walls.append(np.array(pts))
        xs += [x0, x1]
        ys += [y0, y1]
        floor = y0 if floor is None else min(floor, y0)
    if pos is not None and len(pos):
        xy = np.column_stack([pos[:, horizontal], up_sign * pos[:, vertical]])
        xs += [xy[:, 0].min() - diam, xy[:, 0].max() + diam]
        ys += [xy[:, 1].min() - diam, xy[:, 1].max() + diam]
    if not xs:
        xs, ys = [0.0, 1.0], [0.0, 1.0]
    span = max(max(xs) - min(xs), max(ys) - min(ys), 1e-12)
    pad = 0.02 * span
    return View(horizontal, vertical, depth, up_sign, (min(xs) - pad, max(xs) + pad),
                (min(ys) - pad, max(ys) + pad), 0.0 if floor is None else floor, walls)


# ---------------------------------------------------------------- particle colours
class Colourer:
    """Face colours of the particles of a snapshot for one colour mode, plus its legend or colour bar."""

    def __init__(self, mode: str, run: RunData, view: View, first: dict, bands: int = 6,
                 speed_max: float | None = None):
        self.mode = mode
        self.run = run
        if mode == "height":
            h = view.height(first["position"])
            lo, hi = float(h.min()), float(h.max())
            band = np.floor((h - lo) / max(hi - lo, 1e-300) * bands).astype(np.int64)
            band = np.clip(band, 0, bands - 1)
            order = np.argsort(first["id"])
            self._ids = np.asarray(first["id"])[order]
            self._band = band[order]
            self.bands = bands
            self.first_time = first["time"]
        elif mode == "nc" and "contacts" not in run.snapshot_fields:
            raise Unavailable(f"colour nc: {run.lacks_snapshot_fields('contacts')} (the contact number N_c of each "
                              "particle; runs write it since the Sun 2007 analyses)")
        elif mode == "speed":
            from matplotlib.colors import Normalize

            self.norm = Normalize(0.0, max(speed_max or 0.0, 1e-12))
            import matplotlib

            self.cmap = matplotlib.colormaps[style.SPEED_COLOURMAP]

    def colours(self, snap: dict) -> np.ndarray:
        from matplotlib.colors import to_rgba_array

        n = len(snap["diameter"])
        if self.mode == "height":
            ids = np.asarray(snap["id"])
            k = np.clip(np.searchsorted(self._ids, ids), 0, max(len(self._ids) - 1, 0))
            found = self._ids[k] == ids if len(self._ids) else np.zeros(n, bool)
            pal = to_rgba_array(list(style.BAND_COLOURS) + [style.UNBANDED_COLOUR])
            idx = np.where(found, self._band[k] % 2, 2)
            return pal[idx]
        if self.mode == "speed":
            speed = np.linalg.norm(snap["velocity"], axis=1)
            return self.cmap(self.norm(speed))
        if self.mode == "nc":
            if "contacts" not in snap:
                raise Unavailable(f"colour nc: the snapshot at t = {snap['time']:g} s has no contacts field")
            pal = to_rgba_array(style.NC_COLOURS)
            return pal[np.clip(np.asarray(snap["contacts"], np.int64), 0, len(pal) - 1)]
        pal = to_rgba_array(style.LINE_COLOURS)
        return pal[np.asarray(snap["species"], np.int64) % len(pal)]

    def decorate(self, fig, axes, snaps) -> None:
        """Colour bar (speed), legend (species, N_c) or a note on the bands (height)."""
        from matplotlib.cm import ScalarMappable
        from matplotlib.patches import Patch

        if self.mode == "speed":
            fig.colorbar(ScalarMappable(self.norm, self.cmap), ax=axes, label="speed |v| [m/s]", shrink=0.8)
        elif self.mode == "species":
            names = self.run.species_names
            present = sorted({int(s) for snap in snaps for s in np.unique(snap["species"])})
            handles = [Patch(facecolor=style.LINE_COLOURS[s % len(style.LINE_COLOURS)], edgecolor="k",
                             label=names[s] if s < len(names) else f"species {s}") for s in present]
            fig.legend(handles=handles, loc="outside lower center", ncols=min(len(handles), 4))
        elif self.mode == "nc":
            handles = [Patch(facecolor=c, edgecolor="k", label=lab) for c, lab in zip(style.NC_COLOURS, style.NC_LABELS)]
            fig.legend(handles=handles, loc="outside right upper", ncols=1)  # a discrete key beside the panels
        else:
            fig.suptitle(f"colour: band of initial height ({self.bands} bands at t = {self.first_time:.3g} s)",
                         fontsize=style.RC["font.size"])


def speed_max(run: RunData, indices: list[int] | None = None) -> float:
    vmax = 0.0
    for k, (_, snap) in enumerate(run.iter_snapshots(("velocity",))):
        if (indices is None or k in indices) and "velocity" in snap and len(snap["velocity"]):
            vmax = max(vmax, float(np.max(np.linalg.norm(snap["velocity"], axis=1))))
    return vmax


def draw_particles(ax, view: View, snap: dict, colours: np.ndarray):
    """Particles as circles of their true diameter (data units); returns the collection.

    3D runs: nearer particles (smaller depth coordinate) are drawn over farther ones.
    """
    from matplotlib.collections import EllipseCollection

    xy = view.project(snap["position"])
    d = np.asarray(snap["diameter"], float)
    order = np.argsort(-snap["position"][:, view.depth]) if view.depth is not None else slice(None)
    n = len(d)
    coll = EllipseCollection(d[order], d[order], np.zeros(n), units="xy", offsets=xy[order],
                             offset_transform=ax.transData, facecolors=colours[order],
                             edgecolors="#202020" if n <= 5000 else "none", linewidths=0.25)
    ax.add_collection(coll)
    return coll


def setup_particle_axes(ax, view: View, first_panel: bool = True) -> None:
    for line in view.walls:
        ax.plot(line[:, 0], line[:, 1], color=style.WALL_COLOUR, lw=1.2, solid_capstyle="butt")
    ax.set_xlim(*view.xlim)
    ax.set_ylim(*view.ylim)
    ax.set_aspect("equal")
    ax.grid(False)
    ax.set_xlabel(view.axis_label(view.horizontal))
    if first_panel:
        ax.set_ylabel(view.axis_label(view.vertical))


def _time_title(t: float) -> str:
    return f"t = {t:.3f} s" if abs(t) >= 1e-3 or t == 0 else f"t = {t:.3g} s"


@figure("snapshots", "particles at chosen times, coloured by initial height band, speed, species "
                     "(Hoomans et al. 1996 Figs 8/10/12) or number of contacts N_c (Sun et al. 2007 Figs 6/10)",
        lacks=lambda run: run.lacks_snapshots(), stem=lambda o: f"snapshots_{o.color}")
def draw_snapshots(run: RunData, options: PlotOptions):
    indices = select_snapshots(run.snapshot_times, options.times)
    first = run.snapshot(0)
    snaps = [first if k == 0 else run.snapshot(k) for k in indices]
    view = view_of(run, first)
    vmax = speed_max(run, indices) if options.color == "speed" else None
    colourer = Colourer(options.color, run, view, first, options.bands, vmax)
    n = len(snaps)
    panel_w = float(np.clip(style.PANEL_HEIGHT_IN * view.aspect, 1.3, 8.0))
    extra = 1.1 if options.color in ("speed", "nc") else 0.5
    fig = style.new_figure(n * panel_w + extra, style.PANEL_HEIGHT_IN + 0.8)
    axes = fig.subplots(1, n, sharey=True, squeeze=False)[0]
    for i, (ax, snap) in enumerate(zip(axes, snaps)):
        setup_particle_axes(ax, view, first_panel=(i == 0))
        draw_particles(ax, view, snap, colourer.colours(snap))
        ax.set_title(_time_title(snap["time"]))
    colourer.decorate(fig, list(axes), snaps)
    return fig


# ---------------------------------------------------------------- time traces
def _trace_axes(nrows: int = 1):
    w, h = style.TRACE_SIZE_IN
    fig = style.new_figure(w, h if nrows == 1 else 0.6 * h * nrows + 0.6)
    axes = fig.subplots(nrows, 1, sharex=True, squeeze=False)[:, 0]
    axes[-1].set_xlabel(style.label("time_s"))
    return fig, axes


DISSIPATED_COLUMNS = ("dissipated_normal_J", "dissipated_tangential_J")  # hard-sphere runs (Hoomans eq. 51)


@figure("energy", "kinetic, rotational and potential energy (relative to its final value), in hard-sphere runs "
                  "the energy dissipated in collisions, and their sum against time (Hoomans et al. 1996 Fig 9)",
        lacks=lambda run: run.lacks_probes("kinetic_J", "potential_J"))
def draw_energy(run: RunData, options: PlotOptions):
    p = run.probes
    t = p["time_s"]
    kinetic = p["kinetic_J"]
    pe = p["potential_J"]
    finite = np.flatnonzero(np.isfinite(pe))
    pe_rel = pe - (pe[finite[-1]] if len(finite) else 0.0)
    fig, (ax,) = _trace_axes()
    ax.plot(t, kinetic, label="kinetic")
    rotational = np.zeros_like(t)
    if "rotational_J" in p:  # hard-sphere runs without rotation may leave it out
        rotational = p["rotational_J"]
        ax.plot(t, rotational, label="rotational")
    ax.plot(t, pe_rel, label="potential − final potential")
    total = kinetic + rotational + pe_rel
    dissipated = [c for c in DISSIPATED_COLUMNS if c in p]
    if dissipated:  # hard spheres book what collisions take (Hoomans eqs 23, 27, 29): the sum is conserved
        lost = np.sum([p[c] for c in dissipated], axis=0)
        ax.plot(t, lost, label="dissipated in collisions")
        total = total + lost
    ax.plot(t, total, color="k", lw=1.8, label="sum")
    ax.set_ylabel("energy [J]")
    title = "energy budget"
    err = (run.summary or {}).get("energy_error_rel")
    if dissipated and isinstance(err, (int, float)) and not isinstance(err, bool) and np.isfinite(err):
        title += f" (energy conservation error {100.0 * err:.2g} %)"
    ax.set_title(title)
    ax.legend(loc="best")
    return fig


@figure("contacts", "coordination number and number of contacts against time (Sun et al. 2007)",
        lacks=lambda run: run.lacks_probes("coordination", "contacts", "wall_contacts", any_of=True))
def draw_contacts(run: RunData, options: PlotOptions):
    p = run.probes
    t = p["time_s"]
    rows = [["coordination"]] if "coordination" in p else []
    counts = [c for c in ("contacts", "wall_contacts") if c in p]
    if counts:
        rows.append(counts)
    fig, axes = _trace_axes(len(rows))
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
    fig, axes = _trace_axes(2)
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
    fig, (ax,) = _trace_axes()
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


PRESSURE_PROBE_HEIGHT = 0.2  # [m] above the bottom: Hoomans et al. 1996 Figs 11/13, Sun et al. 2007 Fig 3


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


def power_spectrum(t: np.ndarray, y: np.ndarray):
    """One-sided power spectral density of a sampled signal, its mean removed.

    The samples are put on a uniform time grid (the median interval; probes fire on the
    first step after each multiple of their interval, so they are nearly uniform already)
    and Welch's method with a Hann window gives the PSD, with segments of a quarter of the
    record (at least 256 samples, at most all of it).

    Returns (frequency [Hz], PSD [unit^2/Hz], dominant frequency [Hz]: the peak above 0 Hz),
    or None with fewer than 8 finite samples.
    """
    from scipy.signal import welch

    ok = np.isfinite(t) & np.isfinite(y)
    t, y = np.asarray(t, float)[ok], np.asarray(y, float)[ok]
    if len(t) < 8:
        return None
    order = np.argsort(t)
    t, y = t[order], y[order]
    dt = float(np.median(np.diff(t)))
    if not dt > 0:
        return None
    n = int(np.floor((t[-1] - t[0]) / dt + 1e-9)) + 1
    tu = t[0] + dt * np.arange(n)
    yu = np.interp(tu, t, y)
    nperseg = int(min(n, max(256, n // 4)))
    f, psd = welch(yu - yu.mean(), fs=1.0 / dt, window="hann", nperseg=nperseg, detrend="constant")
    if len(f) < 2:
        return None
    dominant = float(f[1 + int(np.argmax(psd[1:]))])
    return f, psd, dominant


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
        ax_f.plot(f, psd, color=colour, label=f"{label}: dominant {dominant:.3g} Hz")
        ax_f.axvline(dominant, color=colour, ls="--", lw=0.9)
        peak = float(psd[1 + int(np.argmax(psd[1:]))])
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
        ax_f.text(0.5, 0.5, "too few samples for a spectrum (8 needed)", transform=ax_f.transAxes,
                  ha="center", va="center")
    return fig


# ---------------------------------------------------------------- gas-field maps
def averaging_window(times: np.ndarray, requested: tuple[float, float] | None = None,
                     what: str = "gas-field snapshot") -> tuple[float, float, np.ndarray]:
    """(t0, t1, mask of ``times`` inside) of a time average over samples at ``times`` (sorted) [s].

    ``requested=None``: 5-10 s when the samples cover it (Sun et al. 2007 Figs 4/8/13),
    else the second half of the samples' span. A requested window with no sample in it
    is a CaseError naming ``what`` the samples are.
    """
    times = np.asarray(times, float)
    tol = 1e-9 * max(abs(times[-1]), 1.0)
    if requested is None:
        if times[0] <= 5.0 + tol and times[-1] >= 10.0 - tol:
            t0, t1 = 5.0, 10.0
        else:
            t0, t1 = times[0] + 0.5 * (times[-1] - times[0]), times[-1]
    else:
        t0, t1 = requested
    mask = (times >= t0 - tol) & (times <= t1 + tol)
    if not mask.any():
        raise CaseError(f"--window {t0:g},{t1:g}: no {what} in it; the {what}s run from "
                        f"{times[0]:g} s to {times[-1]:g} s ({len(times)} of them)")
    return float(t0), float(t1), mask


def _map_axes(run: RunData, npanels: int, colourbar: bool = True):
    """A row of ``npanels`` map axes sized to the gas domain, the x–y plane of the grid."""
    g = run.gas
    fig, axes = _map_grid(g["x_faces"], g["y_faces"], 1, npanels, 1.6 if colourbar else 0.7)
    return fig, axes[0]


def _map_grid(xf, yf, nrows: int, ncols: int, extra_w: float = 1.6, extra_h: float = 0.8, ylim=None):
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


def _matching_particle_snapshots(run: RunData, times: list[float]) -> list[int | None]:
    """Index of the particle snapshot at each time (within half a snapshot interval), else None."""
    if run.lacks_snapshots() is not None:
        return [None] * len(times)
    pt = run.snapshot_times
    tol = 0.5 * float(np.median(np.diff(pt))) if len(pt) > 1 else 0.0
    tol = max(tol, 1e-9 * max(abs(pt[-1]), 1.0))
    out = []
    for t in times:
        k = int(np.argmin(np.abs(pt - t)))
        out.append(k if abs(pt[k] - t) <= tol else None)
    return out


def _lacks_voidage(run: RunData) -> str | None:
    return run.lacks_gas("voidage")


@figure("voidage", "gas voidage maps at chosen times with the particles drawn over them "
                   "(Hoomans et al. 1996 Figs 10/12)", lacks=_lacks_voidage)
def draw_voidage(run: RunData, options: PlotOptions):
    from matplotlib.colors import Normalize

    g = run.gas
    try:
        indices = select_snapshots(g["time"], options.times)
    except CaseError as err:
        raise Unavailable(f"{err} (gas fields)") from None
    times = [float(g["time"][k]) for k in indices]
    maps = [g["voidage"][k] for k in indices]
    lowest = float(np.nanmin(maps))
    norm = Normalize(vmin=min(lowest, 0.999), vmax=1.0)
    fig, axes = _map_axes(run, len(indices))
    particles = _matching_particle_snapshots(run, times) if options.overlay else [None] * len(times)
    mesh = None
    for ax, t, eps, kp in zip(axes, times, maps, particles):
        mesh = ax.pcolormesh(g["x_faces"], g["y_faces"], eps.T, cmap=style.VOIDAGE_COLOURMAP, norm=norm,
                             shading="flat", rasterized=True)
        if kp is not None:
            _draw_particles_over_map(ax, run.snapshot(kp))
        ax.set_title(_time_title(t))
    fig.colorbar(mesh, ax=list(axes), label=style.label("voidage"), shrink=0.8)
    if options.overlay and any(k is None for k in particles):
        fig.suptitle("particles drawn where a particle snapshot matches the time", fontsize=style.RC["font.size"])
    return fig


def _draw_particles_over_map(ax, snap: dict) -> None:
    """Particles (true diameter, x–y plane of the gas grid) as translucent discs over a gas map."""
    from matplotlib.collections import EllipseCollection

    d = np.asarray(snap["diameter"], float)
    n = len(d)
    coll = EllipseCollection(d, d, np.zeros(n), units="xy", offsets=snap["position"][:, :2],
                             offset_transform=ax.transData, facecolors=[style.MAP_PARTICLE_FACE],
                             edgecolors=style.MAP_PARTICLE_EDGE, linewidths=0.3)
    ax.add_collection(coll)


@figure("solids_fraction", "time-averaged solids fraction 1 − ε of the gas cells over a window "
                           "(default 5-10 s, else the second half of the run; Sun et al. 2007 Figs 4/8/13)",
        lacks=lambda run: run.lacks_gas("voidage"))
def draw_solids_fraction(run: RunData, options: PlotOptions):
    from matplotlib.colors import Normalize

    g = run.gas
    try:
        t0, t1, mask = averaging_window(g["time"], options.window)
    except CaseError as err:
        raise Unavailable(str(err)) from None
    mean = np.nanmean(1.0 - g["voidage"][mask], axis=0)
    fig, (ax,) = _map_axes(run, 1)
    norm = Normalize(vmin=0.0, vmax=max(float(np.nanmax(mean)), 1e-3))
    mesh = ax.pcolormesh(g["x_faces"], g["y_faces"], mean.T, cmap=style.SOLIDS_COLOURMAP, norm=norm,
                         shading="flat", rasterized=True)
    fig.colorbar(mesh, ax=ax, label="mean " + style.label("solids_fraction"), shrink=0.8)
    n = int(mask.sum())
    ax.set_title(f"mean over t = {t0:.3g}–{t1:.3g} s\n({n} snapshot{'s' if n != 1 else ''})")
    return fig


# ---------------------------------------------------------------- force maps
FORCE_FIELDS = ("contact_force", "gas_force")
FORCE_SCALE_PERCENTILE = 99.0  # colour scales end here, so one corner cell does not wash out the maps


def _lacks_forces(run: RunData) -> str | None:
    if not run.has_gas_phase:
        return "the run has no gas phase (its case.toml has no [gas] section)"
    why = run.lacks_snapshot_fields(*FORCE_FIELDS)
    if why is not None:
        if run.lacks_snapshots() is None:
            why += (" (coupled soft-sphere runs write contact_force and gas_force; hard-sphere collisions are "
                    "impulses, without a contact force)")
        return why
    try:
        run.gas_grid()
        run.particle_mass(np.zeros(1), np.zeros(1, np.int64))  # the case gives the species densities
    except Unavailable as err:
        return str(err)
    if not np.linalg.norm(run.gravity) > 0:
        return "the case has no gravity, and the force maps are scaled by the particle weight m g"
    return None


@dataclass
class ForceMaps:
    """Cell maps (nx, ny) of ``fluidem.analysis.fluidised.cell_force_maps``: ``contact_force`` and
    ``drag_force`` (means of |F| / (m g)), ``force_ratio`` (contact / drag, −1 where the drag is zero,
    NaN in empty cells) and ``particles`` (particle samples per cell), averaged over the ``snapshots``
    between ``t0`` and ``t1`` [s] (one snapshot, t0 = t1, for the instantaneous maps)."""

    contact_force: np.ndarray
    drag_force: np.ndarray
    force_ratio: np.ndarray
    particles: np.ndarray
    t0: float
    t1: float
    snapshots: int


def force_maps(run: RunData, window: tuple[float, float] | None = None) -> tuple[ForceMaps, ForceMaps]:
    """(instantaneous maps at the last snapshot of the window, maps averaged over the window).

    The window is ``averaging_window`` of the particle snapshots (5–10 s when covered, else the
    second half). The average is over every particle sample of a cell in the window: the sums of
    |F| / (m g) over snapshots divided by the summed particle count, so a cell visited once by one
    particle weighs as little as that one sample; the ratio is the averaged contact over the
    averaged drag force (−1 where no sample had drag). Raises ``Unavailable``.
    """
    from ..analysis.fluidised import cell_force_maps

    grid = run.gas_grid()
    times = run.snapshot_times
    try:
        t0, t1, mask = averaging_window(times, window, what="particle snapshot")
    except CaseError as err:
        raise Unavailable(str(err)) from None
    indices = list(np.flatnonzero(mask))
    shape = grid.shape
    sum_c, sum_d, count = np.zeros(shape), np.zeros(shape), np.zeros(shape)
    last = None
    fields = ("position", "diameter", "species", *FORCE_FIELDS)
    for t, snap in run.iter_snapshots(fields, indices=indices):
        missing = [f for f in ("position", "diameter", *FORCE_FIELDS) if f not in snap]
        if missing:
            raise Unavailable(f"the snapshot at t = {t:g} s has no {', '.join(missing)}")
        species = snap.get("species", np.zeros(len(snap["diameter"]), np.int64))
        mass = run.particle_mass(snap["diameter"], species)
        m = cell_force_maps(grid, snap["position"], mass, snap["contact_force"], snap["gas_force"], run.gravity)
        n = m["particles"]
        sum_c += np.where(n > 0, m["contact_force"] * n, 0.0)
        sum_d += np.where(n > 0, m["drag_force"] * n, 0.0)
        count += n
        last = (t, m)
    t_last, m = last
    inst = ForceMaps(m["contact_force"], m["drag_force"], m["force_ratio"], m["particles"], t_last, t_last, 1)
    with np.errstate(invalid="ignore", divide="ignore"):
        occupied = count > 0
        mean_c = np.where(occupied, sum_c / np.where(occupied, count, 1.0), np.nan)
        mean_d = np.where(occupied, sum_d / np.where(occupied, count, 1.0), np.nan)
        ratio = np.where(occupied, np.where(sum_d > 0, sum_c / np.where(sum_d > 0, sum_d, 1.0), -1.0), np.nan)
    avg = ForceMaps(mean_c, mean_d, ratio, count, t0, t1, len(indices))
    return inst, avg


def _upper(values, floor: float = 1e-12) -> tuple[float, bool]:
    """Colour-scale top: the FORCE_SCALE_PERCENTILE of the finite values; and whether values exceed it."""
    v = np.concatenate([np.ravel(x)[np.isfinite(np.ravel(x))] for x in values])
    if v.size == 0:
        return 1.0, False
    top = max(float(np.percentile(v, FORCE_SCALE_PERCENTILE)), floor)
    return top, bool(v.max() > top)


@figure("forces", "contact force and gas (drag) force per particle weight and their ratio (−1: no drag) on the "
                  "gas grid, at the last snapshot of the averaging window and averaged over it "
                  "(default 5–10 s, else the second half; Sun et al. 2007 Figs 7/12)",
        lacks=_lacks_forces)
def draw_forces(run: RunData, options: PlotOptions):
    import matplotlib
    from matplotlib.colors import Normalize

    grid = run.gas_grid()
    inst, avg = force_maps(run, options.window)
    xf = np.linspace(0.0, grid.size[0], grid.nx + 1)
    yf = np.linspace(0.0, grid.size[1], grid.ny + 1)
    # like Sun's figures (the lower 45 cm of a 90 cm column), show the rows particles reached, not the freeboard
    rows = np.flatnonzero(avg.particles.sum(axis=0) > 0)
    top = yf[-1] if rows.size == 0 else min(yf[-1], yf[rows[-1] + 1] + 0.1 * (yf[-1] - yf[0]))
    fig, axes = _map_grid(xf, yf, 2, 3, extra_w=0.6, extra_h=1.6, ylim=(yf[0], top))
    # one colour scale per column, shared by its two rows: contact forces run to tens of particle weights
    # where drag stays near one, so a common scale would hide the drag map
    fcmap = matplotlib.colormaps[style.FORCE_COLOURMAP]
    rcmap = matplotlib.colormaps[style.RATIO_COLOURMAP].with_extremes(under=style.NO_DRAG_COLOUR)
    columns = [("contact_force", fcmap, "contact force / m g [–]"),
               ("drag_force", fcmap, "gas force / m g [–]"),
               ("force_ratio", rcmap, "contact / gas force [–]")]
    # column heads on the top row; each row says when (Sun's figures: (a) instantaneous, (b) time-averaged)
    heads = ("contact force / m g", "gas force / m g", "contact / gas force\n(grey: −1, no gas force)")
    for c, (name, cmap, label) in enumerate(columns):
        data = [getattr(m, name) for m in (inst, avg)]
        top, over = _upper([np.where(d >= 0, d, np.nan) for d in data])  # the ratio's −1 is drawn grey
        norm = Normalize(0.0, top)
        for r, (maps, values) in enumerate(zip((inst, avg), data)):
            when = (f"t = {maps.t1:.3g} s" if r == 0 else
                    f"mean {maps.t0:.3g}–{maps.t1:.3g} s\n({maps.snapshots} snapshot{'s' if maps.snapshots != 1 else ''})")
            mesh = axes[r, c].pcolormesh(xf, yf, values.T, cmap=cmap, norm=norm, shading="flat", rasterized=True)
            axes[r, c].set_title(f"{heads[c]}\n{when}" if r == 0 else when)
        extend = ("both" if over else "min") if name == "force_ratio" else ("max" if over else "neither")
        fig.colorbar(mesh, ax=list(axes[:, c]), location="bottom", shrink=0.95, aspect=12, extend=extend, label=label)
    return fig
