"""Ergun / Wen–Yu as used by Hoomans et al. (1996), eqs 45-47 with C_D of eq. 38.

    ε < 0.8:  β = 150 (1−ε)²/ε μ/d² + 1.75 (1−ε) ρ |u−v|/d                 eq. 45
    ε ≥ 0.8:  β = 3/4 C_D ε(1−ε)/d ρ |u−v| ε^(−2.65)                       eq. 46
    C_D = 24/Re (1 + 0.15 Re^0.687) (Re < 1000), 0.44 (Re ≥ 1000)            eq. 38
    Re = ε ρ |u−v| d/μ                                                      eq. 47

Valid: Ergun for packed and dense beds (ε ≲ 0.8), Wen–Yu for dilute suspensions
(Richardson–Zaki data, 0.8 ≲ ε ≤ 1), all Re. The switch at ε = 0.8 is discontinuous:
at Re → 0 the Ergun value is 37.5 μ(1−ε)/d² against Wen–Yu's 18·0.8^−2.65 ≈ 32.5 (a
15 % jump); tests state the jump exactly. Reaches Stokes drag 3πμd as ε → 1, Re → 0.
"""
from __future__ import annotations

from typing import ClassVar, Literal

from numba import njit

from ._ergun_wen_yu import ergun_per_solids, wen_yu_per_solids
from .base import DragLaw, drag_laws

CODE = 1
SWITCH = 0.8  # Hoomans 1996 §3.2.2: Ergun below, Wen–Yu at and above


@njit(cache=True, error_model="numpy", inline="always")
def beta_per_solids(p, eps, slip, d, rho, mu):
    """β/(1−ε) [kg m^-3 s^-1], Hoomans 1996 eqs 45-47."""
    if eps < SWITCH:
        return ergun_per_solids(eps, slip, d, rho, mu)  # Hoomans 1996 eq. 45
    return wen_yu_per_solids(eps, slip, d, rho, mu, 2.65, 0.44)  # Hoomans 1996 eqs 46-47, 38


@drag_laws.register("hoomans1996")
class Hoomans1996(DragLaw):
    """Ergun (ε < 0.8) / Wen–Yu (ε ≥ 0.8, ε^−2.65, C_D = 0.44 above Re 1000), Hoomans 1996 eqs 45-47."""

    model: Literal["hoomans1996"] = "hoomans1996"
    code: ClassVar[int] = CODE
    reference_test: ClassVar[str] = "test_closure_matches_published_formula"
