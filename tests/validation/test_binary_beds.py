"""The built-in binary beds segregate the way the Di Renzo–Di Maio criterion predicts (DEM book 2012
two-phase chapter, eqs 13-19).

Each bed starts mixed at random and is fluidised at 1.2 u_mf of its harder-to-fluidise species. After
RUN seconds the segregation index S = 2 (h_1 − h_2)/(h_1 + h_2) of the case's first species over its
second (``analysis.mixing``), averaged over the second half of the run (the summary's
``segregation_index_avg``), must have the sign of the predicted direction: S > 0 when the first species
is the flotsam. The competing pair (the smaller denser against the larger lighter) is run once on each
side of the equilibrium line (``binary-competing``: the larger lighter is the flotsam;
``binary-competing-inverse``: the smaller denser is). The indices, the initial index and the run length
are printed, to be recorded; a bed that disagrees is a finding to report with its numbers.

    python3 -m pytest -m validation tests/validation/test_binary_beds.py -s
"""
from __future__ import annotations

import json

import pytest

import fluidem as fd
from fluidem.cli import main
from fluidem.io.probes_csv import read_probes

pytestmark = pytest.mark.validation

RUN = 5.0  # [s] simulated; the summary averages over its second half


def predicted_flotsam(name: str) -> int:
    """1 or 2: the case species (in case order) the criterion puts on top, at the bed voidage 0.4 of Fig 1."""
    case = fd.load_case(name)
    a, b = case.particles.species
    volume = [s.count * s.diameter**3 for s in (a, b)]
    x1 = volume[0] / sum(volume)
    result = fd.segregation_criterion((a.diameter, b.diameter), (a.density, b.density), x1, voidage=0.4)
    assert result.flotsam in (1, 2), f"{name}: on the equilibrium line ({result.flotsam})"
    return result.flotsam


@pytest.mark.parametrize("name, flotsam", [("binary-size", 1), ("binary-density", 1), ("binary-competing", 2),
                                           ("binary-competing-inverse", 1)])
def test_binary_bed_segregates_as_the_criterion_predicts(tmp_path, name, flotsam):
    assert predicted_flotsam(name) == flotsam  # the cases are set up on the side of the line they claim
    out = tmp_path / "run"
    assert main(["run", name, "--until", str(RUN), "--out", str(out), "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    probes = read_probes(out / "probes.csv")
    s = summary["segregation_index_avg"]
    print(f"\n{name}: run {RUN} s, window {summary['averages_window_s']}, S(0) = {probes['segregation_index'][0]:.4f}, "
          f"S_avg = {s:.4f}, S(end) = {probes['segregation_index'][-1]:.4f}, "
          f"Lacey avg = {summary.get('lacey_index_avg')}, wall {summary['wall_time_s']:.0f} s")
    assert (s > 0.0) == (flotsam == 1), f"{name}: segregation index {s:.4f}, predicted flotsam species {flotsam}"
