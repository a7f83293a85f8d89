"""Sun 2007 analyses (analysis/fluidised.py) on hand-made data with known answers."""
from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from fluidem.analysis import fluidised as F
from fluidem.gas.grid import StaggeredGrid


def grid(nx=3, ny=10, w=0.15, h=0.5):
    return StaggeredGrid(cells=(nx, ny), size=(w, h), depth=0.004)


def test_pressure_drop_of_a_linear_profile_is_exact():
    """p = p0 − a y (plus a lateral variation that averages out): Δp(0 → 0.2) = 0.2 a, even below the first centre."""
    g = grid()
    x, y = np.meshgrid(g.x_centres, g.y_centres, indexing="ij")
    a = 1234.5
    p = 101325.0 - a * y + 7.0 * (x - x.mean())
    assert F.pressure_drop(g, p, 0.2) == pytest.approx(0.2 * a, rel=1e-12)
    top = g.y_centres[-1] + 0.5 * g.dy  # extrapolated above the last centre
    assert F.pressure_drop(g, p, top) == pytest.approx(top * a, rel=1e-12)


def test_pressure_at_a_point_is_bilinear_and_exact_for_a_plane():
    g = grid()
    x, y = np.meshgrid(g.x_centres, g.y_centres, indexing="ij")
    p = 100.0 + 3.0 * x - 50.0 * y
    assert F.pressure_at(g, p, 0.075, 0.2) == pytest.approx(100.0 + 3.0 * 0.075 - 50.0 * 0.2, rel=1e-12)


def test_multicontact_ratio_counts_particles_not_contacts():
    nc = np.array([0, 1, 1, 2, 3, 0])
    assert F.multicontact_ratio(nc) == pytest.approx(2 / 4)
    assert math.isnan(F.multicontact_ratio(np.zeros(5, int)))


def test_contact_numbers_of_a_chain():
    """Three spheres in a touching row and one apart: N_c = 1, 2, 1, 0."""
    from fluidem.particles._neighbours_kernels import build_pairs

    d = 1e-3
    pos = np.array([[0, 0, 0], [0.999 * d, 0, 0], [1.998 * d, 0, 0], [5 * d, 0, 0]], float)
    r = np.full(4, d / 2)
    rs, partner, _, _ = build_pairs(pos, r, 0.1 * d, False)
    eng = SimpleNamespace(state=SimpleNamespace(position=pos, radius=r, n=4), row_start=rs, partner=partner)
    assert F.contact_numbers(eng).tolist() == [1, 2, 1, 0]


def test_cell_force_maps_means_ratio_and_empty_cells():
    g = grid(nx=2, ny=2, w=0.2, h=0.2)  # cells of 0.1 m
    pos = np.array([[0.05, 0.05, 0], [0.06, 0.04, 0], [0.15, 0.05, 0]])
    m = np.array([1.0, 2.0, 1.0])
    grav = np.array([0.0, -10.0, 0.0])
    contact = np.array([[30.0, 40.0, 0], [0, 40.0, 0], [5.0, 0, 0]])  # |F|/mg = 5, 2, 0.5
    drag = np.array([[0, 10.0, 0], [0, 20.0, 0], [0, 0, 0]])  # 1, 1, 0
    out = F.cell_force_maps(g, pos, m, contact, drag, grav)
    assert out["contact_force"][0, 0] == pytest.approx(3.5)
    assert out["drag_force"][0, 0] == pytest.approx(1.0)
    assert out["force_ratio"][0, 0] == pytest.approx(3.5)
    assert out["force_ratio"][1, 0] == -1.0  # drag zero there (Sun's legend)
    assert np.isnan(out["contact_force"][0, 1]) and np.isnan(out["force_ratio"][1, 1])
    assert out["particles"].sum() == 3


def test_dominant_frequency_of_a_noisy_sine():
    rng = np.random.default_rng(0)
    t = np.arange(0.0, 5.0, 0.01)
    s = 300.0 + 50.0 * np.sin(2 * np.pi * 2.6 * t) + 5.0 * rng.standard_normal(t.size)
    # resolution 1/5 s = 0.2 Hz: the peak bin is the one nearest 2.6 Hz
    assert F.dominant_frequency(t, s) == pytest.approx(2.6, abs=0.1)
    assert math.isnan(F.dominant_frequency(t[:4], s[:4]))


def test_spectral_peaks_of_two_tones_give_both_frequencies_and_their_power_ratio():
    """Two sines of amplitudes 50 and 40 Pa on bins of the Welch spectrum (5 s at 100 Hz: segments of 250
    samples, 0.4 Hz apart): peaks at 2.0 and 6.0 Hz, the second (0.8)² = 0.64 as high; the mean and weak
    noise do not count."""
    rng = np.random.default_rng(1)
    t = np.arange(0.0, 5.0 + 1e-9, 0.01)
    s = 2000.0 + 50.0 * np.sin(2 * np.pi * 2.0 * t) + 40.0 * np.sin(2 * np.pi * 6.0 * t + 1.0)
    s += 2.0 * rng.standard_normal(t.size)
    peaks, heights = F.spectral_peaks(t, s, count=2)
    assert peaks == pytest.approx([2.0, 6.0], abs=1e-9)
    assert heights[0] == 1.0 and heights[1] == pytest.approx(0.64, abs=0.03)
    # the louder tone second: the order follows
    louder_second = 2000.0 + 30.0 * np.sin(2 * np.pi * 2.0 * t) + 60.0 * np.sin(2 * np.pi * 6.0 * t)
    peaks, heights = F.spectral_peaks(t, louder_second)
    assert peaks[:2] == pytest.approx([6.0, 2.0], abs=1e-9) and heights[1] == pytest.approx(0.25, abs=0.02)
    assert F.spectral_peaks(t[:10], s[:10]) == ([], [])
    assert F.spectral_peaks(t, np.full(t.size, 5.0)) == ([], [])


def test_averaging_window_is_sun_5_to_10_s_or_the_second_half():
    assert F.averaging_window(20.0) == (5.0, 10.0)
    assert F.averaging_window(10.0) == (5.0, 10.0)
    assert F.averaging_window(2.0) == (1.0, 2.0)


def test_time_averages_from_probes_csv(tmp_path):
    t = np.arange(0.0, 12.0 + 1e-9, 0.01)
    h = np.where((t >= 5.0) & (t <= 10.0), 0.09, 0.5)  # only the window's value may enter the mean
    p = 1000.0 + 100.0 * np.sin(2 * np.pi * 3.0 * t)
    lines = ["time_s,step,mean_particle_height_m,coordination,multicontact_ratio,pressure_drop_20cm_Pa"]
    lines += [f"{a:.10g},{k},{b:.10g},0.5,nan,{c:.10g}" for k, (a, b, c) in enumerate(zip(t, h, p))]
    (tmp_path / "probes.csv").write_text("\n".join(lines) + "\n")
    out = F.time_averages(tmp_path / "probes.csv", 12.0)
    assert out["averages_window_s"] == [5.0, 10.0]
    assert out["averages_samples"] == 501
    assert out["mean_particle_height_avg_m"] == pytest.approx(0.09)
    assert out["coordination_number_avg"] == pytest.approx(0.5)
    assert out["multicontact_ratio_avg"] is None  # only NaN samples
    assert out["pressure_drop_20cm_avg_Pa"] == pytest.approx(1000.0, abs=0.5)
    assert out["pressure_20cm_dominant_frequency_Hz"] == pytest.approx(3.0, abs=0.2)
    # Welch bins 0.4 Hz apart: 3 Hz lies between 2.8 and 3.2
    assert out["pressure_20cm_spectral_peaks_Hz"][0] in (pytest.approx(2.8), pytest.approx(3.2))
    assert out["pressure_20cm_spectral_peak_heights"][0] == 1.0
    assert F.time_averages(tmp_path / "missing.csv", 1.0) == {}


def test_minimum_fluidisation_recovers_ergun_umf_from_a_synthetic_sweep():
    """Δp = a U + b U² up to W/A, then W/A with noise: the fit meets W/A at the exact root."""
    a, b, w = 600.0, 120.0, 128.0
    umf = (-a + math.sqrt(a * a + 4 * b * w)) / (2 * b)
    u = np.linspace(0.0, 0.5, 201)
    rng = np.random.default_rng(1)
    dp = np.where(u < umf, a * u + b * u**2, w + 5.0 * rng.standard_normal(u.size))
    out = F.minimum_fluidisation(u, dp, w)
    assert out["umf"] == pytest.approx(umf, rel=1e-9)
    assert out["a"] == pytest.approx(a, rel=1e-9) and out["b"] == pytest.approx(b, rel=1e-6)
    assert out["plateau_Pa"] == pytest.approx(w, abs=1.5)


def test_wen_yu_of_glass_in_air():
    """0.5 mm glass (2500 kg/m³) in air: Ar = 11354, Re_mf = 6.29, u_mf = 0.1885 m/s (hand calculation)."""
    assert F.wen_yu_umf(0.5e-3, 2500.0, 1.2, 1.8e-5) == pytest.approx(0.18852, rel=1e-4)


def test_bubble_is_an_enclosed_void_region_of_at_least_three_cells():
    g = grid(nx=6, ny=10, w=0.06, h=0.1)  # 1 cm cells
    eps = np.full(g.shape, 0.45)
    eps[:, 7:] = 1.0  # freeboard: connected to the top row, never a bubble
    assert F.bubble_area(g, eps) == 0.0
    eps[2:4, 2:4] = 0.9  # a 2 × 2 enclosed void
    assert F.bubble_area(g, eps) == pytest.approx(4e-4)
    eps[2:4, 4:7] = 0.9  # now it erupts into the freeboard
    assert F.bubble_area(g, eps) == 0.0
    eps = np.full(g.shape, 0.45)
    eps[3, 0:2] = 0.95  # a jet channel of two cells at the orifice
    assert F.bubble_area(g, eps) == 0.0
    eps[0:6, 3:5] = 0.9  # a slug: spans the width, particles above it
    assert F.bubble_area(g, eps) == pytest.approx(12e-4)


def test_bubble_regions_are_the_enclosed_voids_largest_first():
    g = grid(nx=10, ny=10, w=0.1, h=0.1)  # 1 cm cells
    eps = np.full(g.shape, 0.45)
    eps[:, 8:] = 1.0  # freeboard
    eps[1:3, 1:3] = 0.9  # 4 cells
    eps[6:9, 4:7] = 0.9  # 9 cells
    eps[5, 1:3] = 0.9  # 2 cells: too small to be a bubble
    regions = F.bubble_regions(g, eps)
    assert [int(r.sum()) for r in regions] == [9, 4]
    assert regions[0][7, 5] and not regions[0][1, 1]
    assert F.bubble_area(g, eps) == pytest.approx(regions[0].sum() * g.dx * g.dy)
    with pytest.raises(ValueError, match="shape"):
        F.bubble_regions(g, eps.T[:, :5])


def test_slug_is_a_bubble_spanning_the_column():
    """Width fraction: the longest row chord of any bubble over nx; a slug reaches 0.8 of the width."""
    g = grid(nx=10, ny=10, w=0.1, h=0.1)
    eps = np.full(g.shape, 0.45)
    eps[:, 8:] = 1.0  # freeboard: a void, but not a bubble
    assert F.bubble_width_fraction(g, eps) == 0.0 and not F.slug_detected(g, eps)
    eps[4:7, 2:5] = 0.9  # a round bubble 3 cells wide in the middle
    assert F.bubble_width_fraction(g, eps) == pytest.approx(0.3)
    assert not F.slug_detected(g, eps)
    eps[1:9, 3] = 0.9  # the bubble grows sideways to 8 of 10 cells in one row: a slug (0.8)
    assert F.bubble_width_fraction(g, eps) == pytest.approx(0.8)
    assert F.slug_detected(g, eps)
    assert not F.slug_detected(g, eps, min_width_fraction=0.9)
    eps[1, 3] = 0.45  # 7 of 10: a large bubble, not yet a slug
    assert F.bubble_width_fraction(g, eps) == pytest.approx(0.7) and not F.slug_detected(g, eps)
    eps[:, 3] = 0.9  # wall to wall
    assert F.bubble_width_fraction(g, eps) == pytest.approx(1.0) and F.slug_detected(g, eps)
    eps[:, 3:8] = 0.9  # the slug erupts into the freeboard: no longer a bubble, no slug
    assert F.bubble_width_fraction(g, eps) == 0.0 and not F.slug_detected(g, eps)


def test_slug_chord_spans_particle_strands_but_not_a_tilted_bubble():
    g = grid(nx=10, ny=10, w=0.1, h=0.1)
    eps = np.full(g.shape, 0.45)
    eps[:, 8:] = 1.0
    eps[0:10, 2] = 0.9  # a slug row ...
    eps[4:6, 2] = 0.5  # ... with a strand of particles through it, joined below
    eps[3:7, 1] = 0.9
    assert len(F.bubble_regions(g, eps)) == 1
    assert F.bubble_width_fraction(g, eps) == pytest.approx(1.0) and F.slug_detected(g, eps)
    eps = np.full(g.shape, 0.45)
    eps[:, 8:] = 1.0
    for k in range(7):  # a tilted bubble: a staircase from the left wall up to the right, two cells per row ...
        eps[k:k + 2, k] = 0.9
    eps[7:10, 6] = 0.9  # ... and four in its top row
    assert len(F.bubble_regions(g, eps)) == 1
    assert F.bubble_width_fraction(g, eps) == pytest.approx(0.4)  # its bounding box spans the width; no row does
    assert not F.slug_detected(g, eps)


# ---------------------------------------------------------------- bed surface height
D = 4e-3  # [m]


def square_slab(rows, cols, d=D):
    """Centre heights of a square lattice of discs, ``rows`` layers of ``cols``, resting on the floor: top rows × d."""
    return np.repeat((np.arange(rows) + 0.5) * d, cols)


def hexagonal_slab(rows, cols, d=D):
    """Close-packed rows (pitch d √3/2) on the floor: top (rows − 1) d √3/2 + d."""
    return np.repeat(0.5 * d + np.arange(rows) * d * math.sqrt(3) / 2, cols)


@pytest.mark.parametrize("dim2", [True, False])
@pytest.mark.parametrize("rows", [3, 10, 55])
def test_bed_surface_of_a_lattice_slab_is_its_top(dim2, rows):
    """A slab of lattice layers: the surface lies within a quarter of a radius below the slab's top, for 3 to 55
    layers (Sun's jet bed is 55 diameters deep), square and hexagonal, discs and spheres (a layer of spheres as its
    centre heights). The top layer's profile falls below half the slab's mean φ at (z − z_c)/R ≈ 0.92 (discs) or
    0.82 (spheres), and the profile is sampled every tenth of a radius: measured 0.06–0.13 R (discs),
    0.16–0.23 R (spheres)."""
    for h, top in ((square_slab(rows, 24), rows * D), (hexagonal_slab(rows, 24), (rows - 1) * D * math.sqrt(3) / 2 + D)):
        got = F.bed_surface_height(h, np.full(h.size, D / 2), dim2)
        assert -0.25 * D / 2 < got - top <= 0.0, (got, top)


def test_bed_surface_of_a_random_uniform_slab_is_the_middle_of_its_top_ramp():
    """Centres uniform in height over [R, H − R] (a disordered slab, as a fluidised bed's dense part), 2400 discs
    and spheres: the solids fraction ramps down from the slab's to zero over [H − 2R, H], and the surface is
    its middle, H − R, within a fifth of a radius (measured H − 1.1 R), where the 95 % quantile of the tops
    would lie 5 % of H (5.5 radii) below H."""
    rng = np.random.default_rng(3)
    H = 0.22
    h = rng.uniform(D / 2, H - D / 2, 2400)
    for dim2 in (True, False):
        got = F.bed_surface_height(h, np.full(h.size, D / 2), dim2)
        assert abs(got - (H - D / 2)) < 0.2 * D / 2
    assert H - np.quantile(h + D / 2, 0.95) > 4 * D / 2


def test_particles_thrown_up_do_not_move_the_bed_surface():
    """A 20-layer slab (480 discs) and 5 % more thrown up to random heights between one and three slab heights:
    the surface stays where it was without them (within a hundredth of a radius), while the mean centre height
    rises by more than 10 %."""
    rng = np.random.default_rng(7)
    slab = square_slab(20, 24)
    top = 20 * D
    up = rng.uniform(top, 3 * top, 24)
    h = np.concatenate([slab, up])
    r = np.full(h.size, D / 2)
    for dim2 in (True, False):
        alone = F.bed_surface_height(slab, r[:slab.size], dim2)
        assert abs(alone - top) < 0.25 * D / 2
        assert abs(F.bed_surface_height(h, r, dim2) - alone) < 0.01 * D / 2
    assert h.mean() > 1.1 * slab.mean()


def test_bed_surface_of_no_particles_is_nan_and_of_one_is_its_top():
    assert math.isnan(F.bed_surface_height(np.zeros(0), np.zeros(0), True))
    assert F.bed_surface_height(np.array([0.05]), np.array([D / 2]), True) == pytest.approx(0.05 + D / 2, abs=0.1 * D)


def test_solids_profile_integrates_to_the_particles_area_and_volume():
    """Σ profile × step = Σ π R² (discs) or Σ (4/3) π R³ (spheres) to the midpoint rule's error (1e-3 at 20 samples
    per diameter)."""
    rng = np.random.default_rng(1)
    h = rng.uniform(0.01, 0.1, 300)
    r = rng.uniform(1e-3, 2e-3, 300)
    step = 2 * r.mean() / 20
    assert F.solids_profile(h, r, True, step).sum() * step == pytest.approx(np.sum(np.pi * r**2), rel=1e-3)
    assert F.solids_profile(h, r, False, step).sum() * step == pytest.approx(np.sum(4 / 3 * np.pi * r**3), rel=1e-3)
