"""Compiled dispatch over drag laws, written from the ``drag_laws`` registry.

A law is packed into a float64 row (``DragLaw.pack``): slot 0 its integer ``CODE``, then its parameters
in the order its model declares them. ``beta_per_solids`` calls the ``beta_per_solids(p, eps, slip, d,
rho, mu, y)`` kernel of the module that registered the law of code ``p[0]``
(``registry.compiled_switch``); nothing here names a law. All return β/(1 − ε) [kg m^-3 s^-1]; multiply
by (1 − ε) for β per bed volume.
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
        kernel = getattr(sys.modules[cls.__module__], "beta_per_solids", None)
        if kernel is None:
            raise TypeError(f"drag law {name!r}: its module {cls.__module__} defines no beta_per_solids() kernel")
        if cls.code in laws:
            raise ValueError(f"drag law {name!r}: code {cls.code} is taken by another law")
        laws[cls.code] = kernel
    return laws


# β/(1−ε) [kg m^-3 s^-1] of the law packed in p; 0 for an unknown code
beta_per_solids = compiled_switch("beta_per_solids", _laws(), ("p", "eps", "slip", "d", "rho", "mu", "y"),
                                  "int(p[0])", "0.0", __name__, __file__, error_model="numpy")


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
