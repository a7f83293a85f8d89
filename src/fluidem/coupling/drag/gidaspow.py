"""Ergun / Wen–Yu in the form of Sun et al. (2007) eqs 30-31 (Gidaspow 1994; Tsuji et al. 1993).

    ε ≤ 0.8:  β = 150 ε_s²/(ε d²) μ + 1.75 ε_s ρ |u−v|/d                      eq. 30
    ε > 0.8:  β = 3/4 C_D ε ε_s/d ρ |u−v| ε^(−2.7)                             eq. 30
    C_D = 24 (1 + 0.15 Re^0.687)/Re (Re < 1000), 0.43 (Re ≥ 1000)              eq. 31
    Re = d ε |u−v| ρ/μ                                                         after eq. 30

with ε_s = 1 − ε. Differs from ``hoomans1996`` in the Wen–Yu exponent (2.7 against 2.65),
the inertial C_D (0.43 against 0.44) and which side takes ε = 0.8. Valid as there;
discontinuous at ε = 0.8 (Re → 0: Ergun 37.5, Wen–Yu 18·0.8^−2.7 ≈ 32.9, in units of
μ(1−ε)/d²). Reaches Stokes drag as ε → 1, Re → 0.
"""
from __future__ import annotations

from typing import ClassVar, Literal

from numba import njit

from ._ergun_wen_yu import ergun_per_solids, wen_yu_per_solids
from .base import DragLaw, drag_laws

CODE = 2
SWITCH = 0.8  # Sun 2007 eq. 30: Ergun at and below, Wen–Yu above


@njit(cache=True, error_model="numpy", inline="always")
def beta_per_solids(p, eps, slip, d, rho, mu):
    """β/(1−ε) [kg m^-3 s^-1], Sun 2007 eqs 30-31."""
    if eps <= SWITCH:
        return ergun_per_solids(eps, slip, d, rho, mu)  # Sun 2007 eq. 30, first line
    return wen_yu_per_solids(eps, slip, d, rho, mu, 2.7, 0.43)  # Sun 2007 eqs 30-31


@drag_laws.register("gidaspow")
class Gidaspow(DragLaw):
    """Ergun (ε ≤ 0.8) / Wen–Yu (ε > 0.8, ε^−2.7, C_D = 0.43 above Re 1000), Sun 2007 eqs 30-31."""

    model: Literal["gidaspow"] = "gidaspow"
    code: ClassVar[int] = CODE
    reference_test: ClassVar[str] = "test_closure_matches_published_formula"
