"""Thread set-up for Numba's parallel kernels.

Small systems run on one thread by default: below a few thousand particles a DEM
step takes tens of microseconds, less than the cost of waking a thread team, and
on a machine whose other cores are busy every parallel region waits for a
descheduled thread (measured here: 2 threads ran the 500-particle pour 50x slower
than 1 while another process held the second core).
"""

SERIAL_BELOW = 4000  # particles


def prefer_openmp() -> None:
    """Use Numba's OpenMP threading layer when it is available and the user chose none.

    Measured on the 10,000-sphere benchmark bed (2 cores, idle): pair forces took
    1.45 ms (1 thread) and 0.86 ms (2 threads) with OpenMP, 2.15 and 2.20 ms with TBB.
    Numba reads the setting at its first parallel launch, so this works after numba
    was imported too.
    """
    import os

    import numba

    if os.environ.get("NUMBA_THREADING_LAYER") or numba.config.THREADING_LAYER not in ("default", None):
        return
    try:
        import numba.np.ufunc.omppool  # noqa: F401  (present when libgomp is)
    except ImportError:
        return
    numba.config.THREADING_LAYER = "omp"


def set_threads(n: int | None, n_particles: int | None = None) -> int:
    """Use ``n`` compute threads (None: one for small systems, else all cores); returns the number in use."""
    import numba

    if n is None and n_particles is not None and n_particles < SERIAL_BELOW:
        n = 1
    if n is None:
        n = numba.config.NUMBA_NUM_THREADS
    numba.set_num_threads(max(1, min(int(n), numba.config.NUMBA_NUM_THREADS)))
    return numba.get_num_threads()
