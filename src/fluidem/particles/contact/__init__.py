"""Contact models: one file per model, registered by name in ``contact_models``.

Each model owns and validates its parameters (a pydantic model) and packs them
into a fixed-layout float64 row that the compiled kernels read (see ``base.py``
for the slots). The kernels dispatch on the integer code in slot 0
(``_dispatch.py``).
"""
from .base import ContactModel, contact_models
from .spring_dashpot import LinearSpringDashpot
from .hertz_mindlin import HertzMindlin
from .hard_sphere import HardSphere

__all__ = ["ContactModel", "contact_models", "soft_contact_models", "LinearSpringDashpot", "HertzMindlin",
           "HardSphere"]


def soft_contact_models() -> list[str]:
    """Names of the registered soft-sphere (force-based) contact laws."""
    return [n for n in contact_models.names() if not contact_models.get(n).instantaneous]
