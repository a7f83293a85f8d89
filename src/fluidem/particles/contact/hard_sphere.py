"""Instantaneous binary collisions of hard spheres (Hoomans et al. 1996, eqs 1–29).

Chosen with ``model = "hard_sphere"``; it selects the event-driven engine
(``particles/hardsphere.py``) instead of the soft-sphere one. A collision is fixed by
the restitution e (Newton's law, eq. 16) and the Coulomb friction μ (eq. 17); the
sticking class (eq. 25) ends with zero slip (eq. 28). Walls are bodies of infinite
mass; their e_w, μ_w come from ``wall_contact``/``wall_pairs`` as for soft spheres.

Inelastic collapse (infinitely many collisions in finite time, McNamara & Young 1994)
is prevented with the TC model of Luding & McNamara (1998, Granular Matter 1,
113–128): a collision in which either particle had its previous collision less than
``collapse_time`` t_c ago is treated as elastic and frictionless (e = 1, μ = 0). t_c is
the duration of a real contact. A particle that meets others more often than that is in
a lasting multi-particle contact, where a sequence of separate dissipative impacts is
the wrong picture. The default 1e-5 s is the Hertzian contact time of mm-sized glass or
aluminium spheres at impact speeds of about 1 m/s (10–40 µs from 1 down to 0.01 m/s).
Hoomans 1996 used no remedy; ``collapse_time = 0`` reproduces that.

Why the remedy is on by default. Under Hoomans' force step, gravity is added as an
impulse g DT every DT (eqs 33–34). In a resting bed that impulse reaches the floor
through a cascade of collisions microseconds or less apart, and without the remedy
dense frictional beds collapse. Measured:

* the Table 2 bed without gas (2400 spheres of 4 mm in a box 0.15 m wide, e = 0.9,
  μ = 0.3; benchmarks/hardsphere_collisions.py). Remedy off: 1.7 million collisions per
  step at t = 0.17 s, then a step with more than 25 million events, and the event
  limit stopped the run. Remedy on: the bed settles at 30–40 thousand collisions per
  step.
* 150 spheres of 3–4 mm, e = 0.6, μ = 0.5, in a box 0.04 m wide. Remedy off: collapse
  against the walls by t = 0.08 s. Remedy on: the bed settles at about 600 collisions
  per step.

Where the remedy fails: equal spheres that pack in a row fitting exactly between two
parallel walls. The built-in pour case is such a box, 24 diameters wide. Such a row has
gaps of round-off size. The remedy keeps its collisions elastic, so their energy never
leaves, and with t_c = 1e-5 s that row chattered at 2–5 million collisions per step
until the event limit stopped the run at t = 0.24 s. With ``collapse_time = 0`` the same
bed settles, at about 0.25 million collisions per step. Neither setting is safe in such
boxes: 120 spheres of 4 mm (e = 0.8) in a box 10 diameters wide hit the event limit at
t = 0.19 s with the remedy and at t = 0.20 s without it. A bed at rest under gravity and
without gas is the hardest case for Hoomans' scheme. The engine's per-step event limit
turns each such failure into a clear error instead of a hang. Three things help: a box
width that is not a whole number of diameters, a size distribution, or a smaller DT.

Packed row: slot 0 CODE (3), slot 1 restitution e, slot 2 collapse time t_c [s],
slot 7 friction μ.
"""
from __future__ import annotations

from typing import ClassVar, Literal

import numpy as np
from pydantic import Field

from .base import ContactModel, contact_models, empty_row

CODE = 3
SLOT_RESTITUTION, SLOT_COLLAPSE_TIME = 1, 2


@contact_models.register("hard_sphere")
class HardSphere(ContactModel):
    """Hard-sphere collision law of Hoomans 1996: restitution e and friction μ, no stiffness.

    ``collapse_time`` t_c [s] is the TC-model time (Luding & McNamara 1998): a collision
    less than t_c after the previous collision of either particle is elastic and
    frictionless. 0 disables the remedy (as in Hoomans 1996); see the module docstring for
    when to do that.
    """

    model: Literal["hard_sphere"] = "hard_sphere"
    collapse_time: float = Field(
        1e-5, ge=0.0, lt=1.0,
        description="TC-model time t_c [s] (Luding & McNamara 1998): a collision within t_c of the previous one "
                    "of either particle is elastic and frictionless; 0 switches the remedy off (Hoomans 1996)")

    code: ClassVar[int] = CODE
    instantaneous: ClassVar[bool] = True

    def pack(self, body_i, body_j) -> np.ndarray:
        row = empty_row(CODE, self.friction)
        row[SLOT_RESTITUTION] = self.restitution
        row[SLOT_COLLAPSE_TIME] = self.collapse_time
        return row

    def contact_time(self, m_eff, r_eff, impact_velocity, body_i=None, body_j=None) -> float:
        """Collisions are instantaneous: no contact time limits the step."""
        return 0.0
