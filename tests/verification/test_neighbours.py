"""Cell-list + Verlet-list pairs against the O(N²) brute force, compared as exact sets.

``build_pairs`` must list every pair with |r_i − r_j| < a_i + a_j + skin exactly once and
no other (both sides evaluate the same floating-point expression, so equality is exact);
pairs are compared unordered, as the owner of a pair is the particle in the lower slab.
``build_pairs`` finds the pairs of chunks of the particles (in cell order) in parallel, each
into a buffer of its own that grows when too small, so it is tested with every thread (``all_threads``) and with a skin so large
that the first buffers overflow.
The engine's list, rebuilt when a particle has moved more than skin/2, must always hold
every pair in contact.
"""
from __future__ import annotations

import numpy as np
import pytest

from fluidem.particles._neighbours_kernels import build_pairs, carry_history, contacts_first

from _helpers.neighbours import brute_force_pairs, random_packing


def csr_pairs(row_start, partner):
    """The listed pairs as unordered (min, max) tuples; a pair listed twice is an error."""
    rows = np.repeat(np.arange(row_start.shape[0] - 1), np.diff(row_start))
    pairs = set(zip(np.minimum(rows, partner).tolist(), np.maximum(rows, partner).tolist()))
    assert len(pairs) == partner.shape[0], "a pair is listed twice"
    return pairs


def brute_pairs(pos, radius, skin):
    return {(int(i), int(j)) for i, j in brute_force_pairs(pos, radius, skin)}


def check_lists(pos, radius, skin, dim2):
    """build_pairs against brute force, and the invariants the force loops rely on."""
    row_start, partner, slab_start, slab_members = build_pairs(pos, radius, skin, dim2)
    n = pos.shape[0]
    assert row_start.shape == (n + 1,) and row_start[0] == 0 and row_start[-1] == partner.shape[0]
    fast = csr_pairs(row_start, partner)
    expected = brute_pairs(pos, radius, skin)
    assert fast == expected, (f"missing {sorted(expected - fast)[:5]}, extra {sorted(fast - expected)[:5]} "
                              f"of {len(expected)} pairs")
    owner = np.repeat(np.arange(n), np.diff(row_start))
    assert np.all(partner != owner)
    # rows sorted (the engine then puts the touching pairs first: contacts_first)
    for i in range(n):
        assert np.all(np.diff(partner[row_start[i]:row_start[i + 1]]) > 0)
    # slabs: every particle in exactly one; a pair joins its owner's slab to the same or the next slab
    # (the parallel force loop runs even and odd slabs in turn and relies on this to avoid races)
    assert slab_start[0] == 0 and slab_start[-1] == n
    assert np.array_equal(np.sort(slab_members), np.arange(n))
    slab = np.empty(n, np.int64)
    for s in range(slab_start.shape[0] - 1):
        slab[slab_members[slab_start[s]:slab_start[s + 1]]] = s
    step = slab[partner] - slab[owner]
    assert np.all((step == 0) | (step == 1)), "a pair spans non-adjacent slabs or is owned by the upper slab"
    assert np.all(partner[step == 0] > owner[step == 0]), "within a slab the lower index owns the pair"
    return len(expected)


@pytest.mark.parametrize("dim2", [False, True], ids=["3d", "2d"])
@pytest.mark.parametrize("seed", [1, 2, 3])
@pytest.mark.parametrize("skin_in_radii", [0.0, 0.1, 0.5, 2.0])
def test_cell_list_equals_brute_force(all_threads, seed, dim2, skin_in_radii):
    pos, radius = random_packing(seed, 600, dim2)
    npairs = check_lists(pos, radius, skin_in_radii * 1e-3, dim2)
    assert npairs > 200  # the packing is dense enough for the comparison to mean something


@pytest.mark.parametrize("dim2", [False, True], ids=["3d", "2d"])
def test_cell_list_with_a_stray_particle(all_threads, dim2):
    """A particle far away makes the cell grid grow coarser; pairs must not change."""
    pos, radius = random_packing(4, 400, dim2)
    pos = np.vstack([pos, [[1.0, -2.0, pos[0, 2]]] if dim2 else [[1.0, -2.0, 3.0]]])
    radius = np.append(radius, 1e-3)
    assert check_lists(pos, radius, 0.2e-3, dim2) > 150


def test_cell_list_degenerate_layouts():
    """All particles on a line (zero extent in two axes), coincident particles, one particle."""
    n = 40
    line = np.column_stack([np.linspace(0.0, 0.05, n), np.zeros(n), np.zeros(n)])
    check_lists(line, np.full(n, 0.7e-3), 0.1e-3, False)
    check_lists(np.zeros((5, 3)), np.full(5, 1e-3), 0.0, False)
    check_lists(np.zeros((1, 3)), np.full(1, 1e-3), 0.1e-3, False)


@pytest.mark.parametrize("dim2", [False, True], ids=["3d", "2d"])
def test_contacts_first_keeps_every_pair_with_its_history(all_threads, dim2):
    """Each row after contacts_first: the same partners with the same springs, the touching pairs first,
    each part in its former (ascending) order; rows with no contact or no far pair unchanged. On every thread:
    the rows are reordered in work items of ROWS_PER_ITEM (600 rows: three)."""
    rng = np.random.default_rng(5)
    pos, radius = random_packing(3, 600, dim2, solid_fraction=0.5)
    rs, partner, _, _ = build_pairs(pos, radius, 0.5e-3, dim2)
    hist = rng.normal(0.0, 1e-6, (partner.shape[0], 3))
    p0, h0 = partner.copy(), hist.copy()
    contacts_first(pos, radius, rs, partner, hist)
    mixed = 0
    for i in range(pos.shape[0]):
        a, b = rs[i], rs[i + 1]
        d = pos[i] - pos[p0[a:b]]
        touch = np.einsum("ij,ij->i", d, d) < (radius[i] + radius[p0[a:b]]) ** 2
        want = np.concatenate([np.flatnonzero(touch), np.flatnonzero(~touch)])
        np.testing.assert_array_equal(partner[a:b], p0[a:b][want])
        np.testing.assert_array_equal(hist[a:b], h0[a:b][want])
        mixed += bool(touch.any() and not touch.all() and not touch[:touch.sum()].all())
    assert mixed > 50, "too few rows with their contacts out of front to test the reordering"


@pytest.mark.parametrize("dim2", [False, True], ids=["3d", "2d"])
@pytest.mark.parametrize("contact_order", [False, True], ids=["sorted", "contacts-first"])
def test_history_follows_its_pair_across_a_rebuild(all_threads, dim2, contact_order):
    """carry_history against a dictionary: a persisting pair keeps its tangential spring exactly; a pair
    whose owner changed gets it negated (it is kept relative to the owner: n and v_i − v_j flip); a new
    pair starts at zero. Particles move a little and the outermost one far, so slab boundaries shift and
    many pairs change owner. The old list as build_pairs leaves it (rows sorted) and as the engine keeps
    it (touching pairs first, contacts_first)."""
    rng = np.random.default_rng(21)
    skin = 0.3e-3
    pos, radius = random_packing(8, 500, dim2)
    rs0, partner0, _, _ = build_pairs(pos, radius, skin, dim2)
    owner0 = np.repeat(np.arange(pos.shape[0]), np.diff(rs0))
    hist0 = rng.normal(0.0, 1e-6, (partner0.shape[0], 3))
    if contact_order:
        contacts_first(pos, radius, rs0, partner0, hist0)
        owner0 = np.repeat(np.arange(pos.shape[0]), np.diff(rs0))
    old = {(int(i), int(j)): hist0[p] for p, (i, j) in enumerate(zip(owner0, partner0))}

    kept = flipped = new = 0
    for stretch in (3e-3, 7e-3, 11e-3):
        moved = pos + rng.uniform(-1.0, 1.0, pos.shape) * 0.2 * skin
        if dim2:
            moved[:, 2] = pos[:, 2]
        axis = int(np.argmax(np.ptp(pos[:, :2] if dim2 else pos, axis=0)))
        moved[np.argmax(moved[:, axis]), axis] += stretch  # stretch the extent along the slab axis
        rs1, partner1, _, _ = build_pairs(moved, radius, skin, dim2)
        hist1 = carry_history(rs0, partner0, hist0, rs1, partner1)
        owner1 = np.repeat(np.arange(pos.shape[0]), np.diff(rs1))
        for p, (i, j) in enumerate(zip(owner1.tolist(), partner1.tolist())):
            if (i, j) in old:
                np.testing.assert_array_equal(hist1[p], old[(i, j)])
                kept += 1
            elif (j, i) in old:
                np.testing.assert_array_equal(hist1[p], -old[(j, i)])
                flipped += 1
            else:
                np.testing.assert_array_equal(hist1[p], 0.0)
                new += 1
    assert kept > 300 and flipped > 10 and new > 0, (kept, flipped, new)


@pytest.mark.parametrize("dimensions", [3, 2])
def test_engine_list_always_holds_the_contacts(make_engine, contact_law, dimensions):
    """During a run the Verlet list (rebuilt at skin/2 displacement) contains every touching pair."""
    rng = np.random.default_rng(11)
    n = 150
    pos, radius = random_packing(5, n, dimensions == 2, solid_fraction=0.15)
    # make the start non-overlapping: shrink radii to half the nearest distance where needed
    d = np.linalg.norm(pos[:, None, :] - pos[None, :, :], axis=2) + np.eye(n)
    radius = np.minimum(radius, 0.49 * d.min(axis=1))
    vel = rng.normal(0.0, 0.5, (n, 3))
    if dimensions == 2:
        vel[:, 2] = 0.0
    eng = make_engine(pos, 2 * radius, vel, contact=contact_law("linear_spring_dashpot", restitution=0.8),
                      dimensions=dimensions, skin=0.2e-3)
    checked = 0
    for _ in range(300):
        eng.advance(20)
        st = eng.state
        touching = brute_pairs(st.position, st.radius, 0.0)
        listed = csr_pairs(eng.row_start, eng.partner)
        assert touching <= listed, f"pairs in contact but not listed: {sorted(touching - listed)[:5]}"
        checked += len(touching)
    assert eng.rebuilds > 10 and checked > 100  # the list was rebuilt often and contacts occurred


@pytest.mark.parametrize("model", ["linear_spring_dashpot", "hertz_mindlin"])
def test_rebuild_frequency_does_not_change_the_dynamics(tiny_bed_case, model):
    """A frictional bed hitting the floor, run with a thin skin (a rebuild every ~15 steps, every contact
    spans rebuilds, pairs change owner as particles cross slabs) and a thick one (a handful of rebuilds).

    The tangential springs must survive each rebuild unchanged, so the runs differ only by round-off
    from a different summation order (the two lists order the contacts differently). Measured over 2000
    steps (126 rebuilds of the thin list): identical to the last bit for ~750 steps, then round-off that the
    chaotic collisions amplify about tenfold per 250 steps: 1.8e-12 d (Hertz–Mindlin) and 8e-14 d (linear)
    at 2000 steps, 1e-9 d at 3000, so the comparison is made at 2000. Tolerance 1e-10 d in position and
    1e-8 of the largest spin: a lost or sign-flipped tangential history changes the friction force by
    O(μ F_n) and the spins by O(1).
    """
    from fluidem.particles.softsphere import SoftSphereEngine

    def run(skin_in_diameters):
        case = tiny_bed_case(n=150, model=model, restitution=0.5, friction=0.5)
        d = case.particles.species[0].diameter
        case = case.with_overrides({"neighbours.skin": skin_in_diameters * d,
                                    "particles.placement.velocity": [0.3, 0.2, -0.5]})
        eng = SoftSphereEngine(case)
        eng.advance(2000)
        return eng, d

    thin, d = run(0.02)
    thick, _ = run(1.0)
    assert thin.rebuilds > 100 and thick.rebuilds < 10
    spin = np.abs(thin.state.omega).max()
    assert spin > 10.0  # friction has spun the particles up [rad/s]
    assert np.abs(thin.state.position - thick.state.position).max() < 1e-10 * d
    assert np.abs(thin.state.omega - thick.state.omega).max() < 1e-8 * spin
