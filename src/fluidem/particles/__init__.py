"""Particle engines: soft-sphere DEM (``softsphere``) and event-driven hard spheres
(``hardsphere``), walls, neighbour lists and contact laws.

``engine_for(case, state=None)`` builds the engine the case's contact law implies:
``model = "hard_sphere"`` → ``HardSphereEngine``, any other law → ``SoftSphereEngine``.
"""


def engine_for(case, state=None):
    """The particle engine for ``case`` (optionally starting from ``state``)."""
    if getattr(case.particles.contact, "model", None) == "hard_sphere":
        from .hardsphere import HardSphereEngine

        return HardSphereEngine(case, state=state)
    from .softsphere import SoftSphereEngine

    return SoftSphereEngine(case, state=state)
