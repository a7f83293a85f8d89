"""Particles at chosen times (Hoomans et al. 1996 Figs 8/10/12; coloured by N_c, Sun et al. 2007 Figs 6/10),
and the projection, colours and drawing of particles that the animation and the other figures reuse."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import style
from ..run import RunData, Unavailable
from ._shared import PlotOptions, figure, select_snapshots, time_title


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
        ax.set_title(time_title(snap["time"]))
    colourer.decorate(fig, list(axes), snaps)
    return fig
