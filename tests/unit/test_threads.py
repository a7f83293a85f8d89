"""The default thread count: one thread per PARTICLES_PER_THREAD particles, at least one, at most all cores."""
import subprocess
import sys

import numba
import pytest

from fluidem import _threads


@pytest.fixture
def keep_threads():
    before = numba.get_num_threads()
    yield
    numba.set_num_threads(before)


def test_default_threads_follow_the_particle_count(keep_threads):
    cores = numba.config.NUMBA_NUM_THREADS
    per = _threads.PARTICLES_PER_THREAD
    assert _threads.set_threads(None, 500) == 1  # the pour
    assert _threads.set_threads(None, per - 1) == 1
    assert _threads.set_threads(None, 2 * per) == min(2, cores)  # the tsuji-jet-background bed
    assert _threads.set_threads(None, 100 * per) == cores
    assert _threads.set_threads(None) == cores  # no particle count: all cores


def test_threads_asked_for_are_used_up_to_the_cores(keep_threads):
    cores = numba.config.NUMBA_NUM_THREADS
    assert _threads.set_threads(1, 10**6) == 1
    assert _threads.set_threads(cores + 5, 10) == cores


CACHED_NESTED_PARALLEL = """
import numpy as np
from fluidem.particles import _hardsphere_kernels as K
rng = np.random.default_rng(3)
pos = rng.uniform(0.0, 0.05, (500, 3))
pos[:, 2] = 0.002
start, nbr = K.build_neighbours(pos, np.full(500, 1e-3), 5e-4, True)
print(start[-1])
"""


def test_a_cached_kernel_with_a_parallel_kernel_inside_runs_in_a_fresh_process():
    """The hard-sphere list build runs the parallel pair search inside compiled code. Loaded from the
    cache in a process that has not started Numba's thread pool, such a call crashes the process
    (numba/numba#8578), so importing fluidem starts the pool (``_threads.launch_pool``). Two fresh
    processes: the first compiles or loads the kernel, the second surely loads it from the cache."""
    runs = [subprocess.run([sys.executable, "-c", CACHED_NESTED_PARALLEL], capture_output=True, text=True,
                           timeout=600) for _ in range(2)]
    for r in runs:
        assert r.returncode == 0, f"exit status {r.returncode}: {r.stderr[-2000:]}"
    assert runs[0].stdout == runs[1].stdout and int(runs[1].stdout) > 0
