"""The Di Renzo-Di Maio flotsam/jetsam criterion (Di Renzo & Di Maio 2012, §4, eqs 10-19).

Checked against limits derived by hand (equal species, equal densities, equal sizes, the trace
limits x_1 -> 0 and 1), numbers computed by hand, the chapter's eq. 17 solved numerically from its
ingredients (eqs 10, 12-16) with brentq, the chapter's statements (the smaller-and-lighter species
rises; Fig 1's lines at ε = 0.4 lie in the unit square; Fig 2's single line of eq. 18), and bad input.

The chapter's Fig 1 does not state its compositions in the available text; the lines are checked at
x_1 = 0.1, 0.5 and 0.9. Fig 2's experimental points are not given as numbers, so only its line and its
symbol convention are checked.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from fluidem import CaseError, segregation_criterion
from fluidem.analysis.segregation import (
    equilibrium_density_ratio,
    equilibrium_mean_density_ratio,
    minimum_fluidisation_velocity,
    mixture_density,
    sauter_mean_diameter,
    viscous_drag,
)

ROUND_OFF = 1e-13  # a few hundred ulps: each quantity is a handful of products and quotients

G = 9.81
MU = 1.8e-5


# ------------------------------------------------------------------ limits derived by hand

@pytest.mark.parametrize("voidage", [0.3, 0.4, 0.6])
@pytest.mark.parametrize("x1", [0.0, 0.1, 0.5, 0.9, 1.0])
def test_equal_species_lie_on_the_line(x1, voidage):
    """D_1 = D_2, rho_1 = rho_2: D_bar = D, rho_bar = rho, eq. 17's left side is (1-ε) + ε = 1."""
    r = segregation_criterion((5e-4, 5e-4), (2500.0, 2500.0), x1, voidage)
    assert r.flotsam == r.jetsam == "mixed"
    assert r.force_ratio == pytest.approx(1.0, abs=ROUND_OFF)
    assert r.force_ratio_1 == pytest.approx(1.0, abs=ROUND_OFF)
    assert abs(r.relative_gap) < ROUND_OFF and abs(r.mean_density_gap) < ROUND_OFF


CASES_X1 = [0.0, 0.05, 0.25, 0.5, 0.75, 0.95, 1.0]


@pytest.mark.parametrize("voidage", [0.35, 0.4, 0.5])
@pytest.mark.parametrize("x1", CASES_X1)
@pytest.mark.parametrize("ratio", [0.1, 0.5, 0.9, 0.99])
@pytest.mark.parametrize("smaller", [1, 2])
def test_equal_density_the_smaller_rises(smaller, ratio, x1, voidage):
    """The chapter (§4): "the component with the smaller size ... [accumulates] to the bed surface".

    By hand: rho_bar = rho, so eq. 17's left side for species i is 1 - ε + ε D_bar/D_i; D_bar, a
    harmonic mean, lies between the sizes, so it is above 1 for the smaller and below 1 for the larger."""
    small, large = 2e-4 * ratio / 0.5, 2e-4 / 0.5
    diameters = (small, large) if smaller == 1 else (large, small)
    r = segregation_criterion(diameters, (2500.0, 2500.0), x1, voidage)
    assert r.flotsam == smaller and r.jetsam == 3 - smaller
    if 0.0 < x1 < 1.0:
        ratios = {1: r.force_ratio_1, 2: r.force_ratio}
        assert ratios[smaller] > 1.0 > ratios[3 - smaller]


@pytest.mark.parametrize("voidage", [0.35, 0.4, 0.5])
@pytest.mark.parametrize("x1", CASES_X1)
@pytest.mark.parametrize("ratio", [0.1, 0.5, 0.9, 0.99])
@pytest.mark.parametrize("lighter", [1, 2])
def test_equal_size_the_lighter_rises(lighter, ratio, x1, voidage):
    """D_bar = D, so eq. 17's left side for species i is rho_bar/rho_i: above 1 for the lighter."""
    light, heavy = 2500.0 * ratio, 2500.0
    densities = (light, heavy) if lighter == 1 else (heavy, light)
    r = segregation_criterion((1e-3, 1e-3), densities, x1, voidage)
    assert r.flotsam == lighter
    if 0.0 < x1 < 1.0:
        ratios = {1: r.force_ratio_1, 2: r.force_ratio}
        assert ratios[lighter] > 1.0 > ratios[3 - lighter]


def test_smaller_and_lighter_rises_everywhere():
    """The chapter (§4): the smaller, lighter component is the flotsam; only smaller-denser against
    larger-lighter pairs are ambiguous. Checked over a grid of ratios, compositions and voidages."""
    for d in (0.05, 0.3, 0.7, 0.95):
        for s_light in (0.05, 0.3, 0.7, 0.95):
            for x1 in CASES_X1:
                for eps in (0.3, 0.45, 0.6):
                    r = segregation_criterion((d * 1e-3, 1e-3), (s_light * 3000.0, 3000.0), x1, eps)
                    assert r.flotsam == 1, (d, s_light, x1, eps)
                    r = segregation_criterion((1e-3, d * 1e-3), (3000.0, s_light * 3000.0), x1, eps)
                    assert r.flotsam == 2, (d, s_light, x1, eps)


@pytest.mark.parametrize("voidage", [0.4, 0.55])
@pytest.mark.parametrize("d", [0.2, 0.6])
def test_trace_limits(d, voidage):
    """x_1 -> 0: the balance of species 2 in its own bed is trivially 1 (D_bar = D_2, rho_bar = rho_2),
    and a trace particle of species 1 decides: eq. 17 written for it, (rho_2/rho_1)(1 - ε + ε D_2/D_1)
    = 1, gives s = 1/(1 - ε + ε/d). x_1 -> 1: a trace particle of species 2 in a bed of species 1,
    (rho_1/rho_2)(1 - ε + ε D_1/D_2) = 1, gives s = 1 - ε + ε d. Eq. 19 must reach both."""
    eps = voidage
    assert equilibrium_density_ratio(d, 0.0, eps) == pytest.approx(1.0 / (1.0 - eps + eps / d), rel=ROUND_OFF)
    assert equilibrium_density_ratio(d, 1.0, eps) == pytest.approx(1.0 - eps + eps * d, rel=ROUND_OFF)
    for x_trace, x_limit in ((1e-9, 0.0), (1.0 - 1e-9, 1.0)):  # continuous at the ends
        assert equilibrium_density_ratio(d, x_trace, eps) == pytest.approx(
            equilibrium_density_ratio(d, x_limit, eps), rel=1e-8)
    r = segregation_criterion((d * 1e-3, 1e-3), (2500.0, 1000.0), 0.0, eps)
    assert r.force_ratio == pytest.approx(1.0, abs=ROUND_OFF)  # the majority's balance is trivial


# ------------------------------------------------------------------ numbers computed by hand

def test_eqs_10_to_19_by_hand():
    """D_1 = 0.3 mm, rho_1 = 2600 kg/m³ (glass); D_2 = 0.6 mm, rho_2 = 1200 kg/m³; x_1 = 0.25; ε = 0.4.

    eq. 10: D_bar = 1/(0.25/0.3e-3 + 0.75/0.6e-3) = 1/(833.33 + 1250) = 1/2083.33 = 4.8e-4 m
    eq. 11: y_1 = 0.3/0.48 = 0.625, y_2 = 0.6/0.48 = 1.25
    eq. 15: rho_bar = 0.25*2600 + 0.75*1200 = 650 + 900 = 1550 kg/m³
    eq. 16: grad p = 1550 * 0.6 * 9.81 = 9123.3 Pa/m
    eq. 14: u_mf = 9.81 * 0.4³ * 1550 * (4.8e-4)² / (180 * 0.6 * 1.8e-5)
                 = 973.152 * 2.304e-7 / 1.944e-3 = 2.242142208e-4 / 1.944e-3 = 0.115336430 m/s
    eq. 18: d_bar = 0.48/0.6 = 0.8, s_bar = 1200/1550 = 24/31 = 0.774194;
            1 - ε + ε d_bar = 0.6 + 0.32 = 0.92 > s_bar: species 2 rises
    eq. 17: left side = 0.92 / (24/31) = 0.92*1550/1200 = 1426/1200 = 1.188333
            for species 1: (1550/2600)(0.6 + 0.4*0.48/0.3) = (1550/2600)*1.24 = 1922/2600 = 0.739231
    eq. 19: s = 1200/2600 = 6/13 = 0.461538, d = 0.5;
            s_eq = (0.6*0.25 + (1 - 0.6*0.25)*0.5) / (0.25 + 0.75*0.4 + 0.75*0.6*0.5)
                 = (0.15 + 0.425) / (0.55 + 0.225) = 0.575/0.775 = 23/31 = 0.741935 > s: species 2 rises
    """
    r = segregation_criterion((0.3e-3, 0.6e-3), (2600.0, 1200.0), 0.25, 0.4, viscosity=MU, gravity=G)
    assert r.mean_diameter == pytest.approx(4.8e-4, rel=ROUND_OFF)
    assert r.polydispersity == pytest.approx((0.625, 1.25), rel=ROUND_OFF)
    assert r.mean_density == pytest.approx(1550.0, rel=ROUND_OFF)
    assert r.pressure_gradient == pytest.approx(9123.3, rel=ROUND_OFF)
    assert r.minimum_fluidisation_velocity == pytest.approx(2.242142208e-4 / 1.944e-3, rel=ROUND_OFF)
    assert r.mean_size_ratio == pytest.approx(0.8, rel=ROUND_OFF)
    assert r.mean_density_ratio == pytest.approx(24 / 31, rel=ROUND_OFF)
    assert r.equilibrium_mean_density_ratio == pytest.approx(0.92, rel=ROUND_OFF)
    assert r.force_ratio == pytest.approx(1426 / 1200, rel=ROUND_OFF)
    assert r.force_ratio_1 == pytest.approx(1922 / 2600, rel=ROUND_OFF)
    assert r.size_ratio == 0.5 and r.density_ratio == pytest.approx(6 / 13, rel=ROUND_OFF)
    assert r.equilibrium_density_ratio == pytest.approx(23 / 31, rel=ROUND_OFF)
    assert r.flotsam == 2 and r.jetsam == 1
    # the three terms of eq. 17 [N] agree with its closed form
    assert (r.pressure_force_2 + r.drag_2) / r.weight_2 == pytest.approx(r.force_ratio, rel=ROUND_OFF)
    # and the helper functions give the same numbers
    assert sauter_mean_diameter((0.3e-3, 0.6e-3), 0.25) == pytest.approx(4.8e-4, rel=ROUND_OFF)
    assert mixture_density((2600.0, 1200.0), 0.25) == pytest.approx(1550.0, rel=ROUND_OFF)
    assert equilibrium_mean_density_ratio(0.8, 0.4) == pytest.approx(0.92, rel=ROUND_OFF)


def test_carman_kozeny_consistency_eqs_6_13_14_16():
    """Eq. 13 in eq. 6 is the Carman-Kozeny law 180 (1-ε)² μ u/(ε³ D²); at eq. 14's u_mf it carries the
    bed weight, eq. 16, and the mean drag there is (π/6) g ε rho D³, whatever the viscosity."""
    eps, d, rho = 0.42, 2e-4, 2500.0
    for mu in (1.8e-5, 1e-3):
        u = minimum_fluidisation_velocity(d, rho, eps, mu, G)
        f = viscous_drag(eps, mu, u, d)
        grad_p = (1.0 - eps) / eps * 6.0 / math.pi * f / d**3  # eq. 6 (and eq. 8 with D_bar)
        assert grad_p == pytest.approx(rho * (1.0 - eps) * G, rel=ROUND_OFF)  # eq. 16
        assert grad_p == pytest.approx(180.0 * (1 - eps) ** 2 * mu * u / (eps**3 * d * d), rel=ROUND_OFF)
        assert f == pytest.approx(math.pi / 6.0 * G * eps * rho * d**3, rel=ROUND_OFF)


# ------------------------------------------------------------------ eq. 17 = 1 solved numerically

def _eq17_left_side(d1, rho1, d2, rho2, x1, eps):
    """Eq. 17's left side from its ingredients, dimensionally: D_bar (eq. 10), rho_bar (eq. 15), the
    mixture's u_mf (eq. 14), the mean drag there (eq. 13 with D_bar), the drag on a particle of
    species 2 (eq. 12), the pressure gradient (eq. 16)."""
    x2 = 1.0 - x1
    mean_d = 1.0 / (x1 / d1 + x2 / d2)
    mean_rho = rho1 * x1 + rho2 * x2
    u_mf = G * eps**3 * mean_rho * mean_d**2 / (180.0 * (1.0 - eps) * MU)
    mean_drag = 30.0 * (1.0 - eps) / eps**2 * math.pi * MU * u_mf * mean_d
    drag_2 = (d2 / mean_d) ** 2 * mean_drag
    v2 = math.pi / 6.0 * d2**3
    return (v2 * mean_rho * (1.0 - eps) * G + drag_2) / (v2 * rho2 * G)


@pytest.mark.parametrize("voidage", [0.4, 0.5])
@pytest.mark.parametrize("x1", [0.1, 0.3, 0.5, 0.7, 0.9])
@pytest.mark.parametrize("d", [0.1, 0.3, 0.6, 0.9, 1.5])
def test_eq19_is_where_eq17_equals_one(d, x1, voidage):
    """For D_2 = 1 mm, D_1 = d D_2, rho_1 = 2500 kg/m³, solve eq. 17 = 1 for rho_2 with brentq: the
    closed-form line of eq. 19 passes through s = rho_2/rho_1 to round-off; above it species 1 rises."""
    d2, rho1 = 1e-3, 2500.0
    d1 = d * d2
    rho2 = brentq(lambda r2: _eq17_left_side(d1, rho1, d2, r2, x1, voidage) - 1.0, 1e-3 * rho1, 1e3 * rho1,
                  xtol=1e-300, rtol=1e-15)
    s_line = equilibrium_density_ratio(d, x1, voidage)
    assert rho2 / rho1 == pytest.approx(s_line, rel=1e-13)
    # on the line: mixed; a little above or below: the right species rises
    assert segregation_criterion((d1, d2), (rho1, rho2), x1, voidage, tolerance=1e-12).flotsam == "mixed"
    assert segregation_criterion((d1, d2), (rho1, rho2 * 1.01), x1, voidage).flotsam == 1
    assert segregation_criterion((d1, d2), (rho1, rho2 * 0.99), x1, voidage).flotsam == 2
    assert _eq17_left_side(d1, rho1, d2, rho2 * 0.99, x1, voidage) > 1.0  # species 2 pushed up


def test_the_mixture_as_a_whole_is_carried():
    """Summed over the mixture, x_1 rho_1 (R_1 - 1) + x_2 rho_2 (R_2 - 1) = 0: the drag y_i² f_d_bar
    weighted by x_i/D_i³ sums to the mean (eq. 7 with eq. 10), so the pressure gradient carries the
    whole bed and one species rises exactly when the other sinks."""
    rng = np.random.default_rng(2012)
    for _ in range(200):
        d1, d2 = 10 ** rng.uniform(-4.5, -2.5, 2)
        r1, r2 = 10 ** rng.uniform(2.5, 4.0, 2)
        x1, eps = rng.uniform(0.01, 0.99), rng.uniform(0.3, 0.7)
        r = segregation_criterion((d1, d2), (r1, r2), x1, eps)
        net = x1 * r1 * (r.force_ratio_1 - 1.0) + (1.0 - x1) * r2 * (r.force_ratio - 1.0)
        assert abs(net) < 1e-12 * r.mean_density
        rises = {1: r.force_ratio_1 > 1.0, 2: r.force_ratio > 1.0}
        assert rises[r.flotsam] and not rises[r.jetsam]


# ------------------------------------------------------------------ the chapter's figures

FIG1 = {  # x_1: s at d -> 0, d = 0.5 (by hand, ε = 0.4); every line ends at (1, 1)
    # d -> 0: s = (1-ε) x_1 / (x_1 + (1-x_1) ε)
    # d = 0.5: s = ((1-ε) x_1 + (1 - (1-ε) x_1)/2) / (x_1 + (1-x_1) ε + (1-x_1)(1-ε)/2)
    0.1: (0.06 / 0.46, 0.53 / 0.73),    # 0.130435, 0.726027
    0.5: (0.30 / 0.70, 0.65 / 0.85),    # 0.428571, 0.764706
    0.9: (0.54 / 0.94, 0.77 / 0.97),    # 0.574468, 0.793814
}


@pytest.mark.parametrize("x1", sorted(FIG1))
def test_fig1_lines_at_voidage_0_4(x1):
    """Fig 1 (ε = 0.4): the lines in the chart's unit square, through (1, 1), rising with d."""
    at_zero, at_half = FIG1[x1]
    assert equilibrium_density_ratio(1e-15, x1, 0.4) == pytest.approx(at_zero, rel=1e-12)
    assert equilibrium_density_ratio(0.5, x1, 0.4) == pytest.approx(at_half, rel=ROUND_OFF)
    assert equilibrium_density_ratio(1.0, x1, 0.4) == pytest.approx(1.0, rel=ROUND_OFF)
    d = np.linspace(1e-6, 1.0, 1001)
    s = equilibrium_density_ratio(d, x1, 0.4)
    assert np.all(np.diff(s) > 0.0) and np.all((s > 0.0) & (s <= 1.0 + ROUND_OFF))


def test_fig1_lines_ordered_by_composition_and_regions():
    """At a given d < 1 the line is higher the more species 1 there is, and the corners of the chart
    belong to the regions the chapter's sketches show: near (0, 1) (much smaller, about as dense) species 1
    rises; near (1, 0) (about as large, much lighter) species 2 rises."""
    d = np.linspace(0.01, 0.99, 99)
    lines = [equilibrium_density_ratio(d, x1, 0.4) for x1 in (0.1, 0.5, 0.9)]
    assert np.all(lines[0] < lines[1]) and np.all(lines[1] < lines[2])
    for x1 in (0.1, 0.5, 0.9):
        assert segregation_criterion((0.05e-3, 1e-3), (1000.0, 950.0), x1, 0.4).flotsam == 1  # (0.05, 0.95)
        assert segregation_criterion((0.95e-3, 1e-3), (1000.0, 50.0), x1, 0.4).flotsam == 2  # (0.95, 0.05)


def test_fig2_one_line_for_every_composition():
    """Fig 2: in the (d_bar, s_bar) plane eq. 18 is one line, s_bar = 1 - ε + ε d_bar, whatever x_1:
    a system on its composition's line of eq. 19 lies on it; Fig 2's open circles (the larger, lighter
    species rises) lie below it, the solid ones (the smaller, denser species rises) above it."""
    for x1 in (0.1, 0.3, 0.5, 0.7, 0.9):
        for d in (0.2, 0.5, 0.8):
            s = equilibrium_density_ratio(d, x1, 0.4)
            on = segregation_criterion((d * 1e-3, 1e-3), (1000.0, s * 1000.0), x1, 0.4, tolerance=1e-12)
            assert on.flotsam == "mixed"
            assert on.mean_density_ratio == pytest.approx(0.6 + 0.4 * on.mean_size_ratio, rel=ROUND_OFF)
            below = segregation_criterion((d * 1e-3, 1e-3), (1000.0, 0.9 * s * 1000.0), x1, 0.4)
            above = segregation_criterion((d * 1e-3, 1e-3), (1000.0, min(1.1 * s, 1.0) * 1000.0), x1, 0.4)
            assert below.mean_density_gap < 0.0 and below.flotsam == 2  # open circle
            assert above.mean_density_gap > 0.0 and above.flotsam == 1  # solid circle


# ------------------------------------------------------------------ bad input

GOOD = dict(diameters=(3e-4, 6e-4), densities=(2600.0, 1200.0), composition=0.25, voidage=0.4)
BAD = [
    (dict(diameters=(3e-4,)), "diameters = (0.0003,)"),
    (dict(diameters=3e-4), "diameters = 0.0003"),
    (dict(densities=(2600.0,)), "densities = (2600.0,)"),
    (dict(diameters=(3e-4, 6e-4, 1e-3)), "got 3"),
    (dict(diameters=(0.0, 6e-4)), "d1 = 0.0"),
    (dict(diameters=(3e-4, -6e-4)), "d2 = -0.0006"),
    (dict(diameters=(float("nan"), 6e-4)), "d1 = nan"),
    (dict(diameters=(3e-4, float("inf"))), "d2 = inf"),
    (dict(diameters=("abc", 6e-4)), "d1 = 'abc'"),
    (dict(densities=(0.0, 1200.0)), "rho1 = 0.0"),
    (dict(densities=(2600.0, -1.0)), "rho2 = -1.0"),
    (dict(densities=(2600.0, float("inf"))), "rho2 = inf"),
    (dict(densities=(True, 1200.0)), "rho1 = True"),
    (dict(voidage=0.0), "voidage = 0.0"),
    (dict(voidage=1.0), "voidage = 1.0"),
    (dict(voidage=-0.2), "voidage = -0.2"),
    (dict(voidage=float("nan")), "voidage = nan"),
    (dict(composition=-0.1), "composition = -0.1"),
    (dict(composition=1.5), "composition = 1.5"),
    (dict(composition=float("nan")), "composition = nan"),
    (dict(viscosity=0.0), "viscosity = 0.0"),
    (dict(tolerance=-1e-3), "tolerance = -0.001"),
]


@pytest.mark.parametrize("change, message", BAD, ids=[m for _, m in BAD])
def test_bad_input_names_the_argument_and_value(change, message):
    with pytest.raises(CaseError) as err:
        segregation_criterion(**dict(GOOD, **change))
    assert message in str(err.value)


def test_bad_size_ratio_of_the_line():
    with pytest.raises(CaseError, match="size_ratio"):
        equilibrium_density_ratio(-0.5, 0.5, 0.4)
    with pytest.raises(CaseError, match="voidage = 1.2"):
        equilibrium_density_ratio(0.5, 0.5, 1.2)
