"""Validation: the two soft-sphere fluidised beds of Sun, Battaglia & Subramaniam 2007.

Each built-in case runs 10 s (the end of Sun's 5–10 s averaging window) and the tests
read the time averages that ``summary.json`` reports over 5–10 s.

Published (Sun 2007 §4):
- uniform inflow (``goldschmidt``): mean particle height 8.9 cm (TF-DEM), 9.16 cm (TFM),
  11.4 cm (experiment of Goldschmidt et al.); bulk coordination number "around 0.5"
  (Fig 5); multicontact ratio "fluctuating around 0.3" (Fig 11).
- central jet (``tsuji-jet``): coordination number "around 1.2" (Fig 5); multicontact
  ratio above 0.6 most of the time (Fig 11); the pressure drop 20 cm above the inlet
  fluctuates (Fig 3) — its dominant frequency is reported, not asserted. ``tsuji-jet``
  reads Table 1 literally (the jet is the only inflow, u_mf only the initial gas
  velocity), and it has the packed corners beside the jet that Sun describes (Figs 6-7)
  and Sun's contact numbers; ``tsuji-jet-background`` is the earlier reading (the rest of
  the bottom at u_mf, as Hoomans 1996 §5.2 read Tsuji's set-up), which has neither.

Bands: the mean height must fall between Sun's TF-DEM value minus 15 % and the
experiment plus 15 % (the three published numbers span 8.9–11.4 cm). "Around" values are
read as ±50 %. Measured with the defaults ("particle" exchange, "substep" drag, boundary faces folded
and the pressure force paired: ``coupling.boundary_faces``, ``pressure_pairing``; ``NUMBA_NUM_THREADS=1
python -m pytest -m validation tests/validation/test_sun2007.py -s``, 11.5 min): goldschmidt 9.39 cm,
coordination 0.314, multicontact ratio 0.212; tsuji-jet 14.2 cm, 1.42, 0.68; tsuji-jet-background 18.6 cm,
0.576, 0.443, below Sun's 1.2 and 0.6 — the strict xfail below keeps that disagreement visible. A change of
round-off alone moves the 5–10 s means by about 0.03 in coordination (goldschmidt with the boundary faces
exchanged and the pressure force unpaired: 9.33 cm, 0.329, 0.231 for seed 11; after a round-off change
9.23–9.26 cm, 0.303–0.308, 0.216–0.219 over two seeds).
Each run takes 2–15 minutes on this 2-core machine.
"""
import json

import pytest

from fluidem.cli import main

pytestmark = pytest.mark.validation


def run_case(tmp_path_factory, name):
    out = tmp_path_factory.mktemp(name) / "run"
    assert main(["run", name, "--until", "10", "--out", str(out), "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    print(f"\n{name}: " + json.dumps({k: v for k, v in summary.items() if k.endswith(("_avg_m", "_avg", "_Hz",
                                                                                      "_avg_Pa"))}))
    return summary


@pytest.fixture(scope="module")
def goldschmidt(tmp_path_factory):
    return run_case(tmp_path_factory, "goldschmidt")


@pytest.fixture(scope="module")
def tsuji(tmp_path_factory):
    return run_case(tmp_path_factory, "tsuji-jet")


@pytest.fixture(scope="module")
def tsuji_background(tmp_path_factory):
    return run_case(tmp_path_factory, "tsuji-jet-background")


def test_goldschmidt_averages_over_sun_window(goldschmidt):
    assert goldschmidt["averages_window_s"] == [5.0, 10.0]
    assert goldschmidt["averages_samples"] > 100


def test_goldschmidt_mean_particle_height(goldschmidt):
    h = goldschmidt["mean_particle_height_avg_m"]
    assert 0.85 * 0.089 <= h <= 1.15 * 0.114, f"mean particle height {h * 100:.2f} cm"


def test_goldschmidt_coordination_and_multicontacts(goldschmidt):
    assert 0.25 <= goldschmidt["coordination_number_avg"] <= 0.75
    assert 0.15 <= goldschmidt["multicontact_ratio_avg"] <= 0.45


def test_tsuji_jet_pressure_signal_is_reported(tsuji):
    assert tsuji["pressure_drop_20cm_avg_Pa"] > 0.0
    assert tsuji["pressure_20cm_dominant_frequency_Hz"] is not None


def test_tsuji_jet_coordination_and_multicontacts(tsuji):
    """Table 1 read literally (the jet the only inflow): Sun's coordination ~1.2 and multicontact ratio
    above 0.6; measured 1.42 and 0.68 (5-10 s), with a slow dense bed beside the jet. The excess over 1.2 follows
    the pair damping (Table 1's eta is e = 0.9 for one sphere's mass, 0.862 for a pair; 1.31 with e = 0.9 for the
    pair), not the counting (tests/validation/tsuji_contacts.py, docs/gallery.md)."""
    assert 0.6 <= tsuji["coordination_number_avg"] <= 1.8
    assert tsuji["multicontact_ratio_avg"] > 0.6


@pytest.mark.xfail(strict=True, reason="tsuji-jet-background (u_mf background) multicontact ratio 0.44 (5-10 s) "
                                       "against Sun's > 0.6")
def test_tsuji_jet_background_coordination_and_multicontacts(tsuji_background):
    assert 0.6 <= tsuji_background["coordination_number_avg"] <= 1.8
    assert tsuji_background["multicontact_ratio_avg"] > 0.6
