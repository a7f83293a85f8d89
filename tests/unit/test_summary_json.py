"""summary.json is strict JSON: undefined figures are null, never NaN or Infinity."""
import json
import math

import numpy as np
import pytest

from fluidem.io.summary import summary_json


def _reject(name):
    pytest.fail(f"{name} in the summary JSON")


def test_non_finite_figures_become_null():
    """NaN and ±inf, as Python or NumPy floats, nested in dicts and lists, become null; the rest is kept."""
    text = summary_json({"a": math.nan, "b": [1.5, math.inf], "c": {"d": np.float64("nan"), "e": np.float64(2.0)},
                         "f": "text", "g": 3, "h": -math.inf})
    assert json.loads(text, parse_constant=_reject) == {
        "a": None, "b": [1.5, None], "c": {"d": None, "e": 2.0}, "f": "text", "g": 3, "h": None}
