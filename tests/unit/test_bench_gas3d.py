"""``benchmarks/gas3d_step.py``: the pressure corrections it keeps around the compiled Newton loop, and its
``--kernels`` split, on a small grid of its bubbling bed."""
from __future__ import annotations

import contextlib
import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

BENCHMARKS = Path(__file__).resolve().parents[2] / "benchmarks"
STEPS = 4


@pytest.fixture(scope="module")
def g3():
    sys.path.insert(0, str(BENCHMARKS))  # gas3d_step imports harness from its own folder
    try:
        import gas3d_step
    finally:
        sys.path.remove(str(BENCHMARKS))
    return gas3d_step


def run(g3, keep: list | None):
    """Two untimed steps, then STEPS steps of the bed on 8 x 10 x 6 cells (keeping corrections into ``keep``)."""
    solver, state, step_args, dt = g3.bed_problem(8, 10, 6, "multigrid")
    t = 0.0
    with contextlib.ExitStack() as stack:
        for n in range(2 + STEPS):
            if n == 2 and keep is not None:
                stack.enter_context(g3.keeping_corrections(keep, STEPS))
            solver.advance(state, dt, t, **step_args(state, t, dt))
            t += dt
    return solver, state


def test_keeping_corrections_leaves_the_run_as_it_was(g3):
    """The extra residual before each Newton loop repeats the loop's own to the bit: the fields are the same."""
    kept = []
    solver, kept_state = run(g3, kept)
    _, plain_state = run(g3, None)
    for k in ("p", "rho", "u", "v", "w", "voidage"):
        assert np.array_equal(getattr(kept_state, k), getattr(plain_state, k)), k
    assert len(kept) == STEPS and solver.linear_solver == "multigrid"


def test_kept_corrections_are_the_first_newton_systems(g3):
    """Each kept system is a step's first correction: its right-hand side is −R at the step's start (not
    converged: ‖b‖₁ above the tolerance times the reference flow, which the loop's target is a part of),
    its matrix is the assembled Jacobian (the solver's CSC pattern, non-singular), and GMRES with a fresh
    hierarchy reaches the target, as the solver's own loop does."""
    from fluidem.gas import _multigrid3d_kernels as MK
    from fluidem.gas.solver import KRYLOV_MAX

    kept = []
    solver, _ = run(g3, kept)
    n = solver.R.size
    A0 = None
    for data, b, target in kept:
        A = sp.csc_matrix((data, solver._indices, solver._indptr), shape=(n, n))
        assert b.shape == (n,) and np.all(np.isfinite(b)) and np.linalg.norm(b) > 0.0
        assert 0.0 < target < np.linalg.norm(b)  # 1e-5 of ‖b‖ or the floor below it: a correction to make
        x = np.zeros(n)
        mg = solver._mg
        assert MK.mg_setup(data, mg.ell, mg.MGL, mg.MGI, mg.MGA, mg.MGS, mg.MGW, mg.DLU, mg.PIV)
        its = MK.gmres(mg.MGL, mg.MGI, mg.MGA, mg.MGS, mg.MGW, mg.DLU, mg.PIV, mg.KRY, mg.HES, b, x, target,
                       KRYLOV_MAX)
        assert 1 <= its <= 10
        assert np.linalg.norm(b - A @ x) <= target
        if A0 is not None:  # a new matrix each step (the voidage and the gas moved)
            assert abs(A - A0).max() > 0.0
        A0 = A


def test_kernel_split_rows(g3):
    rows = g3.kernel_split("8x10x6", seconds=0.05, warmup=2, count=2)
    by_name = {r[2].strip(): r for r in rows}
    whole = by_name["whole step"][3]
    for name in ("begin_step", "newton_multigrid", "courant_number", "end_step"):
        r = by_name[name]
        assert r[4] == 1.0 and 0.0 <= r[5] <= whole  # one call a step, a part of the step
    assert by_name["newton_multigrid"][5] > 0.0
    gm = next(r for r in rows if r[2].startswith("gmres replayed"))
    assert gm[3] > 0.0 and by_name["mg_setup replayed"][3] > 0.0
    assert "cycle" in by_name and "level 0 down" in by_name
