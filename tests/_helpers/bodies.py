"""Free rigid bodies for the tests: a closed, outward-oriented STL cube (12 triangles)."""
from __future__ import annotations

import numpy as np

# the six faces of a cube, corners numbered by bits (x: 1, y: 2, z: 4), counter-clockwise seen from outside
CUBE_FACES = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]


def write_cube_stl(path, lower, upper):
    """An axis-aligned box from ``lower`` to ``upper`` as 12 outward-facing triangles in an STL file."""
    from stl import mesh

    lo, hi = np.asarray(lower, float), np.asarray(upper, float)
    c = np.array([[hi[0] if i & 1 else lo[0], hi[1] if i & 2 else lo[1], hi[2] if i & 4 else lo[2]]
                  for i in range(8)])
    tris = []
    for a, b, cc, d in CUBE_FACES:
        tris += [(a, b, cc), (a, cc, d)]
    m = mesh.Mesh(np.zeros(len(tris), dtype=mesh.Mesh.dtype))
    for j, t in enumerate(tris):
        m.vectors[j] = c[list(t)]
    m.save(str(path))
    return path
