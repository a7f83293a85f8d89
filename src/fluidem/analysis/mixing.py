"""Per-species analyses of a bed of several species: mean heights, a segregation index, Lacey's mixing index.

``species_heights``     the mean height of each species' particle centres above the floor [m] (the
                        floor and "up" as ``Simulation.mean_height`` takes them: against gravity,
                        from the lower corner of the box).
``segregation_index``   S = 2 (h_a − h_b)/(h_a + h_b) of two species' mean heights: 0 for a mixed
                        bed, > 0 when species a lies above b. Two layers of equal volume, a on top:
                        h_a = 3H/4, h_b = H/4 and S = 1; S is the normalised difference of the species'
                        mean heights used to read the segregation direction of a binary bed (DEM book
                        2012 two-phase chapter §4: the flotsam rises, the jetsam sinks).
``lacey_index``         Lacey's (1954) mixing index over the gas cells, M = (σ₀² − σ²)/(σ₀² − σ_R²):
                        σ² the variance, weighted by each cell's solids volume, of the volume fraction x_c
                        of species a in the solids of cell c (the particles whose centre lies in it), about
                        the bed's fraction p; σ₀² = p (1 − p) of a fully segregated bed; σ_R² = p (1 − p)/n̄
                        of a random mixture with n̄ particles per occupied cell. M = 0 segregated, ≈ 1
                        mixed at random.

``mixing_probes(sim)`` gives the ``probes.csv`` columns of a run with two species or more:
``height_<species>_m`` for each species, and for the first two species ``segregation_index`` and,
with a gas grid, ``lacey_index``. Vectorised NumPy over the particles, between compiled chunks.
"""
from __future__ import annotations

import math

import numpy as np


def _up_and_floor(engine) -> tuple[np.ndarray, float]:
    g = np.asarray(engine.gravity, float)
    gn = float(np.linalg.norm(g))
    up = -g / gn if gn > 0.0 else np.array([0.0, 0.0, 1.0])
    lower = engine.walls.box_lower
    floor = float(np.asarray(lower) @ up) if lower is not None else 0.0
    return up, floor


def species_heights(engine, n_species: int) -> np.ndarray:
    """Mean height above the floor of each species' particle centres [m], (n_species,); NaN for an empty one."""
    st = engine.state
    up, floor = _up_and_floor(engine)
    h = st.position @ up - floor
    count = np.bincount(st.species, minlength=n_species)[:n_species]
    total = np.bincount(st.species, weights=h, minlength=n_species)[:n_species]
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(count > 0, total / np.maximum(count, 1), math.nan)


def segregation_index(height_a: float, height_b: float) -> float:
    """S = 2 (h_a − h_b)/(h_a + h_b) (module docstring); NaN when undefined."""
    s = height_a + height_b
    if not (math.isfinite(s) and s > 0.0):
        return math.nan
    return 2.0 * (height_a - height_b) / s


def lacey_index(grid, position, volume, is_a) -> float:
    """Lacey's mixing index of species ``is_a`` (bool (N,)) over the cells of ``grid`` (module docstring).

    position (N, ≥2) [m], volume (N,) [m³]. NaN when the bed holds only one species or no occupied cell
    has more than one particle on average (σ_R² = σ₀²)."""
    nx, ny = grid.shape
    i = np.clip(np.floor(position[:, 0] / grid.dx).astype(np.int64), 0, nx - 1)
    j = np.clip(np.floor(position[:, 1] / grid.dy).astype(np.int64), 0, ny - 1)
    cell = i * ny + j
    solids = np.bincount(cell, weights=volume, minlength=nx * ny)
    of_a = np.bincount(cell, weights=np.where(is_a, volume, 0.0), minlength=nx * ny)
    number = np.bincount(cell, minlength=nx * ny)
    occupied = solids > 0.0
    if not occupied.any():
        return math.nan
    p = float(of_a.sum() / solids.sum())
    s0 = p * (1.0 - p)
    n_bar = float(number[occupied].mean())
    sr = s0 / n_bar
    if not s0 - sr > 0.0:
        return math.nan
    x = of_a[occupied] / solids[occupied]
    w = solids[occupied]
    var = float(np.sum(w * (x - p) ** 2) / w.sum())
    return (s0 - var) / (s0 - sr)


def mixing_probes(sim) -> dict[str, float]:
    """``probes.csv`` columns of a bed of several species (module docstring)."""
    eng = sim.engine
    names = [s.name for s in sim.case.particles.species]
    h = species_heights(eng, len(names))
    out = {f"height_{name}_m": float(v) for name, v in zip(names, h)}
    out["segregation_index"] = segregation_index(float(h[0]), float(h[1]))
    gas = getattr(sim, "gas", None)
    if gas is not None:
        st = eng.state
        out["lacey_index"] = lacey_index(gas.grid, st.position, math.pi / 6.0 * (2.0 * st.radius) ** 3,
                                         st.species == 0)
    return out
