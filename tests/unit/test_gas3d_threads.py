"""The 3D gas solver's kernels (``_solver3d_kernels``) give bitwise (==) the same fields on one thread and on two.

Their passes over the grid (face fluxes, explicit momentum and stresses, ghost faces, cell residuals, the copies
of the state) run one x plane per work item on Numba's threads when more than one is in use, and as one
serial call otherwise; every sum (mass, flows, the residual norm that stops the iterations) stays one serial
loop in grid order. So a few steps with the particles' β and solids velocity, momentum sources and the pressure
term's voidage must leave every field, iteration count and step figure equal (==) whatever the thread count:
on walled boxes with an inflow and a pressure outlet (ideal gas), on a periodic axis with a continuous outflow,
and on a closed periodic box of constant density (pressure level pinned), with upwind and TVD convection.
"""
from __future__ import annotations

import numba
import numpy as np
import pytest

from fluidem.gas import _layout3d as lay
from fluidem.gas import (
    Circle,
    FreeSlip,
    GasProperties,
    GasSolver,
    Inflow,
    Outflow,
    Periodic,
    PressureOutlet,
    StaggeredGrid,
    Wall,
)

pytestmark = pytest.mark.skipif(numba.config.NUMBA_NUM_THREADS < 2, reason="needs two Numba threads")

STEPS = 3
DT = 2e-4  # [s]


def walled(grid):
    return dict(left=Wall(), right=Wall(), front=Wall(), back=Wall(), top=PressureOutlet(),
                bottom=Inflow(superficial=0.3, voidage=0.4,
                              patches=[Circle(centre=(0.025, 0.02), radius=0.01, interstitial=3.0)]))


def periodic_outflow(grid):
    return dict(left=Periodic(), right=Periodic(), front=FreeSlip(), back=Wall(), top=Outflow(),
                bottom=Inflow(superficial=0.2, voidage=0.5))


def closed(grid):
    return dict(left=Wall(), right=Wall(), front=Periodic(), back=Periodic(), top=Wall(), bottom=Wall())


CASES = {
    "walls-upwind": ((5, 8, 4), walled, {}, "upwind", True),
    "walls-tvd": ((5, 8, 4), walled, {}, "tvd", True),
    "periodic-outflow": ((4, 7, 5), periodic_outflow, {}, "upwind", True),
    "closed-constant-density": ((4, 6, 5), closed, {"density": 1.2}, "upwind", False),
}


def run(name):
    """STEPS steps of case ``name`` with random face β, solids velocities, sources and (every other step) pressure
    voidage; the fields and each step's figures."""
    cells, sides, props, convection, moving = CASES[name]
    grid = StaggeredGrid(cells=cells, size=tuple(0.01 * n for n in cells))
    solver = GasSolver(grid, GasProperties(**props), sides(grid), convection=convection)
    solver.parallel_min_cells = 0  # these small grids too on the threads
    X, Y, Z = grid.centres()
    eps = 0.45 + 0.5 * (Y / Y.max()) ** 2 * (0.8 + 0.2 * np.cos(7 * X / X.max()) * np.sin(3 * Z / Z.max() + 0.3))
    state = solver.initial_state(voidage=eps)
    rng = np.random.default_rng(3)
    steps = []
    for n in range(STEPS):
        shapes = [grid.face_shape(a) for a in range(3)]
        voidage = np.clip(eps * (1 + 0.02 * np.sin(n + 50 * X)), 0.3, 1.0) if moving else eps
        beta = tuple(np.abs(rng.normal(3e4, 1e4, s)) for s in shapes)
        solids = [rng.normal(0.0, 0.05, s) for s in shapes]
        source = [rng.normal(0.0, 10.0, s) for s in shapes]
        pv = tuple(rng.uniform(0.4, 1.0, s) for s in shapes) if n % 2 else None
        info = solver.advance(state, DT, n * DT, voidage=voidage, beta=beta, solids_u=solids[0],
                              solids_v=solids[1], solids_w=solids[2], source_u=source[0], source_v=source[1],
                              source_w=source[2], pressure_voidage=pv)
        steps.append((info.iterations, info.mass_residual, info.inflow_rate, info.outflow_rate, info.mass,
                      info.mass_change_rate, info.courant))
    fields = {k: getattr(state, k).copy() for k in ("p", "rho", "u", "v", "w", "voidage")}
    return fields, steps, int(solver._ipar[lay.I_THREADS])


def with_threads(n, fn, *args):
    """fn(*args) with n Numba threads."""
    before = numba.get_num_threads()
    numba.set_num_threads(min(n, numba.config.NUMBA_NUM_THREADS))
    try:
        return fn(*args)
    finally:
        numba.set_num_threads(before)


@pytest.mark.parametrize("name", list(CASES))
def test_gas3d_steps_same_on_one_and_two_threads(name):
    one, steps_one, threads_one = with_threads(1, run, name)
    two, steps_two, threads_two = with_threads(2, run, name)
    assert (threads_one, threads_two) == (1, 2)  # the serial bodies, then the passes on two threads
    assert steps_one == steps_two  # iterations, mass residual, flows, mass, Courant number: ==
    for key in one:
        assert np.array_equal(one[key], two[key]), key
    assert all(s[0] > 0 for s in steps_one)  # the Newton iterations ran (and converged: advance raises otherwise)


def test_bad_step_inputs_named():
    """The checks that the step inputs pass through compiled loops (β, the voidages) and the state checks kept per
    array object still refuse bad values with their messages, also after a good step."""
    from fluidem.errors import CaseError

    cells = (4, 5, 3)
    grid = StaggeredGrid(cells=cells, size=tuple(0.01 * n for n in cells))
    solver = GasSolver(grid, GasProperties(), walled(grid))
    state = solver.initial_state(voidage=0.6)
    shapes = [grid.face_shape(a) for a in range(3)]
    beta = [np.full(s, 1e4) for s in shapes]
    solver.advance(state, DT, 0.0, beta=tuple(beta))
    bad = [b.copy() for b in beta]
    bad[2][1, 2, 0] = -1.0
    with pytest.raises(CaseError, match=r"gas beta: must be finite and >= 0 \[kg m\^-3 s\^-1\] on every face"):
        solver.advance(state, DT, DT, beta=tuple(bad))
    bad[2][1, 2, 0] = np.nan
    with pytest.raises(CaseError, match="gas beta: must be finite"):
        solver.advance(state, DT, DT, beta=tuple(bad))
    with pytest.raises(CaseError, match="gas beta: must be finite"):
        solver.advance(state, DT, DT, beta=-2.0)
    eps = np.full(cells, 0.6)
    eps[3, 4, 2] = 1.5
    with pytest.raises(CaseError, match=r"gas voidage: value 1.5 outside \(0, 1\]"):
        solver.advance(state, DT, DT, voidage=eps)
    pv = [np.full(s, 0.5) for s in shapes]
    pv[1][0, 0, 0] = 0.0
    with pytest.raises(CaseError, match=r"gas pressure_voidage\[1\]: every face value must lie in \(0, 1\]"):
        solver.advance(state, DT, DT, pressure_voidage=tuple(pv))
    state.p = state.p.astype(np.float32)  # a new object: checked again
    with pytest.raises(CaseError, match="gas state.p: must be a C-contiguous float64 array"):
        solver.advance(state, DT, DT)
    state.p = np.zeros((4, 5, 2))
    with pytest.raises(CaseError, match=r"gas state.p: shape \(4, 5, 2\) does not match \(4, 5, 3\)"):
        solver.advance(state, DT, DT)
