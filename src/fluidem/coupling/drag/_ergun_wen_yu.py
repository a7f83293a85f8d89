"""Compiled Ergun (1952) and Wen & Yu (1966) pieces shared by ``hoomans1996`` and ``gidaspow``.

Both return β/(1 − ε) [kg m^-3 s^-1] (see ``base.py``); kernels only.
"""

from numba import njit


@njit(cache=True, error_model="numpy", inline="always")
def ergun_per_solids(eps, slip, d, rho, mu):
    """β/(1−ε) of Ergun: 150 (1−ε) μ/(ε d²) + 1.75 ρ |u−v|/d (Hoomans 1996 eq. 45, Sun 2007 eq. 30)."""
    return 150.0 * (1.0 - eps) * mu / (eps * d * d) + 1.75 * rho * slip / d


@njit(cache=True, error_model="numpy", inline="always")
def wen_yu_per_solids(eps, slip, d, rho, mu, exponent, cd_inertial):
    """β/(1−ε) of Wen–Yu: 3/4 C_D ε ρ |u−v|/d ε^(−exponent) (Hoomans eq. 46, Sun eq. 30).

    C_D = 24/Re (1 + 0.15 Re^0.687) for Re < 1000, ``cd_inertial`` above (Hoomans eq. 38, Sun eq. 31),
    Re = ε ρ |u−v| d/μ (Hoomans eq. 47). C_D |u−v| is formed without dividing by Re so
    that slip = 0 gives the Stokes value.
    """
    re = eps * rho * slip * d / mu
    if re < 1000.0:
        cd_slip = 24.0 * mu / (eps * rho * d) * (1.0 + 0.15 * re**0.687)
    else:
        cd_slip = cd_inertial * slip
    return 0.75 * cd_slip * eps * rho / d * eps ** (-exponent)
