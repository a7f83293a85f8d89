"""Compiled kernels of the particle → grid mapping on a 3D grid (``voidage.py``): deposits, exact sphere–cell
volumes, diffusion.

``map_solids3d`` is the whole 3D mapping in one call (deposit, smoothing, clipping, averages). Method codes
are the indices in ``voidage.METHODS`` (0 centroid, 3 volume) and weighting codes those in
``voidage.WEIGHTINGS`` (0 number, 1 volume). Periodic axes wrap; along a non-periodic axis the two edge
cells reach to ±∞, so that every particle's whole volume is counted (a sphere poking through a wall or
the domain's side is counted in the edge cell), and Σ_cells (1 − ε) V_cell = Σ_p V_p to round-off.

The exact volume of a sphere inside an axis-aligned box is a closed form (``sphere_box_volume``): the box's
indicator is the signed sum of the indicators of its eight corner octants {x > a, y > b, z > c}
(inclusion–exclusion along each axis), and the sphere's volume in an octant with a, b, c ≥ 0 is the
integral over z of the area of its circular cross-section in the quadrant x > a, y > b,
V(a, b, c) = ∫_c^{z_m} Q(√(r² − z²)) dz, z_m = √(r² − a² − b²), with
Q(ρ) = ½ρ²(π/2 − asin(a/ρ) − asin(b/ρ)) − ½a√(ρ² − a²) − ½b√(ρ² − b²) + ab, which integrates in closed
form (``_corner_primitive``; the asin term by parts, leaving ∫ dz/((r² − z²)√(s² − z²)) =
atan(zb/(r√(s² − z²)))/(rb), s² = r² − b²). A closed form was chosen over a quadrature of the
cross-section areas because the integrand has square-root end-point behaviour where the sphere meets
a cell edge, which a Gauss rule resolves only slowly; the closed form is exact to round-off and costs a
few transcendental calls per cell corner. Octants with a negative bound are reduced to non-negative ones
by the sphere's mirror symmetry (1_{x > a} = 1 − 1_{−x > −a}); an unbounded axis leaves a spherical cap
(two unbounded) or twice the octant at a = 0 (one unbounded).

``volume_deposit`` takes most spheres by a shorter road. A sphere under a cell across has at most one cell
face inside it per axis; with W(T) its volume beyond the faces of the axes in T (the whole sphere, a spherical
cap, twice an octant volume at 0 on the free axis, an octant volume), the cell beyond the faces of H and on
the centre's side of the others holds Σ_{H ⊆ T} (−1)^{|T| − |H|} W(T) (``_split_cells``): one octant volume at
most instead of eight cell corners, the same volumes to round-off. Other spheres evaluate ``corner_volume``
once per grid node around them and sum each cell's eight corners from those values, in the order and with
the signs of ``sphere_box_volume`` (bitwise its volume), so that a node shared by several cells is evaluated
once (a sphere across three faces of each axis: 64 nodes instead of 27 × 8 corners). The per-particle work (the
node values and each cell's volume; for the centroid map each particle's cell) is done first, in chunks of
``CHUNK`` particles on Numba's threads (``prange``), into a scratch array ``work``. The sums onto the grid
follow in particle order, on all threads too: the grid is split along x (its first index, so that each part is
one contiguous block of every grid array) into one slab of whole yz planes per thread (``slab_count``,
``slab_bounds``); each sphere's slabs are marked first, as the bits of one integer (``_volume_slabs``), and
each slab walks the particles in particle order, skips those not marked for it and adds the cells whose
wrapped x index lies in it (``_volume_add``). Every cell then receives the same numbers, in the same order, as
in one serial pass over all particles, so the maps are bitwise the same for any number of threads. At most
``CHUNK`` particles, or one thread, take the one serial pass. The map of the "volume" method with the
"number" weighting adds each particle's count and velocity to the cell of its centre in the same pass
(``_volume_deposit``: one walk over the particles instead of two; the same sums in the same order).
"""
import math

import numba
import numpy as np
from numba import njit, prange

try:  # Numba's own intrinsic for the thread count, which its parallel regions use: a kernel calling it can be
    # cached, while one calling ``numba.get_num_threads`` (a ctypes pointer) cannot
    from numba.np.ufunc.parallel import _iget_num_threads as _num_threads
except ImportError:  # pragma: no cover - a Numba without it: the same number, uncached
    _num_threads = numba.get_num_threads

from ._voidage_kernels import cell_index

CHUNK = 256  # particles per work item of the parallel passes


@njit(cache=True, inline="always")
def _corner_primitive(z, a, b, r, wa, wb):
    """Antiderivative in z of the quadrant area Q of the module docstring (a, b ≥ 0), at z ≥ 0 with
    wa = √(r² − a² − z²), wb = √(r² − b² − z²) given (exact at the upper end, where they are b and a).

    The two axes' asin(q/ρ) terms share the factor −½p and their atan terms the factor r³/3, so each pair
    is taken as one angle: asin(a/ρ) + asin(b/ρ) = arg((wa + i a)(wb + i b)) and
    atan(z a/(r wa)) + atan(z b/(r wb)) = arg((r wa + i z a)(r wb + i z b)), both sums in [0, π]: four
    arctangents instead of six, three at the upper end (where the first sum is π/2). The product's parts
    carry a rounding error below ε|z₁||z₂|, so each angle stays within a few ε of the sum of its two
    arctangents."""
    p = r * r * z - z * z * z / 3.0  # ∫ (r² − z²) dz
    cross = a * wb + b * wa
    real = wa * wb - a * b  # exactly 0 at the upper end (wa = b, wb = a): there the sum is π/2, no call
    # asin(a/ρ) + asin(b/ρ)
    asq = 0.5 * math.pi if real == 0.0 and cross > 0.0 else math.atan2(cross, real)
    at = math.atan2(z * r * cross, r * r * wa * wb - z * z * a * b)
    # −½ ∫ ρ² asin(q/ρ) dz by parts: −½ p asin(q/ρ) + r³/3 atan(z q/(r w)) here, ½ q j below, for both axes
    out = 0.25 * math.pi * p + a * b * z - 0.5 * p * asq + r * r * r / 3.0 * at
    for k in range(2):
        q = a if k == 0 else b
        w = wa if k == 0 else wb
        s2 = r * r - q * q
        asz = math.atan2(z, w)  # asin(z/s)
        j = (s2 * asz - z * w) / 6.0 - 2.0 * r * r / 3.0 * asz
        out += 0.5 * q * j - 0.25 * q * (z * w + s2 * asz)  # and −½ q ∫ √(s² − z²) dz
    return out


@njit(cache=True)
def octant_volume(a, b, c, r):
    """Volume [m³] of the sphere of radius r centred at the origin inside {x > a, y > b, z > c}, a, b, c ≥ 0
    (module docstring)."""
    if a * a + b * b + c * c >= r * r:
        return 0.0
    zm = math.sqrt(r * r - a * a - b * b)
    if c == 0.0:  # the primitive is 0 (to the sign) at z = 0
        return _corner_primitive(zm, a, b, r, b, a)
    wa = math.sqrt(max(r * r - a * a - c * c, 0.0))
    wb = math.sqrt(max(r * r - b * b - c * c, 0.0))
    return _corner_primitive(zm, a, b, r, b, a) - _corner_primitive(c, a, b, r, wa, wb)


@njit(cache=True, inline="always")
def _bounded_volume(a, b, c, ua, ub, uc, r):
    """``octant_volume`` where each bound is ≥ 0 or unbounded (``ua``…: that axis is not restricted)."""
    k = int(ua) + int(ub) + int(uc)
    if k == 3:
        return 4.0 / 3.0 * math.pi * r * r * r
    if k == 2:
        h = c if not uc else (b if not ub else a)
        return math.pi * (r - h) * (r - h) * (2.0 * r + h) / 3.0  # spherical cap beyond h
    if k == 1:  # twice the octant at 0 on the unbounded axis
        if ua:
            return 2.0 * octant_volume(0.0, b, c, r)
        if ub:
            return 2.0 * octant_volume(0.0, a, c, r)
        return 2.0 * octant_volume(0.0, a, b, r)
    return octant_volume(a, b, c, r)


@njit(cache=True, inline="always")
def _terms(a, r):
    """The half-line x > a as signed non-negative half-lines (mirror symmetry): (n, s0, v0, u0, s1, v1, u1),
    n terms, each sign s, bound v ≥ 0 and whether unbounded u; n = 0 when a ≥ r (nothing of the sphere)."""
    if a >= r:
        return 0, 0.0, 0.0, False, 0.0, 0.0, False
    if a >= 0.0:
        return 1, 1.0, a, False, 0.0, 0.0, False
    if a > -r:
        return 2, 1.0, 0.0, True, -1.0, -a, False
    return 1, 1.0, 0.0, True, 0.0, 0.0, False


@njit(cache=True)
def corner_volume(a, b, c, r):
    """Volume [m³] of the sphere of radius r centred at the origin inside {x > a, y > b, z > c}, any a, b, c
    (−∞ allowed)."""
    na, sa0, va0, ua0, sa1, va1, ua1 = _terms(a, r)
    nb, sb0, vb0, ub0, sb1, vb1, ub1 = _terms(b, r)
    nc, sc0, vc0, uc0, sc1, vc1, uc1 = _terms(c, r)
    total = 0.0
    for i in range(na):
        s_i = sa0 if i == 0 else sa1
        v_i = va0 if i == 0 else va1
        u_i = ua0 if i == 0 else ua1
        for j in range(nb):
            s_j = sb0 if j == 0 else sb1
            v_j = vb0 if j == 0 else vb1
            u_j = ub0 if j == 0 else ub1
            for k in range(nc):
                s_k = sc0 if k == 0 else sc1
                v_k = vc0 if k == 0 else vc1
                u_k = uc0 if k == 0 else uc1
                total += s_i * s_j * s_k * _bounded_volume(v_i, v_j, v_k, u_i, u_j, u_k, r)
    return total


@njit(cache=True, inline="always")
def _cap(h, r):
    """Volume [m³] of the sphere of radius r beyond a plane at distance h ∈ [0, r] from its centre."""
    return math.pi * (r - h) * (r - h) * (2.0 * r + h) / 3.0


@njit(cache=True)
def _split_cells(af, bf, cf, hx, hy, hz, lx, ly, lz, ux, uy, uz, r, scale, work, f):
    """The cells of a sphere of radius r that has at most one face inside it per axis (``_volume_range``) and
    their volumes, as (i, j, k, scale V) into work[f], work[f + 4] …; returns their number. hx: the x axis has
    a face, at signed distance af from the centre, between the cells lx (below) and ux (above); without one the
    sphere is in cell lx along x (the same for y and z).

    With W(T) the volume beyond the faces of the axes in T (on the side away from the centre: W(∅) the sphere,
    one face a spherical cap, two faces twice the octant volume at 0 on the free axis, three faces the octant
    volume of the module docstring), the cell beyond the faces of H and on the centre's side of the others has
    V = Σ_{H ⊆ T ⊆ F} (−1)^{|T| − |H|} W(T) (inclusion–exclusion, F the axes with a face): the same volumes as
    ``sphere_box_volume`` to round-off, with one octant volume at most (it takes eight cell corners)."""
    da, db, dc = abs(af), abs(bf), abs(cf)
    whole = 4.0 / 3.0 * math.pi * r * r * r
    wx = _cap(da, r) if hx else 0.0
    wy = _cap(db, r) if hy else 0.0
    wz = _cap(dc, r) if hz else 0.0
    wxy = 2.0 * octant_volume(da, db, 0.0, r) if hx and hy else 0.0
    wxz = 2.0 * octant_volume(da, dc, 0.0, r) if hx and hz else 0.0
    wyz = 2.0 * octant_volume(db, dc, 0.0, r) if hy and hz else 0.0
    wxyz = octant_volume(da, db, dc, r) if hx and hy and hz else 0.0
    beyond = (whole, wx, wy, wxy, wz, wxz, wyz, wxyz)  # W(t), t the bits 1 x, 2 y, 4 z
    faces = (1 if hx else 0) | (2 if hy else 0) | (4 if hz else 0)
    m = 0
    for h in range(8):
        if h & faces != h:
            continue
        v = 0.0
        for t in range(8):
            if t & faces != t or t & h != h:
                continue
            extra = (t ^ h)
            sign = -1.0 if ((extra & 1) + ((extra >> 1) & 1) + ((extra >> 2) & 1)) % 2 == 1 else 1.0
            v += sign * beyond[t]
        if v > 0.0:
            # beyond a face at af ≥ 0 is the cell above it, beyond one at af < 0 the cell below
            i = lx if not hx else (ux if (h & 1 != 0) == (af >= 0.0) else lx)
            j = ly if not hy else (uy if (h & 2 != 0) == (bf >= 0.0) else ly)
            k = lz if not hz else (uz if (h & 4 != 0) == (cf >= 0.0) else lz)
            work[f + 4 * m] = i
            work[f + 4 * m + 1] = j
            work[f + 4 * m + 2] = k
            work[f + 4 * m + 3] = scale * v
            m += 1
    return m


@njit(cache=True)
def sphere_box_volume(cx, cy, cz, r, x0, x1, y0, y1, z0, z1):
    """Exact volume [m³] of the sphere of radius r centred at (cx, cy, cz) inside the box
    [x0, x1] × [y0, y1] × [z0, z1] (bounds may be ±∞): Σ ± ``corner_volume`` over the box's eight corners
    (inclusion–exclusion, module docstring)."""
    total = 0.0
    for i in range(2):
        a = (x0 if i == 0 else x1) - cx
        for j in range(2):
            b = (y0 if j == 0 else y1) - cy
            for k in range(2):
                c = (z0 if k == 0 else z1) - cz
                sign = 1.0 if (i + j + k) % 2 == 0 else -1.0
                total += sign * corner_volume(a, b, c, r)
    return total


@njit(cache=True, inline="always")
def _cell_range(x, r, d, n, periodic):
    """(first, last) cell of one axis that the interval [x − r, x + r] touches; unwrapped on a periodic axis,
    clamped to [0, n − 1] otherwise."""
    a0 = int(math.floor((x - r) / d))
    a1 = int(math.floor((x + r) / d))
    if not periodic:
        a0 = min(max(a0, 0), n - 1)
        a1 = min(max(a1, 0), n - 1)
    return a0, a1


@njit(cache=True, inline="always")
def _bounds(i, d, n, periodic):
    """Lower and upper coordinate of (unwrapped) cell i; the edge cells of a non-periodic axis reach to ±∞."""
    lo = i * d
    hi = (i + 1) * d
    if not periodic:
        if i == 0:
            lo = -math.inf
        if i == n - 1:
            hi = math.inf
    return lo, hi


@njit(cache=True, inline="always")
def _node(a0, m, d, n, periodic):
    """Coordinate of node m of the cells a0, a0 + 1, … of one axis: the lower side of cell a0 (m = 0) or the upper
    side of cell a0 + m − 1, as ``_bounds`` gives them."""
    if m == 0:
        lo, _ = _bounds(a0, d, n, periodic)
        return lo
    _, hi = _bounds(a0 + m - 1, d, n, periodic)
    return hi


@njit(cache=True, inline="always")
def _outside(a0, m, x, r, d, n, periodic):
    """Whether the first of the m nodes from cell a0 lies at or below x − r and the last at or above x + r."""
    return _node(a0, 0, d, n, periodic) - x <= -r and _node(a0, m - 1, d, n, periodic) - x >= r


@njit(cache=True, inline="always")
def _axis_cells(r, d, n, periodic):
    """Most cells along one axis that [x − r, x + r] can touch: ⌊2r/d⌋ + 2 (the margin covering round-off), at
    most n on a non-periodic axis."""
    m = int(math.floor(2.0 * r / d + 1e-6)) + 2
    if not periodic:
        m = min(m, n)
    return m


@njit(cache=True)
def _volume_layout(radius, dx, dy, dz, nx, ny, nz, px, py, pz):
    """(nodes, stride) of the scratch of ``volume_deposit`` per particle: room for the node values of the most
    cells a sphere of the largest radius can overlap, then a count and (i, j, k, V) of each of those cells."""
    rmax = 0.0
    for p in range(radius.shape[0]):
        rmax = max(rmax, radius[p])
    ma, mb, mc = _axis_cells(rmax, dx, nx, px), _axis_cells(rmax, dy, ny, py), _axis_cells(rmax, dz, nz, pz)
    nodes = (ma + 1) * (mb + 1) * (mc + 1)
    return nodes, nodes + 1 + 4 * ma * mb * mc


@njit(cache=True)
def volume_stride(radius, dx, dy, dz, nx, ny, nz, px, py, pz):
    """Scratch entries per particle of ``volume_deposit`` (``_volume_layout``): it takes a ``work`` of at least
    N × this (more is not used)."""
    return _volume_layout(radius, dx, dy, dz, nx, ny, nz, px, py, pz)[1]


@njit(cache=True)
def _volume_range(lo, hi, position, radius, scale, dx, dy, dz, nx, ny, nz, px, py, pz, nodes, stride, work):
    """The per-particle pass of ``volume_deposit`` for p in [lo, hi), into work[p stride:(p + 1) stride]: the
    ``corner_volume`` of each node (mx, my, mz) (``_node``) of the na × nb × nc nodes of the cells the sphere
    overlaps at (mx nb + my) nc + mz (0 without a call where the node lies beyond the sphere along an axis,
    which is what ``corner_volume`` returns there), then at ``nodes`` the number of cells with V_pc > 0 and
    (i, j, k, scale[p] V_pc) of each, i, j, k wrapped: V_pc the Σ ± of its eight corners in the order and with
    the signs of ``sphere_box_volume``. A sphere inside one cell has the one cell and its whole volume, one with
    at most one cell face inside it per axis the cells of ``_split_cells`` (no node values); one whose nodes do
    not fit has the count −1 (``_volume_add`` then takes ``sphere_box_volume``)."""
    for p in range(lo, hi):
        r = radius[p]
        x = position[p, 0]
        y = position[p, 1]
        z = position[p, 2]
        a0, a1 = _cell_range(x, r, dx, nx, px)
        b0, b1 = _cell_range(y, r, dy, ny, py)
        c0, c1 = _cell_range(z, r, dz, nz, pz)
        base = p * stride
        e = base + nodes
        if a0 == a1 and b0 == b1 and c0 == c1:  # inside one cell: its whole volume
            work[e] = 1.0
            work[e + 1] = a0 % nx
            work[e + 2] = b0 % ny
            work[e + 3] = c0 % nz
            work[e + 4] = scale[p] * 4.0 / 3.0 * math.pi * r * r * r
            continue
        na, nb, nc = a1 - a0 + 2, b1 - b0 + 2, c1 - c0 + 2
        if na * nb * nc > nodes:
            work[e] = -1.0
            continue
        # at most two cells per axis (a sphere under a cell across) whose first node lies at or beyond −r and
        # last at or beyond r (as they do but where round-off puts a node on the sphere): each axis has at most
        # one face inside the sphere, and the cells' volumes follow from the volumes beyond those faces
        # (``_split_cells``) without node values
        if (na <= 3 and nb <= 3 and nc <= 3 and _outside(a0, na, x, r, dx, nx, px)
                and _outside(b0, nb, y, r, dy, ny, py) and _outside(c0, nc, z, r, dz, nz, pz)):
            af = _node(a0, 1, dx, nx, px) - x if na == 3 else r
            bf = _node(b0, 1, dy, ny, py) - y if nb == 3 else r
            cf = _node(c0, 1, dz, nz, pz) - z if nc == 3 else r
            work[e] = _split_cells(af, bf, cf, na == 3, nb == 3, nc == 3, a0 % nx, b0 % ny, c0 % nz, (a0 + 1) % nx,
                                   (b0 + 1) % ny, (c0 + 1) % nz, r, scale[p], work, e + 1)
            continue
        for mi in range(na):
            a = _node(a0, mi, dx, nx, px) - x
            for mj in range(nb):
                b = _node(b0, mj, dy, ny, py) - y
                for mk in range(nc):
                    c = _node(c0, mk, dz, nz, pz) - z
                    v = 0.0
                    if a < r and b < r and c < r:
                        v = corner_volume(a, b, c, r)
                    work[base + (mi * nb + mj) * nc + mk] = v
        m = 0
        for i in range(a0, a1 + 1):
            for j in range(b0, b1 + 1):
                for k in range(c0, c1 + 1):
                    v = 0.0
                    for s in range(2):
                        for t in range(2):
                            row = base + ((i - a0 + s) * nb + j - b0 + t) * nc + k - c0
                            for u in range(2):
                                sign = 1.0 if (s + t + u) % 2 == 0 else -1.0
                                v += sign * work[row + u]
                    if v > 0.0:
                        v *= scale[p]
                        f = e + 1 + 4 * m
                        work[f] = i % nx
                        work[f + 1] = j % ny
                        work[f + 2] = k % nz
                        work[f + 3] = v
                        m += 1
        work[e] = m


@njit(cache=True, parallel=True)
def _volume_parallel(position, radius, scale, dx, dy, dz, nx, ny, nz, px, py, pz, nodes, stride, work):
    """``_volume_range`` over all particles in chunks of CHUNK on all threads."""
    n = position.shape[0]
    for c in prange((n + CHUNK - 1) // CHUNK):
        _volume_range(c * CHUNK, min(n, (c + 1) * CHUNK), position, radius, scale, dx, dy, dz, nx, ny, nz, px, py, pz,
                      nodes, stride, work)


@njit(cache=True, inline="always")
def slab_count(nx):
    """Number of x slabs of the parallel grid sums: one per thread (Numba's ``get_num_threads``), at most nx and
    at most 63 (a particle's slabs are the bits of one int64, ``slab_of``). Called only in kernels that call a
    ``parallel=True`` one too, which starts Numba's threads when it is loaded from the cache."""
    return max(1, min(_num_threads(), nx, 63))


@njit(cache=True, inline="always")
def slab_bounds(s, m, nx):
    """[lo, hi) of the x indices of slab s of m: cells and faces lo … hi − 1, the last slab with the face
    nx too (``hi`` = nx + 1), so that every cell and face index along x belongs to exactly one slab."""
    lo = (s * nx) // m
    hi = ((s + 1) * nx) // m
    if s == m - 1:
        hi = nx + 1
    return lo, hi


@njit(cache=True, inline="always")
def slab_of(i, m, nx):
    """The slab of ``slab_bounds`` (of m) that holds x index i (0 … nx): the largest s with (s nx) // m <= i."""
    return min(m - 1, ((i + 1) * m - 1) // nx)


@njit(cache=True)
def slab_bits(m, nx):
    """(nx + 1,) int64: 1 << the slab (of m, ``slab_of``) of each x index 0 … nx."""
    bit = np.empty(nx + 1, np.int64)
    for i in range(nx + 1):
        bit[i] = np.int64(1) << slab_of(i, m, nx)
    return bit


@njit(cache=True)
def _volume_slabs(lo, hi, position, radius, dx, nx, px, bit, slabs, centres):
    """slabs[p] for p in [lo, hi): the bits ``bit[i]`` (``slab_bits``) of the wrapped x indices of the cells of
    ``_cell_range``, which ``_volume_range`` and ``_volume_add`` take for the sphere of p, OR-ed; with
    ``centres`` that of the cell holding its centre (``cell_index``) too."""
    for p in range(lo, hi):
        a0, a1 = _cell_range(position[p, 0], radius[p], dx, nx, px)
        if a1 - a0 + 1 >= nx:
            a0, a1 = 0, nx - 1
        b = np.int64(0)
        for i in range(a0, a1 + 1):
            b |= bit[i % nx]
        if centres:
            b |= bit[cell_index(position[p, 0], 1.0 / dx, nx)]
        slabs[p] = b


@njit(cache=True)
def _volume_add(lo, hi, own, slabs, position, radius, scale, velocity, dx, dy, dz, px, py, pz, nodes, stride, work,
                out, ovx, ovy, ovz, cn, cvx, cvy, cvz):
    """The sums of ``volume_deposit`` onto the cells whose (wrapped) x index lies in [lo, hi), slab ``own`` (its
    bit) of the particles' slabs ``slabs`` (``_volume_slabs``): the cells of ``_volume_range`` added in particle
    order (a sphere with the count −1 by ``sphere_box_volume`` of each cell, as the deposit was before node
    values); a sphere none of whose cells lies in the slab is skipped, one whose cells all lie in it adds them
    without a test. ``slabs`` of size 0: the whole serial pass. ovx, ovy, ovz of size 0: the volumes only.
    cn, cvx, cvy, cvz not of size 0: ``centroid_deposit3d`` with weight 1 into them in the same pass (1 and v[p]
    to the cell holding the centre, ``cell_index``; the slabs then hold that cell's too)."""
    nx, ny, nz = out.shape
    every = slabs.shape[0] == 0
    weigh = ovx.shape[0] > 0  # the velocity sums too
    count = cn.shape[0] > 0  # the number-weighted sums by centres too
    for p in range(position.shape[0]):
        whole = every
        if not every:
            b = slabs[p]
            if b & own == 0:
                continue  # none of its cells in the slab: its scratch is not read
            whole = b == own
        e = p * stride + nodes
        m = int(work[e])
        vx = velocity[p, 0]
        vy = velocity[p, 1]
        vz = velocity[p, 2]
        if count:
            i = cell_index(position[p, 0], 1.0 / dx, nx)
            if whole or lo <= i < hi:
                j = cell_index(position[p, 1], 1.0 / dy, ny)
                k = cell_index(position[p, 2], 1.0 / dz, nz)
                cn[i, j, k] += 1.0
                cvx[i, j, k] += vx
                cvy[i, j, k] += vy
                cvz[i, j, k] += vz
        if m >= 0:
            for q in range(m):
                f = e + 1 + 4 * q
                i = int(work[f])
                if not whole and (i < lo or i >= hi):
                    continue
                j = int(work[f + 1])
                k = int(work[f + 2])
                v = work[f + 3]
                out[i, j, k] += v
                if weigh:
                    ovx[i, j, k] += v * vx
                    ovy[i, j, k] += v * vy
                    ovz[i, j, k] += v * vz
            continue
        r = radius[p]
        x = position[p, 0]
        y = position[p, 1]
        z = position[p, 2]
        a0, a1 = _cell_range(x, r, dx, nx, px)
        b0, b1 = _cell_range(y, r, dy, ny, py)
        c0, c1 = _cell_range(z, r, dz, nz, pz)
        for i in range(a0, a1 + 1):
            ii = i % nx
            if not whole and (ii < lo or ii >= hi):
                continue
            xl, xh = _bounds(i, dx, nx, px)
            for j in range(b0, b1 + 1):
                yl, yh = _bounds(j, dy, ny, py)
                for k in range(c0, c1 + 1):
                    zl, zh = _bounds(k, dz, nz, pz)
                    v = sphere_box_volume(x, y, z, r, xl, xh, yl, yh, zl, zh)
                    if v > 0.0:
                        v *= scale[p]
                        jj, kk = j % ny, k % nz
                        out[ii, jj, kk] += v
                        if weigh:
                            ovx[ii, jj, kk] += v * vx
                            ovy[ii, jj, kk] += v * vy
                            ovz[ii, jj, kk] += v * vz


@njit(cache=True, parallel=True)
def _volume_add_parallel(position, radius, scale, velocity, dx, dy, dz, px, py, pz, nodes, stride, work, out, ovx,
                         ovy, ovz, cn, cvx, cvy, cvz):
    """``_volume_add`` of each x slab (``slab_count``, ``slab_bounds``) on all threads, after each sphere's slabs
    (``_volume_slabs``, in chunks of ``CHUNK``)."""
    nx = out.shape[0]
    m = slab_count(nx)
    n = position.shape[0]
    bit = slab_bits(m, nx)
    slabs = np.empty(n, np.int64)
    centres = cn.shape[0] > 0
    for c in prange((n + CHUNK - 1) // CHUNK):
        _volume_slabs(c * CHUNK, min(n, (c + 1) * CHUNK), position, radius, dx, nx, px, bit, slabs, centres)
    for s in prange(m):
        lo, hi = slab_bounds(s, m, nx)
        _volume_add(lo, hi, bit[lo], slabs, position, radius, scale, velocity, dx, dy, dz, px, py, pz, nodes, stride,
                    work, out, ovx, ovy, ovz, cn, cvx, cvy, cvz)


@njit(cache=True)
def volume_deposit(position, radius, scale, velocity, dx, dy, dz, px, py, pz, out, ovx, ovy, ovz, work=None):
    """Add scale[p] V_pc (and scale[p] V_pc v[p]) to every cell c that the sphere of p overlaps, V_pc the exact
    volume of the sphere in the cell (``sphere_box_volume`` to round-off, by the roads of the module docstring; periodic axes wrapped, non-periodic edge cells unbounded). position, velocity : (N, 3);
    radius, scale : (N,); out, ovx, ovy, ovz : (nx, ny, nz), accumulated into (ovx, ovy, ovz of size 0, e.g.
    (0, 0, 0): the volumes only). work : (≥ N ``volume_stride``,)
    float64 scratch (allocated here if None or shorter)."""
    none = np.empty((0, 0, 0))
    _volume_deposit(position, radius, scale, velocity, dx, dy, dz, px, py, pz, out, ovx, ovy, ovz, none, none, none,
                    none, work)


@njit(cache=True)
def _volume_deposit(position, radius, scale, velocity, dx, dy, dz, px, py, pz, out, ovx, ovy, ovz, cn, cvx, cvy, cvz,
                    work):
    """``volume_deposit``, and with cn, cvx, cvy, cvz not of size 0 the sums of ``centroid_deposit3d`` with
    weight 1 into them in the same pass over the particles (bitwise those of a separate call)."""
    nx, ny, nz = out.shape
    n = position.shape[0]
    nodes, stride = _volume_layout(radius, dx, dy, dz, nx, ny, nz, px, py, pz)
    if work is None:
        buf = np.empty(n * stride)
    elif work.shape[0] < n * stride:
        buf = np.empty(n * stride)
    else:
        buf = work
    if n > CHUNK:
        _volume_parallel(position, radius, scale, dx, dy, dz, nx, ny, nz, px, py, pz, nodes, stride, buf)
    else:
        _volume_range(np.int64(0), n, position, radius, scale, dx, dy, dz, nx, ny, nz, px, py, pz, nodes, stride, buf)
    if n > CHUNK and slab_count(nx) > 1:
        _volume_add_parallel(position, radius, scale, velocity, dx, dy, dz, px, py, pz, nodes, stride, buf, out, ovx,
                             ovy, ovz, cn, cvx, cvy, cvz)
    else:
        _volume_add(np.int64(0), nx, np.int64(1), np.empty(0, np.int64), position, radius, scale, velocity, dx, dy, dz,
                    px, py, pz, nodes, stride, buf, out, ovx, ovy, ovz, cn, cvx, cvy, cvz)


@njit(cache=True)
def _centroid_range(lo, hi, position, dx, dy, dz, nx, ny, nz, cells):
    """cells[p] = (i ny + j) nz + k, the cell holding the centre of p (``cell_index``), for p in [lo, hi); stored
    as float64, exact below 2^53."""
    for p in range(lo, hi):
        i = cell_index(position[p, 0], 1.0 / dx, nx)
        j = cell_index(position[p, 1], 1.0 / dy, ny)
        k = cell_index(position[p, 2], 1.0 / dz, nz)
        cells[p] = (i * ny + j) * nz + k


@njit(cache=True, parallel=True)
def _centroid_parallel(position, dx, dy, dz, nx, ny, nz, cells):
    """``_centroid_range`` over all particles in chunks of CHUNK on all threads."""
    n = position.shape[0]
    for c in prange((n + CHUNK - 1) // CHUNK):
        _centroid_range(c * CHUNK, min(n, (c + 1) * CHUNK), position, dx, dy, dz, nx, ny, nz, cells)


@njit(cache=True)
def _centroid_add(lo, hi, n, weight, velocity, cells, out, ovx, ovy, ovz):
    """The sums of ``centroid_deposit3d`` onto the cells whose x index lies in [lo, hi), in particle order
    (cells of ``_centroid_range``) of the particles 0 … n − 1; [0, nx) is the whole serial pass."""
    nx, ny, nz = out.shape
    nyz = ny * nz
    first = lo * nyz
    last = min(hi, nx) * nyz
    for p in range(n):
        c = int(cells[p])
        if c < first or c >= last:
            continue
        i = c // nyz
        j = (c - i * nyz) // nz
        k = c - i * nyz - j * nz
        w = weight[p]
        out[i, j, k] += w
        ovx[i, j, k] += w * velocity[p, 0]
        ovy[i, j, k] += w * velocity[p, 1]
        ovz[i, j, k] += w * velocity[p, 2]


@njit(cache=True, parallel=True)
def _centroid_add_parallel(n, weight, velocity, cells, out, ovx, ovy, ovz):
    """``_centroid_add`` of each x slab (``slab_count``, ``slab_bounds``) on all threads."""
    nx = out.shape[0]
    m = slab_count(nx)
    for s in prange(m):
        lo, hi = slab_bounds(s, m, nx)
        _centroid_add(lo, hi, n, weight, velocity, cells, out, ovx, ovy, ovz)


@njit(cache=True)
def centroid_deposit3d(position, weight, velocity, dx, dy, dz, out, ovx, ovy, ovz, work=None):
    """Add weight[p] (and weight[p] v[p]) to the cell holding the centre of particle p (Sun 2007 eq. 34 in 3D);
    centres outside count in the nearest edge cell. out, ovx, ovy, ovz : (nx, ny, nz), accumulated into.
    work : (≥ N,) float64 scratch for the cells of the centres (allocated here if None or shorter)."""
    nx, ny, nz = out.shape
    n = position.shape[0]
    if work is None:
        cells = np.empty(n)
    elif work.shape[0] < n:
        cells = np.empty(n)
    else:
        cells = work
    if n > CHUNK:
        _centroid_parallel(position, dx, dy, dz, nx, ny, nz, cells)
    else:
        _centroid_range(np.int64(0), n, position, dx, dy, dz, nx, ny, nz, cells)
    if n > CHUNK and slab_count(nx) > 1:
        _centroid_add_parallel(n, weight, velocity, cells, out, ovx, ovy, ovz)
    else:
        _centroid_add(np.int64(0), nx, n, weight, velocity, cells, out, ovx, ovy, ovz)


@njit(cache=True)
def diffuse3d(field, rx, ry, rz, px, py, pz, steps, work):
    """``steps`` explicit diffusion steps f += rx δ²_x f + ry δ²_y f + rz δ²_z f, with zero flux through the
    sides of a non-periodic axis and wrapped neighbours on a periodic one. Conserves Σ f to round-off;
    stable for rx + ry + rz ≤ 1/2. field, work : (nx, ny, nz)."""
    nx, ny, nz = field.shape
    for _ in range(steps):
        for i in range(nx):
            for j in range(ny):
                for k in range(nz):
                    f = field[i, j, k]
                    lap_x = 0.0
                    if i > 0 or (px and nx > 1):
                        lap_x += field[(i - 1) % nx, j, k] - f
                    if i < nx - 1 or (px and nx > 1):
                        lap_x += field[(i + 1) % nx, j, k] - f
                    lap_y = 0.0
                    if j > 0 or (py and ny > 1):
                        lap_y += field[i, (j - 1) % ny, k] - f
                    if j < ny - 1 or (py and ny > 1):
                        lap_y += field[i, (j + 1) % ny, k] - f
                    lap_z = 0.0
                    if k > 0 or (pz and nz > 1):
                        lap_z += field[i, j, (k - 1) % nz] - f
                    if k < nz - 1 or (pz and nz > 1):
                        lap_z += field[i, j, (k + 1) % nz] - f
                    work[i, j, k] = f + rx * lap_x + ry * lap_y + rz * lap_z
        field[:, :, :] = work


@njit(cache=True)
def deposit_solids3d(method, weighting, position, radius, volume, velocity, dx, dy, dz, px, py, pz, norm, frac,
                     wsum, wvx, wvy, wvz, work=None):
    """Solids fraction ``frac`` (unsmoothed) and the velocity weights ``wsum``, ``wv*`` of each cell of a 3D grid.

    method 0 (centroid): V_p into the cell of the centre (Sun 2007 eq. 34); 3 (volume): the exact volume of
    the sphere in every cell it overlaps (``volume_deposit``). ``frac`` is the deposit over ``norm`` (V_cell).
    weighting 0 (number): wsum counts centres, wv* sum their velocities (Hoomans 1996 eq. 50); 1 (volume):
    wsum is the deposit and wv* the deposit-weighted velocities (Sun 2007 eq. 35).
    position, velocity : (N, 3); radius, volume : (N,); the rest (nx, ny, nz), overwritten. work : float64
    scratch of the deposits (``volume_deposit``, ``centroid_deposit3d``), or None.
    """
    frac[:, :, :] = 0.0
    wvx[:, :, :] = 0.0
    wvy[:, :, :] = 0.0
    wvz[:, :, :] = 0.0
    n = position.shape[0]
    if method == 0:
        centroid_deposit3d(position, volume, velocity, dx, dy, dz, frac, wvx, wvy, wvz, work)  # Sun 2007 eq. 34
    elif weighting == 0:  # the velocity weights by centres (Hoomans 1996 eq. 50) in the same pass
        none = np.empty((0, 0, 0))
        wsum[:, :, :] = 0.0
        _volume_deposit(position, radius, np.ones(n), velocity, dx, dy, dz, px, py, pz, frac, none, none, none, wsum,
                        wvx, wvy, wvz, work)
        frac[:, :, :] /= norm
        return
    else:
        volume_deposit(position, radius, np.ones(n), velocity, dx, dy, dz, px, py, pz, frac, wvx, wvy, wvz, work)
    wsum[:, :, :] = frac
    frac[:, :, :] /= norm
    if weighting == 0:  # Hoomans 1996 eq. 50: by centres, each particle counts once
        wsum[:, :, :] = 0.0
        wvx[:, :, :] = 0.0
        wvy[:, :, :] = 0.0
        wvz[:, :, :] = 0.0
        centroid_deposit3d(position, np.ones(n), velocity, dx, dy, dz, wsum, wvx, wvy, wvz, work)


@njit(cache=True)
def map_solids3d(method, weighting, position, radius, volume, velocity, dx, dy, dz, px, py, pz, norm, rx, ry, rz,
                 steps, min_voidage, voidage, solids_u, solids_v, solids_w, work=None):
    """The particle → grid map of ``VoidageMapping.map`` on a 3D grid; returns the number of clipped cells.

    ``deposit_solids3d``; then ``steps`` diffusion steps of the fraction (``diffuse3d``; 0: none);
    ε = 1 − fraction, raised to min_voidage where below it (and counted); solids velocity wv/wsum, 0 where
    wsum = 0. voidage, solids_u, solids_v, solids_w : (nx, ny, nz) outputs. work : float64 scratch of the
    deposit, of at least N ``volume_stride`` (volume) or N (centroid) entries, or None (allocated here).
    """
    shape = voidage.shape
    frac = np.empty(shape)
    wsum = np.empty(shape)
    wvx = np.empty(shape)
    wvy = np.empty(shape)
    wvz = np.empty(shape)
    deposit_solids3d(method, weighting, position, radius, volume, velocity, dx, dy, dz, px, py, pz, norm, frac,
                     wsum, wvx, wvy, wvz, work)
    if steps > 0:
        diffuse3d(frac, rx, ry, rz, px, py, pz, steps, np.empty(shape))
    nx, ny, nz = shape
    clipped = 0
    for i in range(nx):
        for j in range(ny):
            for k in range(nz):
                e = 1.0 - frac[i, j, k]
                if e < min_voidage:
                    e = min_voidage
                    clipped += 1
                voidage[i, j, k] = e
                w = wsum[i, j, k]
                if w > 0.0:
                    solids_u[i, j, k] = wvx[i, j, k] / w
                    solids_v[i, j, k] = wvy[i, j, k] / w
                    solids_w[i, j, k] = wvz[i, j, k] / w
                else:
                    solids_u[i, j, k] = 0.0
                    solids_v[i, j, k] = 0.0
                    solids_w[i, j, k] = 0.0
    return clipped


@njit(cache=True)
def sauter_inverse3d(position, radius, volume, dx, dy, dz, out):
    """out[i, j, k] = 1/D̄ [1/m] of the particles whose centre lies in cell (i, j, k), Σ V_p/d_p / Σ V_p (DEM
    book 2012 two-phase chapter, eq. 10); cells without particles take the bed's value, which is returned."""
    nx, ny, nz = out.shape
    vol = np.zeros((nx, ny, nz))
    out[:, :, :] = 0.0
    total = 0.0
    total_v = 0.0
    for p in range(position.shape[0]):
        i = cell_index(position[p, 0], 1.0 / dx, nx)
        j = cell_index(position[p, 1], 1.0 / dy, ny)
        k = cell_index(position[p, 2], 1.0 / dz, nz)
        w = volume[p] / (2.0 * radius[p])
        out[i, j, k] += w
        vol[i, j, k] += volume[p]
        total += w
        total_v += volume[p]
    bed = total / total_v if total_v > 0.0 else 0.0
    for i in range(nx):
        for j in range(ny):
            for k in range(nz):
                out[i, j, k] = out[i, j, k] / vol[i, j, k] if vol[i, j, k] > 0.0 else bed
    return bed
