"""Hertz–Mindlin with JKR adhesion (Johnson, Kendall & Roberts 1971; DEM form of Thornton & Ning 1998).

Normal      F_el = 4 E* a³/(3 R*) − sqrt(8 π γ E* a³)                       (JKR 1971; Thornton & Ning 1998)
            δ    = a²/R* − sqrt(2 π γ a / E*)                              (JKR 1971; Thornton & Ning 1998)
            F_n  = F_el − η_n v_n,  η_n = A sqrt((4/3) E* m* a)
Tangential  k_t = 8 G* a, η_t = A sqrt((16/3) G* m* a), |F_t| ≤ μ (F_n + 2 F_c)  (Thornton & Yin 1991)

with E*, G*, A as in ``hertz_mindlin`` (the same restitution-calibrated damping, with the JKR contact
radius a in place of the Hertz one sqrt(R* δ)). γ is the surface energy of the law (J/m², the work of
adhesion: the energy per unit area to part the two surfaces; 2γ_s for two like surfaces of surface energy
γ_s in Johnson's notation).

Hysteresis. A contact forms when the spheres touch (δ = 0, where the force jumps to −(8/9) F_c) and then
holds the pair down to the pull-off separation δ_c < 0, where it breaks (displacement control, the
unstable end of the JKR curve, as Thornton & Ning 1998 break it):

    F_c = (3/2) π γ R*                         the largest attraction, at a = a0/4^(1/3)
    a0³ = 9 π γ R*²/(2 E*)                     contact radius at zero force
    δ_c = −(3/4) (π² γ² R*/E*²)^(1/3)           at a_c = a0/6^(2/3), F = −(5/9) F_c

An approaching pair at δ < 0 feels nothing. The kernels carry a formed contact in the fourth column of
the pair (wall) history, which holds |δ_c| of the contact while it lasts and 0 otherwise; the pair filter
keeps a pair while δ > −hist[3] (``_pair_kernels``), so the neighbour list's skin must exceed |δ_c|
(the engine checks it).

a(δ) is the positive root of the quartic x⁴ − c₁ x − c₀ = 0 in x = sqrt(a), c₁ = R* sqrt(2πγ/E*),
c₀ = R* δ, in closed form (Ferrari's resolvent cubic m³ + c₀ m − c₁²/8 = 0, one real root by Cardano's
formula for every δ ≥ δ_c, where its discriminant vanishes), as Parteli et al. (2014, Sci. Rep. 4, 6227)
do for JKR in DEM. The root is written without differences of nearly equal numbers (m = (c₁²/8)/(s² +
t² + c₀/3) instead of s + t), so it keeps full precision from δ_c to δ ≫ |δ_c|.
"""
from __future__ import annotations

import math
from typing import ClassVar, Literal

import numpy as np
from numba import njit
from pydantic import Field

from .base import SLOT_EXTENDED, contact_models
from .hertz_mindlin import HertzMindlin

CODE = 5
SLOT_SURFACE_ENERGY = 6
TINY = 1e-300  # guards divisions whose result a select then drops


@contact_models.register("hertz_mindlin_jkr")
class HertzMindlinJKR(HertzMindlin):
    """Hertz–Mindlin with JKR adhesion of surface energy γ: contacts form at touch and break at pull-off."""

    model: Literal["hertz_mindlin_jkr"] = "hertz_mindlin_jkr"
    surface_energy: float = Field(
        ge=0.0, description="surface energy gamma [J/m^2] (work of adhesion) of the JKR law; 0: Hertz-Mindlin")

    code: ClassVar[int] = CODE
    adhesive: ClassVar[bool] = True
    reference_test: ClassVar[str] = "test_jkr_pull_off_force_and_zero_load_radius"
    # the cohesive powder of the 2012 DEM-book chapter (Wu & Guo): 1.09e-3 J/m²
    example: ClassVar[dict] = {"youngs_modulus": 1.0e8, "poisson_ratio": 0.3, "surface_energy": 1.09e-3}

    def pack(self, body_i, body_j) -> np.ndarray:
        row = super().pack(body_i, body_j)
        row[0] = CODE
        row[SLOT_SURFACE_ENERGY] = self.surface_energy
        row[SLOT_EXTENDED] = 1.0
        return row

    def pull_off_distance(self, r_eff, body_i=None, body_j=None) -> float:
        """|δ_c| = (3/4) (π² γ² R*/E*²)^(1/3) [m] (where da/dδ is infinite)."""
        e_star, _ = self._moduli(body_i, body_j)
        return 0.75 * (math.pi**2 * self.surface_energy**2 * r_eff / e_star**2) ** (1.0 / 3.0)


@njit(cache=True, error_model="numpy", inline="always")
def contact_radius(e_star, gamma, overlap, r_eff):
    """JKR contact radius a [m] at overlap δ ≥ δ_c: the root of δ = a²/R* − sqrt(2πγa/E*) (module docstring)."""
    c1 = r_eff * math.sqrt(2.0 * math.pi * gamma / e_star)
    c0 = r_eff * overlap
    h = c1 * c1 / 16.0  # −Q/2 of the resolvent cubic m³ + P m + Q, P = c0, Q = −c1²/8
    p3 = c0 / 3.0
    disc = max(h * h + p3 * p3 * p3, 0.0)  # Cardano's discriminant: 0 at δ_c, > 0 above (round-off clipped)
    s = (h + math.sqrt(disc)) ** (1.0 / 3.0)
    t = -p3 / max(s, TINY)  # the other cube root, s t = −P/3
    m = 2.0 * h / max(s * s + t * t + p3, TINY)  # s + t = (s³ + t³)/(s² − s t + t²)
    q = math.sqrt(2.0 * m)
    x = 0.5 * (q + math.sqrt(max(2.0 * c1 / max(q, TINY) - 2.0 * m, 0.0)))
    hertz = math.sqrt(r_eff * max(overlap, 0.0))
    return x * x if gamma > 0.0 else hertz


@njit(cache=True, error_model="numpy", inline="always")
def coefficients(p, overlap, m_eff, r_eff):
    """(elastic normal force [N], η_n [N s/m], k_t [N/m], η_t [N s/m]) of the JKR law above at overlap δ ≥ δ_c
    (negative in a formed contact that is being pulled apart)."""
    e_star = p[1]
    gamma = p[SLOT_SURFACE_ENERGY]
    a = contact_radius(e_star, gamma, overlap, r_eff)
    a3 = a * a * a
    fel = 4.0 * e_star * a3 / (3.0 * r_eff) - math.sqrt(8.0 * math.pi * gamma * e_star * a3)  # JKR 1971
    s = math.sqrt(m_eff * a)
    return fel, p[4] * s, 8.0 * p[2] * a, p[5] * s


@njit(cache=True, error_model="numpy", inline="always")
def pull_off(p, r_eff):
    """(F_c [N], |δ_c| [m]): the JKR pull-off force (3/2) π γ R* and separation (3/4) (π² γ² R*/E*²)^(1/3)."""
    gamma = p[SLOT_SURFACE_ENERGY]
    e_star = p[1]
    return 1.5 * math.pi * gamma * r_eff, 0.75 * (math.pi * math.pi * gamma * gamma * r_eff / (e_star * e_star)) ** (1.0 / 3.0)
