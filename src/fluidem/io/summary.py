"""A run's ``summary.json``: the run's status, timings and headline results (one JSON object), written as
strict JSON (``summary_json``) and read back (``read_summary``)."""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

SUMMARY_FILE = "summary.json"


def read_summary(path: str | Path) -> dict:
    """``summary.json`` as a dict.

    Parameters
    ----------
    path : a run directory or the path of its ``summary.json``.

    Raises ``FileNotFoundError`` without a file, ``OSError`` when it cannot be read and ``ValueError``
    when it is not JSON or not one JSON object.
    """
    path = Path(path)
    if path.is_dir():
        path = path / SUMMARY_FILE
    data = json.loads(path.read_text())
    if not isinstance(data, dict):
        raise ValueError(f"{path} holds a JSON {type(data).__name__}, not an object")
    return data


def finite(value):
    """``value`` with every non-finite float (NaN, ±inf) inside dicts and lists replaced by None."""
    if isinstance(value, dict):
        return {k: finite(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [finite(v) for v in value]
    if isinstance(value, (float, np.floating)) and not math.isfinite(value):
        return None
    return value


def summary_json(summary: dict) -> str:
    """``summary`` as strict JSON text (no NaN or Infinity, which pandas, jq and browsers reject)."""
    return json.dumps(finite(summary), indent=2, allow_nan=False) + "\n"
