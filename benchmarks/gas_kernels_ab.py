"""The gas solver's kernels of the working tree against an earlier commit's, on the matrix of a coupled run.

    NUMBA_NUM_THREADS=2 python benchmarks/gas_kernels_ab.py --base 720b67a --from runs/tj

``--from``: a tsuji-jet run directory (``fluidem run tsuji-jet --until 1.5 --out runs/tj``). Its checkpoint
is resumed and advanced by 20 gas steps; then, on that solver's own arrays, each version's ``band_factor``
(all blocks), ``band_solve``, ``predict_residual`` and ``assemble_pressure`` are timed in alternating rounds
(the shared machine's speed drifts; see ``ab_kernels.py``, whose ``base_package`` extracts the earlier
commit as ``fluidem_base``). First it prints whether both versions give the same bits.
"""
from __future__ import annotations

import argparse
import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from ab_kernels import base_package  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--base", required=True, help="the earlier commit (any git revision)")
    ap.add_argument("--from", dest="run_dir", required=True, help="tsuji-jet run directory with restart.h5")
    ap.add_argument("--rounds", type=int, default=6)
    args = ap.parse_args()
    tmp = Path(tempfile.mkdtemp(prefix="gas_kernels_ab_"))
    try:
        base_package(args.base, tmp)
        sys.path.insert(0, str(tmp))
        import fluidem as fd
        from fluidem.gas import _solver_kernels as K
        from fluidem_base.gas import _solver_kernels as KB

        sim = fd.Simulation(fd.load_case("tsuji-jet"))
        sim.load_checkpoint(Path(args.run_dir) / "restart.h5")
        sim.step_once(20 * sim.gas.substeps)
        s = sim.gas.solver
        data = s.MAT[K.M_DATA].copy()
        n = s._order.size
        work = {}
        for name, mod in (("tree", K), ("base", KB)):
            band, blu, rows = s._band.copy(), s._band_lu.copy(), s.VEC[K.V_ROW:K.V_ROW + 2].copy()
            # the numbering: as blocks and places (2, n) where band_factor takes ``place``, else the order
            num = s._band_place if "place" in mod.band_factor.py_func.__code__.co_varnames else s._order
            mod.band_factor(data, s._csc_indices, s._csc_indptr, num, band, blu, rows, 0)
            b = np.linspace(0.0, 1.0, n)
            x, w, v, y = np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n)
            mod.band_solve(band, blu, s._order, b, x, w, v, y)
            work[name] = (mod, num, band, blu, rows, b, x, w, v, y)
        same = (np.array_equal(work["tree"][2], work["base"][2]) and np.array_equal(work["tree"][6], work["base"][6]))
        print(f"same factors and solution: {same}")
        R = s.VEC[K.V_R]
        pargs = (s.U, s.V, s.C, s.FU, s.FV, s.KU, s.KV, s.row_of, R, s._fpar, s._ipar)
        aargs = (s.MAT[K.M_DATA], s.diag_pos, s.upos, s.vpos, s.pin_pos, s.U, s.V, s.C, s.FU, s.FV, s.KU, s.KV,
                 s._fpar, s._ipar)
        rows_out = {"tree": [], "base": []}
        for r in range(args.rounds):
            for name in (("tree", "base") if r % 2 == 0 else ("base", "tree")):
                mod, num, band, blu, rows, b, x, w, v, y = work[name]
                t = []
                for f, reps in ((lambda: mod.band_factor(data, s._csc_indices, s._csc_indptr, num, band, blu, rows, 0), 200),
                                (lambda: mod.band_solve(band, blu, s._order, b, x, w, v, y), 500),
                                (lambda: mod.predict_residual(*pargs), 1000),
                                (lambda: mod.assemble_pressure(*aargs), 1000)):
                    t0 = time.perf_counter()
                    for _ in range(reps):
                        f()
                    t.append((time.perf_counter() - t0) / reps * 1e6)
                rows_out[name].append(t)
        print("µs per call, median of the rounds:   band_factor  band_solve  predict_residual  assemble_pressure")
        for name, ts in rows_out.items():
            med = np.median(np.array(ts), axis=0)
            print(f"{name:5s} ({args.base if name == 'base' else 'working tree'}): " + "  ".join(f"{m:10.1f}" for m in med))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
