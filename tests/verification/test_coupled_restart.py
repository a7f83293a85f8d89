"""A coupled run stopped at a checkpoint and resumed equals the run made in one go, bit for bit: the
gas state, the phase within the gas step and the pressure-matrix factors the next gas step reuses
(``jacobian_reuse``) are in the restart file. Without the factors the resumed solver would factorise
afresh and the two runs would agree only to the gas tolerance, which a bubbling bed amplifies into
another flow within a fraction of a second."""
import numpy as np
import pytest

from fluidem.case import validate_case

from _helpers.settling import settling_case


def test_resumed_coupled_run_matches_the_uninterrupted_one(stopped_and_resumed):
    case = validate_case(settling_case(end=0.02))
    whole, first, again = stopped_and_resumed(case, 0.0105)  # stops inside a gas step (DT = 1 ms)
    assert first.steps % first.gas.substeps != 0
    assert again.steps == whole.steps
    for k in ("position", "velocity", "omega"):
        assert np.array_equal(getattr(again.state, k), getattr(whole.state, k)), k
    for k in ("p", "rho", "u", "v", "voidage"):
        assert np.array_equal(getattr(again.gas.state, k), getattr(whole.gas.state, k)), k


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
