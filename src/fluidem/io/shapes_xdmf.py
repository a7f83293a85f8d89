"""The wall shapes' triangles at each particle snapshot time, in one HDF5 file indexed by an XDMF file that
ParaView opens beside ``particles.xdmf`` (``shapes.h5``, ``shapes.xdmf``).

Layout of ``shapes.h5`` (float64 [m], int64 connectivity, int32 shape indices)::

    /static/points         (3 T_s, 3)  corners of the triangles of the shapes without motion (written once)
    /static/connectivity   (T_s, 3)    rows 3 t, 3 t + 1, 3 t + 2 of points: triangle t
    /static/shape          (T_s,)      index of each triangle's shape (the order of the case's shape walls)
    /moving/connectivity, /moving/shape   the same for the triangles of the moving shapes
    /snapshots/<6-digit index>/points   (3 T_m, 3) their corners at that time; attrs time [s], step

The triangles are those of ``ShapeSet.world_triangles`` (a segment as a flat triangle, a cylinder as 64),
static ones first, each part in the order of that array. ``shapes.xdmf`` is a temporal collection with one
spatial collection per snapshot: a ``Triangle`` grid ``static`` (the same datasets at every time) and a
``Triangle`` grid ``moving`` (that snapshot's points), each with the cell attribute ``shape``; a part
without triangles is left out. Each snapshot appends its grid in one write (``io/xdmf.py``).
"""
from __future__ import annotations

from pathlib import Path

import h5py
import numpy as np

from ..schedule import EveryTime
from .atomic import write_text_atomic
from .xdmf import XdmfIndex, document, drop_after

SHAPES_SNAPSHOT_FILE = "shapes.h5"
SHAPES_SNAPSHOT_INDEX = "shapes.xdmf"


def moving_triangles(shapes) -> np.ndarray:
    """(T,) bool: the triangles of ``shapes.world_triangles`` whose shape moves (a wall with a motion)."""
    owner = shapes.triangle_shapes()
    moving = np.array([s.source.motion is not None for s in shapes.shapes], dtype=bool)
    return moving[owner] if owner.size else np.zeros(0, dtype=bool)


class ShapeSnapshotWriter:
    """Observer writing the shapes' triangles at its schedule's times (those of the particle snapshots)."""

    def __init__(self, out_dir: Path, schedule=None):
        self.path = Path(out_dir) / SHAPES_SNAPSHOT_FILE
        self.xdmf = Path(out_dir) / SHAPES_SNAPSHOT_INDEX
        self.schedule = schedule or EveryTime(0.01)
        self._times: list[tuple[str, float]] | None = None
        self._index = XdmfIndex(self.xdmf, "shapes")

    def __call__(self, sim) -> None:
        shapes = sim.engine.shapes
        with h5py.File(self.path, "a") as f:
            if "static" not in f:
                _write_parts(f, shapes)
            grp = f.require_group("snapshots")
            if self._times is None:
                self._times = _times(grp)
            counts = _counts(f)
            key = f"{len(grp):06d}"
            g = grp.create_group(key)
            g.attrs["time"] = sim.time
            g.attrs["step"] = sim.steps
            tri = shapes.world_triangles(sim.time)[moving_triangles(shapes)]
            g["points"] = tri.reshape(-1, 3)
        self._times.append((key, float(sim.time)))
        times = self._times
        self._index.append(grid_text(self.path.name, key, float(sim.time), counts),
                           lambda: [grid_text(self.path.name, k, t, counts) for k, t in times])

    def finalize(self, sim) -> None:
        """At the end of a run: the index to disk (each snapshot's append is not synced)."""
        self._index.sync()

    def truncate_after(self, step: int) -> None:
        """Drop snapshots later than ``step`` (used on resume) and write the index again."""
        if not self.path.exists():
            return
        with h5py.File(self.path, "a") as f:
            grp = f.require_group("snapshots")
            drop_after(grp, step)
            times = self._times = _times(grp)
            counts = _counts(f) if "static" in f else (0, 0)
        self._index.forget()
        write_text_atomic(self.xdmf, document("shapes", [grid_text(self.path.name, k, t, counts)
                                                         for k, t in times]))


def _write_parts(f: h5py.File, shapes) -> None:
    """The parts written once: the static triangles, and the connectivity and shape indices of both parts."""
    tri = shapes.world_triangles(0.0)
    owner = shapes.triangle_shapes().astype(np.int32)
    moving = moving_triangles(shapes)
    for name, sel in (("static", ~moving), ("moving", moving)):
        g = f.create_group(name)
        n = int(np.count_nonzero(sel))
        g["connectivity"] = np.arange(3 * n, dtype=np.int64).reshape(n, 3)
        g["shape"] = owner[sel]
        if name == "static":
            g["points"] = tri[sel].reshape(-1, 3)


def _counts(f: h5py.File) -> tuple[int, int]:
    """(static triangles, moving triangles) of an open ``shapes.h5``."""
    return int(f["static/shape"].shape[0]), int(f["moving/shape"].shape[0])


def _times(grp) -> list[tuple[str, float]]:
    return [(k, float(grp[k].attrs["time"])) for k in sorted(grp)]


def _part(h5name: str, name: str, n: int, points: str) -> str:
    """A ``Triangle`` grid of n triangles, its corners at the dataset ``points``."""
    return (
        f'      <Grid Name="{name}" GridType="Uniform">\n'
        f'        <Topology TopologyType="Triangle" NumberOfElements="{n}">\n'
        f'          <DataItem Dimensions="{n} 3" NumberType="Int" Precision="8" Format="HDF">'
        f"{h5name}:/{name}/connectivity</DataItem>\n        </Topology>\n"
        f'        <Geometry GeometryType="XYZ">\n'
        f'          <DataItem Dimensions="{3 * n} 3" NumberType="Float" Precision="8" Format="HDF">'
        f"{h5name}:{points}</DataItem>\n        </Geometry>\n"
        f'        <Attribute Name="shape" AttributeType="Scalar" Center="Cell">\n'
        f'          <DataItem Dimensions="{n}" NumberType="Int" Precision="4" Format="HDF">'
        f"{h5name}:/{name}/shape</DataItem>\n        </Attribute>\n"
        f"      </Grid>"
    )


def grid_text(h5name: str, key: str, t: float, counts: tuple[int, int]) -> str:
    """The XDMF spatial collection of one snapshot: the static and the moving triangles at time t."""
    parts = []
    if counts[0]:
        parts.append(_part(h5name, "static", counts[0], "/static/points"))
    if counts[1]:
        parts.append(_part(h5name, "moving", counts[1], f"/snapshots/{key}/points"))
    return (f'    <Grid Name="shapes_{key}" GridType="Collection" CollectionType="Spatial">\n'
            f'      <Time Value="{t:.9g}"/>\n' + "\n".join(parts) + "\n    </Grid>")
