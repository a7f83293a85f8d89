"""``benchmarks/harness.py``: the interleaving order and the statistics of rounds, on fake timings."""
from __future__ import annotations

import argparse
import importlib.util
import json
import sys
from pathlib import Path

import pytest

HARNESS = Path(__file__).resolve().parents[2] / "benchmarks" / "harness.py"


@pytest.fixture(scope="module")
def harness():
    spec = importlib.util.spec_from_file_location("benchmarks_harness", HARNESS)
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod  # its dataclass looks its module up by name
    try:
        spec.loader.exec_module(mod)
        yield mod
    finally:
        del sys.modules[spec.name]


def fake_variants(calls: list, values: dict):
    """Variants that log their calls and return their next value from ``values`` (one list per name)."""
    its = {name: iter(vals) for name, vals in values.items()}

    def variant(name):
        def measure():
            calls.append(name)
            return next(its[name])

        return measure

    return {name: variant(name) for name in values}


def test_order_alternates_round_by_round(harness):
    assert [harness.round_order(["a", "b"], k) for k in range(4)] == [["a", "b"], ["b", "a"], ["a", "b"], ["b", "a"]]
    assert harness.round_order(["a", "b", "c"], 0) == ["a", "b", "c"]
    assert harness.round_order(["a", "b", "c"], 1) == ["c", "b", "a"]


def test_run_rounds_calls_the_variants_in_that_order_after_the_warm_up(harness):
    calls = []
    rounds = harness.run_rounds(fake_variants(calls, {"a": [0, 1, 2, 3], "b": [0, 10, 20, 30]}), repeat=3, warmup=1)
    # one untimed call each, then A B, B A, A B
    assert calls == ["a", "b", "a", "b", "b", "a", "a", "b"]
    assert rounds.orders == [["a", "b"], ["b", "a"], ["a", "b"]]
    # each variant's values stay in round order whatever the order within a round
    assert rounds.values == {"a": [1.0, 2.0, 3.0], "b": [10.0, 20.0, 30.0]}


def test_median_of_per_round_ratios_is_not_the_ratio_of_medians(harness):
    calls = []
    a = [10.0, 20.0, 30.0, 40.0, 50.0]
    b = [5.0, 40.0, 10.0, 20.0, 25.0]  # per-round a / b: 2, 0.5, 3, 2, 2
    rounds = harness.run_rounds(fake_variants(calls, {"a": a, "b": b}), repeat=5)
    assert rounds.ratios("a", "b") == [2.0, 0.5, 3.0, 2.0, 2.0]
    assert rounds.ratio("a", "b") == 2.0  # the ratio of the medians would be 30 / 20 = 1.5
    assert rounds.ratio("b", "a") == 0.5
    assert rounds.stats("a") == {"n": 5, "min": 10.0, "median": 30.0, "max": 50.0}
    assert rounds.stats("b") == {"n": 5, "min": 5.0, "median": 20.0, "max": 40.0}
    assert "median of per-round ratios 2.000 (min 0.500, max 3.000, 5 rounds)" in rounds.ratio_line("a", "b")


def test_rounds_without_a_value_are_left_out(harness):
    calls = []
    rounds = harness.run_rounds(fake_variants(calls, {"a": [4.0, 6.0, 9.0, 8.0], "peer": [2.0, None, 3.0, 0.0]}),
                                repeat=4)
    assert rounds.values["peer"] == [2.0, None, 3.0, 0.0]
    assert rounds.ratios("a", "peer") == [2.0, 3.0]  # rounds 2 (no value) and 4 (zero) left out
    assert rounds.ratio("a", "peer") == 2.5  # even count: the mean of the middle two
    assert rounds.stats("peer") == {"n": 3, "min": 0.0, "median": 2.0, "max": 3.0}
    assert harness.spread([None]) == {"n": 0, "min": None, "median": None, "max": None}
    empty = harness.run_rounds(fake_variants([], {"a": [1.0], "b": [None]}), repeat=1)
    assert empty.ratio("a", "b") is None and "no round with both" in empty.ratio_line("a", "b")


def test_dict_results_keep_their_extras_round_by_round(harness):
    values = {"x": [{"value": 3.0, "dem_ms": 1.0}, {"value": 1.0, "dem_ms": 0.5}, {"value": 2.0, "dem_ms": 0.75}]}
    rounds = harness.run_rounds(fake_variants([], values), repeat=3)
    assert rounds.values["x"] == [3.0, 1.0, 2.0]
    assert rounds.series("x", "dem_ms") == [1.0, 0.5, 0.75]
    assert rounds.stats("x", "dem_ms") == {"n": 3, "min": 0.5, "median": 0.75, "max": 1.0}


def test_timed_returns_the_clock_difference(harness, monkeypatch):
    ticks = iter([100.0, 102.5])
    monkeypatch.setattr(harness.time, "perf_counter", lambda: next(ticks))
    called = []
    assert harness.timed(lambda: called.append(1))() == 2.5
    assert called == [1]


def test_repeat_must_be_positive(harness):
    ap = argparse.ArgumentParser()
    harness.add_options(ap, repeat=7)
    assert ap.parse_args([]).repeat == 7 and ap.parse_args([]).json is None
    assert ap.parse_args(["--repeat", "2", "--json", "x.json"]).repeat == 2
    with pytest.raises(SystemExit):
        ap.parse_args(["--repeat", "0"])
    with pytest.raises(ValueError, match="at least one round"):
        harness.run_rounds({"a": lambda: 1.0}, repeat=0)


def test_json_holds_the_raw_rounds_and_where_they_were_taken(harness, tmp_path):
    rounds = harness.run_rounds(fake_variants([], {"a": [1.0, 2.0], "b": [4.0, float("nan")]}), repeat=2, unit="s")
    path = tmp_path / "out" / "bench.json"
    harness.write_json(path, {"bed": rounds}, steps=200)
    doc = json.loads(path.read_text())  # strict JSON: the NaN is written as null
    assert {"command", "git_revision", "machine", "measurements", "time_utc"} <= set(doc) and doc["steps"] == 200
    assert doc["machine"]["cpu_count"] >= 1 and "python" in doc["machine"]["versions"]
    bed = doc["measurements"]["bed"]
    assert bed["unit"] == "s" and bed["orders"] == [["a", "b"], ["b", "a"]]
    assert [r["values"] for r in bed["rounds"]] == [{"a": 1.0, "b": 4.0}, {"a": 2.0, "b": None}]
    assert harness.write_json(None, {"bed": rounds}) is None


def test_table_aligns_columns(harness):
    text = harness.format_table(["name", "value"], [["a", 1.23456], ["longer", None]])
    lines = text.splitlines()
    assert lines[0] == "name    value" and lines[1] == "------  -----"
    assert lines[2] == "a       1.235" and lines[3] == "longer      -"
