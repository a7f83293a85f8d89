"""The 3D coupled gas step's kernels timed alone on states captured from a run (``bubbling-3d`` by default).

    NUMBA_NUM_THREADS=2 python benchmarks/coupled3d_kernels.py                 # the bed, 2 threads
    NUMBA_NUM_THREADS=2 PYTHONPATH=<other checkout>/src python benchmarks/coupled3d_kernels.py   # another revision

The run goes to ``--start`` seconds, then the arguments of every call of the multigrid path's Newton loop
(``_solver3d_kernels.newton_multigrid``) and of the last particles → grid map (``_voidage3d_kernels.map_solids3d``)
over the next ``--capture`` seconds are copied. Then, each on a fresh copy of its captured arguments, the least
time of ``--blocks`` blocks (µs):

    newton      the compiled Newton loop of a gas step, averaged over the captured steps
    gmres       one GMRES solve of the last captured step's first correction (its iteration count printed)
    cycle       one multigrid cycle (``mg_cycle``) on that right-hand side
    product     one matrix product (``mg_matvec``)
    map         the whole map (``map_solids3d``), ``--calls`` calls a block

In-run times come from ``benchmarks/coupled_profile.py``; these isolate kernels on a state that does not change,
so that two revisions can be compared where the coupled run's spread (other tenants, the DEM's cache traffic)
hides a change of a few percent. The kernels' signatures must be those of this checkout's.
"""
from __future__ import annotations

import argparse
import math
import time

import numpy as np

import fluidem as fd
from fluidem.coupling import _voidage3d_kernels as VK3
from fluidem.gas import _multigrid3d_kernels as MK
from fluidem.gas import _solver3d_kernels as K3
from fluidem.gas import solver3d as S3


def _copy(args):
    return [a.copy() if isinstance(a, np.ndarray) else a for a in args]


def _least(fn, blocks, calls=1, prepare=None):
    """Least time of one call [µs] over ``blocks`` blocks of ``calls`` calls (``prepare`` before each call,
    untimed only when ``calls`` is 1)."""
    best = math.inf
    for _ in range(blocks):
        if prepare is not None:
            prepare()
        t = time.perf_counter()
        for _ in range(calls):
            fn()
        best = min(best, (time.perf_counter() - t) / calls)
    return 1e6 * best


def capture(case, start: float, span: float):
    """(Newton-loop argument lists, the last map's arguments) of a run of ``case`` from ``start`` over ``span`` [s]."""
    sim = fd.Simulation(fd.load_case(case))
    sim.run(until=start)
    newton, maps = [], []
    loop, mapper = K3.newton_multigrid, VK3.map_solids3d

    def grab_newton(*args):
        newton.append(_copy(args))
        return loop(*args)

    def grab_map(*args):
        maps[:] = [_copy(args)]
        return mapper(*args)

    S3.K3.newton_multigrid = grab_newton
    VK3.map_solids3d = grab_map
    try:
        sim.run(until=start + span)
    finally:
        S3.K3.newton_multigrid = loop
        VK3.map_solids3d = mapper
    if not newton or not maps:
        raise SystemExit(f"{case}: no multigrid Newton loop or 3D map captured (a 3D gas case on the multigrid path?)")
    return newton, maps[0]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--case", default="bubbling-3d", help="built-in 3D case or case file")
    ap.add_argument("--start", type=float, default=0.002, help="simulated time before the capture [s]")
    ap.add_argument("--capture", type=float, default=0.005, help="simulated time captured [s]")
    ap.add_argument("--blocks", type=int, default=50, help="blocks per kernel; the least is printed")
    ap.add_argument("--calls", type=int, default=200, help="map calls per block")
    a = ap.parse_args(argv)
    newton, map_args = capture(a.case, a.start, a.capture)

    fresh = []

    def prepare():
        fresh[:] = [_copy(args) for args in newton]

    def newton_all():
        for args in fresh:
            K3.newton_multigrid(*args)

    t_newton = _least(newton_all, max(1, a.blocks // 10), prepare=prepare) / len(newton)
    # the last step's first correction: its Jacobian, hierarchy and right-hand side, as the loop makes them
    (W, C, F, K, row_of, R, fpar, ipar, out, data, diag_pos, pos, pin_pos, flags, RULES, ell, MGL, MGI, MGA, MGS, MGW,
     DLU, PIV, KRY, HES, rhs, dp, pinned, tol, maxit, red, floor, kmax, counts, chord) = _copy(newton[-1])
    K3.predict_residual(W, C, F, K, row_of, R, fpar, ipar, out)
    K3.assemble_pressure(data, diag_pos, pos, pin_pos, W, C, F, K, fpar, ipar)
    rhs[:] = -R
    if pinned:
        rhs[0] = 0.0
    assert MK.mg_setup(data, ell, MGL, MGI, MGA, MGS, MGW, DLU, PIV)
    target = max(red * math.sqrt(float(rhs @ rhs)), floor * out[K3.O_QREF] / math.sqrt(R.size))
    its = MK.gmres(MGL, MGI, MGA, MGS, MGW, DLU, PIV, KRY, HES, rhs, dp, target, kmax)
    t_gmres = _least(lambda: MK.gmres(MGL, MGI, MGA, MGS, MGW, DLU, PIV, KRY, HES, rhs, dp, target, kmax), a.blocks)
    x, y = np.zeros(R.size), np.zeros(R.size)
    t_cycle = _least(lambda: MK.mg_cycle(MGL, MGI, MGA, MGS, MGW, DLU, PIV, rhs, x), a.blocks)
    t_product = _least(lambda: MK.mg_matvec(MGL, MGI, MGA, x, y), a.blocks, calls=20)
    margs = _copy(map_args)
    t_map = _least(lambda: VK3.map_solids3d(*margs), max(1, a.blocks // 10), calls=a.calls)
    levels = MGL.shape[1] - 1
    sizes = " / ".join("x".join(str(int(MGL[q, lv])) for q in (1, 2, 3)) for lv in range(levels))
    print(f"case {a.case}, {len(newton)} gas steps captured from {a.start:g} s; fluidem {fd.__file__}")
    print(f"multigrid levels {sizes}; GMRES iterations of the timed solve: {its}")
    for name, us in (("newton (per gas step)", t_newton), ("gmres", t_gmres), ("cycle", t_cycle),
                     ("product", t_product), ("map", t_map)):
        print(f"{name:24s} {us:10.1f} us")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
