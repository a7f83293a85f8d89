"""Open sides of the gas: prescribed pressure and continuous outflow (Hoomans 1996 Table 1, flags 5 and 6)."""
from __future__ import annotations

from typing import ClassVar, Literal

from pydantic import Field, field_validator

from ..grid import OUTFLOW, PRESSURE
from .base import BoundaryCondition, Pulse, Table, Value, boundary_conditions, check_number, evaluate


@boundary_conditions.register("pressure_outlet")
class PressureOutlet(BoundaryCondition):
    """Prescribed-pressure side (Hoomans 1996 Table 1, flag 5), free slip.

    Parameters
    ----------
    pressure : float or callable t -> float, optional
        Pressure [Pa] in the boundary cells, i.e. at their centres, half a cell
        outside the domain (Hoomans' prescribed-pressure cell). Default: the gas's
        ``reference_pressure``. Gas may leave or enter; entering gas has the
        voidage of the adjacent interior cell and the density of this pressure.
    """

    kind: Literal["pressure_outlet"] = "pressure_outlet"
    pressure: Value | None = Field(None, description="pressure [Pa] in the boundary cells; default the gas's "
                                                      "reference_pressure")
    flag: ClassVar[int] = PRESSURE
    reference_test: ClassVar[str] = "test_pressure_driven_poiseuille_between_pressure_boundaries"

    @field_validator("pressure", mode="before")
    @classmethod
    def _positive(cls, v):
        return None if v is None else check_number(v, positive=True)

    def prescribed_pressure(self, t: float) -> float | None:
        return None if self.pressure is None else evaluate(self.pressure, t)

    @property
    def time_dependent(self) -> bool:
        return callable(self.pressure)


@boundary_conditions.register("outflow")
class Outflow(BoundaryCondition):
    """Continuous-outflow side (Hoomans 1996 Table 1, flag 6), free slip.

    The velocity through each boundary face copies the adjacent interior face
    (zero normal gradient, taken from the start of the step) and all such faces are
    scaled together so that the outflow closes the domain's mass balance (Versteeg
    & Malalasekera 2007 §11.9). The pressure in the boundary cells copies the interior.
    Outflow sets no pressure level: with no ``PressureOutlet`` the constant-density
    gas keeps the level of its initial state and the ideal gas the level its mass gives.
    """

    kind: Literal["outflow"] = "outflow"
    flag: ClassVar[int] = OUTFLOW
    reference_test: ClassVar[str] = "test_continuous_outflow_has_zero_gradient_and_closes_the_mass_balance"


__all__ = ["PressureOutlet", "Outflow", "Pulse", "Table"]
