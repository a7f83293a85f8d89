"""Scalar probes of a particle system: energies, contacts, wall forces, packing.

Orchestration only: the loops over particles and contacts are the kernels of ``_contacts_kernels``.
"""
from __future__ import annotations

import numpy as np

from ..particles._softsphere_kernels import walls_now
from ..particles.engine import ParticleEngine
from ._contacts_kernels import NO_PERIOD, contact_counts, wall_totals


def energies(engine) -> dict[str, float]:
    """Kinetic, rotational and potential energy [J]; potential relative to the origin, −m g·x
    (``ParticleEngine.energies``, without an engine's further terms)."""
    return ParticleEngine.energies(engine)


def contacts(engine) -> dict[str, float]:
    """Particle contacts, coordination number (mean contacts per particle) and max overlap / diameter;
    ``wall_contacts`` and the overlap count plane walls and wall shapes."""
    st = engine.state
    # contacts across a periodic side by nearest image (engine.period: 0 along the other axes)
    per, total, worst = contact_counts(st.position, st.radius, engine.row_start, engine.partner,
                                       getattr(engine, "period", NO_PERIOD))
    n = max(st.n, 1)
    wall_contacts = 0
    if engine.walls.planes:
        point, normal = wall_positions(engine)
        gap = np.einsum("nwk,wk->nw", st.position[:, None, :] - point[None, :, :], normal) - st.radius[:, None]
        wall_contacts = int(np.sum(gap < 0))
        worst = max(worst, float(np.max(-gap / (2 * st.radius[:, None]), initial=0.0)))
    shapes = getattr(engine, "shapes", None)
    if shapes is not None and len(shapes):  # wall shapes: their contacts, each feature once (as the forces)
        count, overlap, _ = shapes.contacts(st, engine.time)
        wall_contacts += int(count.sum())
        worst = max(worst, float(np.max(overlap / (2 * st.radius), initial=0.0)))
    return {"contacts": int(total), "wall_contacts": wall_contacts, "coordination": 2.0 * total / n,
            "max_overlap_rel": float(max(worst, 0.0))}


def wall_positions(engine):
    """(reference points (W, 3), normals (W, 3)) of the wall planes at the engine's time."""
    return walls_now(engine.wall_motion, engine.wall_point0, engine.time)[:, :3], engine.wall_normal


def wall_forces(engine) -> dict[str, np.ndarray]:
    """Force exerted by the particles on each wall plane [N], by plane name."""
    st = engine.state
    tot = wall_totals(st.position, st.velocity, st.omega, st.radius, st.mass, st.species, engine.pw,
                       engine.wall_motion, engine.wall_point0, engine.wall_normal, engine.wall_hist,
                       engine.time, engine.dt)
    return {name: tot[k] for k, name in enumerate(engine.walls.names)}


def surface_packing_fraction(engine, samples_per_diameter: int = 20) -> float:
    """Area fraction of a settled 2D bed, measured as Hoomans 1996 §5.1 does.

    The area under the upper layer of particles is integrated along x: the free
    surface h(x) is the highest particle boundary above each x (sampled finely);
    the fraction is the particles' disc area over ∫ (h − y_floor) dx. The floor and
    the side limits are the box walls (or the particles' extent without walls). NaN when no particle
    lies above the floor between them.
    """
    st = engine.state
    if st.n == 0:  # every particle gone through an outlet, or none arrived yet
        return float("nan")
    if engine.walls.box_lower is not None:
        x0, y0 = engine.walls.box_lower[0], engine.walls.box_lower[1]
        x1 = engine.walls.box_upper[0]
    else:
        x0 = float(np.min(st.position[:, 0] - st.radius))
        x1 = float(np.max(st.position[:, 0] + st.radius))
        y0 = float(np.min(st.position[:, 1] - st.radius))
    d = 2.0 * float(np.mean(st.radius))
    xs = np.linspace(x0, x1, max(int((x1 - x0) / d * samples_per_diameter), 2))
    dx = np.abs(xs[None, :] - st.position[:, 0:1])
    top = np.where(dx < st.radius[:, None],
                   st.position[:, 1:2] + np.sqrt(np.maximum(st.radius[:, None] ** 2 - dx**2, 0.0)), y0)
    h = top.max(axis=0) - y0
    area = np.trapezoid(h, xs)
    if not area > 0.0:  # no particle above the floor between the side limits (e.g. all fell out of the box)
        return float("nan")
    return float(np.sum(np.pi * st.radius**2) / area)
