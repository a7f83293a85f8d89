"""The ``[coupling]`` section of a case: how gas and particles exchange momentum.

``drag`` is a closure of the ``drag_laws`` registry: a table with the law's ``model`` name and its own
parameters (``drag = { model = "beetstra" }``), or the bare name (``drag = "beetstra"``); ``voidage`` is the particle → grid
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
``drag_update`` says when the particle drag is re-evaluated (re-evaluated every
sub-step with the gas frozen, the default, or held for the whole DT): ``"substep"`` (default) every
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
below its weight over area). ``pressure_pairing`` (default true, with
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

from typing import Annotated, Literal, Union

import numpy as np
from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, model_validator

from .drag import DragLaw, drag_laws
from .voidage import VoidageMapping


def _named(value):
    """A bare law name reads as the table ``{model = name}``."""
    return {"model": value} if isinstance(value, str) else value


# every registered drag law, chosen by its ``model`` key (the registry is the only list of laws)
DragLawChoice = Annotated[Union[tuple(drag_laws.get(n) for n in drag_laws.names())], Field(discriminator="model"),
                          BeforeValidator(_named)]


class CouplingSection(BaseModel):
    """Gas–particle momentum exchange of a coupled run (used only with a ``[gas]`` section)."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, validate_assignment=True)

    drag: DragLawChoice = Field(default_factory=lambda: drag_laws.get("hoomans1996")(),
                                description="drag law: a table with its model name and parameters, or the name")
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
    gpu_exchange: Literal["device", "host"] = Field(
        "device", description="with the particles on the GPU (device = 'gpu'): the particle side of the exchange "
                              "(voidage map, drag, deposit, gas force) on the GPU where the coupling's options "
                              "allow it (device; deposits summed with atomics, so a repeated run agrees to "
                              "round-off), or on the host with the particles fetched once a gas step (host; a "
                              "repeated run agrees bit for bit)")
    polydisperse: Literal["sauter_y2", "none"] | None = Field(
        None, description="drag in a mixture of sizes: 'sauter_y2', each particle takes y² times the law's drag "
                          "at the Sauter mean diameter D̄ of the solids around it, y = d/D̄ (DEM book 2012 "
                          "eqs 10-12); 'none', each particle the law at its own diameter. Default: 'sauter_y2' "
                          "when the particles have more than one diameter, else 'none'")

    @model_validator(mode="after")
    def _total_force_alone(self):
        """A law giving the total gas force (``hoomans1996_total``) already holds the pressure part."""
        name = self.drag.model
        if self.drag.total_force:
            if self.pressure_gradient_force:
                raise ValueError(f"drag = {name!r} gives the total gas force on a particle (Hoomans 1996 "
                                 "eqs 34-35, pressure part included): set pressure_gradient_force = false "
                                 "(got true)")
            if self.momentum_exchange != "cell_beta":
                raise ValueError(f"drag = {name!r} gives the total gas force on a particle, which the gas "
                                 f"(−ε∇p) cannot take back as its opposite: momentum_exchange must be 'cell_beta' "
                                 f"(the gas takes β of Hoomans eqs 45-47 per cell), got {self.momentum_exchange!r}")
            if self.polydisperse == "sauter_y2":
                raise ValueError(f"polydisperse = 'sauter_y2' scales the drag net of the pressure-gradient force "
                                 f"(DEM book 2012 eqs 7-12); drag = {name!r} gives the total gas force: use "
                                 f"polydisperse = 'none' or another law")
        return self

    def resolved_polydisperse(self, diameters) -> str:
        """``polydisperse`` for particles of these diameters: the key, or by default 'sauter_y2' when they
        have more than one size (and the law's force is the drag alone), else 'none'."""
        if self.polydisperse is not None:
            return self.polydisperse
        d = np.asarray(diameters, float)
        several = d.size > 1 and bool(np.any(d != d[0]))
        return "sauter_y2" if several and not self.drag.total_force else "none"

    def drag_law(self) -> DragLaw:
        """The drag law of this section (``drag``)."""
        return self.drag
