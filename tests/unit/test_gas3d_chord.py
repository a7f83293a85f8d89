"""The chord steps of the 3D gas solver's multigrid Newton loop (``_solver3d_kernels.newton_multigrid``).

A Newton iteration after one that cut the mass residual to at most ``solver3d.CHORD_REDUCTION`` of what it was
keeps that iteration's Jacobian and multigrid hierarchy. The convergence test always uses the current residual,
so a step must end within the solver's tolerance whatever Jacobian its corrections used, and where the chord
steps are taken only in the quadratic regime of the iterations they should seldom add one (on this box,
never). Checked on a
walled box with an inflow patch and a pressure outlet, ideal gas, moving voidage and random face β and solids
velocities (a start-up: the pressure changes by 1-2 kPa a step):

* with the threshold in use, every step takes as many iterations as with a fresh Jacobian in each, makes fewer
  hierarchies than iterations, and gives the same fields to 1e-10 of the step's change (both end within the
  mass-residual tolerance, 1e-10 of the reference flow);
* with the threshold at 1 (always a chord step after the first iteration) each step makes one hierarchy and
  still ends within the tolerance (the chord is then slower to converge, which is why the threshold is 1e-3);
* with the threshold at 0 every iteration makes its own hierarchy;
* where GMRES on the kept Jacobian fails, the iteration assembles again and the step is the one of fresh
  Jacobians (the retry branch, reached by making every chord attempt fail).
"""
from __future__ import annotations

import numpy as np
import pytest

from fluidem.gas import Circle, GasProperties, GasSolver, Inflow, PressureOutlet, StaggeredGrid, Wall
from fluidem.gas import solver3d as S3

STEPS = 5
DEFAULT = S3.CHORD_REDUCTION
DT = 2e-4  # [s]


def run(monkeypatch, chord):
    """STEPS steps with the chord threshold ``chord``: the final state and each step's (iterations, hierarchies,
    mass residual, converged, largest pressure change [Pa], largest velocity [m/s])."""
    monkeypatch.setattr(S3, "CHORD_REDUCTION", chord)
    cells = (6, 10, 4)
    grid = StaggeredGrid(cells=cells, size=tuple(0.01 * n for n in cells))
    sides = dict(left=Wall(), right=Wall(), front=Wall(), back=Wall(), top=PressureOutlet(),
                 bottom=Inflow(superficial=0.3, voidage=0.4,
                               patches=[Circle(centre=(0.03, 0.02), radius=0.01, interstitial=3.0)]))
    solver = GasSolver(grid, GasProperties(), sides)
    assert solver.linear_solver == "multigrid"
    X, Y, Z = grid.centres()
    eps = 0.45 + 0.5 * (Y / Y.max()) ** 2 * (0.8 + 0.2 * np.cos(7 * X / X.max()) * np.sin(3 * Z / Z.max() + 0.3))
    state = solver.initial_state(voidage=eps)
    rng = np.random.default_rng(3)
    steps = []
    for n in range(STEPS):
        shapes = [grid.face_shape(a) for a in range(3)]
        voidage = np.clip(eps * (1 + 0.02 * np.sin(n + 50 * X)), 0.3, 1.0)
        beta = tuple(np.abs(rng.normal(3e4, 1e4, s)) for s in shapes)
        solids = [rng.normal(0.0, 0.05, s) for s in shapes]
        made, p0 = solver.factorisations, state.p.copy()
        info = solver.advance(state, DT, n * DT, voidage=voidage, beta=beta, solids_u=solids[0], solids_v=solids[1],
                              solids_w=solids[2])
        assert solver.linear_solver == "multigrid"  # no fall-back to SuperLU
        speed = max(np.abs(a).max() for a in (state.u, state.v, state.w))
        steps.append((info.iterations, solver.factorisations - made, info.mass_residual, info.converged,
                      np.abs(state.p - p0).max(), speed))
    return state, steps, solver.tolerance


def test_chord_steps_keep_the_iterations_and_the_fields(monkeypatch):
    fresh, fresh_steps, tol = run(monkeypatch, 0.0)
    chord, chord_steps, _ = run(monkeypatch, DEFAULT)
    for (it_f, made_f, _, ok_f, change, speed), (it_c, made_c, res_c, ok_c, _, _) in zip(fresh_steps, chord_steps):
        assert ok_f and ok_c and res_c <= tol
        assert made_f == it_f >= 2  # threshold 0: a hierarchy per iteration
        assert it_c == it_f and made_c < it_c  # the same iterations, at least one of them a chord step
        assert change > 100.0  # [Pa] a start-up: the bound below is relative to a real change
    change = max(s[4] for s in fresh_steps)
    speed = max(s[5] for s in fresh_steps)
    assert np.abs(chord.p - fresh.p).max() <= 1e-10 * change
    for a, b in ((chord.u, fresh.u), (chord.v, fresh.v), (chord.w, fresh.w)):
        assert np.abs(a - b).max() <= 1e-10 * speed


@pytest.mark.parametrize("chord, hierarchies", [(1.0, "one"), (0.0, "every iteration")])
def test_the_threshold_decides_which_iterations_make_a_hierarchy(monkeypatch, chord, hierarchies):
    _, steps, tol = run(monkeypatch, chord)
    for it, made, res, ok, _, _ in steps:
        assert ok and res <= tol
        assert made == (1 if hierarchies == "one" else it)
        assert it >= 2


def test_a_chord_step_whose_gmres_fails_assembles_again(monkeypatch):
    """The retry branch: where GMRES on the kept Jacobian does not converge, the iteration assembles the current
    Jacobian, makes its hierarchy and solves again, and the step goes on as if it had never tried the chord.
    ``newton_multigrid`` runs as Python (its ``py_func``) so that its ``gmres`` can be replaced by one that makes
    every chord attempt fail (the real GMRES given no iterations); every iteration after the first tries the chord
    (threshold 1), so every one of them takes the branch."""
    from fluidem.gas import _solver3d_kernels as K3

    fresh, fresh_steps, tol = run(monkeypatch, 0.0)  # compiled; a hierarchy per iteration

    real_gmres, real_setup = K3.gmres, K3.mg_setup
    calls = {"setup": 0, "chord": 0, "since_setup": 0}

    def setup(*args):
        calls["setup"] += 1
        calls["since_setup"] = 0
        return real_setup(*args)

    def gmres(*args):
        calls["since_setup"] += 1
        if calls["since_setup"] > 1:  # no hierarchy made since the last solve: a chord attempt
            calls["chord"] += 1
            return real_gmres(*args[:-1], 0)  # no iterations allowed: -1 unless the residual is already small
        return real_gmres(*args)

    monkeypatch.setattr(K3, "newton_multigrid", K3.newton_multigrid.py_func)
    monkeypatch.setattr(K3, "gmres", gmres)
    monkeypatch.setattr(K3, "mg_setup", setup)
    retried, retried_steps, _ = run(monkeypatch, 1.0)
    iterations = sum(s[0] for s in retried_steps)
    assert calls["chord"] == iterations - STEPS > 0  # every iteration after each step's first tried the chord
    assert calls["setup"] == iterations  # ... failed, and assembled again
    for (it_f, _, _, _, _, _), (it_r, made_r, res_r, ok_r, _, _) in zip(fresh_steps, retried_steps):
        assert ok_r and res_r <= tol
        assert it_r == it_f and made_r == it_r
    change = max(s[4] for s in fresh_steps)
    speed = max(s[5] for s in fresh_steps)
    assert np.abs(retried.p - fresh.p).max() <= 1e-10 * change
    for a, b in ((retried.u, fresh.u), (retried.v, fresh.v), (retried.w, fresh.w)):
        assert np.abs(a - b).max() <= 1e-10 * speed
