"""Contact numbers under the readings of Sun 2007's N_c (analysis.contact_census), on a hand-made set of
eight discs of 4 mm whose contacts are known by construction."""
import math

import numpy as np
import pytest

from fluidem.analysis.contact_census import bulk, census, normal_force, touching_pairs

R = 0.002  # [m]
K, ETA = 800.0, 0.018  # Sun 2007 Table 1, central jet: k_n [N/m], eta_n [N s/m]
OV = 1e-5  # [m] overlap of the touching pairs: k delta = 8e-3 N


def hand_made():
    """0-1-2 a row of three touching discs (N_c 1, 2, 1); 3-4 a touching pair separating at 1 m/s
    (eta v = 1.8e-2 N > k delta: the normal force pulls); 5 alone on the floor (overlap 1e-4 m with the
    wall y = 0); 6-7 a pair 1 micron apart (no contact)."""
    z = R
    x0 = 0.03
    pos = np.array([[x0, 0.05, z], [x0 + 2 * R - OV, 0.05, z], [x0 + 4 * R - 2 * OV, 0.05, z],
                    [0.08, 0.05, z], [0.08 + 2 * R - OV, 0.05, z],
                    [0.12, R - 1e-4, z],
                    [0.05, 0.10, z], [0.05, 0.10 + 2 * R + 1e-6, z]])
    vel = np.zeros_like(pos)
    vel[3, 0], vel[4, 0] = -0.5, 0.5  # v_3 - v_4 along n_34 (from 4 to 3, -x): +1 m/s, separating
    return pos, vel, np.full(len(pos), R)


def test_touching_pairs_are_the_constructed_ones():
    pos, _, rad = hand_made()
    i, j, ov = touching_pairs(pos, rad)
    assert sorted(zip(i.tolist(), j.tolist())) == [(0, 1), (1, 2), (3, 4)]
    assert ov == pytest.approx([OV] * 3, rel=1e-6)


def test_normal_force_of_sun_eq21():
    pos, vel, rad = hand_made()
    i, j, ov = np.array([3]), np.array([4]), np.array([OV])
    # k delta - eta (v_i - v_j).n = 800 * 1e-5 - 0.018 * 1.0
    assert normal_force(pos, vel, i, j, ov, K, ETA)[0] == pytest.approx(K * OV - ETA * 1.0, rel=1e-6)
    assert normal_force(pos, -vel, i, j, ov, K, ETA)[0] == pytest.approx(K * OV + ETA * 1.0, rel=1e-6)


def test_readings_of_the_contact_number():
    pos, vel, rad = hand_made()
    nc = census(pos, vel, rad, K, ETA, lower=(0.0, 0.0, 0.0), upper=(0.15, 0.9, 2 * R))
    assert nc["overlap"].tolist() == [1, 2, 1, 1, 1, 0, 0, 0]
    assert nc["force"].tolist() == [1, 2, 1, 0, 0, 0, 0, 0]
    assert nc["walls"].tolist() == [1, 2, 1, 1, 1, 1, 0, 0]
    # bulk coordination: the mean over all eight; multicontact: N_c > 1 over N_c >= 1
    assert bulk(nc["overlap"]) == pytest.approx((6 / 8, 1 / 5))
    assert bulk(nc["force"]) == pytest.approx((4 / 8, 1 / 3))
    assert bulk(nc["walls"]) == pytest.approx((7 / 8, 1 / 6))


def test_no_contacts():
    c, m = bulk(np.zeros(4, dtype=int))
    assert c == 0.0 and math.isnan(m)
