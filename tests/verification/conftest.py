"""Verification tests run their compiled loops on one thread unless FLUIDEM_TEST_THREADS says otherwise.

The systems here are tiny (1–300 particles) and are stepped in many short calls.
With several OpenMP threads each parallel region costs far more than its work, and
on a shared 2-core machine whose other core is busy the spinning threads were
measured at 2–30 ms per step for one particle (against 3 µs on one thread).
Results do not depend on the thread count, but the code path does: with one thread
the engine takes its serial scatter path, with more the parallel gather path. Run
``FLUIDEM_TEST_THREADS=2 pytest tests/verification`` on an idle machine to verify
the parallel path too. Tests that need every thread request the ``all_threads`` fixture.
"""
import os

import numba
import pytest


def _threads() -> int:
    want = int(os.environ.get("FLUIDEM_TEST_THREADS", "1"))
    return max(1, min(want, numba.config.NUMBA_NUM_THREADS))


@pytest.fixture(autouse=True)
def _test_threads():
    before = numba.get_num_threads()
    numba.set_num_threads(_threads())
    yield
    numba.set_num_threads(before)


@pytest.fixture
def all_threads(_test_threads):
    """Every thread Numba has, for kernels whose parallel path is the point of the test."""
    numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
