"""Periodic box sides in the event-driven hard-sphere engine (``walls.periodic`` with model hard_sphere).

* A free particle crossing a periodic side keeps its velocity bit for bit and re-enters through the opposite
  side: position + image · L is x0 + v t to round-off of the coordinates.
* A collision across the seam gives the post-collision velocities and spins of the same collision in the
  box's interior (Hoomans 1996 eqs 1–29 see only the offset of the centres), to round-off.
* A fully periodic elastic frictionless gas without gravity has no wall: Σ m v and Σ ½ m v² are conserved
  (eqs 1–2, 4–5 and 23 with e = 1, μ = 0) to round-off over thousands of collisions.
* A run restored from a checkpoint continues bit for bit, image counts included.
"""
from __future__ import annotations

import copy

import numpy as np
import pytest

from fluidem.case import read_case_data, validate_case
from fluidem.errors import CaseError
from fluidem.io.restart import load_restart, save_restart
from fluidem.particles.hardsphere import HardSphereEngine
from fluidem.state import ParticleState

from _helpers.periodic import DIAMETER as D, periodic_case_dict


def hard(e=1.0, mu=0.0, collapse_time=0.0):
    return {"model": "hard_sphere", "restitution": e, "friction": mu, "collapse_time": collapse_time}


def engine(tmp_path, pos, vel, *, upper, periodic, contact=None, dt=1e-4, name="p.csv"):
    data = periodic_case_dict(tmp_path / name, pos, vel, upper=upper, periodic=periodic,
                              contact=contact or hard())
    data["time"]["dt"] = dt
    return HardSphereEngine(validate_case(data))


@pytest.mark.parametrize("axis", [0, 1, 2])
@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_crossing_keeps_the_velocity_and_re_enters(tmp_path, axis, sign):
    L = 10 * D
    x0 = np.full(3, 5 * D)
    v = np.zeros(3)
    v[axis] = 2.0 * sign
    eng = engine(tmp_path, [x0], [v], upper=(L, L, L), periodic=["x", "y", "z"])
    for k in range(50):
        eng.advance(10)
        st = eng.state
        assert np.array_equal(st.velocity[0], v)
        assert np.all(st.position[0] >= -0.5 * eng.skin) and np.all(st.position[0] <= L + 0.5 * eng.skin)
        unwrapped = st.position[0] + st.image[0] * L
        np.testing.assert_allclose(unwrapped, x0 + v * eng.time, rtol=0, atol=1e-12)
    assert st.image[0, axis] == sign * 2 and eng.collisions == 0  # 0.1 m in a 0.04 m box: two crossings


def _two(tmp_path, xa, xb, name):
    """Two spheres approaching along x with an offset in y, spinning: one oblique, frictional collision."""
    L = 10 * D
    va, vb = [0.5, 0.1, -0.05], [-0.5, 0.0, 0.1]
    eng = engine(tmp_path, [xa, xb], [va, vb], upper=(L, L, L), periodic=["x"], contact=hard(0.9, 0.3),
                 name=name)
    eng.state.omega[:] = [[10.0, -20.0, 30.0], [-5.0, 15.0, 0.0]]
    eng.record_collisions(10)
    eng.advance(40)
    assert eng.collisions == 1 and eng.wall_collisions == 0  # the pair
    return eng


def test_a_collision_across_the_seam_equals_one_in_the_interior(tmp_path):
    L = 10 * D
    y, z = 5 * D, 5 * D
    seam = _two(tmp_path, [L - 0.5 * D, y, z], [D, y + 0.3 * D, z], "seam.csv")
    inner = _two(tmp_path, [4 * D, y, z], [5.5 * D, y + 0.3 * D, z], "inner.csv")
    np.testing.assert_allclose(seam.state.velocity, inner.state.velocity, rtol=0, atol=1e-14)
    np.testing.assert_allclose(seam.state.omega, inner.state.omega, rtol=0, atol=1e-12)  # |ω| ~ 60 rad/s
    assert seam.logged[0, 0] == pytest.approx(inner.logged[0, 0], abs=1e-15)
    assert not np.array_equal(seam.state.velocity, [[0.5, 0.1, -0.05], [-0.5, 0.0, 0.1]])
    # the offset of the centres is the same too (unwrapped positions, shifted by 4.5 D in x)
    shift = np.array([L - 4.5 * D, 0.0, 0.0])
    np.testing.assert_allclose(seam.state.position[0] + seam.state.image[0] * L - shift,
                               inner.state.position[0], rtol=0, atol=1e-15)


def _gas(tmp_path, contact, seed=3, m=5, spacing=5e-3):
    """m³ spheres on a lattice in a fully periodic cube (no walls), random velocities of about 1 m/s."""
    L = m * spacing
    g = (np.arange(m) + 0.5) * spacing
    pos = np.stack(np.meshgrid(g, g, g, indexing="ij"), -1).reshape(-1, 3)
    vel = np.random.default_rng(seed).normal(0.0, 1.0, pos.shape)
    return engine(tmp_path, pos, vel, upper=(L, L, L), periodic=["x", "y", "z"], contact=contact)


def test_periodic_elastic_gas_conserves_momentum_and_energy(tmp_path):
    eng = _gas(tmp_path, hard(1.0, 0.0))
    assert len(eng.walls.planes) == 0
    m = eng.state.mass[:, None]
    p0 = (m * eng.state.velocity).sum(0)
    e0 = 0.5 * (m * eng.state.velocity**2).sum()
    scale = (m * np.abs(eng.state.velocity)).sum()
    eng.advance(1000)
    p1 = (m * eng.state.velocity).sum(0)
    e1 = 0.5 * (m * eng.state.velocity**2).sum()
    assert eng.collisions > 10_000 and eng.wall_collisions == 0
    assert np.all(np.abs(eng.state.image).sum(0) > 0)  # crossings along every axis
    assert np.max(np.abs(p1 - p0)) < 1e-14 * scale
    assert abs(e1 - e0) < 1e-13 * e0
    assert np.all(np.abs(eng.state.omega) == 0.0)
    # no overlap between nearest images (to round-off of the contact distance)
    i, j = np.triu_indices(eng.state.n, 1)
    d = np.linalg.norm(eng.minimum_image(eng.state.position[i] - eng.state.position[j]), axis=1)
    assert d.min() > D * (1.0 - 1e-9)


def test_restored_periodic_run_continues_bit_for_bit(tmp_path):
    whole = _gas(tmp_path, hard(0.8, 0.3, collapse_time=1e-5), seed=5)
    whole.advance(100)
    save_restart(tmp_path / "r.h5", whole.checkpoint_arrays(), whole.checkpoint_scalars(), whole.case.to_toml())
    whole.advance(100)
    arrays, scalars, _ = load_restart(tmp_path / "r.h5")
    state = ParticleState(**{k[len("state/"):]: v.copy() for k, v in arrays.items() if k.startswith("state/")})
    again = HardSphereEngine(whole.case, state=state)
    again.restore(arrays, scalars)
    again.advance(100)
    assert again.collisions == whole.collisions > 500 and whole.rebuilds > 10
    assert np.any(whole.state.image != 0)
    for k in ("position", "velocity", "omega", "image"):
        np.testing.assert_array_equal(getattr(again.state, k), getattr(whole.state, k))
    assert again.energies() == whole.energies()


def test_a_stopped_periodic_run_resumes_bit_for_bit(tmp_path, stopped_and_resumed):
    """The same through ``Simulation``: a run stopped halfway and resumed from its checkpoint ends where the
    run made in one go ends, image counts included."""
    L = 5 * 5e-3
    g = (np.arange(5) + 0.5) * 5e-3
    pos = np.stack(np.meshgrid(g, g, g, indexing="ij"), -1).reshape(-1, 3)
    vel = np.random.default_rng(7).normal(0.0, 1.0, pos.shape)
    data = periodic_case_dict(tmp_path / "gas.csv", pos, vel, upper=(L, L, L), periodic=["x", "y"],
                              contact=hard(0.8, 0.3, collapse_time=1e-5))
    data["time"].update({"dt": 1e-4, "end": 0.02})
    whole, _, again = stopped_and_resumed(validate_case(data), 0.01)
    a, b = whole.engine, again.engine
    assert a.steps == b.steps == 200 and a.collisions == b.collisions > 500 and a.wall_collisions > 0
    assert np.any(a.state.image[:, :2] != 0) and np.all(a.state.image[:, 2] == 0)
    for k in ("position", "velocity", "omega", "image"):
        np.testing.assert_array_equal(getattr(b.state, k), getattr(a.state, k))


def test_a_box_too_short_for_the_cut_off_is_refused(tmp_path):
    data = periodic_case_dict(tmp_path / "p.csv", [[D, D, D]], upper=(10 * D, 2.2 * D, 10 * D), periodic=["y"],
                              contact=hard())
    with pytest.raises(CaseError, match=r"periodic along y with length .* below twice the neighbour cut-off"):
        HardSphereEngine(validate_case(data))


def test_periodic_sides_with_gas_are_refused():
    data = read_case_data("tsuji-jet")
    data["walls"][0]["periodic"] = ["x"]
    data["gas"]["boundaries"]["left"] = {"kind": "periodic"}
    data["gas"]["boundaries"]["right"] = {"kind": "periodic"}
    data["particles"]["contact"] = hard(0.9, 0.3)
    data["particles"].pop("wall_contact", None)
    with pytest.raises(CaseError, match=r"periodic = \['x'\] and a gas; the hard-sphere engine .* without gas"):
        HardSphereEngine(validate_case(copy.deepcopy(data)))
