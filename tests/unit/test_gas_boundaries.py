"""Boundary-condition objects: validation, inflow segments, velocity conversion, pulses."""
import numpy as np
import pytest

from fluidem.errors import CaseError
from fluidem.gas import (FreeSlip, Inflow, Outflow, Periodic, PressureOutlet, Pulse, Segment, Wall,
                         boundary_conditions)


def test_registry_names_every_condition():
    # Hoomans 1996 Table 1's conditions and periodic sides (a condition added by its own file joins them)
    assert {"free_slip", "inflow", "outflow", "periodic", "pressure_outlet", "wall"} <= set(boundary_conditions.names())
    assert boundary_conditions.get("wall") is Wall and boundary_conditions.get("free_slip") is FreeSlip
    with pytest.raises(KeyError, match="did you mean 'outflow'"):
        boundary_conditions.get("outflw")
    assert {c.flag for c in (Wall(), FreeSlip(), Outflow(), Periodic(), PressureOutlet())} == {2, 3, 5, 6, 8}


def test_superficial_velocity_is_converted_with_the_influx_voidage():
    """Hoomans 1996 §5.2: superficial = voidage of the influx cell × interstitial."""
    bc = Inflow(segments=[Segment(superficial=1.8), Segment(interstitial=45.0, start=0.07, end=0.08)], voidage=0.4)
    np.testing.assert_allclose(bc.velocities(0.0), [4.5, 45.0])
    assert Inflow(superficial=2.6, voidage=0.4).velocities(0.0)[0] == pytest.approx(6.5)
    assert Inflow(interstitial=3.0).velocities(1.0)[0] == 3.0  # voidage 1 by default


def test_face_weights_cover_each_face_once_with_later_segments_on_top():
    edges = np.linspace(0.0, 0.15, 16)  # the 15 bottom faces of the Table 2 grid
    bc = Inflow(segments=[Segment(interstitial=1.0), Segment(interstitial=2.0, start=0.065, end=0.085),
                          Segment(interstitial=3.0, start=0.13)])
    w = bc.face_weights(edges)
    assert w.shape == (3, 15)
    np.testing.assert_allclose(w.sum(axis=0), 1.0)  # the background covers everything
    np.testing.assert_allclose(w[1, 6:9], [0.5, 1.0, 0.5])
    np.testing.assert_allclose(w[0, 6:9], [0.5, 0.0, 0.5])
    np.testing.assert_allclose(w[2, 13:], [1.0, 1.0])
    # a side only partly covered leaves the rest impermeable
    gap = Inflow(segments=[Segment(interstitial=1.0, start=0.0, end=0.05), Segment(interstitial=1.0, start=0.1)])
    np.testing.assert_allclose(gap.face_weights(edges).sum(axis=0), [1.0] * 5 + [0.0] * 5 + [1.0] * 5, atol=1e-12)
    # two disjoint segments in one face each keep their own share
    two = Inflow(segments=[Segment(interstitial=1.0, start=0.0, end=0.005), Segment(interstitial=2.0, start=0.005,
                                                                                    end=0.01)])
    np.testing.assert_allclose(two.face_weights(edges)[:, 0], [0.5, 0.5])


def test_pulse_and_time_dependent_velocities():
    pulse = Pulse(2.5, start=0.1, duration=0.2, otherwise=0.5)
    assert [pulse(t) for t in (0.0, 0.1, 0.2999, 0.3, 1.0)] == [0.5, 2.5, 2.5, 0.5, 0.5]
    bc = Inflow(segments=[Segment(superficial=pulse)], voidage=0.5)
    assert bc.velocities(0.2)[0] == pytest.approx(5.0)
    ramp = Inflow(segments=[Segment(interstitial=lambda t: 10.0 * t)])
    assert ramp.velocities(0.3)[0] == pytest.approx(3.0)
    assert PressureOutlet(pressure=lambda t: 1e5 + t).pressure(2.0) == 1e5 + 2.0


@pytest.mark.parametrize("make, message", [
    (lambda: Segment(), "exactly one of interstitial= or superficial="),
    (lambda: Segment(interstitial=1.0, superficial=0.4), "exactly one"),
    (lambda: Segment(interstitial="fast"), "must be a number or a function"),
    (lambda: Segment(interstitial=float("nan")), "must be finite"),
    (lambda: Segment(interstitial=1.0, start=0.1, end=0.05), "end = 0.05 must exceed start = 0.1"),
    (lambda: Inflow(), "give segments="),
    (lambda: Inflow(segments=[1.0]), "is not a Segment"),
    (lambda: Inflow(superficial=1.0, voidage=0.0), "voidage = 0.0: must be > 0"),
    (lambda: Inflow(superficial=1.0, voidage=1.5), "voidage = 1.5: must be a number in"),
    (lambda: PressureOutlet(pressure=-1.0), "pressure = -1.0: must be > 0"),
    (lambda: Pulse(1.0, duration=0.0), "duration = 0.0"),
])
def test_bad_conditions_are_case_errors(make, message):
    with pytest.raises(CaseError, match=message):
        make()
