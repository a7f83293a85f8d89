"""Thread set-up, done before Numba's first parallel launch.

Numba's TBB layer was measured here at 4–40× slower per parallel region than
OpenMP on 2 cores, so OpenMP is preferred unless the user set a layer.
"""
import os




def set_threads(n: int | None) -> int:
    """Use ``n`` compute threads (None: all available); returns the number in use."""
    import numba

    if n is not None:
        numba.set_num_threads(min(int(n), numba.config.NUMBA_NUM_THREADS))
    return numba.get_num_threads()
