"""A 3D grid one cell deep, free-slip on its two faces across the thin axis, gives the 2D solver's fields.

The 2D problem: a jet through a bed (12 × 20 cells, 0.12 m × 0.2 m, depth 4 mm): no-slip left wall,
free-slip right wall, pressure outlet on top, inflow at the bottom through influx cells of voidage 0.4
(1 m/s interstitial background, an 8 m/s jet over 0.05-0.07 m), a bed of voidage 0.45 with β = 3000
kg m^-3 s^-1 and a rising solids velocity in its lower 8 cm; 30 steps of 0.2 ms, ideal and
constant-density gas, upwind and TVD convection. The 3D grid is one cell (the depth) thick along one axis,
free slip on the two sides across it, and the 2D plane mapped onto the other two axes; with the thin axis
along z the inflow is the same segments, along x and y the jet is a rectangle patch. The 3D fields equal
the 2D ones to the solver's tolerance (measured: p to 1.5e-11 Pa of 1e5, velocities to 5e-15 m/s) and the
velocity across the thin axis stays 0.
"""
import numpy as np
import pytest

from fluidem.gas import (
    FreeSlip,
    GasProperties,
    GasSolver,
    Inflow,
    PressureOutlet,
    Rectangle,
    Segment,
    StaggeredGrid,
    Wall,
)

NX, NY, LX, LY, DEPTH = 12, 20, 0.12, 0.2, 0.004
JET = (0.05, 0.07)


def two_d(props, convection):
    grid = StaggeredGrid(cells=(NX, NY), size=(LX, LY), depth=DEPTH)
    bcs = {"left": Wall(), "right": FreeSlip(), "top": PressureOutlet(),
           "bottom": Inflow(segments=[Segment(interstitial=1.0), Segment(interstitial=8.0, start=JET[0], end=JET[1])],
                            voidage=0.4)}
    return GasSolver(grid, props, bcs, convection=convection, linear_solver="superlu")


# the 2D plane's (x, y) on the 3D axes, and the sides of 2D's left/right and bottom/top, per thin axis
MAPS = {2: ((0, 1), ("left", "right"), ("bottom", "top")),
        0: ((2, 1), ("front", "back"), ("bottom", "top")),
        1: ((0, 2), ("left", "right"), ("front", "back"))}
ACROSS = {0: ("left", "right"), 1: ("bottom", "top"), 2: ("front", "back")}


def three_d(props, convection, thin, linear_solver="superlu"):
    (ax, ay), (lo_x, hi_x), (lo_y, hi_y) = MAPS[thin]
    cells, size = [0, 0, 0], [0.0, 0.0, 0.0]
    cells[ax], cells[ay], cells[thin] = NX, NY, 1
    size[ax], size[ay], size[thin] = LX, LY, DEPTH
    grid = StaggeredGrid(cells=tuple(cells), size=tuple(size))
    if thin == 2:  # the segments run along the bottom's first in-plane axis, x
        inflow = Inflow(segments=[Segment(interstitial=1.0), Segment(interstitial=8.0, start=JET[0], end=JET[1])],
                        voidage=0.4)
    else:  # the jet as a rectangle over the thin axis, in the inflow side's in-plane coordinates
        plane = grid.side_axes(lo_y)
        start = [0.0, 0.0]
        end = [grid.size[plane[0]], grid.size[plane[1]]]
        k = plane.index(ax)
        start[k], end[k] = JET
        inflow = Inflow(interstitial=1.0, voidage=0.4,
                        patches=[Rectangle(start=tuple(start), end=tuple(end), interstitial=8.0)])
    bcs = {lo_x: Wall(), hi_x: FreeSlip(), hi_y: PressureOutlet(), lo_y: inflow}
    bcs.update({s: FreeSlip() for s in ACROSS[thin]})
    gravity = [0.0, 0.0, 0.0]
    gravity[ay] = -9.81
    return GasSolver(grid, props, bcs, gravity=tuple(gravity), convection=convection,
                     linear_solver=linear_solver), (ax, ay)


def to_3d(a, axes, thin):
    """A 2D (x, y) array as the 3D array of the mapped axes (the thin axis of length 1)."""
    b = np.expand_dims(a, 2)  # (x, y, thin)
    order = [0, 0, 0]
    order[axes[0]], order[axes[1]], order[thin] = 0, 1, 2
    return np.ascontiguousarray(np.transpose(b, order))


@pytest.mark.parametrize("thin", [2, 0, 1])
@pytest.mark.parametrize("convection", ["upwind", "tvd"])
@pytest.mark.parametrize("density", [None, 1.2])
def test_one_cell_deep_3d_grid_gives_the_2d_fields(thin, convection, density):
    props = GasProperties(density=density)
    s2 = two_d(props, convection)
    s3, axes = three_d(props, convection, thin)
    _, Y = s2.grid.centres()
    eps = np.where(Y < 0.08, 0.45, 1.0)
    beta = np.where(Y < 0.08, 3000.0, 0.0)
    st2 = s2.initial_state(voidage=eps)
    st3 = s3.initial_state(voidage=to_3d(eps, axes, thin))
    solids = {"solids_u": 0.0, "solids_v": 0.0, "solids_w": 0.0}
    solids[("solids_u", "solids_v", "solids_w")[axes[1]]] = 0.1
    dt = 2e-4
    for k in range(30):
        i2 = s2.advance(st2, dt, k * dt, beta=beta, solids_u=0.0, solids_v=0.1)
        i3 = s3.advance(st3, dt, k * dt, beta=to_3d(beta, axes, thin), **solids)
        assert i3.iterations == i2.iterations
        assert i3.inflow_rate == pytest.approx(i2.inflow_rate, rel=1e-12)
    velocity = (st3.u, st3.v, st3.w)
    assert np.abs(st3.p - to_3d(st2.p, axes, thin)).max() < 1e-9  # [Pa] of 1e5
    assert np.abs(st3.rho - to_3d(st2.rho, axes, thin)).max() < 1e-14
    # face arrays: 2D u on the 3D faces of the axis x maps to, v likewise
    assert np.abs(velocity[axes[0]] - to_3d(st2.u, axes, thin)).max() < 1e-12  # [m/s] of 8
    assert np.abs(velocity[axes[1]] - to_3d(st2.v, axes, thin)).max() < 1e-12
    assert np.abs(velocity[thin]).max() == 0.0
    assert np.abs(st2.v).max() > 7.0  # the jet is there


@pytest.mark.parametrize("thin", [2, 0])
def test_the_multigrid_gives_the_2d_fields_to_the_solver_tolerance(thin):
    """The same with the 3D multigrid-preconditioned GMRES (each correction solved to 1e-4 of its residual,
    the Newton iterations to the mass-residual tolerance 1e-10): equal to the 2D fields within what that
    tolerance allows (measured: p to 2e-9 Pa, velocities to 3e-11 m/s; asserted with a factor 100)."""
    props = GasProperties()
    s2 = two_d(props, "upwind")
    s3, axes = three_d(props, "upwind", thin, linear_solver="multigrid")
    _, Y = s2.grid.centres()
    eps = np.where(Y < 0.08, 0.45, 1.0)
    st2 = s2.initial_state(voidage=eps)
    st3 = s3.initial_state(voidage=to_3d(eps, axes, thin))
    for k in range(30):
        s2.advance(st2, 2e-4, k * 2e-4, beta=np.where(Y < 0.08, 3000.0, 0.0))
        info = s3.advance(st3, 2e-4, k * 2e-4, beta=to_3d(np.where(Y < 0.08, 3000.0, 0.0), axes, thin))
        assert info.converged
    assert s3.linear_solver == "multigrid" and s3.krylov_iterations > 0
    velocity = (st3.u, st3.v, st3.w)
    assert np.abs(st3.p - to_3d(st2.p, axes, thin)).max() < 2e-7  # [Pa] of 1e5
    assert np.abs(velocity[axes[0]] - to_3d(st2.u, axes, thin)).max() < 3e-9  # [m/s] of 8
    assert np.abs(velocity[axes[1]] - to_3d(st2.v, axes, thin)).max() < 3e-9


def test_the_multigrid_gives_way_to_superlu_when_gmres_stalls():
    """One GMRES iteration a correction cannot reach its target: the first step goes on with SuperLU from the
    iteration where GMRES stalled, converges, and the run gives the fields of a SuperLU run to the solver
    tolerance (bounds of the multigrid test above)."""
    props = GasProperties()
    runs = []
    for linear_solver in ("multigrid", "superlu"):
        s3, axes = three_d(props, "upwind", 2, linear_solver=linear_solver)
        s3.krylov_max = 1
        assert s3.linear_solver == linear_solver
        _, Y, _ = s3.grid.centres()
        st = s3.initial_state(voidage=np.where(Y < 0.08, 0.45, 1.0))
        for k in range(5):
            info = s3.advance(st, 2e-4, k * 2e-4, beta=np.where(Y < 0.08, 3000.0, 0.0))
            assert info.converged
        assert s3.linear_solver == "superlu"
        runs.append(st)
    assert np.abs(runs[0].p - runs[1].p).max() < 2e-7  # [Pa]
    for a in "uvw":
        assert np.abs(getattr(runs[0], a) - getattr(runs[1], a)).max() < 3e-9  # [m/s]
