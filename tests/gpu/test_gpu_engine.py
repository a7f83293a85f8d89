"""The GPU soft-sphere engine gives the CPU engine's forces, trajectories and checkpoints.

Tolerances. The GPU engine evaluates the same contact law (the same Python source, compiled for the
device) and the same integrator expressions; what differs is the order in which each particle's contact
forces are added (the GPU walks its full row, the CPU the half list slab by slab), and on a real GPU fused
multiply-adds. So forces agree to round-off: 1e-12 of the largest force is 1e4 times the double-precision
epsilon, room for sums of ~20 terms. Trajectories over a few hundred steps of a dense, frictional packing
amplify round-off only a little: positions to 1e-12 of the box size.
"""
from __future__ import annotations

import numpy as np
import pytest

from fluidem.case import validate_case
from fluidem.particles.softsphere import SoftSphereEngine
from fluidem.particles.softsphere_gpu import SoftSphereGPUEngine, cuda_available

FORCE_RTOL = 1e-12  # of the largest force or torque (module docstring)
POSITION_RTOL = 1e-12  # of the box size

pytestmark = pytest.mark.skipif(not cuda_available(), reason="numba.cuda has no GPU or simulator in this process "
                                "(tests/unit/test_gpu_device.py runs these under NUMBA_ENABLE_CUDASIM=1)")


def _gpu(case, state):
    return SoftSphereGPUEngine(case.with_overrides({"device": "gpu"}), state=state)


def _close(a, b, rtol, scale=None):
    scale = np.abs(a).max() if scale is None else scale
    return float(np.abs(a - b).max() / scale) if scale > 0 else float(np.abs(a - b).max())


@pytest.mark.parametrize("model", ["hertz_mindlin", "linear_spring_dashpot"])
def test_forces_match_cpu_with_friction_and_history(packing_case, clone, model):
    """Pair and wall forces and torques of a random packing with springs set (from 40 CPU steps), the GPU
    engine started from the CPU engine's checkpoint, both laws; contacts with a wall and between species."""
    case, state = packing_case(model, n=150, spin=80.0)
    cpu = SoftSphereEngine(case, state=clone(state))
    cpu.advance(40)
    assert np.count_nonzero(np.any(cpu.hist != 0.0, axis=1)) > 100  # springs set
    assert np.count_nonzero(np.any(cpu.wall_hist != 0.0, axis=2)) > 10  # wall springs set
    gpu = _gpu(case, clone(state))
    gpu.restore(cpu.checkpoint_arrays(), cpu.checkpoint_scalars())
    cpu._compute_forces(update=False)
    gpu._compute_forces(update=False)
    scale = np.abs(cpu.state.force).max()
    assert _close(cpu.state.force, gpu.state.force, FORCE_RTOL, scale) < FORCE_RTOL
    assert _close(cpu.state.torque, gpu.state.torque, FORCE_RTOL) < FORCE_RTOL
    # the springs the GPU returns in the CPU's layout are the CPU's (turned into the current tangent plane by
    # the evaluation, as on the CPU: to round-off)
    back = gpu.checkpoint_arrays()
    assert np.array_equal(back["engine/partner"], cpu.partner)
    assert _close(cpu.hist, back["engine/hist"], FORCE_RTOL) < FORCE_RTOL
    assert np.array_equal(back["engine/wall_hist"], cpu.wall_hist)


def test_forces_from_scratch_match_cpu_in_2d(packing_case, clone):
    """A fresh 2D engine's first forces (list built on the device) are the CPU's."""
    case, state = packing_case("linear_spring_dashpot", n=100, dimensions=2)
    cpu = SoftSphereEngine(case, state=clone(state))
    gpu = _gpu(case, clone(state))
    assert gpu.partner.shape == cpu.partner.shape  # the same pairs listed
    assert _close(cpu.state.force, gpu.state.force, FORCE_RTOL) < FORCE_RTOL
    assert _close(cpu.state.torque, gpu.state.torque, FORCE_RTOL) < FORCE_RTOL
    assert np.all(gpu.state.force[:, 2] == 0.0) and np.all(gpu.state.torque[:, :2] == 0.0)


@pytest.mark.parametrize("model,dimensions,steps", [("hertz_mindlin", 3, 250), ("linear_spring_dashpot", 2, 200)])
def test_trajectories_match_cpu(packing_case, clone, model, dimensions, steps):
    """Positions, velocities and spins over a few hundred steps, with list rebuilds (springs carried over) and
    an oscillating wall, cut into calls of different lengths on each engine."""
    case, state = packing_case(model, n=64 if dimensions == 3 else 60, dimensions=dimensions, speed=2.0,
                               moving_wall=True)
    cpu = SoftSphereEngine(case, state=clone(state))
    gpu = _gpu(case, clone(state))
    cpu.advance(steps)
    done = 0
    for chunk in (1, 49, steps):
        k = min(chunk, steps - done)
        gpu.advance(k)
        done += k
    assert gpu.steps == cpu.steps == steps and gpu.time == cpu.time
    assert cpu.rebuilds >= 2 and gpu.rebuilds == cpu.rebuilds
    size = float(np.max(np.array(case.walls[0].upper)))
    assert _close(cpu.state.position, gpu.state.position, POSITION_RTOL, size) < POSITION_RTOL
    assert _close(cpu.state.velocity, gpu.state.velocity, 1e-9) < 1e-9
    assert _close(cpu.state.omega, gpu.state.omega, 1e-9) < 1e-9
    assert np.count_nonzero(np.any(gpu.hist != 0.0, axis=1)) > 0


def test_gpu_checkpoint_resumes_on_cpu_and_back(packing_case, clone):
    """A GPU checkpoint holds the CPU engine's arrays; the CPU engine resumes it and takes the same next steps
    as the GPU engine (and as a CPU engine that ran throughout); the GPU resumes a CPU checkpoint and its own,
    the latter bit for bit."""
    case, state = packing_case("hertz_mindlin", n=48, speed=3.0)
    cpu = SoftSphereEngine(case, state=clone(state))
    gpu = _gpu(case, clone(state))
    cpu.advance(60)
    gpu.advance(60)
    arrays, scalars = gpu.checkpoint_arrays(), gpu.checkpoint_scalars()
    reference = cpu.checkpoint_arrays()
    assert set(arrays) == set(reference) and scalars.keys() == cpu.checkpoint_scalars().keys()
    for k, a in reference.items():
        assert arrays[k].shape == a.shape and arrays[k].dtype == a.dtype, k
    resumed_cpu = SoftSphereEngine(case, state=clone(state))
    resumed_cpu.restore(arrays, scalars)
    resumed_gpu = _gpu(case, clone(state))
    resumed_gpu.restore(arrays, scalars)
    from_cpu = _gpu(case, clone(state))
    from_cpu.restore(reference, cpu.checkpoint_scalars())
    for eng in (cpu, gpu, resumed_cpu, resumed_gpu, from_cpu):
        eng.advance(60)
    assert gpu.rebuilds > scalars["rebuilds"] > 0  # rebuilds before and after the checkpoint
    size = float(np.max(np.array(case.walls[0].upper)))
    assert resumed_cpu.steps == gpu.steps == 120
    assert _close(gpu.state.position, resumed_cpu.state.position, POSITION_RTOL, size) < POSITION_RTOL
    assert _close(cpu.state.position, resumed_cpu.state.position, POSITION_RTOL, size) < POSITION_RTOL
    assert _close(cpu.state.position, from_cpu.state.position, POSITION_RTOL, size) < POSITION_RTOL
    assert np.array_equal(gpu.state.position, resumed_gpu.state.position)  # bit for bit on the same engine
    assert np.array_equal(gpu.state.omega, resumed_gpu.state.omega)


def test_state_fetched_and_sent_back(packing_case, clone):
    """Reading the state fetches it from the device; a change made to it on the host reaches the next step
    (a coupling sets ext_force; a user may stop the particles)."""
    case, state = packing_case("hertz_mindlin", n=40, two_species=False)
    cpu = SoftSphereEngine(case, state=clone(state))
    gpu = _gpu(case, clone(state))
    for eng in (cpu, gpu):
        eng.advance(5)
        eng.state.velocity[:] = 0.0
        eng.ext_force[:, 0] = 1e-4
        eng.advance(5)
    assert gpu.state.n == 40
    assert _close(cpu.state.velocity, gpu.state.velocity, 1e-9) < 1e-9
    assert np.all(gpu.state.velocity[:, 0] > cpu.state.velocity[:, 0] - 1e-9)
    assert gpu.positions_finite()


def test_run_directory_of_a_gpu_run_resumes_on_the_cpu(packing_case, tmp_path):
    """``Simulation`` with ``device = "gpu"``: its run directory (case.toml, restart.h5) resumes on the CPU
    (``Simulation.resume(..., device="cpu")``, what ``fluidem run --resume DIR --device cpu`` does) and ends
    where a CPU run of the same case ends."""
    from fluidem.simulation import Simulation

    case, state = packing_case("hertz_mindlin", n=27, speed=2.0, two_species=False, pitch=1.1, margin=0.6)
    csv = tmp_path / "particles.csv"
    table = np.column_stack([state.position, 2.0 * state.radius, state.velocity])
    rows = [",".join(repr(float(v)) for v in row) for row in table]
    csv.write_text("x,y,z,diameter,vx,vy,vz\n" + "\n".join(rows) + "\n")
    steps = 40
    case = case.with_overrides({"particles.placement": {"method": "file", "file": str(csv)},
                                "time.end": steps * case.time.dt, "output.checkpoint_interval": 20 * case.time.dt,
                                "output.snapshot_interval": 20 * case.time.dt})
    whole = Simulation(case.with_overrides({"device": "cpu"}))
    whole.run(until=steps * case.time.dt)
    first = Simulation(case.with_overrides({"device": "gpu"}), out_dir=tmp_path / "run")
    assert type(first.engine).__name__ == "SoftSphereGPUEngine"
    first.run(until=20 * case.time.dt)
    again = Simulation.resume(tmp_path / "run", device="cpu")
    assert type(again.engine).__name__ == "SoftSphereEngine" and again.steps == 20
    again.run()
    assert again.steps == whole.steps == steps
    assert _close(whole.state.position, again.state.position, POSITION_RTOL, 0.02) < POSITION_RTOL


def test_coupled_run_matches_cpu(packing_case):
    """A gas-coupled bed on the GPU engine: the particle side of the coupling (voidage map, drag, deposit, gas
    force) runs on the device (``coupling.exchange_gpu``), only cell arrays crossing; over three gas steps of
    four sub-steps the particles follow the CPU engine's run to round-off (few steps: the CUDA simulator runs
    every thread of every launch in Python). The device's map of the final particles is the CPU's."""
    from fluidem import Simulation

    case, _ = packing_case("linear_spring_dashpot", n=24, dimensions=2, speed=0.2, two_species=False)
    data = case.model_dump()
    width, height, depth = data["walls"][0]["upper"]
    data["walls"][0]["upper"] = [width, 3 * height, depth]
    data["time"]["dt"] = 2e-5
    data["gas"] = {"dt": 8e-5, "grid": {"cells": [4, 12], "size": [width, 3 * height], "depth": depth},
                   "boundaries": {"bottom": {"kind": "inflow", "superficial": 1.5}, "top": {"kind": "pressure_outlet"},
                                  "left": {"kind": "wall"}, "right": {"kind": "wall"}}}
    runs = {}
    for device in ("cpu", "gpu"):
        sim = Simulation(validate_case({**data, "device": device}))
        assert type(sim.engine).__name__ == ("SoftSphereGPUEngine" if device == "gpu" else "SoftSphereEngine")
        sim.advance(3 * sim.gas.substeps)
        runs[device] = sim
    cpu, gpu = runs["cpu"], runs["gpu"]
    assert gpu.gas._device is not None and cpu.gas._device is None
    assert gpu.gas.substeps == cpu.gas.substeps == 4
    assert _close(cpu.state.position, gpu.state.position, POSITION_RTOL, 3 * height) < POSITION_RTOL
    assert _close(cpu.state.velocity, gpu.state.velocity, 1e-9) < 1e-9
    assert _close(cpu.engine.ext_force, gpu.engine.ext_force, 1e-9) < 1e-9
    assert np.abs(gpu.engine.ext_force[:, 1]).max() > 0.1 * gpu.state.mass.max() * 9.81  # the gas carries weight
    np.testing.assert_allclose(gpu.gas.state.p, cpu.gas.state.p, rtol=1e-9, atol=1e-9 * np.abs(cpu.gas.state.p).max())
    kp = cpu.gas.checkpoint_arrays()["coupling/kp"]  # K_p of the last gas step, fetched from the device
    assert np.abs(gpu.gas.checkpoint_arrays()["coupling/kp"] - kp).max() <= 1e-9 * np.abs(kp).max()
    on_device = gpu.gas._map()
    st, cg = gpu.state, gpu.gas
    on_host = cg.mapping.map_particles(cg.grid, st.position, st.radius, cg.volume, st.velocity)
    assert on_device.clipped == on_host.clipped
    for a, b in ((on_device.voidage, on_host.voidage), (on_device.solids_u, on_host.solids_u),
                 (on_device.solids_v, on_host.solids_v)):
        assert np.abs(a - b).max() <= 1e-12 * np.abs(b).max()  # cell sums in another order (test_coupling_device)
