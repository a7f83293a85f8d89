"""Instantaneous binary collisions of hard spheres (Hoomans et al. 1996, eqs 1–29).

Chosen with ``model = "hard_sphere"``; it selects the event-driven engine
(``particles/hardsphere.py``) instead of the soft-sphere one. A collision is fixed by
the restitution e (Newton's law, eq. 16) and the Coulomb friction μ (eq. 17); the
sticking class (eq. 25) ends with zero slip (eq. 28). Walls are bodies of infinite
mass; their e_w, μ_w come from ``wall_contact``/``wall_pairs`` as for soft spheres.

Packed row: slot 0 CODE (3), slot 1 restitution e, slot 7 friction μ.
"""
from __future__ import annotations

import math
from typing import ClassVar, Literal

import numpy as np

from .base import ContactModel, contact_models, empty_row

CODE = 3


@contact_models.register("hard_sphere")
class HardSphere(ContactModel):
    """Hard-sphere collision law of Hoomans 1996: restitution e and friction μ, no stiffness."""

    model: Literal["hard_sphere"] = "hard_sphere"

    code: ClassVar[int] = CODE
    instantaneous: ClassVar[bool] = True

    def pack(self, body_i, body_j) -> np.ndarray:
        row = empty_row(CODE, self.friction)
        row[1] = self.restitution
        return row

    def contact_time(self, m_eff, r_eff, impact_velocity, body_i=None, body_j=None) -> float:
        """Collisions are instantaneous: no contact time limits the step."""
        return 0.0
