"""fluidem: discrete-particle simulation of gas–solid flows (soft-sphere DEM first).

Public surface::

    import fluidem as fd
    case = fd.load_case("pour", {"particles.contact.restitution": 1.0})
    sim = fd.Simulation(case, out_dir="runs/pour")
    sim.run(until=0.5)
    table = fd.sweep("pour", vary={"particles.contact.restitution": [0.8, 1.0]}, until=0.5, out="studies/pour")

A case can also be built in Python from the objects the TOML loader builds::

    case = fd.Case(
        name="pour",
        particles=fd.Particles(
            dimensions=2,
            species=[fd.Species(name="aluminium", diameter=4e-3, density=2700.0, count=500)],
            contact=fd.contact.LinearSpringDashpot(stiffness=800.0, restitution=0.9, friction=0.3),
            placement=fd.Placement(method="random", seed=1996)),
        walls=[fd.Wall(name="container", kind="box", lower=(0.0, 0.0, 0.0), upper=(0.096, 0.192, 0.004))],
        time=fd.Time(end=1.5),
        output=fd.Output(snapshot_interval=0.02, probe_interval=0.005))

``fd.segregation_criterion(diameters, densities, composition, voidage)`` says which species of a
fluidised binary mixture rises (Di Renzo & Di Maio 2012; ``fluidem.analysis.segregation``).

``fd.contact`` holds the contact laws (``fd.contact.HertzMindlin``, ...), ``fd.drag`` the drag
closures (``fd.drag.Beetstra``, ...), ``fd.gas`` the gas solver and its boundary conditions
(``fd.gas.Inflow``, ...). A coupled case adds ``gas=fd.Gas(grid=fd.gas.Grid(cells=..., size=...,
depth=...), boundaries={"left": fd.gas.Wall(), ...}, dt=...)`` and ``coupling=fd.Coupling(
drag=fd.drag.Gidaspow(), voidage=fd.VoidageMapping(method="centroid"))``.

The package reports through the ``logging`` logger ``"fluidem"`` and its children (``fluidem.progress``:
the progress lines of a run); it adds only a ``NullHandler``, so nothing is shown until the
application configures logging (the ``fluidem`` command does).
"""
import logging as _logging

import numpy as _np

if not hasattr(_np, "row_stack"):  # NumPy 2.5 dropped it; Numba's and numba-cuda's imports still name it
    _np.row_stack = _np.vstack

from ._numba_cache import install as _install_cache_stamp  # noqa: E402

_logging.getLogger("fluidem").addHandler(_logging.NullHandler())

_install_cache_stamp()  # before any kernel module is imported: their cache locators are chosen at decoration

from ._threads import launch_pool, prefer_openmp  # noqa: E402
from .case import (  # noqa: E402
    Case,
    Motion,
    Neighbours,
    Output,
    PairContact,
    Particles,
    Placement,
    SizeDistribution,
    Species,
    Time,
    Wall,
    WallContact,
    WallPairContact,
    load_case,
)
from .analysis.segregation import segregation_criterion  # noqa: E402
from .coupling import drag  # noqa: E402
from .coupling.schema import CouplingSection as Coupling  # noqa: E402
from .coupling.voidage import VoidageMapping  # noqa: E402
from .errors import CaseError  # noqa: E402
from .particles import contact  # noqa: E402
from . import gas  # noqa: E402
from .gas.schema import GasSection as Gas  # noqa: E402
from .schedule import Every, EveryTime  # noqa: E402


def _distribution_version() -> str:
    """The installed distribution's version (pyproject.toml's ``version``); ``0+unknown`` when the
    package runs from a source tree that was never installed."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("fluidem")
    except PackageNotFoundError:
        return "0+unknown"


__version__ = _distribution_version()

prefer_openmp()
launch_pool()  # after prefer_openmp: the launch fixes the threading layer


def __getattr__(name):
    if name == "Simulation":  # lazily: the engines and writers are not needed to read or build a case
        from .simulation import Simulation

        return Simulation
    if name == "sweep":  # lazily too: a study needs Dask only when it runs
        from .studies import sweep

        return sweep
    raise AttributeError(f"module 'fluidem' has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | {"Simulation", "sweep"})


__all__ = [
    "Case", "Particles", "Species", "Wall", "Time", "Output", "Placement", "Neighbours", "Motion",
    "SizeDistribution", "PairContact", "WallPairContact", "WallContact",
    "Gas", "Coupling", "VoidageMapping", "contact", "drag", "gas", "load_case", "CaseError", "segregation_criterion",
    "Every", "EveryTime", "Simulation", "sweep", "__version__",
]
