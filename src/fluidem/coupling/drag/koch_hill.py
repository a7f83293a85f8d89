"""Koch & Hill (2001) lattice-Boltzmann drag for moderate Reynolds numbers (Hill, Koch & Ladd 2001).

    β = 18 μ ε² φ/d² (F0(φ) + ½ F3(φ) Re),   Re = ε ρ |u−v| d/μ,  φ = 1 − ε
    F0 = (1 + 3√(φ/2) + 135/64 φ ln φ + 16.14 φ)/(1 + 0.681 φ − 8.48 φ² + 8.16 φ³)   φ < 0.4
    F0 = 10 φ/ε³                                                                    φ ≥ 0.4
    F3 = 0.0673 + 0.212 φ + 0.0232/ε⁵

Reference: D. L. Koch, R. J. Hill, Annu. Rev. Fluid Mech. 33 (2001) 619; R. J. Hill,
D. L. Koch, A. J. C. Ladd, J. Fluid Mech. 448 (2001) 243; in this form in N. G. Deen et
al., Chem. Eng. Sci. 62 (2007) 28 (not among the seed references). Valid: random arrays
0 < φ ≲ 0.6, Re ≲ 100 (the F3 term is fitted above Re ≈ 40). F0 → 1 as φ → 0 (slowly,
3√(φ/2)), so Stokes drag is reached as ε → 1, Re → 0. F0 is continuous at φ = 0.4
only to about 2 % (the published fit).
"""
from __future__ import annotations

import math
from typing import ClassVar, Literal

from numba import njit

from .base import DragLaw, drag_laws

CODE = 5


@njit(cache=True, error_model="numpy", inline="always")
def beta_per_solids(p, eps, slip, d, rho, mu):
    """β/(1−ε) [kg m^-3 s^-1] of Koch & Hill 2001."""
    phi = 1.0 - eps
    if phi <= 0.0:
        f0 = 1.0
    elif phi < 0.4:
        f0 = (1.0 + 3.0 * math.sqrt(0.5 * phi) + 135.0 / 64.0 * phi * math.log(phi) + 16.14 * phi) / (
            1.0 + 0.681 * phi - 8.48 * phi * phi + 8.16 * phi * phi * phi)
    else:
        f0 = 10.0 * phi / (eps * eps * eps)
    f3 = 0.0673 + 0.212 * phi + 0.0232 / eps**5
    re = eps * rho * slip * d / mu
    return 18.0 * mu * eps * eps / (d * d) * (f0 + 0.5 * f3 * re)


@drag_laws.register("koch_hill")
class KochHill(DragLaw):
    """Koch & Hill 2001 LB drag, β = 18 μ ε² φ/d² (F0 + ½ F3 Re)."""

    model: Literal["koch_hill"] = "koch_hill"
    code: ClassVar[int] = CODE
    reference_test: ClassVar[str] = "test_closure_matches_published_formula"
