"""Boundary conditions of the gas phase: small objects on named sides, turned into cell flags once.

Each condition carries the integer ``flag`` of Hoomans 1996 Table 1 that
``StaggeredGrid.cell_flags`` writes into the ring of boundary cells, plus the values
the solver needs (inflow velocities, outlet pressure); ``base.py`` states what a
condition answers. Nothing here runs in a time step except evaluating
time-dependent values. Every module of this package is imported here, so a new
condition is one new file whose class registers itself in ``boundary_conditions``.

=================  ====  ===================================================================
condition          flag  on the boundary face / in the boundary cell
=================  ====  ===================================================================
``FreeSlip()``     2     normal velocity 0; tangential velocity mirrored (no shear)
``Wall()``         3     normal velocity 0; tangential velocity 0 on the wall (no slip)
``Inflow(...)``    4     normal velocity prescribed (segments; on a 3D grid also rectangle
                         and circle patches); tangential velocity 0 in the influx cell;
                         voidage of the influx cell fixed (Hoomans §3.5)
``PressureOutlet`` 5     pressure prescribed at the boundary-cell centre, half a cell
                         outside the domain; normal velocity from momentum; free slip
``Outflow()``      6     continuous outflow: zero normal gradient of velocity and pressure;
                         total outflow closes the mass balance; free slip
``Periodic()``     8     the boundary cell is the interior cell on the opposite side
=================  ====  ===================================================================
"""
from ...registry import import_submodules
from .base import BoundaryCondition, Pulse, Table, Value, boundary_conditions, evaluate

import_submodules(__name__, __path__)

from .inflow import Segment  # noqa: E402
from .patches import Circle, Patch, Rectangle  # noqa: E402

# the registered conditions by class name (fd.gas.Wall, ...), those of new files included
globals().update({boundary_conditions.get(n).__name__: boundary_conditions.get(n) for n in boundary_conditions.names()})

__all__ = ["BoundaryCondition", "Pulse", "Table", "Value", "Segment", "Patch", "Rectangle", "Circle",
           "boundary_conditions", "evaluate",
           *(boundary_conditions.get(n).__name__ for n in boundary_conditions.names())]
