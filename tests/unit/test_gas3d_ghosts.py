"""The 3D gas solver's ghost faces (``_solver3d_kernels.fill_face_ghosts``) against the rules written out with
(x, y, z) indices: for each velocity direction a and each axis d, the two ghost layers beyond either side of d
from the side's flag (``_tangential`` across a side parallel to a, ``_normal`` across a side normal to it,
the periodic duplicate face first), the tangential axes before the normal one, k = 1 before k = 2; and the
boundary cells of a centre scalar (``fill_centre_ghosts``) likewise."""
import numpy as np
import pytest

from fluidem.gas import _solver3d_kernels as K3
from fluidem.gas._layout3d import R_COPY, R_FIXED, R_NONE, R_WRAP
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


def centre_reference(q, flags, rule, fixed, n3):
    """``fill_centre_ghosts`` with (x, y, z) indices: each face's boundary cells by the rule of their flag
    (the adjacent interior cell, the fixed value, the opposite interior cell, or left as they are), then the
    edges along each axis (wrapped along a periodic axis, else the mean of the two ring cells beside them),
    then the corners (wrapped, else the mean of three)."""
    def at(d, p, s, t):
        return (p, s, t) if d == 0 else ((t, p, s) if d == 1 else (s, t, p))

    for a in range(3):
        na, nb, nc = n3[a], n3[(a + 1) % 3], n3[(a + 2) % 3]
        for s in range(1, nb + 1):
            for t in range(1, nc + 1):
                for hi in (0, 1):
                    g = at(a, na + 1 if hi else 0, s, t)
                    r = rule[flags[g]]
                    if r == R_COPY:
                        q[g] = q[at(a, na if hi else 1, s, t)]
                    elif r == R_FIXED:
                        q[g] = fixed[g]
                    elif r == R_WRAP:
                        q[g] = q[at(a, 1 if hi else na, s, t)]
    per = (flags[0, 1, 1] == PERIODIC, flags[1, 0, 1] == PERIODIC, flags[1, 1, 0] == PERIODIC)
    for c in range(3):
        a, b = (c + 1) % 3, (c + 2) % 3
        for pa, ia, wa in ((0, 1, n3[a]), (n3[a] + 1, n3[a], 1)):
            for pb, ib, wb in ((0, 1, n3[b]), (n3[b] + 1, n3[b], 1)):
                for pc in range(1, n3[c] + 1):
                    g = at(c, pc, pa, pb)
                    if per[a]:
                        q[g] = q[at(c, pc, wa, pb)]
                    elif per[b]:
                        q[g] = q[at(c, pc, pa, wb)]
                    else:
                        q[g] = 0.5 * (q[at(c, pc, ia, pb)] + q[at(c, pc, pa, ib)])
    nx, ny, nz = n3
    for px, ix, wx in ((0, 1, nx), (nx + 1, nx, 1)):
        for py, iy, wy in ((0, 1, ny), (ny + 1, ny, 1)):
            for pz, iz, wz in ((0, 1, nz), (nz + 1, nz, 1)):
                if per[0]:
                    q[px, py, pz] = q[wx, py, pz]
                elif per[1]:
                    q[px, py, pz] = q[px, wy, pz]
                elif per[2]:
                    q[px, py, pz] = q[px, py, wz]
                else:
                    q[px, py, pz] = (q[ix, py, pz] + q[px, iy, pz] + q[px, py, iz]) / 3.0


@pytest.mark.parametrize("shape", [(4, 5, 1), (1, 3, 2), (3, 2, 4), (15, 40, 3)])
def test_centre_ghosts_follow_the_rules_on_any_side_mix(shape):
    rng = np.random.default_rng(sum(shape))
    nx, ny, nz = shape
    for trial in range(6):
        rule = rng.choice(np.array([R_NONE, R_COPY, R_FIXED, R_WRAP]), size=9)  # a rule per flag (RULES' rows)
        rule[:4] = (R_NONE, R_COPY, R_FIXED, R_WRAP)
        flags = rng.integers(0, rule.size, size=(nx + 2, ny + 2, nz + 2)).astype(np.int8)
        if trial % 2:  # the periodic tests of the edges and corners read flags[0, 1, 1] etc.
            for g in ((0, 1, 1), (1, 0, 1), (1, 1, 0)):
                flags[g] = rng.choice([PERIODIC, NO_SLIP])
        q = rng.standard_normal((nx + 2, ny + 2, nz + 2))
        fixed = rng.standard_normal(q.shape)
        expected = q.copy()
        centre_reference(expected, flags, rule, fixed, shape)
        K3.fill_centre_ghosts(q, flags, rule, fixed, nx, ny, nz)
        assert np.array_equal(q, expected)
