"""What wall shapes cost per step: a settled 3D bed in a box of six planes, the same box as an STL mesh of
12 triangles, and as a fine mesh (each side split into n × n squares, 2 triangles each).

    NUMBA_NUM_THREADS=1 python benchmarks/shapes_cost.py --particles 2000 --fine 20 --per 500 --rounds 5

The bed is settled once in the plane box; the three engines then start from that state and advance in
alternating bursts of ``--per`` steps (the machine's speed drifts, so versions are timed in turns).
Printed: particle-steps per second (median over the rounds) of each, and the largest difference of the
positions from the planes' run at the end (the meshes are the same box: round-off only).
"""
from __future__ import annotations

import argparse
import copy
import tempfile
import time
from pathlib import Path

import numpy as np

from fluidem.case import validate_case
from fluidem.particles.softsphere import SoftSphereEngine

D = 4e-3


def box_stl(path: Path, lo, hi, n: int) -> None:
    """The box lo–hi as an STL file, each side split into n × n squares of two triangles."""
    from stl import mesh

    tris = []
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    s = np.linspace(0.0, 1.0, n + 1)
    for axis in range(3):
        a, b = [k for k in range(3) if k != axis]
        for side in (lo[axis], hi[axis]):
            for i in range(n):
                for j in range(n):
                    q = []
                    for di, dj in ((0, 0), (1, 0), (1, 1), (0, 1)):
                        p = np.empty(3)
                        p[axis] = side
                        p[a] = lo[a] + s[i + di] * (hi[a] - lo[a])
                        p[b] = lo[b] + s[j + dj] * (hi[b] - lo[b])
                        q.append(p)
                    tris += [(q[0], q[1], q[2]), (q[0], q[2], q[3])]
    m = mesh.Mesh(np.zeros(len(tris), dtype=mesh.Mesh.dtype))
    m.vectors[:] = np.array(tris)
    m.save(str(path))


def case(n, walls):
    side = D * 1.1 * (np.ceil(np.sqrt(n / 25.0)) + 0.5)
    return validate_case({
        "particles": {"species": [{"name": "p", "diameter": D, "density": 2500.0, "count": n}],
                      "contact": {"model": "linear_spring_dashpot", "stiffness": 1e3, "restitution": 0.3,
                                  "friction": 0.3},
                      "placement": {"method": "lattice", "spacing": 1.1, "region_lower": [0, 0, 0],
                                    "region_upper": [side, side, 0.3]}},
        "walls": walls(side),
        "time": {"end": 1.0},
    }), side


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--particles", type=int, default=2000)
    ap.add_argument("--fine", type=int, default=20, help="squares per side edge of the fine mesh")
    ap.add_argument("--per", type=int, default=500)
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--settle", type=float, default=0.3, help="[s] of settling in the plane box")
    args = ap.parse_args()
    tmp = Path(tempfile.mkdtemp())

    def planes(side):
        return [{"name": "box", "kind": "box", "lower": [0, 0, 0], "upper": [side, side, 0.3]}]

    base_case, side = case(args.particles, planes)
    base = SoftSphereEngine(base_case)
    base.advance(int(args.settle / base.dt))
    print(f"settled {args.particles} spheres for {args.settle} s in a box {side:.4f} m wide")
    engines = {"planes": SoftSphereEngine(base_case, state=copy.deepcopy(base.state))}
    for name, n in (("mesh 12 triangles", 1), (f"mesh {12 * args.fine**2} triangles", args.fine)):
        path = tmp / f"box{n}.stl"
        box_stl(path, (0, 0, 0), (side, side, 0.3), n)
        c, _ = case(args.particles, lambda s, p=path: [{"name": "box", "kind": "mesh", "file": str(p)}])
        engines[name] = SoftSphereEngine(c, state=copy.deepcopy(base.state))
    for e in engines.values():
        e.advance(20)  # compile, warm
    rates = {k: [] for k in engines}
    for _ in range(args.rounds):
        for k, e in engines.items():
            t0 = time.perf_counter()
            e.advance(args.per)
            rates[k].append(args.per * e.state.n / (time.perf_counter() - t0))
    ref = engines["planes"].state.position
    for k, e in engines.items():
        print(f"{k:>24}: {np.median(rates[k]):.3e} particle-steps/s (min {min(rates[k]):.3e}, max "
              f"{max(rates[k]):.3e}); max |x - x_planes| = {np.abs(e.state.position - ref).max():.2e} m")


if __name__ == "__main__":
    main()
