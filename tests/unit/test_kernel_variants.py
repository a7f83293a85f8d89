"""A run compiles only the kernel variants it uses (``_softsphere_kernels.advance``, ``_pair_kernels.chunk_run``).

The pair and gather loops come in variants: a flat 2D bed or not, a box with periodic sides or not, contact laws
with rolling friction or adhesion or not. The dispatchers choose by ``flat is None``, ``period is None`` and
``laws is None``, which Numba decides when it compiles (dead
branch pruning) where the argument's type is None or a literal constant (``Literal[bool](True)``, what
``advance_flat`` passes), and so leaves the other variants out of the compilation: they cost tens of seconds
of a first run (``benchmarks/compile_time.py``). A test written as ``if flat:`` would still give the same
forces, so the forces cannot show a lapse; here each variant is replaced by a stub, those that must be left
out by one that fails to compile, and a fresh copy of the dispatcher is compiled for each combination
(no cache: a second or so each).
"""
from __future__ import annotations

import numpy as np
import pytest
from numba import njit, typeof, types

from fluidem.particles import _pair_kernels as P
from fluidem.particles import _softsphere_kernels as K


@njit
def _used(*args):
    return 0


@njit
def _left_out(*args):
    return name_that_is_not_defined  # noqa: F821 - fails when typed: compiled only where a branch calls it


FLAT, NOT_FLAT = types.literal(True), types.none
PERIOD, NO_PERIOD = typeof(np.zeros(3)), types.none
SLABS = {"_slab": (NOT_FLAT, NO_PERIOD), "_slab_flat": (FLAT, NO_PERIOD),
         "_slab_periodic": (NOT_FLAT, PERIOD), "_slab_flat_periodic": (FLAT, PERIOD)}


def _chunk_run_types(flat, period, laws=types.boolean):
    work = (np.zeros((1, 4), np.uint32), np.zeros((1, 4), np.uint32), np.zeros((1, 4)), np.zeros((1, 4)),
            np.zeros(4, np.uint8), True, False)
    args = [0, 2, None, (np.zeros((2, 3)),), np.zeros((1, 1, 4)), (np.zeros(2, np.int64),), np.zeros((2, 3)), 1e-5,
            True, np.zeros((2, 3)), np.zeros((2, 3)), work, np.int64(0), None, None]
    sig = [typeof(a) for a in args]
    sig[2], sig[13], sig[14] = flat, period, laws
    return tuple(sig)


@pytest.mark.parametrize("flat", [FLAT, NOT_FLAT], ids=["flat", "not-flat"])
@pytest.mark.parametrize("period", [NO_PERIOD, PERIOD], ids=["no-period", "period"])
def test_chunk_run_compiles_only_the_slab_variants_of_its_bed(monkeypatch, flat, period):
    """None leaves out the variants of the other kind; a literal True those of beds that are not flat; a
    run-time array (a periodic box) keeps both periodic and non-periodic slabs (its test is made when it runs)."""
    for name, (f, p) in SLABS.items():
        used = f == flat and (p == period or period == PERIOD)
        monkeypatch.setattr(P, name, _used if used else _left_out)
    njit(P.chunk_run.py_func).compile(_chunk_run_types(flat, period))


def test_a_run_time_flag_would_compile_every_variant(monkeypatch):
    """The stubs catch a lapse: with ``flat`` a run-time bool, the not-flat slab is compiled too."""
    for name in SLABS:
        monkeypatch.setattr(P, name, _used if name == "_slab_flat" else _left_out)
    with pytest.raises(Exception, match="name_that_is_not_defined"):
        njit(P.chunk_run.py_func).compile(_chunk_run_types(types.boolean, NO_PERIOD))


@pytest.mark.parametrize("flat", [FLAT, NOT_FLAT], ids=["flat", "not-flat"])
def test_the_gather_compiles_only_its_variant(monkeypatch, flat):
    """``_gather_parallel`` (threads) and ``gather_forces`` (one thread) call ``_gather_range_flat`` or
    ``_gather_range``, never both."""
    monkeypatch.setattr(K, "_gather_range_flat", _used if flat == FLAT else _left_out)
    monkeypatch.setattr(K, "_gather_range", _left_out if flat == FLAT else _used)
    sig = [types.float64] * 29 + [typeof(np.zeros(3, np.int64)), flat, types.boolean]
    njit(parallel=True)(K._gather_parallel.py_func).compile(tuple(sig))
    monkeypatch.setattr(K, "_gather_parallel", _used)
    monkeypatch.setattr(K, "walls_now", njit(lambda motion, point0, t: np.zeros((1, 6))))
    array = typeof(np.zeros((1, 6)))
    sig = [array] + [types.float64] * 6 + [array] * 2 + [types.float64] * 22 + [typeof(np.zeros(3, np.int64)), flat,
                                                                               types.boolean]
    njit(K.gather_forces.py_func).compile(tuple(sig))


def test_without_extended_laws_the_slabs_and_the_gather_leave_the_full_law_out(monkeypatch):
    """``laws`` None (no rolling friction or adhesion in the run): the slab compiles without ``_law_ext`` and the
    particle gather without ``contact_force_full`` (both replaced by failing stubs); with a run-time value both
    laws are kept (the table's flags choose as the run goes)."""
    monkeypatch.setattr(P, "_law_ext", _left_out)
    njit(P._slab_flat.py_func).compile(_slab_types(types.none))
    with pytest.raises(Exception, match="name_that_is_not_defined"):
        njit(P._slab_flat.py_func).compile(_slab_types(types.boolean))
    monkeypatch.setattr(K, "contact_force_full", _left_out)
    njit(K._gather_range_flat.py_func).compile(_gather_range_types(types.none))
    with pytest.raises(Exception, match="name_that_is_not_defined"):
        njit(K._gather_range_flat.py_func).compile(_gather_range_types(types.boolean))


def _slab_types(laws):
    """The argument types of ``_slab_flat`` for the engine's arrays, with ``laws`` of the given type."""
    import fluidem as fd
    from fluidem.particles.softsphere import SoftSphereEngine

    eng = SoftSphereEngine(fd.load_case("pour").with_overrides({"particles.species.0.count": 20}))
    st = eng.state
    state = (st.position, st.velocity, st.omega, st.radius, st.mass, st.species)
    lists = (eng.row_start, eng.partner, eng.slab_start, eng.slab_members)
    cbuf, ibuf, G, out, touch, uniform, ext = P.make_work(eng.pp, eng.row_start, eng.hist, eng.slab_start,
                                                          eng.slab_members, 1)
    args = (0, state, eng.pp, lists, eng.hist, eng.dt, True, st.force, st.torque, touch, cbuf[0], ibuf[0], G[0],
            out[0], uniform, None, ext, np.zeros(3))
    sig = [typeof(a) for a in args]
    sig[15] = laws
    return tuple(sig)


def _gather_range_types(laws):
    """The argument types of ``_gather_range_flat`` for the engine's arrays, with ``laws`` of the given type."""
    import fluidem as fd
    from fluidem.particles.softsphere import SoftSphereEngine

    eng = SoftSphereEngine(fd.load_case("pour").with_overrides({"particles.species.0.count": 20}))
    st = eng.state
    args = (0, st.n, st.position, st.velocity, st.omega, st.radius, st.mass, st.species, eng.pw, np.zeros((4, 6)),
            eng.wall_normal, K.wall_axes(eng.wall_normal), eng.wall_hist, eng.wall_touch, eng.near_count,
            eng.near_wall, eng.gravity, eng.ext_force, eng.ext_damping, False, True, st.force, st.torque, eng.dt,
            st.force, st.torque, eng.inv_mass, eng.inv_inertia, 0, eng.ref_pos, 1.0, None)
    sig = [typeof(a) for a in args]
    sig[-1] = laws
    return tuple(sig)


def test_the_engine_passes_none_for_what_its_run_lacks(tiny_bed_case):
    """``SoftSphereEngine._variants``: flat 2D or not, and None for no periodic side, no wall shape and no
    contact law with rolling friction or adhesion."""
    import fluidem as fd
    from fluidem.particles.softsphere import SoftSphereEngine

    flat, period, shapes, laws = SoftSphereEngine(fd.load_case("pour"))._variants()
    assert flat is True and period is None and shapes is None and laws is None
    flat, period, shapes, laws = SoftSphereEngine(tiny_bed_case(n=20))._variants()
    assert flat is False and period is None and shapes is None and laws is None
    case = fd.load_case("pour").with_overrides({"walls.0.periodic": ["x"], "particles.species.0.count": 50})
    flat, period, shapes, laws = SoftSphereEngine(case)._variants()
    assert flat is True and period.tolist() == [0.096, 0.0, 0.0] and shapes is None and laws is None
    case = fd.load_case("drum-3d").with_overrides({"particles.species.0.count": 20})
    flat, period, shapes, laws = SoftSphereEngine(case)._variants()
    assert flat is False and period is None and shapes[0].shape[0] > 0 and laws is None
    case = fd.load_case("drum-3d-cohesive").with_overrides({"particles.species.0.count": 20})
    assert SoftSphereEngine(case)._variants()[3] is True  # JKR between the particles


def test_pair_forces_refuses_a_false_flat(tiny_bed_case):
    """``flat`` is None or True: False, which the branches would take for a flat bed, is refused."""
    from fluidem.particles.softsphere import SoftSphereEngine

    eng = SoftSphereEngine(tiny_bed_case(n=20))
    st = eng.state
    with pytest.raises(ValueError, match="flat must be None"):
        K.pair_forces(st.position, st.velocity, st.omega, st.radius, st.mass, st.species, eng.pp, eng.row_start,
                      eng.partner, eng.slab_start, eng.slab_members, eng.hist.copy(), eng.dt, True,
                      np.zeros_like(st.force), np.zeros_like(st.force), np.array([0, eng.slab_start.shape[0] - 1]),
                      False)


def test_the_hard_sphere_step_without_periodic_sides_compiles_no_periodic_list(monkeypatch):
    """The event-driven engine passes ``period`` None in a box without periodic sides, and its ``advance`` then
    leaves the periodic list build and the wrap out (a copy compiled with those two as failing stubs runs)."""
    import fluidem as fd
    from fluidem.particles import _hardsphere_kernels as H
    from fluidem.particles.hardsphere import HardSphereEngine

    case = fd.load_case("pour").with_overrides({
        "particles.contact": {"model": "hard_sphere", "restitution": 0.9, "friction": 0.3},
        "particles.species.0.count": 30, "time.dt": 1e-4})
    eng = HardSphereEngine(case)
    monkeypatch.setattr(H, "build_neighbours_periodic", _left_out)
    monkeypatch.setattr(H, "_wrap", _left_out)
    monkeypatch.setattr(H, "advance", njit(error_model="numpy")(H.advance.py_func))
    eng.advance(2)
    assert eng.steps == 2
