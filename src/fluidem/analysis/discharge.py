"""Discharge of a hopper or silo: the steady mass flow rate through its orifice, the bulk density of its bed,
and Beverloo's correlation to compare them with.

``steady_rate(time, mass)`` fits the discharged mass (an outlet's running ``outlet_<name>_mass_kg`` column of
probes.csv) against time by least squares over the middle of the discharge (by default while between 20 % and
60 % of the final mass has left: after the start-up, before the bed runs low), its slope the steady rate.
``beverloo_rate`` is W = C ρ_b √g (D₀ − k d)^{5/2} (Beverloo, Leniger & van de Velde 1961, Chem. Eng. Sci. 15,
260), with C = 0.58 and k = 1.5 by default, the values Nedderman (1992, Statics and Kinematics of Granular
Materials, ch. 10) gives as typical (C within 0.55–0.65, k within 1.3–1.5 over published data).
``bulk_density`` is the mass of the particles whose centres lie in a vertical cylinder of the bed (between two
heights, within a radius of the axis) over its volume, which is unbiased for a bed uniform across the region.

Orchestration only (NumPy on arrays, no loop over particles).
"""
from __future__ import annotations

import math

import numpy as np

BEVERLOO_C = 0.58  # discharge coefficient C [-] (Nedderman 1992 ch. 10: 0.55-0.65)
BEVERLOO_K = 1.5  # empty-annulus coefficient k [-] (Nedderman 1992 ch. 10: 1.3-1.5)


def beverloo_rate(bulk_density: float, orifice_diameter: float, particle_diameter: float, g: float = 9.81,
                  c: float = BEVERLOO_C, k: float = BEVERLOO_K) -> float:
    """Mass flow rate [kg/s] through a circular orifice, W = C ρ_b √g (D₀ − k d)^{5/2} (Beverloo et al. 1961).

    bulk_density ρ_b [kg/m^3], orifice_diameter D₀ [m], particle_diameter d [m], g [m/s^2]. Valid for
    D₀ > ~6 d (no arching) in a flat-bottomed bin or a hopper whose walls are too shallow for mass flow, where
    the rate does not depend on the bed height above a fill of about one bin diameter."""
    free = orifice_diameter - k * particle_diameter
    if free <= 0.0:
        raise ValueError(f"orifice_diameter = {orifice_diameter} m is not above k d = {k * particle_diameter} m")
    return c * bulk_density * math.sqrt(g) * free**2.5


def steady_rate(time: np.ndarray, mass: np.ndarray, lo: float = 0.2, hi: float = 0.6) -> tuple[float, float, float]:
    """(rate [kg/s], t_start [s], t_end [s]): the least-squares slope of the discharged mass against time over
    the samples where it lies between ``lo`` and ``hi`` of its final value, and the times the window spans.
    ValueError with fewer than three samples there.

    time : (T,) [s]; mass : (T,) the running discharged mass [kg] (non-decreasing)."""
    time = np.asarray(time, float)
    mass = np.asarray(mass, float)
    total = float(mass[-1]) if mass.size else 0.0
    sel = (mass >= lo * total) & (mass <= hi * total)
    if total <= 0.0 or sel.sum() < 3:
        raise ValueError(f"the discharge window ({lo:g} to {hi:g} of the final mass {total:g} kg) holds "
                         f"{int(sel.sum())} samples; at least 3 are needed")
    rate = float(np.polyfit(time[sel], mass[sel], 1)[0])
    return rate, float(time[sel][0]), float(time[sel][-1])


def bulk_density(position: np.ndarray, radius: np.ndarray, density: np.ndarray | float, axis_point, up,
                 r_max: float, lo: float, hi: float) -> float:
    """Bulk density [kg/m^3]: the mass of the spheres whose centres lie within ``r_max`` [m] of the vertical
    line through ``axis_point`` along ``up`` and between heights ``lo`` and ``hi`` [m] along it, over the
    volume π r_max² (hi − lo) of that cylinder.

    position : (N, 3) [m]; radius : (N,) [m]; density : material density [kg/m^3], one or (N,)."""
    up = np.asarray(up, float) / np.linalg.norm(up)
    rel = np.asarray(position, float) - np.asarray(axis_point, float)
    h = rel @ up
    r = np.linalg.norm(rel - h[:, None] * up, axis=1)
    inside = (r <= r_max) & (h >= lo) & (h <= hi)
    mass = np.broadcast_to(np.asarray(density, float), radius.shape) * (4.0 / 3.0) * np.pi * radius**3
    return float(mass[inside].sum() / (np.pi * r_max**2 * (hi - lo)))
