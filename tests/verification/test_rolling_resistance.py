"""Rolling resistance, constant directional torque (``rolling_friction``, ``rolling_model = "cdt"``).

A sphere rolling without slip on a plane feels the torque M = −μ_r a m g ω/|ω| (R* = a, F_n = m g). With
the friction force F at the contact point, m dv/dt = F and I dω/dt = −a F − μ_r a m g; rolling (v = a ω) and
I = (2/5) m a² give dv/dt = −μ_r g/(1 + I/(m a²)) = −(5/7) μ_r g, so the sphere stops after

    t_s = 7 v0/(5 μ_r g),    s = v0 t_s/2 = 7 v0²/(10 μ_r g).

Between spheres the torque is −μ_r R* |F_n| ω_r/|ω_r| on i and the opposite on j, ω_r = ω_i − ω_j.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from _helpers.heap import heap_angle

DIAMETER = 4e-3  # [m]
DENSITY = 2500.0  # [kg/m^3]
G = 9.81  # [m/s^2]
V0 = 0.1  # [m/s]
ROLLING = 0.1  # μ_r

# STOP_TOL = 2 %: the discrete dynamics add the start-up of the tangential spring (it loads within ~10 contact
#   times, 1e-3 of t_s) and, once stopped, the chatter of the torque's sign at |ω| ≤ M dt/I (displacements of
#   ~a M dt²/I a step, 1e-9 of s); the continuous result is exact otherwise, since the torque does not depend
#   on the speed. A torque on the wrong lever (a/2, 2a) or without the load F_n moves s by 30 % or more.
STOP_TOL = 0.02


def equilibrium_overlap(law, mass, radius):
    if law["model"] == "linear_spring_dashpot":
        return mass * G / law["stiffness"]
    e_star = law["youngs_modulus"] / (2.0 * (1.0 - law["poisson_ratio"] ** 2))
    return (mass * G / (4.0 / 3.0 * e_star * math.sqrt(radius))) ** (2.0 / 3.0)


@pytest.mark.parametrize("model,dimensions,rolling_model", [
    ("linear_spring_dashpot", 3, "cdt"), ("hertz_mindlin", 3, "cdt"), ("linear_spring_dashpot", 2, "cdt"),
    ("linear_spring_dashpot", 3, "epsd"), ("hertz_mindlin", 3, "epsd"), ("linear_spring_dashpot", 2, "epsd")])
def test_rolling_sphere_stops_after_the_analytic_distance(make_engine, contact_law, model, dimensions, rolling_model):
    """cdt and epsd alike: the epsd spring reaches its limit μ_r R* F_n within a rotation of μ_r R* F_n / k_r
    (k_r = k_t a², a wind-up of μ_r m g / k_t: 1e-5 of s here) and then holds it while the sphere rolls."""
    law = contact_law(model, restitution=0.5, friction=0.5, rolling_friction=ROLLING, rolling_model=rolling_model)
    a = 0.5 * DIAMETER
    mass = DENSITY * math.pi * DIAMETER**3 / 6.0
    h = a - equilibrium_overlap(law, mass, a)
    if dimensions == 3:  # floor z = 0, rolling along +x: ω_y = v0/a
        pos, up, omega = [[0.0, 0.0, h]], [0.0, 0.0, 1.0], [[0.0, V0 / a, 0.0]]
    else:  # floor y = 0 in the x-y plane: ω_z = −v0/a
        pos, up, omega = [[0.0, h, 0.0]], [0.0, 1.0, 0.0], [[0.0, 0.0, -V0 / a]]
    floor = {"name": "floor", "kind": "plane", "point": [0.0, 0.0, 0.0], "normal": up}
    eng = make_engine(pos, DIAMETER, [[V0, 0.0, 0.0]], omega=omega, contact=law, walls=[floor],
                      gravity=tuple(-G * np.array(up)), density=DENSITY, dimensions=dimensions, impact_velocity=V0)
    t_stop = 7.0 * V0 / (5.0 * ROLLING * G)
    eng.advance(int(0.5 * t_stop / eng.dt))
    # halfway in time the speed is v0/2 (constant deceleration)
    assert eng.state.velocity[0, 0] == pytest.approx(V0 - 5.0 / 7.0 * ROLLING * G * eng.time, abs=STOP_TOL * V0)
    eng.advance(int(0.8 * t_stop / eng.dt))
    s = eng.state.position[0, 0]
    assert s == pytest.approx(7.0 * V0**2 / (10.0 * ROLLING * G), rel=STOP_TOL)
    assert abs(eng.state.velocity[0, 0]) < 1e-3 * V0, "the sphere has stopped"


def test_rolling_torque_between_two_spheres(two_particles):
    """Without Coulomb friction the only torques are the rolling ones: −μ_r R* F_n ω̂_r on 0, the opposite on 1."""
    d0, d1 = 4e-3, 3e-3
    omega = np.array([[10.0, -20.0, 50.0], [-5.0, 15.0, -30.0]])
    eng = two_particles(overlap=0.01 * d1, model="linear_spring_dashpot", diameters=(d0, d1), omega=omega,
                        friction=0.0, rolling_friction=ROLLING, stiffness=1e4)
    f, t = eng.state.force, eng.state.torque
    fn = abs(f[0, 0])
    r_eff = 0.25 * d0 * d1 / (0.5 * (d0 + d1))
    w = omega[0] - omega[1]
    expected = -ROLLING * r_eff * fn * w / np.linalg.norm(w)
    np.testing.assert_allclose(t[0], expected, rtol=1e-12)
    np.testing.assert_allclose(t[1], -expected, rtol=1e-12)
    # the plain law (no rolling friction) gives the same force and no torque
    plain = two_particles(overlap=0.01 * d1, model="linear_spring_dashpot", diameters=(d0, d1), omega=omega,
                          friction=0.0, stiffness=1e4)
    np.testing.assert_array_equal(plain.state.force, f)
    assert not plain.state.torque.any()


def test_angle_of_repose_grows_with_rolling_friction():
    """300 discs poured from a column onto a floor (2D): a larger μ_r builds a steeper heap.

    Measured (4 mm discs, μ = 0.5, linear law, 1.2 s; about 15 s of run time): 0.6° without rolling
    friction (a tenth of the discs roll away and the rest spreads into three layers), 8.5° with μ_r = 0.3
    (a heap seven diameters high). Margin 5°: the flank fit of a heap this small scatters by a degree or two."""
    from fluidem.case import validate_case
    from fluidem.particles.softsphere import SoftSphereEngine

    angles = {}
    for mu_r in (0.0, 0.3):
        case = validate_case({
            "name": "heap", "gravity": [0.0, -G, 0.0],
            "particles": {"dimensions": 2,
                          "species": [{"name": "p", "diameter": DIAMETER, "density": DENSITY, "count": 300}],
                          "contact": {"model": "linear_spring_dashpot", "stiffness": 1e4, "restitution": 0.3,
                                      "friction": 0.5, "rolling_friction": mu_r},
                          "placement": {"method": "random", "seed": 11, "region_lower": [-0.02, 0.004, 0.0],
                                        "region_upper": [0.02, 0.24, 0.0]}},
            "walls": [{"name": "floor", "kind": "plane", "point": [0.0, 0.0, 0.0], "normal": [0.0, 1.0, 0.0]}],
            "time": {"end": 1.2}})
        eng = SoftSphereEngine(case)
        eng.advance(int(1.2 / eng.dt))
        st = eng.state
        # the heap has settled (without rolling friction a tenth of the discs leave it and keep rolling on the floor)
        assert np.median(np.linalg.norm(st.velocity, axis=1)) < 1e-3, "the heap has settled"
        angles[mu_r] = heap_angle(st.position, st.radius)
    print(f"angle of repose: mu_r = 0: {angles[0.0]:.1f} deg, mu_r = 0.3: {angles[0.3]:.1f} deg")
    assert angles[0.3] > angles[0.0] + 5.0
