"""Why the narrow beds of test_umf_sweep.py fluidise late: the wall layers and the depth-averaged gas.

Runs the u_mf sweep (``_helpers.umf_sweep``: frictionless 0.5 mm glass spheres, particle and wall
friction 0, 20 spheres per d² of bed area) on a bed ``--width`` × ``--depth`` diameters and measures,
at the end of the gas-free settling (t = T_SETTLE):

- the solids fraction across the depth (z) and the width (x) in slabs, each sphere cut exactly by the
  slab planes (the volume of a sphere between two planes), counted over the spheres whose centres lie in
  the bed's interior heights (3 d above the floor to 3 d below the top centre); the first half diameter at
  each wall against the cap volume of the layer that touches it, (2/3) π r² n_A with n_A its centres per
  wall area (no sphere of another layer reaches there);
- the bed's mean voidage ε̄ (what the depth-averaged 2D gas sees: the interior's mean over the whole
  cross-section), the core voidage ε_core (more than 1.5 d from every wall) and the equivalent wall layer
  δ_w of voidage 1 that turns ε_core into ε̄: 1 − ε̄ = (1 − ε_core)(1 − 2 δ_w / L) for walls L apart;
- Ergun's u_mf (∇p = 150 (1−ε)² μ U/(ε³ d²) + 1.75 (1−ε) ρ U²/(ε³ d) = (1−ε)(ρ_p−ρ) g) at ε_core, at ε̄, and
  for parallel channels: slabs across the depth (and the width: the x walls too) each at its own voidage,
  one common pressure gradient (the bed's weight per area over its height), U = the mean of the slabs'
  U (the bypass a depth-resolved gas would allow);
- Ergun's coefficients of the fixed bed, Δp = a U + b U², from the cell voidages of the settled bed (rows in
  series, the columns at the mean U) against those the sweep's fixed-bed branch fits;
- the voidage interpolated at the particles (Hoomans eq. 40, wall rule "copy", as the drag sees it)
  against that of their cells.

Then the sweep to U_MAX and u_mf and the plateau as test_umf_sweep.py measures them.

    python tests/validation/umf_walls.py [--width 20] [--depth 5] [--count N] [--set KEY=VALUE ...]
        [--no-sweep]
"""
import argparse
import sys
import tomllib
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tests/, for _helpers
from _helpers.umf_walls import measure  # noqa: E402


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--width", type=float, default=20.0, help="bed width [diameters]")
    ap.add_argument("--depth", type=float, default=5.0, help="bed depth [diameters]")
    ap.add_argument("--count", type=int, default=None, help="spheres (default 20 per d² of bed area)")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="case override (TOML value)")
    ap.add_argument("--no-sweep", action="store_true", help="stop after the settled-bed measures")
    args = ap.parse_args(argv)
    overrides = {}
    for item in args.set:
        key, _, text = item.partition("=")
        try:
            overrides[key] = tomllib.loads(f"v = {text}")["v"]
        except tomllib.TOMLDecodeError:
            overrides[key] = text
    measure(args.width, args.depth, args.count, overrides, sweep=not args.no_sweep)


if __name__ == "__main__":
    main()
