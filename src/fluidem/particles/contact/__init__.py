"""Contact models: one file per model, registered by name in ``contact_models``.

Each model owns and validates its parameters (a pydantic model) and packs them
into a fixed-layout float64 row that the compiled kernels read (see ``base.py``
for the slots). The kernels dispatch on the integer code in slot 0
(``_dispatch.py``, written from the registry). Every module of this package is
imported here, so a new model is one new file: its class registers itself with
``@contact_models.register("name")``.
"""
from ...registry import import_submodules
from .base import ContactModel, contact_models

import_submodules(__name__, __path__)

# the registered models by class name: fd.contact.HertzMindlin, ...
globals().update({contact_models.get(n).__name__: contact_models.get(n) for n in contact_models.names()})

__all__ = ["ContactModel", "contact_models", "soft_contact_models",
           *(contact_models.get(n).__name__ for n in contact_models.names())]


def soft_contact_models() -> list[str]:
    """Names of the registered soft-sphere (force-based) contact laws."""
    return [n for n in contact_models.names() if not contact_models.get(n).instantaneous]
