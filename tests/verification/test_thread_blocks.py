"""The threads' shares of the soft-sphere force loops (``_softsphere_kernels.thread_blocks``).

Each thread takes a contiguous block of slabs in the pair loop and the particles of those slabs
(in the engine's slab-ordered numbering) in the force-gathering pass. The split must cover every
slab once, balance the work it counts, and, whatever it is, leave the sums bitwise those of the
serial loop: a particle gets its terms in the same order (the even slabs, then the odd ones).
"""
from __future__ import annotations

import numpy as np
import pytest

from fluidem.particles import _softsphere_kernels as K
from fluidem.particles.softsphere import SoftSphereEngine


@pytest.fixture
def settled(tiny_bed_case):
    """400 spheres squeezed onto a jittered lattice of 0.995 d (about six contacts each), moving and
    spinning at random, with random tangential springs: every term of the contact law is non-zero."""
    eng = SoftSphereEngine(tiny_bed_case(n=400, model="hertz_mindlin", box=(5 * 4e-3, 5 * 4e-3, 30 * 4e-3), restitution=0.7,
                                         friction=0.4))
    st, rng, d = eng.state, np.random.default_rng(11), 2 * eng.state.radius[0]
    grid = np.stack(np.meshgrid(np.arange(5), np.arange(5), np.arange(16), indexing="ij"), -1).reshape(-1, 3)
    st.position[:] = (grid[:400] + 0.5) * 0.995 * d + rng.uniform(-0.002, 0.002, (400, 3)) * d
    st.velocity[:] = rng.normal(0.0, 0.05, (400, 3))
    st.omega[:] = rng.normal(0.0, 20.0, (400, 3))
    eng.row_start, eng.partner, eng.hist, eng.slab_start, eng.slab_members = K.rebuild(
        st.position, st.radius, eng.skin, eng.dim2, eng.row_start, eng.partner, eng.hist, eng.ref_pos)
    eng.hist[:] = rng.normal(0.0, 1e-6, eng.hist.shape)
    return eng


def work_of_slabs(eng):
    """The work thread_blocks counts per slab: PAIR_WEIGHT per listed pair of its members' rows + 1 per member."""
    rows = np.diff(eng.row_start)
    return np.array([np.sum(K.PAIR_WEIGHT * rows[eng.slab_members[a:b]] + 1.0)
                     for a, b in zip(eng.slab_start[:-1], eng.slab_start[1:])])


@pytest.mark.parametrize("nthreads", [1, 2, 3, 5])
def test_blocks_cover_every_slab_once_and_share_the_work(settled, nthreads):
    eng = settled
    block = K.thread_blocks(eng.row_start, eng.slab_start, eng.slab_members, nthreads)
    nslab = eng.slab_start.shape[0] - 1
    assert block.shape == (nthreads + 1,) and block[0] == 0 and block[-1] == nslab
    assert np.all(np.diff(block) >= 0)
    work = work_of_slabs(eng)
    share = np.array([work[block[k]:block[k + 1]].sum() for k in range(nthreads)])
    assert share.sum() == pytest.approx(work.sum())
    # each block ends at the first slab where the running sum reaches its share: no block exceeds
    # total / nthreads by more than one slab's work
    assert share.max() <= work.sum() / nthreads + work.max() + 1e-9


def sums(eng, block):
    """Contact sums of the engine's current state with the slabs split as ``block`` says."""
    st = eng.state
    sum_f, sum_c = np.zeros_like(st.force), np.zeros_like(st.force)
    hist = eng.hist.copy()
    K.pair_forces(st.position, st.velocity, st.omega, st.radius, st.mass, st.species, eng.pp, eng.row_start,
                  eng.partner, eng.slab_start, eng.slab_members, hist, eng.dt, True, sum_f, sum_c, block)
    return sum_f, sum_c, hist


def gathered(eng, first):
    """Total force and torque (mode 0: forces only) with the particles split at ``first``."""
    st = eng.state
    sum_f, sum_c, _ = sums(eng, np.array([0, eng.slab_start.shape[0] - 1]))
    force, torque = np.empty_like(st.force), np.empty_like(st.force)
    K.gather_forces(st.position, st.velocity, st.omega, st.radius, st.mass, st.species, eng.pw, eng.wall_motion,
                    eng.wall_point0, eng.wall_normal, K.wall_axes(eng.wall_normal), eng.wall_hist.copy(),
                    eng.wall_touch.copy(), eng.near_count, eng.near_wall, eng.gravity, eng.ext_force,
                    eng.ext_damping, False, eng.dim2, sum_f, sum_c, eng.time, eng.dt, force, torque, eng.inv_mass,
                    eng.inv_inertia, 0, eng.ref_pos, 1.0, first)
    assert not sum_f.any() and not sum_c.any(), "the pass leaves the sums zero"
    return force, torque


@pytest.mark.parametrize("nthreads", [2, 3, 5])
def test_any_split_gives_the_serial_sums_bitwise(all_threads, settled, nthreads):
    """Pair sums and updated tangential springs of the blocks, of lopsided splits (one block holding
    everything, empty blocks) and of the serial loop are bitwise equal; so are the gathered forces."""
    eng = settled
    nslab = eng.slab_start.shape[0] - 1
    serial = sums(eng, np.array([0, nslab]))
    assert np.count_nonzero(np.linalg.norm(serial[0], axis=1)) == 400, "every sphere in contact"
    splits = [K.thread_blocks(eng.row_start, eng.slab_start, eng.slab_members, nthreads),
              np.array([0] + [nslab] * nthreads), np.array([0] * nthreads + [nslab]),
              np.linspace(0, nslab, nthreads + 1).astype(np.int64)]
    for block in splits:
        for a, b in zip(serial, sums(eng, block)):
            assert np.array_equal(a, b), block
    f1, t1 = gathered(eng, np.array([0, eng.state.position.shape[0]]))
    for block in splits:
        f2, t2 = gathered(eng, eng.slab_start[block])
        assert np.array_equal(f1, f2) and np.array_equal(t1, t2), block
