"""Property-based checks of case validation (Hypothesis): every built-in case, mutated at a random key
(a wrong type, NaN or ±inf, a negative or huge number, an unknown key, a table where a value goes or a
value where a table goes, a list of the wrong length, a key removed), either validates into a case
without non-finite numbers or is refused with a ``CaseError`` whose message names a key, never any
other exception. A few such mutations go through ``fluidem run --set`` as well: exit status 2, no
traceback, no run directory. No simulation runs here: the command-line examples are limited to
mutations that validation refuses.

Derandomised and with a modest number of examples, so that the test is cheap and gives the same
examples on every run.
"""
from __future__ import annotations

import copy
import json
import math
import re

import pytest

pytest.importorskip("hypothesis")  # in the ``test`` extra

from hypothesis import HealthCheck, assume, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

from fluidem.case import Case, builtin_cases, load_case, read_case_data, validate_case  # noqa: E402
from fluidem.cli import main  # noqa: E402
from fluidem.errors import CaseError  # noqa: E402

CASES = {name: read_case_data(path) for name, path in sorted(builtin_cases().items())}
UNKNOWN = "no_such_key"


def leaves(node, path=()):
    """Every key path of ``node`` (tables, lists and values), depth first."""
    out = [path] if path else []
    items = node.items() if isinstance(node, dict) else enumerate(node) if isinstance(node, list) else ()
    for k, v in items:
        out += leaves(v, path + (k,))
    return out


def get(node, path):
    for k in path:
        node = node[k]
    return node


PATHS = {name: leaves(data) for name, data in CASES.items()}
TABLES = {name: [()] + [p for p in PATHS[name] if isinstance(get(CASES[name], p), dict)] for name in CASES}

WRONG_VALUES = st.one_of(
    st.sampled_from([math.nan, math.inf, -math.inf, -1.0, -1, 0, 0.0, 1e308, -1e308, 10**30, 1e-320,
                     True, False, "", "text", [], [1.0], [1.0, 2.0, 3.0, 4.0], {}, {"a": 1.0}]),
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(min_value=-(10**20), max_value=10**20),
    st.text(max_size=8),
)


@st.composite
def mutations(draw):
    """(case name, mutated data, dotted key of the mutation, kind of mutation)."""
    name = draw(st.sampled_from(sorted(CASES)))
    data = copy.deepcopy(CASES[name])
    kind = draw(st.sampled_from(["value", "non_finite", "unknown_key", "table_for_value", "value_for_table",
                                 "list_length", "remove"]))
    if kind == "unknown_key":
        path = draw(st.sampled_from(TABLES[name]))
        get(data, path)[UNKNOWN] = draw(WRONG_VALUES)
        return name, data, ".".join(map(str, path + (UNKNOWN,))), kind
    path = draw(st.sampled_from(PATHS[name]))
    parent, key = get(data, path[:-1]), path[-1]
    old = parent[key]
    if kind == "value":
        parent[key] = draw(WRONG_VALUES)
    elif kind == "non_finite":
        new = draw(st.sampled_from([math.nan, math.inf, -math.inf]))
        if isinstance(old, list) and old and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in old):
            i = draw(st.integers(0, len(old) - 1))
            parent[key] = old[:i] + [new] + old[i + 1:]
        else:
            parent[key] = new
    elif kind == "table_for_value":
        parent[key] = {"value": old} if not isinstance(old, dict) else {"nested": {"value": 1.0}}
    elif kind == "value_for_table":
        parent[key] = draw(st.sampled_from([1.0, "text", [1.0, 2.0]]))
    elif kind == "list_length":
        if isinstance(old, list) and old:
            parent[key] = draw(st.sampled_from([old[:-1], old + [old[-1]], []]))
        else:
            parent[key] = [old, old]
    else:  # remove
        del parent[key]
    return name, data, ".".join(map(str, path)), kind


def assert_names_a_key(message: str, key: str, name: str) -> None:
    """The message names, as a key, the mutated key, a table above it, or another key of the case (a check
    between keys names the key it reads: a box against the gas grid). A key as a key: followed by " =", ":",
    " (", a quote or a deeper part, not a word of the text that happens to be a key's name."""
    parts = key.split(".")
    candidates = {".".join(parts[:n]) for n in range(1, len(parts) + 1)}
    candidates |= {".".join(map(str, p)) for p in PATHS[name]} | set(Case.model_fields)
    assert any(re.search(rf"(?<![\w.]){re.escape(k)}(?= =|:| \(|'|\.\w)", message) for k in candidates), \
        f"no key named in the message for {key!r}:\n{message}"


def non_finite(node, path=()):
    """Key paths of NaN/±inf numbers in a dumped case."""
    if isinstance(node, float):
        return [path] if not math.isfinite(node) else []
    items = node.items() if isinstance(node, dict) else enumerate(node) if isinstance(node, (list, tuple)) else ()
    return [p for k, v in items for p in non_finite(v, path + (k,))]


@settings(max_examples=160, deadline=None, derandomize=True, database=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(mutations())
def test_a_mutated_case_validates_or_is_refused_naming_a_key(mutation):
    name, data, key, kind = mutation
    try:
        case = validate_case(data)
    except CaseError as err:
        message = str(err)
        assert message.strip(), "empty message"
        assert "pydantic" not in message.lower()
        assert_names_a_key(message, key, name)
        if kind == "unknown_key":
            assert UNKNOWN in message and "allowed" in message
        return
    assert isinstance(case, Case)
    # a validated case holds finite numbers only; inf stands for "for ever" in a pulse's duration alone
    dumped = case.model_dump(mode="python")
    bad = [p for p in non_finite(dumped) if not (p[-1] == "duration" and dumped and get(dumped, p) == math.inf)]
    assert not bad, f"{key}: non-finite numbers in a validated case at {bad}"
    if kind == "non_finite" and key.endswith(".duration") and get(data, key.split(".")) == math.inf:
        return  # a pulse that lasts for ever: the one key where inf is a value
    assert kind not in ("unknown_key", "non_finite"), f"{kind} mutation at {key} was accepted"


def toml_value(value) -> str:
    """``value`` as the text of a ``--set`` value (TOML)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return "nan" if math.isnan(value) else ("inf" if value > 0 else "-inf") if math.isinf(value) else repr(value)
    if isinstance(value, int):
        return str(value)
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, list):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    return "{" + ", ".join(f"{k} = {toml_value(v)}" for k, v in value.items()) + "}"


@st.composite
def set_mutations(draw):
    """(case name, dotted key, value) for ``--set key=value``: a value of the wrong kind at an existing key or
    any value at an unknown key."""
    name = draw(st.sampled_from(sorted(CASES)))
    if draw(st.booleans()):
        path = draw(st.sampled_from(TABLES[name][1:] or [()])) + (UNKNOWN,)
    else:
        path = draw(st.sampled_from([p for p in PATHS[name] if not isinstance(get(CASES[name], p), (dict, list))]))
    value = draw(st.sampled_from([math.nan, math.inf, -math.inf, -1.0, 0, "text", [1.0], {"a": 1.0}, True]))
    return name, ".".join(map(str, path)), value


@settings(max_examples=40, deadline=None, derandomize=True, database=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(set_mutations())
def test_a_refused_set_exits_2_and_writes_nothing(tmp_path_factory, capsys, mutation):
    name, key, value = mutation
    text = toml_value(value)
    try:
        load_case(name, {key: value})
    except CaseError:
        pass
    else:
        assume(False)  # valid: it would run a simulation, which this test does not do
    out_dir = tmp_path_factory.mktemp("fuzz") / "run"
    rc = main(["run", name, "--set", f"{key}={text}", "--out", str(out_dir)])
    out, err = capsys.readouterr()
    assert rc == 2, f"--set {key}={text}: exit status {rc}\n{err}"
    assert "Traceback" not in err and err.startswith("fluidem: error:"), err
    assert out == ""
    assert not out_dir.exists()
    assert_names_a_key(err, key, name)


@pytest.mark.parametrize("name", sorted(CASES))
def test_every_builtin_case_validates_unchanged(name):
    assert isinstance(validate_case(copy.deepcopy(CASES[name])), Case)


@pytest.mark.parametrize("key, value", [
    ("gas.boundaries.bottom.voidage", {"value": 1.0}),  # once a TypeError: a table compared with a number
    ("gas.boundaries.no_such_key", math.nan),  # an unknown side is named as such, whatever its value
    ("walls", [{"name": "column", "kind": "plane", "point": [0, 0, 0], "normal": [0, 1, 0]}] * 2),
])
def test_found_by_fuzzing(key, value):
    data = copy.deepcopy(CASES["goldschmidt"])
    parts = key.split(".")
    get(data, parts[:-1])[parts[-1]] = value
    with pytest.raises(CaseError) as info:
        validate_case(data)
    assert_names_a_key(str(info.value), key, "goldschmidt")
    assert key.rsplit(".", 1)[-1] in str(info.value)
