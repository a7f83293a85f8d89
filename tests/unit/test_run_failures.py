"""Runs that blow up end as ``failed``: the health checks of ``fluidem.checks`` between compiled chunks.

Each blow-up (too soft contacts for fast particles, a launch at 1e6 m/s, huge gravity, a Hertz law at high
speed, a particle pushed out of the box, an overlap beyond ``checks.max_overlap``, a gas step that fails)
exits with status 1 and one error line, writes summary.json with status ``failed`` and a ``failure`` entry
(the check, the particle, where, when), and leaves in restart.h5 the last checkpoint written before the
failure, never the broken state. The check functions are tested on hand-made states: a particle exactly at
a limit passes, one just beyond fails.
"""
from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import traceback
from pathlib import Path

import numpy as np
import pytest

from fluidem import checks as C
from fluidem.case import read_case_data
from fluidem.checks import ChecksSection, RunChecks, RunFailure
from fluidem.cli import main
from fluidem.io.restart import load_restart
from fluidem.simulation import Simulation

POUR_BOX = (0.096, 0.192)  # the pour case's container [m]
DIAMETER = 0.004  # the pour and tsuji-jet particles [m]


@pytest.fixture(autouse=True, scope="module")
def _restore_numba_threads():
    """In-process runs change Numba's thread count; give later test modules it back."""
    import numba

    before = numba.get_num_threads()
    yield
    numba.set_num_threads(before)


@pytest.fixture
def saved(monkeypatch):
    """Every checkpoint a Simulation writes, as (steps, time, position copy, velocity copy), in order."""
    out = []
    original = Simulation.save_checkpoint

    def save(self, path):
        original(self, path)
        st = self.engine.state
        order = np.argsort(st.ids)
        out.append((self.steps, self.time, st.position[order].copy(), st.velocity[order].copy()))

    monkeypatch.setattr(Simulation, "save_checkpoint", save)
    return out


def cli(argv, capsys):
    """``fluidem ARGV`` in-process: (exit status, stdout, stderr); an escaping exception is a traceback."""
    try:
        rc = main([str(a) for a in argv])
    except SystemExit as exc:
        rc = exc.code
    except Exception:  # noqa: BLE001 - the test inspects it
        out, err = capsys.readouterr()
        return 1, out, err + traceback.format_exc()
    out, err = capsys.readouterr()
    return rc, out, err


def failed_run(argv, out, capsys) -> dict:
    """Run and check the common contract of a failed run; the failure entry of summary.json."""
    rc, stdout, stderr = cli(["run", *argv, "--out", out, "--quiet"], capsys)
    assert rc == 1, stderr
    assert "Traceback" not in stderr
    lines = stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("fluidem: error: run failed: "), stderr
    assert stdout == ""
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "failed"
    failure = summary["failure"]
    assert failure["time_s"] == pytest.approx(summary["sim_time_s"], rel=1e-12)
    assert failure["last_good_time_s"] <= failure["time_s"]
    assert f"t = {failure['time_s']:.6g} s" in lines[0]
    assert failure["check"] in lines[0]
    if failure["particle_id"] is not None:
        assert f"particle {failure['particle_id']}" in lines[0]
        assert 0 <= failure["particle_id"] < summary["n_particles"]
    failure["stderr"] = lines[0]
    failure["summary"] = summary
    return failure


def assert_last_good_checkpoint(out, saved, failure):
    """restart.h5 holds the last checkpoint written before the failure, not the broken state."""
    assert saved, "no checkpoint was written"
    steps, t, position, velocity = saved[-1]
    assert t <= failure["last_good_time_s"] + 1e-12 and failure["last_good_time_s"] <= failure["time_s"]
    arrays, scalars, _ = load_restart(out / "restart.h5")
    assert int(scalars["steps"]) == steps
    order = np.argsort(arrays["state/ids"])
    np.testing.assert_array_equal(arrays["state/position"][order], position)
    np.testing.assert_array_equal(arrays["state/velocity"][order], velocity)
    assert failure["checkpoint_time_s"] == pytest.approx(t, abs=1e-15)
    assert failure["checkpoint"] == str(out / "restart.h5")
    # the broken particle is not where the checkpoint has it (a gas step that fails leaves the particles as they were)
    if failure["check"] != "gas" and failure["position_m"] is not None:
        assert not np.allclose(position[failure["particle_id"]], failure["position_m"])


# ====================================================================== blow-ups through the command line
def test_too_soft_contacts_let_fast_particles_through_the_floor(tmp_path, capsys, saved):
    out = tmp_path / "run"
    f = failed_run(["pour", "--until", "0.05", "--set", "particles.contact.stiffness=1e-3",
                    "--set", "particles.placement.velocity=[0.0, -5.0, 0.0]"], out, capsys)
    assert f["check"] == "domain"
    # beyond the floor (y = 0) by more than one diameter
    assert f["position_m"][1] < -DIAMETER
    assert f["value"] == pytest.approx(-f["position_m"][1], rel=1e-9)
    assert f["limit"] == pytest.approx(DIAMETER)
    assert "container.ymin" in f["message"]
    assert "contact time" in f["hint"] and "particles.placement.velocity" in f["hint"]
    assert_last_good_checkpoint(out, saved, f)


def test_launch_at_a_million_metres_per_second(tmp_path, capsys, saved):
    out = tmp_path / "run"
    f = failed_run(["pour", "--until", "0.05", "--set", "particles.placement.velocity=[1e6, 0.0, 0.0]"], out,
                   capsys)
    assert f["check"] == "domain"
    assert f["position_m"][0] > POUR_BOX[0] + DIAMETER  # out through the right wall
    assert f["value"] == pytest.approx(f["position_m"][0] - POUR_BOX[0], rel=1e-9)
    assert "container.xmax" in f["message"]
    assert "diameters per time step" in f["hint"] and "[1e+06, 0, 0]" in f["hint"]
    # it failed in the first chunk: the checkpoint is that of t = 0
    assert f["last_good_time_s"] == 0.0 and f["checkpoint_time_s"] == 0.0
    assert_last_good_checkpoint(out, saved, f)
    # the summary of the broken state has no infinite or NaN figure (null instead) and no warning was printed
    assert f["summary"]["packing_fraction"] is None or math.isfinite(f["summary"]["packing_fraction"])


def test_huge_gravity(tmp_path, capsys, saved):
    out = tmp_path / "run"
    f = failed_run(["pour", "--until", "0.05", "--set", "gravity=[0.0, -1e7, 0.0]"], out, capsys)
    assert f["check"] == "domain"
    assert f["position_m"][1] < -DIAMETER
    assert "times Earth's" in f["hint"]
    assert_last_good_checkpoint(out, saved, f)


def test_hertz_contacts_at_high_speed(tmp_path, capsys, saved):
    import tomli_w

    data = read_case_data("pour")
    data["particles"]["contact"] = {"model": "hertz_mindlin", "youngs_modulus": 1e8, "poisson_ratio": 0.3,
                                    "restitution": 0.9, "friction": 0.3}
    case = tmp_path / "hertz.toml"
    case.write_text(tomli_w.dumps(data))
    out = tmp_path / "run"
    f = failed_run([case, "--until", "0.01", "--set", "particles.placement.velocity=[0.0, -300.0, 0.0]"], out,
                   capsys)
    assert f["check"] == "overlap"
    assert f["limit"] == ChecksSection().max_overlap
    assert f["value"] > f["limit"]
    assert "time.impact_velocity" in f["hint"]
    assert_last_good_checkpoint(out, saved, f)


def test_a_particle_pushed_out_of_the_box(tmp_path, capsys, saved, monkeypatch):
    """A particle moved by hand 3 diameters beyond the right wall after t = 5 ms: the chunk that did it fails,
    and restart.h5 keeps the last checkpoint before (every 2 ms)."""
    from fluidem.particles.softsphere import SoftSphereEngine

    original = SoftSphereEngine.advance
    victim = 17
    where = np.array([POUR_BOX[0] + 3.0 * DIAMETER, 0.05, 0.002])

    def advance(self, nsteps):
        original(self, nsteps)
        if self.time >= 0.005:
            k = int(np.flatnonzero(self.state.ids == victim)[0])
            self.state.position[k] = where

    monkeypatch.setattr(SoftSphereEngine, "advance", advance)
    out = tmp_path / "run"
    f = failed_run(["pour", "--until", "0.02", "--set", "output.checkpoint_interval=0.002",
                    "--set", "output.probe_interval=0.001"], out, capsys)
    assert f["check"] == "domain" and f["particle_id"] == victim
    assert f["position_m"] == pytest.approx(list(where), abs=0.0)
    assert f["value"] == pytest.approx(3.0 * DIAMETER)  # beyond the wall plane x = 0.096
    assert f["limit"] == pytest.approx(DIAMETER)
    assert 0.005 <= f["time_s"] < 0.0075 and f["last_good_time_s"] < 0.005
    assert_last_good_checkpoint(out, saved, f)
    assert saved[-1][1] == pytest.approx(0.004, abs=2e-5)
    # the outputs up to the failure are kept, none of the broken state
    import csv

    with open(out / "probes.csv", newline="") as fh:
        times = [float(r["time_s"]) for r in csv.DictReader(fh)]
    assert times[0] == 0.0 and 0.004 - 2e-5 < times[-1] < f["time_s"]
    from fluidem.io.snapshots import read_snapshot

    assert read_snapshot(out / "particles.h5")["time"] < f["time_s"]


def test_an_overlap_beyond_the_limit(tmp_path, capsys, saved, write_particles):
    """Two particles stacked on a floor, their contact so soft that the upper one's weight presses them
    together by 0.6 diameters at rest: the run fails once the overlap passes checks.max_overlap = 0.5."""
    import tomli_w

    d, rho, g = DIAMETER, 2500.0, 9.81
    m = rho * math.pi / 6.0 * d**3
    k = m * g / (0.6 * d)  # static overlap m g / k = 0.6 d
    path = write_particles([[0.006, 0.5 * d, 0.002], [0.006, 1.5 * d + 1e-4, 0.002]], d)
    data = {
        "name": "soft-stack", "gravity": [0.0, -g, 0.0],
        "particles": {"dimensions": 2,
                      "species": [{"name": "p", "diameter": d, "density": rho, "count": 2}],
                      "contact": {"model": "linear_spring_dashpot", "stiffness": k, "restitution": 0.3,
                                  "friction": 0.3},
                      "wall_contact": {"model": "linear_spring_dashpot", "stiffness": 1000.0, "restitution": 0.3,
                                       "friction": 0.3},
                      "placement": {"method": "file", "file": str(path)}},
        "walls": [{"name": "box", "kind": "box", "lower": [0.0, 0.0, 0.0], "upper": [0.012, 0.05, 0.004]}],
        "time": {"end": 0.5},
        "output": {"checkpoint_interval": 0.01},
        "checks": {"max_overlap": 0.5},
    }
    case = tmp_path / "stack.toml"
    case.write_text(tomli_w.dumps(data))
    out = tmp_path / "run"
    f = failed_run([case], out, capsys)
    assert f["check"] == "overlap"
    assert f["particle_id"] in (0, 1) and "particle 0" in f["message"] and "particle 1" in f["message"]
    assert f["limit"] == 0.5
    assert 0.5 < f["value"] < 1.2  # past the limit, below twice the static overlap (the undamped overshoot)
    assert "particles.contact.stiffness" in f["hint"]
    assert_last_good_checkpoint(out, saved, f)


def test_a_gas_step_that_fails(tmp_path, capsys, saved, monkeypatch):
    """The gas solver raises GasConvergenceError from t = 5 ms on: status failed, check "gas", no traceback."""
    from fluidem.gas.solver import GasConvergenceError, GasSolver

    original = GasSolver.advance

    def advance(self, state, dt, t=0.0, **kw):
        if t >= 0.005 - 1e-12:
            raise GasConvergenceError(f"gas step from t = {t:.6g} s with dt = {dt:g} s did not converge (mass "
                                      "residual 0.5); Courant number 3.1: keep it below 1 (0.5 with "
                                      "convection='tvd'), see GasSolver.max_time_step")
        return original(self, state, dt, t, **kw)

    monkeypatch.setattr(GasSolver, "advance", advance)
    out = tmp_path / "run"
    f = failed_run(["tsuji-jet", "--until", "0.01", "--set", "particles.species.0.count=300",
                    "--set", "output.checkpoint_interval=0.002"], out, capsys)
    assert f["check"] == "gas"
    assert "gas step from t = 0.005 s" in f["message"] and "did not converge" in f["message"]
    assert "gas.dt = 0.0002 s" in f["hint"] and "Courant" in f["hint"]
    assert f["particle_id"] is not None  # the fastest particle, named in the hint
    assert f"particle {f['particle_id']}" in f["hint"]
    assert f["time_s"] == pytest.approx(0.005, abs=1e-9)
    assert_last_good_checkpoint(out, saved, f)
    assert saved[-1][1] == pytest.approx(0.004, abs=1e-9)


def test_absurd_particle_speeds_make_the_gas_diverge(tmp_path, capsys, saved):
    """300 particles launched at 1e4 m/s drag the gas along: its first step does not converge."""
    out = tmp_path / "run"
    f = failed_run(["tsuji-jet", "--until", "0.01", "--set", "particles.species.0.count=300",
                    "--set", "particles.placement.velocity=[0.0, 1e4, 0.0]"], out, capsys)
    assert f["check"] == "gas"
    assert f["time_s"] == 0.0 and "gas step from t = 0 s" in f["message"] and "did not converge" in f["message"]
    assert "Courant number" in f["message"]
    assert "moves at 1e+04 m/s" in f["hint"] and "[0, 10000, 0]" in f["hint"]
    assert f["checkpoint_time_s"] == 0.0
    assert_last_good_checkpoint(out, saved, f)


def test_absurd_particle_speeds_in_a_full_coupled_bed(tmp_path, capsys, saved):
    """The full tsuji-jet bed launched at 1e4 m/s leaves the gas grid within a few gas steps and the exchange
    then refuses the particles: the failure names the particle out of the domain and adds the gas's error."""
    out = tmp_path / "run"
    f = failed_run(["tsuji-jet", "--until", "0.01", "--set", "particles.placement.velocity=[0.0, 1e4, 0.0]"],
                   out, capsys)
    assert f["check"] == "domain"
    assert f["position_m"][1] > 0.9 + DIAMETER  # above the column and its grid
    assert "then the gas step failed" in f["message"]
    assert_last_good_checkpoint(out, saved, f)


def test_failed_run_from_a_real_process_has_no_traceback(tmp_path):
    out = tmp_path / "run"
    import fluidem

    # the fluidem these tests import, wherever the process starts
    src = str(Path(fluidem.__file__).resolve().parents[1])
    env = dict(os.environ, PYTHONUNBUFFERED="1",
               PYTHONPATH=os.pathsep.join([src, *filter(None, [os.environ.get("PYTHONPATH")])]))
    p = subprocess.run([sys.executable, "-m", "fluidem", "run", "pour", "--until", "0.01", "--out", str(out),
                        "--set", "particles.placement.velocity=[1e6, 0.0, 0.0]", "--quiet"], env=env,
                       capture_output=True, text=True, timeout=600, cwd=tmp_path, check=False)
    assert p.returncode == 1
    assert p.stdout == ""
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("fluidem: error: run failed: domain check failed"), p.stderr
    assert "RuntimeWarning" not in p.stderr
    assert json.loads((out / "summary.json").read_text())["status"] == "failed"


def test_the_checks_section_is_validated(tmp_path, capsys):
    rc, _, err = cli(["run", "pour", "--out", tmp_path / "run", "--set", "checks.max_overlap=1.5"], capsys)
    assert rc == 2 and "checks.max_overlap = 1.5" in err
    rc, _, err = cli(["run", "pour", "--out", tmp_path / "run", "--set", "checks.max_overlaps=0.1"], capsys)
    assert rc == 2 and "checks.max_overlaps" in err and "max_overlap" in err
    assert not (tmp_path / "run").exists()


# ====================================================================== the check functions on hand-made states
def test_scan_finds_the_first_non_finite_particle_and_leaves_it_out():
    pos = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [3.0, 0.0, 0.0]])
    vel = np.zeros((4, 3))
    radius, mass = np.full(4, 0.25), np.full(4, 2.0)
    assert C.scan(pos, radius, velocity=vel, mass=mass).first_bad == -1
    vel[2, 1] = np.inf
    pos[3, 0] = np.nan
    vel[0, 0] = 1.0
    sc = C.scan(pos, radius, velocity=vel, mass=mass)
    assert sc.first_bad == 2
    assert sc.kinetic == 1.0 and sc.mass_total == 8.0  # particles 2 and 3 left out of the energy, not the mass
    omega = np.zeros((4, 3))
    omega[1, 2] = np.nan
    assert C.scan(pos, radius, velocity=np.zeros((4, 3)), omega=omega).first_bad == 1


def test_domain_exactly_at_the_margin_passes_and_just_beyond_fails():
    # a floor y = 0 (normal +y) and a wall x = 1 (normal −x); diameter 0.5, margin 1 diameter: limit 0.5 m
    walls = {"wall_point": np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]),
             "wall_normal": np.array([[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])}
    radius = np.array([0.25, 0.25])
    pos = np.array([[0.5, -0.5, 0.0], [1.5, 0.5, 0.0]])  # both exactly one diameter behind a wall
    sc = C.scan(pos, radius, margin=1.0, **walls)
    assert (sc.excess, sc.excess_i) == (0.0, -1)
    pos[1, 0] = np.nextafter(1.5, 2.0)
    sc = C.scan(pos, radius, margin=1.0, **walls)
    assert (sc.excess_i, sc.excess_where) == (1, 1) and 0.0 < sc.excess < 1e-15
    pos[0, 1] = -0.75  # further out than particle 1: the worst is reported
    sc = C.scan(pos, radius, margin=1.0, **walls)
    assert (sc.excess_i, sc.excess, sc.excess_where) == (0, 0.25, 0)
    # margin 0: the centre may reach the plane, not pass it
    assert C.scan(np.array([[0.5, 0.0, 0.0]]), radius[:1], margin=0.0, **walls).excess_i == -1
    assert C.scan(np.array([[0.5, -1e-12, 0.0]]), radius[:1], margin=0.0, **walls).excess_i == 0


def test_domain_of_a_box_of_bounds():
    # the gas grid [0, 1] x [0, 2], no bound along z; diameter 0.25, margin 2 diameters: limit 0.5 m
    box = {"lower": np.array([0.0, 0.0, -np.inf]), "upper": np.array([1.0, 2.0, np.inf]), "margin": 2.0}
    radius = np.array([0.125, 0.125])
    pos = np.array([[-0.5, 1.0, 1e9], [0.5, 2.5, 0.0]])  # exactly at the limit (left, top)
    assert C.scan(pos, radius, **box).excess_i == -1
    pos[1, 1] = 2.625
    sc = C.scan(pos, radius, **box)
    assert (sc.excess_i, sc.excess) == (1, 0.125)
    assert sc.excess_where == -1 - (2 * 1 + 1)  # y, upper side
    pos[0, 0] = -1.0
    sc = C.scan(pos, radius, **box)
    assert (sc.excess_i, sc.excess, sc.excess_where) == (0, 0.5, -1)  # x, lower side


def test_largest_overlap_of_pairs_and_walls():
    radius = np.array([0.5, 0.5, 0.25])
    pos = np.array([[0.0, 10.0, 0.0], [0.75, 10.0, 0.0], [5.0, 0.125, 0.0]])
    row_start = np.array([0, 2, 2, 2])
    partner = np.array([1, 2], dtype=np.int32)  # pairs (0, 1) touching and (0, 2) apart
    assert C.largest_pair_overlap(pos, radius, row_start, partner) == (0.25, 0, 1)  # 0.25 m of 1 m
    # a floor y = 0: particle 2 (diameter 0.5) overlaps it by 0.125 m, 0.25 of its diameter
    floor = {"wall_point": np.zeros((1, 3)), "wall_normal": np.array([[0.0, 1.0, 0.0]])}
    sc = C.scan(pos, radius, **floor)
    assert (sc.wall_rel, sc.wall_i, sc.wall_w) == (0.25, 2, 0)
    pos[2, 1] = 0.0  # now by 0.25 m, half its diameter
    assert C.scan(pos, radius, **floor).wall_rel == 0.5
    # nothing touches
    pos[1, 0] = 2.0
    pos[2, 1] = 1.0
    assert C.largest_pair_overlap(pos, radius, row_start, partner) == (0.0, -1, -1)
    assert C.scan(pos, radius, **floor).wall_rel < 0.0
    assert C.scan(pos, radius).wall_rel == -np.inf  # no walls


def test_scan_measures_the_height_span_along_up():
    pos = np.array([[0.0, 1.0, 5.0], [0.0, -2.0, 7.0]])
    sc = C.scan(pos, np.full(2, 0.1), up=np.array([0.0, 1.0, 0.0]))
    assert (sc.height_lo, sc.height_hi) == (-2.0, 1.0)


def test_kinetic_energy_jump_at_the_factor_passes_and_above_fails():
    assert not C.kinetic_energy_jumped(1000.0, 1.0, 0.5, 1000.0)
    assert C.kinetic_energy_jumped(np.nextafter(1000.0, 2000.0), 1.0, 0.5, 1000.0)
    # the supply scale counts when it is the larger
    assert not C.kinetic_energy_jumped(4000.0, 1.0, 4.0, 1000.0)
    assert C.kinetic_energy_jumped(4001.0, 1.0, 4.0, 1000.0)
    # nothing to compare with: no failure
    assert not C.kinetic_energy_jumped(1.0, 0.0, 0.0, 1000.0)


def test_energy_supply_covers_a_fall_and_the_gas_speed():
    # 2 kg falling through 3 m under 10 m/s^2: 60 J; free fall for 0.5 s: (10*0.5)^2/2 * 2 = 25 J; 4 m/s: 16 J
    assert C.energy_supply(2.0, 10.0, 3.0, 4.0, 0.5) == pytest.approx(60.0 + 25.0 + 16.0)
    assert C.energy_supply(2.0, 0.0, 3.0, 0.0, 0.5) == 0.0


def test_kinetic_energies_count_rotation():
    args = (np.array([2.0]), np.array([[3.0, 0.0, 4.0]]), np.array([0.5]), np.array([[0.0, 0.0, 2.0]]))
    assert C.kinetic_energies(*args) == pytest.approx([25.0 + 1.0])
    m, v, inertia, w = args
    assert C.scan(np.zeros((1, 3)), np.array([0.1]), velocity=v, mass=m, inertia=inertia, omega=w).kinetic == 26.0


# ====================================================================== RunChecks on small engines
def test_overlap_exactly_at_the_limit_passes_and_just_above_fails(two_particles):
    eng = two_particles(overlap=0.3 * DIAMETER)
    rel = C.largest_pair_overlap(eng.state.position, eng.state.radius, eng.row_start, eng.partner)[0]
    assert rel == pytest.approx(0.3, rel=1e-9)
    checks = RunChecks(ChecksSection(max_overlap=rel), eng)
    checks.start()
    checks()
    checks = RunChecks(ChecksSection(max_overlap=np.nextafter(rel, 0.0)), eng)
    checks.start()
    with pytest.raises(RunFailure) as info:
        checks()
    f = info.value
    assert f.check == "overlap" and f.particle_id == 0 and f.value == rel
    assert "particle 1" in f.message
    # off: no check but the finite one
    checks = RunChecks(ChecksSection(max_overlap=0.01, enabled=False), eng)
    checks()


def test_a_kinetic_energy_jump_names_the_particle(two_particles):
    eng = two_particles(overlap=0.0, vel=[[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]])  # no gravity, no walls
    checks = RunChecks(ChecksSection(), eng)
    checks.start()
    eng.state.velocity[1] *= math.sqrt(2001.0)  # KE m/2 (1 + 2001) = 1001 × before, m (2 particles at 1 m/s)
    with pytest.raises(RunFailure) as info:
        checks()
    f = info.value
    assert f.check == "kinetic_energy" and f.particle_id == 1
    m = float(eng.state.mass[0])
    assert f.value == pytest.approx(0.5 * m * 2002.0)
    assert f.limit == pytest.approx(1000.0 * m)  # 1000 × the kinetic energy before
    assert "time step" in f.hint
    # a jump below the factor passes
    eng.state.velocity[1] = [-math.sqrt(1997.0), 0.0, 0.0]
    checks()


def test_non_finite_names_the_particle_and_no_longer_blames_stiffness(two_particles):
    eng = two_particles(overlap=0.0)
    checks = RunChecks(ChecksSection(enabled=False), eng)
    checks.start()
    eng.state.velocity[1, 0] = np.nan
    with pytest.raises(RunFailure) as info:
        checks()
    f = info.value
    assert f.check == "non_finite" and f.particle_id == int(eng.state.ids[1])
    assert "velocity" in f.message
    assert "too stiff" not in str(f)
