"""Which species of a fluidised binary mixture rises (flotsam) and which sinks (jetsam).

The criterion of Di Renzo & Di Maio, "Two-phase systems", in *Discrete Element Modelling of
Particulate Media* (RSC, 2012), §4, eqs 10-19: a force balance on one particle of species 2 in a
homogeneous mixture of the two species at the mixture's minimum fluidisation. The particle is pushed
up by the bed's pressure gradient (eq 16) and by the drag of the polydisperse law of van der Hoef et
al. (eq 12) at the mixture's minimum fluidisation velocity (eqs 13-14), and pulled down by its weight.
If the push exceeds the weight (eq 17's left side above 1), species 2 rises: it is the flotsam and
species 1 the jetsam. Everything here is arithmetic on a handful of scalars: no particles, no run, no
gas density (Archimedean buoyancy is neglected, as in the chapter).

Notation (SI): species ``i`` has diameter ``D_i`` [m] and density ``rho_i`` [kg/m³]; ``x_1`` is the
volume fraction of species 1 in the solids (``x_2 = 1 - x_1``); ``voidage`` is the bed voidage ε.
Dimensionless ratios: ``s = rho_2/rho_1`` and ``d = D_1/D_2`` (the axes of the chapter's Fig 1),
``s_bar = rho_2/rho_bar`` and ``d_bar = D_bar/D_2`` (the axes of its Fig 2).

The chapter's equation 19, the equilibrium line in the ``(d, s)`` plane at a given composition, lost
its printed form in the available text; ``equilibrium_density_ratio`` derives it from eqs 10, 15 and
18 (the derivation is in its docstring).
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from ..errors import CaseError

GRAVITY = 9.81  # [m/s²]
AIR_VISCOSITY = 1.8e-5  # [Pa s], air at 20 °C: the default gas for u_mf (the criterion does not use it)
MIXED_TOLERANCE = 1e-9  # |s/s_eq - 1| at or below which a system counts as on the equilibrium line
FIG1_VOIDAGE = 0.4  # the chapter's Fig 1 caption
CHART_COMPOSITIONS = (0.1, 0.3, 0.5, 0.7, 0.9)  # x_1 of the chart's lines (Fig 1 does not list its own)

__all__ = ["SegregationResult", "segregation_criterion", "sauter_mean_diameter", "mixture_density",
           "viscous_drag", "minimum_fluidisation_velocity", "equilibrium_mean_density_ratio",
           "equilibrium_density_ratio", "GRAVITY", "AIR_VISCOSITY", "MIXED_TOLERANCE", "FIG1_VOIDAGE",
           "CHART_COMPOSITIONS"]


# --- input checks: each error names the argument and its value -------------------------------------

def _number(name: str, value) -> float:
    if isinstance(value, (bool, np.bool_, str)):
        raise CaseError(f"{name} = {value!r}: give a number", [((name,), value, "not a number")])
    try:
        out = float(value)
    except (TypeError, ValueError):
        raise CaseError(f"{name} = {value!r}: give a number", [((name,), value, "not a number")]) from None
    if not math.isfinite(out):
        raise CaseError(f"{name} = {value!r}: give a finite number", [((name,), value, "not finite")])
    return out


def _positive(name: str, value, what: str) -> float:
    out = _number(name, value)
    if out <= 0.0:
        raise CaseError(f"{name} = {value!r}: {what} must be positive", [((name,), value, "not positive")])
    return out


def _check_voidage(value, name: str = "voidage") -> float:
    out = _number(name, value)
    if not 0.0 < out < 1.0:
        raise CaseError(f"{name} = {value!r}: the bed voidage ε must lie strictly between 0 and 1",
                        [((name,), value, "outside (0, 1)")])
    return out


def _check_composition(value, name: str = "composition") -> float:
    out = _number(name, value)
    if not 0.0 <= out <= 1.0:
        raise CaseError(f"{name} = {value!r}: the volume fraction x1 of species 1 in the solids must lie "
                        "in [0, 1]", [((name,), value, "outside [0, 1]")])
    return out


def _pair(name: str, values, what: str, unit: str) -> tuple[float, float]:
    if isinstance(values, (str, bytes)) or not hasattr(values, "__len__"):
        raise CaseError(f"{name} = {values!r}: give two {what}s [{unit}], of species 1 and species 2",
                        [((name,), values, "not a pair")])
    if len(values) != 2:
        raise CaseError(f"{name} = {tuple(values)!r}: give two {what}s [{unit}], of species 1 and species 2 "
                        f"(got {len(values)})", [((name,), values, "not two values")])
    symbol = "d" if what == "diameter" else "rho"
    return tuple(_positive(f"{symbol}{i + 1}", v, f"the {what} of species {i + 1} [{unit}]")
                 for i, v in enumerate(values))


# --- the chapter's equations -----------------------------------------------------------------------

def sauter_mean_diameter(diameters, composition) -> float:
    """Sauter mean diameter of the mixture, D_bar = (x_1/D_1 + x_2/D_2)^-1 [m] (Di Renzo & Di Maio 2012 eq. 10).

    Parameters
    ----------
    diameters : (D_1, D_2) [m], positive.
    composition : x_1, the volume fraction of species 1 in the solids, in [0, 1].
    """
    d1, d2 = _pair("diameters", diameters, "diameter", "m")
    x1 = _check_composition(composition)
    return 1.0 / (x1 / d1 + (1.0 - x1) / d2)


def mixture_density(densities, composition) -> float:
    """Volume-weighted solids density, rho_bar = rho_1 x_1 + rho_2 (1 - x_1) [kg/m³] (Di Renzo & Di Maio 2012 eq. 15)."""
    r1, r2 = _pair("densities", densities, "density", "kg/m³")
    x1 = _check_composition(composition)
    return r1 * x1 + r2 * (1.0 - x1)


def viscous_drag(voidage, viscosity, velocity, diameter) -> float:
    """Drag on one particle in the viscous regime, f_d = 30 (1-ε)/ε² π μ u D [N] (Di Renzo & Di Maio 2012 eq. 13).

    The force net of the pressure-gradient term; with eq. 6 it gives the Carman-Kozeny pressure drop
    180 (1-ε)² μ u / (ε³ D²). ``velocity`` is the superficial gas velocity u [m/s]. Valid for creeping
    flow through the bed (particle Reynolds number well below 1-10); not the Ergun inertial term.
    """
    eps = _check_voidage(voidage)
    mu = _positive("viscosity", viscosity, "the gas viscosity [Pa s]")
    d = _positive("diameter", diameter, "the particle diameter [m]")
    u = _number("velocity", velocity)
    return 30.0 * (1.0 - eps) / eps**2 * math.pi * mu * u * d


def minimum_fluidisation_velocity(diameter, density, voidage, viscosity=AIR_VISCOSITY, gravity=GRAVITY) -> float:
    """Minimum fluidisation velocity in the viscous regime [m/s] (Di Renzo & Di Maio 2012 eq. 14).

    u_mf = g ε³ rho D² / (180 (1-ε) μ): the superficial velocity at which the Carman-Kozeny pressure
    drop of eq. 13 carries the bed weight, eq. 16, with the gas density neglected. For a mixture, pass
    the Sauter mean diameter (eq. 10) and the mixture density (eq. 15). Valid while the particle
    Reynolds number at u_mf stays below about 1-10 (fine powders); larger particles need Ergun's
    inertial term, which the chapter's criterion leaves out.
    """
    d = _positive("diameter", diameter, "the particle diameter [m]")
    rho = _positive("density", density, "the particle density [kg/m³]")
    eps = _check_voidage(voidage)
    mu = _positive("viscosity", viscosity, "the gas viscosity [Pa s]")
    g = _positive("gravity", gravity, "the gravitational acceleration [m/s²]")
    return g * eps**3 * rho * d * d / (180.0 * (1.0 - eps) * mu)


def equilibrium_mean_density_ratio(mean_size_ratio, voidage):
    """The equilibrium line of the mean ratios, s_bar = 1 - ε + ε d_bar (Di Renzo & Di Maio 2012 eq. 18).

    ``mean_size_ratio`` is d_bar = D_bar/D_2 (a number or an array); returns s_bar = rho_2/rho_bar on
    the line. The line is the same for every composition (the chapter's Fig 2). A system with
    s_bar below it has species 2 as flotsam, above it as jetsam.
    """
    eps = _check_voidage(voidage)
    db = np.asarray(mean_size_ratio, dtype=float)
    if db.size and not (np.all(np.isfinite(db)) and np.all(db > 0.0)):
        raise CaseError(f"mean_size_ratio = {mean_size_ratio!r}: d_bar = D_bar/D_2 must be positive and finite")
    out = 1.0 - eps + eps * db
    return float(out) if out.ndim == 0 else out


def equilibrium_density_ratio(size_ratio, composition, voidage=FIG1_VOIDAGE):
    """The equilibrium line in the (d, s) plane at one composition (Di Renzo & Di Maio 2012 eq. 19, derived here).

    Returns s = rho_2/rho_1 on the line for d = D_1/D_2 (a number or an array):

        s = [(1-ε) x_1 + (1 - (1-ε) x_1) d] / [x_1 + (1-x_1) ε + (1-x_1)(1-ε) d]

    The printed form of the chapter's eq. 19 was lost from the available text; this is its content
    derived from eqs 10, 15 and 18. With s_bar = rho_2/rho_bar and rho_bar from eq. 15,
    s_bar = s / (x_1 + (1-x_1) s); with d_bar = D_bar/D_2 and D_bar from eq. 10,
    d_bar = d / (x_1 + (1-x_1) d). Eq. 18, s_bar = 1 - ε + ε d_bar =: A, is linear in s once
    multiplied out: s = A x_1 / (1 - (1-x_1) A), and putting A in terms of d gives the line above.

    Properties: every line passes through (d, s) = (1, 1) (equal size and density); at d -> 0 it
    reaches s = (1-ε) x_1 / (x_1 + (1-x_1) ε); s rises with d and with x_1. At x_1 = 1 it is
    s = 1 - ε + ε d and at x_1 = 0 it is s = d / (ε + (1-ε) d): in these limits the balance of the
    majority species is trivially 1, and the line is the balance of the trace species. A system above
    its line (s larger: species 2 relatively dense) has species 1 as flotsam; below it, species 2.
    The line is a Möbius (linear-fractional) curve in d, not a straight line.

    Parameters
    ----------
    size_ratio : d = D_1/D_2 [–], positive (a number or an array).
    composition : x_1 in [0, 1].
    voidage : ε in (0, 1); the chapter's Fig 1 uses 0.4.
    """
    x1 = _check_composition(composition)
    eps = _check_voidage(voidage)
    d = np.asarray(size_ratio, dtype=float)
    if d.size and not (np.all(np.isfinite(d)) and np.all(d > 0.0)):
        raise CaseError(f"size_ratio = {size_ratio!r}: d = D1/D2 must be positive and finite")
    x2 = 1.0 - x1
    out = ((1.0 - eps) * x1 + (1.0 - (1.0 - eps) * x1) * d) / (x1 + x2 * eps + x2 * (1.0 - eps) * d)
    return float(out) if out.ndim == 0 else out


# --- the criterion ---------------------------------------------------------------------------------

def _describe(i: int, d1: float, r1: float, d2: float, r2: float) -> str:
    """'the larger, lighter' and the like, for species ``i`` against the other one."""
    di, dj, ri, rj = (d1, d2, r1, r2) if i == 1 else (d2, d1, r2, r1)
    size = "same size" if di == dj else ("smaller" if di < dj else "larger")
    dens = "same density" if ri == rj else ("lighter" if ri < rj else "denser")
    return f"{size}, {dens}"


@dataclass(frozen=True)
class SegregationResult:
    """The criterion's verdict on one binary system, with the quantities it went through.

    ``flotsam`` is 1 or 2 (the species that rises to the bed surface) or ``"mixed"`` (on the
    equilibrium line within ``tolerance``); ``jetsam`` is the other one. Units are SI; the equation
    numbers are those of Di Renzo & Di Maio 2012. ``print(result)`` gives a table;
    ``result.as_dict()`` a JSON-ready dict.

    Attributes
    ----------
    diameters, densities : (D_1, D_2) [m], (rho_1, rho_2) [kg/m³], as given.
    composition : x_1, the volume fraction of species 1 in the solids [–].
    voidage : ε [–].
    mean_diameter : D_bar, Sauter mean (eq. 10) [m].
    polydispersity : (y_1, y_2) = D_i/D_bar (eq. 11) [–]; the drag on species i is y_i² times the mean (eq. 12).
    mean_density : rho_bar (eq. 15) [kg/m³].
    pressure_gradient : ∇p = rho_bar (1-ε) g, the fluidised mixture's (eq. 16) [Pa/m].
    minimum_fluidisation_velocity : u_mf of the mixture, eq. 14 with D_bar and rho_bar [m/s].
    species_minimum_fluidisation_velocity : (u_mf,1, u_mf,2), eq. 14 for each species alone [m/s].
    mean_drag : f_d_bar, eq. 13 at the mixture's u_mf with D_bar: (π/6) g ε rho_bar D_bar³ [N].
    pressure_force_2, drag_2, weight_2 : the terms of eq. 17 for one particle of species 2 [N]:
        V_2 rho_bar (1-ε) g; y_2² f_d_bar = (π/6) g ε rho_bar D_bar D_2²; V_2 rho_2 g.
    force_ratio : eq. 17's left side for species 2, (pressure_force_2 + drag_2) / weight_2:
        above 1 species 2 rises, below 1 it sinks.
    force_ratio_1 : the same balance written for a particle of species 1. In a mixture
        (0 < x_1 < 1), x_1 rho_1 (force_ratio_1 - 1) + x_2 rho_2 (force_ratio - 1) = 0: the mixture as a
        whole is carried, so one species rises exactly when the other sinks.
    size_ratio, density_ratio : d = D_1/D_2 and s = rho_2/rho_1 (Fig 1's axes).
    mean_size_ratio, mean_density_ratio : d_bar = D_bar/D_2 and s_bar = rho_2/rho_bar (Fig 2's axes).
    equilibrium_mean_density_ratio : 1 - ε + ε d_bar, the s_bar of eq. 18 at this d_bar.
    mean_density_gap : s_bar - (1 - ε + ε d_bar): negative when species 2 is flotsam (zero at x_1 = 0,
        where the balance of species 2 in its own bed is trivial).
    equilibrium_density_ratio : s_eq, the s of eq. 19 at this d and x_1.
    density_ratio_gap : s - s_eq: positive when species 1 is flotsam, negative when species 2 is.
    relative_gap : s/s_eq - 1, what ``tolerance`` is compared with.
    flotsam, jetsam : 1, 2 or "mixed".
    tolerance : the |relative_gap| at or below which the system counts as mixed.
    """

    diameters: tuple[float, float]
    densities: tuple[float, float]
    composition: float
    voidage: float
    viscosity: float
    gravity: float
    mean_diameter: float
    polydispersity: tuple[float, float]
    mean_density: float
    pressure_gradient: float
    minimum_fluidisation_velocity: float
    species_minimum_fluidisation_velocity: tuple[float, float]
    mean_drag: float
    pressure_force_2: float
    drag_2: float
    weight_2: float
    force_ratio: float
    force_ratio_1: float
    size_ratio: float
    density_ratio: float
    mean_size_ratio: float
    mean_density_ratio: float
    equilibrium_mean_density_ratio: float
    mean_density_gap: float
    equilibrium_density_ratio: float
    density_ratio_gap: float
    relative_gap: float
    flotsam: int | str
    jetsam: int | str
    tolerance: float

    def describe(self, species: int | str) -> str:
        """'species 2 (larger, lighter)', or 'neither: the mixture stays mixed' for ``"mixed"``."""
        if species == "mixed":
            return "neither: on the equilibrium line, the bed stays mixed"
        (d1, d2), (r1, r2) = self.diameters, self.densities
        return f"species {species} ({_describe(int(species), d1, r1, d2, r2)})"

    def as_dict(self) -> dict:
        """The fields as plain Python numbers, lists and strings (JSON-ready)."""
        out = asdict(self)
        for k, v in out.items():
            if isinstance(v, tuple):
                out[k] = list(v)
        return out

    def table(self) -> str:
        """A readable table: inputs, intermediate quantities with their equation numbers, the verdict."""
        (d1, d2), (r1, r2) = self.diameters, self.densities
        rows = [
            ("diameter of species 1", "D1", d1, "m", ""),
            ("diameter of species 2", "D2", d2, "m", ""),
            ("density of species 1", "rho1", r1, "kg/m³", ""),
            ("density of species 2", "rho2", r2, "kg/m³", ""),
            ("volume fraction of species 1", "x1", self.composition, "–", ""),
            ("bed voidage", "eps", self.voidage, "–", ""),
            ("Sauter mean diameter", "D_bar", self.mean_diameter, "m", "10"),
            ("polydispersity index, species 1", "y1", self.polydispersity[0], "–", "11"),
            ("polydispersity index, species 2", "y2", self.polydispersity[1], "–", "11"),
            ("mixture density", "rho_bar", self.mean_density, "kg/m³", "15"),
            ("pressure gradient, fluidised", "grad p", self.pressure_gradient, "Pa/m", "16"),
            (f"u_mf of the mixture (mu = {self.viscosity:.3g} Pa s)", "u_mf", self.minimum_fluidisation_velocity,
             "m/s", "14"),
            ("u_mf of species 1 alone", "u_mf1", self.species_minimum_fluidisation_velocity[0], "m/s", "14"),
            ("u_mf of species 2 alone", "u_mf2", self.species_minimum_fluidisation_velocity[1], "m/s", "14"),
            ("pressure force on a particle 2", "F_p2", self.pressure_force_2, "N", "17"),
            ("drag on a particle 2 at u_mf", "F_d2", self.drag_2, "N", "12-14"),
            ("weight of a particle 2", "W2", self.weight_2, "N", "17"),
            ("force ratio, species 2 (>1 rises)", "R2", self.force_ratio, "–", "17"),
            ("force ratio, species 1 (>1 rises)", "R1", self.force_ratio_1, "–", "17"),
            ("size ratio D1/D2", "d", self.size_ratio, "–", "19"),
            ("density ratio rho2/rho1", "s", self.density_ratio, "–", "19"),
            ("s on the equilibrium line", "s_eq", self.equilibrium_density_ratio, "–", "19"),
            ("gap s - s_eq (>0: 1 rises)", "", self.density_ratio_gap, "–", "19"),
            ("mean size ratio D_bar/D2", "d_bar", self.mean_size_ratio, "–", "18"),
            ("mean density ratio rho2/rho_bar", "s_bar", self.mean_density_ratio, "–", "18"),
            ("s_bar on the line, 1-eps+eps d_bar", "", self.equilibrium_mean_density_ratio, "–", "18"),
        ]
        w = max(len(r[0]) for r in rows)
        lines = [f"{'quantity':<{w}}  {'symbol':<8} {'value':>12}  {'unit':<6} eq"]
        for name, sym, value, unit, eq in rows:
            lines.append(f"{name:<{w}}  {sym:<8} {value:>12.6g}  {unit:<6} {eq}")
        lines.append(f"flotsam (rises): {self.describe(self.flotsam)}")
        if self.flotsam != "mixed":
            lines.append(f"jetsam (sinks):  {self.describe(self.jetsam)}")
        return "\n".join(lines)

    def __str__(self) -> str:
        return self.table()


def segregation_criterion(diameters, densities, composition, voidage=FIG1_VOIDAGE, *, viscosity=AIR_VISCOSITY,
                          gravity=GRAVITY, tolerance=MIXED_TOLERANCE) -> SegregationResult:
    """Flotsam or jetsam: the Di Renzo-Di Maio criterion for a fluidised binary mixture (Di Renzo & Di Maio 2012 eqs 10-19).

    A particle of species 2 in the homogeneous mixture at its minimum fluidisation feels the bed's
    pressure gradient (eq. 16) over its volume and the drag of eq. 12, y_2² times the mean drag of
    eq. 13 at the mixture's u_mf (eq. 14 with D_bar, rho_bar); eq. 17 compares them with its weight:

        [V_2 rho_bar (1-ε) g + (π/6) g ε rho_bar D_bar D_2²] / (V_2 rho_2 g) = 1          (17)

    which, with s_bar = rho_2/rho_bar and d_bar = D_bar/D_2, is s_bar = 1 - ε + ε d_bar (eq. 18).
    The verdict uses the same balance written as eq. 19 (``equilibrium_density_ratio``): species 1
    is flotsam when s = rho_2/rho_1 lies above the line s_eq(d, x_1) at d = D_1/D_2, species 2 when
    it lies below; within ``tolerance`` (relative) of the line the mixture stays mixed. For
    0 < x_1 < 1 this is exactly eq. 17's left side above or below 1; eq. 19's form also decides the
    limits x_1 = 0 and 1, where the balance of the majority species is trivially 1 and the trace
    species decides.

    The drag and u_mf are those of the viscous regime (eqs 13-14) and the gas density is neglected; the
    verdict does not depend on the viscosity or on g, which only scale the reported u_mf and forces.
    The species may be given in either order: the chapter takes species 1 as the smaller, but the
    equations hold for any labels.

    Parameters
    ----------
    diameters : (D_1, D_2) [m], positive and finite.
    densities : (rho_1, rho_2) [kg/m³], positive and finite.
    composition : x_1, the volume fraction of species 1 in the solids, in [0, 1].
    voidage : ε, strictly between 0 and 1 (default 0.4, the chapter's Fig 1).
    viscosity : gas viscosity μ [Pa s] for the reported u_mf (default 1.8e-5, air at 20 °C).
    gravity : g [m/s²] for the reported forces and u_mf (default 9.81).
    tolerance : |s/s_eq - 1| at or below which the system counts as mixed (default 1e-9: round-off,
        not a physical mixing band; widen it to call near-equilibrium systems mixed).

    Returns
    -------
    SegregationResult

    Raises
    ------
    CaseError
        An argument missing a species, not positive, not finite, or outside its range; the message
        names the argument and its value.

    Examples
    --------
    >>> r = segregation_criterion((0.3e-3, 0.6e-3), (2600.0, 1200.0), composition=0.25, voidage=0.4)
    >>> r.flotsam, round(r.force_ratio, 6)
    (2, 1.188333)
    """
    d1, d2 = _pair("diameters", diameters, "diameter", "m")
    r1, r2 = _pair("densities", densities, "density", "kg/m³")
    x1 = _check_composition(composition)
    eps = _check_voidage(voidage)
    mu = _positive("viscosity", viscosity, "the gas viscosity [Pa s]")
    g = _positive("gravity", gravity, "the gravitational acceleration [m/s²]")
    tol = _number("tolerance", tolerance)
    if tol < 0.0:
        raise CaseError(f"tolerance = {tolerance!r}: must be zero or positive", [(("tolerance",), tolerance, "< 0")])
    x2 = 1.0 - x1

    mean_d = 1.0 / (x1 / d1 + x2 / d2)                                   # eq. 10
    y1, y2 = d1 / mean_d, d2 / mean_d                                    # eq. 11
    mean_rho = r1 * x1 + r2 * x2                                         # eq. 15
    grad_p = mean_rho * (1.0 - eps) * g                                  # eq. 16
    u_mf = minimum_fluidisation_velocity(mean_d, mean_rho, eps, mu, g)   # eq. 14, mixture
    u_mf1 = minimum_fluidisation_velocity(d1, r1, eps, mu, g)
    u_mf2 = minimum_fluidisation_velocity(d2, r2, eps, mu, g)
    mean_drag = 30.0 * (1.0 - eps) / eps**2 * math.pi * mu * u_mf * mean_d  # eq. 13 at u_mf
    v2 = math.pi / 6.0 * d2**3
    pressure_force_2 = v2 * grad_p                                       # eq. 17, first term
    drag_2 = y2 * y2 * mean_drag                                         # eq. 12
    weight_2 = v2 * r2 * g
    # the ratios of eq. 17 in closed form ((π/6) and g cancel): (rho_bar/rho_i) (1 - ε + ε D_bar/D_i)
    force_ratio = mean_rho / r2 * (1.0 - eps + eps * mean_d / d2)
    force_ratio_1 = mean_rho / r1 * (1.0 - eps + eps * mean_d / d1)

    d, s = d1 / d2, r2 / r1
    d_bar, s_bar = mean_d / d2, r2 / mean_rho
    s_bar_eq = 1.0 - eps + eps * d_bar                                   # eq. 18
    s_eq = equilibrium_density_ratio(d, x1, eps)                         # eq. 19
    relative_gap = s / s_eq - 1.0
    if abs(relative_gap) <= tol:
        flotsam, jetsam = "mixed", "mixed"
    elif relative_gap > 0.0:
        flotsam, jetsam = 1, 2
    else:
        flotsam, jetsam = 2, 1
    return SegregationResult(
        diameters=(d1, d2), densities=(r1, r2), composition=x1, voidage=eps, viscosity=mu, gravity=g,
        mean_diameter=mean_d, polydispersity=(y1, y2), mean_density=mean_rho, pressure_gradient=grad_p,
        minimum_fluidisation_velocity=u_mf, species_minimum_fluidisation_velocity=(u_mf1, u_mf2),
        mean_drag=mean_drag, pressure_force_2=pressure_force_2, drag_2=drag_2, weight_2=weight_2,
        force_ratio=force_ratio, force_ratio_1=force_ratio_1, size_ratio=d, density_ratio=s,
        mean_size_ratio=d_bar, mean_density_ratio=s_bar, equilibrium_mean_density_ratio=s_bar_eq,
        mean_density_gap=s_bar - s_bar_eq, equilibrium_density_ratio=s_eq, density_ratio_gap=s - s_eq,
        relative_gap=relative_gap, flotsam=flotsam, jetsam=jetsam, tolerance=tol)
