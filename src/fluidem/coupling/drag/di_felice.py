"""Di Felice (1994) voidage function with a single-sphere drag coefficient.

    F  = ½ ρ C_D (π d²/4) ε² |u−v| (u−v) ε^(−χ)
    C_D = (0.63 + 4.8/√Re)²,  χ = 3.7 − 0.65 exp(−(1.5 − log10 Re)²/2),  Re = ε ρ |u−v| d/μ

Reference: R. Di Felice, Int. J. Multiphase Flow 20 (1994) 153, as cited by the DEM
book 2012 two-phase chapters (ref. 6; the chapter names the law but prints no formula).
Here F is taken as the drag ε f_d of Sun 2007 eq. 28, so
β/(1−ε) = F/(V_p (u−v)) = 3/4 C_D ρ |u−v| ε^(2−χ)/d.

Valid: 10^-2 ≲ Re ≲ 10^4, all voidages of fluidised and sedimenting suspensions.
*Not* Stokes drag at Re → 0: C_D → 4.8²/Re = 23.04/Re, so the drag tends to
0.96 · 3πμd (u−v) (4 % low), the known limit of the Dallavalle C_D. For ε ≲ 0.44 and
0.1 ≲ Re ≲ 4, β falls slightly (< 0.1 %) as the slip grows, because χ(Re) falls; the force
β V_p/(1−ε) |u−v| still grows.
"""
from __future__ import annotations

import math
from typing import ClassVar, Literal

from numba import njit

from .base import DragLaw, drag_laws

CODE = 3


@njit(cache=True, error_model="numpy", inline="always")
def beta_per_solids(p, eps, slip, d, rho, mu):
    """β/(1−ε) [kg m^-3 s^-1] of Di Felice 1994."""
    re = eps * rho * slip * d / mu
    # C_D |u−v| = (0.63 √|u−v| + 4.8 √(μ/(ερd)))², finite at zero slip
    root = 0.63 * math.sqrt(slip) + 4.8 * math.sqrt(mu / (eps * rho * d))
    if re > 0.0:
        t = 1.5 - math.log10(re)
        chi = 3.7 - 0.65 * math.exp(-0.5 * t * t)
    else:
        chi = 3.7
    return 0.75 * root * root * rho / d * eps ** (2.0 - chi)


@drag_laws.register("di_felice")
class DiFelice(DragLaw):
    """Di Felice 1994: C_D = (0.63 + 4.8/√Re)², voidage function ε^(−χ(Re)); 4 % below Stokes at Re → 0."""

    model: Literal["di_felice"] = "di_felice"
    code: ClassVar[int] = CODE
    reference_test: ClassVar[str] = "test_closure_matches_published_formula"
    stokes_limit: ClassVar[bool] = False
