"""Shared test fixtures. Each fixture is a factory: call it with what the test needs.

Plain functions and constants shared by several test modules live in ``tests/_helpers/``
(``from _helpers.coupling import MAPPINGS``); test modules never import one another.

Engines are built the way a user would build one: a case dictionary validated by
``fluidem.case.validate_case`` whose particles come from a CSV file
(``placement.method = "file"``) written to the test's ``tmp_path``. When a test
needs an initial spin (which a particle file cannot give) the state is built with
``ParticleState.create`` and handed to the engine.

Factories
---------
contact_law(model, **changes)      contact-law dict with test defaults for a registered model
write_particles(pos, diam, ...)    CSV particle file, returns its path
make_case(pos, diam, ...)          validated ``Case`` with the particles from a file
make_engine(pos, diam, ...)        ``SoftSphereEngine`` of that case (optionally with initial spins)
two_particles(overlap=..., ...)    engine of two spheres along x, overlapping by ``overlap`` [m]
tiny_bed_case(...)                 case of a small 3D bed dropped from a lattice into a box
stopped_and_resumed(case, stop)    (whole, first, again): the case run in one go; run to ``stop`` with a
                                   run directory; and resumed from that directory's checkpoint to the end
"""
from __future__ import annotations

import contextlib
import io
import shutil
from pathlib import Path

import numpy as np
import pytest

from fluidem.case import validate_case
from fluidem.particles.contact import contact_models
from fluidem.particles.softsphere import SoftSphereEngine
from fluidem.state import ParticleState

# Test material: 4 mm glass-like spheres (the benchmark bed of PEERS.md).
DIAMETER = 4e-3  # [m]
DENSITY = 2500.0  # [kg/m^3]



def law_dict(model: str, **changes) -> dict:
    """Contact-law dictionary of a registered model with the test defaults, updated by ``changes``."""
    if model not in contact_models:
        raise KeyError(f"{model!r} is not a registered contact model: {contact_models.names()}")
    # each model's ``example`` parameters (a valid law of the model): the registry-parametrised tests cover a
    # new model without further code
    return {"model": model, "restitution": 0.9, "friction": 0.3, **contact_models.get(model).example, **changes}


def write_particle_csv(path, pos, diam, vel=None, species=None):
    """Write x,y,z,diameter[,species][,vx,vy,vz] rows; returns ``path``."""
    pos = np.atleast_2d(np.asarray(pos, float))
    diam = np.broadcast_to(np.asarray(diam, float), (pos.shape[0],))
    cols = [pos[:, 0], pos[:, 1], pos[:, 2], diam]
    header = ["x", "y", "z", "diameter"]
    if species is not None:
        cols.append(np.broadcast_to(np.asarray(species, np.int64), (pos.shape[0],)))
        header.append("species")
    if vel is not None:
        vel = np.atleast_2d(np.asarray(vel, float))
        cols += [vel[:, 0], vel[:, 1], vel[:, 2]]
        header += ["vx", "vy", "vz"]
    with open(path, "w") as f:
        f.write(",".join(header) + "\n")
        for row in zip(*cols):
            f.write(",".join(repr(int(v)) if isinstance(v, np.integer) else repr(float(v)) for v in row) + "\n")
    return path


def case_dict(file, n, *, contact, walls=(), gravity=(0.0, 0.0, 0.0), dimensions=3, dt=None,
              impact_velocity=1.0, density=DENSITY, diameter=DIAMETER, species=None, skin=None,
              wall_contact=None, end=1.0) -> dict:
    """Case dictionary with particles read from ``file`` (one species unless ``species`` is given)."""
    data = {
        "name": "test",
        "gravity": list(gravity),
        "particles": {
            "dimensions": dimensions,
            "species": species if species is not None else
            [{"name": "p", "diameter": diameter, "density": density, "count": n}],
            "contact": contact,
            "placement": {"method": "file", "file": str(file)},
        },
        "walls": [dict(w) for w in walls],
        "time": {"end": end, "impact_velocity": impact_velocity},
    }
    if dt is not None:
        data["time"]["dt"] = dt
    if skin is not None:
        data["neighbours"] = {"skin": skin}
    if wall_contact is not None:
        data["particles"]["wall_contact"] = wall_contact
    return data


@pytest.fixture
def contact_law():
    """``contact_law(model, **changes)`` -> contact-law dict with test defaults."""
    return law_dict


@pytest.fixture
def write_particles(tmp_path):
    """``write_particles(pos, diam, vel=None, species=None, name=...)`` -> path of a particle CSV."""
    counter = iter(range(10**6))

    def _write(pos, diam, vel=None, species=None, name=None):
        path = tmp_path / (name or f"particles_{next(counter)}.csv")
        return write_particle_csv(path, pos, diam, vel, species)

    return _write


@pytest.fixture
def make_case(write_particles):
    """``make_case(pos, diam, vel=None, *, contact, walls=(), gravity=(0,0,0), dimensions=3, dt=None, ...)``."""

    def _make(pos, diam, vel=None, *, species_index=None, **kw):
        pos = np.atleast_2d(np.asarray(pos, float))
        path = write_particles(pos, diam, vel, species_index)
        return validate_case(case_dict(path, pos.shape[0], **kw))

    return _make


@pytest.fixture
def make_engine(make_case):
    """``make_engine(pos, diam, vel=None, *, omega=None, **case_kw)`` -> SoftSphereEngine.

    With ``omega`` the particle state is built directly (a file cannot carry spins)
    and the engine evaluates its first forces with those spins.
    """

    def _make(pos, diam, vel=None, *, omega=None, **kw):
        case = make_case(pos, diam, vel, **kw)
        if omega is None:
            return SoftSphereEngine(case)
        pos = np.atleast_2d(np.asarray(pos, float))
        n = pos.shape[0]
        vel = np.zeros((n, 3)) if vel is None else np.atleast_2d(np.asarray(vel, float))
        diam = np.broadcast_to(np.asarray(diam, float), (n,))
        dens = np.array([s.density for s in case.particles.species])
        state = ParticleState.create(pos.copy(), vel.copy(), diam.copy(), np.zeros(n, np.int64), dens)
        state.omega[...] = np.atleast_2d(np.asarray(omega, float))
        return SoftSphereEngine(case, state=state)

    return _make


@pytest.fixture
def two_particles(make_engine):
    """``two_particles(overlap=..., model=..., diameters=(d, d), vel=..., omega=..., **law)``.

    Two spheres on the x axis, particle 0 at the origin and particle 1 at
    x = a_0 + a_1 − overlap; no gravity, no walls.
    """

    def _make(overlap=0.0, model="linear_spring_dashpot", diameters=(DIAMETER, DIAMETER), vel=None, omega=None,
              dimensions=3, dt=None, **law):
        d0, d1 = diameters
        # 0.5 d0 + 0.5 d1 is exactly the engine's a_0 + a_1, so overlap=0 means touching to the last bit
        pos = np.array([[0.0, 0.0, 0.0], [(0.5 * d0 + 0.5 * d1) - overlap, 0.0, 0.0]])
        return make_engine(pos, np.array([d0, d1]), vel, omega=omega, contact=law_dict(model, **law),
                           dimensions=dimensions, dt=dt)

    return _make


@pytest.fixture
def tiny_bed_case(tmp_path):
    """``tiny_bed_case(n=..., model=..., box=(Lx, Ly, Lz), **law)`` -> Case of a bed dropped from a lattice.

    3D box wall named ``box`` with lower corner at the origin, gravity −9.81 along z,
    monodisperse spheres of ``DIAMETER`` on a loose lattice (placement ``lattice``).
    """

    def _make(n=150, model="linear_spring_dashpot", box=(5 * DIAMETER, 5 * DIAMETER, 20 * DIAMETER), dt=None,
              seed=7, **law):
        data = {
            "name": "tiny-bed",
            "gravity": [0.0, 0.0, -9.81],
            "particles": {
                "dimensions": 3,
                "species": [{"name": "p", "diameter": DIAMETER, "density": DENSITY, "count": n}],
                "contact": law_dict(model, **law),
                "placement": {"method": "lattice", "spacing": 1.1, "seed": seed},
            },
            "walls": [{"name": "box", "kind": "box", "lower": [0.0, 0.0, 0.0], "upper": list(box)}],
            "time": {"end": 1.0},
        }
        if dt is not None:
            data["time"]["dt"] = dt
        return validate_case(data)

    return _make


@pytest.fixture
def stopped_and_resumed(tmp_path):
    """Factory: a run made in one go, the same run stopped at ``stop`` (checkpoint in tmp_path/"run") and
    the one resumed from it with ``Simulation.resume``, each run to the case's end: (whole, first, again)."""
    from fluidem.simulation import Simulation

    def make(case, stop):
        whole = Simulation(case)
        whole.run()
        first = Simulation(case, out_dir=tmp_path / "run")
        first.run(until=stop)
        again = Simulation.resume(tmp_path / "run")
        again.run()
        return whole, first, again

    return make


@pytest.fixture(scope="session")
def pour_run(tmp_path_factory) -> Path:
    """A 0.05 s run of the built-in pour case, made once per test run (plotting and report tests share it)."""
    out = tmp_path_factory.getbasetemp() / "pour-0.05s"
    if not (out / "summary.json").exists():
        import numba

        from fluidem.cli import main

        if out.exists():
            shutil.rmtree(out)
        threads = numba.get_num_threads()
        try:
            with contextlib.redirect_stdout(io.StringIO()):  # the run prints its summary
                assert main(["run", "pour", "--until", "0.05", "--out", str(out), "--quiet"]) == 0
        finally:
            numba.set_num_threads(threads)  # a run picks its own thread count; later tests get theirs back
    return out
