"""Hertz normal contact with Mindlin tangential stiffness, viscous damping and a Coulomb limit.

Normal      F_n = (4/3) E* sqrt(R*) δ^(3/2) − η_n v_n,  η_n = A sqrt(m* k_h) δ^(1/4),  k_h = (4/3) E* sqrt(R*)
Tangential  k_t = 8 G* sqrt(R* δ) (Mindlin), F_t = −k_t u_t − η_t v_t, η_t = A sqrt(m* k_t / 1.5), |F_t| ≤ μ|F_n|

with 1/E* = (1−ν_i²)/E_i + (1−ν_j²)/E_j and 1/G* = 2(2−ν_i)(1+ν_i)/E_i + 2(2−ν_j)(1+ν_j)/E_j.
This is the Hertz–Mindlin law of the 2012 DEM-book chapter (Wu & Guo) in the form
LIGGGHTS and EDEM use (their 2 sqrt(5/6) β equals our A/sqrt(5)).

The damping constant A is not taken from an approximate formula: with the scaling
δ = L y, t = T s the normal equation becomes y'' = −y^(3/2) − A y^(1/4) y', whose
restitution depends on A alone. We integrate it once (SciPy) and solve e(A) = e_n
exactly, so the requested restitution is met at every impact speed.
Valid for small overlaps δ ≪ R*; not an adhesive law (that is ``hertz_mindlin_jkr``).
"""
from __future__ import annotations

import math
from functools import lru_cache
from typing import ClassVar, Literal

import numpy as np
from numba import njit
from pydantic import Field

from .base import SoftContactModel, contact_models, empty_row

CODE = 2


@lru_cache(maxsize=256)
def _scaled_collision(damping: float) -> tuple[float, float]:
    """(restitution, duration) of y'' = −y^1.5 − A y^0.25 y', y(0)=0, y'(0)=1 in scaled units."""
    from scipy.integrate import solve_ivp

    def rhs(t, s):
        y, v = s
        yp = max(y, 0.0)
        return [v, -(yp**1.5) - damping * yp**0.25 * v]

    def leave(t, s):
        return s[0]

    leave.terminal = True
    leave.direction = -1
    sol = solve_ivp(rhs, (0.0, 100.0), [0.0, 1.0], events=leave, rtol=1e-11, atol=1e-13, first_step=1e-6,
                    max_step=0.01)
    if sol.t_events[0].size == 0:
        return 0.0, math.inf
    return -float(sol.y_events[0][0][1]), float(sol.t_events[0][0])


@lru_cache(maxsize=256)
def damping_constant(restitution: float) -> float:
    """A such that the Hertz law above rebounds with the given restitution (exact, by root finding)."""
    if restitution >= 1.0:
        return 0.0
    from scipy.optimize import brentq

    hi = 1.0
    while _scaled_collision(hi)[0] > restitution:
        hi *= 2.0
        if hi > 1e4:
            raise ValueError(f"restitution {restitution} is too small for the Hertz damping law")
    return brentq(lambda a: _scaled_collision(a)[0] - restitution, 0.0, hi, xtol=1e-12)


def effective_moduli(e_i, nu_i, e_j, nu_j):
    """(E*, G*) of a contact of two bodies (j may be a rigid wall of its own E, ν)."""
    e_star = 1.0 / ((1 - nu_i**2) / e_i + (1 - nu_j**2) / e_j)
    g_star = 1.0 / (2 * (2 - nu_i) * (1 + nu_i) / e_i + 2 * (2 - nu_j) * (1 + nu_j) / e_j)
    return e_star, g_star


def contact_time_hertz(m_eff, r_eff, e_star, impact_velocity, restitution=1.0) -> float:
    """Duration of a head-on Hertz impact [s]; for e = 1 it is 2.868 (m*²/(R* E*² v))^(1/5)."""
    k_h = 4.0 / 3.0 * e_star * math.sqrt(r_eff)
    # scales: L^(5/2) = m v² / k_h... from y'' = −y^1.5 with y'(0)=1: L = (m v²/k_h)^(2/5), T = L / v
    length = (m_eff * impact_velocity**2 / k_h) ** 0.4
    return _scaled_collision(damping_constant(restitution))[1] * length / impact_velocity


@contact_models.register("hertz_mindlin")
class HertzMindlin(SoftContactModel):
    """Hertz normal + Mindlin tangential stiffness with restitution-calibrated damping and Coulomb friction."""

    model: Literal["hertz_mindlin"] = "hertz_mindlin"
    youngs_modulus: float = Field(gt=0.0, description="Young's modulus E [Pa] of bodies that give none of their own")
    poisson_ratio: float = Field(0.3, gt=-1.0, lt=0.5, description="Poisson ratio nu [-] of bodies that give none")

    code: ClassVar[int] = CODE
    reference_test: ClassVar[str] = "test_particle_particle_collision"  # restitution, Hertz impact time
    example: ClassVar[dict] = {"youngs_modulus": 1.0e8, "poisson_ratio": 0.3}

    def _moduli(self, body_i, body_j):
        def mat(b):
            e = getattr(b, "youngs_modulus", None) if b is not None else None
            nu = getattr(b, "poisson_ratio", None) if b is not None else None
            return (e if e is not None else self.youngs_modulus, nu if nu is not None else self.poisson_ratio)

        ei, nui = mat(body_i)
        ej, nuj = mat(body_j)
        return effective_moduli(ei, nui, ej, nuj)

    def pack(self, body_i, body_j) -> np.ndarray:
        row = empty_row(CODE, self.friction)
        e_star, g_star = self._moduli(body_i, body_j)
        a = damping_constant(self.restitution)
        row[1], row[2], row[3] = e_star, g_star, a
        # precomputed damping factors: η_n = A sqrt(4/3 E*) sqrt(m* a), η_t = A sqrt(16/3 G*) sqrt(m* a), a = sqrt(R* δ)
        row[4] = a * math.sqrt(4.0 / 3.0 * e_star)
        row[5] = a * math.sqrt(16.0 / 3.0 * g_star)
        return self.pack_rolling(row)

    def contact_time(self, m_eff, r_eff, impact_velocity, body_i=None, body_j=None) -> float:
        e_star, _ = self._moduli(body_i, body_j)
        return contact_time_hertz(m_eff, r_eff, e_star, impact_velocity, self.restitution)


@njit(cache=True, error_model="numpy", inline="always")
def coefficients(p, overlap, m_eff, r_eff):
    """(elastic normal force [N], η_n [N s/m], k_t [N/m], η_t [N s/m]) of the Hertz–Mindlin law above.

    With a = sqrt(R* δ): F_el = (4/3) E* a δ, k_t = 8 G* a, η_n = A sqrt((4/3) E* m* a),
    η_t = A sqrt((16/3) G* m* a), i.e. the formulas of the module docstring with two square roots.
    """
    a = math.sqrt(r_eff * overlap)
    s = math.sqrt(m_eff * a)
    return 4.0 / 3.0 * p[1] * a * overlap, p[4] * s, 8.0 * p[2] * a, p[5] * s
