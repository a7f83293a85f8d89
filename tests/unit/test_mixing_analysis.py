"""Per-species analyses (analysis/mixing.py) on hand-made beds whose answers are known in closed form."""
from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from fluidem.analysis.mixing import lacey_index, segregation_index, species_heights
from fluidem.gas import StaggeredGrid

GRID = StaggeredGrid(cells=(10, 20), size=(0.1, 0.2), depth=0.004)


def engine(position, species, lower=(0.0, 0.0, 0.0)):
    state = SimpleNamespace(position=np.asarray(position, float), species=np.asarray(species, np.int64))
    walls = SimpleNamespace(box_lower=np.asarray(lower, float))
    return SimpleNamespace(state=state, walls=walls, gravity=np.array([0.0, -9.81, 0.0]))


def layers(h, n_per_row=40, rows=20, a_on_top=True):
    """Two layers of equal count (and volume): rows 0..rows/2−1 of one species, the rest of the other, in
    a bed of height h (centres evenly spaced from 0 to h)."""
    y = (np.arange(rows) + 0.5) * h / rows
    x = (np.arange(n_per_row) + 0.5) * GRID.size[0] / n_per_row
    pos = np.array([[xi, yi, 0.002] for yi in y for xi in x])
    top = pos[:, 1] > h / 2
    species = np.where(top, 0, 1) if a_on_top else np.where(top, 1, 0)
    return pos, species


def test_species_heights_are_the_mean_centre_heights_above_the_floor():
    pos = [[0.01, 0.03, 0.0], [0.02, 0.05, 0.0], [0.03, 0.11, 0.0]]
    h = species_heights(engine(pos, [0, 0, 1], lower=(0.0, 0.01, 0.0)), 3)
    np.testing.assert_allclose(h[:2], [0.03, 0.10], rtol=1e-14)
    assert math.isnan(h[2])  # an empty species


def test_two_layers_of_equal_volume_give_an_index_of_one_with_the_sign_of_the_top_species():
    h = 0.08
    for a_on_top, sign in ((True, 1.0), (False, -1.0)):
        pos, species = layers(h, a_on_top=a_on_top)
        ha, hb = species_heights(engine(pos, species), 2)
        assert ha == pytest.approx(3 * h / 4 if a_on_top else h / 4, rel=1e-12)
        assert segregation_index(ha, hb) == pytest.approx(sign * 1.0, rel=1e-12)
    assert segregation_index(0.05, 0.05) == 0.0
    assert math.isnan(segregation_index(math.nan, 0.05))


def test_lacey_index_is_zero_for_a_segregated_bed_and_one_over_one_minus_one_over_n_for_uniform_cells():
    volume = np.full(800, 1e-9)
    # segregated: every cell holds one species only (the layers split at a cell boundary, 0.04 m)
    pos, species = layers(0.08)
    assert lacey_index(GRID, pos, volume, species == 0) == pytest.approx(0.0, abs=1e-12)
    # each cell holds 2 of each species: x_c = p everywhere, σ² = 0, M = σ₀²/(σ₀² − σ₀²/n̄) with n̄ = 4
    cells = [(i, j) for i in range(10) for j in range(20)]
    pos = np.array([[(i + f) * GRID.dx, (j + 0.5) * GRID.dy, 0.0] for i, j in cells for f in (0.2, 0.4, 0.6, 0.8)])
    is_a = np.tile([True, False, True, False], len(cells))
    assert lacey_index(GRID, pos, np.full(len(pos), 1e-9), is_a) == pytest.approx(1.0 / (1.0 - 1.0 / 4.0), rel=1e-12)


def test_lacey_index_of_a_random_mixture_is_one_on_average():
    """Particles of equal volume, each of species a with probability p, n per cell: E[σ²] = p(1 − p)/n, so
    the index averages 1 over many beds (Lacey 1954)."""
    rng = np.random.default_rng(7)
    n_per_cell, p = 9, 0.3
    cells = [(i, j) for i in range(10) for j in range(20)]
    pos = np.array([[(i + 0.5) * GRID.dx, (j + 0.5) * GRID.dy, 0.0] for i, j in cells for _ in range(n_per_cell)])
    values = [lacey_index(GRID, pos, np.full(len(pos), 1e-9), rng.random(len(pos)) < p) for _ in range(200)]
    # the standard error of the mean of 200 beds is about 0.01 here
    assert np.mean(values) == pytest.approx(1.0, abs=0.04)
