"""Thread set-up for Numba's parallel kernels.

Small systems run on one thread by default: below a few thousand particles a DEM
step takes tens of microseconds, less than the cost of waking a thread team, and
on a machine whose other cores are busy every parallel region waits for a
descheduled thread (measured here: 2 threads ran the 500-particle pour 50x slower
than 1 while another process held the second core).
"""

SERIAL_BELOW = 4000  # particles


def set_threads(n: int | None, n_particles: int | None = None) -> int:
    """Use ``n`` compute threads (None: one for small systems, else all cores); returns the number in use."""
    import numba

    if n is None and n_particles is not None and n_particles < SERIAL_BELOW:
        n = 1
    if n is None:
        n = numba.config.NUMBA_NUM_THREADS
    numba.set_num_threads(max(1, min(int(n), numba.config.NUMBA_NUM_THREADS)))
    return numba.get_num_threads()
