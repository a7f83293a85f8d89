"""The 3D gas solver's ghost faces (``_solver3d_kernels.fill_face_ghosts``) against the rules written out with
(x, y, z) indices: for each velocity direction a and each axis d, the two ghost layers beyond either side of d
from the side's flag (``_tangential`` across a side parallel to a, ``_normal`` across a side normal to it,
the periodic duplicate face first), the tangential axes before the normal one, k = 1 before k = 2."""
import numpy as np
import pytest

from fluidem.gas import _solver3d_kernels as K3
from fluidem.gas._solver_kernels import _normal, _tangential
from fluidem.gas.grid import FREE_SLIP, INFLOW, NO_SLIP, OUTFLOW, PERIODIC, PRESSURE

FLAGS = (NO_SLIP, FREE_SLIP, INFLOW, PERIODIC, PRESSURE, OUTFLOW)


def reference(W, flags, n3):
    tan, nor = _tangential.py_func, _normal.py_func

    def at(d, p, s, t):
        return (p, s, t) if d == 0 else ((t, p, s) if d == 1 else (s, t, p))

    for a in range(3):
        for q in range(3):
            Wa = W[a]
            d = (a + 1 + q) % 3
            e1, e2 = (d + 1) % 3, (d + 2) % 3
            n = n3[d]
            for s in range(n3[e1] + 4 + (e1 == a)):
                cs = min(max(s - 2, 0), n3[e1] - 1) + 1
                for t in range(n3[e2] + 4 + (e2 == a)):
                    ct = min(max(t - 2, 0), n3[e2] - 1) + 1
                    flo, fhi = flags[at(d, 0, cs, ct)], flags[at(d, n + 1, cs, ct)]
                    if d != a:
                        for k in (1, 2):
                            Wa[at(d, 2 - k, s, t)] = tan(flo, Wa[at(d, 1 + k, s, t)], Wa[at(d, 2 + (n - k) % n, s, t)])
                            Wa[at(d, n + 1 + k, s, t)] = tan(fhi, Wa[at(d, n + 2 - k, s, t)],
                                                             Wa[at(d, 2 + (k - 1) % n, s, t)])
                    else:
                        if fhi == PERIODIC:
                            Wa[at(d, n + 2, s, t)] = Wa[at(d, 2, s, t)]
                        for k in (1, 2):
                            Wa[at(d, 2 - k, s, t)] = nor(flo, Wa[at(d, 2, s, t)], Wa[at(d, 2 + k, s, t)],
                                                         Wa[at(d, 2 + (n - k) % n, s, t)])
                            Wa[at(d, n + 2 + k, s, t)] = nor(fhi, Wa[at(d, n + 2, s, t)], Wa[at(d, n + 2 - k, s, t)],
                                                             Wa[at(d, 2 + k % n, s, t)])


@pytest.mark.parametrize("shape", [(4, 5, 1), (1, 3, 2), (3, 2, 4)])
@pytest.mark.parametrize("threads", [1, 2])
def test_ghost_faces_follow_the_rules_on_any_side_mix(shape, threads):
    rng = np.random.default_rng(sum(shape) + threads)
    nx, ny, nz = shape
    for _ in range(5):
        flags = rng.choice(np.array(FLAGS, dtype=np.int8), size=(nx + 2, ny + 2, nz + 2))
        W = rng.standard_normal((3, nx + 5, ny + 5, nz + 5))
        expected = W.copy()
        reference(expected, flags, shape)
        K3.fill_face_ghosts(W, flags, nx, ny, nz, threads)
        assert np.array_equal(W, expected)
