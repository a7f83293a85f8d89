"""Validation: Hoomans et al. 1996 §5.1, pouring 500 particles into a 24 × 48 diameter container.

Published area fraction of the settled bed: 0.832 ± 0.010 (Hoomans, hard spheres),
0.80 (Hogue & Newland 1994), 0.805 (Rosato et al. 1986).

Known disagreement (recorded, not tuned away): our soft-sphere `pour` case settles
denser, 0.846–0.859 over four placement seeds (1996, 1, 2, 3) with k_n = 800 N/m, and
0.854 with k_n = 8000 N/m (overlaps 10× smaller), so it is not contact compliance.
The published-span test is therefore a strict xfail: it turns into a failure the day
the model agrees, so the note is revisited. The hexagonal bound is a hard law.
Each test runs the full case (1.5 s simulated, 20–40 s on 2 cores).
"""
import json
import math

import pytest

from fluidem.cli import main

pytestmark = pytest.mark.validation

PUBLISHED_LOW = 0.80 - 0.010   # lowest published value minus Hoomans' stated uncertainty
PUBLISHED_HIGH = 0.832 + 0.010  # Hoomans' value plus its stated uncertainty
HEXAGONAL = math.pi / (2 * math.sqrt(3))  # 0.9069, densest packing of equal discs


@pytest.fixture(scope="module")
def summary(tmp_path_factory):
    out = tmp_path_factory.mktemp("pour") / "run"
    assert main(["run", "pour", "--out", str(out), "--quiet"]) == 0
    return json.loads((out / "summary.json").read_text())


def test_pour_settles_below_the_hexagonal_bound(summary):
    assert summary["status"] == "completed"
    # settled: kinetic energy far below the ~1e-2 J of potential energy released
    assert summary["kinetic_energy_J"] < 1e-8
    assert summary["packing_fraction"] < HEXAGONAL


@pytest.mark.xfail(strict=True, reason="soft-sphere pour packs 0.846-0.859 (4 seeds) vs published 0.80-0.842")
def test_pour_packing_fraction_in_published_span(summary):
    phi = summary["packing_fraction"]
    assert PUBLISHED_LOW <= phi <= PUBLISHED_HIGH, f"packing fraction {phi:.4f} outside published span"
