"""Beetstra, van der Hoef & Kuipers (2007) lattice-Boltzmann drag.

Monodisperse (φ = 1 − ε, Re = ε ρ |u−v| D/μ, the superficial-velocity Reynolds number)::

    F(φ, Re) = 10 φ/ε² + ε² (1 + 1.5 √φ)
             + 0.413 Re/(24 ε²) · (1/ε + 3 φ ε + 8.4 Re^−0.343) / (1 + 10^(3φ) Re^(−(1+4φ)/2))
    β = 18 μ ε φ F/D²          (the force on a particle is β V_p/φ (u−v) = 3π μ D ε F (u−v))

Reference: R. Beetstra, M. A. van der Hoef, J. A. M. Kuipers, AIChE J. 53 (2007) 489
(ref. 8 of the DEM book 2012 two-phase chapters). In a mixture, the polydisperse rule f_di = y_i² f̄_d
(DEM book 2012 chapter, van der Hoef et al. 2005, eqs 10-12) that van der Hoef and Beetstra derived
with this closure is applied to every law by ``_dispatch.beta_per_solids``.

Valid: 0.1 ≲ φ ≲ 0.6 and Re ≲ 1000 (the LB data); F → 1 as φ → 0 and Re → 0 (Stokes).
"""
from __future__ import annotations

import math
from typing import ClassVar, Literal

from numba import njit

from .base import DragLaw, drag_laws

CODE = 4


@njit(cache=True, error_model="numpy", inline="always")
def normalised_drag(eps, re):
    """F(φ, Re) of Beetstra et al. 2007 (normalised by the Stokes drag 3πμD ε|u−v|)."""
    phi = 1.0 - eps
    f0 = 10.0 * phi / (eps * eps) + eps * eps * (1.0 + 1.5 * math.sqrt(phi))
    if re <= 0.0:
        return f0
    a = 0.5 * (1.0 + 4.0 * phi)
    ra = re**a  # 1/(1 + 10^(3φ) Re^−a) = Re^a/(Re^a + 10^(3φ)): no overflow at small Re
    f1 = 0.413 * re / (24.0 * eps * eps) * (1.0 / eps + 3.0 * phi * eps + 8.4 * re ** (-0.343)) \
        * ra / (ra + 10.0 ** (3.0 * phi))
    return f0 + f1


@njit(cache=True, error_model="numpy", inline="always")
def beta_per_solids(p, eps, slip, d, rho, mu):
    """β/(1−ε) [kg m^-3 s^-1] = 18 μ ε F/d² of a monodisperse bed of diameter d."""
    re = eps * rho * slip * d / mu
    return 18.0 * mu * eps * normalised_drag(eps, re) / (d * d)


@drag_laws.register("beetstra")
class Beetstra(DragLaw):
    """Beetstra et al. 2007 LB drag (the reference pairing of the polydisperse y_i² rule, DEM book 2012 eq. 12)."""

    model: Literal["beetstra"] = "beetstra"
    code: ClassVar[int] = CODE
    reference_test: ClassVar[str] = "test_closure_matches_published_formula"
