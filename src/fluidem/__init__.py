"""fluidem: discrete-particle simulation of gas–solid flows (soft-sphere DEM first).

Public surface::

    import fluidem as fd
    case = fd.load_case("pour", {"particles.contact.restitution": 1.0})
    sim = fd.Simulation(case, out_dir="runs/pour")
    sim.run(until=0.5)
"""
from ._numba_cache import install as _install_cache_stamp

_install_cache_stamp()  # before any kernel module is imported: their cache locators are chosen at decoration

from ._threads import launch_pool, prefer_openmp  # noqa: E402
from .case import Case, load_case  # noqa: E402
from .errors import CaseError  # noqa: E402
from .schedule import Every, EveryTime  # noqa: E402

__version__ = "0.1.0"

prefer_openmp()
launch_pool()  # after prefer_openmp: the launch fixes the threading layer


def __getattr__(name):
    if name == "Simulation":
        from .simulation import Simulation

        return Simulation
    raise AttributeError(name)


__all__ = ["Case", "load_case", "CaseError", "Every", "EveryTime", "Simulation", "__version__"]
