"""Discharge analysis (``analysis.discharge``): the steady rate of a discharge curve, Beverloo's
correlation by hand, and the bulk density of a lattice."""
from __future__ import annotations

import math

import numpy as np
import pytest

from fluidem.analysis.discharge import beverloo_rate, bulk_density, steady_rate


def test_steady_rate_is_the_slope_of_the_middle_of_the_discharge():
    """A curve that starts slowly, runs at 0.12 kg/s and tails off: the window 20-60 % of the final mass lies
    on the straight part, whose slope comes back to round-off."""
    t = np.linspace(0.0, 3.0, 301)
    m = np.where(t < 0.3, 0.2 * t**2, 0.018 + 0.12 * (t - 0.3))
    m = np.minimum(m, 0.25 - 0.01 * np.exp(-(t - 2.0)))  # a tail that flattens as the bed runs out
    rate, a, b = steady_rate(t, m)
    assert rate == pytest.approx(0.12, rel=1e-9)
    assert 0.3 < a < b < 2.0
    with pytest.raises(ValueError, match="at least 3"):
        steady_rate(t[:2], m[:2])


def test_beverloo_by_hand():
    # C ρ_b √g (D0 − k d)^2.5 = 0.58 · 1500 · 3.13209 · (0.024 − 1.5 · 0.004)^2.5 = 2724.9 · 4.3469e-5 = 0.11845 kg/s
    assert beverloo_rate(1500.0, 0.024, 0.004) == pytest.approx(0.58 * 1500 * math.sqrt(9.81) * 0.018**2.5,
                                                               rel=1e-12)
    assert beverloo_rate(1500.0, 0.024, 0.004) == pytest.approx(0.11845, rel=1e-4)
    assert beverloo_rate(1500.0, 0.024, 0.004, k=1.4) == pytest.approx(0.12514, rel=1e-4)
    with pytest.raises(ValueError, match="not above"):
        beverloo_rate(1500.0, 0.005, 0.004)


def test_bulk_density_of_a_cubic_lattice():
    """Spheres of diameter d on a simple cubic lattice of pitch d pack at π/6; a region of many cells
    returns π/6 ρ to within its edge cells: 20 layers between heights off the lattice planes, and 317 lattice
    points within 10 pitches of the axis where the circle's area holds 314.2 (1 %)."""
    d, rho = 0.004, 2500.0
    g = np.arange(-15, 16) * d
    x, y, z = np.meshgrid(g, g, np.arange(0, 30) * d, indexing="ij")
    pos = np.column_stack([x.ravel(), y.ravel(), z.ravel()])
    got = bulk_density(pos, np.full(len(pos), d / 2), rho, (0.0, 0.0, 0.0), (0.0, 0.0, 1.0), 10 * d, 5.5 * d, 25.5 * d)
    assert got == pytest.approx(math.pi / 6 * rho * 317 / (100 * math.pi), rel=1e-12)
