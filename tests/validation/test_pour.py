"""Validation: Hoomans et al. 1996 §5.1, pouring 500 particles into a 24 × 48 diameter container.

Published area fraction of the settled bed: 0.832 ± 0.010 (Hoomans, hard spheres),
0.80 (Hogue & Newland 1994), 0.805 (Rosato et al. 1986).

Known disagreement (recorded, not tuned away): our soft-sphere `pour` case settles
denser, 0.846–0.859 over four placement seeds (1996, 1, 2, 3) with k_n = 800 N/m, and
0.854 with k_n = 8000 N/m (overlaps 10× smaller), so it is not contact compliance.
A single pour is chaotic: a change of round-off alone (the flat 2D pair loop)
moved seed 1996 from 0.8476 to 0.8416, just inside the span, while seeds 1–5 gave
0.853, 0.848, 0.848, 0.852, 0.856. The published-span test therefore reads the mean over
the four seeds (0.848 now) and is a strict xfail: it turns into a failure the day the model
agrees, so the note is revisited. The hexagonal bound is a hard law, checked on every pour.
The four pours run the full case (1.5 s simulated, 8–40 s each).
"""
import json
import math

import pytest

from fluidem.cli import main

pytestmark = pytest.mark.validation

PUBLISHED_LOW = 0.80 - 0.010   # lowest published value minus Hoomans' stated uncertainty
PUBLISHED_HIGH = 0.832 + 0.010  # Hoomans' value plus its stated uncertainty
HEXAGONAL = math.pi / (2 * math.sqrt(3))  # 0.9069, densest packing of equal discs


SEEDS = (1996, 1, 2, 3)  # the case's own placement seed and three more


@pytest.fixture(scope="module")
def summaries(tmp_path_factory):
    out = []
    for seed in SEEDS:
        run = tmp_path_factory.mktemp("pour") / f"seed{seed}"
        assert main(["run", "pour", "--out", str(run), "--quiet", "--set", f"particles.placement.seed={seed}"]) == 0
        out.append(json.loads((run / "summary.json").read_text()))
    return out


def test_pour_settles_below_the_hexagonal_bound(summaries):
    for summary in summaries:
        assert summary["status"] == "completed"
        # settled: kinetic energy far below the ~1e-2 J of potential energy released
        assert summary["kinetic_energy_J"] < 1e-8
        assert summary["packing_fraction"] < HEXAGONAL


@pytest.mark.xfail(strict=True, reason="soft-sphere pour packs 0.848 on average over 4 seeds (0.842-0.853) vs "
                                       "published 0.80-0.842")
def test_pour_packing_fraction_in_published_span(summaries):
    phis = [s["packing_fraction"] for s in summaries]
    phi = sum(phis) / len(phis)
    assert PUBLISHED_LOW <= phi <= PUBLISHED_HIGH, \
        f"mean packing fraction {phi:.4f} over seeds {SEEDS} ({', '.join(f'{p:.4f}' for p in phis)}) outside the span"
