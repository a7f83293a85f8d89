"""Particle snapshots in one HDF5 file, indexed by an XDMF file that ParaView opens.

Layout of ``particles.h5``: ``/snapshots/<6-digit index>/{position, velocity, omega,
diameter, species, id}`` (and ``image``, (N, 3) int, in a box with periodic sides: the crossings of each
side, with the attribute ``period``, the box length L along each periodic axis: position + image · L is the
unwrapped position) plus the writer's extra fields (e.g. ``contacts`` N_c,
``contact_force``, ``gas_force``), with attributes ``time`` [s] and ``step``. ``particles.xdmf`` is a temporal
collection of Polyvertex grids pointing at those datasets; each snapshot appends its grid
in one write (``io/xdmf.py``), so it is valid between snapshots, and it is written whole again on
resume. ``snapshot_index``, ``snapshot_fields``, ``read_snapshot`` and ``iter_snapshots`` read the
file back.
"""
from __future__ import annotations

from pathlib import Path

import h5py
import numpy as np

from ..schedule import EveryTime
from .atomic import write_text_atomic
from .xdmf import XdmfIndex, document, drop_after

SNAPSHOT_FILE = "particles.h5"
SNAPSHOT_INDEX = "particles.xdmf"


class ParticleWriter:
    """Observer writing particle snapshots; ``schedule`` decides when."""

    def __init__(self, out_dir: Path, schedule=None, extra_fields=None):
        self.path = Path(out_dir) / SNAPSHOT_FILE
        self.xdmf = Path(out_dir) / SNAPSHOT_INDEX
        self.schedule = schedule or EveryTime(0.01)
        self.extra_fields = extra_fields or {}
        # (key, time) of the file's snapshots: read from the file once, then kept up to date here (reading
        # every snapshot's time back on each write made a run's output cost grow with the square of its length)
        self._times: list[tuple[str, float, int]] | None = None
        # particles.xdmf, appended to one grid a snapshot (io/xdmf.py); _layout: the particle count and fields
        # of the grids in it (a snapshot with others has the whole index written again in its layout)
        self._index = XdmfIndex(self.xdmf, "particles")
        self._layout = None

    def __call__(self, sim) -> None:
        st = sim.engine.state
        with h5py.File(self.path, "a") as f:
            grp = f.require_group("snapshots")
            if self._times is None:
                self._times = _times(grp)
            key = f"{len(grp):06d}"
            g = grp.create_group(key)
            g.attrs["time"] = sim.time
            g.attrs["step"] = sim.steps
            # rows in the order of the particles' ids (a soft-sphere engine may renumber its particles in
            # cell order, state.ids follows them): row k is particle k in every snapshot
            by_id = _id_order(st.ids)
            data = {"position": st.position[by_id], "velocity": st.velocity[by_id], "omega": st.omega[by_id],
                    "diameter": 2.0 * st.radius[by_id], "species": st.species[by_id].astype(np.int32),
                    "id": st.ids[by_id]}
            if getattr(sim.engine, "periodic", False):  # periodic sides: the counts that unwrap the positions
                data["image"] = st.image[by_id]
                g.attrs["period"] = sim.engine.period  # (3,) [m] box length along each periodic axis, else 0
            for name, fn in self.extra_fields.items():
                data[name] = np.asarray(fn(sim))[by_id]
            for name, value in data.items():
                g[name] = value
            fields = _field_layout(data)  # from the arrays: reading the datasets back cost ~3 ms a snapshot
        self._times.append((key, float(sim.time), st.n))
        times = self._times

        def all_grids():
            return [grid_text(self.path.name, k, t, n, fields) for k, t, n in times]

        if fields != self._layout:
            self._index.rewrite(all_grids())
            self._layout = fields
        else:  # each grid with its own particle count (inlets and outlets change it)
            self._index.append(grid_text(self.path.name, key, float(sim.time), st.n, fields), all_grids)

    def finalize(self, sim) -> None:
        """At the end of a run: the index to disk (each snapshot's append is not synced)."""
        self._index.sync()

    def truncate_after(self, step: int) -> None:
        """Drop snapshots later than ``step`` (used on resume)."""
        if not self.path.exists():
            return
        with h5py.File(self.path, "a") as f:
            grp = f.require_group("snapshots")
            drop_after(grp, step)
            times = self._times = _times(grp)
            fields = _field_layout(grp[times[-1][0]]) if times else None
        self._layout = None  # the next snapshot writes the index whole
        write_text_atomic(self.xdmf, xdmf_text(self.path.name, times, fields))


def _id_order(ids: np.ndarray):
    """Index putting the rows in id order: a slice if they are in it already."""
    if ids.size == 0 or (ids[0] == 0 and np.all(np.diff(ids) == 1)):
        return slice(None)
    return np.argsort(ids, kind="stable")


def _times(grp) -> list[tuple[str, float, int]]:
    """(key, time, particle count) of the snapshots in ``grp``, in order."""
    return [(k, float(grp[k].attrs["time"]), int(grp[k]["position"].shape[0])) for k in sorted(grp)]


def _field_layout(group) -> dict[str, tuple[str, int, str, int]]:
    """name → (XDMF attribute type, components, number type, precision) of a snapshot's datasets, in the
    order HDF5 lists a group's members (by name); ``group`` is an h5py group or a dict of arrays."""
    out = {}
    for name in sorted(group):
        if name == "position":
            continue
        ds = group[name]
        comp = ds.shape[1] if ds.ndim == 2 else 1
        num = "Int" if np.issubdtype(ds.dtype, np.integer) else "Float"
        out[name] = ("Vector" if comp == 3 else "Scalar", comp, num, ds.dtype.itemsize)
    return out


def grid_text(h5name: str, key: str, t: float, n: int, fields) -> str:
    """The XDMF ``<Grid>`` element of one snapshot (``xdmf_text`` joins them)."""
    attrs = []
    for name, (kind, comp, num, prec) in fields.items():
        dims = f"{n} {comp}" if comp > 1 else f"{n}"
        attrs.append(
            f'      <Attribute Name="{name}" AttributeType="{kind}" Center="Node">\n'
            f'        <DataItem Dimensions="{dims}" NumberType="{num}" Precision="{prec}" Format="HDF">'
            f"{h5name}:/snapshots/{key}/{name}</DataItem>\n      </Attribute>"
        )
    return (
        f'    <Grid Name="particles_{key}" GridType="Uniform">\n'
        f'      <Time Value="{t:.9g}"/>\n'
        f'      <Topology TopologyType="Polyvertex" NumberOfElements="{n}" NodesPerElement="1"/>\n'
        f'      <Geometry GeometryType="XYZ">\n'
        f'        <DataItem Dimensions="{n} 3" NumberType="Float" Precision="8" Format="HDF">'
        f"{h5name}:/snapshots/{key}/position</DataItem>\n      </Geometry>\n"
        + "\n".join(attrs)
        + "\n    </Grid>"
    )


def xdmf_text(h5name: str, times: list[tuple[str, float, int]], fields) -> str:
    """The whole ``particles.xdmf``: one grid of n particles with ``fields`` (``_field_layout``; None
    when ``times`` is empty) per (key, time, n) in ``times``."""
    return document("particles", [grid_text(h5name, key, t, n, fields) for key, t, n in times])


def _snapshot_file(path: str | Path) -> Path:
    """``path`` itself, or the ``particles.h5`` in it when it is a run directory."""
    path = Path(path)
    return path / SNAPSHOT_FILE if path.is_dir() else path


def _snapshots_group(f: h5py.File):
    """The ``/snapshots`` group of an open ``particles.h5``; KeyError without one."""
    grp = f.get("snapshots")
    if grp is None:
        raise KeyError(f"{Path(f.filename).name} has no /snapshots group")
    return grp


def snapshot_index(path: str | Path) -> list[tuple[str, float]]:
    """(group key, time [s]) of every snapshot of a ``particles.h5``, in order.

    ``path`` is a run directory or the file. Raises ``FileNotFoundError`` (``OSError``) without a
    readable file and ``KeyError`` when it has no ``/snapshots`` group or a snapshot no time.
    """
    with h5py.File(_snapshot_file(path), "r") as f:
        grp = _snapshots_group(f)
        return [(k, float(grp[k].attrs["time"])) for k in sorted(grp)]


def snapshot_fields(path: str | Path, index: int = 0) -> tuple[str, ...]:
    """Names of the datasets of snapshot ``index`` of a ``particles.h5``, sorted; nothing else is read.
    Raises as ``read_snapshot`` does."""
    with h5py.File(_snapshot_file(path), "r") as f:
        grp = _snapshots_group(f)
        return tuple(grp[sorted(grp)[index]])


def read_snapshot(path: str | Path, index: int = -1) -> dict:
    """Snapshot ``index`` (negative counts from the end) of a ``particles.h5``: its datasets as arrays by
    name (``position`` (N, 3) [m], ``velocity`` (N, 3) [m/s], ``diameter`` (N,) [m], ``species``, ``id``
    and the writer's extra fields) plus ``time`` [s] (and ``period`` (3,) [m] in a box with periodic sides, with
    the dataset ``image``). ``path`` is a run directory or the file.
    Raises as ``snapshot_index`` does, and ``IndexError`` for an index the file does not have."""
    with h5py.File(_snapshot_file(path), "r") as f:
        grp = _snapshots_group(f)
        g = grp[sorted(grp)[index]]
        out = {k: np.asarray(g[k]) for k in g}
        out["time"] = float(g.attrs["time"])
        if "period" in g.attrs:  # a box with periodic sides: position + image · period unwraps the positions
            out["period"] = np.asarray(g.attrs["period"])
    return out


def iter_snapshots(path: str | Path, fields=None, indices=None):
    """Yield (time [s], {field: array}) for every snapshot of a ``particles.h5`` in order (or those at
    ``indices``), opening the file once.

    ``fields``: the dataset names to read (default all); a snapshot without one leaves it out.
    ``path`` is a run directory or the file. Raises as ``snapshot_index`` and ``read_snapshot`` do.
    """
    with h5py.File(_snapshot_file(path), "r") as f:
        grp = _snapshots_group(f)
        keys = sorted(grp)
        for k in range(len(keys)) if indices is None else indices:
            g = grp[keys[k]]
            names = list(g) if fields is None else [name for name in fields if name in g]
            yield float(g.attrs["time"]), {name: np.asarray(g[name]) for name in names}
