"""Compiled dispatch over drag laws by integer code (one branch per closure).

Codes: 1 hoomans1996, 2 gidaspow, 3 di_felice, 4 beetstra, 5 koch_hill, 6 hoomans1996_total
(each file's ``CODE``).
All return β/(1 − ε) [kg m^-3 s^-1]; multiply by (1 − ε) for β per bed volume.
"""
from numba import njit

from . import beetstra, di_felice, gidaspow, hoomans1996, hoomans1996_total, koch_hill


@njit(cache=True, error_model="numpy")
def beta_per_solids(code, eps, slip, d, rho, mu, y):
    """β/(1−ε) [kg m^-3 s^-1] of closure ``code``; 0 for an unknown code."""
    if code == hoomans1996.CODE:
        return hoomans1996.beta_per_solids(eps, slip, d, rho, mu, y)
    if code == gidaspow.CODE:
        return gidaspow.beta_per_solids(eps, slip, d, rho, mu, y)
    if code == di_felice.CODE:
        return di_felice.beta_per_solids(eps, slip, d, rho, mu, y)
    if code == beetstra.CODE:
        return beetstra.beta_per_solids(eps, slip, d, rho, mu, y)
    if code == koch_hill.CODE:
        return koch_hill.beta_per_solids(eps, slip, d, rho, mu, y)
    if code == hoomans1996_total.CODE:
        return hoomans1996_total.beta_per_solids(eps, slip, d, rho, mu, y)
    return 0.0


@njit(cache=True, error_model="numpy")
def beta(code, eps, slip, d, rho, mu, y):
    """β [kg m^-3 s^-1] per unit bed volume of closure ``code``."""
    return (1.0 - eps) * beta_per_solids(code, eps, slip, d, rho, mu, y)


@njit(cache=True, error_model="numpy")
def beta_array(code, per_bed, eps, slip, d, rho, mu, y, out):
    """out[k] = β (per_bed) or β/(1−ε) at each k; all arrays (n,) float64."""
    for k in range(eps.size):
        b = beta_per_solids(code, eps[k], slip[k], d[k], rho[k], mu[k], y[k])
        out[k] = (1.0 - eps[k]) * b if per_bed else b
