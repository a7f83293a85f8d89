"""CUDA device versions of the contact dispatch: the same Python source as ``_dispatch``, compiled for the GPU.

``contact_force`` here is ``_dispatch.contact_force`` (the one place where a contact's force is assembled,
Sun 2007 eqs 19–22) and ``coefficients`` the registry's switch over every force-based model
(``registry.compiled_switch``), both compiled with ``cuda.jit(device=True)`` from the source of their CPU
versions (``.py_func``), with the names they call bound to device versions. Nothing here names a model:
a model registered for the CPU kernels (its module's ``CODE`` and ``coefficients``) is on the GPU too, as
long as its ``coefficients`` is plain arithmetic on scalars and ``math`` (what a CUDA device function may
hold). Imported only where a GPU engine is built: importing it needs ``numba.cuda``.
"""
from __future__ import annotations

import types

from numba import cuda

from ...registry import compiled_switch
from . import _dispatch


def device_function(kernel, **names):
    """``kernel`` (an ``njit`` function) compiled as a CUDA device function from its Python source; ``names``
    rebind globals its source calls (an ``njit`` function cannot be called from a CUDA kernel, its device
    version can)."""
    py = getattr(kernel, "py_func", kernel)
    scope = dict(py.__globals__)
    scope.update(names)
    func = types.FunctionType(py.__code__, scope, py.__name__, py.__defaults__, py.__closure__)
    func.__qualname__ = py.__qualname__
    func.__doc__ = py.__doc__
    return cuda.jit(device=True)(func)


try:  # numba-cuda keeps its own cache machinery: fluidem's one source stamp there too (``_numba_cache``)
    from numba.cuda.core import caching as _cuda_caching
except Exception:  # noqa: BLE001 - numba's own numba.cuda caches through numba.core.caching, stamped at import
    _cuda_caching = None
if _cuda_caching is not None:
    from ..._numba_cache import install

    install(caching=_cuda_caching)


def cached_kernel(func):
    """``func`` compiled as a CUDA kernel with numba-cuda's on-disk cache (``cuda.jit(cache=True)``, one file per
    compute capability in ``__pycache__``, under fluidem's one source stamp: ``_numba_cache``); a plain
    ``cuda.jit`` kernel where this numba.cuda refuses the option."""
    try:
        return cuda.jit(cache=True)(func)
    except (TypeError, NotImplementedError):  # a numba.cuda without on-disk caching of kernels
        return cuda.jit(func)


def _device_laws() -> dict:
    """{CODE: device coefficients} of every registered force-based contact model."""
    return {code: device_function(kernel) for code, kernel in _dispatch._force_laws(False).items()}


# (elastic normal force [N], η_n [N s/m], k_t [N/m], η_t [N s/m]) of the model coded in p[0]
coefficients = compiled_switch("coefficients", _device_laws(), ("p", "overlap", "m_eff", "r_eff"), "int(p[0])",
                               "0.0, 0.0, 0.0, 0.0", __name__, __file__, jit=cuda.jit(device=True))

# (fn, ftx, fty, ftz, hx, hy, hz) of one contact: ``_dispatch.contact_force`` on the GPU
contact_force = device_function(_dispatch.contact_force, coefficients=coefficients)
