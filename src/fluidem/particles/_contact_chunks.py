"""Compiled soft-sphere pair forces with the contact law vectorised over contacts (Sun 2007 eqs 17–24).

The scalar pair loop (``_softsphere_kernels._slab_pairs``) evaluates one contact at a time.
Its Hertz–Mindlin law is a chain of five square roots and five divisions per contact, each
waiting for the last, and the core cannot start the next contact's chain before the current
one retires: about 120 cycles a contact (10,000-sphere bench bed, one thread), though the
divider alone needs 70 of them. Here the same law runs over chunks of contacts laid out
side by side, so that LLVM vectorises it: four contacts per AVX2 instruction, a square root
or a division every ~2 cycles per contact instead of ~9, and the chains of four contacts in
flight at once. The pairs of one slab go through three passes:

1. ``_filter``: every listed pair of the slab's members is tested for contact
   (``r² < (a_i + a_j)²``, the scalar loop's test) and the touching ones are appended,
   without a branch, to a list (pair slot, owner). A contact that ended since the last
   step has its tangential spring reset here: ``touch`` holds each listed pair's state of
   the last step, so the spring array is read only for those (a rare, well-predicted branch).
2. per chunk of ``CHUNK`` contacts: ``_gather`` copies what the law reads of each contact
   (centre offset, radii, masses, relative velocity, a_i ω_i + a_j ω_j, spring, the contact
   law's parameters) into rows of one flat array ``G`` (row q of contact c at
   ``G[q * CHUNK + c]``); ``_law`` runs ``contact/_dispatch.contact_force`` (branch-free)
   over the chunk into ``O``; ``_scatter`` adds each force and torque to both particles'
   sums and stores the spring. Rows of one array at constant offsets let LLVM prove that
   ``G`` and ``O`` are two objects, with one run-time overlap check; separate arrays per
   quantity needed more checks than the vectoriser allows ("too many memory checks"), and
   one buffer for a whole slab (instead of chunks of 128, 23 KB) thrashed the L1 cache.

A chunk's law is specialised at compile time for the contact model (``code``: every
species pair must use the same law; a mixed table takes the scalar loop) and for flat 2D
beds (``flat``, see ``is_flat``): the z terms are left out. Measured on the 10,000-sphere
bench bed, one thread, pair forces alone (``benchmarks/README.md``): see there.

Each particle's force sum receives its terms in the order of the slab's contact list
(slabs of one parity in parallel, then the other), whatever the number of threads: the
sums are bitwise independent of the thread count, as with the scalar loop. They differ
from the scalar loop's at round-off (that loop sums a row in registers first).
"""
import math

import numpy as np
from numba import njit

from .contact import hertz_mindlin, spring_dashpot
from .contact._dispatch import contact_force

U = np.uintp  # unsigned array index (see _softsphere_kernels)

CHUNK = 128  # contacts per chunk: G and O of one chunk (23 KB) stay in the L1 cache
# rows of G: what the law reads of a contact
G_RX, G_RY, G_RZ, G_AI, G_AJ, G_MI, G_MJ, G_VX, G_VY, G_VZ, G_OX, G_OY, G_OZ, G_HX, G_HY, G_HZ = range(16)
G_LAW = 16  # rows G_LAW … G_LAW + 5: slots 1, 2, 3, 4, 5 and 7 of the packed contact row (contact/base.py)
LAW_SLOTS = (1, 2, 3, 4, 5, 7)
N_G = G_LAW + 6
# rows of O: what the law gives
O_FX, O_FY, O_FZ, O_CX, O_CY, O_CZ, O_HX, O_HY, O_HZ = range(9)
N_O = 9

VECTOR_CODES = (spring_dashpot.CODE, hertz_mindlin.CODE)  # models with a compiled chunk law


@njit(cache=True, error_model="numpy")
def table_code(pp):
    """The model code shared by every species pair of the contact table pp (S, S, 8), or 0 if they differ
    or the model has no chunk law (the scalar loop then runs)."""
    code = int(pp[0, 0, 0])
    for a in range(pp.shape[0]):
        for b in range(pp.shape[1]):
            if int(pp[a, b, 0]) != code:
                return 0
    if code == spring_dashpot.CODE or code == hertz_mindlin.CODE:
        return code
    return 0


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
    list rebuild: (cbuf, ibuf, G, O, touch, uniform).

    cbuf, ibuf (nthreads, M) uint32: a thread's contact list of one slab (pair slot, owner), M the most
    listed pairs of any slab; G (nthreads, N_G · CHUNK), O (nthreads, N_O · CHUNK): a thread's chunk;
    touch (P,) uint8: 1 where the pair's spring is set (it touched at the last evaluation: a spring is
    zero otherwise); uniform: one contact row for all species pairs, copied into every G here.
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
    O = np.empty((nthreads, N_O * CHUNK))
    npair = hist.shape[0]
    touch = np.empty(npair, dtype=np.uint8)
    for p in range(npair):
        touch[p] = (hist[p, 0] != 0.0) | (hist[p, 1] != 0.0) | (hist[p, 2] != 0.0)
    uniform = _uniform(pp)
    if uniform:
        for t in range(nthreads):
            for q in range(6):
                v = pp[0, 0, LAW_SLOTS[q]]
                for c in range(CHUNK):
                    G[t, (G_LAW + q) * CHUNK + c] = v
    return cbuf, ibuf, G, O, touch, uniform


@njit(cache=True, error_model="numpy", inline="always")
def _filter(flat, s, pos, radius, row_start, partner, slab_start, slab_members, hist, touch, cbuf, ibuf):
    """The touching pairs of slab s into cbuf/ibuf (returns their number); springs of ended contacts reset."""
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
            cut = ai + radius[j]
            t = rx * rx + ry * ry + rz * rz < cut * cut
            if touch[p] > t:  # touched at the last evaluation, not now: the contact ended
                hist[p, U(0)] = 0.0
                hist[p, U(1)] = 0.0
                hist[p, U(2)] = 0.0
            touch[p] = t
            cbuf[k] = p
            ibuf[k] = i
            k += U(t)
    return k


@njit(cache=True, error_model="numpy", inline="always")
def _gather(flat, uniform, c0, n, pos, vel, omega, radius, mass, species, pp, partner, hist, cbuf, ibuf, G):
    """What the law reads of contacts c0 … c0 + n − 1 of the list into the rows of G."""
    for c_ in range(n):
        c = U(c_)
        p = U(cbuf[U(c0) + c])
        i = U(ibuf[U(c0) + c])
        j = U(partner[p])
        ai = radius[i]
        aj = radius[j]
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
            G[U(G_RZ * CHUNK) + c] = pos[i, U(2)] - pos[j, U(2)]
            G[U(G_VZ * CHUNK) + c] = vel[i, U(2)] - vel[j, U(2)]
            G[U(G_OX * CHUNK) + c] = ai * omega[i, U(0)] + aj * omega[j, U(0)]
            G[U(G_OY * CHUNK) + c] = ai * omega[i, U(1)] + aj * omega[j, U(1)]
            G[U(G_HZ * CHUNK) + c] = hist[p, U(2)]
        if not uniform:
            si = U(species[i])
            sj = U(species[j])
            G[U((G_LAW + 0) * CHUNK) + c] = pp[si, sj, U(1)]
            G[U((G_LAW + 1) * CHUNK) + c] = pp[si, sj, U(2)]
            G[U((G_LAW + 2) * CHUNK) + c] = pp[si, sj, U(3)]
            G[U((G_LAW + 3) * CHUNK) + c] = pp[si, sj, U(4)]
            G[U((G_LAW + 4) * CHUNK) + c] = pp[si, sj, U(5)]
            G[U((G_LAW + 5) * CHUNK) + c] = pp[si, sj, U(7)]


@njit(cache=True, error_model="numpy", inline="always")
def _law_body(flat, code, n, G, O, dt, update):
    """The contact law of model ``code`` (a constant) for the n contacts of a chunk: G → O. No branch
    depends on the data, so that the loop is vectorised."""
    for c_ in range(n):
        c = U(c_)
        rx = G[U(G_RX * CHUNK) + c]
        ry = G[U(G_RY * CHUNK) + c]
        rz = 0.0 if flat else G[U(G_RZ * CHUNK) + c]
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
        # lever arms a r/(a_i + a_j) of both spheres (see _softsphere_kernels._slab_pairs_body)
        lever = r / cut
        wx = 0.0 if flat else G[U(G_OX * CHUNK) + c] * lever
        wy = 0.0 if flat else G[U(G_OY * CHUNK) + c] * lever
        wz = G[U(G_OZ * CHUNK) + c] * lever
        law = (float(code), G[U((G_LAW + 0) * CHUNK) + c], G[U((G_LAW + 1) * CHUNK) + c],
               G[U((G_LAW + 2) * CHUNK) + c], G[U((G_LAW + 3) * CHUNK) + c], G[U((G_LAW + 4) * CHUNK) + c], 0.0,
               G[U((G_LAW + 5) * CHUNK) + c])
        fn, ftx, fty, ftz, hx, hy, hz = contact_force(
            law, cut - r, nx, ny, nz, G[U(G_VX * CHUNK) + c], G[U(G_VY * CHUNK) + c],
            0.0 if flat else G[U(G_VZ * CHUNK) + c], wx, wy, wz, m_eff, r_eff, dt,
            G[U(G_HX * CHUNK) + c], G[U(G_HY * CHUNK) + c], 0.0 if flat else G[U(G_HZ * CHUNK) + c], update)
        O[U(O_FX * CHUNK) + c] = fn * nx + ftx
        O[U(O_FY * CHUNK) + c] = fn * ny + fty
        O[U(O_CZ * CHUNK) + c] = -(nx * fty - ny * ftx) * lever
        O[U(O_HX * CHUNK) + c] = hx
        O[U(O_HY * CHUNK) + c] = hy
        if not flat:
            O[U(O_FZ * CHUNK) + c] = fn * nz + ftz
            O[U(O_CX * CHUNK) + c] = -(ny * ftz - nz * fty) * lever
            O[U(O_CY * CHUNK) + c] = -(nz * ftx - nx * ftz) * lever
            O[U(O_HZ * CHUNK) + c] = hz


@njit(cache=True, error_model="numpy", fastmath=True)
def _law_linear(n, G, O, dt, update):
    _law_body(False, spring_dashpot.CODE, n, G, O, dt, update)


@njit(cache=True, error_model="numpy", fastmath=True)
def _law_linear_flat(n, G, O, dt, update):
    _law_body(True, spring_dashpot.CODE, n, G, O, dt, update)


@njit(cache=True, error_model="numpy", fastmath=True)
def _law_hertz(n, G, O, dt, update):
    _law_body(False, hertz_mindlin.CODE, n, G, O, dt, update)


@njit(cache=True, error_model="numpy", fastmath=True)
def _law_hertz_flat(n, G, O, dt, update):
    _law_body(True, hertz_mindlin.CODE, n, G, O, dt, update)


@njit(cache=True, error_model="numpy", inline="always")
def _scatter(flat, c0, n, partner, hist, sum_f, sum_c, cbuf, ibuf, O):
    """Forces and torques of contacts c0 … c0 + n − 1 into both particles' sums (+F on i, −F on j, the same
    −n × F_t per unit lever on both); springs stored."""
    for c_ in range(n):
        c = U(c_)
        p = U(cbuf[U(c0) + c])
        i = U(ibuf[U(c0) + c])
        j = U(partner[p])
        fx = O[U(O_FX * CHUNK) + c]
        fy = O[U(O_FY * CHUNK) + c]
        cz = O[U(O_CZ * CHUNK) + c]
        sum_f[i, U(0)] += fx
        sum_f[i, U(1)] += fy
        sum_c[i, U(2)] += cz
        sum_f[j, U(0)] -= fx
        sum_f[j, U(1)] -= fy
        sum_c[j, U(2)] += cz
        hist[p, U(0)] = O[U(O_HX * CHUNK) + c]
        hist[p, U(1)] = O[U(O_HY * CHUNK) + c]
        if not flat:
            fz = O[U(O_FZ * CHUNK) + c]
            cx = O[U(O_CX * CHUNK) + c]
            cy = O[U(O_CY * CHUNK) + c]
            sum_f[i, U(2)] += fz
            sum_c[i, U(0)] += cx
            sum_c[i, U(1)] += cy
            sum_f[j, U(2)] -= fz
            sum_c[j, U(0)] += cx
            sum_c[j, U(1)] += cy
            hist[p, U(2)] = O[U(O_HZ * CHUNK) + c]


@njit(cache=True, error_model="numpy", inline="always")
def _slab_body(flat, s, code, state, pp, lists, hist, dt, update, sum_f, sum_c, touch, cbuf, ibuf, G, O, uniform):
    """The contacts of slab s: filter, then gather, law and scatter chunk by chunk.
    state: (pos, vel, omega, radius, mass, species); lists: (row_start, partner, slab_start, slab_members)."""
    pos, vel, omega, radius, mass, species = state
    row_start, partner, slab_start, slab_members = lists
    k = _filter(flat, s, pos, radius, row_start, partner, slab_start, slab_members, hist, touch, cbuf, ibuf)
    for c0 in range(0, k, CHUNK):
        n = min(CHUNK, k - c0)
        _gather(flat, uniform, c0, n, pos, vel, omega, radius, mass, species, pp, partner, hist, cbuf, ibuf, G)
        if code == hertz_mindlin.CODE:
            if flat:
                _law_hertz_flat(n, G, O, dt, update)
            else:
                _law_hertz(n, G, O, dt, update)
        else:
            if flat:
                _law_linear_flat(n, G, O, dt, update)
            else:
                _law_linear(n, G, O, dt, update)
        _scatter(flat, c0, n, partner, hist, sum_f, sum_c, cbuf, ibuf, O)


@njit(cache=True, error_model="numpy")
def _slab(s, code, state, pp, lists, hist, dt, update, sum_f, sum_c, touch, cbuf, ibuf, G, O, uniform):
    """``_slab_body`` in 3D."""
    _slab_body(False, s, code, state, pp, lists, hist, dt, update, sum_f, sum_c, touch, cbuf, ibuf, G, O, uniform)


@njit(cache=True, error_model="numpy")
def _slab_flat(s, code, state, pp, lists, hist, dt, update, sum_f, sum_c, touch, cbuf, ibuf, G, O, uniform):
    """``_slab_body`` of a flat 2D bed."""
    _slab_body(True, s, code, state, pp, lists, hist, dt, update, sum_f, sum_c, touch, cbuf, ibuf, G, O, uniform)


@njit(cache=True, error_model="numpy")
def chunk_run(start, stop, flat, code, state, pp, lists, hist, dt, update, sum_f, sum_c, work, t):
    """The contacts of slabs start, start + 2, … below stop (one parity) with thread t's work rows."""
    cbuf, ibuf, G, O, touch, uniform = work
    cb = cbuf[t]
    ib = ibuf[t]
    g = G[t]
    o = O[t]
    for s in range(start, stop, 2):
        if flat:
            _slab_flat(s, code, state, pp, lists, hist, dt, update, sum_f, sum_c, touch, cb, ib, g, o, uniform)
        else:
            _slab(s, code, state, pp, lists, hist, dt, update, sum_f, sum_c, touch, cb, ib, g, o, uniform)
