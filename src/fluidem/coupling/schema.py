"""The ``[coupling]`` section of a case: how gas and particles exchange momentum.

``drag`` names a closure of the ``drag_laws`` registry; ``voidage`` is the particle → grid
mapping (``VoidageMapping``: method, smoothing, velocity weighting, minimum voidage);
``pressure_gradient_force`` adds −V_p ∇p to each particle (Sun 2007 eq. 28);
``momentum_exchange`` says how drag passes between the phases (``exchange.py``):
``"particle"`` each particle's own drag (Sun 2007 eq. 29), and the gas receives exactly its
opposite on the faces the particle's gas velocity was interpolated from; ``"cell"`` Sun's
cell-averaged drag β V_cell (u − v_s), shared by the particles of the cell in proportion to
their volume, the gas receiving its opposite; ``"cell_beta"`` the gas takes β of the
cell-averaged slip while each particle takes its own drag — as MFIX in Sun 2007 (the
assumption after eq. 35), not equal and opposite; kept to compare with it.
``hoomans1996_total`` (Hoomans 1996 eqs 35-39 on the particles, eqs 45-47 for the gas) is his
own formulation: it requires ``pressure_gradient_force = false`` and ``momentum_exchange =
"cell_beta"`` (checked here).
``drag_update`` says when the particle drag is re-evaluated (the issue's "re-evaluated every
sub-step with the gas frozen (default) or held for the whole DT"): ``"substep"`` (default) every
DEM sub-step in the gas field of that DT — for the "particle" exchange with its drag coefficient
K_p, gas velocity and pressure gradient at the particle kept from the step's start and the
particle's own velocity of each sub-step, inside the engine's one compiled call; for "cell" and
"cell_beta" with the particle's current position and velocity, one call per sub-step (slower) —
or ``"frozen"``, the force of the step's start held for the whole DT. The gas has taken its
share at the step's start, so only ``"frozen"`` pairs the two sides exactly.
``boundary_faces`` (``"particle"`` exchange): a face the gas does not solve (a wall's or an
inflow's) has no momentum control volume; with ``"fold"`` (default) a particle in the half cell
along it takes the gas velocity of the first interior face and hands its drag to the gas there
(that face's control volume takes in the half cell, 1.5 cells, as ∇p is interpolated), with
``"exchange"`` it interpolates towards the boundary's velocity and the drag on the boundary
face is momentum exchanged with the boundary: the gas pressure then does not carry the
weight that particles near an inflow put there (the fluidised bed's pressure drop was 4-5 %
below its weight over area, issue 4). ``pressure_pairing`` (default true, with
``pressure_gradient_force``): the gas's −ε∇p takes on each face the voidage 1 − Σ_p w_pf V_p / V_f
(``_paired_kernels.pressure_voidage``) instead of the mean of the mapped cell voidages, so that
the pressure force is exchanged as exactly as the drag (exactly with ``"fold"``: with ``"exchange"`` the
gas does not give up the pressure force of the particles in the boundary half cells); false keeps the
mapped voidage (as MFIX, where gas and particle pressure forces agree only up to the mapping).

Example (TOML)::

    [coupling]
    drag = "hoomans1996"
    pressure_gradient_force = true
    momentum_exchange = "particle"
    drag_update = "substep"
    [coupling.voidage]
    method = "centroid"
"""
from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

from .drag import DragLaw, drag_laws
from .voidage import VoidageMapping


class CouplingSection(BaseModel):
    """Gas–particle momentum exchange of a coupled run (used only with a ``[gas]`` section)."""

    model_config = ConfigDict(extra="forbid", validate_assignment=True)

    drag: str = Field("hoomans1996", description="drag law by name (drag_laws registry)")
    voidage: VoidageMapping = Field(default_factory=VoidageMapping, description="particle → grid mapping")
    pressure_gradient_force: bool = Field(True, description="add −V_p ∇p to each particle (Sun 2007 eq. 28)")
    momentum_exchange: Literal["particle", "cell", "cell_beta"] = Field(
        "particle", description="drag per particle, paired with the gas (particle); Sun's cell-averaged drag "
                                "shared in the cell (cell); or the unpaired MFIX 2007 form (cell_beta)")
    drag_update: Literal["substep", "frozen"] = Field("substep", description="drag re-evaluated per DEM sub-step "
                                                                           "(gas frozen) or held for the gas step")
    boundary_faces: Literal["fold", "exchange"] = Field(
        "fold", description="particle exchange: drag of a particle in the half cell along a wall or inflow from "
                            "and to the first face the gas solves (fold), or interpolated towards the boundary "
                            "face and exchanged with the boundary (exchange)")
    pressure_pairing: bool = Field(
        True, description="the gas's pressure term −ε∇p takes on each face the voidage left by the particle "
                          "volume deposited there as the particles' ∇p is interpolated, so that it loses exactly "
                          "the −V_p ∇p the particles gain (with pressure_gradient_force; particle and cell "
                          "exchange)")

    @field_validator("drag")
    @classmethod
    def _known(cls, v):
        if v not in drag_laws:
            raise ValueError(f"unknown drag law {v!r}; allowed: {', '.join(drag_laws.names())}")
        return v

    @model_validator(mode="after")
    def _total_force_alone(self):
        """A law giving the total gas force (``hoomans1996_total``) already holds the pressure part."""
        if drag_laws.get(self.drag).total_force:
            if self.pressure_gradient_force:
                raise ValueError(f"drag = {self.drag!r} gives the total gas force on a particle (Hoomans 1996 "
                                 "eqs 34-35, pressure part included): set pressure_gradient_force = false "
                                 "(got true)")
            if self.momentum_exchange != "cell_beta":
                raise ValueError(f"drag = {self.drag!r} gives the total gas force on a particle, which the gas "
                                 f"(−ε∇p) cannot take back as its opposite: momentum_exchange must be 'cell_beta' "
                                 f"(the gas takes β of Hoomans eqs 45-47 per cell), got {self.momentum_exchange!r}")
        return self

    def drag_law(self) -> DragLaw:
        return drag_laws.get(self.drag)()
