"""Write the STL mesh of the ``hopper-3d`` built-in case (``src/fluidem/cases/hopper-3d.stl``).

A conical hopper on a vertical cylindrical bin, axis along z, in metres: the cone runs from the circular
orifice of radius ``orifice_radius`` at z = 0 up to the bin radius ``radius`` at the height where its wall
makes ``half_angle`` with the axis, and the bin's wall goes on up to ``height``. Each circle is a polygon of
``segments`` sides, and each quad between two rings two triangles (numpy-stl, binary STL).

    python3 tools/hopper_mesh.py                      # writes src/fluidem/cases/hopper-3d.stl
    python3 tools/hopper_mesh.py --out other.stl --segments 64
"""
from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np
from stl import mesh

ROOT = Path(__file__).resolve().parents[1]
RADIUS = 0.040  # bin radius [m] (20 diameters of 4 mm)
ORIFICE_RADIUS = 0.012  # orifice radius [m] (D0 = 24 mm, 6 diameters)
HALF_ANGLE = 60.0  # cone wall from the vertical [deg]
HEIGHT = 0.12  # top of the bin wall [m]
SEGMENTS = 48


def hopper_triangles(radius=RADIUS, orifice_radius=ORIFICE_RADIUS, half_angle=HALF_ANGLE, height=HEIGHT,
                     segments=SEGMENTS) -> np.ndarray:
    """(T, 3, 3) corners [m] of the cone's and the bin's triangles."""
    cone_top = (radius - orifice_radius) / math.tan(math.radians(half_angle))
    th = np.linspace(0.0, 2.0 * math.pi, segments + 1)

    def ring(r, z):
        return np.column_stack([r * np.cos(th), r * np.sin(th), np.full(th.size, z)])

    tris = []
    for lower, upper in ((ring(orifice_radius, 0.0), ring(radius, cone_top)),
                         (ring(radius, cone_top), ring(radius, height))):
        for j in range(segments):
            tris.append([lower[j], lower[j + 1], upper[j + 1]])
            tris.append([lower[j], upper[j + 1], upper[j]])
    return np.array(tris)


def main(argv=None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", default=str(ROOT / "src" / "fluidem" / "cases" / "hopper-3d.stl"))
    p.add_argument("--segments", type=int, default=SEGMENTS)
    args = p.parse_args(argv)
    tri = hopper_triangles(segments=args.segments)
    m = mesh.Mesh(np.zeros(len(tri), dtype=mesh.Mesh.dtype))
    m.vectors[:] = tri
    m.save(args.out)
    cone_top = (RADIUS - ORIFICE_RADIUS) / math.tan(math.radians(HALF_ANGLE))
    print(f"{args.out}: {len(tri)} triangles, cone top at z = {cone_top:.5f} m")


if __name__ == "__main__":
    main()
