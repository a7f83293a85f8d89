"""The gas section of a case file: the gas step against the fastest inflow (``GasSection._inflow_courant``)."""
import pytest

from fluidem.case import load_case
from fluidem.errors import CaseError


def test_a_gas_step_whose_inflow_crosses_more_than_a_cell_is_refused_with_the_largest_allowed_step():
    """tsuji-jet-background: the 39 m/s jet into 0.02 m tall cells allows DT up to 0.02 / 39 = 5.13e-4 s (upwind)."""
    assert load_case("tsuji-jet-background", {"gas.dt": 5.1e-4}).gas.dt == 5.1e-4
    with pytest.raises(CaseError) as err:
        load_case("tsuji-jet-background", {"gas.dt": 1e-3})
    msg = str(err.value)
    assert "gas.dt = 0.001 s" in msg and "39 m/s" in msg and "1.95 cells" in msg
    assert "at most 1 with convection = 'upwind'" in msg and "use gas.dt <= 0.000513 s" in msg


def test_tvd_convection_halves_the_allowed_step():
    with pytest.raises(CaseError, match=r"at most 0.5 with convection = 'tvd': use gas.dt <= 0.000256 s"):
        load_case("tsuji-jet-background", {"gas.dt": 3e-4, "gas.convection": "tvd"})


def test_pulses_count_at_their_peak_and_superficial_velocities_as_interstitial():
    """hoomans-experiment: a 2.5 m/s superficial pulse through a distributor of voidage 0.4 is 6.25 m/s
    interstitial; 5 mm cells allow DT up to 8e-4 s."""
    with pytest.raises(CaseError, match=r"6.25 m/s \(interstitial\).*use gas.dt <= 0.0008 s"):
        load_case("hoomans-experiment", {"gas.dt": 1e-3})


def test_tables_count_at_their_fastest_point():
    bottom = {"kind": "inflow", "superficial": {"table": [[0.0, 0.0], [1.0, 50.0], [2.0, 10.0]]}}
    assert load_case("tsuji-jet-background", {"gas.boundaries.bottom": bottom, "gas.dt": 4e-4}).gas.dt == 4e-4
    with pytest.raises(CaseError, match=r"50 m/s \(interstitial\) crosses 1.25 cells"):
        load_case("tsuji-jet-background", {"gas.boundaries.bottom": bottom, "gas.dt": 5e-4})
