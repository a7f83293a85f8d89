"""Periodic sides of the gas (flag 8, not in Hoomans 1996)."""
from __future__ import annotations

from typing import ClassVar, Literal

from ..grid import PERIODIC
from .base import BoundaryCondition, boundary_conditions


@boundary_conditions.register("periodic")
class Periodic(BoundaryCondition):
    """Periodic side (flag 8): leaving gas re-enters through the opposite side; the boundary cell is the interior
    cell on the opposite side. Both opposite sides must be ``Periodic()``."""

    kind: Literal["periodic"] = "periodic"
    flag: ClassVar[int] = PERIODIC
    reference_test: ClassVar[str] = "test_periodic_sides_make_the_solution_invariant_under_shifts"
