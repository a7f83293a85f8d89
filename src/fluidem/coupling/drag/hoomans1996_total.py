"""Hoomans et al. (1996)'s own particle force: eqs 35-39, the total gas force on a particle.

    F_d = π/8 d² C_d' ρ |v| v,   |v| v = ε² |u−v_p| (u−v_p)                  eqs 35-36
    C_d' = C_d ε^(−4.7)                      (Wen & Yu 1966)                  eq. 37
    C_d = 24/Re (1 + 0.15 Re^0.687) (Re < 1000), 0.44 (Re ≥ 1000)             eq. 38
    Re = ε ρ |u−v_p| d/μ                                                     eq. 39

so that β/(1−ε) = F_d/(V_p |u−v_p|) = 3/4 C_d ρ |u−v_p| ε^(−2.7)/d at every voidage.
Hoomans' particle balance (eq. 34) has gravity and this force only: F_d is the *total*
gas force, its pressure part included, so a case using this law sets
``pressure_gradient_force = false``. His gas equation (eq. 43) takes −ε∇p and the
interphase β of eqs 45-47 (``hoomans1996``) from the cell's voidage and mean solids
velocity: the ``cell_beta`` exchange, which this law requires (the gas side of the paired
exchanges would count the pressure part twice). With the 2D → 3D voidage of eq. 49 both
sides then see the voidage of a 3D bed, and the bed pressure drop meets its weight.

Valid: Wen & Yu's data (Richardson–Zaki), all Re. In dense beds it parts from the gas's
Ergun β by regime: at ε = 0.4 the superficial velocity at which it carries a particle is
1.64 m/s against Ergun's 1.70 m/s for Hoomans' 4 mm aluminium (Re ≈ 500), but 0.385 against
0.521 m/s for his 850 µm glass (Re ≈ 30), where a fluidised bed's pressure drop then falls short
of its weight (tests/validation/test_hoomans_experiment.py). Reaches Stokes drag 3πμd as
ε → 1, Re → 0.
"""
from __future__ import annotations

from typing import ClassVar, Literal

from numba import njit

from . import hoomans1996
from ._ergun_wen_yu import wen_yu_per_solids
from .base import DragLaw, drag_laws

CODE = 6
EXPONENT = 3.7  # ε^(−4.7) of eq. 37 times the ε² of eq. 36, over the ε of wen_yu_per_solids' form


@njit(cache=True, error_model="numpy", inline="always")
def beta_per_solids(p, eps, slip, d, rho, mu):
    """β/(1−ε) [kg m^-3 s^-1] of Hoomans 1996 eqs 35-39: 3/4 C_d ρ |u−v| ε^(−2.7)/d."""
    return wen_yu_per_solids(eps, slip, d, rho, mu, EXPONENT, 0.44)


@drag_laws.register("hoomans1996_total")
class Hoomans1996Total(DragLaw):
    """Hoomans 1996 eqs 35-39 on the particles (total gas force), eqs 45-47 as the gas's β."""

    model: Literal["hoomans1996_total"] = "hoomans1996_total"
    code: ClassVar[int] = CODE
    reference_test: ClassVar[str] = "test_closure_matches_published_formula"
    gas_code: ClassVar[int] = hoomans1996.CODE
    total_force: ClassVar[bool] = True
