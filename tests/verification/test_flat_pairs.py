"""The pair loop of flat 2D beds (``_pair_kernels._slab_flat``) against the general one.

A one-layer 2D bed (every centre at the same z, no motion along z, spin about z only, every
tangential spring in the plane: ``is_flat``) has exact zeros in all z components of the contact
law; the flat variant leaves them out. Its sums must equal the general loop's to round-off (the
compiler may contract the remaining products into fused multiply-adds differently), for every
contact model, and ``is_flat`` must refuse a bed that breaks any of the four conditions.
"""
from __future__ import annotations

import numpy as np
import pytest

from fluidem.particles import _softsphere_kernels as K
from fluidem.particles._neighbours_kernels import build_pairs
from fluidem.particles.contact import soft_contact_models
from fluidem.particles.softsphere import SoftSphereEngine


def flat_bed(engine, seed=5):
    """400 discs of the engine's size on a jittered square lattice of 0.995 d in the plane z = 0.01 m, moving
    in the plane and spinning about z at random, with random in-plane tangential springs."""
    st, rng = engine.state, np.random.default_rng(seed)
    d = 2 * st.radius[0]
    grid = np.stack(np.meshgrid(np.arange(20), np.arange(20), indexing="ij"), -1).reshape(-1, 2)
    pos = np.zeros((400, 3))
    pos[:, :2] = (grid + 0.5) * 0.995 * d + rng.uniform(-0.002, 0.002, (400, 2)) * d
    pos[:, 2] = 0.01
    vel = np.zeros((400, 3))
    vel[:, :2] = rng.normal(0.0, 0.05, (400, 2))
    omega = np.zeros((400, 3))
    omega[:, 2] = rng.normal(0.0, 20.0, 400)
    row_start, partner, slab_start, slab_members = build_pairs(pos, st.radius, 0.1 * d, True)
    hist = np.zeros((partner.shape[0], 3))
    hist[:, :2] = rng.normal(0.0, 1e-6, (partner.shape[0], 2))
    return pos, vel, omega, row_start, partner, slab_start, slab_members, hist


def pair_sums(engine, bed, flat):
    pos, vel, omega, row_start, partner, slab_start, slab_members, hist = bed
    st = engine.state
    sum_f, sum_c, h = np.zeros((400, 3)), np.zeros((400, 3)), hist.copy()
    K.pair_forces(pos, vel, omega, st.radius, st.mass, st.species, engine.pp, row_start, partner, slab_start,
                  slab_members, h, engine.dt, True, sum_f, sum_c, np.array([0, slab_start.shape[0] - 1]), flat)
    return sum_f, sum_c, h


@pytest.mark.parametrize("model", soft_contact_models())
def test_flat_pair_loop_gives_the_general_sums(tiny_bed_case, model):
    eng = SoftSphereEngine(tiny_bed_case(n=400, model=model, box=(5 * 4e-3, 5 * 4e-3, 30 * 4e-3), restitution=0.7,
                                         friction=0.4))
    bed = flat_bed(eng)
    assert K.is_flat(bed[0], bed[1], bed[2], bed[7])
    general, flat = pair_sums(eng, bed, None), pair_sums(eng, bed, True)
    f, c, h = general
    assert np.count_nonzero(np.linalg.norm(f, axis=1)) == 400, "every disc in contact"
    assert np.count_nonzero(c[:, 2]) == 400, "friction acts on every disc"
    # what the flat loop leaves out is exactly zero in the general one
    assert not f[:, 2].any() and not c[:, :2].any() and not h[:, 2].any()
    for name, a, b in zip(("force sums", "torque sums", "springs"), general, flat):
        np.testing.assert_allclose(b, a, rtol=0.0, atol=1e-13 * np.abs(a).max(), err_msg=name)


def test_is_flat_refuses_each_way_out_of_the_plane(tiny_bed_case):
    eng = SoftSphereEngine(tiny_bed_case(n=400, box=(5 * 4e-3, 5 * 4e-3, 30 * 4e-3)))
    pos, vel, omega, *_, hist = flat_bed(eng)
    assert K.is_flat(pos, vel, omega, hist)
    for arr, idx in ((pos, (7, 2)), (vel, (8, 2)), (omega, (9, 0)), (omega, (10, 1)), (hist, (11, 2))):
        keep = arr[idx]
        arr[idx] += 1e-9
        assert not K.is_flat(pos, vel, omega, hist), idx
        arr[idx] = keep
    assert K.is_flat(pos, vel, omega, hist)
