"""fluidem: discrete-particle simulation of gas–solid flows (soft-sphere DEM first).

Public surface::

    import fluidem as fd
    case = fd.load_case("pour", {"particles.contact.restitution": 1.0})
    sim = fd.Simulation(case, out_dir="runs/pour")
    sim.run(until=0.5)
"""
from ._threads import launch_pool, prefer_openmp
from .case import Case, load_case
from .errors import CaseError
from .schedule import Every, EveryTime

__version__ = "0.1.0"

prefer_openmp()
launch_pool()  # after prefer_openmp: the launch fixes the threading layer


def __getattr__(name):
    if name == "Simulation":
        from .simulation import Simulation

        return Simulation
    raise AttributeError(name)


__all__ = ["Case", "load_case", "CaseError", "Every", "EveryTime", "Simulation", "__version__"]
