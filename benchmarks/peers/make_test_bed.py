#!/usr/bin/env python3
"""Write a loose, unsettled test bed (jittered cubic lattice, no overlaps) as an npz.

Only for functional tests of run_peers.py; for the real benchmark bed use
``run_peers.py --settle-with-lammps``.

    python benchmarks/peers/make_test_bed.py --n 2000 --box 0.04 --out /tmp/bed.npz

The npz holds: position (N,3), diameter (N,), box_lower (3,), box_upper (3,), all in m.
"""
from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np


def lattice_bed(n: int, box: float, d: float = 0.004, spacing: float = 1.1,
                jitter: float = 0.04, seed: int = 1, headroom: float = 0.0) -> dict:
    """N spheres of diameter d on a jittered cubic lattice in a box x box (x, y) column.

    spacing: lattice pitch in diameters; jitter: max random offset per axis in diameters
    (keep 2*jitter < spacing - 1 so no two spheres overlap). The box height is the lattice
    height plus ``headroom`` (m).
    """
    if 2.0 * jitter >= spacing - 1.0:
        raise ValueError("2*jitter must be < spacing - 1 so that spheres do not overlap")
    pitch = spacing * d
    margin = 0.5 * d + (spacing - 1.0) * 0.5 * d       # centre to wall, before jitter
    per_row = int(math.floor((box - 2.0 * margin) / pitch)) + 1
    if per_row < 1:
        raise ValueError("box too small for one sphere")
    per_layer = per_row * per_row
    layers = int(math.ceil(n / per_layer))
    ii = np.arange(n)
    iz, rem = np.divmod(ii, per_layer)
    iy, ix = np.divmod(rem, per_row)
    # centre the lattice in x, y
    span = (per_row - 1) * pitch
    x0 = 0.5 * (box - span)
    pos = np.stack([x0 + ix * pitch, x0 + iy * pitch, margin + iz * pitch], axis=1)
    rng = np.random.default_rng(seed)
    pos += rng.uniform(-jitter * d, jitter * d, size=pos.shape)
    top = margin + (layers - 1) * pitch + margin
    return {
        "position": pos.astype(np.float64),
        "diameter": np.full(n, d, dtype=np.float64),
        "box_lower": np.zeros(3),
        "box_upper": np.array([box, box, top + headroom]),
    }


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=2000)
    ap.add_argument("--box", type=float, default=0.04, help="box side in x and y [m]")
    ap.add_argument("--d", type=float, default=0.004, help="sphere diameter [m]")
    ap.add_argument("--spacing", type=float, default=1.1, help="lattice pitch / d")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--out", required=True)
    a = ap.parse_args(argv)
    bed = lattice_bed(a.n, a.box, a.d, a.spacing, seed=a.seed)
    Path(a.out).parent.mkdir(parents=True, exist_ok=True)
    np.savez(a.out, **bed)
    print(f"wrote {a.out}: {a.n} spheres, box {bed['box_upper'].tolist()} m")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
