"""The ``[coupling]`` section of a case: how gas and particles exchange momentum.

``drag`` names a closure of the ``drag_laws`` registry; ``voidage`` is the particle → grid
mapping (``VoidageMapping``: method, smoothing, velocity weighting, minimum voidage);
``pressure_gradient_force`` adds −V_p ∇p to each particle (Sun 2007 eq. 28);
``drag_update`` says when the particle drag is re-evaluated: ``"frozen"`` once per gas
step DT (one compiled call for all DEM sub-steps), ``"substep"`` every DEM sub-step with
the particle's current position and velocity in the gas field of that DT (slower: one
call per sub-step).

Example (TOML)::

    [coupling]
    drag = "hoomans1996"
    pressure_gradient_force = true
    drag_update = "frozen"
    [coupling.voidage]
    method = "centroid"
"""
from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, field_validator

from .drag import DragLaw, drag_laws
from .voidage import VoidageMapping


class CouplingSection(BaseModel):
    """Gas–particle momentum exchange of a coupled run (used only with a ``[gas]`` section)."""

    model_config = ConfigDict(extra="forbid", validate_assignment=True)

    drag: str = Field("hoomans1996", description="drag law by name (drag_laws registry)")
    voidage: VoidageMapping = Field(default_factory=VoidageMapping, description="particle → grid mapping")
    pressure_gradient_force: bool = Field(True, description="add −V_p ∇p to each particle (Sun 2007 eq. 28)")
    drag_update: Literal["substep", "frozen"] = Field("frozen", description="drag re-evaluated per DEM sub-step "
                                                                          "or once per gas step")

    @field_validator("drag")
    @classmethod
    def _known(cls, v):
        if v not in drag_laws:
            raise ValueError(f"unknown drag law {v!r}; allowed: {', '.join(drag_laws.names())}")
        return v

    def drag_law(self) -> DragLaw:
        return drag_laws.get(self.drag)()
