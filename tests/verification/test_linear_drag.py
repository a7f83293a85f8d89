"""The soft-sphere engine's linear external drag ext_force − c v (``ext_damping``), against the exact solution.

A lone sphere, no gravity, no contacts: m dv/dt = F − c v relaxes as
v(t) = F/c + (v0 − F/c) exp(−c t/m). The coupling's default ``drag_update = "substep"`` hands the
engine K_p as c, so this is the particle side of the gas drag within a gas step. The force is
evaluated at the half-kicked velocity of velocity Verlet (as the contact dashpots are), which makes
the scheme first order in c dt/m: halving dt halves the error.
"""
from __future__ import annotations

import math

import numpy as np

from fluidem.case import validate_case
from fluidem.particles.softsphere import SoftSphereEngine

V0 = np.array([0.0, 1.0, 0.0])
V_TERMINAL = np.array([2.0, 0.0, -0.5])


def lone_sphere(tmp_path, v0):
    """An engine with one sphere of 1 mm at (0.5, 0.5, 0.5) m moving at v0; no gravity, no walls."""
    csv = tmp_path / "lone.csv"
    csv.write_text("x,y,z,diameter,vx,vy,vz\n0.5,0.5,0.5,0.001,%g,%g,%g\n" % tuple(v0))
    return SoftSphereEngine(validate_case({
        "name": "lone-sphere", "gravity": [0.0, 0.0, 0.0],
        "particles": {"dimensions": 3, "species": [{"diameter": 1e-3, "density": 2500.0, "count": 1}],
                      "contact": {"model": "linear_spring_dashpot", "stiffness": 100.0, "restitution": 0.9},
                      "placement": {"method": "file", "file": str(csv)}},
        "time": {"end": 1.0, "dt": 1e-5},
    }))


def relax(tmp_path, dt, duration=1.0, rate=1.0):
    """Relative velocity error after ``duration`` of relaxation at c/m = ``rate`` [1/s] with steps ``dt``."""
    eng = lone_sphere(tmp_path, V0)
    eng.dt = dt  # far above the contact limit: there are no contacts
    m = eng.state.mass[0]
    c = rate * m
    eng.ext_damping[:] = c
    eng.ext_force[:] = c * V_TERMINAL
    eng._compute_forces(update=False)
    n = int(round(duration / dt))
    eng.advance(n)
    exact = V_TERMINAL + (V0 - V_TERMINAL) * math.exp(-rate * n * dt)
    np.testing.assert_array_equal(eng.external_force()[0], c * V_TERMINAL - c * eng.state.velocity[0])
    return float(np.abs(eng.state.velocity[0] - exact).max() / np.abs(V0 - V_TERMINAL).max())


def test_linear_drag_relaxes_to_the_exponential_at_first_order(tmp_path):
    e1 = relax(tmp_path, 0.01)
    e2 = relax(tmp_path, 0.005)
    assert e1 < 0.25 * 0.01, e1  # c dt/m = 0.01; measured 1.8e-3
    assert 1.9 < e1 / e2 < 2.1, (e1, e2)  # first order: measured 2.00


def test_zero_drag_leaves_the_external_force_alone(tmp_path):
    """c = 0: v(t) = v0 + F t/m exactly up to round-off (ext_force − 0 v is ext_force)."""
    eng = lone_sphere(tmp_path, [0.0, 1.0, 0.0])
    m = eng.state.mass[0]
    eng.ext_force[:] = [m * 3.0, 0.0, 0.0]
    eng._compute_forces(update=False)
    eng.advance(1000)
    np.testing.assert_allclose(eng.state.velocity[0], [3.0 * 1000 * eng.dt, 1.0, 0.0], rtol=1e-12, atol=1e-15)
