"""Schedules: when an observer fires, as a function of the step counter.

The clock is step-based (time = step * dt exactly), so a schedule can say in
advance at which step it fires next; the simulation advances in compiled chunks
up to that step.
"""
from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class Every:
    """Fire every ``steps`` time steps."""

    steps: int

    def __post_init__(self):
        if self.steps < 1:
            raise ValueError(f"Every(steps={self.steps}): steps must be >= 1")

    def next_step(self, step: int, dt: float) -> int:
        """First step strictly after ``step`` at which this schedule fires."""
        return (step // self.steps + 1) * self.steps


@dataclass(frozen=True)
class EveryTime:
    """Fire each time the simulated time crosses a multiple of ``seconds``."""

    seconds: float

    def __post_init__(self):
        if not self.seconds > 0:
            raise ValueError(f"EveryTime(seconds={self.seconds}): seconds must be > 0")

    def next_step(self, step: int, dt: float) -> int:
        k = math.floor(step * dt / self.seconds * (1 + 1e-12)) + 1
        nxt = math.ceil(k * self.seconds / dt * (1 - 1e-12))
        return max(nxt, step + 1)
