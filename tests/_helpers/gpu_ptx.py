"""Compile every GPU kernel of fluidem to PTX for a compute capability, without a GPU (numba-cuda, NVVM and
NVRTC installed). The CUDA simulator runs the kernels as Python and checks no types; this checks that
numba-cuda types and compiles them. Run as ``python3 tests/_helpers/gpu_ptx.py [major minor]``; prints one
line per kernel and exits non-zero on the first failure.
"""
from __future__ import annotations

import sys
import types

import numpy as np

if not hasattr(np, "row_stack"):
    np.row_stack = np.vstack


def kernel_signatures(SC, NC, T) -> dict:
    """{kernel: argument types} as the GPU engine launches them (C-contiguous device arrays)."""
    f1, f2, f3 = T.float64[::1], T.float64[:, ::1], T.float64[:, :, ::1]
    i1, i2, l1, u2 = T.int32[::1], T.int32[:, ::1], T.int64[::1], T.uint8[:, ::1]
    b, f, i = T.boolean, T.float64, T.int64
    return {
        SC.pair_and_wall_forces: (f2, f2, f2, f1, f1, l1, f3, i2, i1, f3, f3, f2, f2, f2, i, f3, u2, f1, f2, f1, b, b,
                                  f, f, b, f2, f2),
        SC.kick_drift: (f2, f2, f2, f2, f2, f1, f1, f, i, b, f2, f, i1),
        SC.all_finite: (f2, i1),
        NC.fill_int: (i1, i),
        NC.bounds: (f2, f1, f1),
        NC.bin_cells: (f2, f, f, f, f, f, f, i, i, i, i1, i2, i1),
        NC.fill_rows: (f2, f1, f, f, f, f, f, f, f, i, i, i, i1, i2, i2, i1, i1),
        NC.carry_history: (i2, i1, f3, i2, i1, f3),
    }


def coupling_signatures(VC, PC, T) -> dict:
    """{kernel: argument types} of the gas coupling's device kernels as ``coupling.exchange_gpu`` launches them."""
    f1, f2, i1 = T.float64[::1], T.float64[:, ::1], T.int32[::1]
    b, f = T.boolean, T.float64
    return {
        VC.centroid_deposit: (f2, f2, f1, f, f, b, f2, f2, f2, f2),
        VC.area_deposit: (f2, f2, f1, f1, b, f, f, b, f2, f2, f2, f2),
        VC.sauter_deposit: (f2, f1, f1, f, f, f2, f2),
        VC.zero: (f2,),
        PC.deposit: (f1, f2, f2, f1, f1, f2, f2, f2, f2, f, f2, f, f, f, b, b, b, f1, f2, f2, f2, f2, f2, b, f2, f2,
                     i1),
        PC.forces_split: (f2, f2, f1, f1, f2, f2, f2, f, f, b, b, b, b, b, f2, f1, f2),
        PC.forces: (f2, f2, f1, f1, f2, f2, f2, f, f, b, b, b, b, b, f2, f2),
    }


def cell_signatures(CC, T) -> dict:
    """{kernel: argument types} of the 2D "cell" and "cell_beta" exchanges' device kernels as
    ``coupling.exchange_gpu`` launches them."""
    f1, f2, f3, i1 = T.float64[::1], T.float64[:, ::1], T.float64[:, :, ::1], T.int32[::1]
    b, f = T.boolean, T.float64
    return {
        CC.cell_beta_deposit: (f1, f2, f1, f1) + (f2,) * 6 + (f, f2, f, f, f2, i1),
        CC.pressure_deposit: (f2, f1, f, f, b, b, f2, f2),
        CC.cell_solids: (f2, f1, f, f, f2),
        CC.forces: (f2, f1) + (f2,) * 7 + (f, f, f, b, b, b, f2, f2),
        CC.gas_forces: (f1, f2, f2, f1, f1, f3, f3, f3, f2) + (f1,) * 4 + (f,) * 4 + (b, b, f2, f2, i1),
    }


def coupling3d_signatures(VC3, PC3, T) -> dict:
    """{kernel: argument types} of the 3D gas coupling's device kernels as ``coupling.exchange3d_gpu`` launches
    them."""
    f1, f2, f3, i1 = T.float64[::1], T.float64[:, ::1], T.float64[:, :, ::1], T.int32[::1]
    b, f = T.boolean, T.float64
    return {
        VC3.centroid_deposit3d: (f2, f2, f1, f, f, f, b) + (f3,) * 5,
        VC3.volume_deposit3d: (f2, f2, f1) + (f,) * 6 + (b,) * 4 + (f3,) * 5,
        VC3.sauter_deposit3d: (f2, f1, f1, f, f, f, f3, f3),
        VC3.zero3: (f3,),
        PC3.deposit3d: (f1, f2, f2, f1, f1) + (f3,) * 5 + (f, f3) + (f,) * 4 + (b,) * 4 + (f1,) + (f3,) * 7 + (b,)
        + (f3,) * 3 + (i1,),
        PC3.forces_split3d: (f2, f2, f1, f1) + (f3,) * 4 + (f,) * 3 + (b,) * 5 + (f2, f1, f2),
        PC3.forces3d: (f2, f2, f1, f1) + (f3,) * 4 + (f,) * 3 + (b,) * 5 + (f2, f2),
    }


def cell3d_signatures(CC3, T) -> dict:
    """{kernel: argument types} of the 3D "cell" and "cell_beta" exchanges' device kernels as
    ``coupling.exchange3d_gpu`` launches them."""
    f1, f2, f3, i1, b1 = T.float64[::1], T.float64[:, ::1], T.float64[:, :, ::1], T.int32[::1], T.boolean[::1]
    b, f = T.boolean, T.float64
    return {
        CC3.cell_beta_deposit3d: (f1, f2, f1, f1) + (f3,) * 8 + (f, f3, f, f, f, f3, i1),
        CC3.pressure_deposit3d: (f2, f1, f, f, f, b, b, b, f3, f3, f3),
        CC3.cell_solids3d: (f2, f1, f, f, f, f3),
        CC3.cell_forces3d: (f2, f1) + (f3,) * 9 + (f,) * 4 + (b,) * 4 + (f2, f2),
        CC3.kp_now3d: (f1, f2, f2, f1, f1) + (f3,) * 5 + (f, f3) + (f,) * 4 + (b,) * 4 + (f1, b1, i1),
    }


def main(cc=(9, 0)) -> int:
    import numba.cuda.dispatcher as dispatcher
    from numba import cuda
    from numba import types as T

    # device functions are compiled for the current device's compute capability; there is none here
    dispatcher.get_current_device = lambda: types.SimpleNamespace(compute_capability=cc)
    from fluidem.particles import _neighbours_cuda as NC
    from fluidem.particles import _softsphere_cuda as SC
    from fluidem.coupling import _paired_cuda as PC
    from fluidem.coupling import _voidage_cuda as VC
    from fluidem.coupling import _paired3d_cuda as PC3
    from fluidem.coupling import _voidage3d_cuda as VC3
    from fluidem.coupling import _cell_cuda as CC
    from fluidem.coupling import _cell3d_cuda as CC3

    for kernel, sig in {**kernel_signatures(SC, NC, T), **coupling_signatures(VC, PC, T),
                        **coupling3d_signatures(VC3, PC3, T), **cell_signatures(CC, T),
                        **cell3d_signatures(CC3, T)}.items():
        ptx, _ = cuda.compile_ptx(kernel.py_func, sig, cc=cc)
        print(f"{kernel.py_func.__name__}: {len(ptx)} characters of PTX for sm_{cc[0]}{cc[1]}")
    return 0


if __name__ == "__main__":
    sys.exit(main(tuple(int(a) for a in sys.argv[1:3]) if len(sys.argv) > 2 else (9, 0)))
