"""Compiled contacts of spheres with wall shapes: triangles, 2D segments and cylinders, rigidly moving.

A shape is a set of elements in its own body frame (the case's geometry at rest); its pose at time t is
a displacement d(t) and a rotation R(t) about an axis through a point c, so that a body point x_b sits at
x = c + R (x_b − c) + d in the world (``pose``). Contacts are found in the body frame: the particle centre
is taken there (x_b = c + Rᵀ (x − d − c)), the element's closest point and normal are found, and both are
turned back. ``shape_forces`` adds the contact forces into the soft-sphere engine's per-particle sums once
per step; the elements each particle can reach are listed at each Verlet-list rebuild (``near_elements``),
and each contact's tangential spring lives in a few history slots per particle keyed by element id.
A free body (motion kind FREE) keeps its own state in its motion row and moves by the reaction of its
contacts and gravity (``bodies_step``), with the particles' velocity-Verlet step.
"""
import math

import numpy as np
from numba import njit

from .contact._dispatch import contact_force_full
from .contact.base import N_SLOTS

assert N_SLOTS == 12, "_law_row reads 12 slots of a packed contact row"

# element kinds
TRIANGLE, SEGMENT, CYLINDER = 1, 2, 3
# feature of a closest point: a face (or a segment's or cylinder's interior), an edge, a vertex
FACE, EDGE, VERTEX = 0, 1, 2
# shape motion kinds (shapes.py builds the table; the first three are those of walls.py)
STATIC, CONSTANT_VELOCITY, OSCILLATING, ROTATION, TABLE, FREE = 0, 1, 2, 3, 4, 5
# columns of the (S, POSE_COLS) pose table: d (0:3), R row-major (3:12), d' (12:15), ω vector (15:18), c (18:21),
# rotation angle θ (21)
POSE_COLS = 22
MOTION_COLS = 16  # motion row before a TABLE's poses (5 numbers each: t, dx, dy, dz, θ)
# a FREE body's state, from MOTION_COLS on in its motion row (changed in place as it moves): displacement d of the
# centre of mass (0:3), its velocity v (3:6), unit quaternion q = (w, x, y, z) of the rotation R (6:10), angular
# momentum π in the principal axes (10:13), principal moments I_k (13:16), principal axes Q (16:25, row-major, the
# columns in the body frame), mass M (25), 1/0 per world axis free/fixed (26:29), rotation free 1/0 (29), force F
# (30:33) and torque T about the centre of mass (33:36) of the last step, d (36:39) and q (39:43) at the last near
# list, gravity g (43:46), planar 1/0 (46: a 2D body, torque about z only)
BODY_D, BODY_V, BODY_Q, BODY_PI, BODY_I, BODY_AXES, BODY_MASS = 0, 3, 6, 10, 13, 16, 25
BODY_FREE, BODY_ROTATES, BODY_F, BODY_T, BODY_DREF, BODY_QREF, BODY_G, BODY_PLANAR = 26, 29, 30, 33, 36, 39, 43, 46
BODY_COLS = 48
MAX_CANDIDATES = 16  # touching elements of one particle considered at one step (more: the nearest are kept)
# info counters (int64 array): 0 particles with near elements, 1 last reorder step seen, 2 near-list overflows,
# 3 history-slot overflows, 4 shape-list rebuilds, 5 list capacity K needed at the last rebuild, 6 lists to be made
# anew at the next call (set by the engine: a restore, a wider list), 7 free bodies
INFO_ACTIVE, INFO_REORDER, INFO_NEAR_OVERFLOW, INFO_SLOT_OVERFLOW, INFO_REBUILDS, INFO_NEEDED = 0, 1, 2, 3, 4, 5
INFO_FORCE_REBUILD = 6
INFO_BODIES = 7  # free bodies among the shapes (set up once)
# grid (float64): origin (0:3), cell size (3), skin (4) of the broad phase


# ---------------------------------------------------------------- geometry
@njit(cache=True, error_model="numpy")
def closest_on_triangle(px, py, pz, geom, e):
    """Closest point of triangle e (vertices geom[e, 0:3], 3:6, 6:9) to p, and its feature (FACE, EDGE,
    VERTEX): the Voronoi-region walk of Ericson, Real-Time Collision Detection (2005) §5.1.5."""
    ax, ay, az = geom[e, 0], geom[e, 1], geom[e, 2]
    bx, by, bz = geom[e, 3], geom[e, 4], geom[e, 5]
    cx, cy, cz = geom[e, 6], geom[e, 7], geom[e, 8]
    abx, aby, abz = bx - ax, by - ay, bz - az
    acx, acy, acz = cx - ax, cy - ay, cz - az
    apx, apy, apz = px - ax, py - ay, pz - az
    d1 = abx * apx + aby * apy + abz * apz
    d2 = acx * apx + acy * apy + acz * apz
    if d1 <= 0.0 and d2 <= 0.0:
        return ax, ay, az, VERTEX
    bpx, bpy, bpz = px - bx, py - by, pz - bz
    d3 = abx * bpx + aby * bpy + abz * bpz
    d4 = acx * bpx + acy * bpy + acz * bpz
    if d3 >= 0.0 and d4 <= d3:
        return bx, by, bz, VERTEX
    vc = d1 * d4 - d3 * d2
    if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
        v = d1 / (d1 - d3)
        return ax + v * abx, ay + v * aby, az + v * abz, EDGE
    cpx, cpy, cpz = px - cx, py - cy, pz - cz
    d5 = abx * cpx + aby * cpy + abz * cpz
    d6 = acx * cpx + acy * cpy + acz * cpz
    if d6 >= 0.0 and d5 <= d6:
        return cx, cy, cz, VERTEX
    vb = d5 * d2 - d1 * d6
    if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
        w = d2 / (d2 - d6)
        return ax + w * acx, ay + w * acy, az + w * acz, EDGE
    va = d3 * d6 - d5 * d4
    if va <= 0.0 and (d4 - d3) >= 0.0 and (d5 - d6) >= 0.0:
        w = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        return bx + w * (cx - bx), by + w * (cy - by), bz + w * (cz - bz), EDGE
    den = 1.0 / (va + vb + vc)
    v = vb * den
    w = vc * den
    return ax + abx * v + acx * w, ay + aby * v + acy * w, az + abz * v + acz * w, FACE


@njit(cache=True, error_model="numpy")
def closest_on_segment(px, py, pz, geom, e):
    """Closest point of the 2D segment e (ends geom[e, 0:2], 3:5; in the x-y plane) to p, at p's own z (a
    segment is a wall across the whole depth), and its feature (FACE inside, VERTEX at an end)."""
    ax, ay = geom[e, 0], geom[e, 1]
    dx, dy = geom[e, 3] - ax, geom[e, 4] - ay
    ll = dx * dx + dy * dy
    s = ((px - ax) * dx + (py - ay) * dy) / ll
    if s <= 0.0:
        return ax, ay, pz, VERTEX
    if s >= 1.0:
        return ax + dx, ay + dy, pz, VERTEX
    return ax + s * dx, ay + s * dy, pz, FACE


@njit(cache=True, error_model="numpy")
def closest_on_cylinder(px, py, pz, geom, e):
    """Closest point of the lateral surface of cylinder e to p: axis point c = geom[e, 0:3], unit axis
    u = 3:6, radius R = 6, length L = 7 (from c along u); its feature: FACE between the ends, EDGE on an end
    rim. On the axis itself (no radial direction) the point is taken along an axis-normal direction."""
    cx, cy, cz = geom[e, 0], geom[e, 1], geom[e, 2]
    ux, uy, uz = geom[e, 3], geom[e, 4], geom[e, 5]
    rad, length = geom[e, 6], geom[e, 7]
    wx, wy, wz = px - cx, py - cy, pz - cz
    s = wx * ux + wy * uy + wz * uz
    rx, ry, rz = wx - s * ux, wy - s * uy, wz - s * uz
    rho = math.sqrt(rx * rx + ry * ry + rz * rz)
    if rho == 0.0:  # any axis-normal direction
        if abs(ux) < 0.9:
            rx, ry, rz = 0.0, -uz, uy
        else:
            rx, ry, rz = uz, 0.0, -ux
        rho = math.sqrt(rx * rx + ry * ry + rz * rz)
    feature = FACE
    if s < 0.0:
        s = 0.0
        feature = EDGE
    elif s > length:
        s = length
        feature = EDGE
    f = rad / rho
    return cx + s * ux + f * rx, cy + s * uy + f * ry, cz + s * uz + f * rz, feature


@njit(cache=True, error_model="numpy")
def closest_point(kind, px, py, pz, geom, e):
    """Closest point (body frame) of element e of ``kind`` to p, and its feature."""
    if kind == TRIANGLE:
        return closest_on_triangle(px, py, pz, geom, e)
    if kind == SEGMENT:
        return closest_on_segment(px, py, pz, geom, e)
    return closest_on_cylinder(px, py, pz, geom, e)


@njit(cache=True, error_model="numpy")
def face_side(kind, px, py, pz, qx, qy, qz, geom, e):
    """Unit normal (body frame) from element e's closest point q toward p, and the signed gap along it.

    A triangle or segment is two-sided: n = (p − q)/|p − q|, and where p lies on the element itself its
    plane's normal. A cylinder's lateral surface has one side facing the particles (geom[e, 8] = +1: inside,
    −1: outside): on a face its normal points to that side and the gap is negative once the centre has
    crossed the surface; at a rim, (p − q)/|p − q|."""
    dx, dy, dz = px - qx, py - qy, pz - qz
    d = math.sqrt(dx * dx + dy * dy + dz * dz)
    if kind == CYLINDER:
        ux, uy, uz = geom[e, 3], geom[e, 4], geom[e, 5]
        s = (px - geom[e, 0]) * ux + (py - geom[e, 1]) * uy + (pz - geom[e, 2]) * uz
        if s >= 0.0 and s <= geom[e, 7]:
            # outward radial unit vector at q
            rx = qx - geom[e, 0] - s * ux
            ry = qy - geom[e, 1] - s * uy
            rz = qz - geom[e, 2] - s * uz
            inv = 1.0 / geom[e, 6]
            side = geom[e, 8]
            nx, ny, nz = -side * rx * inv, -side * ry * inv, -side * rz * inv
            return nx, ny, nz, dx * nx + dy * ny + dz * nz
    if d > 0.0:
        return dx / d, dy / d, dz / d, d
    if kind == TRIANGLE:
        ax, ay, az = geom[e, 0], geom[e, 1], geom[e, 2]
        ux, uy, uz = geom[e, 3] - ax, geom[e, 4] - ay, geom[e, 5] - az
        vx, vy, vz = geom[e, 6] - ax, geom[e, 7] - ay, geom[e, 8] - az
        nx, ny, nz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
    else:
        nx, ny, nz = -(geom[e, 4] - geom[e, 1]), geom[e, 3] - geom[e, 0], 0.0
    m = math.sqrt(nx * nx + ny * ny + nz * nz)
    return nx / m, ny / m, nz / m, 0.0


@njit(cache=True, error_model="numpy")
def element_distance(kind, px, py, pz, geom, e):
    """|p − q| with q the closest point of element e to p (body frame)."""
    qx, qy, qz, _ = closest_point(kind, px, py, pz, geom, e)
    return math.sqrt((px - qx) ** 2 + (py - qy) ** 2 + (pz - qz) ** 2)


# ---------------------------------------------------------------- motion
@njit(cache=True, error_model="numpy")
def _rotate_about(out, k, ux, uy, uz, th, w):
    """Rodrigues' rotation by θ about the unit axis u into pose row k, R = c I + s [u]x + (1 − c) u uᵀ, and
    the angular velocity vector w u."""
    c = math.cos(th)
    s = math.sin(th)
    C = 1.0 - c
    out[k, 3] = c + ux * ux * C
    out[k, 4] = ux * uy * C - uz * s
    out[k, 5] = ux * uz * C + uy * s
    out[k, 6] = uy * ux * C + uz * s
    out[k, 7] = c + uy * uy * C
    out[k, 8] = uy * uz * C - ux * s
    out[k, 9] = uz * ux * C - uy * s
    out[k, 10] = uz * uy * C + ux * s
    out[k, 11] = c + uz * uz * C
    out[k, 15] = w * ux
    out[k, 16] = w * uy
    out[k, 17] = w * uz
    out[k, 21] = th


@njit(cache=True, error_model="numpy")
def pose(motion, t, out):
    """Fill out (S, POSE_COLS) with each shape's pose at time t from its motion row
    (kind, v or A (1:4), f [Hz] (4), φ (5), c (6:9), unit axis u (9:12), ω [rad/s] (12), poses in the table
    (13), then the table's rows t, dx, dy, dz, θ from MOTION_COLS on):
    constant velocity d = v t; oscillation d = A sin(2π f t + φ), d' = 2π f A cos(2π f t + φ); rotation
    R = Rodrigues' rotation by θ = ω t about u through c, surface velocity ω u × (x − c); table: d and θ
    interpolated linearly between the rows (velocities constant between them), held before the first
    and after the last (at rest); a free body: its own state (``body_pose``, t not used)."""
    for k in range(motion.shape[0]):
        kind = int(motion[k, 0])
        for j in range(POSE_COLS):
            out[k, j] = 0.0
        out[k, 3] = 1.0
        out[k, 7] = 1.0
        out[k, 11] = 1.0
        out[k, 18] = motion[k, 6]
        out[k, 19] = motion[k, 7]
        out[k, 20] = motion[k, 8]
        if kind == CONSTANT_VELOCITY:
            for j in range(3):
                out[k, j] = motion[k, 1 + j] * t
                out[k, 12 + j] = motion[k, 1 + j]
        elif kind == OSCILLATING:
            om = 2.0 * math.pi * motion[k, 4]
            s = math.sin(om * t + motion[k, 5])
            c = math.cos(om * t + motion[k, 5]) * om
            for j in range(3):
                out[k, j] = motion[k, 1 + j] * s
                out[k, 12 + j] = motion[k, 1 + j] * c
        elif kind == ROTATION:
            w = motion[k, 12]
            _rotate_about(out, k, motion[k, 9], motion[k, 10], motion[k, 11], w * t, w)
        elif kind == TABLE:
            nt = int(motion[k, 13])
            b = MOTION_COLS
            last = b + 5 * (nt - 1)
            if nt == 1 or t <= motion[k, b]:
                lo, f, rate = b, 0.0, 0.0
            elif t >= motion[k, last]:
                lo, f, rate = last - 5, 1.0, 0.0
            else:  # the row with t_lo <= t < t_lo+1 (bisection)
                i0, i1 = 0, nt - 1
                while i1 - i0 > 1:
                    mid = (i0 + i1) // 2
                    if motion[k, b + 5 * mid] <= t:
                        i0 = mid
                    else:
                        i1 = mid
                lo = b + 5 * i0
                span = motion[k, lo + 5] - motion[k, lo]
                f = (t - motion[k, lo]) / span
                rate = 1.0 / span
            hi = lo + 5 if nt > 1 else lo
            for j in range(3):
                out[k, j] = (1.0 - f) * motion[k, lo + 1 + j] + f * motion[k, hi + 1 + j]
                out[k, 12 + j] = (motion[k, hi + 1 + j] - motion[k, lo + 1 + j]) * rate
            th = (1.0 - f) * motion[k, lo + 4] + f * motion[k, hi + 4]
            _rotate_about(out, k, motion[k, 9], motion[k, 10], motion[k, 11], th,
                          (motion[k, hi + 4] - motion[k, lo + 4]) * rate)
        elif kind == FREE:
            body_pose(motion, k, out)


@njit(cache=True, error_model="numpy", inline="always")
def to_body(P, k, x, y, z):
    """World point → body frame of shape k: c + Rᵀ (x − d − c)."""
    wx = x - P[k, 0] - P[k, 18]
    wy = y - P[k, 1] - P[k, 19]
    wz = z - P[k, 2] - P[k, 20]
    return (P[k, 18] + P[k, 3] * wx + P[k, 6] * wy + P[k, 9] * wz,
            P[k, 19] + P[k, 4] * wx + P[k, 7] * wy + P[k, 10] * wz,
            P[k, 20] + P[k, 5] * wx + P[k, 8] * wy + P[k, 11] * wz)


@njit(cache=True, error_model="numpy", inline="always")
def to_world(P, k, x, y, z):
    """Body point of shape k → world: c + R (x − c) + d."""
    wx = x - P[k, 18]
    wy = y - P[k, 19]
    wz = z - P[k, 20]
    return (P[k, 18] + P[k, 0] + P[k, 3] * wx + P[k, 4] * wy + P[k, 5] * wz,
            P[k, 19] + P[k, 1] + P[k, 6] * wx + P[k, 7] * wy + P[k, 8] * wz,
            P[k, 20] + P[k, 2] + P[k, 9] * wx + P[k, 10] * wy + P[k, 11] * wz)


@njit(cache=True, error_model="numpy", inline="always")
def rotate(P, k, x, y, z):
    """Body direction of shape k → world direction: R v."""
    return (P[k, 3] * x + P[k, 4] * y + P[k, 5] * z, P[k, 6] * x + P[k, 7] * y + P[k, 8] * z,
            P[k, 9] * x + P[k, 10] * y + P[k, 11] * z)


@njit(cache=True, error_model="numpy")
def moved_since(motion, reach, t0, t):
    """Upper bound over the shapes of how far a point of a shape moved between t0 and t [m]: |d(t) − d(t0)|
    plus |θ(t) − θ(t0)| times the shape's largest distance from its rotation axis point (``reach``); a free
    body: since its pose at the last near list (``body_moved``)."""
    moving = False
    for k in range(motion.shape[0]):
        moving |= int(motion[k, 0]) != STATIC
    if not moving:
        return 0.0
    p0 = np.empty((motion.shape[0], POSE_COLS))
    p1 = np.empty((motion.shape[0], POSE_COLS))
    pose(motion, t0, p0)
    pose(motion, t, p1)
    worst = 0.0
    for k in range(motion.shape[0]):
        if int(motion[k, 0]) == STATIC:
            continue
        if int(motion[k, 0]) == FREE:  # its own pose against that at the last near list
            worst = max(worst, body_moved(motion, k, reach[k]))
            continue
        dd = math.sqrt((p1[k, 0] - p0[k, 0]) ** 2 + (p1[k, 1] - p0[k, 1]) ** 2 + (p1[k, 2] - p0[k, 2]) ** 2)
        dd += abs(p1[k, 21] - p0[k, 21]) * reach[k]
        worst = max(worst, dd)
    return worst


# ---------------------------------------------------------------- broad phase
@njit(cache=True, error_model="numpy")
def bin_elements(box, lo, h, dims):
    """CSR (cell_start, cell_elems) of the elements whose (inflated) bounding box ``box`` (E, 6: lo, hi,
    body frame) overlaps each cell of the uniform grid (origin lo, cell size h, dims cells), cell index
    (ix * dims[1] + iy) * dims[2] + iz."""
    ncell = dims[0] * dims[1] * dims[2]
    count = np.zeros(ncell + 1, dtype=np.int64)
    for pass_ in range(2):
        if pass_ == 1:
            for c in range(ncell):
                count[c + 1] += count[c]
            elems = np.empty(count[ncell], dtype=np.int64)
            fill = count[:ncell].copy()
        for e in range(box.shape[0]):
            i0 = np.empty(3, dtype=np.int64)
            i1 = np.empty(3, dtype=np.int64)
            for d in range(3):
                i0[d] = min(max(int(math.floor((box[e, d] - lo[d]) / h)), 0), dims[d] - 1)
                i1[d] = min(max(int(math.floor((box[e, 3 + d] - lo[d]) / h)), 0), dims[d] - 1)
            for ix in range(i0[0], i1[0] + 1):
                for iy in range(i0[1], i1[1] + 1):
                    for iz in range(i0[2], i1[2] + 1):
                        c = (ix * dims[1] + iy) * dims[2] + iz
                        if pass_ == 0:
                            count[c + 1] += 1
                        else:
                            elems[fill[c]] = e
                            fill[c] += 1
    return count, elems


@njit(cache=True, error_model="numpy")
def near_elements(pos, radius, skin, kind, owner, geom, P, grid, dims, cell_start, cell_elems, near_count,
                  near_elem, active, info):
    """List, per particle, the elements within a + skin of its centre (``near_elem[i, :near_count[i]]``,
    ascending element id) and the particles that have any (``active[:info[INFO_ACTIVE]]``).

    Between two lists no particle moves more than skin/2 and no shape point more than skin/2 (``advance``
    and ``shape_forces`` rebuild the lists before either happens), so an element farther than a + skin cannot
    be touched before the next list. Candidates come from the cell of the particle's centre (in each shape's
    body frame) in the grid of element boxes inflated by the largest a + skin (``bin_elements``); a row with
    more than K = near_elem.shape[1] elements keeps its K nearest and counts an overflow (the engine then
    widens the table)."""
    n = pos.shape[0]
    ns = P.shape[0]
    K = near_elem.shape[1]
    nact = 0
    needed = 0
    lo0, lo1, lo2, h = grid[0], grid[1], grid[2], grid[3]
    dist = np.empty(K)
    for i in range(n):
        c = 0
        a = radius[i]
        for k in range(ns):
            bx, by, bz = to_body(P, k, pos[i, 0], pos[i, 1], pos[i, 2])
            # an axis of one cell takes every coordinate (2D: the segments span the depth)
            ix = int(math.floor((bx - lo0) / h)) if dims[0] > 1 else 0
            iy = int(math.floor((by - lo1) / h)) if dims[1] > 1 else 0
            iz = int(math.floor((bz - lo2) / h)) if dims[2] > 1 else 0
            if ix < 0 or iy < 0 or iz < 0 or ix >= dims[0] or iy >= dims[1] or iz >= dims[2]:
                continue
            cell = (ix * dims[1] + iy) * dims[2] + iz
            for m in range(cell_start[cell], cell_start[cell + 1]):
                e = cell_elems[m]
                if owner[e] != k:
                    continue
                d = element_distance(kind[e], bx, by, bz, geom, e)
                if d >= a + skin:
                    continue
                # keep the K nearest, in ascending distance
                if c < K:
                    j = c
                elif d < dist[K - 1]:
                    j = K - 1
                else:
                    c += 1
                    continue
                while j > 0 and dist[j - 1] > d:
                    dist[j] = dist[j - 1]
                    near_elem[i, j] = near_elem[i, j - 1]
                    j -= 1
                dist[j] = d
                near_elem[i, j] = e
                c += 1
        needed = max(needed, c)
        if c > K:
            info[INFO_NEAR_OVERFLOW] += 1
            c = K
        # ascending element id within the row (the order contacts are taken in)
        near_elem[i, :c] = np.sort(near_elem[i, :c])
        near_count[i] = c
        if c > 0:
            active[nact] = i
            nact += 1
    info[INFO_ACTIVE] = nact
    info[INFO_NEEDED] = needed


# ---------------------------------------------------------------- forces
@njit(cache=True, error_model="numpy", inline="always")
def _law_row(table, a, b):
    return (table[a, b, 0], table[a, b, 1], table[a, b, 2], table[a, b, 3], table[a, b, 4], table[a, b, 5],
            table[a, b, 6], table[a, b, 7], table[a, b, 8], table[a, b, 9], table[a, b, 10], table[a, b, 11])


@njit(cache=True, error_model="numpy")
def particle_contacts(i, pos, radius, kind, owner, geom, P, near_count, near_elem, cand_e, cand_f, keep):
    """The contacts of particle i with its near elements, each feature once: returns m and fills cand_e[:m]
    (element ids) and cand_f[:m, :] (world closest point 0:3, world unit normal toward the particle 3:6,
    overlap 6, feature 7); ``keep`` (MAX_CANDIDATES,) bool is work space.

    A sphere on an edge or vertex shared by several elements finds the same closest point on each; as
    LIGGGHTS mesh walls do, contacts are taken face first, then edges, then vertices (deepest first within
    each), and an edge or vertex contact is dropped when its point q lies (within 1e-9 of the radius) on
    another touching element that is nearer (q is not that element's closest point: the sphere faces the
    element's interior, not q's edge) or already taken (the same point found again). The two triangles of a
    flat square give one contact on their shared edge, and on a finely meshed plane a sphere near a vertex
    feels the plane's one contact, not those of the edges around it; a sphere beyond a convex edge or
    vertex, which is every touching element's closest point, feels it once."""
    a = radius[i]
    m = 0
    for q in range(near_count[i]):
        e = near_elem[i, q]
        k = owner[e]
        bx, by, bz = to_body(P, k, pos[i, 0], pos[i, 1], pos[i, 2])
        qx, qy, qz, feat = closest_point(kind[e], bx, by, bz, geom, e)
        nx, ny, nz, gap = face_side(kind[e], bx, by, bz, qx, qy, qz, geom, e)
        overlap = a - gap
        if overlap <= 0.0:
            continue
        wx, wy, wz = to_world(P, k, qx, qy, qz)
        nx, ny, nz = rotate(P, k, nx, ny, nz)
        # insertion by (feature, −overlap): faces first, deeper first; the MAX_CANDIDATES first kept
        cap = cand_e.shape[0]
        if m < cap:
            j = m
            m += 1
        elif (cand_f[cap - 1, 7] > feat) or (cand_f[cap - 1, 7] == feat and cand_f[cap - 1, 6] < overlap):
            j = cap - 1
        else:
            continue
        while j > 0 and ((cand_f[j - 1, 7] > feat) or (cand_f[j - 1, 7] == feat and cand_f[j - 1, 6] < overlap)):
            cand_e[j] = cand_e[j - 1]
            for col in range(8):
                cand_f[j, col] = cand_f[j - 1, col]
            j -= 1
        cand_e[j] = e
        cand_f[j, 0] = wx
        cand_f[j, 1] = wy
        cand_f[j, 2] = wz
        cand_f[j, 3] = nx
        cand_f[j, 4] = ny
        cand_f[j, 5] = nz
        cand_f[j, 6] = overlap
        cand_f[j, 7] = feat
    # an edge or vertex contact at q is dropped where q lies on another touching element that either is
    # nearer (q is then not that element's closest point: the sphere faces its interior, not the edge) or
    # has been taken already (the same point found twice)
    tol = 1e-9 * a
    for c in range(m):
        keep[c] = True
        if cand_f[c, 7] == FACE:
            continue
        for j in range(m):
            if j == c:
                continue
            if not (cand_f[j, 6] > cand_f[c, 6] + tol or (j < c and keep[j])):
                continue
            e = cand_e[j]
            k = owner[e]
            bx, by, bz = to_body(P, k, cand_f[c, 0], cand_f[c, 1], cand_f[c, 2])
            if element_distance(kind[e], bx, by, bz, geom, e) <= tol:
                keep[c] = False
                break
    kept = 0
    for c in range(m):
        if keep[c]:
            cand_e[kept] = cand_e[c]
            for col in range(8):
                cand_f[kept, col] = cand_f[c, col]
            kept += 1
    return kept


@njit(cache=True, error_model="numpy")
def shape_forces(shapes, pos, ref_pos, vel, omega, radius, mass, species, ids, rebuilt, last_reorder, t, dt, update,
                 flat, sum_f, sum_c):
    """Add the shape contact forces into the per-particle sums (force in sum_f, −n × F_t per unit lever arm
    in sum_c, as for pairs and planes) at time t, and the reaction on each shape into its load row.

    ``shapes``: the tuple ``shapes.ShapeSet.kernel_arrays()`` makes (the skin in grid[4]). Nothing is done
    without elements.
    ``rebuilt``: the Verlet list was rebuilt at this step (the near lists are made anew, as when a shape
    moved more than skin/2 since the last ones), around ``ref_pos``, the positions of the last Verlet list
    (no particle is more than skin/2 from them until the next one). ``last_reorder``: the step of the last renumbering of the
    particles; when it changed, the per-particle arrays (slots, lists) follow the particles by their ids
    (−1: no renumbering to follow).
    ``update``: store the tangential springs (False: forces only). ``flat``: a flat 2D bed (z parts of
    sum_f, x and y of sum_c left alone). Each contact is a spring-dashpot contact of the registered law
    (``contact_force_full``) with the wall's surface velocity at the contact point,
    v_w = d' + ω × (x_c − c − d), in the relative velocity; the torque lever is the radius, as for planes.
    A contact's spring is kept in a history slot of the particle keyed by element id; a new contact takes
    over the slot of a contact of the same particle that ended at this step (a sphere rolling from one
    triangle onto its neighbour keeps its spring), else a free slot, and a slot is freed when its contact ends.
    """
    (kind, owner, geom, motion, reach, grid, dims, cell_start, cell_elems, table, near_count, near_elem, active,
     info, slot_elem, slot_hist, ids_seen, ref_t, load) = shapes
    if kind.shape[0] == 0:
        return
    n = pos.shape[0]
    ns = motion.shape[0]
    P = np.empty((ns, POSE_COLS))
    skin = grid[4]
    if info[INFO_FORCE_REBUILD] != 0:
        rebuilt = True
        info[INFO_FORCE_REBUILD] = 0
    if update and last_reorder >= 0 and last_reorder != info[INFO_REORDER]:
        _follow_ids(ids, ids_seen, slot_elem, slot_hist)
        info[INFO_REORDER] = last_reorder
        rebuilt = True
    if not rebuilt and moved_since(motion, reach, ref_t[0], t) > 0.5 * skin:
        rebuilt = True
    if rebuilt:
        pose(motion, t, P)
        near_elements(ref_pos, radius, skin, kind, owner, geom, P, grid, dims, cell_start, cell_elems, near_count,
                      near_elem, active, info)
        ref_t[0] = t
        body_mark(motion)
        info[INFO_REBUILDS] += 1
        if update:
            _free_unlisted(n, near_count, near_elem, slot_elem, slot_hist)
    else:
        pose(motion, t, P)
    for k in range(ns):
        for j in range(6):
            load[k, j] = 0.0
    cand_e = np.empty(MAX_CANDIDATES, dtype=np.int64)
    cand_f = np.empty((MAX_CANDIDATES, 8))
    H = slot_elem.shape[1]
    roll = slot_hist.shape[2] > 3  # an epsd law: the rolling spring torque in columns 3-5
    used = np.zeros(H, dtype=np.bool_)
    keep = np.zeros(MAX_CANDIDATES, dtype=np.bool_)
    slot_of = np.empty(MAX_CANDIDATES, dtype=np.int64)
    for q in range(info[INFO_ACTIVE]):
        i = active[q]
        m = particle_contacts(i, pos, radius, kind, owner, geom, P, near_count, near_elem, cand_e, cand_f, keep)
        if m == 0 and not update:
            continue
        a = radius[i]
        for h in range(H):
            used[h] = False
        # contacts that go on keep their slots
        for c in range(m):
            slot_of[c] = -1
            for h in range(H):
                if slot_elem[i, h] == cand_e[c]:
                    slot_of[c] = h
                    used[h] = True
                    break
        # a new contact takes over the slot of one that ended now, else a free one
        for c in range(m):
            if slot_of[c] >= 0:
                continue
            for h in range(H):
                if not used[h] and slot_elem[i, h] >= 0:
                    slot_of[c] = h
                    used[h] = True
                    break
            if slot_of[c] < 0:
                for h in range(H):
                    if not used[h] and slot_elem[i, h] < 0:
                        slot_of[c] = h
                        used[h] = True
                        break
            if slot_of[c] < 0 and update:
                info[INFO_SLOT_OVERFLOW] += 1
        if update:  # slots whose contact ended (and were not taken over) are freed
            for h in range(H):
                if not used[h] and slot_elem[i, h] >= 0:
                    slot_elem[i, h] = -1
                    for j in range(slot_hist.shape[2]):
                        slot_hist[i, h, j] = 0.0
        for c in range(m):
            e = cand_e[c]
            k = owner[e]
            cx, cy, cz = cand_f[c, 0], cand_f[c, 1], cand_f[c, 2]
            nx, ny, nz = cand_f[c, 3], cand_f[c, 4], cand_f[c, 5]
            overlap = cand_f[c, 6]
            # surface velocity of the shape at the contact point: d' + ω × (x_c − c − d)
            rx = cx - P[k, 18] - P[k, 0]
            ry = cy - P[k, 19] - P[k, 1]
            rz = cz - P[k, 20] - P[k, 2]
            wx, wy, wz = P[k, 15], P[k, 16], P[k, 17]
            vwx = P[k, 12] + wy * rz - wz * ry
            vwy = P[k, 13] + wz * rx - wx * rz
            vwz = P[k, 14] + wx * ry - wy * rx
            h = slot_of[c]
            h0 = slot_hist[i, h, 0] if h >= 0 else 0.0
            h1 = slot_hist[i, h, 1] if h >= 0 else 0.0
            h2 = slot_hist[i, h, 2] if h >= 0 else 0.0
            # an epsd law's rolling spring torque in columns 3-5 of the slot (the shape's spin is not
            # subtracted: the rolling resistance acts on ω_i, as at a plane wall)
            g0 = slot_hist[i, h, 3] if roll and h >= 0 else 0.0
            g1 = slot_hist[i, h, 4] if roll and h >= 0 else 0.0
            g2 = slot_hist[i, h, 5] if roll and h >= 0 else 0.0
            fn, ftx, fty, ftz, hx, hy, hz, _reach, mx, my, mz, gx, gy, gz = contact_force_full(
                _law_row(table, species[i], k), overlap, nx, ny, nz, vel[i, 0] - vwx, vel[i, 1] - vwy,
                vel[i, 2] - vwz, a * omega[i, 0], a * omega[i, 1], a * omega[i, 2], omega[i, 0], omega[i, 1],
                omega[i, 2], mass[i], a, 1.4 * mass[i] * a * a, dt, h0, h1, h2, g0, g1, g2, update)
            if update and h >= 0:
                slot_elem[i, h] = e
                slot_hist[i, h, 0] = hx
                slot_hist[i, h, 1] = hy
                slot_hist[i, h, 2] = hz
                if roll:
                    slot_hist[i, h, 3] = gx
                    slot_hist[i, h, 4] = gy
                    slot_hist[i, h, 5] = gz
            fx = fn * nx + ftx
            fy = fn * ny + fty
            fz = fn * nz + ftz
            sum_f[i, 0] += fx
            sum_f[i, 1] += fy
            sum_c[i, 2] -= nx * fty - ny * ftx - mz / a
            if not flat:
                sum_f[i, 2] += fz
                sum_c[i, 0] -= ny * ftz - nz * fty - mx / a
                sum_c[i, 1] -= nz * ftx - nx * ftz - my / a
            # the reaction on the shape, and its moment about the shape's reference point c + d
            load[k, 0] -= fx
            load[k, 1] -= fy
            load[k, 2] -= fz
            load[k, 3] -= ry * fz - rz * fy
            load[k, 4] -= rz * fx - rx * fz
            load[k, 5] -= rx * fy - ry * fx


@njit(cache=True, error_model="numpy", inline="always")
def shape_step(shapes, pos, ref_pos, vel, omega, radius, mass, species, ids, rebuilt, last_reorder, t, dt, update,
               flat, sum_f, sum_c):
    """``shape_forces`` where there are shapes: inlined into the stepping loop, so that a run without shapes
    pays a test per step, not a call that unpacks the shapes' arrays."""
    if shapes[0].shape[0] > 0:
        shape_forces(shapes, pos, ref_pos, vel, omega, radius, mass, species, ids, rebuilt, last_reorder, t, dt,
                     update, flat, sum_f, sum_c)


@njit(cache=True, error_model="numpy")
def _free_unlisted(n, near_count, near_elem, slot_elem, slot_hist):
    """Free the history slots whose element is no longer in the particle's near list (out of reach: the
    contact has ended)."""
    for i in range(n):
        for h in range(slot_elem.shape[1]):
            e = slot_elem[i, h]
            if e < 0:
                continue
            found = False
            for q in range(near_count[i]):
                if near_elem[i, q] == e:
                    found = True
                    break
            if not found:
                slot_elem[i, h] = -1
                for j in range(slot_hist.shape[2]):
                    slot_hist[i, h, j] = 0.0


@njit(cache=True, error_model="numpy")
def _follow_ids(ids, ids_seen, slot_elem, slot_hist):
    """After a renumbering of the particles: move each particle's history slots to its new row (matched by
    ``ids``, the particles' own numbers; ``ids_seen`` holds them as the rows were) and update ids_seen."""
    new_rows = np.argsort(ids)
    old_rows = np.argsort(ids_seen)
    old_elem = slot_elem.copy()
    old_hist = slot_hist.copy()
    for r in range(ids.shape[0]):
        slot_elem[new_rows[r], :] = old_elem[old_rows[r], :]
        slot_hist[new_rows[r], :, :] = old_hist[old_rows[r], :, :]
    ids_seen[:] = ids


@njit(cache=True, error_model="numpy")
def deepest_contacts(shapes, pos, radius, t, overlap, element):
    """Per particle, the largest overlap with a shape element at time t (0 where none touches) and that
    element (−1: none), over the near lists of the last ``shape_forces`` call (for the set-up check)."""
    (kind, owner, geom, motion, reach, grid, dims, cell_start, cell_elems, table, near_count, near_elem, active,
     info, slot_elem, slot_hist, ids_seen, ref_t, load) = shapes
    overlap[:] = 0.0
    element[:] = -1
    if kind.shape[0] == 0:
        return
    P = np.empty((motion.shape[0], POSE_COLS))
    pose(motion, t, P)
    cand_e = np.empty(MAX_CANDIDATES, dtype=np.int64)
    cand_f = np.empty((MAX_CANDIDATES, 8))
    keep = np.zeros(MAX_CANDIDATES, dtype=np.bool_)
    for q in range(info[INFO_ACTIVE]):
        i = active[q]
        m = particle_contacts(i, pos, radius, kind, owner, geom, P, near_count, near_elem, cand_e, cand_f, keep)
        for c in range(m):
            if cand_f[c, 6] > overlap[i]:
                overlap[i] = cand_f[c, 6]
                element[i] = cand_e[c]


# ---------------------------------------------------------------- free bodies (Newton–Euler)
@njit(cache=True, error_model="numpy", inline="always")
def _quat_matrix(w, x, y, z):
    """Rotation matrix (row-major, 9 values) of the unit quaternion (w, x, y, z): R v = q v q*."""
    return (1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - w * z), 2.0 * (x * z + w * y),
            2.0 * (x * y + w * z), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - w * x),
            2.0 * (x * z - w * y), 2.0 * (y * z + w * x), 1.0 - 2.0 * (x * x + y * y))


@njit(cache=True, error_model="numpy")
def body_pose(motion, k, out):
    """Pose row k of free body k from its state (``BODY_*`` columns of its motion row): d, R of its quaternion,
    d' = v, angular velocity ω = R Q diag(1/I_k) π (world), θ = the angle of R. The centre c (out[k, 18:21]) is
    its centre of mass at rest."""
    b = MOTION_COLS
    for j in range(3):
        out[k, j] = motion[k, b + BODY_D + j]
        out[k, 12 + j] = motion[k, b + BODY_V + j]
    q = b + BODY_Q
    w, x, y, z = motion[k, q], motion[k, q + 1], motion[k, q + 2], motion[k, q + 3]
    R = _quat_matrix(w, x, y, z)
    for j in range(9):
        out[k, 3 + j] = R[j]
    # body-frame angular velocity Q diag(1/I) π, then into the world
    a = b + BODY_AXES
    wp0 = motion[k, b + BODY_PI] / motion[k, b + BODY_I]
    wp1 = motion[k, b + BODY_PI + 1] / motion[k, b + BODY_I + 1]
    wp2 = motion[k, b + BODY_PI + 2] / motion[k, b + BODY_I + 2]
    wb0 = motion[k, a] * wp0 + motion[k, a + 1] * wp1 + motion[k, a + 2] * wp2
    wb1 = motion[k, a + 3] * wp0 + motion[k, a + 4] * wp1 + motion[k, a + 5] * wp2
    wb2 = motion[k, a + 6] * wp0 + motion[k, a + 7] * wp1 + motion[k, a + 8] * wp2
    out[k, 15] = R[0] * wb0 + R[1] * wb1 + R[2] * wb2
    out[k, 16] = R[3] * wb0 + R[4] * wb1 + R[5] * wb2
    out[k, 17] = R[6] * wb0 + R[7] * wb1 + R[8] * wb2
    out[k, 21] = 2.0 * math.atan2(math.sqrt(x * x + y * y + z * z), abs(w))


@njit(cache=True, error_model="numpy")
def body_moved(motion, k, reach):
    """How far a point of free body k may have moved since its last near list [m]: |d − d_ref| plus the angle
    of R_refᵀ R, 2 acos |q_ref · q|, times its reach."""
    b = MOTION_COLS
    dd = 0.0
    dot = 0.0
    for j in range(3):
        dd += (motion[k, b + BODY_D + j] - motion[k, b + BODY_DREF + j]) ** 2
    for j in range(4):
        dot += motion[k, b + BODY_Q + j] * motion[k, b + BODY_QREF + j]
    return math.sqrt(dd) + 2.0 * math.acos(min(abs(dot), 1.0)) * reach


@njit(cache=True, error_model="numpy")
def body_mark(motion):
    """Keep each free body's pose as that of the near lists made now (``body_moved``)."""
    if motion.shape[1] < MOTION_COLS + BODY_COLS:
        return
    b = MOTION_COLS
    for k in range(motion.shape[0]):
        if int(motion[k, 0]) == FREE:
            for j in range(3):
                motion[k, b + BODY_DREF + j] = motion[k, b + BODY_D + j]
            for j in range(4):
                motion[k, b + BODY_QREF + j] = motion[k, b + BODY_Q + j]


@njit(cache=True, error_model="numpy")
def body_loads(motion, load):
    """Each free body's force and torque for its kicks from the particles' reaction ``load`` (about its centre
    of mass): F = (load + M g) on its free axes, T = load's torque where it rotates (about z only when
    planar), both world frame (Wu & Guo 2012 eqs 10a-b without the gas term)."""
    b = MOTION_COLS
    for k in range(motion.shape[0]):
        if int(motion[k, 0]) != FREE:
            continue
        m = motion[k, b + BODY_MASS]
        for j in range(3):
            motion[k, b + BODY_F + j] = (load[k, j] + m * motion[k, b + BODY_G + j]) * motion[k, b + BODY_FREE + j]
            motion[k, b + BODY_T + j] = load[k, 3 + j] * motion[k, b + BODY_ROTATES]
        if motion[k, b + BODY_PLANAR] != 0.0:
            motion[k, b + BODY_T] = 0.0
            motion[k, b + BODY_T + 1] = 0.0


@njit(cache=True, error_model="numpy")
def body_kick(motion, k, half):
    """Half kick of free body k with its stored force and torque: v += F/M h, π += Qᵀ Rᵀ T h (the world torque
    turned into the principal axes)."""
    b = MOTION_COLS
    im = 1.0 / motion[k, b + BODY_MASS]
    for j in range(3):
        motion[k, b + BODY_V + j] += half * motion[k, b + BODY_F + j] * im
    if motion[k, b + BODY_ROTATES] == 0.0:
        return
    q = b + BODY_Q
    R = _quat_matrix(motion[k, q], motion[k, q + 1], motion[k, q + 2], motion[k, q + 3])
    tx, ty, tz = motion[k, b + BODY_T], motion[k, b + BODY_T + 1], motion[k, b + BODY_T + 2]
    bx = R[0] * tx + R[3] * ty + R[6] * tz
    by = R[1] * tx + R[4] * ty + R[7] * tz
    bz = R[2] * tx + R[5] * ty + R[8] * tz
    a = b + BODY_AXES
    for j in range(3):
        motion[k, b + BODY_PI + j] += half * (motion[k, a + j] * bx + motion[k, a + 3 + j] * by
                                              + motion[k, a + 6 + j] * bz)


@njit(cache=True, error_model="numpy")
def _free_rotor(motion, k, ax, h):
    """The exact flow over time h of the free rotor's part π_a² / (2 I_a): the body turns by φ = h π_a / I_a
    about its principal axis a, q ← q ⊗ (cos φ/2, sin φ/2 Q e_a), and π turns the other way in the principal
    frame, (π_i, π_j) ← (c π_i + s π_j, −s π_i + c π_j) with (a, i, j) cyclic (Miller et al. 2002, NO_SQUISH;
    dπ/dt = π × ω, Euler's equations without torque)."""
    b = MOTION_COLS
    phi = h * motion[k, b + BODY_PI + ax] / motion[k, b + BODY_I + ax]
    if phi == 0.0:
        return
    i = (ax + 1) % 3
    j = (ax + 2) % 3
    c = math.cos(phi)
    s = math.sin(phi)
    pi_i = motion[k, b + BODY_PI + i]
    pi_j = motion[k, b + BODY_PI + j]
    motion[k, b + BODY_PI + i] = c * pi_i + s * pi_j
    motion[k, b + BODY_PI + j] = -s * pi_i + c * pi_j
    ch = math.cos(0.5 * phi)
    sh = math.sin(0.5 * phi)
    a = b + BODY_AXES
    ux, uy, uz = sh * motion[k, a + ax], sh * motion[k, a + 3 + ax], sh * motion[k, a + 6 + ax]
    q = b + BODY_Q
    w, x, y, z = motion[k, q], motion[k, q + 1], motion[k, q + 2], motion[k, q + 3]
    motion[k, q] = w * ch - x * ux - y * uy - z * uz
    motion[k, q + 1] = w * ux + ch * x + y * uz - z * uy
    motion[k, q + 2] = w * uy + ch * y + z * ux - x * uz
    motion[k, q + 3] = w * uz + ch * z + x * uy - y * ux


@njit(cache=True, error_model="numpy")
def body_drift(motion, k, dt):
    """Drift of free body k: d += v dt, and the free rotor over dt split symmetrically into the exact rotations
    about the principal axes, 1 (dt/2), 2 (dt/2), 3 (dt), 2 (dt/2), 1 (dt/2) (Miller et al. 2002, symplectic
    and time-reversible; |L| is kept to round-off); q is normalised again."""
    b = MOTION_COLS
    for j in range(3):
        motion[k, b + BODY_D + j] += dt * motion[k, b + BODY_V + j]
    if motion[k, b + BODY_ROTATES] == 0.0:
        return
    half = 0.5 * dt
    _free_rotor(motion, k, 0, half)
    _free_rotor(motion, k, 1, half)
    _free_rotor(motion, k, 2, dt)
    _free_rotor(motion, k, 1, half)
    _free_rotor(motion, k, 0, half)
    q = b + BODY_Q
    norm = math.sqrt(motion[k, q] ** 2 + motion[k, q + 1] ** 2 + motion[k, q + 2] ** 2 + motion[k, q + 3] ** 2)
    for j in range(4):
        motion[k, q + j] /= norm


@njit(cache=True, error_model="numpy")
def bodies_kick_drift(shapes, dt):
    """The opening half kick and the drift of every free body (the start of an ``advance`` call, as
    ``_kick_drift`` for the particles)."""
    motion = shapes[3]
    for k in range(motion.shape[0]):
        if int(motion[k, 0]) == FREE:
            body_kick(motion, k, 0.5 * dt)
            body_drift(motion, k, dt)


@njit(cache=True, error_model="numpy")
def bodies_step(shapes, dt, mode):
    """After the forces of a step: each free body's force and torque (``body_loads``), its closing half kick,
    and (mode 2, as the particles' fused pass) the next step's opening half kick and drift. Velocity Verlet as
    for the particles (Wu & Guo 2012 eqs 10a-b: M dv/dt = Σ F_c + M g, I dω/dt = Σ T_c in the body frame)."""
    motion = shapes[3]
    load = shapes[18]
    body_loads(motion, load)
    for k in range(motion.shape[0]):
        if int(motion[k, 0]) == FREE:
            body_kick(motion, k, 0.5 * dt)
            if mode == 2:
                body_kick(motion, k, 0.5 * dt)
                body_drift(motion, k, dt)


@njit(cache=True, error_model="numpy", inline="always")
def has_bodies(shapes):
    """True if a shape is a free body (its motion row holds the body's state)."""
    return shapes[13][INFO_BODIES] > 0


@njit(cache=True, error_model="numpy")
def contact_census(shapes, pos, radius, t, count, overlap, element):
    """Per particle, its contacts with shape elements at time t (count (N,) int64, each feature once, as
    ``shape_forces`` feels them), the largest overlap [m] (0 where none touches) and that element (−1: none),
    over the near lists of the last ``shape_forces`` call (for the outputs: probes, run checks)."""
    (kind, owner, geom, motion, reach, grid, dims, cell_start, cell_elems, table, near_count, near_elem, active,
     info, slot_elem, slot_hist, ids_seen, ref_t, load) = shapes
    count[:] = 0
    overlap[:] = 0.0
    element[:] = -1
    if kind.shape[0] == 0:
        return
    P = np.empty((motion.shape[0], POSE_COLS))
    pose(motion, t, P)
    cand_e = np.empty(MAX_CANDIDATES, dtype=np.int64)
    cand_f = np.empty((MAX_CANDIDATES, 8))
    keep = np.zeros(MAX_CANDIDATES, dtype=np.bool_)
    for q in range(info[INFO_ACTIVE]):
        i = active[q]
        m = particle_contacts(i, pos, radius, kind, owner, geom, P, near_count, near_elem, cand_e, cand_f, keep)
        count[i] = m
        for c in range(m):
            if cand_f[c, 6] > overlap[i]:
                overlap[i] = cand_f[c, 6]
                element[i] = cand_e[c]
