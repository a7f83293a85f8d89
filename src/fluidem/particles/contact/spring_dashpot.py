"""Linear spring–dashpot contacts with a Coulomb-limited tangential spring (Sun et al. 2007, eqs 17–26).

Normal force  F_n = k_n δ n − η_n v_n            (Sun 2007 eq. 21 with f = 1, η_n = γ_n m_eff)
Tangential    F_t = −k_t u_t − η_t v_t, |F_t| ≤ μ|F_n|   (eq. 22 and the truncation below it)

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

from .base import ContactModel, contact_models, empty_row

CODE = 1


def damping_ratio(restitution: float) -> float:
    """ζ such that a linear spring–dashpot with η = 2ζ sqrt(k m) rebounds with e (Sun 2007 eqs 25–26)."""
    if restitution >= 1.0:
        return 0.0
    ln_e = math.log(restitution)
    return -ln_e / math.sqrt(math.pi**2 + ln_e**2)


@contact_models.register("linear_spring_dashpot")
class LinearSpringDashpot(ContactModel):
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

    code: ClassVar[int] = CODE
    reference_test: ClassVar[str] = "test_particle_particle_collision"  # Sun 2007 eqs 25-26
    example: ClassVar[dict] = {"stiffness": 1.0e4}

    def pack(self, body_i, body_j) -> np.ndarray:
        row = empty_row(CODE, self.friction)
        row[1] = self.stiffness
        row[2] = self.tangential_stiffness if self.tangential_stiffness is not None else 2.0 / 7.0 * self.stiffness
        if self.damping is None:
            row[3] = damping_ratio(self.restitution)
        else:
            row[4] = self.damping
        row[5] = self.tangential_damping_factor
        return row

    def contact_time(self, m_eff, r_eff, impact_velocity, body_i=None, body_j=None) -> float:
        """Sun 2007 eq. 26: t_c = π (k_n/m_eff − γ_n²/4)^(−1/2)."""
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
