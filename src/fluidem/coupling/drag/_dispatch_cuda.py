"""CUDA device versions of the drag dispatch: the registered laws' own Python source, compiled for the GPU.

``monodisperse`` is the registry's switch over every drag law (``_dispatch.monodisperse``, written by
``registry.compiled_switch``) with each law's ``beta_per_solids`` compiled by ``cuda.jit(device=True)``, and
``beta_per_solids`` is ``_dispatch.beta_per_solids`` (DEM book 2012 eq. 12 through eq. 11) calling it. The
laws' helpers (``_ergun_wen_yu``, Beetstra's ``normalised_drag``) become device functions too
(``device_tree``). Nothing here names a law: a law registered for the CPU kernels is on the GPU as long as its
kernel is plain arithmetic on scalars and ``math``. Imported only where the device exchange is built:
importing it needs ``numba.cuda``.
"""
from __future__ import annotations

from numba import cuda
from numba.core.registry import CPUDispatcher

from ...particles.contact._dispatch_cuda import device_function
from ...registry import compiled_switch
from . import _dispatch

_DONE: dict = {}  # njit function → its device version (each compiled once per process)


def device_tree(kernel, **names):
    """``kernel`` (an ``njit`` function) as a CUDA device function, every ``njit`` function it calls by a global
    name replaced by its own device version, recursively; ``names`` rebind other globals first (as
    ``device_function``'s)."""
    key = (kernel, tuple(sorted(names)))
    if key in _DONE:
        return _DONE[key]
    py = getattr(kernel, "py_func", kernel)
    bound = {}
    for name in py.__code__.co_names:
        if name in names:
            bound[name] = names[name]
            continue
        obj = py.__globals__.get(name)
        if isinstance(obj, CPUDispatcher):
            bound[name] = device_tree(obj, **names)
    out = _DONE[key] = device_function(kernel, **bound)
    return out


def _device_laws() -> dict:
    """{CODE: device beta_per_solids} of every registered drag law."""
    return {code: device_tree(kernel) for code, kernel in _dispatch._laws().items()}


# β/(1−ε) [kg m^-3 s^-1] of the law packed in p for a monodisperse bed of diameter d; 0 for an unknown code
monodisperse = compiled_switch("monodisperse", _device_laws(), ("p", "eps", "slip", "d", "rho", "mu"), "int(p[0])",
                               "0.0", __name__, __file__, jit=cuda.jit(device=True))

# β_i/(1−ε) of a particle of diameter d = y D̄ (DEM book 2012 eq. 12 through eq. 11): ``_dispatch.beta_per_solids``
beta_per_solids = device_function(_dispatch.beta_per_solids, monodisperse=monodisperse)
