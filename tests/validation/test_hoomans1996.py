"""Validation: bubbles and slugs in the Table 2 bed of Hoomans et al. 1996 (§5.2–5.3, Figs 10–13).

2400 hard spheres of 4 mm in a 0.15 × 0.5 m column (15 × 25 cells), 1 s simulated, each
set-up with the non-ideal particles of the case files (e = e_w = 0.9, μ = μ_w = 0.3) and,
where the paper compares, the ideal ones (e = e_w = 1.0, μ = μ_w = 0.0).

Published (Hoomans 1996):
- §5.3.1, ``hoomans-orifice`` (45 m/s interstitial orifice over 4.5 m/s): non-ideal —
  "explosive bubble growth", "initially a bubble is formed at the orifice but after a few
  centimetres of elevation the bubble transforms into a slug" (Fig 10 a, c); ideal — "no
  bubble formation can be observed" (Fig 10 b, d); the pressure 20 cm above the jet has
  "the strongest peaks" for the non-ideal particles (Fig 11).
- §5.3.2, ``hoomans-slug`` (uniform 7.5 m/s): non-ideal particles slug; ideal — "no
  slugging occurred at all and the bed expanded homogeneously" (Fig 12); the non-ideal
  pressure 20 cm above the jet shows "the characteristic pressure peaks" of the slugs
  (Fig 13, again the line with the strongest peaks).
- §5.2, ``hoomans-tsuji`` (Tsuji's 6.5 m/s interstitial orifice, non-ideal particles):
  "no bubble formation was observed", only a slightly raised porosity above the jet.

Criteria, evaluated on every gas snapshot (``gas.h5``, every 10 ms, 101 per run) with
the functions of ``fluidem.analysis.fluidised``, from ``STARTUP_S`` = 0.3 s on except the
bubble at the orifice (why: the comment at ``STARTUP_S``):
- bubble (``bubble_area``/``bubble_regions``): a 4-connected region of cells with
  ε > 0.8 (``BUBBLE_VOIDAGE``) not connected to the freeboard, of at least 3 cells
  (``BUBBLE_MIN_CELLS``; the one-cell jet channel at the orifice is no bubble).
- slug (``slug_detected``): a bubble whose chord in one cell row spans at least 0.8 of
  the column width (``SLUG_WIDTH_FRACTION``; 12 of the 15 cells), i.e. a void that
  reaches, or nearly reaches, both side walls.
- at the orifice: the first bubble contains a cell of the orifice column (the central
  one of the 15, where Hoomans' jet enters) in the lowest ``ORIFICE_ROWS`` rows.
- pressure peaks: standard deviation and peak-to-peak of the probe
  ``pressure_20cm_gauge_Pa`` (``probes.csv``, every 1 ms) from ``STARTUP_S`` to 1 s;
  "strongest peaks" is read as at least ``PEAK_RATIO`` times the ideal run's, both
  statistics.

What this model gave last (1 s each; snapshots every 10 ms):
- orifice, non-ideal: first bubble 0.04 s on the orifice, slug from 0.42 s, largest bubble
  346 cm²; ideal: bubbles of up to 50 cm² until 0.41 s, no slug. Pressure 20 cm up over
  0.3–1 s: std 634 vs 137 Pa, peak-to-peak 2554 vs 555 Pa (non-ideal vs ideal).
- slug case, non-ideal: slugs at 42 snapshots in 0.3–0.78 s; ideal: no slug after the
  start-up, bubbles of up to 72 cm² until 0.49 s. Pressure: std 717 vs 160 Pa,
  peak-to-peak 2197 vs 617 Pa.
- Tsuji's jet: bubbles from 0.31 s, up to 124 cm², a slug at 0.59–0.62 s.
Disagreements with the paper are strict xfails with these numbers in their reasons; they
turn into failures the day the model agrees, so the notes are revisited.
Each run takes 30 s on an idle 2-core machine, up to 90 s on a busy one (five runs).
"""
from __future__ import annotations

import csv
import json
import time
from dataclasses import dataclass, field

import numpy as np
import pytest

import fluidem as fd
from fluidem.analysis import fluidised as F
from fluidem.cli import main
from fluidem.io import read_gas_fields

pytestmark = pytest.mark.validation

SIM_TIME = 1.0  # [s] "the simulations were continued for one second real time" (Hoomans §5.3)
IDEAL = ("--set", "particles.contact.restitution=1.0", "--set", "particles.contact.friction=0.0")  # e = e_w, μ = μ_w
# Start-up. Hoomans (§4.1) started from a bed already brought to minimum fluidisation; the
# case files switch the full gas flow on at t = 0 into a bed at rest on a lattice (their
# "our reading"). The first tenths of a second therefore have no counterpart in the paper: the
# gauge pressure 20 cm up rises from 0 to the weight of the bed above it (not a peak), and a
# uniform inflow lifts the packed bed off the distributor as one plug over a gas gap that
# spans the column (a "slug" by the criterion, for ideal particles too). Hoomans: the ideal
# bed height "remains relatively constant" after 0.3 s; the statements about the state of the
# bed (no bubble, slugs / no slugs) and the pressure statistics are therefore taken from
# 0.3 s on, for both particle kinds alike. The bubble at the orifice forms when the jet comes
# on, as in the paper, and is looked for over the whole run.
STARTUP_S = 0.3
# "The line with the strongest peaks" (Figs 11, 13): the non-ideal run's fluctuations must be
# at least twice the ideal run's, in standard deviation and in peak-to-peak. A factor 2 is a
# modest reading of "strongest" that still excludes two runs of similar bubbling.
PEAK_RATIO = 2.0
# "A bubble is formed at the orifice": the first bubble reaches down into the lowest two cell
# rows (4 cm, ten particle diameters) of the orifice column, i.e. it sits on the jet.
ORIFICE_ROWS = 2


@dataclass
class Bed:
    """One run and its bubble / slug / pressure history."""

    label: str
    summary: dict
    wall_s: float
    time: np.ndarray  # snapshot times [s]
    area: np.ndarray  # largest bubble area per snapshot [m²]
    width: np.ndarray  # widest bubble chord per snapshot, fraction of the column width
    slug: np.ndarray  # slug_detected per snapshot
    first_bubble: np.ndarray | None  # mask (nx, ny) of the largest bubble at the first snapshot with one
    orifice_column: int
    probe_time: np.ndarray = field(repr=False)
    pressure: np.ndarray = field(repr=False)  # pressure_20cm_gauge_Pa [Pa]

    def pressure_stats(self, start=STARTUP_S) -> tuple[float, float]:
        """(standard deviation, peak-to-peak) [Pa] of the gauge pressure 20 cm up from ``start`` on."""
        s = self.pressure[self.probe_time >= start - 1e-9]
        return float(s.std()), float(np.ptp(s))

    def settled(self) -> np.ndarray:
        """Snapshots after the start-up (t >= STARTUP_S)."""
        return self.time >= STARTUP_S - 1e-9

    def times(self, mask) -> str:
        t = self.time[mask]
        return f"{t.size} snapshots" + (f", {t[0]:.2f}-{t[-1]:.2f} s" if t.size else "")

    def describe(self) -> str:
        k = int(self.area.argmax())
        sd, pp = self.pressure_stats()
        sd0, pp0 = self.pressure_stats(0.0)
        late = self.settled()
        return (f"{self.label}: wall {self.wall_s:.0f} s; max bubble {self.area.max() * 1e4:.0f} cm2 at "
                f"{self.time[k]:.2f} s; bubbles {self.times(self.area > 0)}; max width {self.width.max():.2f} "
                f"at {self.time[int(self.width.argmax())]:.2f} s; slugs {self.times(self.slug)}; after "
                f"{STARTUP_S} s: max bubble {self.area[late].max() * 1e4:.0f} cm2, bubbles "
                f"{self.times(late & (self.area > 0))}, slugs {self.times(late & self.slug)}; p20 gauge "
                f"std {sd:.0f} Pa, p2p {pp:.0f} Pa from {STARTUP_S} s (from 0 s: {sd0:.0f}, {pp0:.0f}); "
                f"probe max bubble {self.summary.get('bubble_max_area_m2', float('nan')) * 1e4:.0f} cm2")


def run_bed(tmp_path_factory, case: str, label: str, extra=()) -> Bed:
    out = tmp_path_factory.mktemp(label) / "run"
    t0 = time.perf_counter()
    assert main(["run", case, "--until", str(SIM_TIME), "--out", str(out), "--quiet", *extra]) == 0
    wall = time.perf_counter() - t0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "completed" and summary["sim_time_s"] == pytest.approx(SIM_TIME)
    grid = fd.load_case(out / "case.toml").gas.grid.build()
    gas = read_gas_fields(out, ["voidage"])
    eps = gas["voidage"]
    area = np.array([F.bubble_area(grid, e) for e in eps])
    width = np.array([F.bubble_width_fraction(grid, e) for e in eps])
    slug = np.array([F.slug_detected(grid, e) for e in eps])
    first = None
    if (area > 0).any():
        first = F.bubble_regions(grid, eps[int(np.flatnonzero(area > 0)[0])])[0]
    with open(out / "probes.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    bed = Bed(label=label, summary=summary, wall_s=wall, time=gas["time"], area=area, width=width, slug=slug,
              first_bubble=first, orifice_column=grid.nx // 2,
              probe_time=np.array([float(r["time_s"]) for r in rows]),
              pressure=np.array([float(r["pressure_20cm_gauge_Pa"]) for r in rows]))
    assert bed.time[-1] == pytest.approx(SIM_TIME) and bed.time.size >= 50
    print("\n" + bed.describe())
    return bed


@pytest.fixture(scope="module")
def orifice(tmp_path_factory):
    return run_bed(tmp_path_factory, "hoomans-orifice", "orifice-nonideal")


@pytest.fixture(scope="module")
def orifice_ideal(tmp_path_factory):
    return run_bed(tmp_path_factory, "hoomans-orifice", "orifice-ideal", IDEAL)


@pytest.fixture(scope="module")
def slug(tmp_path_factory):
    return run_bed(tmp_path_factory, "hoomans-slug", "slug-nonideal")


@pytest.fixture(scope="module")
def slug_ideal(tmp_path_factory):
    return run_bed(tmp_path_factory, "hoomans-slug", "slug-ideal", IDEAL)


@pytest.fixture(scope="module")
def tsuji(tmp_path_factory):
    return run_bed(tmp_path_factory, "hoomans-tsuji", "tsuji")


# §5.3.1, Figs 10-11: single orifice at 10 u_mf


def test_orifice_nonideal_bubble_forms_at_the_orifice_and_grows_into_a_slug(orifice):
    bubbles = np.flatnonzero(orifice.area > 0)
    assert bubbles.size, orifice.describe()
    k0 = bubbles[0]
    rows = np.flatnonzero(orifice.first_bubble[orifice.orifice_column])
    assert rows.size and rows[0] < ORIFICE_ROWS, \
        f"first bubble ({orifice.time[k0]:.2f} s) not on the orifice: orifice-column rows {rows.tolist()}"
    assert not orifice.slug[k0], "the first bubble is already a slug"
    assert orifice.slug.any(), orifice.describe()
    assert orifice.time[np.flatnonzero(orifice.slug)[0]] > orifice.time[k0]


@pytest.mark.xfail(strict=True, reason=(
    "ideal particles (e = 1, mu = 0): after the 0.3 s start-up still bubbles (eps > 0.8, >= 3 cells) of up to "
    "42 cm2 at 0.30-0.41 s (50 cm2 at 0.23 s), none later, never a slug (widest 0.53 of the column); Hoomans "
    "Fig 10 b, d: no bubble formation (the non-ideal run here: 346 cm2 and a slug)"))
def test_orifice_ideal_forms_no_bubble(orifice_ideal):
    assert not (orifice_ideal.area[orifice_ideal.settled()] > 0).any(), orifice_ideal.describe()


def test_orifice_ideal_bubbles_are_far_smaller_than_nonideal(orifice, orifice_ideal):
    """The contrast of Fig 10 read relatively (the absolute reading, no bubble, is the xfail above): over the
    whole run the non-ideal bed's largest bubble is at least PEAK_RATIO times the ideal bed's."""
    assert orifice.area.max() >= PEAK_RATIO * orifice_ideal.area.max(), \
        f"{orifice.describe()}\n{orifice_ideal.describe()}"


def test_orifice_pressure_peaks_stronger_for_nonideal_particles(orifice, orifice_ideal):
    """Fig 11: the pressure 20 cm above the jet has the strongest peaks for e = 0.9, mu = 0.3."""
    (sd, pp), (sd_i, pp_i) = orifice.pressure_stats(), orifice_ideal.pressure_stats()
    msg = f"non-ideal std {sd:.0f} Pa, p2p {pp:.0f} Pa; ideal std {sd_i:.0f} Pa, p2p {pp_i:.0f} Pa"
    assert sd >= PEAK_RATIO * sd_i, msg
    assert pp >= PEAK_RATIO * pp_i, msg


# §5.3.2, Figs 12-13: homogeneous inflow at 1.75 u_mf


def test_slug_case_nonideal_particles_slug(slug):
    assert slug.slug[slug.settled()].any(), slug.describe()


def test_slug_case_ideal_particles_never_slug(slug_ideal):
    assert not slug_ideal.slug[slug_ideal.settled()].any(), slug_ideal.describe()


@pytest.mark.xfail(strict=True, reason=(
    "ideal particles at 1.75 u_mf: after the 0.3 s start-up bubbles (eps > 0.8, >= 3 cells) of up to 72 cm2 at "
    "0.30-0.49 s, none later, and no slug (in the start-up the bed lifts as a plug over a full-width gas gap at "
    "0.09-0.12 s); Hoomans Fig 12 b, d: homogeneous expansion"))
def test_slug_case_ideal_bed_expands_homogeneously(slug_ideal):
    assert not (slug_ideal.area[slug_ideal.settled()] > 0).any(), slug_ideal.describe()


def test_slug_case_pressure_peaks_stronger_for_nonideal_particles(slug, slug_ideal):
    """Fig 13: the characteristic pressure peaks of the slugs, for the non-ideal particles only."""
    (sd, pp), (sd_i, pp_i) = slug.pressure_stats(), slug_ideal.pressure_stats()
    msg = f"non-ideal std {sd:.0f} Pa, p2p {pp:.0f} Pa; ideal std {sd_i:.0f} Pa, p2p {pp_i:.0f} Pa"
    assert sd >= PEAK_RATIO * sd_i, msg
    assert pp >= PEAK_RATIO * pp_i, msg


# §5.2: Tsuji's jet, 2.6 m/s superficial


@pytest.mark.xfail(strict=True, reason=(
    "hoomans-tsuji (6.5 m/s interstitial jet, e = 0.9, mu = 0.3): bubbles from 0.31 s to the end, up to 124 cm2 "
    "at 0.60 s, and a slug lifting the bed as a plug at 0.59-0.62 s; Hoomans §5.2 (and his experiment with 4 mm "
    "glass beads): no bubble formation, only a slightly raised porosity above the jet"))
def test_tsuji_jet_forms_no_bubble(tsuji):
    assert not (tsuji.area[tsuji.settled()] > 0).any(), tsuji.describe()
