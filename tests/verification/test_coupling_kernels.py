"""The compiled coupling (coupling/_exchange_kernels, _voidage_kernels.map_solids) against a NumPy reference.

The reference below is the NumPy orchestration the kernels replaced: bilinear interpolation of
the wall-extended staggered fields (Hoomans 1996 eqs 40-41), cell β by bincount (Sun 2007
eq. 33), particle force from the vectorised ``DragLaw.particle_force`` (eq. 29) minus V_p ∇p
(eq. 28), and the particle → grid map (Sun 2007 eqs 34-35, Hoomans 1996 §3.4, eqs 49-50).
Random polydisperse particles (some on cell faces, some outside the domain) over a random gas
state; every drag law and every voidage mapping; equal to 1e-12 relative (in practice to the bit).
The particles have many sizes, so the drag is the polydisperse one (DEM book 2012 eqs 10-12): the
reference takes 1/D̄ per cell by bincount and y = d/D̄ of the particle's cell (cell β) or
interpolated as ε (particle forces).
"""
from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

import fluidem as fd
from fluidem.coupling import drag as D
from fluidem.coupling._voidage_kernels import disc_rect_area
from fluidem.coupling.exchange import GasCoupling
from fluidem.coupling.voidage import EQ49_FACTOR, SolidsMap
from fluidem.gas.solver import GasState

from _helpers.coupling import MAPPINGS, random_gas, random_particles

RTOL = 1e-12


# ------------------------------------------------------------------ NumPy reference
def ref_nodes(grid, location):
    """(x nodes, y nodes, shift x, shift y) of a field extended to the walls."""
    xc = np.concatenate(([0.0], grid.x_centres, [grid.size[0]]))
    yc = np.concatenate(([0.0], grid.y_centres, [grid.size[1]]))
    return {"centre": (xc, yc, 0.5, 0.5), "x_face": (grid.x_faces, yc, 0.0, 0.5),
            "y_face": (xc, grid.y_faces, 0.5, 0.0)}[location]


def ref_extend(f, pad_x, pad_y, linear):
    """Append one boundary node per side: copy of the nearest, or 1.5 f0 − 0.5 f1; x first, then y."""
    def edges(first, second):
        return (1.5 * first - 0.5 * second) if (linear and second is not None) else first
    if pad_x:
        n = f.shape[0]
        f = np.concatenate((edges(f[0], f[1] if n > 1 else None)[None], f,
                            edges(f[-1], f[-2] if n > 1 else None)[None]), axis=0)
    if pad_y:
        n = f.shape[1]
        f = np.concatenate((edges(f[:, 0], f[:, 1] if n > 1 else None)[:, None], f,
                            edges(f[:, -1], f[:, -2] if n > 1 else None)[:, None]), axis=1)
    return f


def ref_locate(x, xs, inv_d, shift):
    k = np.clip(np.floor(x * inv_d + shift).astype(np.int64), 0, xs.size - 2)
    t = np.clip((x - xs[k]) / (xs[k + 1] - xs[k]), 0.0, 1.0)
    return k, t


def ref_interpolate(grid, field, pos, location, linear):
    """Hoomans 1996 eqs 40-41 on the wall-extended nodes; positions outside are clamped."""
    xs, ys, sx, sy = ref_nodes(grid, location)
    ext = ref_extend(np.asarray(field, float), location != "x_face", location != "y_face", linear)
    i, tx = ref_locate(pos[:, 0], xs, 1.0 / grid.dx, sx)
    j, ty = ref_locate(pos[:, 1], ys, 1.0 / grid.dy, sy)
    return ((1.0 - tx) * (1.0 - ty) * ext[i, j] + tx * (1.0 - ty) * ext[i + 1, j]
            + tx * ty * ext[i + 1, j + 1] + (1.0 - tx) * ty * ext[i, j + 1])


def ref_pressure_gradient(grid, p):
    """Centred differences on interior faces, wall faces copy their neighbour."""
    gx = np.zeros(grid.u_shape)
    gy = np.zeros(grid.v_shape)
    gx[1:-1] = np.diff(p, axis=0) / grid.dx
    gy[:, 1:-1] = np.diff(p, axis=1) / grid.dy
    if gx.shape[0] >= 3:
        gx[0], gx[-1] = gx[1], gx[-2]
    if gy.shape[1] >= 3:
        gy[:, 0], gy[:, -1] = gy[:, 1], gy[:, -2]
    return gx, gy


def ref_inv_dbar(grid, pos, radius):
    """1/D̄ per cell (DEM book 2012 eq. 10): Σ V/d / Σ V over the centres in the cell; the bed's in empty cells."""
    nx, ny = grid.shape
    d = 2.0 * radius
    volume = math.pi / 6.0 * d**3
    i = np.clip(np.floor(pos[:, 0] / grid.dx).astype(np.int64), 0, nx - 1)
    j = np.clip(np.floor(pos[:, 1] / grid.dy).astype(np.int64), 0, ny - 1)
    s = np.bincount(i * ny + j, weights=volume / d, minlength=nx * ny).reshape(nx, ny)
    v = np.bincount(i * ny + j, weights=volume, minlength=nx * ny).reshape(nx, ny)
    return np.where(v > 0.0, s / np.where(v > 0.0, v, 1.0), (volume / d).sum() / volume.sum())


def ref_y(cpl, pos, radius, at_cell):
    """y = d/D̄ of each particle (eq. 11): 1/D̄ of its cell, or interpolated to it; 1 without the mixture rule."""
    if cpl.polydisperse != "sauter_y2":
        return np.ones_like(radius)
    grid = cpl.grid
    inv = ref_inv_dbar(grid, pos, radius)
    if at_cell:
        nx, ny = grid.shape
        i = np.clip((pos[:, 0] / grid.dx).astype(np.int64), 0, nx - 1)
        j = np.clip((pos[:, 1] / grid.dy).astype(np.int64), 0, ny - 1)
        return 2.0 * radius * inv[i, j]
    return 2.0 * radius * ref_interpolate(grid, inv, pos, "centre", False)


def ref_particle_forces(cpl, pos, vel, radius):
    grid, gs = cpl.grid, cpl.state
    d = 2.0 * radius
    volume = math.pi / 6.0 * d**3
    ug = np.zeros_like(vel)
    ug[:, 0] = ref_interpolate(grid, gs.u, pos, "x_face", True)
    ug[:, 1] = ref_interpolate(grid, gs.v, pos, "y_face", True)
    eps = np.clip(ref_interpolate(grid, gs.voidage, pos, "centre", False), cpl.mapping.minimum_voidage, 1.0)
    rho = ref_interpolate(grid, gs.rho, pos, "centre", False)
    force = cpl.drag.particle_force(eps, ug, vel, d, rho, cpl.solver.props.viscosity,
                                    ref_y(cpl, pos, radius, False))  # Sun 2007 eq. 29, DEM book 2012 eq. 12
    if cpl.options.pressure_gradient_force:  # eq. 28
        gx, gy = ref_pressure_gradient(grid, gs.p)
        force[:, 0] -= volume * ref_interpolate(grid, gx, pos, "x_face", False)
        force[:, 1] -= volume * ref_interpolate(grid, gy, pos, "y_face", False)
    if cpl.engine.dim2:
        force[:, 2] = 0.0
    return force


def ref_cell_beta(cpl, pos, radius, voidage, su, sv):
    grid, gs = cpl.grid, cpl.state
    nx, ny = grid.shape
    d = 2.0 * radius
    slip = np.hypot(0.5 * (gs.u[:-1] + gs.u[1:]) - su, 0.5 * (gs.v[:, :-1] + gs.v[:, 1:]) - sv)
    i = np.clip((pos[:, 0] / grid.dx).astype(np.int64), 0, nx - 1)
    j = np.clip((pos[:, 1] / grid.dy).astype(np.int64), 0, ny - 1)
    coef = cpl.drag.gas_side().beta_per_solids(voidage[i, j], slip[i, j], d, gs.rho[i, j], cpl.solver.props.viscosity,
                                               ref_y(cpl, pos, radius, True)) * (math.pi / 6.0 * d**3)
    return np.bincount(i * ny + j, weights=coef, minlength=nx * ny).reshape(nx, ny) / grid.cell_volume


def ref_smooth(f, grid, width):
    total = 0.5 * width * width
    steps = max(1, math.ceil(total * (1.0 / grid.dx**2 + 1.0 / grid.dy**2) / 0.4))
    rx, ry = total / steps / grid.dx**2, total / steps / grid.dy**2
    f = f.copy()
    for _ in range(steps):
        p = np.pad(f, 1, mode="edge")  # zero flux: the ghost equals its neighbour
        f = f + rx * ((p[:-2, 1:-1] - f) + (p[2:, 1:-1] - f)) + ry * ((p[1:-1, :-2] - f) + (p[1:-1, 2:] - f))
    return f


def ref_map(mapping, grid, pos, radius, vel):
    nx, ny = grid.shape
    d = 2.0 * radius
    volume = math.pi / 6.0 * d**3
    ci = np.clip(np.floor(pos[:, 0] * (1.0 / grid.dx)).astype(np.int64), 0, nx - 1)
    cj = np.clip(np.floor(pos[:, 1] * (1.0 / grid.dy)).astype(np.int64), 0, ny - 1)

    def centroid(w):
        k = ci * ny + cj
        return [np.bincount(k, weights=a, minlength=nx * ny).reshape(nx, ny)
                for a in (w, w * vel[:, 0], w * vel[:, 1])]

    if mapping.method == "centroid":
        dep, wvx, wvy = centroid(volume)  # Sun 2007 eq. 34
    else:  # every (particle, cell) disc area, in particle order (Hoomans 1996 §3.4)
        r = 0.5 * d
        scale = np.ones_like(d) if mapping.method == "area" else volume / (math.pi * r * r)
        dep, wvx, wvy = (np.zeros((nx, ny)) for _ in range(3))
        for p in range(len(d)):
            for i in range(max(math.floor((pos[p, 0] - r[p]) / grid.dx), 0),
                           min(math.floor((pos[p, 0] + r[p]) / grid.dx), nx - 1) + 1):
                for j in range(max(math.floor((pos[p, 1] - r[p]) / grid.dy), 0),
                               min(math.floor((pos[p, 1] + r[p]) / grid.dy), ny - 1) + 1):
                    a = disc_rect_area(pos[p, 0], pos[p, 1], r[p], i * grid.dx, (i + 1) * grid.dx,
                                       j * grid.dy, (j + 1) * grid.dy)
                    if a > 0.0:
                        w = scale[p] * a
                        dep[i, j] += w
                        wvx[i, j] += w * vel[p, 0]
                        wvy[i, j] += w * vel[p, 1]
    wsum = dep.copy()
    frac = dep / (grid.dx * grid.dy if mapping.method == "area" else grid.cell_volume)
    if mapping.velocity_weighting == "number":  # Hoomans 1996 eq. 50
        wsum, wvx, wvy = centroid(np.ones_like(d))
    if mapping.smoothing_width > 0.0:
        frac = ref_smooth(frac, grid, mapping.smoothing_width)
    eps = 1.0 - frac
    if mapping.to_3d:  # Hoomans 1996 eq. 49
        eps = 1.0 - EQ49_FACTOR * np.clip(1.0 - eps, 0.0, None) ** 1.5
    low = eps < mapping.minimum_voidage
    safe = np.where(wsum > 0.0, wsum, 1.0)
    return SolidsMap(np.where(low, mapping.minimum_voidage, eps), np.where(wsum > 0.0, wvx / safe, 0.0),
                     np.where(wsum > 0.0, wvy / safe, 0.0), int(np.count_nonzero(low)))


# ------------------------------------------------------------------ set-up
def coupling(drag, mapping, pgf=True, dim2=True, n=600, seed=11, random_state=True, exchange="cell_beta"):
    """GasCoupling of the tsuji-jet-background case over a stand-in engine holding random particles (no −V_p∇p for a
    law that gives the total gas force, which the case validation requires)."""
    pgf = pgf and not D.drag_laws.get(drag).total_force
    case = fd.load_case("tsuji-jet-background").with_overrides({"coupling.drag": drag, "coupling.voidage": mapping,
                                                      "coupling.pressure_gradient_force": pgf,
                                                      "coupling.momentum_exchange": exchange})
    grid_probe = case.gas.build(case.gravity).grid
    pos, radius, vel = random_particles(grid_probe, n, seed)
    state = SimpleNamespace(position=pos, radius=radius, velocity=vel, force=np.zeros_like(pos), n=n)
    engine = SimpleNamespace(state=state, dt=1e-5, steps=0, time=0.0, dim2=dim2, ext_force=np.zeros_like(pos))
    cpl = GasCoupling(case, engine)
    if random_state:
        cpl.state = random_gas(cpl.grid, seed + 1)
    return cpl


def worst(got, ref):
    """Largest |got − ref| relative to max |ref| (0 for two zero arrays)."""
    scale = np.max(np.abs(ref))
    return float(np.max(np.abs(got - ref)) / scale) if scale > 0 else float(np.max(np.abs(got)))


def check(got, ref, what):
    assert got.shape == ref.shape, what
    assert np.array_equal(np.isnan(got), np.isnan(ref)), what
    w = worst(got, ref)
    assert w <= RTOL, f"{what}: worst relative difference {w:.3g}"
    np.testing.assert_allclose(got, ref, rtol=RTOL, atol=RTOL * np.max(np.abs(ref)), err_msg=what)
    return w


# ------------------------------------------------------------------ tests
@pytest.mark.parametrize("mapping", list(MAPPINGS))
@pytest.mark.parametrize("drag", D.drag_laws.names())
def test_compiled_coupling_matches_numpy_reference(drag, mapping):
    """map, cell β and particle forces of GasCoupling against the NumPy reference, every drag law × mapping."""
    cpl = coupling(drag, MAPPINGS[mapping])
    st = cpl.engine.state
    assert cpl.polydisperse == ("none" if D.drag_laws.get(drag).total_force else "sauter_y2")  # many sizes
    smap = cpl._map()
    ref = ref_map(cpl.mapping, cpl.grid, st.position, st.radius, st.velocity)
    for k in ("voidage", "solids_u", "solids_v"):
        check(getattr(smap, k), getattr(ref, k), f"map {k}")
    assert smap.clipped == ref.clipped
    # cell β on the map and on a random (voidage, solids velocity) field
    check(cpl.cell_beta(smap.voidage, smap.solids_u, smap.solids_v),
          ref_cell_beta(cpl, st.position, st.radius, ref.voidage, ref.solids_u, ref.solids_v), "cell beta (map)")
    rng = np.random.default_rng(5)
    eps, su, sv = rng.uniform(0.3, 1.0, cpl.grid.shape), rng.normal(0, 1, cpl.grid.shape), rng.normal(0, 1, cpl.grid.shape)
    check(cpl.cell_beta(eps, su, sv), ref_cell_beta(cpl, st.position, st.radius, eps, su, sv), "cell beta (random)")
    check(cpl.particle_forces(), ref_particle_forces(cpl, st.position, st.velocity, st.radius), "particle forces")


@pytest.mark.parametrize("pgf", [True, False])
@pytest.mark.parametrize("dim2", [True, False])
def test_particle_forces_with_and_without_pressure_gradient_and_z(pgf, dim2):
    cpl = coupling("beetstra", MAPPINGS["centroid-number"], pgf=pgf, dim2=dim2, seed=4)
    st = cpl.engine.state
    got = cpl.particle_forces()
    check(got, ref_particle_forces(cpl, st.position, st.velocity, st.radius), "particle forces")
    assert (np.all(got[:, 2] == 0.0)) == dim2


def test_public_voidage_map_matches_reference_with_2d_positions_and_no_velocity():
    cpl = coupling("gidaspow", MAPPINGS["area-volume"], seed=8)
    st = cpl.engine.state
    got = cpl.mapping.map(cpl.grid, st.position[:, :2], 2.0 * st.radius)
    ref = ref_map(cpl.mapping, cpl.grid, st.position, st.radius, np.zeros_like(st.velocity))
    for k in ("voidage", "solids_u", "solids_v"):
        check(getattr(got, k), getattr(ref, k), f"map {k}")


def test_set_particle_forces_keeps_the_total_force_consistent():
    cpl = coupling("hoomans1996", MAPPINGS["centroid-number"], seed=2)
    eng = cpl.engine
    rng = np.random.default_rng(0)
    eng.ext_force[...] = rng.normal(size=eng.ext_force.shape)
    eng.state.force[...] = rng.normal(size=eng.ext_force.shape)
    before = eng.state.force - eng.ext_force  # everything but the gas
    cpl.set_particle_forces()
    new = ref_particle_forces(cpl, eng.state.position, eng.state.velocity, eng.state.radius)
    check(eng.ext_force, new, "ext_force")
    np.testing.assert_allclose(eng.state.force, before + new, rtol=1e-12, atol=1e-12 * np.abs(new).max())


def test_gas_step_records_the_map_and_beta_it_used():
    """last_map / last_beta are the mapping at the step's start and the β handed to the gas."""
    cpl = coupling("koch_hill", MAPPINGS["centroid-volume"], seed=6, random_state=False)
    st = cpl.engine.state
    assert cpl.last_beta is None and cpl.last_map.voidage.shape == cpl.grid.shape
    gas0 = cpl.state.copy()
    ref = ref_map(cpl.mapping, cpl.grid, st.position, st.radius, st.velocity)
    cpl.gas_step()
    assert cpl.gas_steps == 1
    for k in ("voidage", "solids_u", "solids_v"):
        check(getattr(cpl.last_map, k), getattr(ref, k), f"last_map {k}")
    after = cpl.state
    cpl.state = gas0
    check(cpl.last_beta, ref_cell_beta(cpl, st.position, st.radius, ref.voidage, ref.solids_u, ref.solids_v),
          "last_beta")
    cpl.state = after
    check(cpl.engine.ext_force, ref_particle_forces(cpl, st.position, st.velocity, st.radius), "forces after step")


def test_out_of_range_gas_state_raises():
    cpl = coupling("gidaspow", MAPPINGS["centroid-number"], seed=3)
    cpl.state.rho[...] = -1.0
    smap = cpl._map()
    with pytest.raises(ValueError, match="out of range"):
        cpl.cell_beta(smap.voidage, smap.solids_u, smap.solids_v)
    with pytest.raises(ValueError, match="out of range"):
        cpl.particle_forces()


def test_wrong_shapes_are_refused_before_the_kernels_index_them():
    cpl = coupling("gidaspow", MAPPINGS["centroid-number"], seed=3)
    smap = cpl._map()
    with pytest.raises(ValueError, match="shape"):
        cpl.cell_beta(smap.voidage[:-1], smap.solids_u, smap.solids_v)
    with pytest.raises(ValueError, match="out must be"):
        cpl.particle_forces(out=np.empty((3, 3)))
    cpl.state = GasState(p=cpl.state.p, rho=cpl.state.rho, u=cpl.state.u[:-1], v=cpl.state.v,
                         voidage=cpl.state.voidage)
    with pytest.raises(ValueError, match="gas state u"):
        cpl.particle_forces()


@pytest.mark.parametrize("drag", ["gidaspow", "di_felice"])
def test_paired_kernels_give_the_same_bits_on_any_number_of_threads(all_threads, drag):
    """``deposit`` and ``particle_forces_split`` with ``parallel`` (chunks of particles on all threads) equal
    their serial path to the last bit: K_p, the face sums in particle order, the split forces. Some
    particles out of the drag law's range (voidage 0 at their place) check the skipped ones too."""
    from fluidem.coupling import _paired_kernels as P

    cpl = coupling(drag, {"method": "centroid"}, n=1500, exchange="particle")
    cpl.state.voidage[2:8, 4:12] = 0.0  # with minimum voidage 0 below, the particles inside are out of range
    st, gs, gd = cpl.engine.state, cpl.state, cpl.grid

    def deposit(parallel):
        kp = np.zeros(st.n)
        sums = [np.zeros(a.shape) for a in cpl._faces]
        kc = np.zeros(gd.shape)
        face = [np.zeros(gd.u_shape), np.zeros(gd.u_shape), np.zeros(gd.v_shape), np.zeros(gd.v_shape)]
        pv = [np.zeros(gd.u_shape), np.zeros(gd.v_shape)]
        bad = P.deposit(cpl.drag.pack(), st.position, st.velocity, st.radius, cpl.volume, gs.u, gs.v, gs.voidage,
                        gs.rho, cpl.solver.props.viscosity, cpl._inv_dbar, gd.dx, gd.dy, 0.0, *cpl._periodic, kp, *sums, kc,
                        gd.cell_volume, *cpl._face_volumes, *face, True, *pv, parallel)
        return bad, [kp, kc, *sums, *face, *pv]

    def split(kp, parallel):
        ext, damp, total = np.ones((st.n, 3)), np.full(st.n, 0.5), np.zeros((st.n, 3))
        P.particle_forces_split(st.position, st.velocity, cpl.volume, kp, gs.u, gs.v, gs.p, gd.dx, gd.dy,
                                *cpl._periodic, True, True, True, ext, damp, total, parallel)
        return [ext, damp, total]

    bad, serial = deposit(False)
    bad_p, par = deposit(True)
    assert 0 < bad == bad_p < st.n // 10
    for a, b in zip(serial, par):
        np.testing.assert_array_equal(a, b)
    kp = np.nan_to_num(serial[0])
    for a, b in zip(split(kp, False), split(kp, True)):
        np.testing.assert_array_equal(a, b)
    assert np.abs(split(kp, False)[0]).max() > 0.0
