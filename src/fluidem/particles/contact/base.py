"""Base class of contact models and the layout of their packed parameter rows.

The compiled kernels see a contact law as one float64 row per (species, species)
or (species, wall) pair. Slot meanings are fixed here; each model documents how
it fills them:

====  =====================  ============================================
slot  linear_spring_dashpot  hertz_mindlin
====  =====================  ============================================
0     CODE (1)               CODE (2)
1     k_n [N/m]              E* [Pa]
2     k_t [N/m]              G* [Pa]
3     zeta_n [-]             A [-] (dimensionless Hertz damping)
4     eta_n fixed [N s/m]    A sqrt(4/3 E*)  (derived)
5     eta_t / eta_n [-]      A sqrt(16/3 G*) (derived)
6     unused                 unused
7     friction mu [-]        friction mu [-]
====  =====================  ============================================
"""
from __future__ import annotations

from typing import ClassVar

import numpy as np
from pydantic import BaseModel, ConfigDict, Field

from ...registry import Registry

N_SLOTS = 8
SLOT_CODE, SLOT_FRICTION = 0, 7

contact_models: Registry[type["ContactModel"]] = Registry("contact model")


class ContactModel(BaseModel):
    """Parameters shared by every contact law: restitution and Coulomb friction."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, validate_assignment=True)

    restitution: float = Field(0.9, gt=0.0, le=1.0, description="normal restitution coefficient e_n [-]")
    friction: float = Field(0.3, ge=0.0, description="Coulomb friction coefficient mu [-]")

    code: ClassVar[int] = 0
    instantaneous: ClassVar[bool] = False  # True: hard-sphere collisions, handled by the event-driven engine
    # the test that checks this law against an analytic or published result (a function name under tests/)
    reference_test: ClassVar[str] = ""
    # parameters that make a valid law of this model besides restitution and friction (the registry-parametrised
    # tests build each model from them)
    example: ClassVar[dict] = {}

    def pack(self, body_i: "Material", body_j: "Material | None") -> np.ndarray:
        """Parameter row for a contact of body i with body j (j=None: a rigid wall of i's material)."""
        raise NotImplementedError

    def contact_time(self, m_eff: float, r_eff: float, impact_velocity: float, body_i, body_j) -> float:
        """Duration of a head-on collision [s] used to choose the time step."""
        raise NotImplementedError


class Material(BaseModel):
    """Elastic constants of a body, needed by Hertz–Mindlin; ignored by linear springs."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)

    youngs_modulus: float | None = None
    poisson_ratio: float | None = None


def empty_row(code: int, friction: float) -> np.ndarray:
    row = np.zeros(N_SLOTS)
    row[SLOT_CODE] = code
    row[SLOT_FRICTION] = friction
    return row
