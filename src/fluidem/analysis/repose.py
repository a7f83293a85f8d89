"""Dynamic angle of repose of the bed in a rotating drum, from the particle positions.

``repose_angle(position, radius, drum)`` measures the free surface's inclination to the horizontal in the
plane across the drum's axis: positions are taken in the drum's frame (along the axis; across it,
horizontally; up, against gravity), the particles within two largest diameters of either end plate are left
out (their friction holds the surface up there), the middle half of the drum's diameter (|across| <= R/2,
where the rolling surface is flat and its curved ends at the wall are left out) is cut into bins across it of
about one and a half largest diameters, the highest particle centre of each bin marks the surface there, and a
straight line is fitted by least squares to those centres (height against across). The angle
is atan |slope| in degrees. ``drum_of(case)`` finds the drum of a case: a cylinder wall with particles inside,
rotating (``motion.kind = 'rotation'``) about its own axis, which lies across gravity.

Orchestration only (NumPy on arrays, no loop over particles).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

END_GAP = 2.0  # largest diameters left out beside each end plate
BIN_WIDTH = 1.5  # bin width across the drum [largest diameters]
MIDDLE = 0.5  # fit over |across| <= MIDDLE R
MIN_BINS = 4  # fewer bins with particles: no angle (NaN)


@dataclass(frozen=True)
class Drum:
    """A drum: a point of its axis at one end [m], the unit axis, radius and length [m], the unit vector
    against gravity in the plane across the axis ("up"), and the unit horizontal across the axis."""

    point: np.ndarray
    axis: np.ndarray
    radius: float
    length: float
    up: np.ndarray
    across: np.ndarray

    @classmethod
    def of(cls, point, axis, radius, length, gravity) -> "Drum":
        a = np.asarray(axis, float) / np.linalg.norm(axis)
        g = np.asarray(gravity, float)
        up = -(g - (g @ a) * a)
        up /= np.linalg.norm(up)
        return cls(np.asarray(point, float), a, float(radius), float(length), up, np.cross(a, up))


def drum_of(case) -> Drum | None:
    """The case's drum (the first cylinder wall with ``inside`` particles whose ``rotation`` motion turns it
    about its own axis, that axis across gravity), or None."""
    g = np.asarray(case.gravity, float)
    if not np.linalg.norm(g) > 0.0:
        return None
    for w in case.walls:
        m = w.motion
        if w.kind != "cylinder" or not w.inside or m is None or m.kind != "rotation":
            continue
        a = np.asarray(w.axis, float) / np.linalg.norm(w.axis)
        b = np.asarray(m.axis, float) / np.linalg.norm(m.axis)
        off = np.asarray(m.axis_point, float) - np.asarray(w.point, float)
        same_axis = abs(abs(a @ b) - 1.0) < 1e-9 and np.linalg.norm(off - (off @ a) * a) <= 1e-9 * w.radius
        if same_axis and abs(a @ g) <= 1e-6 * np.linalg.norm(g):
            return Drum.of(w.point, w.axis, w.radius, w.length, g)
    return None


def surface_profile(position: np.ndarray, radius: np.ndarray, drum: Drum) -> tuple[np.ndarray, np.ndarray]:
    """(across (B,), height (B,)) [m]: the highest particle centre (up from the axis) of each bin across the
    drum that holds a particle of the drum's middle (``END_GAP`` largest diameters from each end), bins of
    about ``BIN_WIDTH`` largest diameters tiling |across| <= ``MIDDLE`` R; across is that particle's own.

    position : (N, 3) float64 particle centres [m]; radius : (N,) float64 [m]."""
    if position.shape[0] == 0:
        return np.zeros(0), np.zeros(0)
    d = 2.0 * float(np.max(radius))
    rel = position - drum.point
    along = rel @ drum.axis
    x = rel @ drum.across
    h = rel @ drum.up
    half = MIDDLE * drum.radius
    keep = (along > END_GAP * d) & (along < drum.length - END_GAP * d) & (np.abs(x) <= half)
    if not keep.any():
        return np.zeros(0), np.zeros(0)
    nbins = max(int(round(2.0 * half / (BIN_WIDTH * d))), 1)
    x, h = x[keep], h[keep]
    k = np.clip(((x + half) / (2.0 * half) * nbins).astype(np.int64), 0, nbins - 1)
    order = np.lexsort((h, k))  # by bin, then height: each bin's last entry is its highest particle
    last = order[np.r_[k[order][1:] != k[order][:-1], True]]
    return x[last], h[last]


def repose_angle(position: np.ndarray, radius: np.ndarray, drum: Drum) -> float:
    """Dynamic angle of repose [deg] of the free surface (module docstring): atan |slope| of the least-squares
    line through the bins' surface heights; NaN with fewer than ``MIN_BINS`` bins."""
    x, h = surface_profile(position, radius, drum)
    if x.size < MIN_BINS:
        return float("nan")
    slope = np.polyfit(x, h, 1)[0]
    return float(math.degrees(math.atan(abs(slope))))


def repose_probes(sim, drum: Drum) -> dict:
    """``repose_angle_deg`` of the particles now, for probes.csv (a case with a drum)."""
    st = sim.engine.state
    return {"repose_angle_deg": repose_angle(st.position, st.radius, drum)}


def summary_entries(sim, drum: Drum) -> dict:
    """Summary entries of a drum run: ``repose_angle_deg`` at the end and ``repose_angle_avg_deg``, the mean of
    the probes' ``repose_angle_deg`` over the second half of the run (the rolling bed after its start)."""
    from ..io.probes_csv import read_probes

    st = sim.engine.state
    out = {"repose_angle_deg": repose_angle(st.position, st.radius, drum)}
    path = Path(sim.out_dir) / "probes.csv" if sim.out_dir is not None else None
    if path is not None and path.exists():
        cols = read_probes(path)
        if "repose_angle_deg" in cols and cols["time_s"].size:
            t = cols["time_s"]
            vals = cols["repose_angle_deg"][t >= 0.5 * sim.time - 1e-9]
            vals = vals[np.isfinite(vals)]
            out["repose_angle_avg_deg"] = float(vals.mean()) if vals.size else None
    return out
