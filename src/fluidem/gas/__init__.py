"""Gas phase: volume-averaged Navier–Stokes on a staggered grid (Hoomans 1996 eqs 42-48, Table 1).

Public surface::

    from fluidem.gas import (StaggeredGrid, GasProperties, GasSolver, GasState,
                             Wall, FreeSlip, Inflow, Segment, Pulse, PressureOutlet, Outflow, Periodic)

    grid = StaggeredGrid(cells=(15, 25), size=(0.15, 0.5), depth=0.004)
    solver = GasSolver(grid, GasProperties(), {"left": Wall(), "right": Wall(), "top": PressureOutlet(),
                       "bottom": Inflow(segments=[Segment(interstitial=4.5),
                                                  Segment(interstitial=45.0, start=0.07, end=0.08)], voidage=0.4)})
    state = solver.initial_state(voidage=0.4)
    info = solver.advance(state, dt=1e-4, t=0.0, beta=beta, solids_u=vs_x, solids_v=vs_y)

The particle side enters only as arrays (voidage, β with the solids velocity, or a
momentum source), so the solver runs and is verified on its own.
"""
from .boundaries import (BoundaryCondition, Circle, FreeSlip, Inflow, Outflow, Periodic, PressureOutlet, Pulse, Rectangle,
                         Segment, Table, Wall, boundary_conditions)
from .grid import (CORNER, FLAG_NAMES, FREE_SLIP, INFLOW, INTERIOR, NO_SLIP, OUTFLOW, PERIODIC, PRESSURE,
                   StaggeredGrid)
from .solver import GasConvergenceError, GasProperties, GasSolver, GasState, StepInfo
from .solver3d import GasSolver3D
from .schema import GasSection, GridSpec as Grid, PropertiesSpec as Properties  # the case's [gas] building blocks

__all__ = [
    "GasSection", "Grid", "Properties", "StaggeredGrid", "GasProperties", "GasSolver", "GasSolver3D", "GasState", "StepInfo", "GasConvergenceError",
    "BoundaryCondition", "Wall", "FreeSlip", "Inflow", "Segment", "Rectangle", "Circle", "Pulse", "Table", "PressureOutlet",
    "Outflow", "Periodic", "boundary_conditions", "INTERIOR", "FREE_SLIP", "NO_SLIP", "INFLOW", "PRESSURE",
    "OUTFLOW", "CORNER", "PERIODIC", "FLAG_NAMES",
]
