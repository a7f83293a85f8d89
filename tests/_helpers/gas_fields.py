"""The tiny coupled jet bed that writes gas fields (tests/unit/test_gas_fields.py, test_plotting_gas.py)."""
from __future__ import annotations

from pathlib import Path

from fluidem.case import validate_case
from fluidem.io.gas_fields import GasFieldWriter
from fluidem.schedule import EveryTime
from fluidem.simulation import Simulation


def tiny_jet_case(end=0.02, snapshot_interval=0.002) -> dict:
    """A 6 x 24 cell (0.06 x 0.24 m) bed of 60 glass spheres with a central jet: a coupled run of
    ~1 s wall time per 0.02 s. Gas step 0.2 ms, 14 DEM sub-steps."""
    return {
        "name": "tiny-jet",
        "particles": {
            "dimensions": 2,
            "species": [{"name": "glass", "diameter": 0.004, "density": 2500.0, "count": 60}],
            "contact": {"model": "linear_spring_dashpot", "stiffness": 800.0, "restitution": 0.9, "friction": 0.2},
            "placement": {"method": "random", "region_lower": [0.0, 0.0, 0.002],
                          "region_upper": [0.06, 0.05, 0.002], "seed": 3},
        },
        "walls": [{"name": "column", "kind": "box", "lower": [0.0, 0.0, 0.0], "upper": [0.06, 0.24, 0.004]}],
        "gas": {
            "dt": 2e-4,
            "grid": {"cells": [6, 24], "size": [0.06, 0.24], "depth": 0.004},
            "initial_velocity": [0.0, 1.0],
            "boundaries": {
                "left": {"kind": "wall"}, "right": {"kind": "wall"}, "top": {"kind": "pressure_outlet"},
                "bottom": {"kind": "inflow", "voidage": 1.0,
                           "segments": [{"superficial": 1.0}, {"superficial": 10.0, "start": 0.025, "end": 0.035}]},
            },
        },
        "coupling": {"drag": "gidaspow", "pressure_gradient_force": True},
        "time": {"end": end},
        "output": {"snapshot_interval": snapshot_interval, "probe_interval": 0.001, "checkpoint_interval": 0.01},
    }


def run_tiny_jet(out: Path, until=None, **case_kw) -> Simulation:
    """Run the tiny bed into ``out`` with a GasFieldWriter at the particle snapshot interval."""
    case = validate_case(tiny_jet_case(**case_kw))
    sim = Simulation(case, out_dir=out)
    sim.observers["gas_fields"] = GasFieldWriter(out, EveryTime(case.output.snapshot_interval))
    sim.run(until=until)
    return sim
