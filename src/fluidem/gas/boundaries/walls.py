"""Impermeable walls of the gas (Hoomans 1996 Table 1, flags 2 and 3)."""
from __future__ import annotations

from typing import ClassVar, Literal

from ..grid import FREE_SLIP, NO_SLIP
from .base import BoundaryCondition, boundary_conditions


@boundary_conditions.register("wall")
class Wall(BoundaryCondition):
    """Impermeable no-slip wall (Hoomans 1996 Table 1, flag 3): u_n = 0, u_t = 0 on the wall."""

    kind: Literal["wall"] = "wall"
    flag: ClassVar[int] = NO_SLIP
    reference_test: ClassVar[str] = "test_no_slip_walls_damp_the_half_sine_at_the_analytic_rate"


@boundary_conditions.register("free_slip")
class FreeSlip(BoundaryCondition):
    """Impermeable free-slip wall (Hoomans 1996 Table 1, flag 2): u_n = 0, ∂u_t/∂n = 0."""

    kind: Literal["free_slip"] = "free_slip"
    flag: ClassVar[int] = FREE_SLIP
    reference_test: ClassVar[str] = "test_free_slip_walls_damp_the_half_cosine_and_leave_uniform_flow"
