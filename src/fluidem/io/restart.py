"""Restart files: the whole engine state in one HDF5 file, replaced atomically."""
from __future__ import annotations

import json
from pathlib import Path

import h5py
import numpy as np

from .atomic import atomic_path

RESTART_NAME = "restart.h5"


def save_restart(path: Path, arrays: dict[str, np.ndarray], scalars: dict, case_toml: str) -> None:
    with atomic_path(Path(path)) as tmp:
        with h5py.File(tmp, "w") as f:
            for k, v in arrays.items():
                f.create_dataset(k, data=v)
            f.attrs["scalars"] = json.dumps(scalars)
            f.attrs["case_toml"] = case_toml


def load_restart(path: Path) -> tuple[dict[str, np.ndarray], dict, str]:
    arrays: dict[str, np.ndarray] = {}
    with h5py.File(path, "r") as f:
        def visit(name, obj):
            if isinstance(obj, h5py.Dataset):
                arrays[name] = np.asarray(obj)

        f.visititems(visit)
        scalars = json.loads(f.attrs["scalars"])
        case_toml = str(f.attrs["case_toml"])
    return arrays, scalars, case_toml
