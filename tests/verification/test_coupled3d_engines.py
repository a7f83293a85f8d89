"""The 3D coupling with the hard-sphere engine and with a mixture of sizes (the polydisperse drag, DEM book 2012
eqs 10-12, y = d/D̄ from the 3D cells' Sauter means): both run, and the mixture's gas loses exactly the drag its
particles gain (``exchange_balance``, to round-off)."""
import numpy as np

import fluidem as fd
from fluidem.simulation import Simulation


def test_hard_spheres_on_a_3d_gas_grid():
    case = fd.load_case("bubbling-3d").with_overrides({
        "particles.contact": {"model": "hard_sphere", "restitution": 0.9, "friction": 0.3},
        "particles.species.0.count": 400, "time.dt": 1e-4})
    sim = Simulation(case)
    sim.advance(20 * sim.gas.substeps)
    assert sim.gas.gas_steps == 20
    assert np.all(np.isfinite(sim.state.velocity)) and np.abs(sim.state.velocity).max() > 0.0


def test_a_mixture_on_a_3d_gas_grid_exchanges_drag_in_pairs():
    case = fd.load_case("bubbling-3d").with_overrides({
        "particles.species": [{"name": "a", "diameter": 0.0012, "density": 1000.0, "count": 300},
                              {"name": "b", "diameter": 0.0008, "density": 1000.0, "count": 300}],
        "coupling.drag_update": "frozen"})
    sim = Simulation(case)
    assert sim.gas.polydisperse == "sauter_y2"
    sim.advance(3 * sim.gas.substeps)
    sim.gas.gas_step()
    b = sim.gas.exchange_balance()
    err = np.abs(b["gas"] + b["boundary"] - b["particles"]).max() / np.abs(b["particles"]).max()
    assert err < 1e-12, err
