"""Particle engines: soft-sphere DEM (``softsphere``) and event-driven hard spheres
(``hardsphere``) on a shared base (``engine.ParticleEngine``), walls, neighbour lists and
contact laws.

``engine_for(case, state=None)`` builds the engine the case's contact law implies:
``model = "hard_sphere"`` → ``HardSphereEngine``, any other law → ``SoftSphereEngine``.
"""
from .engine import ParticleEngine, engine_for

__all__ = ["ParticleEngine", "engine_for"]
