"""Walls as planes: each plane has a reference point, an inward unit normal and a motion.

A box wall becomes its axis-aligned planes (four in 2D, six in 3D, one fewer with
``open_top``), named ``<box>.xmin`` … ``<box>.zmax``; an axis in the box's ``periodic`` list has no planes:
its two sides are joined instead (``WallSet.period``). Motion is a constant velocity
or a sinusoidal oscillation; kernels evaluate it from the time (``wall_state``). The other wall kinds
(polyline, polygon, cylinder, mesh) are shapes (``shapes.py``).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ._softsphere_kernels import CONSTANT_VELOCITY, OSCILLATING, STATIC


@dataclass
class WallPlane:
    name: str
    point: np.ndarray
    normal: np.ndarray
    source: object  # the case's Wall entry (material, contact overrides, motion)


@dataclass
class WallSet:
    planes: list[WallPlane] = field(default_factory=list)
    box_lower: np.ndarray | None = None
    box_upper: np.ndarray | None = None
    # the length [m] of the box along each periodic axis, 0 along the others (no periodic side: all 0)
    period: np.ndarray = field(default_factory=lambda: np.zeros(3))
    period_lower: np.ndarray = field(default_factory=lambda: np.zeros(3))  # that box's lower corner [m]

    @property
    def names(self) -> list[str]:
        return [p.name for p in self.planes]

    def arrays(self):
        """(point0 (W,3), normal (W,3), motion (W,6)) float64 tables for the kernels."""
        w = len(self.planes)
        point = np.zeros((w, 3))
        normal = np.zeros((w, 3))
        motion = np.zeros((w, 6))
        for k, pl in enumerate(self.planes):
            point[k] = pl.point
            normal[k] = pl.normal
            m = pl.source.motion
            if m is None:
                motion[k, 0] = STATIC
            elif m.kind == "constant_velocity":
                motion[k, 0] = CONSTANT_VELOCITY
                motion[k, 1:4] = m.velocity
            else:
                motion[k, 0] = OSCILLATING
                motion[k, 1:4] = m.amplitude
                motion[k, 4] = m.frequency
                motion[k, 5] = m.phase
        return point, normal, motion


def build_walls(case) -> WallSet:
    dim2 = case.particles.dimensions == 2
    g = np.array(case.gravity)
    ws = WallSet()
    for wall in case.walls:
        if wall.kind not in ("plane", "box"):
            continue  # a wall shape (shapes.py)
        if wall.kind == "plane":
            n = np.array(wall.normal, float)
            n /= np.linalg.norm(n)
            if dim2 and abs(n[2]) > 1e-12:
                from ..errors import CaseError

                raise CaseError(
                    f"walls: plane {wall.name!r} has normal {list(wall.normal)} with a z part; in 2D walls lie in the x-y plane"
                )
            ws.planes.append(WallPlane(wall.name, np.array(wall.point, float), n, wall))
            continue
        lo = np.array(wall.lower, float)
        hi = np.array(wall.upper, float)
        ws.box_lower = lo if ws.box_lower is None else np.minimum(ws.box_lower, lo)
        ws.box_upper = hi if ws.box_upper is None else np.maximum(ws.box_upper, hi)
        up_axis = int(np.argmax(np.abs(g))) if np.any(g) else None
        for d, ax in enumerate("xyz"):
            if dim2 and d == 2:
                continue
            if ax in wall.periodic:  # a periodic pair of sides, not two walls
                ws.period[d] = hi[d] - lo[d]
                ws.period_lower[d] = lo[d]
                continue
            for side, point, sign in (("min", lo, 1.0), ("max", hi, -1.0)):
                if wall.open_top and d == up_axis and (sign < 0) == (g[d] < 0):
                    continue
                n = np.zeros(3)
                n[d] = sign
                ws.planes.append(WallPlane(f"{wall.name}.{ax}{side}", point.copy(), n, wall))
    return ws
