"""Validation of the 3D hopper and drum cases without gas.

``hopper-3d``: the steady discharge rate against Beverloo's correlation W = C ρ_b √g (D₀ − k d)^{5/2}
(Beverloo, Leniger & van de Velde 1961), with C = 0.58 and k = 1.5 (Nedderman 1992, ch. 10, as typical of
published data: C 0.55–0.65, k 1.3–1.5) and the bulk density ρ_b measured in the run. The hopper's cone is
60° from the vertical: steeper than the angle of internal friction would need for mass flow, so it empties in
funnel flow, through a stagnant cone, as a flat-bottomed bin does, for which the correlation was made.
Tolerance ±15 %: the spread of C over the published data alone is ±8 % about 0.58 (0.55–0.65, and 0.58 is
not its midpoint), and k between 1.3 and 1.5 moves (D₀ − k d)^{5/2} by 12 % at D₀ = 6 d; the soft contact
law and the 48-sided orifice are not the experiments' hard glass and circle.

``drum-3d`` and ``drum-3d-cohesive``: the dynamic angle of repose of the rolling bed (``analysis.repose``,
mean over the second half of the 3 s run) is larger with JKR cohesion between the particles (Bond number 8.6)
than without, as Wu & Guo (DEM book 2012) found for the cohesive powder of their roll-compaction hopper. The
cohesive bed slumps in intermittent avalanches (its angle swings between about 27° and 63°), the dry one rolls
(±1.5°), so the difference of the means must exceed twice its standard error, taken from block means: the
151 probes of the window in 5 blocks of 0.3 s, longer than the angles' correlation times (e-folding of the
autocorrelation 0.05 s dry, 0.14 s cohesive), so the blocks are nearly independent.

Measured (``python3 -m fluidem run CASE --out DIR --threads 1`` for each case, then the functions below on
DIR; the same figures as ``pytest -m validation tests/validation/test_hopper_drum.py -s`` prints):
hopper-3d 0.1068 kg/s over 0.53–1.48 s, ρ_b = 1462 kg/m³, Beverloo 0.1155 kg/s, ratio 0.925;
drum-3d 31.9 ± 1.5° (standard error 0.25°); drum-3d-cohesive 45.9 ± 12.8° (standard error 5.5°):
the difference 14.0° against twice its standard error, 11.1°.
"""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

from fluidem.analysis.discharge import beverloo_rate, bulk_density, steady_rate
from fluidem.case import load_case
from fluidem.cli import main
from fluidem.io.probes_csv import read_probes
from fluidem.io.snapshots import iter_snapshots

pytestmark = pytest.mark.validation

ORIFICE_DIAMETER = 0.024  # [m], the mesh's (tools/hopper_mesh.py)
BIN_RADIUS = 0.040
CONE_TOP = (0.040 - 0.012) / math.tan(math.radians(60.0))  # [m], where the cone meets the bin
TOLERANCE = 0.15  # module docstring
SETTLED = 0.2  # [s] the lattice has fallen onto the cone by then (its top from 0.11 m to 0.045 m above the orifice)


@pytest.fixture(scope="module")
def hopper_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("hopper") / "run"
    assert main(["run", "hopper-3d", "--out", str(out), "--quiet", "--threads", "1"]) == 0
    return out


def hopper_figures(out):
    """(steady rate [kg/s], window (t0, t1) [s], bulk density [kg/m^3], Beverloo's rate [kg/s])."""
    case = load_case("hopper-3d")
    probes = read_probes(out / "probes.csv")
    rate, t0, t1 = steady_rate(probes["time_s"], probes["outlet_discharge_mass_kg"])
    d = case.particles.species[0].diameter
    rho = case.particles.species[0].density
    # the bed at rest in the bin: from when it has collapsed onto the cone (0.2 s) to the window's start, in the
    # bin's lowest three diameters above the cone (below the free surface then), two diameters off the bin wall
    rhos = []
    for t, snap in iter_snapshots(out, fields=("position", "diameter")):
        if SETTLED <= t <= t0:
            rhos.append(bulk_density(snap["position"], snap["diameter"] / 2, rho, (0.0, 0.0, 0.0), (0.0, 0.0, 1.0),
                                     BIN_RADIUS - 2 * d, CONE_TOP, CONE_TOP + 3 * d))
    rho_b = float(np.mean(rhos))
    return rate, (t0, t1), rho_b, beverloo_rate(rho_b, ORIFICE_DIAMETER, d)


def test_hopper_discharges_at_beverloos_rate(hopper_run):
    summary = json.loads((hopper_run / "summary.json").read_text())
    assert summary["status"] == "completed"
    rate, window, rho_b, expected = hopper_figures(hopper_run)
    print(f"hopper-3d: steady rate {rate:.4f} kg/s over {window[0]:.2f}-{window[1]:.2f} s, bulk density "
          f"{rho_b:.0f} kg/m3, Beverloo {expected:.4f} kg/s, ratio {rate / expected:.3f}")
    assert rate == pytest.approx(expected, rel=TOLERANCE)


@pytest.fixture(scope="module")
def drum_runs(tmp_path_factory):
    out = {}
    for name in ("drum-3d", "drum-3d-cohesive"):
        run = tmp_path_factory.mktemp(name) / "run"
        assert main(["run", name, "--out", str(run), "--quiet", "--threads", "1"]) == 0
        out[name] = run
    return out


BLOCKS = 5  # block means of the angle over the window (module docstring)


def drum_angle(run):
    """(mean, standard deviation, standard error of the mean from ``BLOCKS`` block means) [deg] of
    repose_angle_deg over the second half of the run."""
    probes = read_probes(run / "probes.csv")
    t = probes["time_s"]
    a = probes["repose_angle_deg"][t >= 0.5 * t[-1] - 1e-9]
    summary = json.loads((run / "summary.json").read_text())
    assert summary["repose_angle_avg_deg"] == pytest.approx(float(np.mean(a)), rel=1e-9)
    blocks = np.array([b.mean() for b in np.array_split(a, BLOCKS)])
    return float(np.mean(a)), float(np.std(a)), float(blocks.std(ddof=1) / math.sqrt(BLOCKS))


def test_cohesive_drum_has_the_larger_angle_of_repose(drum_runs):
    dry, dry_sd, dry_se = drum_angle(drum_runs["drum-3d"])
    wet, wet_sd, wet_se = drum_angle(drum_runs["drum-3d-cohesive"])
    print(f"drum-3d: {dry:.1f} ± {dry_sd:.1f} deg (standard error {dry_se:.2f}); drum-3d-cohesive: {wet:.1f} ± "
          f"{wet_sd:.1f} deg (standard error {wet_se:.2f})")
    assert 10.0 < dry < 45.0  # a rolling bed of frictional spheres
    assert wet - dry > 2.0 * math.hypot(dry_se, wet_se)
