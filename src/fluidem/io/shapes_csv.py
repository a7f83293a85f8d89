"""The wall shapes of a run: the force and torque on each shape and its pose, one CSV row per probe time
(``shapes.csv`` beside ``probes.csv``), and the shapes' triangles at t = 0 (``shapes.stl``).

Columns of ``shapes.csv``: ``time_s``, ``step``, then per shape ``<name>.fx_N``, ``fy_N``, ``fz_N`` (the
force the particles exert on it), ``tx_Nm``, ``ty_Nm``, ``tz_Nm`` (their torque about the shape's reference
point: its rotation axis point, else the centroid of its corners, moving with it), ``dx_m``, ``dy_m``,
``dz_m`` (its displacement) and ``angle_rad`` (its rotation about its axis). A free body (``motion.kind =
'free'``) has its torque about its centre of mass, its centre of mass's displacement, the angle of its rotation
from rest, and more columns: ``vx_m/s``, ``vy_m/s``, ``vz_m/s`` (velocity of the centre of mass), ``wx_rad/s``,
``wy_rad/s``, ``wz_rad/s`` (angular velocity, world frame) and ``qw``, ``qx``, ``qy``, ``qz`` (the unit
quaternion of its rotation from rest). The forces are those of the last DEM step before the row's time. ``shapes.stl`` holds every triangle (a segment as a flat triangle, a
cylinder as 64) where the case puts it; with the pose columns, ParaView's Transform filter moves it.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..schedule import EveryTime
from .probes_csv import ProbeWriter

SHAPES_FILE = "shapes.csv"
SHAPES_GEOMETRY = "shapes.stl"


def shape_probes(sim) -> dict[str, float]:
    """The columns of one ``shapes.csv`` row (without time and step) for ``sim.engine.shapes``."""
    shapes = sim.engine.shapes
    row = {}
    for k, name in enumerate(shapes.names):
        f = shapes.load[k]
        for j, col in enumerate(("fx_N", "fy_N", "fz_N", "tx_Nm", "ty_Nm", "tz_Nm")):
            row[f"{name}.{col}"] = float(f[j])
        d, angle = shapes.displacement(k, sim.engine.time)
        for j, col in enumerate(("dx_m", "dy_m", "dz_m")):
            row[f"{name}.{col}"] = float(d[j])
        row[f"{name}.angle_rad"] = float(angle)
        if shapes.shapes[k].body is not None:
            b = shapes.body_state(k)
            for j, col in enumerate(("vx_m/s", "vy_m/s", "vz_m/s")):
                row[f"{name}.{col}"] = float(b["velocity"][j])
            for j, col in enumerate(("wx_rad/s", "wy_rad/s", "wz_rad/s")):
                row[f"{name}.{col}"] = float(b["angular_velocity"][j])
            for j, col in enumerate(("qw", "qx", "qy", "qz")):
                row[f"{name}.{col}"] = float(b["quaternion"][j])
    return row


class ShapeWriter(ProbeWriter):
    """Observer appending a row of ``shape_probes`` to shapes.csv (and writing shapes.stl at its first call)."""

    def __init__(self, out_dir: Path, schedule=None):
        super().__init__(out_dir, [shape_probes], schedule or EveryTime(0.001))
        self.path = Path(out_dir) / SHAPES_FILE
        self.geometry = Path(out_dir) / SHAPES_GEOMETRY

    def __call__(self, sim) -> None:
        if not self.geometry.exists():
            write_stl(self.geometry, sim.engine.shapes.world_triangles(0.0))
        super().__call__(sim)


def write_stl(path: Path, triangles: np.ndarray) -> None:
    """(T, 3, 3) triangles as a binary STL file (numpy-stl)."""
    from stl import mesh

    m = mesh.Mesh(np.zeros(len(triangles), dtype=mesh.Mesh.dtype))
    m.vectors[:] = triangles
    m.update_normals()
    tmp = Path(str(path) + ".tmp")
    m.save(str(tmp))
    tmp.replace(path)
