"""Base class of drag laws, their registry, and the conventions every closure follows.

Every closure gives the interphase momentum-transfer coefficient β [kg m^-3 s^-1]
*per unit bed volume*, the β of the gas momentum equation −β(u − v) (Hoomans 1996
eq. 43, Sun 2007 eqs 30 and 33). The drag force on one particle of volume V_p is then

    F = β V_p / (1 − ε) (u − v)                     (Sun 2007 eqs 28-29: ε f_d = β V_p/ε_s (u − v))

which is the drag *without* the −V_p ∇p term; in a homogeneous bed that term adds
F (1 − ε)/ε, so the total gas force is F/ε = β V_p/(ε(1 − ε)) (u − v), the form of Hoomans
1996 eq. 35 (whose F_d is the total force because his eq. 34 has no pressure-gradient term).
Hoomans' own particle force is not that of his gas-side β (eqs 45-47, ``hoomans1996``) but
Wen & Yu's C_d ε^-4.7 at every voidage: ``hoomans1996_total`` (``total_force = True``, its
gas side named by ``gas_code``), used without −V_p ∇p and with the "cell_beta" exchange.

Because β ∝ (1 − ε) in every closure, the kernels compute β/(1 − ε) [kg m^-3 s^-1 per
unit solids volume] and the force coefficient β V_p/(1 − ε) stays finite for a lone
particle (ε = 1). ``slip_speed`` is |u − v| with u the interstitial gas velocity;
the particle Reynolds number is Re = ε ρ_g |u − v| d / μ_g (Hoomans eq. 39/47, Sun eq. 31).
"""
from __future__ import annotations

import math
from typing import ClassVar

import numpy as np
from pydantic import BaseModel, ConfigDict

from ...registry import Registry

drag_laws: Registry[type["DragLaw"]] = Registry("drag law")


class DragLaw(BaseModel):
    """A drag closure chosen by name (its ``model`` key); subclasses set ``code`` (see ``_dispatch.py``).

    A law's parameters are its other fields, numbers all; ``pack`` lays them out after the code in the
    order they are declared, and the law's ``beta_per_solids(p, ...)`` kernel reads them from ``p[1:]``.
    """

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True)

    code: ClassVar[int] = 0
    stokes_limit: ClassVar[bool] = True  # β V_p/(1-ε) -> 3π μ d as ε -> 1, Re -> 0
    # The β the gas takes from a cell's voidage and mean solids velocity ("cell", "cell_beta" exchanges):
    # None = this law's own; a law whose particle force differs from its gas-side β names the gas code.
    gas_code: ClassVar[int | None] = None
    # True: the particle force is the total gas force (pressure part included, Hoomans 1996 eq. 34-35),
    # to be used without −V_p ∇p and with the "cell_beta" exchange (coupling/schema.py checks it)
    total_force: ClassVar[bool] = False
    # the test that checks this law against its published formula or data (a function name under tests/)
    reference_test: ClassVar[str] = ""

    @classmethod
    def cell_code(cls) -> int:
        """Code of the β the gas takes per cell (``gas_code``, else ``code``)."""
        return cls.code if cls.gas_code is None else cls.gas_code

    def gas_side(self) -> "DragLaw":
        """The law whose β the gas takes per cell: this one, or the registered law of ``gas_code``."""
        code = self.cell_code()
        if code == self.code:
            return self
        return next(drag_laws.get(n)() for n in drag_laws.names() if drag_laws.get(n).code == code)

    def pack(self) -> np.ndarray:
        """The float64 row the kernels read: [code, parameters in declaration order]."""
        params = [getattr(self, f) for f in type(self).model_fields if f != "model"]
        return np.array([float(self.code), *(float(v) for v in params)])

    def beta(self, voidage, slip_speed, diameter, gas_density, gas_viscosity, y_ratio=1.0) -> np.ndarray:
        """β [kg m^-3 s^-1] per unit bed volume of the particle force; arguments broadcast against each other.

        voidage ε [-] in (0, 1], slip_speed |u − v| [m/s], diameter d [m],
        gas_density ρ_g [kg/m^3], gas_viscosity μ_g [Pa s], y_ratio d_i/D̄ [-]
        (polydisperse index, DEM book 2012 eq. 11: the force is y² times the law's at D̄, eq. 12;
        1 for a monodisperse bed).
        """
        return _evaluate(self.pack(), True, voidage, slip_speed, diameter, gas_density, gas_viscosity, y_ratio)

    def beta_per_solids(self, voidage, slip_speed, diameter, gas_density, gas_viscosity,
                        y_ratio=1.0) -> np.ndarray:
        """β/(1 − ε) [kg m^-3 s^-1]: finite at ε = 1."""
        return _evaluate(self.pack(), False, voidage, slip_speed, diameter, gas_density, gas_viscosity, y_ratio)

    def force_coefficient(self, voidage, slip_speed, diameter, gas_density, gas_viscosity,
                          y_ratio=1.0) -> np.ndarray:
        """β V_p/(1 − ε) [kg/s]: the drag on one particle is this times (u − v) [N]."""
        d = np.asarray(diameter, float)
        return self.beta_per_solids(voidage, slip_speed, d, gas_density, gas_viscosity, y_ratio) * (
            math.pi / 6.0 * d**3)

    def particle_force(self, voidage, gas_velocity, particle_velocity, diameter, gas_density, gas_viscosity,
                       y_ratio=1.0) -> np.ndarray:
        """Drag force on each particle [N], (N, 3): β V_p/(1 − ε) (u − v) (Sun 2007 eqs 28-29).

        gas_velocity, particle_velocity : (N, 3) [m/s]; the scalars are (N,) or broadcastable.
        Excludes −V_p ∇p (add it separately, Sun 2007 eq. 28).
        """
        w = np.asarray(gas_velocity, float) - np.asarray(particle_velocity, float)
        slip = np.sqrt(np.einsum("...k,...k->...", w, w))
        c = self.force_coefficient(voidage, slip, diameter, gas_density, gas_viscosity, y_ratio)
        return np.asarray(c)[..., None] * w


def _evaluate(law, per_bed, voidage, slip_speed, diameter, gas_density, gas_viscosity, y_ratio):
    from . import _dispatch

    args = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in
                                 (voidage, slip_speed, diameter, gas_density, gas_viscosity, y_ratio)))
    shape = args[0].shape
    flat = [np.array(a, dtype=float, order="C").ravel() for a in args]  # owned, writeable copies
    eps = flat[0]
    if np.any(~(eps > 0.0) | ~(eps <= 1.0)):
        raise ValueError(f"voidage must lie in (0, 1]; got values from {eps.min()!r} to {eps.max()!r}")
    if np.any(flat[1] < 0.0) or np.any(flat[2] <= 0.0) or np.any(flat[3] <= 0.0) or np.any(flat[4] <= 0.0) \
            or np.any(flat[5] <= 0.0):
        raise ValueError("slip_speed must be >= 0 and diameter, gas_density, gas_viscosity, y_ratio > 0")
    out = np.empty(eps.size)
    _dispatch.beta_array(law, per_bed, *flat, out)
    return out.reshape(shape) if shape else float(out[0])
