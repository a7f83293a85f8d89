"""Thread set-up for Numba's parallel kernels.

By default a run takes one thread per PARTICLES_PER_THREAD particles, up to all cores. A
thread's share must be worth waking it for: a soft-sphere step of a few hundred particles takes
tens of microseconds, about what a parallel region costs, and on a machine whose other cores are
busy every parallel region waits for a descheduled thread (measured here: 2 threads ran the
500-particle pour 50x slower than 1 while another process held the second core). With 1200
particles each, two threads run the 2400-particle tsuji-jet-background bed 1.15-1.2x faster than one
(``benchmarks/threads_ab.py --problem coupled``; the DEM alone 1.2-1.4x), as each keeps its own block of particles
(``_softsphere_kernels.thread_blocks``).
"""

import logging

PARTICLES_PER_THREAD = 1200

log = logging.getLogger(__name__)


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


def launch_pool() -> None:
    """Start Numba's thread pool now, if this process has not yet.

    Numba starts it at the first call of a parallel kernel from Python, or at ``get_num_threads`` /
    ``set_num_threads``, but not when a parallel kernel runs inside another compiled function loaded
    from the cache: that call then finds no pool and the process crashes (numba issue #8578; seen
    here as a segmentation fault of a second ``HardSphereEngine`` script, whose list build calls the
    parallel pair search). The package calls it at import (4 ms), after ``prefer_openmp``: the first
    launch fixes the threading layer.
    """
    import numba

    numba.get_num_threads()


def set_threads(n: int | None, n_particles: int | None = None) -> int:
    """Use ``n`` compute threads (None: one per PARTICLES_PER_THREAD particles, at least one, at most all
    cores; all cores when the count is not given); returns the number in use. More threads than cores
    are not started: the run takes the cores there are and says so in a warning."""
    import numba

    cores = numba.config.NUMBA_NUM_THREADS
    if n is None:
        n = cores
        if n_particles is not None:
            n = min(n, max(1, int(n_particles) // PARTICLES_PER_THREAD))
    elif int(n) > cores:
        log.warning("%d threads asked, %d core%s: using %d", int(n), cores, "" if cores == 1 else "s", cores)
    numba.set_num_threads(max(1, min(int(n), cores)))
    return numba.get_num_threads()
