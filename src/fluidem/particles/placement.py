"""Initial particle sets: diameters from each species' distribution, then positions.

Methods (``particles.placement.method``): ``random`` (non-overlapping random fill of a
region), ``lattice`` (square/cubic lattice with a small random disturbance, Hoomans
1996 §4.1) and ``file`` (CSV or HDF5 list). Overlaps and particles outside the walls
are errors that name the particles.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import CaseError
from ._placement_kernels import random_fill


def draw_diameters(case, rng) -> tuple[np.ndarray, np.ndarray]:
    """(diameter (N,), species index (N,)) for all species of the case."""
    diam, spec = [], []
    for k, sp in enumerate(case.particles.species):
        dist = sp.size_distribution
        if dist is None:
            d = np.full(sp.count, sp.diameter)
        elif dist.kind == "uniform":
            d = rng.uniform(dist.min, dist.max, sp.count)
        else:
            if dist.kind == "normal":
                d = rng.normal(sp.diameter, dist.std, sp.count)
            else:
                d = sp.diameter * np.exp(rng.normal(-0.5 * dist.std**2, dist.std, sp.count))
            lo = dist.min if dist.min is not None else 0.1 * sp.diameter
            hi = dist.max if dist.max is not None else 10.0 * sp.diameter
            d = np.clip(d, lo, hi)
        diam.append(d)
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
    lo, hi = region(case, walls)
    z0 = 0.5 * (lo[2] + hi[2]) if dim2 else 0.0
    if pl.method == "random":
        order = np.argsort(-diam, kind="stable")
        pos_sorted, placed = random_fill(0.5 * diam[order], lo, hi, dim2, z0, pl.seed % (2**31), 20000)
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
    """Particles from CSV (header x,y,z,diameter[,species][,vx,vy,vz]) or HDF5 datasets of the same names."""
    if not path.exists():
        raise CaseError(f"particles.placement.file = {str(path)!r}: no such file")
    names = [s.name for s in case.particles.species]
    if path.suffix in (".h5", ".hdf5"):
        import h5py

        with h5py.File(path, "r") as f:
            cols = {k: np.asarray(f[k]) for k in f.keys() if isinstance(f[k], h5py.Dataset)}
        if "position" in cols:
            p = cols.pop("position")
            cols.update(x=p[:, 0], y=p[:, 1], z=p[:, 2])
    else:
        try:
            arr = np.genfromtxt(path, delimiter=",", names=True, dtype=None, encoding="utf-8")
        except Exception as err:  # noqa: BLE001 - report any parse failure as bad input
            raise CaseError(f"particles.placement.file = {str(path)!r}: cannot read CSV: {err}") from None
        arr = np.atleast_1d(arr)
        cols = {k: arr[k] for k in arr.dtype.names}
    for key in ("x", "y", "z", "diameter"):
        if key not in cols:
            raise CaseError(f"particles.placement.file = {str(path)!r}: column {key!r} missing (need x, y, z, diameter)")
    n = len(cols["x"])
    pos = np.column_stack([np.asarray(cols[k], float) for k in "xyz"])
    diam = np.asarray(cols["diameter"], float)
    if np.any(~(diam > 0)):
        bad = int(np.flatnonzero(~(diam > 0))[0])
        raise CaseError(f"particles.placement.file: diameter of row {bad} is {diam[bad]}; must be > 0")
    if "species" in cols:
        raw = cols["species"]
        if raw.dtype.kind in "iu":
            spec = np.asarray(raw, np.int64)
        else:
            lookup = {nm: k for k, nm in enumerate(names)}
            try:
                spec = np.array([lookup[str(s)] for s in raw], np.int64)
            except KeyError as err:
                raise CaseError(f"particles.placement.file: species {err.args[0]!r} is not one of {names}") from None
        if spec.min() < 0 or spec.max() >= len(names):
            raise CaseError(f"particles.placement.file: species index outside 0..{len(names) - 1}")
    else:
        spec = np.zeros(n, np.int64)
    vel = np.zeros((n, 3))
    for d, k in enumerate(("vx", "vy", "vz")):
        if k in cols:
            vel[:, d] = np.asarray(cols[k], float)
    return pos, vel, diam, spec
