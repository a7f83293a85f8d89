"""Compiled dispatch over drag laws, written from the ``drag_laws`` registry.

A law is packed into a float64 row (``DragLaw.pack``): slot 0 its integer ``CODE``, then its parameters
in the order its model declares them. ``monodisperse`` calls the ``beta_per_solids(p, eps, slip, d,
rho, mu)`` kernel of the module that registered the law of code ``p[0]``
(``registry.compiled_switch``); nothing here names a law. All return β/(1 − ε) [kg m^-3 s^-1]; multiply
by (1 − ε) for β per bed volume.

``beta_per_solids`` adds the polydisperse rule of van der Hoef et al. (DEM book 2012 two-phase chapter,
eqs 10-12) for every law: in a mixture of Sauter mean diameter D̄ = (Σ x_i/D_i)^−1 (eq. 10), a particle
of diameter D_i has y_i = D_i/D̄ (eq. 11) and feels f_di = y_i² f̄_d (eq. 12), f̄_d the drag of the law
on a particle of diameter D̄ (Reynolds number with D̄) at the same ε and slip. Per unit solids volume:
β_i/(1 − ε) = f_di/(V_i |u − v|) = y_i² f̄_d/(y_i³ V̄ |u − v|) = β̄/((1 − ε) y_i). With y = 1 it is the
law itself, bit for bit (d/1 and b/1 are exact). Summed over a mixture, Σ_i x_i f_di/D_i³ = f̄_d/D̄³:
the bed's pressure drop is that of the law at D̄ (eqs 7-8).
"""
import sys

from numba import njit

from ...registry import compiled_switch
from .base import drag_laws


def _laws() -> dict:
    """{CODE: beta_per_solids kernel} of every registered drag law."""
    laws = {}
    for name in drag_laws.names():
        cls = drag_laws.get(name)
        kernel = getattr(sys.modules[cls.__module__], "beta_per_solids", None)  # (p, eps, slip, d, rho, mu)
        if kernel is None:
            raise TypeError(f"drag law {name!r}: its module {cls.__module__} defines no beta_per_solids() kernel")
        if cls.code in laws:
            raise ValueError(f"drag law {name!r}: code {cls.code} is taken by another law")
        laws[cls.code] = kernel
    return laws


# β/(1−ε) [kg m^-3 s^-1] of the law packed in p for a monodisperse bed of diameter d; 0 for an unknown code
monodisperse = compiled_switch("monodisperse", _laws(), ("p", "eps", "slip", "d", "rho", "mu"),
                               "int(p[0])", "0.0", __name__, __file__, error_model="numpy")


@njit(cache=True, error_model="numpy", inline="always")
def beta_per_solids(p, eps, slip, d, rho, mu, y):
    """β_i/(1−ε) [kg m^-3 s^-1] of a particle of diameter d = y D̄ in a mixture of Sauter mean D̄
    (DEM book 2012 eq. 12 through eq. 11: the law at D̄ = d/y, divided by y); y = 1: the law itself."""
    return monodisperse(p, eps, slip, d / y, rho, mu) / y


@njit(cache=True, error_model="numpy")
def beta(p, eps, slip, d, rho, mu, y):
    """β [kg m^-3 s^-1] per unit bed volume of the law packed in p."""
    return (1.0 - eps) * beta_per_solids(p, eps, slip, d, rho, mu, y)


@njit(cache=True, error_model="numpy")
def beta_array(p, per_bed, eps, slip, d, rho, mu, y, out):
    """out[k] = β (per_bed) or β/(1−ε) at each k; all arrays (n,) float64."""
    for k in range(eps.size):
        b = beta_per_solids(p, eps[k], slip[k], d[k], rho[k], mu[k], y[k])
        out[k] = (1.0 - eps[k]) * b if per_bed else b
