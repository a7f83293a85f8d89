"""Validation: what raises u_mf of the narrow sweep beds (test_umf_sweep.py) above Wen & Yu.

The 20 × 5 diameter bed of ``_helpers.umf_sweep`` (2000 frictionless 0.5 mm glass spheres, gas cells of
4 d × 4 d, the bed about 17 d high: 4.3 cell rows), measured by ``umf_walls.measure`` at the end of the
gas-free settling and in the fixed bed of the sweep (U = 0.05-0.15 m/s, below u_mf):

- Janssen: particle and wall friction are 0, so the walls' forces are horizontal and carry no weight.
- The wall layers: the first half diameter at each wall holds the caps of the layer of spheres that
  touches it, (2/3) π r² n_A of solids per volume (n_A the touching centres per wall area), with a few
  spheres of the next layer reaching in: voidage 0.47-0.52, not ≈ 1; the slab just beyond (0.3-0.6 d)
  is the densest of the bed (0.20-0.22), and the cross-section's mean voidage equals the core's
  (more than 1.5 d from every wall) within 0.005 (four placements: equivalent layer of voidage 1
  of 0.000-0.005 d). The walls do not loosen what the depth-averaged gas sees.
- The gas: in the interior of the fixed bed (3-11 d above the floor) each particle carries 0.89-0.99 of
  Ergun's force at the bed's mean voidage; the top five diameters carry 0.88 down to 0.15 (the partly
  filled top row of cells takes the row's mean voidage, and the particles interpolate between it and the
  empty row above, ε → 1), the lowest ones 0.89-0.91 (the gas velocity interpolated towards the inflow
  face's U/ε_in, ε_in = 1). The bed's pressure drop is 0.79-0.83 of Ergun's, and u_mf comes out
  1.23 times Ergun's at the mean voidage (0.237 against 0.192 m/s).
- With rows of one diameter (``gas.grid.cells = [5, 60]``) the same bed's pressure drop is 0.94-0.97 of
  Ergun's and u_mf 0.2095 m/s (1.07 times Ergun's 0.1954); rows of 2 d: 0.2129 m/s (1.10 times): the
  excess over Ergun goes with the vertical cell size. The width and depth of the bed change u_mf through
  the packing: ε̄ 0.385-0.388 in beds 5 d deep, 0.371-0.377 in beds 10 d deep (Ergun's u_mf 0.189-0.195
  against 0.168-0.176 m/s), which is the difference between +24 % (20 × 5 d) and +7 % (60 × 10 d).

    NUMBA_NUM_THREADS=1 python -m pytest -m validation tests/validation/test_umf_walls.py -s   # 2 min
    python tests/validation/umf_walls.py [--width 20] [--depth 5] [--set KEY=VALUE]            # one bed
"""
import numpy as np
import pytest

from _helpers.umf_walls import measure

pytestmark = pytest.mark.validation

ERGUN_TOLERANCE = 0.10  # Ergun's equation for a bed of equal spheres, read as ±10 %


@pytest.fixture(scope="module")
def bed():
    return measure(20.0, 5.0)


@pytest.fixture(scope="module")
def fine_rows():
    return measure(20.0, 5.0, overrides={"gas.grid.cells": [5, 60]})


def test_sweep_bed_is_frictionless(bed):
    """No friction at the particles or the walls: no weight carried by the walls (Janssen)."""
    assert bed["particle_friction"] == 0.0 and bed["wall_friction"] == 0.0


def test_wall_layer_holds_the_caps_of_the_touching_layer(bed):
    """Measured 0.47-0.52 against 0.49-0.57 from the touching layer's caps (the rest: spheres of the next layer)."""
    for solids, caps, _ in bed["wall_layers"]:
        assert caps - 0.005 <= solids <= caps + 0.08
        assert 0.4 < 1.0 - solids < 0.6


def test_walls_do_not_loosen_the_mean_voidage(bed):
    """Cross-section mean against the core: measured 0.3874 against 0.3859."""
    assert abs(bed["eps_mean"] - bed["eps_core"]) < 0.01


def test_interior_carries_ergun_force(bed):
    """Gas force per particle 3-11 d above the floor over Ergun's at ε̄: measured 0.89-0.99."""
    ratio = bed["layer_force_over_ergun"][3:11]
    assert np.all(np.abs(ratio - 1.0) < ERGUN_TOLERANCE + 0.02)  # + the interior cells' voidage above ε̄ (≤ 0.006)


@pytest.mark.xfail(strict=True, reason="rows of 4 d: the fixed bed's pressure drop is 0.79-0.83 of Ergun's at the "
                   "mean voidage (u_mf 1.23 times Ergun's): the top five diameters carry 0.15-0.88 of Ergun's force, the "
                   "partly filled top row and the interpolation towards the empty row above")
def test_fixed_bed_pressure_drop_is_ergun(bed):
    assert abs(bed["fixed_dp_over_ergun"] - 1.0) < ERGUN_TOLERANCE


def test_fixed_bed_pressure_drop_is_ergun_with_one_diameter_rows(fine_rows):
    """Rows of one diameter: measured 0.94-0.97 of Ergun's, u_mf 1.07 times Ergun's at ε̄."""
    assert abs(fine_rows["fixed_dp_over_ergun"] - 1.0) < ERGUN_TOLERANCE
