"""Contact and gas force per particle weight and their ratio on the gas grid (Sun et al. 2007 Figs 7/12), from
the particle snapshots' ``contact_force`` and ``gas_force`` (``analysis.fluidised.cell_force_maps``)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...errors import CaseError
from .. import style
from ..run import RunData, Unavailable
from ._shared import PlotOptions, averaging_window, figure, map_grid

FORCE_FIELDS = ("contact_force", "gas_force")
FORCE_SCALE_PERCENTILE = 99.0  # colour scales end here, so one corner cell does not wash out the maps


def lacks_forces(run: RunData) -> str | None:
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
    from ...analysis.fluidised import cell_force_maps

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
        lacks=lacks_forces)
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
    fig, axes = map_grid(xf, yf, 2, 3, extra_w=0.6, extra_h=1.6, ylim=(yf[0], top))
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
