"""Restart files: the whole engine state in one HDF5 file, replaced atomically, the one before kept.

A run directory holds its newest checkpoint in ``restart.h5`` and the one before it in
``restart.prev.h5``. A new checkpoint is written to ``restart.h5.tmp`` and synced; then ``restart.h5``
is renamed to ``restart.prev.h5`` and the new file to ``restart.h5`` (``atomic.atomic_path``). A crash,
a full disk or one damaged file therefore never leaves a run without a complete checkpoint: resuming
takes ``restart.h5`` and, where that cannot be read, ``restart.prev.h5`` (``CHECKPOINT_NAMES``).

Layout: one dataset per array (``state/position``, ``engine/…``, ``gas/…``) and the attributes
``scalars`` (JSON), ``case_toml`` (the case as TOML) and ``checksums`` (JSON: the CRC-32 of each
array's bytes, checked on reading; files written before it existed have none and are read unchecked).
``load_restart`` raises ``CheckpointError`` with the file and what is wrong with it, never an HDF5 or
JSON error.
"""
from __future__ import annotations

import json
import zlib
from pathlib import Path

import h5py
import numpy as np

from ..errors import CheckpointError
from .atomic import atomic_path

RESTART_NAME = "restart.h5"
PREVIOUS_RESTART_NAME = "restart.prev.h5"
CHECKPOINT_NAMES = (RESTART_NAME, PREVIOUS_RESTART_NAME)  # newest first


def _checksum(a: np.ndarray) -> int:
    return zlib.crc32(np.ascontiguousarray(a)) if a.size else 0


def save_restart(path: Path, arrays: dict[str, np.ndarray], scalars: dict, case_toml: str,
                 previous: Path | None = None) -> None:
    """Write a checkpoint to ``path`` atomically; with ``previous``, the file ``path`` held until now is
    kept under that name (``restart.prev.h5``). A failed write (OSError: a full disk) leaves both files as
    they were."""
    sums = {}
    with atomic_path(Path(path), previous=previous) as tmp:
        with h5py.File(tmp, "w") as f:
            for k, v in arrays.items():
                v = np.asarray(v)
                f.create_dataset(k, data=v)
                sums[k] = _checksum(v)
            f.attrs["scalars"] = json.dumps(scalars)
            f.attrs["case_toml"] = case_toml
            f.attrs["checksums"] = json.dumps(sums)


def _unusable(path: Path, reason: str) -> CheckpointError:
    return CheckpointError(f"checkpoint {path}: {reason}", path=path, reason=reason)


def load_restart(path: Path) -> tuple[dict[str, np.ndarray], dict, str]:
    """(arrays by dataset name, scalars, case TOML) of the checkpoint ``path``.

    Raises ``CheckpointError`` (``path``, ``reason``) when the file is missing, empty, not HDF5,
    truncated, lacks an attribute or holds an array that does not match its checksum.
    """
    path = Path(path)
    try:
        size = path.stat().st_size
    except FileNotFoundError:
        raise _unusable(path, "missing") from None
    except OSError as err:
        raise _unusable(path, f"cannot be read ({err.strerror or err})") from None
    if size == 0:
        raise _unusable(path, "empty (0 bytes)")
    try:
        signature = h5py.is_hdf5(path)
    except OSError as err:
        raise _unusable(path, f"cannot be read ({err.strerror or err})") from None
    if not signature:
        raise _unusable(path, f"not an HDF5 file ({size} bytes without the HDF5 signature)")
    arrays: dict[str, np.ndarray] = {}
    try:
        with h5py.File(path, "r") as f:
            for name in ("scalars", "case_toml"):
                if name not in f.attrs:
                    raise _unusable(path, f"lacks the attribute {name!r}; not a fluidem checkpoint")

            def visit(name, obj):
                if isinstance(obj, h5py.Dataset):
                    arrays[name] = np.asarray(obj)

            f.visititems(visit)
            scalars_text = f.attrs["scalars"]
            case_toml = str(f.attrs["case_toml"])
            sums_text = f.attrs.get("checksums")
    except CheckpointError:
        raise
    except Exception as err:  # noqa: BLE001 - a damaged file can fail in HDF5 in many ways; each is this one
        raise _unusable(path, f"truncated or damaged (HDF5: {err})") from None
    try:
        scalars = json.loads(scalars_text)
        sums = json.loads(sums_text) if sums_text is not None else {}
    except (ValueError, TypeError) as err:
        raise _unusable(path, f"damaged: its attributes are not valid JSON ({err})") from None
    if not isinstance(scalars, dict):
        raise _unusable(path, "damaged: its attribute 'scalars' is not a table of values")
    for name, expected in sums.items():
        if name not in arrays:
            raise _unusable(path, f"lacks the array {name!r} that it was written with")
        if _checksum(arrays[name]) != expected:
            raise _unusable(path, f"damaged: the array {name!r} does not match its checksum")
    return arrays, scalars, case_toml
