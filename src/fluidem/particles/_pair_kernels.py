"""Compiled soft-sphere pair forces with the contact law vectorised over contacts (Sun 2007 eqs 17–24).

A scalar pair loop, one contact at a time (fluidem's until 2026-11-26), is slow for a reason
that has little to do with memory: its Hertz–Mindlin law is a chain of five square roots and
five divisions per contact, each waiting for the last, and the core cannot start the next
contact's chain before the current one retires: about 120 cycles a contact (10,000-sphere
bench bed, one thread; ``llvm-mca -mcpu=znver3``), though the divider alone needs 70 of them.
Here the same law runs over chunks of contacts laid out side by side, so that LLVM vectorises
it: four contacts per AVX2 instruction (a square root costs ~1 ns per contact instead of
~3), and the chains of four contacts in flight at once. The pairs of one slab go through
three passes:

1. ``_filter``: every listed pair of the slab's members is tested for contact
   (``r² < (a_i + a_j)²``, the scalar loop's test) and the touching ones are appended,
   without a branch, to a list (pair slot, owner). A contact that ended since the last
   step has its tangential spring reset here: ``touch`` holds each listed pair's state of
   the last step, so the spring array is read only for those (a rare, well-predicted branch).
2. per chunk of ``CHUNK`` contacts: ``_gather`` copies what the law reads of each contact
   (centre offset, radii, masses, relative velocity, a_i ω_i + a_j ω_j, spring, the contact
   law's parameters) into rows of one flat array ``G`` (row q of contact c at
   ``G[q * CHUNK + c]``); ``_law`` runs ``contact/_dispatch.contact_force`` (branch-free)
   over the chunk into ``out``; ``_scatter`` adds each force and torque to both particles'
   sums and stores the spring. Rows of one array at constant offsets let LLVM prove that
   ``G`` and ``out`` are two objects, with one run-time overlap check; separate arrays per
   quantity needed more checks than the vectoriser allows ("too many memory checks"), and
   one buffer for a whole slab (instead of chunks of 128) thrashed the L1 cache.

The law reads each contact's model code from its row of ``G`` like its parameters, so one
compiled law serves every model and any table of species pairs, models mixed or not:
``coefficients`` then computes each model's coefficients for all four contacts of an
instruction and keeps the one of each contact's model (the linear law costs one square
root). Flat 2D beds (``flat``, see ``_softsphere_kernels.is_flat``) leave the z terms out of
the filter, gather and scatter; the law computes them, as zeros (one law to compile, not two).
Measured in ``benchmarks/README.md``.

A table with rolling friction or an adhesive law (slots 8 and 10 of ``contact/base.py``; ``ext`` of
``make_work``) runs ``_law_ext`` instead: ``contact_force_full`` in scalar code, with the relative spin
gathered and the rolling torques and pull-off distances scattered. An adhesive law's contacts last
beyond touch: the fourth history column holds each formed contact's pull-off distance, which widens
``_filter``'s contact test for that pair until the pair parts beyond it (then the column is reset). A table
with the ``epsd`` rolling model keeps each contact's rolling spring torque in history columns 4-6 (relative
to the owner i, as the tangential spring), gathered and scattered with the rest.

Each particle's force sum receives its terms in the order of the slab's contact list
(slabs of one parity in parallel, then the other), whatever the number of threads: the
sums are bitwise independent of the thread count. They equal a contact-by-contact evaluation
of the law to round-off (tests/verification/test_pair_kernels.py).
"""
import math

import numpy as np
from numba import njit

from ._neighbours_kernels import nearest_image
from .contact._dispatch import contact_force, contact_force_full
from .contact.base import N_SLOTS, ROLLING_HISTORY, SLOT_EXTENDED, SLOT_ROLLING_FRICTION

U = np.uintp  # unsigned array index (see _softsphere_kernels)

CHUNK = 128  # contacts per chunk: the rows of G and out that _law reads and writes take 38 KB, about the L1 cache
# (chunks of 32 and 64 ran as fast)
# rows of G: what the law reads of a contact
G_RX, G_RY, G_RZ, G_AI, G_AJ, G_MI, G_MJ, G_VX, G_VY, G_VZ, G_OX, G_OY, G_OZ, G_HX, G_HY, G_HZ = range(16)
G_LAW = 16  # rows G_LAW … G_LAW + N_SLOTS − 1: the slots of the packed contact row (contact/base.py; slot 0 the code)
# extended law only (rolling resistance, adhesion): the relative spin ω_i − ω_j
G_SX, G_SY, G_SZ = G_LAW + N_SLOTS, G_LAW + N_SLOTS + 1, G_LAW + N_SLOTS + 2
# extended law with a rolling spring (history columns 4-6): its torque before the step
G_GX, G_GY, G_GZ = G_LAW + N_SLOTS + 3, G_LAW + N_SLOTS + 4, G_LAW + N_SLOTS + 5
N_G = G_LAW + N_SLOTS + 6
# rows of out: what the law gives
O_FX, O_FY, O_FZ, O_CX, O_CY, O_CZ, O_HX, O_HY, O_HZ = range(9)
# extended law only: the pull-off distance (history column 3) and the rolling torque per unit radius on i and on j
O_REACH, O_MIX, O_MIY, O_MIZ, O_MJX, O_MJY, O_MJZ = range(9, 16)
O_GX, O_GY, O_GZ = range(16, 19)  # the new rolling spring torque (history columns 4-6)
N_O = 19


@njit(cache=True, error_model="numpy")
def _uniform(pp):
    """True if every species pair has the same contact row (its parameters are then copied into G once)."""
    for a in range(pp.shape[0]):
        for b in range(pp.shape[1]):
            for k in range(pp.shape[2]):
                if pp[a, b, k] != pp[0, 0, k]:
                    return False
    return True


@njit(cache=True, error_model="numpy")
def make_work(pp, row_start, hist, slab_start, slab_members, nthreads):
    """Work arrays of the chunked pair forces for the current Verlet list, made at each ``advance`` call and
    list rebuild: (cbuf, ibuf, G, out, touch, uniform, ext).

    cbuf, ibuf (nthreads, M) uint32: a thread's contact list of one slab (pair slot, owner), M the most
    listed pairs of any slab; G (nthreads, N_G · CHUNK), out (nthreads, N_O · CHUNK): a thread's chunk;
    touch (P,) uint8: 1 where the pair's spring is set (it touched at the last evaluation: a spring is
    zero otherwise; with an adhesive law, also where its history column 3 marks a formed contact); uniform:
    one contact row for all species pairs, copied into every G here; ext: some row has rolling friction or an
    adhesive law (slots 8, 10), which selects the extended law (``_law_ext``). The z rows of G start at zero
    and stay so in a flat bed.
    """
    nslab = slab_start.shape[0] - 1
    most = 0
    for s in range(nslab):
        c = 0
        for m in range(slab_start[s], slab_start[s + 1]):
            i = slab_members[m]
            c += row_start[i + 1] - row_start[i]
        most = max(most, c)
    cbuf = np.empty((nthreads, max(most, 1)), dtype=np.uint32)
    ibuf = np.empty((nthreads, max(most, 1)), dtype=np.uint32)
    G = np.zeros((nthreads, N_G * CHUNK))
    out = np.empty((nthreads, N_O * CHUNK))
    npair = hist.shape[0]
    touch = np.empty(npair, dtype=np.uint8)
    for p in range(npair):
        touch[p] = (hist[p, 0] != 0.0) | (hist[p, 1] != 0.0) | (hist[p, 2] != 0.0)
    for e in range(3, hist.shape[1]):  # an adhesive law's pull-off distance, a rolling spring
        for p in range(npair):
            touch[p] |= hist[p, e] != 0.0
    uniform = _uniform(pp)
    ext = False
    for a in range(pp.shape[0]):
        for b in range(pp.shape[1]):
            ext |= (pp[a, b, SLOT_ROLLING_FRICTION] != 0.0) | (pp[a, b, SLOT_EXTENDED] != 0.0)
    if uniform:
        chunk = G.shape[1] // N_G  # CHUNK, as a run-time value: with the constant LLVM unrolled these loops whole
        for t in range(nthreads):  # (N_SLOTS × 128 stores), which took ~20 s to compile
            for q in range(N_SLOTS):
                v = pp[0, 0, q]
                for c in range(chunk):
                    G[t, (G_LAW + q) * chunk + c] = v
    return cbuf, ibuf, G, out, touch, uniform, ext


@njit(cache=True, error_model="numpy", inline="always")
def _filter(flat, per, period, s, pos, radius, row_start, partner, slab_start, slab_members, hist, touch, cbuf, ibuf):
    """The touching pairs of slab s into cbuf/ibuf (returns their number); springs of ended contacts reset.
    With a fourth history column (an adhesive law) a pair is in contact while r < a_i + a_j + hist[3]: its
    pull-off distance once formed, 0 before. ``per`` (a constant where inlined): a box with periodic sides,
    offsets by nearest image (``_neighbours_kernels.nearest_image``, ``period`` (3,) its lengths)."""
    wide = hist.shape[1] > 3
    us = U(s)
    k = U(0)
    for m in range(slab_start[us], slab_start[us + U(1)]):
        i = U(slab_members[U(m)])
        xi = pos[i, U(0)]
        yi = pos[i, U(1)]
        zi = 0.0 if flat else pos[i, U(2)]
        ai = radius[i]
        for p_ in range(row_start[i], row_start[i + U(1)]):
            p = U(p_)
            j = U(partner[p])
            rx = xi - pos[j, U(0)]
            ry = yi - pos[j, U(1)]
            rz = 0.0 if flat else zi - pos[j, U(2)]
            if per:
                rx = nearest_image(rx, period[0])
                ry = nearest_image(ry, period[1])
                if not flat:
                    rz = nearest_image(rz, period[2])
            cut = ai + radius[j]
            if wide:
                cut += hist[p, U(3)]
            t = rx * rx + ry * ry + rz * rz < cut * cut
            if touch[p] > t:  # touched at the last evaluation, not now: the contact ended
                hist[p, U(0)] = 0.0
                hist[p, U(1)] = 0.0
                hist[p, U(2)] = 0.0
                if wide:
                    for e in range(3, hist.shape[1]):
                        hist[p, U(e)] = 0.0
            touch[p] = t
            cbuf[k] = p
            ibuf[k] = i
            k += U(t)
    return k


@njit(cache=True, error_model="numpy", inline="always")
def _gather(flat, per, period, uniform, laws, ext, c0, n, pos, vel, omega, radius, mass, species, pp, partner, hist,
            cbuf, ibuf, G):
    """What the law reads of contacts c0 … c0 + n − 1 of the list into the rows of G (ext: also the relative
    spin, and the rolling spring where the history has its columns; never where ``laws`` is None, see
    ``chunk_run``). ``per``: centre offsets by nearest image (as ``_filter``)."""
    rolling = hist.shape[1] > ROLLING_HISTORY
    for c_ in range(n):
        c = U(c_)
        p = U(cbuf[U(c0) + c])
        i = U(ibuf[U(c0) + c])
        j = U(partner[p])
        ai = radius[i]
        aj = radius[j]
        if per:
            G[U(G_RX * CHUNK) + c] = nearest_image(pos[i, U(0)] - pos[j, U(0)], period[0])
            G[U(G_RY * CHUNK) + c] = nearest_image(pos[i, U(1)] - pos[j, U(1)], period[1])
        else:
            G[U(G_RX * CHUNK) + c] = pos[i, U(0)] - pos[j, U(0)]
            G[U(G_RY * CHUNK) + c] = pos[i, U(1)] - pos[j, U(1)]
        G[U(G_AI * CHUNK) + c] = ai
        G[U(G_AJ * CHUNK) + c] = aj
        G[U(G_MI * CHUNK) + c] = mass[i]
        G[U(G_MJ * CHUNK) + c] = mass[j]
        G[U(G_VX * CHUNK) + c] = vel[i, U(0)] - vel[j, U(0)]
        G[U(G_VY * CHUNK) + c] = vel[i, U(1)] - vel[j, U(1)]
        G[U(G_OZ * CHUNK) + c] = ai * omega[i, U(2)] + aj * omega[j, U(2)]
        G[U(G_HX * CHUNK) + c] = hist[p, U(0)]
        G[U(G_HY * CHUNK) + c] = hist[p, U(1)]
        if not flat:
            if per:
                G[U(G_RZ * CHUNK) + c] = nearest_image(pos[i, U(2)] - pos[j, U(2)], period[2])
            else:
                G[U(G_RZ * CHUNK) + c] = pos[i, U(2)] - pos[j, U(2)]
            G[U(G_VZ * CHUNK) + c] = vel[i, U(2)] - vel[j, U(2)]
            G[U(G_OX * CHUNK) + c] = ai * omega[i, U(0)] + aj * omega[j, U(0)]
            G[U(G_OY * CHUNK) + c] = ai * omega[i, U(1)] + aj * omega[j, U(1)]
            G[U(G_HZ * CHUNK) + c] = hist[p, U(2)]
        if not uniform:
            si = U(species[i])
            sj = U(species[j])
            for q in range(N_SLOTS):
                G[U((G_LAW + q) * CHUNK) + c] = pp[si, sj, U(q)]
        if laws is not None:
            if ext:
                G[U(G_SZ * CHUNK) + c] = omega[i, U(2)] - omega[j, U(2)]
                if not flat:
                    G[U(G_SX * CHUNK) + c] = omega[i, U(0)] - omega[j, U(0)]
                    G[U(G_SY * CHUNK) + c] = omega[i, U(1)] - omega[j, U(1)]
                if rolling:
                    G[U(G_GZ * CHUNK) + c] = hist[p, U(ROLLING_HISTORY + 2)]
                    if not flat:
                        G[U(G_GX * CHUNK) + c] = hist[p, U(ROLLING_HISTORY)]
                        G[U(G_GY * CHUNK) + c] = hist[p, U(ROLLING_HISTORY + 1)]


@njit(cache=True, error_model="numpy", fastmath=True)
def _law(n, G, out, dt, update):
    """The contact law of each of the n contacts of a chunk (its model coded in its row G_LAW): G → out. No
    branch depends on the data, so that the loop is vectorised; z terms are zeros in a flat bed."""
    for c_ in range(n):
        c = U(c_)
        rx = G[U(G_RX * CHUNK) + c]
        ry = G[U(G_RY * CHUNK) + c]
        rz = G[U(G_RZ * CHUNK) + c]
        ai = G[U(G_AI * CHUNK) + c]
        aj = G[U(G_AJ * CHUNK) + c]
        mi = G[U(G_MI * CHUNK) + c]
        mj = G[U(G_MJ * CHUNK) + c]
        r = math.sqrt(rx * rx + ry * ry + rz * rz)
        inv_r = 1.0 / r
        nx = rx * inv_r
        ny = ry * inv_r
        nz = rz * inv_r
        cut = ai + aj
        m_eff = mi * mj / (mi + mj)
        r_eff = ai * aj / (ai + aj)
        # lever arms a_i r/(a_i + a_j) and a_j r/(a_i + a_j): they meet at one contact point and add up to the
        # centre distance (Sun 2007 eq. 24 takes r/2 for equal spheres), so friction conserves angular
        # momentum; the contact-point velocity (eq. 19) uses the same levers
        lever = r / cut
        law = (G[U((G_LAW + 0) * CHUNK) + c], G[U((G_LAW + 1) * CHUNK) + c], G[U((G_LAW + 2) * CHUNK) + c],
               G[U((G_LAW + 3) * CHUNK) + c], G[U((G_LAW + 4) * CHUNK) + c], G[U((G_LAW + 5) * CHUNK) + c],
               G[U((G_LAW + 6) * CHUNK) + c], G[U((G_LAW + 7) * CHUNK) + c])
        fn, ftx, fty, ftz, hx, hy, hz = contact_force(
            law, cut - r, nx, ny, nz, G[U(G_VX * CHUNK) + c], G[U(G_VY * CHUNK) + c], G[U(G_VZ * CHUNK) + c],
            G[U(G_OX * CHUNK) + c] * lever, G[U(G_OY * CHUNK) + c] * lever, G[U(G_OZ * CHUNK) + c] * lever,
            m_eff, r_eff, dt, G[U(G_HX * CHUNK) + c], G[U(G_HY * CHUNK) + c], G[U(G_HZ * CHUNK) + c], update)
        # force on i; torque per unit lever on both: (−ℓ_i n) × F_t = ℓ_i (−n × F_t) on i, (ℓ_j n) × (−F_t) on j
        out[U(O_FX * CHUNK) + c] = fn * nx + ftx
        out[U(O_FY * CHUNK) + c] = fn * ny + fty
        out[U(O_FZ * CHUNK) + c] = fn * nz + ftz
        out[U(O_CX * CHUNK) + c] = -(ny * ftz - nz * fty) * lever
        out[U(O_CY * CHUNK) + c] = -(nz * ftx - nx * ftz) * lever
        out[U(O_CZ * CHUNK) + c] = -(nx * fty - ny * ftx) * lever
        out[U(O_HX * CHUNK) + c] = hx
        out[U(O_HY * CHUNK) + c] = hy
        out[U(O_HZ * CHUNK) + c] = hz


@njit(cache=True, error_model="numpy")
def _law_ext(n, G, out, dt, update):
    """``_law`` for tables with rolling friction or an adhesive law: ``contact_force_full`` (every law; overlaps
    down to the pull-off distance; rolling torque), and the pull-off distance and rolling torques into out.
    Scalar code (the JKR contact radius takes a cube root, which does not vectorise)."""
    for c_ in range(n):
        c = U(c_)
        rx = G[U(G_RX * CHUNK) + c]
        ry = G[U(G_RY * CHUNK) + c]
        rz = G[U(G_RZ * CHUNK) + c]
        ai = G[U(G_AI * CHUNK) + c]
        aj = G[U(G_AJ * CHUNK) + c]
        mi = G[U(G_MI * CHUNK) + c]
        mj = G[U(G_MJ * CHUNK) + c]
        r = math.sqrt(rx * rx + ry * ry + rz * rz)
        inv_r = 1.0 / r
        nx = rx * inv_r
        ny = ry * inv_r
        nz = rz * inv_r
        cut = ai + aj
        m_eff = mi * mj / (mi + mj)
        r_eff = ai * aj / (ai + aj)
        lever = r / cut  # as in _law
        law = (G[U((G_LAW + 0) * CHUNK) + c], G[U((G_LAW + 1) * CHUNK) + c], G[U((G_LAW + 2) * CHUNK) + c],
               G[U((G_LAW + 3) * CHUNK) + c], G[U((G_LAW + 4) * CHUNK) + c], G[U((G_LAW + 5) * CHUNK) + c],
               G[U((G_LAW + 6) * CHUNK) + c], G[U((G_LAW + 7) * CHUNK) + c], G[U((G_LAW + 8) * CHUNK) + c],
               G[U((G_LAW + 9) * CHUNK) + c], G[U((G_LAW + 10) * CHUNK) + c], G[U((G_LAW + 11) * CHUNK) + c])
        # rolling inertia of the contact, 1/(1/(I_i + m_i a_i²) + 1/(I_j + m_j a_j²)) with I = (2/5) m a² (solid
        # spheres, state.py) (Ai et al. 2011 eq. 18; the epsd damping reads it)
        ki = 1.4 * mi * ai * ai
        kj = 1.4 * mj * aj * aj
        i_r = ki * kj / (ki + kj)
        fn, ftx, fty, ftz, hx, hy, hz, reach, mx, my, mz, gx, gy, gz = contact_force_full(
            law, cut - r, nx, ny, nz, G[U(G_VX * CHUNK) + c], G[U(G_VY * CHUNK) + c], G[U(G_VZ * CHUNK) + c],
            G[U(G_OX * CHUNK) + c] * lever, G[U(G_OY * CHUNK) + c] * lever, G[U(G_OZ * CHUNK) + c] * lever,
            G[U(G_SX * CHUNK) + c], G[U(G_SY * CHUNK) + c], G[U(G_SZ * CHUNK) + c],
            m_eff, r_eff, i_r, dt, G[U(G_HX * CHUNK) + c], G[U(G_HY * CHUNK) + c], G[U(G_HZ * CHUNK) + c],
            G[U(G_GX * CHUNK) + c], G[U(G_GY * CHUNK) + c], G[U(G_GZ * CHUNK) + c], update)
        out[U(O_FX * CHUNK) + c] = fn * nx + ftx
        out[U(O_FY * CHUNK) + c] = fn * ny + fty
        out[U(O_FZ * CHUNK) + c] = fn * nz + ftz
        out[U(O_CX * CHUNK) + c] = -(ny * ftz - nz * fty) * lever
        out[U(O_CY * CHUNK) + c] = -(nz * ftx - nx * ftz) * lever
        out[U(O_CZ * CHUNK) + c] = -(nx * fty - ny * ftx) * lever
        out[U(O_HX * CHUNK) + c] = hx
        out[U(O_HY * CHUNK) + c] = hy
        out[U(O_HZ * CHUNK) + c] = hz
        out[U(O_REACH * CHUNK) + c] = reach
        # the torque m on i and −m on j, per unit radius (the force pass multiplies the sums by the radius)
        out[U(O_MIX * CHUNK) + c] = mx / ai
        out[U(O_MIY * CHUNK) + c] = my / ai
        out[U(O_MIZ * CHUNK) + c] = mz / ai
        out[U(O_MJX * CHUNK) + c] = -mx / aj
        out[U(O_MJY * CHUNK) + c] = -my / aj
        out[U(O_MJZ * CHUNK) + c] = -mz / aj
        out[U(O_GX * CHUNK) + c] = gx
        out[U(O_GY * CHUNK) + c] = gy
        out[U(O_GZ * CHUNK) + c] = gz


@njit(cache=True, error_model="numpy", inline="always")
def _scatter(flat, laws, ext, c0, n, partner, hist, sum_f, sum_c, cbuf, ibuf, out):
    """Forces and torques of contacts c0 … c0 + n − 1 into both particles' sums (+F on i, −F on j, the same
    −n × F_t per unit lever on both); springs stored. ext: also the rolling torques, and the pull-off distance
    into history column 3 where there is one, the rolling spring into columns 4-6 where they are (never where
    ``laws`` is None)."""
    wide = hist.shape[1] > 3
    rolling = hist.shape[1] > ROLLING_HISTORY
    for c_ in range(n):
        c = U(c_)
        p = U(cbuf[U(c0) + c])
        i = U(ibuf[U(c0) + c])
        j = U(partner[p])
        fx = out[U(O_FX * CHUNK) + c]
        fy = out[U(O_FY * CHUNK) + c]
        cz = out[U(O_CZ * CHUNK) + c]
        sum_f[i, U(0)] += fx
        sum_f[i, U(1)] += fy
        sum_c[i, U(2)] += cz
        sum_f[j, U(0)] -= fx
        sum_f[j, U(1)] -= fy
        sum_c[j, U(2)] += cz
        hist[p, U(0)] = out[U(O_HX * CHUNK) + c]
        hist[p, U(1)] = out[U(O_HY * CHUNK) + c]
        if not flat:
            fz = out[U(O_FZ * CHUNK) + c]
            cx = out[U(O_CX * CHUNK) + c]
            cy = out[U(O_CY * CHUNK) + c]
            sum_f[i, U(2)] += fz
            sum_c[i, U(0)] += cx
            sum_c[i, U(1)] += cy
            sum_f[j, U(2)] -= fz
            sum_c[j, U(0)] += cx
            sum_c[j, U(1)] += cy
            hist[p, U(2)] = out[U(O_HZ * CHUNK) + c]
        if laws is not None:
            if ext:
                sum_c[i, U(2)] += out[U(O_MIZ * CHUNK) + c]
                sum_c[j, U(2)] += out[U(O_MJZ * CHUNK) + c]
                if not flat:
                    sum_c[i, U(0)] += out[U(O_MIX * CHUNK) + c]
                    sum_c[i, U(1)] += out[U(O_MIY * CHUNK) + c]
                    sum_c[j, U(0)] += out[U(O_MJX * CHUNK) + c]
                    sum_c[j, U(1)] += out[U(O_MJY * CHUNK) + c]
                if wide:
                    hist[p, U(3)] = out[U(O_REACH * CHUNK) + c]
                if rolling:
                    hist[p, U(ROLLING_HISTORY + 2)] = out[U(O_GZ * CHUNK) + c]
                    if not flat:
                        hist[p, U(ROLLING_HISTORY)] = out[U(O_GX * CHUNK) + c]
                        hist[p, U(ROLLING_HISTORY + 1)] = out[U(O_GY * CHUNK) + c]


@njit(cache=True, error_model="numpy", inline="always")
def _slab_body(flat, per, period, s, state, pp, lists, hist, dt, update, sum_f, sum_c, touch, cbuf, ibuf, G, out, uniform,
               laws, ext):
    """The contacts of slab s: filter, then gather, law and scatter chunk by chunk.
    state: (pos, vel, omega, radius, mass, species); lists: (row_start, partner, slab_start, slab_members).
    ``per``: a box with periodic sides of lengths ``period`` (centre offsets by nearest image)."""
    pos, vel, omega, radius, mass, species = state
    row_start, partner, slab_start, slab_members = lists
    k = _filter(flat, per, period, s, pos, radius, row_start, partner, slab_start, slab_members, hist, touch, cbuf,
                ibuf)
    for c0 in range(0, k, CHUNK):
        n = min(CHUNK, k - c0)
        _gather(flat, per, period, uniform, laws, ext, c0, n, pos, vel, omega, radius, mass, species, pp, partner, hist,
                cbuf, ibuf, G)
        if laws is None:
            _law(n, G, out, dt, update)
        elif ext:
            _law_ext(n, G, out, dt, update)
        else:
            _law(n, G, out, dt, update)
        _scatter(flat, laws, ext, c0, n, partner, hist, sum_f, sum_c, cbuf, ibuf, out)


@njit(cache=True, error_model="numpy")
def _slab(s, state, pp, lists, hist, dt, update, sum_f, sum_c, touch, cbuf, ibuf, G, out, uniform, laws, ext,
          period):
    """``_slab_body`` in 3D."""
    _slab_body(False, False, period, s, state, pp, lists, hist, dt, update, sum_f, sum_c, touch, cbuf, ibuf, G, out,
               uniform, laws, ext)


@njit(cache=True, error_model="numpy")
def _slab_flat(s, state, pp, lists, hist, dt, update, sum_f, sum_c, touch, cbuf, ibuf, G, out, uniform, laws, ext,
               period):
    """``_slab_body`` of a flat 2D bed."""
    _slab_body(True, False, period, s, state, pp, lists, hist, dt, update, sum_f, sum_c, touch, cbuf, ibuf, G, out,
               uniform, laws, ext)


@njit(cache=True, error_model="numpy")
def _slab_periodic(s, state, pp, lists, hist, dt, update, sum_f, sum_c, touch, cbuf, ibuf, G, out, uniform, laws,
                   ext, period):
    """``_slab_body`` in 3D, a box with periodic sides."""
    _slab_body(False, True, period, s, state, pp, lists, hist, dt, update, sum_f, sum_c, touch, cbuf, ibuf, G, out,
               uniform, laws, ext)


@njit(cache=True, error_model="numpy")
def _slab_flat_periodic(s, state, pp, lists, hist, dt, update, sum_f, sum_c, touch, cbuf, ibuf, G, out, uniform,
                        laws, ext, period):
    """``_slab_body`` of a flat 2D bed, a box with periodic sides."""
    _slab_body(True, True, period, s, state, pp, lists, hist, dt, update, sum_f, sum_c, touch, cbuf, ibuf, G, out,
               uniform, laws, ext)


@njit(cache=True, error_model="numpy")
def chunk_run(start, stop, flat, state, pp, lists, hist, dt, update, sum_f, sum_c, work, t, period, laws):
    """The contacts of slabs start, start + 2, … below stop (one parity) with thread t's work rows.
    ``flat``: None, or True for a flat 2D bed. ``period``: None (no periodic side), or (3,) the box's length
    along each periodic axis, 0 elsewhere. Both choose the slab variant when this is compiled: Numba drops a
    branch on ``arg is None`` from the compilation, with the variant it calls, so a run compiles only the
    variant it uses (the others took 4 - 5 s each of a first run's compiling). ``laws``: None where no contact
    law of the run has rolling friction or adhesion (no row of the table is ``extended``), which leaves the
    extended law (``_law_ext``) and its gathers and scatters out; else any value (``ext`` of the work arrays
    then chooses as the run goes)."""
    cbuf, ibuf, G, out, touch, uniform, ext = work
    cb = cbuf[t]
    ib = ibuf[t]
    g = G[t]
    o = out[t]
    if period is None:
        box = np.zeros(3)  # not read: the slabs of a box without periodic sides take no nearest image
        for s in range(start, stop, 2):
            if flat is None:
                _slab(s, state, pp, lists, hist, dt, update, sum_f, sum_c, touch, cb, ib, g, o, uniform, laws, ext, box)
            else:
                _slab_flat(s, state, pp, lists, hist, dt, update, sum_f, sum_c, touch, cb, ib, g, o, uniform, laws, ext,
                           box)
    else:
        for s in range(start, stop, 2):
            if flat is None:
                _slab_periodic(s, state, pp, lists, hist, dt, update, sum_f, sum_c, touch, cb, ib, g, o, uniform, laws,
                               ext, period)
            else:
                _slab_flat_periodic(s, state, pp, lists, hist, dt, update, sum_f, sum_c, touch, cb, ib, g, o, uniform,
                                    laws, ext, period)
