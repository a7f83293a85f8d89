"""Gas fields at cell centres in one HDF5 file, indexed by an XDMF file that ParaView opens.

``GasFieldWriter`` is an observer of a coupled run: each time its schedule fires it appends
one snapshot of the gas state to ``gas.h5`` and then its grid to ``gas.xdmf`` (one write,
``io/xdmf.py``), so the index lists only snapshots that were written completely and is valid
between snapshots. A run without gas (``sim.gas is None``) writes nothing. ``read_gas_fields``
reads a run's file back as NumPy arrays stacked over time, ``read_gas_grid`` its grid.

Layout of ``gas.h5`` (all float64, SI units)::

    attrs      format = "fluidem-gas", version = 1, nx, ny, dx [m], dy [m], depth [m],
               layout = "(ny, nx): row j is y, x varies fastest"
    /grid      x_faces (nx+1,), y_faces (ny+1,), x_centres (nx,), y_centres (ny,) [m]
    /snapshots/<6-digit index>   attrs time [s], step, complete (set last)
        voidage          ε [-]
        solids_fraction  1 − ε [-]
        p                pressure [Pa]
        rho              gas density [kg/m^3]
        ux, uy           interstitial gas velocity at the centre [m/s]: the mean of the two faces
        superficial_ux, superficial_uy   ε ux, ε uy [m/s]
        solids_u, solids_v   cell-averaged solids velocity [m/s]   (when the coupling exposes it)
        beta             interphase momentum-exchange coefficient β [kg m^-3 s^-1] of the last gas
                         step (likewise; NaN before the first gas step)

Every field is stored as ``(ny, nx)``: row ``j`` is the cell row at height
``(j + 1/2) dy``, and x varies fastest. That is the order XDMF and VTK expect for cell
data, so ParaView reads the datasets in place; ``read_gas_fields`` transposes back to the
grid's ``(nx, ny)`` convention (``gas/grid.py``).

``gas.xdmf`` is an XDMF 3 temporal collection of ``2DRectMesh`` grids with ``VXVY``
geometry (the face coordinates in ``/grid``) and one ``Center="Cell"`` scalar attribute per
dataset. ParaView's XDMF 3 readers (Xdmf3ReaderS/T) put it in the x–y plane with the
particles of ``particles.xdmf``. Vectors for glyphs or streamlines: Calculator
``ux*iHat + uy*jHat``.

A 3D grid (a state with ``w``) is written the same way with a third axis: the attributes ``nz``
and ``dz``, ``/grid`` ``z_faces`` (nz+1,) and ``z_centres`` (nz,), the fields ``uz`` and
``superficial_uz`` besides the others, every field stored as ``(nz, ny, nx)`` (x fastest), and
``3DRectMesh`` grids with ``VXVYVZ`` geometry, which ParaView opens as a 3D rectilinear grid
(vectors: ``ux*iHat + uy*jHat + uz*kHat``). ``read_gas_fields`` gives (T, nx, ny, nz) arrays.
"""
from __future__ import annotations

import os
import warnings
from pathlib import Path

import h5py
import numpy as np

from ..schedule import EveryTime
from .atomic import write_text_atomic
from .xdmf import XdmfIndex, document

GAS_FILE = "gas.h5"
GAS_INDEX = "gas.xdmf"
FORMAT, VERSION = "fluidem-gas", 1

# Fields every snapshot holds, then the ones written when the coupling exposes them.
FIELDS = ("voidage", "solids_fraction", "p", "rho", "ux", "uy", "superficial_ux", "superficial_uy")
FIELDS_Z = ("uz", "superficial_uz")  # the fields of a 3D grid besides FIELDS
OPTIONAL_FIELDS = ("solids_u", "solids_v", "solids_w", "beta")
ALL_FIELDS = FIELDS + FIELDS_Z + OPTIONAL_FIELDS
UNITS = {"voidage": "-", "solids_fraction": "-", "p": "Pa", "rho": "kg/m^3", "ux": "m/s", "uy": "m/s",
         "superficial_ux": "m/s", "superficial_uy": "m/s", "uz": "m/s", "superficial_uz": "m/s",
         "solids_u": "m/s", "solids_v": "m/s", "solids_w": "m/s",
         "beta": "kg/(m^3 s)"}


def cell_fields(state, last_map=None, last_beta=None) -> dict[str, np.ndarray]:
    """Cell-centred fields of a ``GasState``, each (nx, ny) float64, or (nx, ny, nz) with ``uz`` and
    ``superficial_uz`` for a 3D state (names and units: module docstring).

    ``last_map`` is the coupling's last ``SolidsMap`` (``solids_u``, ``solids_v``) and
    ``last_beta`` its last β per cell; either may be None and is then left out.
    """
    eps = np.asarray(state.voidage, float)
    ux = 0.5 * (state.u[:-1, :] + state.u[1:, :])  # x-faces i and i+1 bound cell i (gas/grid.py)
    uy = 0.5 * (state.v[:, :-1] + state.v[:, 1:])  # y-faces j and j+1 bound cell j
    out = {
        "voidage": eps,
        "solids_fraction": 1.0 - eps,
        "p": np.asarray(state.p, float),
        "rho": np.asarray(state.rho, float),
        "ux": ux,
        "uy": uy,
        "superficial_ux": eps * ux,
        "superficial_uy": eps * uy,
    }
    w = getattr(state, "w", None)
    if w is not None:  # z-faces k and k+1 bound cell k
        out["uz"] = 0.5 * (w[:, :, :-1] + w[:, :, 1:])
        out["superficial_uz"] = eps * out["uz"]
    if last_map is not None:
        for name in ("solids_u", "solids_v", "solids_w"):
            value = getattr(last_map, name, None)
            if value is not None:
                out[name] = np.asarray(value, float)
    if last_beta is not None:
        out["beta"] = np.asarray(last_beta, float)
    return out


def _coupling_fields(gas) -> dict[str, np.ndarray]:
    """``cell_fields`` of a ``GasCoupling``; β is NaN (not left out) while a coupling that keeps
    ``last_beta`` has none yet (before its first gas step), so every snapshot has the same fields."""
    fields = cell_fields(gas.state, getattr(gas, "last_map", None), getattr(gas, "last_beta", None))
    if "beta" not in fields and hasattr(gas, "last_beta"):
        fields["beta"] = np.full(gas.grid.shape, np.nan)
    return fields


class GasFieldWriter:
    """Observer writing the gas fields of a coupled run to ``gas.h5`` + ``gas.xdmf``.

    Parameters
    ----------
    out_dir : the run directory.
    schedule : ``Every``/``EveryTime``; the run's default is the particle snapshot interval.

    A snapshot group gets ``complete = True`` only after all its datasets are written;
    the index, the reader and ``truncate_after`` ignore or drop groups without it (a run
    killed in the middle of a write).
    """

    def __init__(self, out_dir: Path, schedule=None):
        self.path = Path(out_dir) / GAS_FILE
        self.xdmf = Path(out_dir) / GAS_INDEX
        self.schedule = schedule or EveryTime(0.01)
        # the index of the file's complete snapshots and the next group key, read from the file once and
        # then kept up to date here: reading it back on every snapshot cost O(snapshots) attribute reads
        # each time (40 ms per snapshot after 150 of them; 6 s of a 40 s hoomans-orifice run)
        self._index: list[tuple[str, float, list[str]]] | None = None
        self._next_key = 0
        # gas.xdmf, appended to one grid a snapshot (io/xdmf.py; rewriting it whole cost O(snapshots) each time)
        self._xdmf_index = XdmfIndex(self.xdmf, "gas")

    def __call__(self, sim) -> None:
        gas = getattr(sim, "gas", None)
        if gas is None:
            return
        grid = gas.grid
        fields = _coupling_fields(gas)
        for name, value in fields.items():
            if value.shape != grid.shape:
                raise ValueError(f"gas field {name!r} has shape {value.shape}; the grid's cells are {grid.shape}")
        with h5py.File(self.path, "a") as f:
            _write_grid(f, grid)
            grp = f.require_group("snapshots")
            if self._index is None:
                self._load_index(f)
            key = f"{self._next_key:06d}"
            g = grp.create_group(key)
            self._next_key += 1
            g.attrs["time"] = float(sim.time)
            g.attrs["step"] = int(sim.steps)
            for name, value in fields.items():
                d = g.create_dataset(name, data=np.ascontiguousarray(value.T))
                d.attrs["units"] = UNITS[name]
            f.flush()
            g.attrs["complete"] = True
        names = [n for n in ALL_FIELDS if n in fields]
        self._index.append((key, float(sim.time), names))
        index = self._index
        nz = getattr(grid, "nz", None)
        self._xdmf_index.append(
            grid_text(self.path.name, key, float(sim.time), names, grid.nx, grid.ny, nz),
            lambda: [grid_text(self.path.name, k, t, ns, grid.nx, grid.ny, nz) for k, t, ns in index])

    def _load_index(self, f: h5py.File) -> None:
        """The index of the complete snapshots in ``f`` and the key after its last group (complete or not)."""
        self._index = _index(f)
        keys = sorted(f["snapshots"]) if "snapshots" in f else []
        self._next_key = int(keys[-1]) + 1 if keys else 0

    def truncate_after(self, step: int) -> None:
        """Drop snapshots later than ``step`` and incomplete ones (used on resume), then rewrite the index.

        A ``gas.h5`` that HDF5 cannot open (a crash during a write) is kept as
        ``gas.h5.unreadable`` and the run starts a new one, so the run stays resumable.
        """
        if not self.path.exists():
            return
        try:
            with h5py.File(self.path, "a") as f:
                grp = f.require_group("snapshots")
                for k in list(grp):
                    if not grp[k].attrs.get("complete", False) or int(grp[k].attrs["step"]) > step:
                        del grp[k]
                self._load_index(f)
                index = self._index
                nx, ny = (int(f.attrs["nx"]), int(f.attrs["ny"])) if "nx" in f.attrs else (0, 0)
                nz = int(f.attrs["nz"]) if "nz" in f.attrs else None
        except (OSError, KeyError) as err:
            aside = self.path.with_name(self.path.name + ".unreadable")
            os.replace(self.path, aside)
            warnings.warn(f"{self.path} could not be read on resume ({err}); moved to {aside.name}, "
                          f"gas fields start again from this step", RuntimeWarning, stacklevel=2)
            index, nx, ny, nz = [], 0, 0, None
            self._index, self._next_key = None, 0  # the new file's, on the next snapshot
        write_text_atomic(self.xdmf, xdmf_text(self.path.name, index, nx, ny, nz))
        self._xdmf_index.forget()

    def finalize(self, sim) -> None:
        """Rewrite the index from the file. It is up to date after every snapshot already, so a file
        that cannot be read now (the run is ending on an error) leaves the last index as it is."""
        if not self.path.exists():
            return
        try:
            with h5py.File(self.path, "r") as f:
                index = _index(f)
                nx, ny = int(f.attrs.get("nx", 0)), int(f.attrs.get("ny", 0))
                nz = int(f.attrs["nz"]) if "nz" in f.attrs else None
        except (OSError, KeyError):
            return
        write_text_atomic(self.xdmf, xdmf_text(self.path.name, index, nx, ny, nz))  # durable: the run's last
        self._xdmf_index.forget()


def _write_grid(f: h5py.File, grid) -> None:
    """File attributes and ``/grid`` on the first snapshot; later ones must have the same grid."""
    if "grid" in f:
        held = tuple(int(f.attrs[k]) for k in ("nx", "ny", "nz") if k in f.attrs)
        if held != tuple(grid.shape):
            raise ValueError(f"{f.filename} holds a {' x '.join(map(str, held))} grid; "
                             f"this run's is {' x '.join(map(str, grid.shape))}")
        return
    f.attrs.update(format=FORMAT, version=VERSION, nx=grid.nx, ny=grid.ny, dx=grid.dx, dy=grid.dy,
                   depth=grid.depth, layout="(ny, nx): row j is y, x varies fastest")
    g = f.create_group("grid")
    g["x_faces"], g["y_faces"] = grid.x_faces, grid.y_faces
    g["x_centres"], g["y_centres"] = grid.x_centres, grid.y_centres
    if getattr(grid, "dimensions", 2) == 3:
        f.attrs.update(nz=grid.nz, dz=grid.dz, layout="(nz, ny, nx): x varies fastest, then y")
        g["z_faces"], g["z_centres"] = grid.z_faces, grid.z_centres


def _index(f: h5py.File) -> list[tuple[str, float, list[str]]]:
    """(key, time, field names) of the complete snapshots, in order."""
    grp = f.get("snapshots")
    if grp is None:
        return []
    out = []
    for k in sorted(grp):
        g = grp[k]
        if g.attrs.get("complete", False):
            out.append((k, float(g.attrs["time"]), [n for n in ALL_FIELDS if n in g]))
    return out


def grid_text(h5name: str, key: str, t: float, names: list[str], nx: int, ny: int, nz: int | None = None) -> str:
    """The XDMF ``<Grid>`` element of one snapshot with the fields ``names`` (``xdmf_text`` joins them): a
    2DRectMesh, or with ``nz`` a 3DRectMesh."""
    cells = f"{ny} {nx}" if nz is None else f"{nz} {ny} {nx}"
    attrs = [
        f'      <Attribute Name="{name}" AttributeType="Scalar" Center="Cell">\n'
        f'        <DataItem Dimensions="{cells}" NumberType="Float" Precision="8" Format="HDF">'
        f"{h5name}:/snapshots/{key}/{name}</DataItem>\n      </Attribute>"
        for name in names
    ]
    axes = [("x", nx), ("y", ny)] + ([] if nz is None else [("z", nz)])
    topology = (f'      <Topology TopologyType="2DRectMesh" Dimensions="{ny + 1} {nx + 1}"/>\n' if nz is None else
                f'      <Topology TopologyType="3DRectMesh" Dimensions="{nz + 1} {ny + 1} {nx + 1}"/>\n')
    return (
        f'    <Grid Name="gas_{key}" GridType="Uniform">\n'
        f'      <Time Value="{t:.9g}"/>\n'
        + topology
        + f'      <Geometry GeometryType="{"VXVY" if nz is None else "VXVYVZ"}">\n'
        + "".join(f'        <DataItem Dimensions="{n + 1}" NumberType="Float" Precision="8" Format="HDF">'
                  f"{h5name}:/grid/{a}_faces</DataItem>\n" for a, n in axes)
        + "      </Geometry>\n"
        + "\n".join(attrs)
        + "\n    </Grid>"
    )


def xdmf_text(h5name: str, index: list[tuple[str, float, list[str]]], nx: int, ny: int, nz: int | None = None) -> str:
    """XDMF 3 temporal collection of 2DRectMesh (3DRectMesh with ``nz``) grids, one per snapshot in ``index``."""
    return document("gas", [grid_text(h5name, key, t, names, nx, ny, nz) for key, t, names in index])


def _gas_file(run_dir: str | Path) -> Path:
    """The ``gas.h5`` of a run directory (or ``run_dir`` itself when it is the file); FileNotFoundError
    without one."""
    path = Path(run_dir)
    if path.is_dir():
        path = path / GAS_FILE
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no gas fields (runs with a gas phase write {GAS_FILE})")
    return path


def read_gas_grid(run_dir: str | Path) -> dict[str, float]:
    """The grid of a run's ``gas.h5`` from its file attributes: ``nx``, ``ny`` (int), ``dx``, ``dy`` [m] and
    ``depth`` [m] (1.0 when the file does not give it); of a 3D grid also ``nz`` (int) and ``dz`` [m].

    ``run_dir`` is a run directory or the file. Raises ``FileNotFoundError`` without a file, ``OSError``
    when HDF5 cannot open it and ``KeyError`` when it lacks an attribute.
    """
    with h5py.File(_gas_file(run_dir), "r") as f:
        a = f.attrs
        out = {"nx": int(a["nx"]), "ny": int(a["ny"]), "dx": float(a["dx"]), "dy": float(a["dy"]),
               "depth": float(a.get("depth", 1.0))}
        if "nz" in a:
            out.update(nz=int(a["nz"]), dz=float(a["dz"]))
        return out


def read_gas_fields(run_dir: str | Path, fields=None) -> dict[str, np.ndarray]:
    """The gas fields of a run, stacked over time.

    Parameters
    ----------
    run_dir : a run directory (or the path of its ``gas.h5``).
    fields : names to read (default all present); an unknown name raises ``KeyError``.

    Returns
    -------
    dict with ``time`` (T,) [s], ``step`` (T,) int, ``x``/``y`` cell centres (nx,)/(ny,) [m],
    ``x_faces``/``y_faces`` (nx+1,)/(ny+1,) [m], and each field as (T, nx, ny) float64
    (``field[k, i, j]`` is cell (i, j) at ``time[k]``; NaN in a snapshot without it). A 3D grid adds
    ``z``, ``z_faces`` and gives the fields as (T, nx, ny, nz).
    Only completely written snapshots are read. Raises ``FileNotFoundError`` without a file.

    Examples
    --------
    >>> g = read_gas_fields("runs/jet")
    >>> mean_solids = g["solids_fraction"][g["time"] >= 5.0].mean(axis=0)   # (nx, ny)
    >>> import pandas as pd; pd.Series(g["p"][:, 7, 10], index=g["time"])    # one cell's pressure
    """
    path = _gas_file(run_dir)
    with h5py.File(path, "r") as f:
        if "grid" not in f:
            raise KeyError(f"{path} has no /grid group; it is not a fluidem gas-field file")
        gridg = f["grid"]
        out: dict[str, np.ndarray] = {
            "x": np.asarray(gridg["x_centres"]), "y": np.asarray(gridg["y_centres"]),
            "x_faces": np.asarray(gridg["x_faces"]), "y_faces": np.asarray(gridg["y_faces"]),
        }
        shape = (len(out["x"]), len(out["y"]))
        if "z_centres" in gridg:
            out["z"], out["z_faces"] = np.asarray(gridg["z_centres"]), np.asarray(gridg["z_faces"])
            shape += (len(out["z"]),)
        index = _index(f)
        present = [n for n in ALL_FIELDS if any(n in names for _, _, names in index)]
        if fields is None:
            names = present
        else:
            names = list(fields)
            unknown = [n for n in names if n not in ALL_FIELDS]
            if unknown:
                raise KeyError(f"unknown gas field(s) {unknown}; the fields are {list(ALL_FIELDS)}")
        grp = f["snapshots"] if index else None
        out["time"] = np.array([t for _, t, _ in index], float)
        out["step"] = np.array([int(grp[k].attrs["step"]) for k, _, _ in index], np.int64) if index \
            else np.zeros(0, np.int64)
        for name in names:
            stack = np.full((len(index),) + shape, np.nan)
            for k, (key, _, have) in enumerate(index):
                if name in have:
                    stack[k] = np.asarray(grp[key][name]).T
            out[name] = stack
    return out
