"""Initial particle sets: diameters from each species' distribution, then positions.

Methods (``particles.placement.method``): ``random`` (non-overlapping random fill of a
region; across a periodic side of the box, by nearest image), ``lattice`` (square/cubic lattice with a small random disturbance, Hoomans
1996 §4.1) and ``file`` (CSV or HDF5 list). Overlaps and particles outside the walls
are errors that name the particles.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..errors import CaseError
from ._placement_kernels import random_fill


def species_diameters(sp, count: int, rng) -> np.ndarray:
    """``count`` diameters of species ``sp`` [m]: its ``diameter``, or draws from its ``size_distribution``
    (normal and lognormal clipped to min/max, by default 0.1 and 10 times the diameter)."""
    dist = sp.size_distribution
    if dist is None:
        return np.full(count, sp.diameter)
    if dist.kind == "uniform":
        return rng.uniform(dist.min, dist.max, count)
    if dist.kind == "normal":
        d = rng.normal(sp.diameter, dist.std, count)
    else:
        d = sp.diameter * np.exp(rng.normal(-0.5 * dist.std**2, dist.std, count))
    lo = dist.min if dist.min is not None else 0.1 * sp.diameter
    hi = dist.max if dist.max is not None else 10.0 * sp.diameter
    return np.clip(d, lo, hi)


def draw_diameters(case, rng) -> tuple[np.ndarray, np.ndarray]:
    """(diameter (N,), species index (N,)) for all species of the case."""
    diam, spec = [], []
    for k, sp in enumerate(case.particles.species):
        diam.append(species_diameters(sp, sp.count, rng))
        spec.append(np.full(sp.count, k, dtype=np.int64))
    return np.concatenate(diam), np.concatenate(spec)


def region(case, walls) -> tuple[np.ndarray, np.ndarray]:
    pl = case.particles.placement
    lo = np.array(pl.region_lower) if pl.region_lower is not None else None
    hi = np.array(pl.region_upper) if pl.region_upper is not None else None
    if lo is None or hi is None:
        if walls.box_lower is None:
            raise CaseError("particles.placement: region_lower and region_upper are needed when no box wall is given")
        lo = walls.box_lower if lo is None else lo
        hi = walls.box_upper if hi is None else hi
    for d, ax in enumerate("xyz"):
        if case.particles.dimensions == 2 and d == 2:
            continue
        if not hi[d] > lo[d]:
            raise CaseError(f"particles.placement: region upper {ax} = {hi[d]} must exceed lower {ax} = {lo[d]}")
    return lo.astype(float), hi.astype(float)


def place(case, walls) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(position (N,3), velocity (N,3), diameter (N,), species (N,)) for the case's placement."""
    pl = case.particles.placement
    dim2 = case.particles.dimensions == 2
    if pl.method == "file":
        return read_particle_file(case, Path(pl.file))
    rng = np.random.default_rng(pl.seed)
    diam, spec = draw_diameters(case, rng)
    n = diam.size
    if n == 0:  # every species waits for its inlet
        return np.zeros((0, 3)), np.zeros((0, 3)), diam, spec
    lo, hi = region(case, walls)
    z0 = 0.5 * (lo[2] + hi[2]) if dim2 else 0.0
    if pl.method == "random":
        order = np.argsort(-diam, kind="stable")
        # a periodic axis of the box that the region spans whole: centres anywhere along it, no overlap across
        period = np.where((walls.period > 0.0) & np.isclose(lo, walls.period_lower, rtol=0.0, atol=1e-12)
                          & np.isclose(hi - lo, walls.period, rtol=1e-12, atol=0.0), walls.period, 0.0)
        pos_sorted, placed = random_fill(0.5 * diam[order], lo, hi, dim2, z0, pl.seed % (2**31), 20000, period)
        if placed < n:
            frac = _filled_fraction(diam, lo, hi, dim2)
            raise CaseError(
                f"particles.placement: could place only {placed} of {n} particles at random in the region "
                f"{lo.tolist()}–{hi.tolist()} (solid fraction asked {frac:.2f}); enlarge the region or use "
                f"method = 'lattice'"
            )
        pos = np.empty_like(pos_sorted)
        pos[order] = pos_sorted
    else:
        pitch = pl.spacing * diam.max()
        dims = 2 if dim2 else 3
        counts = [max(1, int(np.floor((hi[d] - lo[d]) / pitch))) for d in range(dims)]
        capacity = int(np.prod(counts))
        if capacity < n:
            raise CaseError(
                f"particles.placement: a lattice of pitch {pitch:.4g} m holds {capacity} particles in the region, "
                f"{n} asked; enlarge the region or lower placement.spacing (>= 1)"
            )
        # fill layer by layer against gravity: the fastest index is x, the slowest the vertical axis
        g = np.array(case.gravity)
        up = int(np.argmax(np.abs(g[:dims])))
        axes = [d for d in range(dims) if d != up] + [up]
        idx = np.arange(n)
        pos = np.zeros((n, 3))
        stride = 1
        for d in axes:
            k = (idx // stride) % counts[d]
            stride *= counts[d]
            start = lo[d] + 0.5 * pitch if g[d] <= 0 else hi[d] - 0.5 * pitch
            step = pitch if g[d] <= 0 else -pitch
            pos[:, d] = start + step * k
        if dim2:
            pos[:, 2] = z0
        shift = rng.uniform(-1.0, 1.0, (n, 3)) * min(pl.perturbation * diam.max(), 0.5 * (pitch - diam.max()))
        if dim2:
            shift[:, 2] = 0.0
        pos += shift
    vel = np.tile(np.array(pl.velocity, dtype=float), (n, 1))
    if dim2:
        vel[:, 2] = 0.0
    return pos, vel, diam, spec


def _filled_fraction(diam, lo, hi, dim2):
    if dim2:
        return float(np.sum(np.pi * diam**2 / 4) / ((hi[0] - lo[0]) * (hi[1] - lo[1])))
    return float(np.sum(np.pi * diam**3 / 6) / np.prod(hi - lo))


def read_particle_file(case, path: Path):
    """Particles from CSV (header x,y,z,diameter[,species][,vx,vy,vz]) or HDF5 datasets of the same names.

    Every number must be finite and each species must have as many rows as its ``count`` (all rows are
    the first species where the file has no species column); otherwise CaseError names the file, the
    row and the column."""
    where = f"particles.placement.file = {str(path)!r}"
    if not path.exists():
        raise CaseError(f"{where}: no such file")
    if path.is_dir():
        raise CaseError(f"{where}: is a folder, not a CSV or HDF5 file")
    names = [s.name for s in case.particles.species]
    csv = path.suffix not in (".h5", ".hdf5")
    if not csv:
        import h5py

        try:
            with h5py.File(path, "r") as f:
                cols = {k: np.asarray(f[k]) for k in f.keys() if isinstance(f[k], h5py.Dataset)}
        except OSError as err:
            raise CaseError(f"{where}: cannot read HDF5: {err}") from None
        if "position" in cols:
            p = cols.pop("position")
            if p.ndim != 2 or p.shape[1] != 3:
                raise CaseError(f"{where}: dataset 'position' has shape {p.shape}; need (N, 3)")
            cols.update(x=p[:, 0], y=p[:, 1], z=p[:, 2])
    else:
        try:
            arr = np.genfromtxt(path, delimiter=",", names=True, dtype=None, encoding="utf-8")
        except Exception as err:  # noqa: BLE001 - report any parse failure as bad input
            raise CaseError(f"{where}: cannot read CSV: {err}") from None
        if arr.dtype.names is None:
            raise CaseError(f"{where}: cannot read CSV: no header line x,y,z,diameter[,species][,vx,vy,vz]")
        arr = np.atleast_1d(arr)
        cols = {k: arr[k] for k in arr.dtype.names}

    def row(k: int) -> str:  # a data row by its particle index, with its line in a CSV (after the header)
        return f"row {k} (line {k + 2})" if csv else f"row {k}"

    for key in ("x", "y", "z", "diameter"):
        if key not in cols:
            raise CaseError(f"{where}: column {key!r} missing (need x, y, z, diameter)")
    n = len(np.atleast_1d(cols["x"]))
    if n == 0:
        raise CaseError(f"{where}: no particle rows (a header only)")

    def numbers(key: str) -> np.ndarray:
        raw = np.atleast_1d(np.asarray(cols[key]))
        if raw.shape != (n,):
            raise CaseError(f"{where}: column {key!r} has {raw.size} values, column 'x' {n}")
        if raw.dtype.kind not in "iuf":
            bad = next((k for k, v in enumerate(raw) if not _is_number(v)), 0)
            raise CaseError(f"{where}: column {key!r}, {row(bad)}: {str(raw[bad])!r} is not a number")
        out = raw.astype(float)
        notfinite = np.flatnonzero(~np.isfinite(out))
        if notfinite.size:
            bad = int(notfinite[0])
            more = f" (and {notfinite.size - 1} more rows)" if notfinite.size > 1 else ""
            note = " (an empty cell reads as nan)" if csv and math.isnan(out[bad]) else ""
            raise CaseError(f"{where}: column {key!r}, {row(bad)}: {float(out[bad])!r}{note}{more}; "
                            "every value must be a finite number")
        return out

    pos = np.column_stack([numbers(k) for k in "xyz"])
    diam = numbers("diameter")
    if np.any(~(diam > 0)):
        bad = int(np.flatnonzero(~(diam > 0))[0])
        raise CaseError(f"{where}: column 'diameter', {row(bad)}: {diam[bad]}; must be > 0")
    if "species" in cols:
        raw = np.atleast_1d(np.asarray(cols["species"]))
        if raw.dtype.kind in "iu":
            spec = np.asarray(raw, np.int64)
        else:
            lookup = {nm: k for k, nm in enumerate(names)}
            try:
                spec = np.array([lookup[s.decode() if isinstance(s, bytes) else str(s)] for s in raw], np.int64)
            except KeyError as err:
                raise CaseError(f"{where}: species {err.args[0]!r} is not one of {names}") from None
        if spec.size and (spec.min() < 0 or spec.max() >= len(names)):
            raise CaseError(f"{where}: species index outside 0..{len(names) - 1}")
    else:
        spec = np.zeros(n, np.int64)
    found = np.bincount(spec, minlength=len(names))
    for k, sp in enumerate(case.particles.species):
        if found[k] != sp.count:
            if "species" in cols:
                how = f"rows of species {sp.name!r}"
            elif k == 0:
                how = f"rows (without a species column every row is the first species, {names[0]!r})"
            else:
                how = f"rows of species {sp.name!r} (the file has no species column)"
            raise CaseError(f"{where}: {found[k]} {how}, but particles.species.{k}.count = {sp.count}; "
                            "the file and the counts must agree")
    vel = np.zeros((n, 3))
    for d, k in enumerate(("vx", "vy", "vz")):
        if k in cols:
            vel[:, d] = numbers(k)
    return pos, vel, diam, spec


def _is_number(value) -> bool:
    try:
        float(value)
    except (TypeError, ValueError):
        return False
    return True
