"""Contact models: one file per model, registered by name in ``contact_models``.

Each model owns and validates its parameters (a pydantic model) and packs them
into a fixed-layout float64 row that the compiled kernels read (see ``base.py``
for the slots). The kernels dispatch on the integer code in slot 0
(``_dispatch.py``).
"""
from .base import ContactModel, contact_models
from .spring_dashpot import LinearSpringDashpot
from .hertz_mindlin import HertzMindlin

__all__ = ["ContactModel", "contact_models", "LinearSpringDashpot", "HertzMindlin"]
