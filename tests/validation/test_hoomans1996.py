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

Model (the case files): Hoomans' own coupling, ``drag = "hoomans1996_total"``: each particle takes the
total gas force of eqs 35-39 (no separate −V_p∇p, eq. 34), the gas takes β of eqs 45-47 from the cell
(``momentum_exchange = "cell_beta"``), voidage by disc area converted with eq. 49. With it the bed pressure
drop meets the bed weight per area (ideal orifice run: 3482 Pa over T0-0.2 to T0, 3632 Pa from T0, against
W/A = 3551 Pa). The results of Ergun/Wen-Yu (eqs 45-47) on the particles plus −V_p∇p are given below
for comparison.

Start-up (Hoomans §4.1, the case files): 0 to T0 = 0.5 s the lattice under the u_mf background alone
(4.5 m/s interstitial on every bottom cell); from T0 the case's inflow, to T0 + 1 s. Without the jet the
ideal bed settles at 129.3-129.4 mm (mean particle height over T0-0.2 to T0, three runs) without
bubbles; the non-ideal bed lifts to 151.9-158.4 mm and already bubbles at the u_mf background (from
T0-0.26 s, up to 96-180 cm2, slugs in 0-4 snapshots): in this model the settled 2D bed's lower cells have
an eq-49 voidage of 0.31-0.33, where eqs 35-39 carry the particles at 0.78-0.93 m/s; a slow velocity sweep
lifts the bed from about 1.0 m/s and finds bubbles in every probe row from 1.8 m/s, the case's background
(``tests/validation/hoomans_bubbles.py``; docs/gallery.md). Hoomans' 1.77 m/s u_mf is Wen & Yu's
correlation, which assumes a 3D bed's ε_mf of about 0.415.

Criteria, evaluated on every gas snapshot (``gas.h5``, every 10 ms, 101 from T0 on) with the functions of
``fluidem.analysis.fluidised``, from the jet onset ``CHECK_FROM`` = T0 on:
- bubble (``bubble_area``/``bubble_regions``): a 4-connected region of cells with
  ε > 0.8 (``BUBBLE_VOIDAGE``) not connected to the freeboard, of at least 3 cells
  (``BUBBLE_MIN_CELLS``; the one-cell jet channel at the orifice is no bubble).
- slug (``slug_detected``): a bubble whose chord in one cell row spans at least 0.8 of
  the column width (``SLUG_WIDTH_FRACTION``; 12 of the 15 cells), i.e. a void that
  reaches, or nearly reaches, both side walls.
- at the orifice: the first bubble from T0 on contains a cell of the orifice column (the
  central one of the 15, where Hoomans' jet enters) in the lowest ``ORIFICE_ROWS`` rows.
- pressure peaks: standard deviation and peak-to-peak of the probe
  ``pressure_20cm_gauge_Pa`` (``probes.csv``, every 1 ms) from T0 to T0 + 1 s;
  "strongest peaks" is read as at least ``PEAK_RATIO`` times the ideal run's, both
  statistics.
Each set-up is run three times (``SEEDS``: lattice perturbations), as one realisation's figures move by
tens of percent with round-off (a first realisation gave pressure std 518 vs 292 Pa at the orifice,
1.77x; the three below give 2.34x): "no bubble", "slugs" and the bubble at the orifice are required of
every run, the contrasts (largest bubble, pressure fluctuations) of the means over the runs.

What this model gave (three runs each, T0 + 1 s, times from the jet onset T0; hoomans1996_total):
- orifice, non-ideal: the start-up bubble is there at T0 (not on the orifice), bubbles in all 101
  snapshots, slugs in 53-80, largest bubble 260-454 cm2 (mean 335); ideal: smaller bubbles in 31-39
  snapshots from T0+0.05 s, 42-62 cm2 at most (mean 55), no slug. Pressure 20 cm up from T0: std 722 vs
  308 Pa (means; 2.34x), peak-to-peak 3479 vs 1124 Pa (3.10x).
- slug case, non-ideal: slugs in 53-87 snapshots, bubbles up to 310-430 cm2; ideal: bubbles in 35-40
  snapshots from T0+0.09-0.13 s, up to 108-126 cm2, slugs in 8-13 snapshots at T0+0.24-0.39 s.
  Pressure: std 791 vs 383 Pa (2.07x), peak-to-peak 3569 vs 1336 Pa (2.67x).
- Tsuji's jet: bubbles in 68-73 snapshots T0 to the end, up to 128-166 cm2, slugs in 23-25 to T0+0.77 s.
Ergun/Wen-Yu + −V_p∇p instead ("particle" exchange; one run): orifice non-ideal 390 cm2, slugs
in 82 snapshots, ideal 198 cm2 with slugs at T0+0.38-0.52 s, pressure std 2216 vs 369 Pa; slug case ideal
slugs in 31 snapshots, bubbles up to 274 cm2; Tsuji's jet bubbles in 90 snapshots, up to 120 cm2. The ideal
beds bubble far less with Hoomans' own model; the non-ideal beds' pressure swings are a third.
With the background at the model's own u_mf instead (2.5 m/s interstitial, 1.0 m/s superficial; three runs
each, ``hoomans_background.py``): non-ideal, no bubble before T0, a bubble on the orifice at T0+0.04 s and
slugs from T0+0.25-0.28 s, up to 266-282 cm2; ideal, a three-cell bubble in 2 snapshots of one run, none in
the other two; pressure std 467 vs 106 Pa. The orifice xfails below are the model's u_mf, not the jet.
Disagreements with the paper are strict xfails with these numbers in their reasons; they
turn into failures the day the model agrees, so the notes are revisited.
Each run of 1.5 s takes 45-140 s on one core of the 2-core machine (the non-ideal orifice runs the
slowest); the module's 15 runs took 16 min (``NUMBA_NUM_THREADS=1``).
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

# Start-up (Hoomans §4.1; the case files): 0-T0 the lattice under the minimum-fluidisation background
# alone (4.5 m/s interstitial everywhere, 1.8 m/s superficial, u_mf 1.77 m/s); from T0 the case's own
# inflow (the jet). Over T0-0.2 s to T0 (module docstring) ideal particles rest at 127.1-131.0 mm mean
# particle height; non-ideal ones lift to 146.3-162.5 mm and bubble. Before T0 every run of one particle
# kind is identical (same inflow, deterministic), as Hoomans' "identical initial conditions" (§5.3).
T0 = 0.5  # [s] jet onset; all times below are from t = 0, reported also relative to T0
SIM_TIME = T0 + 1.0  # [s] "the simulations were continued for one second real time" (Hoomans §5.3)
IDEAL = ("--set", "particles.contact.restitution=1.0", "--set", "particles.contact.friction=0.0")  # e = e_w, μ = μ_w
# The statements about the state of the bed (no bubble, slugs / no slugs), the pressure statistics and
# the bubble at the orifice are taken from the jet onset T0 on (CHECK_FROM), for both particle kinds.
# The onset has a transient (the step in inflow lifts the ideal bed on a full-width gas gap: slugs at
# T0+0.08 to T0+0.50 s in the slug case); it lasts half of the second the paper describes, so no offset
# is taken for it.
CHECK_FROM = T0
# "The line with the strongest peaks" (Figs 11, 13): the non-ideal run's fluctuations must be
# at least twice the ideal run's, in standard deviation and in peak-to-peak. A factor 2 is a
# modest reading of "strongest" that still excludes two runs of similar bubbling.
PEAK_RATIO = 2.0
# "A bubble is formed at the orifice": the first bubble reaches down into the lowest two cell
# rows (4 cm, ten particle diameters) of the orifice column, i.e. it sits on the jet.
ORIFICE_ROWS = 2
# Three realisations of each set-up: the case's lattice perturbation (seed 1996) and two others.
SEEDS = (1996, 1, 2)


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
    first_bubble: np.ndarray | None  # mask (nx, ny) of the largest bubble at the first snapshot from CHECK_FROM with one
    orifice_column: int
    probe_time: np.ndarray = field(repr=False)
    pressure: np.ndarray = field(repr=False)  # pressure_20cm_gauge_Pa [Pa]
    height: np.ndarray = field(repr=False)  # mean_particle_height_m [m]

    def pressure_stats(self, start=CHECK_FROM) -> tuple[float, float]:
        """(standard deviation, peak-to-peak) [Pa] of the gauge pressure 20 cm up from ``start`` on."""
        s = self.pressure[self.probe_time >= start - 1e-9]
        return float(s.std()), float(np.ptp(s))

    def settled(self) -> np.ndarray:
        """Snapshots from the jet onset on (t >= CHECK_FROM)."""
        return self.time >= CHECK_FROM - 1e-9

    def times(self, mask) -> str:
        """Count and span of the snapshots in ``mask``, times after the jet onset T0."""
        t = self.time[mask] - T0
        return f"{t.size} snapshots" + (f", T0{t[0]:+.2f} to T0{t[-1]:+.2f} s" if t.size else "")

    def describe(self) -> str:
        late = self.settled()
        k = int(np.flatnonzero(late)[self.area[late].argmax()])
        kw = int(np.flatnonzero(late)[self.width[late].argmax()])
        sd, pp = self.pressure_stats()
        sd0, pp0 = self.pressure_stats(0.0)
        h = self.height
        before = (self.probe_time >= T0 - 0.2 - 1e-9) & (self.probe_time < T0 - 1e-9)
        return (f"{self.label}: wall {self.wall_s:.0f} s; start-up (t < T0 = {T0} s): max bubble "
                f"{self.area[~late].max() * 1e4:.0f} cm2, bubbles {self.times(~late & (self.area > 0))}, slugs "
                f"{self.times(~late & self.slug)}, mean height over T0-0.2 to T0 {h[before].mean() * 1e3:.1f} mm "
                f"({h[before].min() * 1e3:.1f}-{h[before].max() * 1e3:.1f}); from T0: max bubble "
                f"{self.area[k] * 1e4:.0f} cm2 at T0{self.time[k] - T0:+.2f} s, bubbles "
                f"{self.times(late & (self.area > 0))}, max width {self.width[kw]:.2f} at T0{self.time[kw] - T0:+.2f} s, "
                f"slugs {self.times(late & self.slug)}; p20 gauge std {sd:.0f} Pa, p2p {pp:.0f} Pa from T0 "
                f"(from 0 s: {sd0:.0f}, {pp0:.0f}); mean height from T0 {h[self.probe_time >= T0 - 1e-9].mean() * 1e3:.1f} mm")


def run_bed(tmp_path_factory, case: str, label: str, extra=()) -> Bed:
    out = tmp_path_factory.mktemp(label) / "run"
    t0 = time.perf_counter()
    assert fd.load_case(case).time.end == pytest.approx(SIM_TIME)  # the case file's T0 + 1 s
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
    onset = (area > 0) & (gas["time"] >= CHECK_FROM - 1e-9)
    if onset.any():
        first = F.bubble_regions(grid, eps[int(np.flatnonzero(onset)[0])])[0]
    with open(out / "probes.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    bed = Bed(label=label, summary=summary, wall_s=wall, time=gas["time"], area=area, width=width, slug=slug,
              first_bubble=first, orifice_column=grid.nx // 2,
              probe_time=np.array([float(r["time_s"]) for r in rows]),
              pressure=np.array([float(r["pressure_20cm_gauge_Pa"]) for r in rows]),
              height=np.array([float(r["mean_particle_height_m"]) for r in rows]))
    assert bed.time[-1] == pytest.approx(SIM_TIME) and bed.settled().sum() >= 50
    print("\n" + bed.describe())
    return bed


@dataclass
class Beds:
    """Realisations of one set-up that differ only in the lattice perturbation (placement seeds ``SEEDS``).

    Each run is chaotic, so one realisation's bubble sizes and pressure swings move by tens of percent
    with round-off; statements about every run ("no bubble", "slugs") are checked on each, and the
    contrasts between particle kinds (largest bubble, pressure fluctuations) on the means over the runs.
    """

    label: str
    runs: list

    def pressure_stats(self) -> tuple[float, float]:
        """Means over the runs of (standard deviation, peak-to-peak) [Pa] of the gauge pressure from T0."""
        stats = np.array([b.pressure_stats() for b in self.runs])
        return float(stats[:, 0].mean()), float(stats[:, 1].mean())

    def largest_bubble(self) -> float:
        """Mean over the runs of the largest bubble [m²] from T0."""
        return float(np.mean([b.area[b.settled()].max() for b in self.runs]))

    def describe(self) -> str:
        return "\n".join(b.describe() for b in self.runs)


def run_beds(tmp_path_factory, case: str, label: str, extra=()) -> Beds:
    return Beds(label, [run_bed(tmp_path_factory, case, f"{label}-seed{seed}",
                                (*extra, "--set", f"particles.placement.seed={seed}")) for seed in SEEDS])


@pytest.fixture(scope="module")
def orifice(tmp_path_factory):
    return run_beds(tmp_path_factory, "hoomans-orifice", "orifice-nonideal")


@pytest.fixture(scope="module")
def orifice_ideal(tmp_path_factory):
    return run_beds(tmp_path_factory, "hoomans-orifice", "orifice-ideal", IDEAL)


@pytest.fixture(scope="module")
def slug(tmp_path_factory):
    return run_beds(tmp_path_factory, "hoomans-slug", "slug-nonideal")


@pytest.fixture(scope="module")
def slug_ideal(tmp_path_factory):
    return run_beds(tmp_path_factory, "hoomans-slug", "slug-ideal", IDEAL)


@pytest.fixture(scope="module")
def tsuji(tmp_path_factory):
    return run_beds(tmp_path_factory, "hoomans-tsuji", "tsuji")


# §5.3.1, Figs 10-11: single orifice at 10 u_mf


@pytest.mark.xfail(strict=True, reason=(
    "from the jet onset T0 the first bubble is the one the non-ideal bed already forms at the u_mf background "
    "(from T0-0.26 s, up to 96-180 cm2 in three runs), not on the orifice; slugs in 53-80 of 101 snapshots, "
    "largest bubbles 260-454 cm2; Hoomans Fig 10 a, c: a bubble forms at the orifice and turns into a slug"))
def test_orifice_nonideal_bubble_forms_at_the_orifice_and_grows_into_a_slug(orifice):
    for bed in orifice.runs:
        late = bed.settled()
        bubbles = np.flatnonzero(late & (bed.area > 0))
        assert bubbles.size, bed.describe()
        k0 = bubbles[0]
        rows = np.flatnonzero(bed.first_bubble[bed.orifice_column])
        assert rows.size and rows[0] < ORIFICE_ROWS, \
            f"{bed.label}: first bubble (T0{bed.time[k0] - T0:+.2f} s) not on the orifice: orifice-column rows " \
            f"{rows.tolist()}"
        assert not bed.slug[k0], f"{bed.label}: the first bubble is already a slug"
        assert (late & bed.slug).any(), bed.describe()
        assert bed.time[np.flatnonzero(late & bed.slug)[0]] > bed.time[k0]


@pytest.mark.xfail(strict=True, reason=(
    "ideal particles (e = 1, mu = 0): none in the u_mf start-up, but from the jet onset T0 smaller bubbles (eps > "
    "0.8, >= 3 cells) in 31-39 snapshots of each of three runs from T0+0.05 s, up to 42-62 cm2, no slug; Hoomans "
    "Fig 10 b, d: no bubble formation (the non-ideal runs here: 260-454 cm2 and slugs)"))
def test_orifice_ideal_forms_no_bubble(orifice_ideal):
    for bed in orifice_ideal.runs:
        assert not (bed.area[bed.settled()] > 0).any(), bed.describe()


def test_orifice_ideal_bubbles_are_far_smaller_than_nonideal(orifice, orifice_ideal):
    """The contrast of Fig 10 read relatively (the absolute reading, no bubble, is the xfail above): from the
    jet onset on the non-ideal bed's largest bubble is at least PEAK_RATIO times the ideal bed's, means over the
    runs (measured 335 against 55 cm2, 6.1x)."""
    assert orifice.largest_bubble() >= PEAK_RATIO * orifice_ideal.largest_bubble(), \
        f"{orifice.describe()}\n{orifice_ideal.describe()}"


def test_orifice_pressure_peaks_stronger_for_nonideal_particles(orifice, orifice_ideal):
    """Fig 11: the pressure 20 cm above the jet has the strongest peaks for e = 0.9, mu = 0.3 (means over the
    runs: std 722 vs 308 Pa, 2.34x; peak-to-peak 3479 vs 1124 Pa, 3.10x; a single run gave 1.77x in std)."""
    (sd, pp), (sd_i, pp_i) = orifice.pressure_stats(), orifice_ideal.pressure_stats()
    msg = f"non-ideal std {sd:.0f} Pa, p2p {pp:.0f} Pa; ideal std {sd_i:.0f} Pa, p2p {pp_i:.0f} Pa"
    assert sd >= PEAK_RATIO * sd_i, msg
    assert pp >= PEAK_RATIO * pp_i, msg


# §5.3.2, Figs 12-13: homogeneous inflow at 1.75 u_mf


def test_slug_case_nonideal_particles_slug(slug):
    for bed in slug.runs:
        assert bed.slug[bed.settled()].any(), bed.describe()


@pytest.mark.xfail(strict=True, reason=(
    "ideal particles: after the inflow steps from 4.5 to 7.5 m/s at T0, slugs at T0+0.24 to T0+0.39 s in each of "
    "three runs (8-13 of 101 snapshots); Hoomans Fig 12 b, d: no slugging at all"))
def test_slug_case_ideal_particles_never_slug(slug_ideal):
    for bed in slug_ideal.runs:
        assert not bed.slug[bed.settled()].any(), bed.describe()


@pytest.mark.xfail(strict=True, reason=(
    "ideal particles at 1.75 u_mf: from T0 bubbles (eps > 0.8, >= 3 cells) in 35-40 snapshots of each of three "
    "runs, up to 108-126 cm2, slugs at T0+0.24-0.39 s; Hoomans Fig 12 b, d: homogeneous expansion"))
def test_slug_case_ideal_bed_expands_homogeneously(slug_ideal):
    for bed in slug_ideal.runs:
        assert not (bed.area[bed.settled()] > 0).any(), bed.describe()


def test_slug_case_pressure_peaks_stronger_for_nonideal_particles(slug, slug_ideal):
    """Fig 13: the characteristic pressure peaks of the slugs, for the non-ideal particles only (means over the
    runs: std 791 vs 383 Pa, 2.07x; peak-to-peak 3569 vs 1336 Pa, 2.67x; single runs from 1.8x to 2.4x in std)."""
    (sd, pp), (sd_i, pp_i) = slug.pressure_stats(), slug_ideal.pressure_stats()
    msg = f"non-ideal std {sd:.0f} Pa, p2p {pp:.0f} Pa; ideal std {sd_i:.0f} Pa, p2p {pp_i:.0f} Pa"
    assert sd >= PEAK_RATIO * sd_i, msg
    assert pp >= PEAK_RATIO * pp_i, msg


# §5.2: Tsuji's jet, 2.6 m/s superficial


@pytest.mark.xfail(strict=True, reason=(
    "hoomans-tsuji (6.5 m/s interstitial jet, e = 0.9, mu = 0.3): the bed bubbles already at the u_mf background "
    "(up to 96-180 cm2 before T0, three runs); from T0 bubbles in 68-73 of 101 snapshots, up to 128-166 cm2, "
    "slugs in 23-25 until T0+0.77 s; Hoomans §5.2 (and his experiment with 4 mm glass beads): no bubble "
    "formation, only a slightly raised porosity above the jet"))
def test_tsuji_jet_forms_no_bubble(tsuji):
    for bed in tsuji.runs:
        assert not (bed.area[bed.settled()] > 0).any(), bed.describe()
