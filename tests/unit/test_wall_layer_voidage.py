"""The slab solids fraction of the u_mf wall study (``_helpers.umf_walls``) against closed forms.

A sphere cut by planes (the spherical cap, V(h) = π (r²(h + r) − (h³ + r³)/3) below the plane at h from the
centre) and the half-diameter layer at a flat wall under a hexagonal layer of spheres touching it: its solids
fraction is (2/3) π r² n_A with n_A = 1/(2√3 r²), i.e. π/(3√3) = 0.6046 (voidage 0.3954), the same as
the whole layer's, 0 < z < 2r. A random layer at a wall keeps the same (2/3) π r² n_A with its own n_A.
"""
import math

import numpy as np
import pytest

from _helpers.umf_walls import cap_volume, slab_fraction

R = 0.25e-3  # [m]


def test_cap_volume_limits():
    full = 4.0 / 3.0 * math.pi * R**3
    assert cap_volume(np.array([R, 0.0, -R, 2 * R, -2 * R]), R) == pytest.approx([full, full / 2, 0.0, full, 0.0])


def test_cap_volume_is_the_spherical_cap():
    h = 0.3 * R  # cap of height r − h above the plane: π t² (3r − t)/3 with t = r − h
    t = R - h
    assert 4.0 / 3.0 * math.pi * R**3 - cap_volume(h, R) == pytest.approx(math.pi * t * t * (3 * R - t) / 3.0)


def hexagonal_layer(m=8, k=6):
    """Centres (N,) of z and the cross-section area [m²] of a hexagonal layer touching the wall z = 0."""
    x = np.arange(m) * 2 * R
    rows = [np.column_stack([x + (R if j % 2 else 0.0), np.full(m, j * math.sqrt(3) * R)]) for j in range(2 * k)]
    xy = np.vstack(rows)
    area = (2 * R * m) * (math.sqrt(3) * R * 2 * k)
    return np.full(xy.shape[0], R), area, xy.shape[0] / area


def test_half_diameter_layer_of_a_hexagonal_layer():
    z, area, n_a = hexagonal_layer()
    assert n_a == pytest.approx(1.0 / (2 * math.sqrt(3) * R * R))
    half = slab_fraction(z, R, np.array([0.0, R]), area)[0]
    assert half == pytest.approx(2.0 / 3.0 * math.pi * R * R * n_a)
    assert half == pytest.approx(math.pi / (3 * math.sqrt(3)))
    assert slab_fraction(z, R, np.array([0.0, 2 * R]), area)[0] == pytest.approx(half)


def test_slabs_add_up_to_the_spheres_volume():
    rng = np.random.default_rng(3)
    z = rng.uniform(R, 10 * R, 200)
    edges = np.linspace(0.0, 11 * R, 45)
    phi = slab_fraction(z, R, edges, 1.0)
    assert np.sum(phi * np.diff(edges)) == pytest.approx(z.size * 4.0 / 3.0 * math.pi * R**3)
