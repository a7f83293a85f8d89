"""Linear spring–dashpot contacts with a Coulomb-limited tangential spring (Sun et al. 2007, eqs 17–26).

Normal force  F_n = f(δ/d) (k_n δ n − η_n v_n)            (Sun 2007 eq. 21, η_n = γ_n m_eff)
Tangential    F_t = −f(δ/d) (k_t u_t + η_t v_t), |F_t| ≤ μ|F_n|   (eq. 22 and the truncation below it)

``nonlinearity = "none"`` (the default) takes f = 1, the linear spring–dashpot; ``"hertzian"``
takes f = sqrt(δ/d), Sun's "Hertzian contacts with viscoelastic damping" (after Silbert et al.
2001), with d = 4R*: the diameter for two equal spheres, 2 d_i/(1 + d_i/d_j) in general, and
twice the particle diameter against a wall (a sphere of infinite radius). The Hertzian variant
packs its own code (``HERTZIAN``) and kernel (``hertzian_coefficients``) and runs in the extended
(scalar) code, so the linear law's compiled code is untouched by it. Its restitution depends on the impact speed; ``restitution``
sets ζ as for the linear law.

The user gives k_n and either the restitution e_n or the damping coefficient η_n
[N s/m] (Sun's Table 1 gives the latter). From e_n, η_n = 2 ζ sqrt(k_n m_eff) with
ζ = −ln e / sqrt(π² + ln² e), which is eqs 25–26 solved for γ_n; it is evaluated
per contact so that polydisperse pairs all get the requested restitution.
"""
from __future__ import annotations

import math
from typing import ClassVar, Literal

import numpy as np
from numba import njit
from pydantic import Field

from .base import SLOT_EXTENDED, SoftContactModel, contact_models, empty_row
from .hertz_mindlin import contact_time_hertz

CODE = 1
HERTZIAN = 4  # the code of the variant with f(δ/d) = sqrt(δ/d)


def damping_ratio(restitution: float) -> float:
    """ζ such that a linear spring–dashpot with η = 2ζ sqrt(k m) rebounds with e (Sun 2007 eqs 25–26)."""
    if restitution >= 1.0:
        return 0.0
    ln_e = math.log(restitution)
    return -ln_e / math.sqrt(math.pi**2 + ln_e**2)


@contact_models.register("linear_spring_dashpot")
class LinearSpringDashpot(SoftContactModel):
    """Linear spring–dashpot (Sun 2007 eqs 21–26), tangential spring with Coulomb limit."""

    model: Literal["linear_spring_dashpot"] = "linear_spring_dashpot"
    stiffness: float = Field(gt=0.0, description="normal spring stiffness k_n [N/m]")
    tangential_stiffness: float | None = Field(
        None, gt=0.0, description="tangential stiffness k_t [N/m]; default 2/7 k_n"
    )
    damping: float | None = Field(
        None, ge=0.0, description="normal damping coefficient eta_n = gamma_n m_eff [N s/m]; overrides restitution"
    )
    tangential_damping_factor: float = Field(0.5, ge=0.0, description="eta_t / eta_n [-] (MFIX default 0.5)")
    restitution: float = Field(0.9, gt=0.0, le=1.0, description="normal restitution e_n [-] (ignored if damping given)")
    nonlinearity: Literal["none", "hertzian"] = Field(
        "none", description="f(delta/d) of Sun 2007 eq. 21: 'none' f = 1 (linear), 'hertzian' f = sqrt(delta/d) "
                            "with d = 4 R*")

    code: ClassVar[int] = CODE
    extra_codes: ClassVar[dict] = {HERTZIAN: "hertzian_coefficients"}
    reference_test: ClassVar[str] = "test_particle_particle_collision"  # Sun 2007 eqs 25-26
    example: ClassVar[dict] = {"stiffness": 1.0e4}

    def pack(self, body_i, body_j) -> np.ndarray:
        row = empty_row(HERTZIAN if self.nonlinearity == "hertzian" else CODE, self.friction)
        row[1] = self.stiffness
        row[2] = self.tangential_stiffness if self.tangential_stiffness is not None else 2.0 / 7.0 * self.stiffness
        if self.damping is None:
            row[3] = damping_ratio(self.restitution)
        else:
            row[4] = self.damping
        row[5] = self.tangential_damping_factor
        if self.nonlinearity == "hertzian":
            row[SLOT_EXTENDED] = 1.0  # a variant code: the extended code runs it (slot 10, base.py)
        return self.pack_rolling(row)

    def contact_time(self, m_eff, r_eff, impact_velocity, body_i=None, body_j=None) -> float:
        """Sun 2007 eq. 26: t_c = π (k_n/m_eff − γ_n²/4)^(−1/2); Hertzian variant: the undamped Hertz impact
        time of its elastic force (k_n/sqrt(4R*)) δ^(3/2), the same as Hertz with E* = 3 k_n/(8 R*)."""
        if self.nonlinearity == "hertzian":
            return contact_time_hertz(m_eff, r_eff, 3.0 * self.stiffness / (8.0 * r_eff), impact_velocity, 1.0)
        row = self.pack(body_i, body_j)
        eta = row[4] + 2.0 * row[3] * math.sqrt(self.stiffness * m_eff)
        gamma = eta / m_eff
        disc = self.stiffness / m_eff - 0.25 * gamma**2
        if disc <= 0:
            return math.inf  # overdamped: no rebound; the caller reports it
        return math.pi / math.sqrt(disc)


@njit(cache=True, error_model="numpy", inline="always")
def coefficients(p, overlap, m_eff, r_eff):
    """(elastic normal force [N], η_n [N s/m], k_t [N/m], η_t [N s/m]) for a linear contact (Sun 2007 eq. 21–22)."""
    kn = p[1]
    eta_n = p[4] + 2.0 * p[3] * math.sqrt(kn * m_eff)
    return kn * overlap, eta_n, p[2], p[5] * eta_n


@njit(cache=True, error_model="numpy", inline="always")
def hertzian_coefficients(p, overlap, m_eff, r_eff):
    """The coefficients above times f(δ/d) = sqrt(δ/d), d = 4 R* (Sun 2007 eq. 21–22, Hertzian contacts)."""
    f = math.sqrt(overlap / (4.0 * r_eff))
    kn = p[1]
    eta_n = (p[4] + 2.0 * p[3] * math.sqrt(kn * m_eff)) * f
    return kn * overlap * f, eta_n, p[2] * f, p[5] * eta_n
