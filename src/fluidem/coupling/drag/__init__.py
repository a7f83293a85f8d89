"""Drag laws: one file per closure, registered by name in ``drag_laws``.

Each closure is a pydantic model (``extra="forbid"``) with an integer ``code`` and its own
parameters; the compiled kernels dispatch on the code in slot 0 of its packed row
(``_dispatch.py``, written from the registry). Conventions (β per unit bed volume, force
per particle β V_p/(1 − ε) (u − v)) are in ``base.py``. Every module of this package is
imported here, so a new law is one new file that registers itself with
``@drag_laws.register("name")``.
"""
from ...registry import import_submodules
from .base import DragLaw, drag_laws

import_submodules(__name__, __path__)

# the registered laws by class name: fd.drag.Beetstra, ...
globals().update({drag_laws.get(n).__name__: drag_laws.get(n) for n in drag_laws.names()})

__all__ = ["DragLaw", "drag_laws", *(drag_laws.get(n).__name__ for n in drag_laws.names())]
