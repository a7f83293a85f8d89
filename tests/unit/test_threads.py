"""The default thread count: one thread per PARTICLES_PER_THREAD particles, at least one, at most all cores."""
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
    assert _threads.set_threads(None, 2 * per) == min(2, cores)  # the tsuji-jet bed
    assert _threads.set_threads(None, 100 * per) == cores
    assert _threads.set_threads(None) == cores  # no particle count: all cores


def test_threads_asked_for_are_used_up_to_the_cores(keep_threads):
    cores = numba.config.NUMBA_NUM_THREADS
    assert _threads.set_threads(1, 10**6) == 1
    assert _threads.set_threads(cores + 5, 10) == cores
