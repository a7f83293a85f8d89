"""Read a run directory for plotting: case, summary, probes, particle snapshots and gas fields.

``RunData(path)`` checks that ``path`` is a run directory (it holds ``case.toml``) and
raises ``CaseError`` otherwise. Everything else is optional: a quantity the run lacks
(no ``probes.csv``, no ``particles.h5``, no ``gas.h5``, a column that is not there) is
reported by ``RunData.lacks_*`` as a one-line reason, so figures skip with a note instead
of failing.
The files are read by the readers of ``fluidem.io`` (``summary.read_summary``,
``probes_csv.read_probes``, ``snapshots.snapshot_index`` / ``snapshot_fields`` / ``read_snapshot`` /
``iter_snapshots``, ``gas_fields.read_gas_fields`` / ``read_gas_grid``); nothing in the run directory
is changed.
"""
from __future__ import annotations

import csv
import tomllib
from functools import cached_property
from pathlib import Path

import numpy as np

from ..errors import CaseError
from ..io import snapshots as particles_h5
from ..io.gas_fields import GAS_FILE, read_gas_fields, read_gas_grid
from ..io.probes_csv import PROBES_FILE, read_probes
from ..io.snapshots import SNAPSHOT_FILE
from ..io.summary import read_summary

CASE_FILE = "case.toml"


class Unavailable(Exception):
    """A quantity the run does not have (or cannot be read); the message is a one-line reason."""


def _reason(err: Exception) -> str:
    """The first line of a reader's error (a KeyError's message without the quotes ``str`` adds)."""
    text = str(err.args[0]) if isinstance(err, KeyError) and err.args else str(err)
    return text.splitlines()[0] if text else type(err).__name__


class RunData:
    """Read-only view of one run directory.

    Parameters
    ----------
    path : the run directory (``fluidem run --out DIR``).

    Raises
    ------
    CaseError : ``path`` does not exist, is not a folder, or has no readable ``case.toml``.
    """

    def __init__(self, path: str | Path):
        self.path = Path(path)
        if not self.path.exists():
            raise CaseError(f"run directory {str(path)!r} does not exist")
        if not self.path.is_dir():
            raise CaseError(f"{str(path)!r} is not a run directory (it is a file); give the folder of a run")
        case_file = self.path / CASE_FILE
        if not case_file.is_file():
            raise CaseError(f"{str(path)!r} is not a run directory: it has no {CASE_FILE} "
                            f"(made by `fluidem run CASE --out DIR`)")
        try:
            self.case_text = case_file.read_text()
            self.case = tomllib.loads(self.case_text)
        except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as err:
            raise CaseError(f"{str(case_file)!r} cannot be read: {err}") from None

    # ------------------------------------------------------------ identity
    @property
    def name(self) -> str:
        """Label of the run in legends and tables: the folder name."""
        return self.path.resolve().name or str(self.path)

    @property
    def case_name(self) -> str:
        return str(self.case.get("name", ""))

    @property
    def dimensions(self) -> int:
        return int(self.case.get("particles", {}).get("dimensions", 3))

    @property
    def gravity(self) -> np.ndarray:
        g = self.case.get("gravity")
        if g is None:  # the schema's default
            g = (0.0, -9.81, 0.0) if self.dimensions == 2 else (0.0, 0.0, -9.81)
        return np.asarray(g, float)

    @property
    def species_names(self) -> list[str]:
        species = self.case.get("particles", {}).get("species", [])
        return [str(s.get("name", f"species {k}")) for k, s in enumerate(species)]

    @property
    def species_densities(self) -> np.ndarray:
        """Material density [kg/m^3] of each species, (S,); raises ``Unavailable`` when case.toml lacks one."""
        species = self.case.get("particles", {}).get("species", [])
        try:
            dens = np.array([float(s["density"]) for s in species], float)
        except (KeyError, TypeError, ValueError):
            raise Unavailable(f"{CASE_FILE} has a species without a density") from None
        if dens.size == 0 or not np.all(np.isfinite(dens) & (dens > 0)):
            raise Unavailable(f"{CASE_FILE} has no particle species with a density")
        return dens

    def particle_mass(self, diameter: np.ndarray, species: np.ndarray) -> np.ndarray:
        """Mass [kg] of spheres of ``diameter`` [m] (N,) and ``species`` (N,): ρ_s π d³/6, as the engines
        compute it (2D runs included). Raises ``Unavailable`` for a species index the case does not have."""
        dens = self.species_densities
        species = np.asarray(species, np.int64)
        if species.size and (species.min() < 0 or species.max() >= dens.size):
            raise Unavailable(f"a snapshot has species index {int(species.max())}, but {CASE_FILE} lists "
                              f"{dens.size} species")
        return dens[species] * np.pi / 6.0 * np.asarray(diameter, float) ** 3

    def boxes(self) -> list[dict]:
        """Box walls as dicts: ``lower`` [m] (3,), ``upper`` [m] (3,), ``open_top``, ``name``."""
        out = []
        for w in self.case.get("walls", []):
            if w.get("kind") == "box" and w.get("lower") is not None and w.get("upper") is not None:
                out.append({"lower": np.asarray(w["lower"], float), "upper": np.asarray(w["upper"], float),
                            "open_top": bool(w.get("open_top", False)), "name": str(w.get("name", "box"))})
        return out

    # ------------------------------------------------------------ summary
    @cached_property
    def summary(self) -> dict | None:
        """``summary.json`` as a dict, or None when missing or unreadable."""
        try:
            return read_summary(self.path)
        except (OSError, ValueError):
            return None

    # ------------------------------------------------------------ probes
    @cached_property
    def _probes(self) -> tuple[dict[str, np.ndarray] | None, str | None]:
        path = self.path / PROBES_FILE
        if not path.is_file():
            return None, f"the run has no {PROBES_FILE}"
        try:
            cols = read_probes(path)
        except (OSError, UnicodeDecodeError, csv.Error) as err:
            return None, f"{PROBES_FILE} cannot be read: {err}"
        if not cols:
            return None, f"{PROBES_FILE} is empty"
        return cols, None

    @property
    def probes(self) -> dict[str, np.ndarray]:
        """Columns of ``probes.csv`` as float arrays (unparsable cells are NaN); raises ``Unavailable``."""
        cols, why = self._probes
        if cols is None:
            raise Unavailable(why)
        return cols

    def probe_columns(self) -> list[str]:
        cols, _ = self._probes
        return list(cols) if cols else []

    def lacks_probes(self, *columns: str, any_of: bool = False, min_rows: int = 2) -> str | None:
        """Why the run cannot give a trace of ``columns`` against time (None when it can).

        With ``any_of=True`` one of ``columns`` is enough.
        """
        cols, why = self._probes
        if cols is None:
            return why
        if "time_s" not in cols:
            return f"{PROBES_FILE} has no time_s column"
        if len(cols["time_s"]) < min_rows:
            return f"{PROBES_FILE} has {len(cols['time_s'])} row(s); a trace needs {min_rows}"
        present = [c for c in columns if c in cols]
        if any_of and not present and columns:
            return f"{PROBES_FILE} has none of the columns {', '.join(columns)}"
        missing = [c for c in columns if c not in cols]
        if not any_of and missing:
            return f"{PROBES_FILE} has no column {', '.join(missing)}"
        return None

    # ------------------------------------------------------------ snapshots
    @cached_property
    def _snapshot_index(self) -> tuple[list[tuple[str, float]] | None, str | None]:
        path = self.path / SNAPSHOT_FILE
        if not path.is_file():
            return None, f"the run has no particle snapshots ({SNAPSHOT_FILE})"
        try:
            index = particles_h5.snapshot_index(path)
        except (OSError, KeyError, ValueError) as err:
            return None, f"{SNAPSHOT_FILE} cannot be read: {_reason(err)}"
        if not index:
            return None, f"{SNAPSHOT_FILE} holds no snapshots"
        return index, None

    def lacks_snapshots(self) -> str | None:
        return self._snapshot_index[1]

    @cached_property
    def snapshot_fields(self) -> tuple[str, ...]:
        """Names of the datasets of the first snapshot (() without snapshots)."""
        index, _ = self._snapshot_index
        if not index:
            return ()
        try:
            return particles_h5.snapshot_fields(self.path, 0)
        except (OSError, KeyError, ValueError, IndexError):
            return ()

    def lacks_snapshot_fields(self, *fields: str) -> str | None:
        """Why the particle snapshots cannot give ``fields`` (None when they can)."""
        why = self.lacks_snapshots()
        if why is not None:
            return why
        missing = [f for f in fields if f not in self.snapshot_fields]
        if missing:
            return f"{SNAPSHOT_FILE} has no field {', '.join(missing)}"
        return None

    @property
    def snapshot_times(self) -> np.ndarray:
        """Times [s] of the snapshots, in order; raises ``Unavailable``."""
        index, why = self._snapshot_index
        if index is None:
            raise Unavailable(why)
        return np.array([t for _, t in index])

    def snapshot(self, k: int) -> dict[str, np.ndarray]:
        """Snapshot ``k`` (negative counts from the end): arrays by name plus ``time`` [s].

        ``position`` (N, 3) [m], ``velocity`` (N, 3) [m/s], ``diameter`` (N,) [m],
        ``species`` (N,) and ``id`` (N,); ``id`` defaults to 0..N-1 and ``species`` to 0.
        """
        index, why = self._snapshot_index
        if index is None:
            raise Unavailable(why)
        key, t = index[k]
        try:
            out = particles_h5.read_snapshot(self.path, k)
        except (OSError, KeyError, ValueError, IndexError) as err:
            raise Unavailable(f"{SNAPSHOT_FILE} snapshot {key} cannot be read: {_reason(err)}") from None
        if "position" not in out or "diameter" not in out:
            raise Unavailable(f"{SNAPSHOT_FILE} snapshot {key} has no position or diameter")
        n = out["position"].shape[0]
        out.setdefault("id", np.arange(n))
        out.setdefault("species", np.zeros(n, np.int32))
        out.setdefault("velocity", np.zeros((n, 3)))
        out["time"] = t
        return out

    def iter_snapshots(self, fields: tuple[str, ...] = ("position",), indices=None):
        """Yield (time [s], {field: array}) for every snapshot (or those at ``indices``), opening the file once."""
        index, why = self._snapshot_index
        if index is None:
            raise Unavailable(why)
        try:
            yield from particles_h5.iter_snapshots(self.path, fields, indices)
        except (OSError, KeyError, ValueError, IndexError) as err:
            raise Unavailable(f"{SNAPSHOT_FILE} cannot be read: {_reason(err)}") from None

    # ------------------------------------------------------------ gas fields
    @property
    def has_gas_phase(self) -> bool:
        """The case has a ``[gas]`` section (a coupled run)."""
        return isinstance(self.case.get("gas"), dict)

    @cached_property
    def _gas(self) -> tuple[dict[str, np.ndarray] | None, str | None]:
        path = self.path / GAS_FILE
        if not path.is_file():
            if not self.has_gas_phase:
                return None, "the run has no gas phase (its case.toml has no [gas] section)"
            return None, f"the run has no gas fields ({GAS_FILE})"
        try:
            data = read_gas_fields(path)
        except (OSError, KeyError, ValueError) as err:
            return None, f"{GAS_FILE} cannot be read: {_reason(err)}"
        if len(data["time"]) == 0:
            return None, f"{GAS_FILE} holds no complete snapshots"
        if "z" in data:  # a 3D grid: the x–y maps show each field averaged along z (a pseudo-2D bed's depth)
            data = {k: (v.mean(axis=3) if isinstance(v, np.ndarray) and v.ndim == 4 else v) for k, v in data.items()}
        return data, None

    def lacks_gas(self, *fields: str) -> str | None:
        """Why the run cannot give gas-field maps of ``fields`` (None when it can)."""
        data, why = self._gas
        if data is None:
            return why
        missing = [f for f in fields if f not in data or not np.isfinite(data[f]).any()]
        if missing:
            return f"{GAS_FILE} has no field {', '.join(missing)}"
        return None

    @property
    def gas(self) -> dict[str, np.ndarray]:
        """``gas.h5`` as ``fluidem.io.read_gas_fields`` returns it (fields (T, nx, ny); a 3D grid's averaged along
        z); raises ``Unavailable``."""
        data, why = self._gas
        if data is None:
            raise Unavailable(why)
        return data

    def gas_grid(self):
        """The run's ``fluidem.gas.grid.StaggeredGrid``: from case.toml's ``[gas.grid]``, else from the
        attributes of ``gas.h5``; raises ``Unavailable`` when neither gives it."""
        from ..gas.grid import StaggeredGrid

        spec = self.case.get("gas", {}).get("grid") if self.has_gas_phase else None
        if isinstance(spec, dict) and "cells" in spec and "size" in spec:
            try:
                return StaggeredGrid(cells=tuple(spec["cells"]), size=tuple(spec["size"]),
                                     depth=float(spec.get("depth", 1.0)))
            except (CaseError, TypeError, ValueError):
                pass
        try:
            a = read_gas_grid(self.path)
            return StaggeredGrid(cells=(a["nx"], a["ny"]), size=(a["nx"] * a["dx"], a["ny"] * a["dy"]),
                                 depth=a["depth"])
        except (OSError, KeyError, ValueError, TypeError, CaseError):
            pass
        if not self.has_gas_phase:
            raise Unavailable("the run has no gas phase (its case.toml has no [gas] section)")
        raise Unavailable(f"neither {CASE_FILE} [gas.grid] nor {GAS_FILE} gives the gas grid")

    @property
    def gas_times(self) -> np.ndarray:
        """Times [s] of the gas-field snapshots, in order; raises ``Unavailable``."""
        return self.gas["time"]
