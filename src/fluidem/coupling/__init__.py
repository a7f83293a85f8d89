"""Gas–particle coupling: drag laws, voidage mapping particles → grid, interpolation grid → particles.

``drag`` gives β per unit bed volume by name; ``voidage`` maps particles onto the
``StaggeredGrid`` centres (Sun 2007 eqs 34-35, Hoomans 1996 §3.4, eqs 49-50);
``interpolation`` samples gas fields at particle positions (Hoomans 1996 eqs 40-41).
"""
from . import drag, interpolation, voidage
from .drag import DragLaw, drag_laws

__all__ = ["drag", "drag_laws", "DragLaw", "interpolation", "voidage"]
