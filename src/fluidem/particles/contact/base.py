"""Base class of contact models and the layout of their packed parameter rows.

The compiled kernels see a contact law as one float64 row per (species, species)
or (species, wall) pair. Slot meanings are fixed here; each model documents how
it fills them:

====  =====================  ============================================  ==============================
slot  linear_spring_dashpot  hertz_mindlin                                 hertz_mindlin_jkr
====  =====================  ============================================  ==============================
0     CODE (1; 4 Hertzian)   CODE (2)                                      CODE (5)
1     k_n [N/m]              E* [Pa]                                       E* [Pa]
2     k_t [N/m]              G* [Pa]                                       G* [Pa]
3     zeta_n [-]             A [-] (dimensionless Hertz damping)           A [-]
4     eta_n fixed [N s/m]    A sqrt(4/3 E*)  (derived)                     A sqrt(4/3 E*)
5     eta_t / eta_n [-]      A sqrt(16/3 G*) (derived)                     A sqrt(16/3 G*)
6     unused                 unused                                        surface energy gamma [J/m^2]
7     friction mu [-]        friction mu [-]                               friction mu [-]
====  =====================  ============================================  ==============================

Slots 8 and up are the same for every force-based law:

====  ==============================================================================
8     rolling friction mu_r [-] (0: no rolling resistance)
9     rolling model (ROLLING_CDT = 1: constant directional torque; ROLLING_EPSD = 2: elastic–plastic
      spring–dashpot)
10    1.0 for a row that needs the extended code: an adhesive law (its contacts outlast touch) or a
      variant code of a law (``extra_codes``); else 0.0
11    rolling damping ratio eta_r [-] of the ``epsd`` model (0 otherwise)
====  ==============================================================================

A row whose slots 8 and 10 are zero runs the plain pair and wall code, the same
compiled code, and the same numbers, as before those slots existed; a non-zero
slot 8 or 10 in any row of a table selects the extended code (rolling torques,
adhesive contacts, variant laws) for that table.

A table with an ``epsd`` row (slot 9 = ROLLING_EPSD) keeps each contact's rolling spring torque [N m] in
three more history columns (``ROLLING_HISTORY``: columns 4-6 of the pair and plane-wall histories, after the
adhesive column 3, which such a table also has; columns 3-5 of a wall shape's history slots); the other
tables keep their three (four with an adhesive law) columns.
"""
from __future__ import annotations

from typing import ClassVar, Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, model_validator

from ...registry import Registry

N_SLOTS = 12
SLOT_CODE, SLOT_FRICTION = 0, 7
SLOT_ROLLING_FRICTION, SLOT_ROLLING_MODEL, SLOT_EXTENDED = 8, 9, 10  # SLOT_EXTENDED: slot 10 below
SLOT_ROLLING_DAMPING = 11
ROLLING_CDT = 1  # rolling model code: constant directional torque
ROLLING_EPSD = 2  # rolling model code: elastic–plastic spring–dashpot (a rolling spring with history)
ROLLING_HISTORY = 4  # first history column of the rolling spring torque in a pair or plane-wall history


def uses_rolling_spring(table: np.ndarray) -> bool:
    """True if some row of a packed table (..., N_SLOTS) has the ``epsd`` rolling model: its contacts keep a
    rolling spring torque in their history."""
    return bool(np.any(table[..., SLOT_ROLLING_MODEL] == ROLLING_EPSD))

contact_models: Registry[type["ContactModel"]] = Registry("contact model")


class ContactModel(BaseModel):
    """Parameters shared by every contact law: restitution and Coulomb friction."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, validate_assignment=True)

    restitution: float = Field(0.9, gt=0.0, le=1.0, description="normal restitution coefficient e_n [-]")
    friction: float = Field(0.3, ge=0.0, description="Coulomb friction coefficient mu [-]")

    code: ClassVar[int] = 0
    # further codes the model packs for variants of its law, each with its own kernel in the model's module:
    # {code: name of the coefficients kernel}; a row with such a code sets slot 10 (the extended code runs it)
    extra_codes: ClassVar[dict] = {}
    # an adhesive law: contacts persist into negative overlap down to the law's pull-off distance (its module
    # defines ``pull_off(p, r_eff)``), per-contact state in a fourth history column
    adhesive: ClassVar[bool] = False
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


class SoftContactModel(ContactModel):
    """A force-based law: adds the rolling resistance shared by every soft-sphere law."""

    rolling_friction: float = Field(
        0.0, ge=0.0, description="rolling friction coefficient mu_r [-]: a torque mu_r R* |F_n| against the relative "
                                 "spin (0: no rolling resistance)")
    rolling_model: Literal["cdt", "epsd"] = Field(
        "cdt", description="rolling resistance model: 'cdt', the constant directional torque (Ai et al. 2011 model A, "
                           "LIGGGHTS rolling_friction cdt); 'epsd', the elastic–plastic spring–dashpot (Ai et al. "
                           "2011 model C with the rolling stiffness k_r = k_t R*^2 of Iwashita & Oda 1998, LIGGGHTS "
                           "rolling_friction epsd2): a rolling spring kept per contact, its torque capped at "
                           "mu_r R* |F_n|")
    rolling_damping: float = Field(
        0.0, ge=0.0, description="rolling_model 'epsd' only: viscous rolling damping ratio eta_r [-], the dashpot "
                                 "C_r = eta_r 2 sqrt(I_r k_r) acting while the rolling spring is below its limit "
                                 "(Ai et al. 2011 eqs 17-18; 0: none, the LIGGGHTS epsd2 choice)")

    @model_validator(mode="after")
    def _check_rolling(self):
        if self.rolling_damping > 0.0 and self.rolling_model != "epsd":
            raise ValueError(f"rolling_damping = {self.rolling_damping:g} needs rolling_model = 'epsd' (the "
                             f"{self.rolling_model!r} model has no rolling spring to damp); set rolling_model = "
                             "'epsd' or leave rolling_damping at 0")
        return self

    def pack_rolling(self, row: np.ndarray) -> np.ndarray:
        """Fill the rolling slots of a packed row (slots 8, 9 and 11); returns the row."""
        row[SLOT_ROLLING_FRICTION] = self.rolling_friction
        if self.rolling_friction > 0.0:
            row[SLOT_ROLLING_MODEL] = ROLLING_EPSD if self.rolling_model == "epsd" else ROLLING_CDT
            if self.rolling_model == "epsd":
                row[SLOT_ROLLING_DAMPING] = self.rolling_damping
        else:
            row[SLOT_ROLLING_MODEL] = 0.0
        return row

    def pull_off_distance(self, r_eff: float, body_i, body_j) -> float:
        """Separation beyond touch [m] down to which a contact of this law lasts (0: it ends at touch)."""
        return 0.0


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
