"""Gas voidage maps at chosen times with the particles over them (Hoomans et al. 1996 Figs 10/12) and the
time-averaged solids fraction map (Sun et al. 2007 Figs 4/8/13), from gas.h5."""
from __future__ import annotations

import numpy as np

from ...errors import CaseError
from .. import style
from ..run import RunData, Unavailable
from ._shared import PlotOptions, averaging_window, figure, map_axes, select_snapshots, time_title


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
    fig, axes = map_axes(run, len(indices))
    particles = _matching_particle_snapshots(run, times) if options.overlay else [None] * len(times)
    mesh = None
    for ax, t, eps, kp in zip(axes, times, maps, particles):
        mesh = ax.pcolormesh(g["x_faces"], g["y_faces"], eps.T, cmap=style.VOIDAGE_COLOURMAP, norm=norm,
                             shading="flat", rasterized=True)
        if kp is not None:
            _draw_particles_over_map(ax, run.snapshot(kp))
        ax.set_title(time_title(t))
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
    fig, (ax,) = map_axes(run, 1)
    norm = Normalize(vmin=0.0, vmax=max(float(np.nanmax(mean)), 1e-3))
    mesh = ax.pcolormesh(g["x_faces"], g["y_faces"], mean.T, cmap=style.SOLIDS_COLOURMAP, norm=norm,
                         shading="flat", rasterized=True)
    fig.colorbar(mesh, ax=ax, label="mean " + style.label("solids_fraction"), shrink=0.8)
    n = int(mask.sum())
    ax.set_title(f"mean over t = {t0:.3g}–{t1:.3g} s\n({n} snapshot{'s' if n != 1 else ''})")
    return fig
