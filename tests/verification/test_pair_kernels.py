"""The chunked, vectorised pair forces (``_pair_kernels``) against the contact law evaluated pair by pair.

``pair_forces`` filters the touching pairs, copies them into chunks, runs the contact law
(``contact/_dispatch.contact_force``) over a chunk as vector code and adds each contact's force
to both particles' sums. The reference here calls the same law for one listed pair at a time,
in plain compiled code, and adds the forces up with NumPy. The sums must agree to round-off for
every contact model, in 3D and on flat 2D beds, with one contact row for all species pairs
(copied into the chunks once), several (gathered per contact) or several of different models,
with contacts that stick and contacts that slip, and with springs of pairs that no longer touch
reset to zero.
"""
from __future__ import annotations

import numpy as np
import pytest
from numba import njit

from fluidem.particles import _pair_kernels as C
from fluidem.particles import _softsphere_kernels as K
from fluidem.particles._neighbours_kernels import build_pairs
from fluidem.particles.contact import contact_models, soft_contact_models
from fluidem.particles.contact._dispatch import contact_force
from fluidem.particles.contact.base import N_SLOTS

# the plain (vectorised) law: every model but the adhesive ones, whose contacts outlast touch and take the
# extended law (their pair forces are checked against the analytic JKR curve in test_jkr.py)
PLAIN_MODELS = [m for m in soft_contact_models() if not contact_models.get(m).adhesive]

D = 4e-3  # [m] mean diameter
RHO = (2700.0, 8900.0)  # [kg/m³] two species: aluminium and bronze


def law(model, **kw):
    cls = contact_models.get(model)
    base = {"linear_spring_dashpot": {"stiffness": 800.0}, "hertz_mindlin": {"youngs_modulus": 5e6}}[model]
    return cls(**{**base, **kw})


def table(model, mixed):
    """(S, S, N_SLOTS) contact table: one species, or two whose three pairs differ in restitution and friction (the
    linear law also in stiffness); symmetric."""
    if not mixed:
        return law(model, restitution=0.7, friction=0.4).pack(None, None)[None, None, :].copy()
    a, b, ab = (law(model, restitution=e, friction=mu) for e, mu in ((0.7, 0.4), (0.9, 0.2), (0.5, 0.6)))
    if model == "linear_spring_dashpot":
        b = law(model, stiffness=1200.0, restitution=0.9, friction=0.2)
    pp = np.empty((2, 2, N_SLOTS))
    pp[0, 0], pp[1, 1] = a.pack(None, None), b.pack(None, None)
    pp[0, 1] = pp[1, 0] = ab.pack(None, None)
    return pp


def bed(flat, mixed, seed=3):
    """600 spheres of ±5 % diameter on a jittered lattice of 0.985 d (about six contacts each in 3D, four in
    2D), moving and spinning at random, springs random on every listed pair (also on those that do not
    touch: they must be reset). Sliding speeds of ~0.3 m/s make some contacts slip."""
    rng = np.random.default_rng(seed)
    n = 600
    radius = 0.5 * D * rng.uniform(0.95, 1.05, n)
    species = rng.integers(0, 2, n) if mixed else np.zeros(n, np.int64)
    mass = np.array(RHO)[species] * 4.0 / 3.0 * np.pi * radius**3
    if flat:
        grid = np.stack(np.meshgrid(np.arange(30), np.arange(20), indexing="ij"), -1).reshape(-1, 2)
        pos = np.zeros((n, 3))
        pos[:, :2] = (grid + 0.5) * 0.985 * D + rng.uniform(-0.004, 0.004, (n, 2)) * D
        pos[:, 2] = 0.01
    else:
        grid = np.stack(np.meshgrid(np.arange(10), np.arange(10), np.arange(6), indexing="ij"), -1).reshape(-1, 3)
        pos = (grid + 0.5) * 0.985 * D + rng.uniform(-0.004, 0.004, (n, 3)) * D
    vel = rng.normal(0.0, 0.3, (n, 3))
    omega = rng.normal(0.0, 50.0, (n, 3))
    if flat:
        vel[:, 2] = 0.0
        omega[:, :2] = 0.0
    row_start, partner, slab_start, slab_members = build_pairs(pos, radius, 0.1 * D, flat)
    hist = rng.normal(0.0, 2e-6, (partner.shape[0], 3))
    if flat:
        hist[:, 2] = 0.0
    return dict(pos=pos, vel=vel, omega=omega, radius=radius, mass=mass, species=species, row_start=row_start,
                partner=partner, slab_start=slab_start, slab_members=slab_members, hist=hist)


def sums(b, pp, flat, update=True, nthreads=1):
    f, c, h = np.zeros((600, 3)), np.zeros((600, 3)), b["hist"].copy()
    block = K.thread_blocks(b["row_start"], b["slab_start"], b["slab_members"], nthreads)
    K.pair_forces(b["pos"], b["vel"], b["omega"], b["radius"], b["mass"], b["species"], pp, b["row_start"],
                  b["partner"], b["slab_start"], b["slab_members"], h, 1e-5, update, f, c, block,
                  True if flat else None)
    return f, c, h


def reference(b, pp, update=True):
    """Pair by pair: the force on i and j and −n × F_t per unit lever of every listed pair (zero where it does
    not touch), summed with np.add.at; springs of pairs that do not touch reset."""
    f, c, h, _, _, _ = _pairwise(b["pos"], b["vel"], b["omega"], b["radius"], b["mass"], b["species"], pp,
                                 b["row_start"], b["partner"], b["hist"], update)
    i = np.repeat(np.arange(600), np.diff(b["row_start"]))
    j = b["partner"]
    fs, cs = np.zeros((600, 3)), np.zeros((600, 3))
    np.add.at(fs, i, f)
    np.add.at(fs, j, -f)
    np.add.at(cs, i, c)
    np.add.at(cs, j, c)
    return fs, cs, h


@njit(cache=True)
def _pairwise(pos, vel, omega, radius, mass, species, pp, row_start, partner, hist, update):
    """Per listed pair: force on i, −n × F_t per unit lever, new spring, whether it touches, F_n and |F_t|."""
    npair = partner.shape[0]
    f, c, h, touch = np.zeros((npair, 3)), np.zeros((npair, 3)), np.zeros((npair, 3)), np.zeros(npair, np.bool_)
    fnorm, ftan = np.zeros(npair), np.zeros(npair)
    for i in range(pos.shape[0]):
        for p in range(row_start[i], row_start[i + 1]):
            j = partner[p]
            r = pos[i] - pos[j]
            d = np.sqrt(np.sum(r * r))
            cut = radius[i] + radius[j]
            if d >= cut:
                continue
            touch[p] = True
            n = r / d
            lever = d / cut  # a_i d/(a_i + a_j): where the spheres meet
            w = (radius[i] * omega[i] + radius[j] * omega[j]) * lever
            v = vel[i] - vel[j]
            fn, ftx, fty, ftz, hx, hy, hz = contact_force(
                pp[species[i], species[j]], cut - d, n[0], n[1], n[2], v[0], v[1], v[2], w[0], w[1], w[2],
                mass[i] * mass[j] / (mass[i] + mass[j]), radius[i] * radius[j] / cut, 1e-5,
                hist[p, 0], hist[p, 1], hist[p, 2], update)
            ft = np.array([ftx, fty, ftz])
            f[p] = fn * n + ft
            c[p] = -np.cross(n, ft) * lever
            h[p] = (hx, hy, hz)
            fnorm[p] = fn
            ftan[p] = np.sqrt(ftx * ftx + fty * fty + ftz * ftz)
    return f, c, h, touch, fnorm, ftan


def slipping(b, pp, update):
    """(slipping, sticking) touching pairs under the scalar law (|F_t| at μ F_n, or below it)."""
    _, _, _, touch, fn, ft = _pairwise(b["pos"], b["vel"], b["omega"], b["radius"], b["mass"], b["species"], pp,
                                       b["row_start"], b["partner"], b["hist"], update)
    i = np.repeat(np.arange(b["pos"].shape[0]), np.diff(b["row_start"]))
    lim = pp[b["species"][i], b["species"][b["partner"]], 7] * np.maximum(fn, 0.0)
    at_limit = np.abs(ft - lim) <= 1e-12 * lim
    return int(np.sum(touch & at_limit)), int(np.sum(touch & ~at_limit & (ft < lim)))


def agree(expected, chunked):
    """Force and torque sums to 1e-13 of the largest: round-off (the vector code is compiled with fastmath, the
    reference without). Springs to 1e-11: a slipping contact's spring is (F_t + η_t u_t)/k_t, a difference of
    nearly equal terms that magnifies round-off (seen: 7e-13 of the largest spring)."""
    for name, a, x, tol in zip(("force sums", "torque sums", "springs"), expected, chunked, (1e-13, 1e-13, 1e-11)):
        np.testing.assert_allclose(x, a, rtol=0.0, atol=tol * np.abs(a).max(), err_msg=name)


def touching(b):
    i = np.repeat(np.arange(600), np.diff(b["row_start"]))
    j = b["partner"]
    d = np.linalg.norm(b["pos"][i] - b["pos"][j], axis=1)
    return d < b["radius"][i] + b["radius"][j]


@pytest.mark.parametrize("update", [True, False], ids=["update", "no-update"])
@pytest.mark.parametrize("mixed", [False, True], ids=["one-row", "two-species"])
@pytest.mark.parametrize("flat", [False, True], ids=["3d", "flat"])
@pytest.mark.parametrize("model", PLAIN_MODELS)
def test_chunks_give_the_pairwise_sums(model, flat, mixed, update):
    pp = table(model, mixed)
    b = bed(flat, mixed)
    touch = touching(b)
    assert 500 < touch.sum() < touch.size, "contacts and listed pairs that do not touch"
    slip, stick = slipping(b, pp, update)
    assert slip > 50 and stick > 50, "both branches of the Coulomb limit"
    expected, chunked = reference(b, pp, update), sums(b, pp, flat, update)
    assert not chunked[2][~touch].any(), "springs of listed pairs that do not touch are reset"
    assert chunked[2][touch].any(axis=1).all()
    agree(expected, chunked)
    if flat:  # what the flat law leaves out stays zero
        assert not chunked[0][:, 2].any() and not chunked[1][:, :2].any() and not chunked[2][:, 2].any()


@pytest.mark.parametrize("model", PLAIN_MODELS)
def test_any_thread_split_gives_the_same_bits(model):
    """Each slab's contact list is one thread's, in one order: 2, 3 and 5 blocks give the serial sums exactly."""
    pp = table(model, True)
    b = bed(False, True)
    serial = sums(b, pp, False)
    for nthreads in (2, 3, 5):
        split = sums(b, pp, False, nthreads=nthreads)
        for a, x in zip(serial, split):
            np.testing.assert_array_equal(x, a)


@pytest.mark.parametrize("flat", [False, True], ids=["3d", "flat"])
def test_a_table_of_two_models(flat):
    """Hertz–Mindlin between like species, a linear spring between unlike ones: each contact gets its own
    model's law in the same vector code (each contact's model code is read from its row of the chunk)."""
    pp = table("hertz_mindlin", True)
    pp[0, 1] = pp[1, 0] = law("linear_spring_dashpot", restitution=0.5, friction=0.6).pack(None, None)
    b = bed(flat, True)
    expected, chunked = reference(b, pp), sums(b, pp, flat)
    agree(expected, chunked)
    # the linear law is what acts between unlike species: its forces differ from Hertz's by far
    hertz = pp.copy()
    hertz[0, 1] = hertz[1, 0] = hertz[0, 0]
    assert np.abs(sums(b, hertz, flat)[0] - chunked[0]).max() > 0.1 * np.abs(chunked[0]).max()


def test_a_contact_that_ends_resets_its_spring_between_steps():
    """Within one ``advance`` call the chunk path reads a spring only where the pair touched at the last step
    (``touch``): a pair that separates has its spring zeroed at the next step, one that never touched keeps
    its zero."""
    pp = table("hertz_mindlin", False)
    b = bed(False, False)
    t0 = touching(b)
    block = np.array([0, b["slab_start"].shape[0] - 1])
    work = C.make_work(pp, b["row_start"], b["hist"], b["slab_start"], b["slab_members"], 1)
    assert work[4].all(), "every random spring counts as set"
    f, c, h = np.zeros((600, 3)), np.zeros((600, 3)), b["hist"].copy()
    args = (b["radius"], b["mass"], b["species"], pp, b["row_start"], b["partner"], b["slab_start"], b["slab_members"])
    K.pair_forces(b["pos"], b["vel"], b["omega"], *args, h, 1e-5, True, f, c, block, None, work)
    np.testing.assert_array_equal(work[4].astype(bool), t0)
    assert h[t0].all(axis=1).any() and not h[~t0].any()
    # spread the bed by 2 %: some contacts end
    pos = b["pos"] * 1.02
    i = np.repeat(np.arange(600), np.diff(b["row_start"]))
    j = b["partner"]
    t1 = np.linalg.norm(pos[i] - pos[j], axis=1) < b["radius"][i] + b["radius"][j]
    assert (t0 & ~t1).sum() > 100
    f[:] = 0.0
    c[:] = 0.0
    K.pair_forces(pos, b["vel"], b["omega"], *args, h, 1e-5, True, f, c, block, None, work)
    assert not h[~t1].any(), "ended contacts' springs are zero"
    assert h[t1].any(axis=1).all()
    np.testing.assert_array_equal(work[4].astype(bool), t1)


def test_the_law_compiles_to_vector_code():
    """The point of the chunks: LLVM vectorises the law's loop (square roots on vectors of doubles). A data-
    dependent branch or a loop in a model's ``coefficients`` would silently turn it back into scalar code,
    about 1.4× slower on the bench bed. Compiled afresh here (a cached kernel carries no IR)."""
    import re

    import numba

    law = numba.njit(error_model="numpy", fastmath=True)(C._law.py_func)
    law(1, np.zeros(C.N_G * C.CHUNK), np.zeros(C.N_O * C.CHUNK), 1e-5, True)
    ir = law.inspect_llvm(law.signatures[0])
    assert re.search(r"llvm\.sqrt\.v[248]f64", ir), "the chunk law is not vectorised"
