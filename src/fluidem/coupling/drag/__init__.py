"""Drag laws: one file per closure, registered by name in ``drag_laws``.

Each closure is a pydantic model (``extra="forbid"``) with an integer ``code``; the
compiled kernels dispatch on it (``_dispatch.py``). Conventions (β per unit bed volume,
force per particle β V_p/(1 − ε) (u − v)) are in ``base.py``.
"""
from .base import DragLaw, drag_laws
from .hoomans1996 import Hoomans1996
from .gidaspow import Gidaspow
from .di_felice import DiFelice
from .beetstra import Beetstra
from .koch_hill import KochHill
from .hoomans1996_total import Hoomans1996Total

__all__ = ["DragLaw", "drag_laws", "Hoomans1996", "Gidaspow", "DiFelice", "Beetstra", "KochHill", "Hoomans1996Total"]
