"""A rough wall time of a case before it runs (``fluidem cases``), from its size and time steps alone.

Work: particle-steps N × t_end / dt, with dt the case's ``time.dt`` or ``dt_fraction`` × the contact time
of the smallest sphere of each species with itself under the case's contact law (the soft-sphere engine
takes the shortest over all pairs and walls, which for the built-in cases is the same within a few per
cent), or the gas step DT for hard spheres; plus, with a gas, gas steps × cells (all of a 3D grid's). The rates are one core's,
measured on the 2-core development machine in long runs (compile time excluded): a coupled soft-sphere
bed (``binary-density``, 5 s) ran 5.8e6 particle-steps/s with 2.2 ms per gas step of 450 cells; hard
spheres (``hoomans-orifice``) about 1e6 particle-steps/s. The estimate is good to a factor of 2 or 3:
bubbling, collisions per step and the machine change it. No particle is placed and nothing compiles.
"""
from __future__ import annotations

import math

SOFT_RATE = 5.8e6  # particle-steps per second, one core, soft spheres
HARD_RATE = 1.0e6  # particle-steps per second, one core, hard spheres (collisions included, loosely)
GAS_CELL_STEP = 5e-6  # seconds per gas cell and gas step (map, drag, pressure correction)


def _dt(case) -> float | None:
    """The DEM step the case will take (None: unknown without placing particles)."""
    t = case.time
    contact = case.particles.contact
    if contact.instantaneous:
        return case.gas.dt if case.gas is not None else (t.dt or 1e-4)
    if t.dt is not None:
        return t.dt
    times = []
    for sp in case.particles.species:
        d = sp.diameter
        dist = sp.size_distribution
        if dist is not None and dist.min is not None:
            d = dist.min
        if not d:
            continue
        m = sp.density * math.pi / 6.0 * d**3
        try:
            times.append(contact.contact_time(0.5 * m, 0.25 * d, t.impact_velocity, sp, sp))
        except (NotImplementedError, ValueError, ZeroDivisionError):
            continue
    times = [x for x in times if x > 0.0 and math.isfinite(x)]
    return t.dt_fraction * min(times) if times else None


def wall_time_estimate(case) -> float | None:
    """Rough wall seconds of the whole case on one core (module docstring); None where it cannot tell."""
    dt = _dt(case)
    if dt is None or not dt > 0.0:
        return None
    n = sum(s.count for s in case.particles.species)
    end = case.time.end
    seconds = n * end / dt / (HARD_RATE if case.particles.contact.instantaneous else SOFT_RATE)
    if case.gas is not None:
        cells = math.prod(case.gas.grid.cells)  # every axis: nx × ny, or nx × ny × nz on a 3D grid
        seconds += end / case.gas.dt * max(cells * GAS_CELL_STEP, 1e-3)
    return seconds


def human(seconds: float | None) -> str:
    """``~40 s``, ``~12 min``, ``~3.5 h``; ``?`` for None."""
    if seconds is None:
        return "?"
    if seconds < 90:
        return f"~{max(seconds, 1):.0f} s"
    if seconds < 90 * 60:
        return f"~{seconds / 60:.0f} min"
    return f"~{seconds / 3600:.1f} h"
