"""Schedules: ``next_step(step, dt)`` is the first step strictly after ``step`` at which the schedule fires.

``Every(n)`` fires at multiples of n steps. ``EveryTime(s)`` fires at the first step whose time
reaches each multiple of s, i.e. at steps ceil(k s / dt) (k = 1, 2, ...), with exact multiples
not pushed one step late by floating-point round-off.
"""
from __future__ import annotations

import math

import pytest

from fluidem.schedule import Every, EveryTime


def firing_steps(schedule, dt, n, start=0):
    """The first ``n`` steps after ``start`` at which ``schedule`` fires, by chaining next_step."""
    out, step = [], start
    for _ in range(n):
        step = schedule.next_step(step, dt)
        out.append(step)
    return out


# ---------------------------------------------------------------- Every
@pytest.mark.parametrize("steps", [1, 3, 10])
def test_every_fires_at_multiples(steps):
    assert firing_steps(Every(steps), 0.1, 5) == [steps * k for k in range(1, 6)]


def test_every_next_step_is_strictly_after_the_current_step():
    e = Every(5)
    assert e.next_step(0, 1e-3) == 5
    assert e.next_step(4, 1e-3) == 5
    assert e.next_step(5, 1e-3) == 10  # firing now does not count: strictly after
    assert e.next_step(6, 1e-3) == 10


def test_every_ignores_dt():
    assert Every(7).next_step(13, 1.0) == Every(7).next_step(13, 1e-9) == 14


@pytest.mark.parametrize("bad", [0, -1])
def test_every_rejects_non_positive_steps(bad):
    with pytest.raises(ValueError, match="steps must be >= 1"):
        Every(bad)


# ---------------------------------------------------------------- EveryTime
def test_every_time_with_dt_dividing_the_interval():
    assert firing_steps(EveryTime(0.01), 0.001, 4) == [10, 20, 30, 40]


def test_every_time_with_dt_not_dividing_the_interval():
    # s / dt = 2.5: fires at ceil(2.5 k) = 3, 5, 8, 10, 13, 15
    assert firing_steps(EveryTime(0.0025), 0.001, 6) == [3, 5, 8, 10, 13, 15]


def test_every_time_exact_multiples_are_not_pushed_late_by_round_off():
    # 0.07 / 0.01 = 7.000000000000001 in floating point; the schedule must still fire at step 7
    assert 0.07 / 0.01 > 7 and 2 * 0.07 / 0.01 > 14
    assert firing_steps(EveryTime(0.07), 0.01, 4) == [7, 14, 21, 28]
    assert firing_steps(EveryTime(0.1), 0.01, 6) == [10, 20, 30, 40, 50, 60]


def test_every_time_interval_below_dt_fires_every_step():
    assert firing_steps(EveryTime(0.001), 0.0025, 5) == [1, 2, 3, 4, 5]


@pytest.mark.parametrize("seconds, dt", [
    (0.005, 1.4949792210730588e-05),  # the pour case's probe interval and time step
    (0.02, 1.4949792210730588e-05),
    (1e-3, 3e-4),
    (0.7, 0.3),
])
def test_every_time_matches_brute_force_crossing(seconds, dt):
    """Each firing step is the first step at or after a multiple of ``seconds``; none is skipped or repeated."""
    steps = firing_steps(EveryTime(seconds), dt, 40)
    assert steps == sorted(set(steps))
    for k, n in enumerate(steps, start=1):
        assert n == math.ceil(k * seconds / dt * (1 - 1e-12))
        assert n * dt >= k * seconds * (1 - 1e-12)
        assert (n - 1) * dt < k * seconds


def test_every_time_resumes_from_any_step():
    """Starting from a step in the middle (a resumed run) gives the same later firing steps."""
    dt, s = 1.4949792210730588e-05, 0.005
    full = firing_steps(EveryTime(s), dt, 20)
    for start in (full[3], full[3] + 1, full[3] - 1, 1000):
        later = [n for n in full if n > start]
        assert firing_steps(EveryTime(s), dt, len(later), start=start) == later


def test_every_time_on_pour_probe_steps():
    # pour: dt = t_c/50; probes at 0.005 s fire at these steps (also checked end-to-end in test_cli)
    dt = 1.4949792210730588e-05
    assert firing_steps(EveryTime(0.005), dt, 4) == [335, 669, 1004, 1338]
    assert EveryTime(0.005).next_step(1338, dt) == 1673


def test_every_time_next_step_always_advances():
    e = EveryTime(1e-6)
    for step in (0, 1, 10**6, 10**9):
        assert e.next_step(step, 1.0) == step + 1


@pytest.mark.parametrize("bad", [0.0, -1.0, float("nan")])
def test_every_time_rejects_non_positive_interval(bad):
    with pytest.raises(ValueError, match="seconds must be > 0"):
        EveryTime(bad)


def test_schedules_are_immutable_values():
    assert Every(3) == Every(3)
    assert EveryTime(0.1) == EveryTime(0.1)
    with pytest.raises(AttributeError):
        Every(3).steps = 4
