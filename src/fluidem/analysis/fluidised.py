"""The analyses of Sun et al. 2007 for fluidised beds: contacts, forces, pressure, averages.

Definitions (Sun 2007, §4):

- ``N_c`` of a particle: its number of contacting particle neighbours (wall contacts are
  not neighbours); the bulk coordination number (Fig 5) is the mean of N_c.
- multicontact ratio (Fig 11): particles with N_c > 1 over particles with N_c ≥ 1.
- contact force of a particle: the sum of its particle and wall contact forces; drag
  force: the gas force on it (drag, plus −V_p∇p when that force is on). Maps (Figs 7/12)
  are cell means of the magnitudes scaled by the particle weight m g, and the cell ratio
  of contact to drag force (−1 where the drag is zero, as Sun's legend).
- pressure drop at a height (Fig 3): the width-averaged gas pressure at the inlet
  boundary minus that at the height, both linearly interpolated (extrapolated to the
  inlet) between cell-centre rows.
- pressure 20 cm above the jet (Hoomans 1996 Figs 11/13): the gauge pressure (relative to
  the reference pressure) at mid-width, bilinear between cell centres.
- bubble (Hoomans 1996 §5.3): the largest 4-connected region of cells with
  ε > 0.8 not connected to the freeboard, at least 3 cells; ``bubble_detected`` in the
  summary says whether one formed at any probe time.
- mean particle height (Fig 9): the arithmetic mean of the particle centres' heights
  above the floor (``mean_particle_height_m``; not a surface height).
- bed surface height (``bed_surface_height``; this package's definition, no paper's): the
  height above the floor where the horizontally averaged solids fraction φ(z) falls below
  ``BED_SURFACE_FRACTION`` (one half) of its mean over the bed beneath, the axial-profile
  reading of a bed's height. A few particles thrown up into the freeboard stay far below that
  level and do not move it; a uniform slab gives its top within a tenth of a radius.

Time averages for ``summary.json`` are taken from ``probes.csv`` over 5–10 s (Sun's
window) when the run reaches 10 s, else over the second half of the run; the window
used is reported. The spectrum of the pressure signal is ``analysis.spectrum.power_spectrum``.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..io.probes_csv import read_probes
from ._contacts_kernels import NO_PERIOD, contact_counts
from .spectrum import MIN_SAMPLES as SPECTRUM_MIN_SAMPLES, dominant_frequency, spectral_peaks

PRESSURE_PROBE_HEIGHT = 0.20  # [m] above the inlet, Sun 2007 Fig 3 / Hoomans 1996 §5.3
SUN_WINDOW = (5.0, 10.0)  # [s] Sun 2007 time averages


def contact_numbers(engine) -> np.ndarray:
    """N_c per particle (particle–particle contacts only), (N,) int64."""
    st = engine.state
    row_start = getattr(engine, "row_start", None)
    if row_start is None or st.n == 0:
        return np.zeros(st.n, dtype=np.int64)
    return contact_counts(st.position, st.radius, row_start, engine.partner, getattr(engine, "period", NO_PERIOD))[0]


def multicontact_ratio(nc: np.ndarray) -> float:
    """Particles in multicontact (N_c > 1) over particles in contact (N_c ≥ 1); NaN when none touch."""
    touching = int(np.count_nonzero(nc >= 1))
    return float(np.count_nonzero(nc >= 2) / touching) if touching else math.nan


def contact_force(engine) -> np.ndarray:
    """Sum of the contact forces (particles and walls) on each particle [N], (N, 3).

    The engine's total force is contacts + m g + gas force (``gas_force``); soft-sphere
    engines only (hard-sphere collisions are impulses and have no force). With a drag that
    follows the particle's velocity every sub-step (``ext_damping``) the total force was
    evaluated at the mid-step velocity and the gas force here at the current one: they differ
    by K_p a dt/2, far below the contact forces this is used for.
    """
    st = engine.state
    return st.force - st.mass[:, None] * engine.gravity[None, :] - gas_force(engine)


def gas_force(engine) -> np.ndarray:
    """The gas force on each particle [N], (N, 3) (drag, with −V_p∇p when enabled), at the current velocity."""
    if hasattr(engine, "external_force"):
        return engine.external_force()
    return engine.ext_force.copy()


def up_axis(grid, gravity) -> int:
    """The grid axis along which heights are measured: that of gravity on a 3D grid (y without gravity), y in 2D."""
    g = np.asarray(gravity, float)[:grid.dimensions]
    return int(np.argmax(np.abs(g))) if grid.dimensions == 3 and np.any(g != 0.0) else 1


def pressure_at_heights(grid, p: np.ndarray, heights, axis: int = 1) -> np.ndarray:
    """Width-averaged pressure [Pa] at the given heights, linear in y between cell-centre rows and
    extrapolated linearly below the first and above the last row.

    The extrapolation to the inflow is the coupled model's own inlet pressure: the half cell below
    the first centre belongs to the first interior face's momentum control volume
    (``coupling.boundary_faces = "fold"``, ``coupling.exchange.face_volumes``), across which the
    pressure falls with that face's gradient. On a 3D grid the heights are along ``axis`` (``up_axis``) and
    the pressure is averaged over each layer of cells across it."""
    yc = (grid.x_centres, grid.y_centres, grid.z_centres)[axis] if grid.dimensions == 3 else grid.y_centres
    pa = np.asarray(p, float)
    prof = pa.mean(axis=tuple(a for a in range(pa.ndim) if a != axis)) if grid.dimensions == 3 else pa.mean(axis=0)
    h = np.atleast_1d(np.asarray(heights, float))
    out = np.interp(h, yc, prof)
    # np.interp clamps; extrapolate linearly below the first and above the last centre
    lo, hi = h < yc[0], h > yc[-1]
    if yc.size > 1:
        out[lo] = prof[0] + (h[lo] - yc[0]) * (prof[1] - prof[0]) / (yc[1] - yc[0])
        out[hi] = prof[-1] + (h[hi] - yc[-1]) * (prof[-1] - prof[-2]) / (yc[-1] - yc[-2])
    return out


def pressure_drop(grid, p: np.ndarray, height: float = PRESSURE_PROBE_HEIGHT, axis: int = 1) -> float:
    """p(inlet) − p(height) [Pa], width-averaged (Sun 2007 Fig 3); on a 3D grid heights along ``axis``."""
    a, b = pressure_at_heights(grid, p, [0.0, height], axis)
    return float(a - b)


def pressure_at(grid, p: np.ndarray, x: float, y: float) -> float:
    """Gas pressure [Pa] at (x, y), bilinear between cell centres (clamped to the outermost centres)."""
    xc, yc = grid.x_centres, grid.y_centres
    fx = float(np.clip((x - xc[0]) / grid.dx, 0.0, xc.size - 1))
    fy = float(np.clip((y - yc[0]) / grid.dy, 0.0, yc.size - 1))
    i, j = min(int(fx), xc.size - 2) if xc.size > 1 else 0, min(int(fy), yc.size - 2) if yc.size > 1 else 0
    a, b = fx - i, fy - j
    i1, j1 = min(i + 1, xc.size - 1), min(j + 1, yc.size - 1)
    return float((1 - a) * (1 - b) * p[i, j] + a * (1 - b) * p[i1, j] + (1 - a) * b * p[i, j1] + a * b * p[i1, j1])


BUBBLE_VOIDAGE = 0.8  # a bubble cell has ε above this (Hoomans 1996 Figs 10/12 by eye)
BUBBLE_MIN_CELLS = 3  # smaller void regions (the jet channel at an orifice) are not bubbles


def _bubbles(voidage: np.ndarray, threshold: float) -> tuple[np.ndarray, np.ndarray]:
    """(labels (nx, ny) of the 4-connected regions of cells with ε > ``threshold``, cells per label with
    0 for every label that is no bubble: the background, a region open to the top row (the freeboard)
    or one of fewer than ``BUBBLE_MIN_CELLS`` cells)."""
    from scipy import ndimage

    labels, n = ndimage.label(np.asarray(voidage) > threshold)
    sizes = np.bincount(labels.ravel(), minlength=n + 1)
    sizes[0] = 0
    sizes[np.unique(labels[:, -1])] = 0
    sizes[sizes < BUBBLE_MIN_CELLS] = 0
    return labels, sizes


def bubble_area(grid, voidage: np.ndarray, threshold: float = BUBBLE_VOIDAGE) -> float:
    """Area [m²] of the largest bubble: a 4-connected region of cells with ε > ``threshold`` that is
    not connected to the top row (the freeboard), so a void enclosed by particles, slugs included.
    Regions of fewer than ``BUBBLE_MIN_CELLS`` cells count as no bubble (0)."""
    _, sizes = _bubbles(voidage, threshold)
    return float(sizes.max() * grid.dx * grid.dy)


# A slug is a bubble as wide as the column: one that touches or nearly touches both side
# walls. The usual rule of thumb has bubbles turn into slugs once they grow past about two
# thirds of the column width; 0.8 is stricter, so a large bubble in the middle of the bed is
# not called a slug, while it leaves room for the particles that slide down the walls past a
# slug, which keep a wall cell below ε = 0.8. On Hoomans' grid (15 cells of 10 mm) that is 12
# of the 15 cells of one row.
SLUG_WIDTH_FRACTION = 0.8


def bubble_regions(grid, voidage: np.ndarray, threshold: float = BUBBLE_VOIDAGE) -> list[np.ndarray]:
    """The bubbles that ``bubble_area`` considers, as boolean masks (nx, ny), largest first.

    A bubble is a 4-connected region of cells with ε > ``threshold`` not connected to the
    top row (the freeboard) and of at least ``BUBBLE_MIN_CELLS`` cells; the largest mask's
    area is ``bubble_area``.
    """
    eps = np.asarray(voidage)
    if eps.shape != tuple(grid.shape):
        raise ValueError(f"voidage has shape {eps.shape}; the grid's cells are {tuple(grid.shape)}")
    labels, sizes = _bubbles(eps, threshold)
    keep = np.flatnonzero(sizes)
    return [labels == k for k in keep[np.argsort(-sizes[keep], kind="stable")]]


def bubble_width_fraction(grid, voidage: np.ndarray, threshold: float = BUBBLE_VOIDAGE) -> float:
    """The widest horizontal chord of any bubble over the column width (0.0 without a bubble).

    The chord of a bubble in a cell row runs from its leftmost to its rightmost cell in that
    row (inclusive), so a strand of particles inside a slug does not shorten it; the result is
    the largest chord over all rows and bubbles, in cells over ``nx`` (1.0: wall to wall).
    """
    best = 0
    for mask in bubble_regions(grid, voidage, threshold):
        first = np.argmax(mask, axis=0)  # leftmost and rightmost cell of each row
        last = mask.shape[0] - 1 - np.argmax(mask[::-1], axis=0)
        best = max(best, int(np.max(np.where(mask.any(axis=0), last - first + 1, 0))))
    return best / grid.nx


def slug_detected(grid, voidage: np.ndarray, threshold: float = BUBBLE_VOIDAGE,
                  min_width_fraction: float = SLUG_WIDTH_FRACTION) -> bool:
    """Whether the bed holds a slug: a bubble (see ``bubble_regions``) whose chord in some cell row
    spans at least ``min_width_fraction`` of the column width (``bubble_width_fraction``), i.e. a
    void that reaches, or nearly reaches, both side walls. A void open to the freeboard (a slug
    erupting at the surface) is no longer a bubble and so no slug."""
    return bubble_width_fraction(grid, voidage, threshold) >= min_width_fraction - 1e-12


BED_SURFACE_FRACTION = 0.5  # the surface: where φ(z) falls below this fraction of the mean φ of the bed beneath
PROFILE_STEPS_PER_DIAMETER = 20  # resolution of the solids-fraction profile of ``bed_surface_height``


def solids_profile(heights, radius, dim2: bool, step: float) -> np.ndarray:
    """Solids per unit height at z_b = (b + ½) step above the floor, b = 0, 1, …: Σ_i of the chord
    2 √(R_i² − (z_b − h_i)²) of each disc (``dim2``) or the section π (R_i² − (z_b − h_i)²) of each sphere,
    [m] or [m²]. Over a cross-section it is the horizontally averaged solids fraction φ(z_b), up to that
    constant. ``heights`` (N,) centre heights above the floor [m], ``radius`` (N,) [m]; vectorised over the
    (N, K) bins each particle spans."""
    h = np.asarray(heights, float)
    r = np.asarray(radius, float)
    k = int(np.ceil(2.0 * r.max() / step)) + 2
    first = np.maximum(np.floor((h - r) / step).astype(np.int64), 0)
    bins = first[:, None] + np.arange(k)[None, :]
    d2 = r[:, None] ** 2 - ((bins + 0.5) * step - h[:, None]) ** 2
    w = 2.0 * np.sqrt(np.maximum(d2, 0.0)) if dim2 else np.pi * np.maximum(d2, 0.0)
    return np.bincount(bins.ravel(), weights=w.ravel(), minlength=int(bins.max()) + 1)


def bed_surface_height(heights, radius, dim2: bool, fraction: float = BED_SURFACE_FRACTION) -> float:
    """Height of the bed surface above the floor [m]: the top of the highest level z where the horizontally
    averaged solids fraction φ(z) is at least ``fraction`` of its mean over [0, H], H the surface itself.

    H is found by iteration from the highest particle top: the mean over [0, H] is taken, H moves down to the
    highest level that reaches ``fraction`` of it, and so on until H stays (a lower H raises the mean, so H
    only falls; two or three rounds). φ is sampled ``PROFILE_STEPS_PER_DIAMETER`` times per mean diameter
    (``solids_profile``); the width of the bed cancels from the criterion. Particles thrown up into the
    freeboard hold φ there far below half the bed's, unless they crowd a level as densely as the bed; a
    uniform slab's profile falls from its mean to zero within its top layer and gives the slab's top within
    a tenth of a radius. NaN without particles. (This package's definition: the axial-profile reading of a
    bed's height, which ``mean_particle_height_m``, a mean of centre heights, is not.)
    """
    h = np.asarray(heights, float)
    r = np.asarray(radius, float)
    if h.size == 0:
        return math.nan
    step = 2.0 * float(r.mean()) / PROFILE_STEPS_PER_DIAMETER
    prof = solids_profile(h, r, dim2, step)
    top = float(np.max(h + r))
    cum = np.cumsum(prof) * step  # solids below the top of each bin
    for _ in range(200):
        nb = max(min(int(np.ceil(top / step - 1e-9)), prof.size), 1)
        mean = cum[nb - 1] / (nb * step)
        keep = np.flatnonzero(prof[:nb] >= fraction * mean)
        new = (keep[-1] + 1) * step if keep.size else top
        if new >= top:
            break
        top = new
    return float(min(top, np.max(h + r)))


def bed_probes(sim) -> dict[str, float]:
    """probes.csv columns of a fluidised bed: N_c statistics, mean and surface height, pressure drop."""
    eng = sim.engine
    nc = contact_numbers(eng)
    out = {"mean_particle_height_m": sim.mean_height(), "bed_surface_height_m": sim.bed_surface_height(),
           "multicontact_ratio": multicontact_ratio(nc),
           "particles_in_contact": int(np.count_nonzero(nc >= 1))}
    gas = getattr(sim, "gas", None)
    if gas is not None and gas.grid.dimensions == 3:  # pressure drops along gravity; the maps below are 2D
        grid = gas.grid
        axis = up_axis(grid, eng.gravity)
        top = grid.size[axis]
        if PRESSURE_PROBE_HEIGHT < top:
            out["pressure_drop_20cm_Pa"] = pressure_drop(grid, gas.state.p, PRESSURE_PROBE_HEIGHT, axis)
        out["pressure_drop_bed_Pa"] = pressure_drop(grid, gas.state.p, top, axis)
    elif gas is not None:
        grid = gas.grid
        top = grid.y_centres[-1] + 0.5 * grid.dy
        if PRESSURE_PROBE_HEIGHT < top:
            out["pressure_drop_20cm_Pa"] = pressure_drop(grid, gas.state.p, PRESSURE_PROBE_HEIGHT)
            # Hoomans 1996 Figs 11/13: the (gauge) pressure 20 cm above the central jet
            width = grid.x_centres[-1] + 0.5 * grid.dx
            out["pressure_20cm_gauge_Pa"] = (pressure_at(grid, gas.state.p, 0.5 * width, PRESSURE_PROBE_HEIGHT)
                                             - sim.case.gas.properties.reference_pressure)
        out["pressure_drop_bed_Pa"] = pressure_drop(grid, gas.state.p, top)
        out["bubble_area_m2"] = bubble_area(grid, gas.state.voidage)
        if hasattr(eng, "external_force"):  # soft spheres (hard-sphere collisions have no contact force)
            out["contact_drag_ratio_max"] = largest_force_ratio(grid, eng)
    return out


def largest_force_ratio(grid, engine) -> float:
    """The largest cell ratio of contact force to gas force now (Sun 2007 Figs 7/12: "contact forces
    may be as high as 100 times that of the drag forces"); NaN when no cell has both."""
    st = engine.state
    ratio = cell_force_maps(grid, st.position, st.mass, contact_force(engine), gas_force(engine),
                            engine.gravity)["force_ratio"]
    ratio = ratio[np.isfinite(ratio) & (ratio >= 0.0)]
    return float(ratio.max()) if ratio.size else math.nan


def cell_force_maps(grid, position, mass, contact, drag, gravity) -> dict[str, np.ndarray]:
    """Cell maps (nx, ny) of mean |F_contact|/(m g), mean |F_drag|/(m g) and their ratio (Sun Figs 7/12).

    Cells without particles are NaN; the ratio is −1 where the drag is zero (Sun's legend).
    """
    nx, ny = grid.shape
    i = np.clip((position[:, 0] / grid.dx).astype(np.int64), 0, nx - 1)
    j = np.clip((position[:, 1] / grid.dy).astype(np.int64), 0, ny - 1)
    cell = i * ny + j
    weight = mass * np.linalg.norm(gravity)
    fc = np.linalg.norm(contact, axis=1) / weight
    fd = np.linalg.norm(drag, axis=1) / weight
    count = np.bincount(cell, minlength=nx * ny).reshape(nx, ny).astype(float)
    sc = np.bincount(cell, weights=fc, minlength=nx * ny).reshape(nx, ny)
    sd = np.bincount(cell, weights=fd, minlength=nx * ny).reshape(nx, ny)
    with np.errstate(invalid="ignore", divide="ignore"):
        mc = np.where(count > 0, sc / count, np.nan)
        md = np.where(count > 0, sd / count, np.nan)
        ratio = np.where(count > 0, np.where(sd > 0, sc / np.where(sd > 0, sd, 1.0), -1.0), np.nan)
    return {"contact_force": mc, "drag_force": md, "force_ratio": ratio, "particles": count}


def averaging_window(t_end: float, window=SUN_WINDOW, t_start: float = 0.0) -> tuple[float, float]:
    """(t0, t1) [s] of the time averages over a record from ``t_start`` to ``t_end`` [s]: Sun's 5–10 s
    ``window`` when the record covers it, else the record's second half."""
    tol = 1e-9 * max(abs(t_end), 1.0)
    if t_start <= window[0] + tol and t_end >= window[1] - tol:
        return float(window[0]), float(window[1])
    return t_start + 0.5 * (t_end - t_start), t_end


AVERAGED = {  # probes.csv column → summary key of its time average
    "mean_particle_height_m": "mean_particle_height_avg_m",
    "bed_surface_height_m": "bed_surface_height_avg_m",
    "coordination": "coordination_number_avg",
    "multicontact_ratio": "multicontact_ratio_avg",
    "pressure_drop_20cm_Pa": "pressure_drop_20cm_avg_Pa",
    "pressure_drop_bed_Pa": "pressure_drop_bed_avg_Pa",
    "contact_drag_ratio_max": "contact_drag_ratio_max_avg",
}


def time_averages(probes_csv: str | Path, t_end: float) -> dict:
    """Summary entries: time averages of the bed probes over ``averaging_window`` (with a bed of several
    species also of ``height_<species>_m``, ``segregation_index`` and ``lacey_index``, ``analysis.mixing``:
    ``height_<species>_avg_m``, ``segregation_index_avg``, ``lacey_index_avg``), and the spectrum of the
    20 cm pressure drop there (``analysis.spectrum``): the frequency of its highest peak and its highest
    peaks with their relative heights, when the window holds enough samples for a spectrum."""
    path = Path(probes_csv)
    if not path.exists():
        return {}
    cols = read_probes(path)
    if "time_s" not in cols or cols["time_s"].size == 0:
        return {}
    a, b = averaging_window(t_end)
    t = cols["time_s"]
    sel = (t >= a - 1e-9) & (t <= b + 1e-9)
    out: dict = {"averages_window_s": [a, b], "averages_samples": int(sel.sum())}
    mixing = {c: (c[:-2] + "_avg_m" if c.endswith("_m") else c + "_avg") for c in cols
              if (c.startswith("height_") and c.endswith("_m")) or c in ("segregation_index", "lacey_index")}
    for col, key in {**AVERAGED, **mixing}.items():
        if col not in cols or not sel.any():
            continue
        vals = cols[col][sel]
        vals = vals[np.isfinite(vals)]
        out[key] = float(vals.mean()) if vals.size else None
    if "bubble_area_m2" in cols:  # over the whole run: does a bubble ever form?
        areas = cols["bubble_area_m2"]
        out["bubble_max_area_m2"] = float(areas.max())
        out["bubble_detected"] = bool(areas.max() > 0.0)
    if "pressure_drop_20cm_Pa" in cols and sel.sum() >= SPECTRUM_MIN_SAMPLES:
        s = cols["pressure_drop_20cm_Pa"][sel]
        f = dominant_frequency(t[sel], s)
        out["pressure_20cm_dominant_frequency_Hz"] = f if math.isfinite(f) else None
        peaks, heights = spectral_peaks(t[sel], s)
        out["pressure_20cm_spectral_peaks_Hz"] = peaks
        out["pressure_20cm_spectral_peak_heights"] = heights
    return out


def wen_yu_umf(diameter: float, particle_density: float, gas_density: float, viscosity: float,
               g: float = 9.81) -> float:
    """Minimum fluidisation velocity [m/s] of Wen & Yu (1966): Re_mf = sqrt(33.7² + 0.0408 Ar) − 33.7."""
    ar = gas_density * (particle_density - gas_density) * g * diameter**3 / viscosity**2
    return (math.sqrt(33.7**2 + 0.0408 * ar) - 33.7) * viscosity / (gas_density * diameter)


def minimum_fluidisation(superficial, pressure_drop_pa, weight_per_area: float, fixed_below: float = 0.8,
                         fluidised_above: float = 1.3) -> dict:
    """u_mf from a sweep of superficial velocity, as measured in the laboratory.

    The samples are in sweep order (rising U). The fixed-bed branch (the samples before Δp
    first reaches ``fixed_below`` W/A) is fitted by least squares
    with Ergun's form Δp = a U + b U² (a, b ≥ 0); u_mf is where that curve reaches the bed weight over
    area W/A. The plateau is the mean Δp over U > ``fluidised_above`` u_mf.
    Returns ``umf``, ``plateau_Pa``, ``a``, ``b`` (NaN where the sweep lacks the points).
    """
    u = np.asarray(superficial, float)
    dp = np.asarray(pressure_drop_pa, float)
    # the fixed bed: the points of a rising sweep before Δp first reaches fixed_below W/A
    over = np.flatnonzero(dp >= fixed_below * weight_per_area)
    fixed = (np.arange(u.size) < (over[0] if over.size else u.size)) & (u > 0)
    out = {"umf": math.nan, "plateau_Pa": math.nan, "a": math.nan, "b": math.nan}
    if fixed.sum() < 3:
        return out
    from scipy.optimize import nnls

    A = np.column_stack([u[fixed], u[fixed] ** 2])
    (a, b), _ = nnls(A, dp[fixed])  # Ergun's coefficients are not negative
    if b > 1e-12 * abs(a):
        umf = (-a + math.sqrt(a * a + 4 * b * weight_per_area)) / (2 * b)
    else:
        umf = weight_per_area / a
    out.update(umf=float(umf), a=float(a), b=float(b))
    fluid = u > fluidised_above * umf
    if fluid.any():
        out["plateau_Pa"] = float(dp[fluid].mean())
    return out
