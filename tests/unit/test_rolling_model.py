"""The rolling-model keys: packed slots, the refusal of a rolling dashpot without a spring, and the history
columns an ``epsd`` law adds (only where some law uses it; the plane-wall columns are read by
``tests/verification/test_rolling_spring.py``)."""
from __future__ import annotations

import numpy as np
import pytest
from pydantic import ValidationError

from fluidem.particles.contact.base import (ROLLING_CDT, ROLLING_EPSD, ROLLING_HISTORY, SLOT_ROLLING_DAMPING,
                                            SLOT_ROLLING_FRICTION, SLOT_ROLLING_MODEL)
from fluidem.particles.contact.hertz_mindlin import HertzMindlin
from fluidem.particles.contact.spring_dashpot import LinearSpringDashpot


def test_packed_rolling_slots():
    cdt = LinearSpringDashpot(stiffness=1e4, rolling_friction=0.1).pack(None, None)
    assert (cdt[SLOT_ROLLING_FRICTION], cdt[SLOT_ROLLING_MODEL], cdt[SLOT_ROLLING_DAMPING]) == (0.1, ROLLING_CDT, 0.0)
    epsd = LinearSpringDashpot(stiffness=1e4, rolling_friction=0.1, rolling_model="epsd",
                               rolling_damping=0.3).pack(None, None)
    assert (epsd[SLOT_ROLLING_FRICTION], epsd[SLOT_ROLLING_MODEL], epsd[SLOT_ROLLING_DAMPING]) == \
        (0.1, ROLLING_EPSD, 0.3)
    none = LinearSpringDashpot(stiffness=1e4, rolling_model="epsd").pack(None, None)
    assert none[SLOT_ROLLING_MODEL] == 0.0, "without rolling friction there is no rolling model to run"


def test_rolling_damping_needs_epsd():
    with pytest.raises(ValidationError, match="rolling_damping = 0.3 needs rolling_model = 'epsd'"):
        HertzMindlin(youngs_modulus=1e7, poisson_ratio=0.3, rolling_friction=0.1, rolling_damping=0.3)
    with pytest.raises(ValidationError, match="rolling_model"):
        LinearSpringDashpot(stiffness=1e4, rolling_friction=0.1, rolling_model="epsd3")


@pytest.mark.parametrize("rolling_model,width", [("cdt", 3), ("epsd", ROLLING_HISTORY + 3)])
def test_history_columns(two_particles, rolling_model, width):
    eng = two_particles(overlap=1e-5, model="linear_spring_dashpot", rolling_friction=0.1,
                        rolling_model=rolling_model, stiffness=1e4)
    assert eng.hist.shape[1] == width
    assert np.all(eng.hist[:, 3:] == 0.0)


def test_rolling_spring_changes_sign_with_the_pair_owner():
    """A pair listed under its other particle after a rebuild: the springs (tangential, columns 0-2, and rolling,
    4-6) are kept relative to the owner and change sign; the adhesive column 3 is a scalar of the pair."""
    from fluidem.particles._neighbours_kernels import carry_history

    old_start, old_partner = np.array([0, 1, 1]), np.array([1], dtype=np.int32)  # pair (0, 1) owned by 0
    old_hist = np.array([[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0]])
    new_start, new_partner = np.array([0, 0, 1]), np.array([0], dtype=np.int32)  # now owned by 1
    hist = carry_history(old_start, old_partner, old_hist, new_start, new_partner)
    np.testing.assert_array_equal(hist, [[-1.0, -2.0, -3.0, 4.0, -5.0, -6.0, -7.0]])
