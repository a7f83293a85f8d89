"""A coupled run stopped at a checkpoint and resumed equals the run made in one go (the gas state
and the phase within the gas step are in the restart file). Not bit for bit: the resumed gas
solver starts with a fresh pressure-matrix factorisation where the uninterrupted one reuses an
older one (``jacobian_reuse``), so the two agree to the gas tolerance, not to the last bit."""
import numpy as np
import pytest

from fluidem.case import validate_case
from test_coupled_settling import settling_case


def test_resumed_coupled_run_matches_the_uninterrupted_one(stopped_and_resumed):
    case = validate_case(settling_case(end=0.02))
    whole, first, again = stopped_and_resumed(case, 0.0105)  # stops inside a gas step (DT = 1 ms)
    assert first.step % first.gas.substeps != 0
    assert again.step == whole.step
    np.testing.assert_allclose(again.state.position, whole.state.position, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(again.state.velocity, whole.state.velocity, rtol=1e-6, atol=1e-12)
    np.testing.assert_allclose(again.gas.state.p, whole.gas.state.p, rtol=1e-12)
    for k in ("u", "v"):
        np.testing.assert_allclose(getattr(again.gas.state, k), getattr(whole.gas.state, k), rtol=0, atol=1e-9)


def test_largest_gas_courant_number_is_kept_across_a_resume(stopped_and_resumed):
    """``courant_max`` (summary ``gas_courant_max``) is the largest max|u| DT/dx + max|v| DT/dy of the
    run's gas steps, carried in the checkpoint."""
    case = validate_case(settling_case(end=0.02))
    whole, first, again = stopped_and_resumed(case, 0.0105)
    gs, gd, dt = whole.gas.state, whole.gas.grid, whole.gas.gas_dt
    last = np.abs(gs.u).max() * dt / gd.dx + np.abs(gs.v).max() * dt / gd.dy
    assert whole.gas.last_info.courant == pytest.approx(last, rel=1e-12)
    assert whole.gas.courant_max >= last > 0.0
    assert 0.0 < first.gas.courant_max <= whole.gas.courant_max
    assert again.gas.courant_max == pytest.approx(whole.gas.courant_max, rel=1e-6)
    assert whole.summary()["gas_courant_max"] == whole.gas.courant_max
