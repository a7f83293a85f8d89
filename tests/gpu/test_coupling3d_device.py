"""The particle side of the 3D gas coupling on the GPU against the CPU kernels it mirrors.

``coupling._voidage3d_cuda`` (``centroid_deposit3d``, ``volume_deposit3d``) against
``_voidage3d_kernels.deposit_solids3d``, and ``coupling._paired3d_cuda`` (``deposit3d``, ``forces3d``,
``forces_split3d``) against ``_paired3d_kernels``, on a small random system: spheres of radius up to half a
cell scattered over a 4 × 6 × 4 grid and a little beyond it (centres on faces, spheres across the periodic
sides), random gas fields, every registered drag law, folded and unfolded boundary faces, periodic axes. Then
a coupled 3D bed on the GPU engine with ``coupling.gpu_exchange`` "device" against "host".

Tolerances. Each particle's numbers (K_p, its force) come from the CPU's own source compiled for the device:
1e-13 relative (on a GPU a multiply and an add may be fused into one rounding; the simulator gives the CPU's
bits). The cell and face sums are added with atomics, in another order than the CPU's particle order: a sum of
M terms can then differ by about M ε of the sum of their magnitudes; with at most 40 terms per node (each
sphere's exact volume in a cell an inclusion–exclusion of 8 corner volumes, each a few terms of the sphere's
size) and ε = 2.2e-16, 1e-12 of the array's largest magnitude holds that with room. The coupled run: the
2D coupled run's bounds (``test_gpu_engine.test_coupled_run_matches_cpu``), 1e-9, for three gas steps whose
round-off the particle contacts amplify.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from fluidem.coupling import _exchange3d_kernels as X3
from fluidem.coupling import _paired3d_kernels as P3
from fluidem.coupling import _voidage3d_kernels as VK3
from fluidem.coupling.drag import drag_laws
from fluidem.coupling.exchange3d import face_volumes3d
from fluidem.particles.softsphere_gpu import cuda_available

pytestmark = pytest.mark.skipif(not cuda_available(), reason="numba.cuda has no GPU or simulator in this process "
                                "(tests/unit/test_gpu_device.py runs these under NUMBA_ENABLE_CUDASIM=1)")

PER_PARTICLE_RTOL = 1e-13
SUM_RTOL = 1e-12
NX, NY, NZ, DX, DY, DZ = 4, 6, 4, 0.01, 0.015, 0.008
CELLS, SIZES = (NX, NY, NZ), (DX, DY, DZ)
MU = 1.8e-5


def _system(seed=11, n=40):
    """Spheres of radius 1.5-4 mm (up to half a cell: each overlaps up to 3 cells per axis), some centres
    outside the grid, some on faces, some across the sides; random gas fields, one cell of negative gas density
    (drag arguments out of range for the particles around it)."""
    rng = np.random.default_rng(seed)
    pos = np.column_stack([rng.uniform(-0.1 * d, (m + 0.1) * d, n) for m, d in zip(CELLS, SIZES)])
    pos[:3, 0] = [0.0, NX * DX, 2 * DX]  # centres on faces
    pos[:3, 1] = [DY, 0.5 * DY, NY * DY]
    pos[3:6, 2] = [1e-3, NZ * DZ - 1e-3, 3 * DZ]
    vel = rng.normal(0.0, 0.3, (n, 3))
    radius = rng.uniform(1.5e-3, 4e-3, n)
    volume = math.pi / 6.0 * (2.0 * radius) ** 3
    gas = {"u": rng.normal(1.0, 0.5, (NX + 1, NY, NZ)), "v": rng.normal(1.5, 0.5, (NX, NY + 1, NZ)),
           "w": rng.normal(-0.3, 0.5, (NX, NY, NZ + 1)), "voidage": rng.uniform(0.35, 1.05, CELLS),
           "rho": rng.uniform(1.1, 1.3, CELLS), "p": rng.normal(0.0, 50.0, CELLS)}
    gas["rho"][NX - 1, NY - 1, NZ - 1] = -20.0
    return pos, vel, radius, volume, gas


def _dev(*arrays):
    from numba import cuda

    return [cuda.to_device(np.ascontiguousarray(a)) for a in arrays]


def _sum_close(a, b):
    scale = np.abs(a).max()
    assert np.abs(a - b).max() <= SUM_RTOL * scale if scale > 0 else np.array_equal(a, b)


def _cpu_map(method, by_volume, pos, radius, volume, vel, periodic):
    """(deposit, wsum, wvx, wvy, wvz) of ``_voidage3d_kernels.deposit_solids3d``, the deposit before / V_cell."""
    out = [np.empty(CELLS) for _ in range(5)]
    VK3.deposit_solids3d(0 if method == "centroid" else 3, 1 if by_volume else 0, pos, radius, volume, vel, *SIZES,
                         *periodic, 1.0, *out)
    return out


def _device_map(method, by_volume, pos, radius, volume, vel, periodic):
    """(solids, count, wvx, wvy, wvz) of the device deposit."""
    from fluidem.coupling import _voidage3d_cuda as VC

    cells = _dev(*(np.zeros(CELLS) for _ in range(5)))
    d_pos, d_vel, d_rad, d_vol = _dev(pos, vel, radius, volume)
    inv = tuple(1.0 / d for d in SIZES)
    if method == "centroid":
        VC.centroid_deposit3d[1, VC.THREADS](d_pos, d_vel, d_vol, *inv, by_volume, *cells)
    else:
        VC.volume_deposit3d[1, VC.THREADS](d_pos, d_vel, d_rad, *SIZES, *inv, *periodic, by_volume, *cells)
    return [c.copy_to_host() for c in cells]


@pytest.mark.parametrize("by_volume", [False, True])
def test_centroid_deposit3d_matches_cpu(by_volume):
    """Σ V_p, the velocity weights and the weighted velocities of each cell (Sun 2007 eqs 34-35 in 3D, Hoomans
    1996 eq. 50), centres outside the grid in its edge cells, centres on faces in the CPU's cell."""
    pos, vel, radius, volume, _ = _system()
    frac, wsum, wvx, wvy, wvz = _cpu_map("centroid", by_volume, pos, radius, volume, vel, (False,) * 3)
    solids, count, gx, gy, gz = _device_map("centroid", by_volume, pos, radius, volume, vel, (False,) * 3)
    assert count.sum() == pos.shape[0]
    _sum_close(frac, solids)
    _sum_close(wsum, solids if by_volume else count)
    for cpu, dev in ((wvx, gx), (wvy, gy), (wvz, gz)):
        _sum_close(cpu, dev)


@pytest.mark.parametrize("periodic,by_volume", [((False, False, False), True), ((True, False, True), True),
                                                ((False, True, False), False)])
def test_volume_deposit3d_matches_cpu(periodic, by_volume):
    """The exact volume of each sphere in every cell it overlaps (``_voidage3d_kernels.sphere_box_volume``
    compiled for the device), across periodic sides and out of the non-periodic edge cells, and its velocity
    weights; Σ over the cells is Σ 4/3 π r³ (every sphere's whole volume counted: the module docstring of
    ``_voidage3d_kernels``)."""
    pos, vel, radius, volume, _ = _system(seed=4)
    frac, wsum, wvx, wvy, wvz = _cpu_map("volume", by_volume, pos, radius, volume, vel, periodic)
    solids, count, gx, gy, gz = _device_map("volume", by_volume, pos, radius, volume, vel, periodic)
    spheres = (4.0 / 3.0 * math.pi * radius**3).sum()
    assert abs(solids.sum() - spheres) <= 1e-13 * spheres
    assert np.count_nonzero(solids) > pos.shape[0]  # spheres straddling cells
    _sum_close(frac, solids)
    _sum_close(wsum, solids if by_volume else count)
    for cpu, dev in ((wvx, gx), (wvy, gy), (wvz, gz)):
        _sum_close(cpu, dev)


def test_sauter_deposit3d_matches_cpu():
    """Σ V_p/d_p and Σ V_p of the centres in each cell, finished on the host into 1/D̄ (DEM book 2012 two-phase
    chapter, eq. 10): ``_voidage3d_cuda.sauter_deposit3d`` and ``exchange_gpu.sauter_finish`` against
    ``_voidage3d_kernels.sauter_inverse3d``; an empty cell takes the bed's value."""
    from fluidem.coupling import _voidage3d_cuda as VC
    from fluidem.coupling.exchange_gpu import sauter_finish

    pos, _, radius, volume, _ = _system(seed=3)
    expected = np.empty(CELLS)
    bed = VK3.sauter_inverse3d(pos, radius, volume, *SIZES, expected)
    sums = _dev(np.zeros(CELLS), np.zeros(CELLS))
    d_pos, d_rad, d_vol = _dev(pos, radius, volume)
    VC.sauter_deposit3d[1, VC.THREADS](d_pos, d_rad, d_vol, *(1.0 / d for d in SIZES), *sums)
    got = np.empty(CELLS)
    by_size, by_volume = (a.copy_to_host() for a in sums)
    assert np.any(by_volume == 0.0) and np.count_nonzero(by_volume) > 1  # empty cells: the bed's value
    assert abs(sauter_finish(by_size, by_volume, got) - bed) <= PER_PARTICLE_RTOL * bed
    assert np.all(np.abs(got - expected) <= SUM_RTOL * np.abs(expected).max())


def _cpu_deposit(law, pos, vel, radius, volume, gas, periodic, fold, pair, inv_dbar=None):
    vf = face_volumes3d(CELLS, periodic, DX * DY * DZ)
    faces = [f.shape for f in vf]
    sums = {k: np.zeros(faces[a]) for a, ks in enumerate((("AU", "BU"), ("AV", "BV"), ("AW", "BW"))) for k in ks}
    sums["KC"] = np.zeros(CELLS)
    finished = [np.zeros(faces[a]) for a in range(3) for _ in range(2)]  # β, u_s of each axis
    eps = [np.zeros(s) for s in faces]
    kp = np.zeros(pos.shape[0])
    bad = P3.deposit3d(law, pos, vel, radius, volume, gas["u"], gas["v"], gas["w"], gas["voidage"], gas["rho"], MU,
                       np.zeros((0, 0, 0)) if inv_dbar is None else inv_dbar, *SIZES, 0.3, *periodic, fold, kp, *sums.values(), *vf, *finished, pair,
                       *eps)
    return kp, sums, eps, vf, bad


@pytest.mark.parametrize("law_name,periodic,fold,pair,mixture",
                         [(name, (False, False, True), True, True, False) for name in drag_laws.names()]
                         + [("gidaspow", (True, False, False), False, True, False),
                            ("gidaspow", (False, True, True), True, False, False),
                            ("beetstra", (False, False, True), True, True, True),
                            ("gidaspow", (True, False, True), False, True, True)])
def test_deposit3d_matches_cpu(law_name, periodic, fold, pair, mixture):
    """K_p of each particle (every registered drag law), the face sums A_f, B_f on the x-, y- and z-faces, Σ K_p
    per cell and the particle volume on the faces of the pressure term, against ``_paired3d_kernels.deposit3d``;
    out-of-range particles counted and given NaN as there. ``mixture``: the polydisperse drag, y = d/D̄ with 1/D̄
    of the cells interpolated to the particle (DEM book 2012 eqs 10-12)."""
    from fluidem.coupling import _paired3d_cuda as PC

    pos, vel, radius, volume, gas = _system()
    law = drag_laws.get(law_name)().pack()
    inv_dbar = np.random.default_rng(4).uniform(100.0, 300.0, CELLS) if mixture else np.zeros((0, 0, 0))
    kp, sums, eps, vf, bad = _cpu_deposit(law, pos, vel, radius, volume, gas, periodic, fold, pair, inv_dbar)
    assert 0 < bad < pos.shape[0] // 4
    if mixture:  # y ≠ 1 changes K_p
        mono = _cpu_deposit(law, pos, vel, radius, volume, gas, periodic, fold, pair)[0]
        assert not np.allclose(kp[~np.isnan(kp)], mono[~np.isnan(mono)], rtol=1e-3)
    names = ("AU", "BU", "AV", "BV", "AW", "BW", "KC", "EU", "EV", "EW")
    shapes = [a.shape for a in sums.values()] + [e.shape for e in eps]
    dsums = dict(zip(names, _dev(*(np.zeros(s) for s in shapes))))
    d_kp, d_bad = _dev(np.zeros(pos.shape[0]), np.zeros(1, dtype=np.int32))
    args = _dev(law, pos, vel, radius, volume, gas["u"], gas["v"], gas["w"], gas["voidage"], gas["rho"])
    PC.deposit3d[1, PC.THREADS](*args, MU, *_dev(inv_dbar), *SIZES, 0.3, *periodic, fold, d_kp, *(dsums[k] for k in names[:7]), pair,
                                dsums["EU"], dsums["EV"], dsums["EW"], d_bad)
    got = {k: a.copy_to_host() for k, a in dsums.items()}
    assert int(d_bad.copy_to_host()[0]) == bad
    gkp = d_kp.copy_to_host()
    assert np.array_equal(np.isnan(gkp), np.isnan(kp))
    ok = ~np.isnan(kp)
    assert np.all(np.abs(gkp[ok] - kp[ok]) <= PER_PARTICLE_RTOL * np.abs(kp[ok]))
    for k in names[:7]:
        _sum_close(sums[k], got[k])
    assert got["AW"].any() and got["BW"].any()
    if pair:  # the CPU turned its sums into 1 − E/V_f (clipped at 0.3): the same on the device's sums
        for e_cpu, k, f in zip(eps, ("EU", "EV", "EW"), vf):
            P3._voidage_of(got[k], f, 0.3)
            _sum_close(e_cpu, got[k])
    else:
        assert not any(got[k].any() for k in ("EU", "EV", "EW"))


@pytest.mark.parametrize("split", [True, False])
@pytest.mark.parametrize("pressure,periodic", [(True, (False, False, True)), (False, (True, True, False))])
def test_particle_forces3d_match_cpu(split, pressure, periodic):
    """The gas force of each particle from K_p (``forces_split3d`` / ``forces3d`` against
    ``_paired3d_kernels.particle_forces_split3d`` / ``particle_forces3d``), the engine's total force following."""
    from fluidem.coupling import _paired3d_cuda as PC

    pos, vel, radius, volume, gas = _system(seed=5)
    gas["rho"][:] = 1.2
    law = drag_laws.get("gidaspow")().pack()
    kp, *_ = _cpu_deposit(law, pos, vel, radius, volume, gas, periodic, True, True)
    rng = np.random.default_rng(2)
    n = pos.shape[0]
    ext, damp, total = rng.normal(size=(n, 3)), rng.uniform(size=n), rng.normal(size=(n, 3))
    d_ext, d_damp, d_total = _dev(ext, damp, total)
    args = _dev(pos, vel, volume, kp, gas["u"], gas["v"], gas["w"], gas["p"])
    fields = (gas["u"], gas["v"], gas["w"], gas["p"])
    if split:
        P3.particle_forces_split3d(pos, vel, volume, kp, *fields, *SIZES, *periodic, True, pressure, ext, damp, total)
        PC.forces_split3d[1, PC.THREADS](*args, *SIZES, *periodic, True, pressure, d_ext, d_damp, d_total)
    else:
        P3.particle_forces3d(pos, vel, volume, kp, *fields, *SIZES, *periodic, True, pressure, ext, total)
        PC.forces3d[1, PC.THREADS](*args, *SIZES, *periodic, True, pressure, d_ext, d_total)
    for cpu, dev in ((ext, d_ext), (damp, d_damp), (total, d_total)):
        got = dev.copy_to_host()
        assert np.all(np.abs(got - cpu) <= PER_PARTICLE_RTOL * np.abs(cpu).max())


def test_refusals_on_a_3d_grid():
    """Both 3D voidage methods have device kernels, and every exchange ('particle', 'cell', 'cell_beta')."""
    from types import SimpleNamespace

    from fluidem.case import load_case
    from fluidem.coupling.exchange_gpu import refusals

    def coupling(case, **kw):
        c = case.coupling
        return SimpleNamespace(options=c, exchange=kw.get("exchange", c.momentum_exchange), mapping=c.voidage,
                               polydisperse=c.resolved_polydisperse([1.2e-3]))

    bed = load_case("bubbling-3d")
    assert bed.coupling.voidage.method == "volume"
    assert refusals(coupling(bed), dimensions=3) == []
    assert refusals(coupling(load_case("bubbling-3d", {"coupling.voidage.method": "centroid"})), dimensions=3) == []
    assert refusals(coupling(bed, exchange="cell"), dimensions=3) == []
    assert refusals(coupling(bed, exchange="cell_beta"), dimensions=3) == []
    assert refusals(coupling(load_case("bubbling-3d", {"coupling.gpu_exchange": "host"})), dimensions=3) == [
        "coupling.gpu_exchange = 'host'"]


@pytest.mark.parametrize("mixture", [False, True])
def test_cell_beta_deposit3d_matches_cpu(mixture):
    """Σ β/(1 − ε) V_p of the particles centred in each cell over V_cell, β/(1 − ε) at the cell's ε, gas density
    and slip |u_c − v_s,c| (Sun 2007 eq. 33; with ``mixture`` y = d/D̄ of the cell): ``_cell3d_cuda.
    cell_beta_deposit3d`` against ``_exchange3d_kernels.cell_beta3d``, out-of-range particles counted and left out
    as there."""
    from fluidem.coupling import _cell3d_cuda as C3

    pos, _, radius, volume, gas = _system()
    rng = np.random.default_rng(8)
    solids = [rng.normal(0.0, 0.3, CELLS) for _ in range(3)]
    inv_dbar = rng.uniform(200.0, 700.0, CELLS) if mixture else np.zeros((0, 0, 0))
    law = drag_laws.get("beetstra")().pack()
    beta = np.empty(CELLS)
    vc = DX * DY * DZ
    bad = X3.cell_beta3d(law, pos, radius, volume, gas["u"], gas["v"], gas["w"], gas["rho"], gas["voidage"], *solids,
                         MU, inv_dbar, *SIZES, vc, beta)
    assert 0 < bad < pos.shape[0] // 4 and np.count_nonzero(beta) > 10
    d_out, d_bad = _dev(np.zeros(CELLS), np.zeros(1, dtype=np.int32))
    args = _dev(law, pos, radius, volume, gas["u"], gas["v"], gas["w"], gas["rho"], gas["voidage"], *solids)
    C3.cell_beta_deposit3d[1, C3.THREADS](*args, MU, *_dev(inv_dbar), *SIZES, d_out, d_bad)
    assert int(d_bad.copy_to_host()[0]) == bad
    _sum_close(beta, d_out.copy_to_host() / vc)


@pytest.mark.parametrize("periodic", [(False, False, False), (True, False, True)])
def test_pressure_deposit3d_matches_cpu(periodic):
    """The particle volume on the x-, y- and z-faces of each particle's folded ∇p interpolation, finished into the
    pressure voidage max(1 − Σ w V_p / V_f, ε_min): ``_cell3d_cuda.pressure_deposit3d`` against
    ``_exchange3d_kernels.pressure_voidage3d``, across periodic sides."""
    from fluidem.coupling import _cell3d_cuda as C3

    pos, _, _, volume, _ = _system(seed=6)
    volume = volume * 5.0  # faces filled past the clipping, some
    vf = face_volumes3d(CELLS, periodic, DX * DY * DZ)
    eps = [np.empty(f.shape) for f in vf]
    X3.pressure_voidage3d(pos, volume, *SIZES, *periodic, *vf, 0.3, *eps)
    assert min(e.min() for e in eps) == 0.3 and any(np.any((e > 0.3) & (e < 1.0)) for e in eps)
    dev = _dev(*(np.zeros(f.shape) for f in vf))
    C3.pressure_deposit3d[1, C3.THREADS](*_dev(pos, volume), *SIZES, *periodic, *dev)
    for cpu, d, f in zip(eps, dev, vf):
        got = d.copy_to_host()
        P3._voidage_of(got, f, 0.3)
        _sum_close(cpu, got)


@pytest.mark.parametrize("pressure,periodic", [(True, (False, False, True)), (False, (True, True, False))])
def test_cell_forces3d_match_cpu(pressure, periodic):
    """Each particle's share V_p/Σ V_r of its cell's drag β V_c (u_c − u_s,c), minus V_p ∇p, the engine's total
    following: ``_cell3d_cuda.cell_solids3d`` and ``cell_forces3d`` against ``_exchange3d_kernels.cell_forces3d``;
    Σ V_p per cell against the cells of the centres counted by NumPy (trunc(x/d) clamped)."""
    from fluidem.coupling import _cell3d_cuda as C3

    pos, vel, _, volume, gas = _system(seed=5)
    rng = np.random.default_rng(9)
    beta, *solids = rng.uniform(0.0, 3e4, CELLS), *(rng.normal(0.0, 0.3, CELLS) for _ in range(3))
    n = pos.shape[0]
    ext, total = rng.normal(size=(n, 3)), rng.normal(size=(n, 3))
    d_ext, d_total = _dev(ext, total)
    vc = DX * DY * DZ
    fields = (gas["u"], gas["v"], gas["w"], gas["p"])
    X3.cell_forces3d(pos, vel, volume, beta, *solids, *fields, *SIZES, vc, *periodic, pressure, ext, total)
    d_pos, d_vol, d_solids = _dev(pos, volume, np.zeros(CELLS))
    C3.cell_solids3d[1, C3.THREADS](d_pos, d_vol, *SIZES, d_solids)
    cell = [np.clip(np.trunc(pos[:, a] / SIZES[a]), 0, CELLS[a] - 1).astype(int) for a in range(3)]
    expected = np.bincount(np.ravel_multi_index(cell, CELLS), volume, minlength=NX * NY * NZ).reshape(CELLS)
    _sum_close(expected, d_solids.copy_to_host())
    C3.cell_forces3d[1, C3.THREADS](d_pos, d_vol, d_solids, *_dev(beta, *solids, *fields), *SIZES, vc, *periodic,
                                    pressure, d_ext, d_total)
    for cpu, dev in ((ext, d_ext), (total, d_total)):
        got = dev.copy_to_host()
        assert np.all(np.abs(got - cpu) <= PER_PARTICLE_RTOL * np.abs(cpu).max())


@pytest.mark.parametrize("fold,mixture", [(False, False), (True, True)])
def test_kp_now3d_matches_cpu(fold, mixture):
    """K_p = β/(1 − ε_p) V_p (Sun 2007 eq. 29) of each particle at the current gas without face sums, the
    "cell_beta" exchange's drag: ``_cell3d_cuda.kp_now3d`` against ``_paired3d_kernels.kp3d``, out-of-range
    particles counted and given NaN as there."""
    from fluidem.coupling import _cell3d_cuda as C3

    pos, vel, radius, volume, gas = _system()
    law = drag_laws.get("gidaspow")().pack()
    inv_dbar = np.random.default_rng(4).uniform(100.0, 300.0, CELLS) if mixture else np.zeros((0, 0, 0))
    n = pos.shape[0]
    kp, valid = np.zeros(n), np.empty(n, np.bool_)
    fields = (gas["u"], gas["v"], gas["w"], gas["voidage"], gas["rho"])
    periodic = (True, False, False)
    bad = P3.kp3d(law, pos, vel, radius, volume, *fields, MU, inv_dbar, *SIZES, 0.3, *periodic, fold, kp, valid)
    assert 0 < bad < n // 4
    d_kp, d_valid, d_bad = _dev(np.zeros(n), np.zeros(n, np.bool_), np.zeros(1, dtype=np.int32))
    C3.kp_now3d[1, C3.THREADS](*_dev(law, pos, vel, radius, volume, *fields), MU, *_dev(inv_dbar), *SIZES, 0.3,
                               *periodic, fold, d_kp, d_valid, d_bad)
    assert int(d_bad.copy_to_host()[0]) == bad
    assert np.array_equal(d_valid.copy_to_host(), valid)
    got = d_kp.copy_to_host()
    assert np.array_equal(np.isnan(got), ~valid)
    assert np.all(np.abs(got[valid] - kp[valid]) <= PER_PARTICLE_RTOL * np.abs(kp[valid]))


def _bed(packing_case, n=216, two_species=False):
    """A 3D bed of n spheres of 4 mm (and 3.6 mm with ``two_species``) on a 4 × 6 × 4 gas grid, gas from below
    (y up), walls all round."""
    case, _ = packing_case("linear_spring_dashpot", n=n, dimensions=3, speed=0.2, two_species=two_species)
    data = case.model_dump()
    width, height, depth = data["walls"][0]["upper"]
    data["gravity"] = [0.0, -9.81, 0.0]
    data["walls"][0]["upper"] = [width, 3 * height, depth]
    data["time"]["dt"] = 2e-5
    data["gas"] = {"dt": 8e-5, "grid": {"cells": [4, 6, 4], "size": [width, 3 * height, depth]},
                   "initial_velocity": [0.0, 1.5, 0.0],
                   "boundaries": {"bottom": {"kind": "inflow", "superficial": 1.5, "voidage": 1.0},
                                  "top": {"kind": "pressure_outlet"}, "left": {"kind": "wall"},
                                  "right": {"kind": "wall"}, "front": {"kind": "wall"}, "back": {"kind": "wall"}}}
    data["coupling"] = {"drag": "gidaspow", "voidage": {"method": "volume"}}
    return data, 3 * height


def _device_and_host(data, gas_steps):
    """The case ``data`` run for ``gas_steps`` gas steps on the GPU engine with the coupling's particle side on the
    device and on the host: (device run, host run)."""
    from fluidem import Simulation
    from fluidem.case import validate_case

    runs = {}
    for mode in ("device", "host"):
        data["coupling"]["gpu_exchange"] = mode
        sim = Simulation(validate_case({**data, "device": "gpu"}))
        sim.advance(gas_steps * sim.gas.substeps)
        runs[mode] = sim
    return runs["device"], runs["host"]


def test_coupled3d_run_device_matches_host(packing_case):
    """The GPU engine on a 3D gas grid with the coupling's particle side on the device (exact-volume map, drag,
    deposit, gas force: ``coupling.exchange3d_gpu``) against the same run with it on the host
    (``gpu_exchange = "host"``): over three gas steps of four sub-steps the particles and the gas agree to
    round-off; a checkpoint's K_p goes back to the device. The device's map of the final particles is the
    host's for both methods, both weightings, with smoothing and clipping."""
    from fluidem import Simulation
    from fluidem.case import validate_case
    from fluidem.coupling.voidage import VoidageMapping

    data, height = _bed(packing_case)
    runs = {}
    for mode in ("device", "host"):
        data["coupling"]["gpu_exchange"] = mode
        sim = Simulation(validate_case({**data, "device": "gpu"}))
        assert type(sim.gas).__name__ == "DeviceGasCoupling3D"
        sim.advance(3 * sim.gas.substeps)
        runs[mode] = sim
    dev, host = runs["device"], runs["host"]
    assert dev.gas._device is not None and host.gas._device is None
    assert dev.gas.substeps == host.gas.substeps == 4 and dev.gas.gas_steps == 3
    assert np.abs(dev.state.position - host.state.position).max() <= 1e-9 * height
    for a, b in ((dev.state.velocity, host.state.velocity), (dev.engine.ext_force, host.engine.ext_force)):
        assert np.abs(a - b).max() <= 1e-9 * np.abs(b).max()
    assert np.abs(host.engine.ext_force[:, 1]).max() > 0.1 * host.state.mass.max() * 9.81  # the gas carries weight
    for k in ("p", "u", "v", "w", "voidage"):
        b = getattr(host.gas.state, k)
        assert np.abs(getattr(dev.gas.state, k) - b).max() <= 1e-9 * np.abs(b).max(), k
    kp = host.gas.checkpoint_arrays()["coupling/kp"]  # K_p of the last gas step, fetched from the device
    assert np.abs(dev.gas.checkpoint_arrays()["coupling/kp"] - kp).max() <= 1e-9 * np.abs(kp).max()
    bal, ref = dev.gas.exchange_balance(), host.gas.exchange_balance()  # K_p fetched for the host's sums
    for k in ("gas", "boundary", "particles", "pressure_gas", "pressure_particles"):
        assert np.abs(bal[k] - ref[k]).max() <= 1e-9 * np.abs(ref[k]).max(), k
    arrays = {k: np.array(v) for k, v in dev.gas.checkpoint_arrays().items()}  # a checkpoint's K_p to the device
    data["coupling"]["gpu_exchange"] = "device"
    again = Simulation(validate_case({**data, "device": "gpu"}))
    again.gas.restore(arrays, dev.gas.checkpoint_scalars())
    assert np.array_equal(again.gas._device.kp.copy_to_host(), arrays["coupling/kp"])
    cg, st = dev.gas, dev.state
    for mapping in (VoidageMapping(method="volume"), VoidageMapping(method="centroid", velocity_weighting="volume"),
                    VoidageMapping(method="volume", velocity_weighting="volume", smoothing_width=5e-3,
                                   minimum_voidage=0.6)):
        on_device = cg._device.map(mapping, cg.grid)
        on_host = mapping.map_particles(cg.grid, st.position, st.radius, cg.volume, st.velocity, cg._periodic)
        assert on_device.clipped == on_host.clipped
        for a, b in ((on_device.voidage, on_host.voidage), (on_device.solids_u, on_host.solids_u),
                     (on_device.solids_v, on_host.solids_v), (on_device.solids_w, on_host.solids_w)):
            assert np.abs(a - b).max() <= SUM_RTOL * np.abs(b).max()
    assert on_host.clipped > 0  # minimum_voidage 0.6 clips the packed cells


def test_coupled3d_polydisperse_device_matches_host(packing_case):
    """``polydisperse = "sauter_y2"`` on a 3D grid with the particle side on the device (1/D̄ of each cell from
    the device's sums, y = d/D̄ in the device's K_p) against the host: two gas steps of four sub-steps agree to
    round-off (the bounds of ``test_coupled3d_run_device_matches_host``)."""
    data, height = _bed(packing_case, n=125, two_species=True)
    data["coupling"]["polydisperse"] = "sauter_y2"
    dev, host = _device_and_host(data, 2)
    assert dev.gas._device is not None and host.gas._device is None and dev.gas.gas_steps == 2
    inv = host.gas._inv_dbar
    assert inv.shape == CELLS and 1 / 4e-3 < inv.max() <= 1 / 3.6e-3 * (1.0 + 1e-12)
    assert inv.min() >= 1 / 4e-3 * (1.0 - 1e-12) and np.any((inv > 250.001) & (inv < 277.7))  # mixed cells
    assert np.abs(dev.gas._inv_dbar - inv).max() <= SUM_RTOL * inv.max()
    assert np.abs(dev.state.position - host.state.position).max() <= 1e-9 * height
    for a, b in ((dev.state.velocity, host.state.velocity), (dev.engine.ext_force, host.engine.ext_force)):
        assert np.abs(a - b).max() <= 1e-9 * np.abs(b).max()
    for k in ("p", "u", "v", "w"):
        b = getattr(host.gas.state, k)
        assert np.abs(getattr(dev.gas.state, k) - b).max() <= 1e-9 * np.abs(b).max(), k
    kp = host.gas.checkpoint_arrays()["coupling/kp"]
    assert np.abs(dev.gas.checkpoint_arrays()["coupling/kp"] - kp).max() <= 1e-9 * np.abs(kp).max()


@pytest.mark.parametrize("exchange", ["cell", "cell_beta"])
def test_coupled3d_cell_exchange_device_matches_host(packing_case, exchange):
    """``momentum_exchange = "cell"`` and ``"cell_beta"`` on a 3D grid with the particle side on the device (the
    cell β sums; for "cell" the pressure voidage's face sums and each particle's share of its cell's drag, for
    "cell_beta" each particle's K_p evaluated at every sub-step: ``coupling._cell3d_cuda``) against the host
    (``gpu_exchange = "host"``): three gas steps of four sub-steps agree to round-off (the bounds of
    ``test_coupled3d_run_device_matches_host``), as do the cell β, the pressure voidage and ``exchange_balance``."""
    data, height = _bed(packing_case, n=125 if exchange == "cell" else 64)
    data["coupling"]["momentum_exchange"] = exchange
    dev, host = _device_and_host(data, 3)
    assert dev.gas._device is not None and host.gas._device is None and dev.gas.gas_steps == 3
    assert np.abs(dev.state.position - host.state.position).max() <= 1e-9 * height
    for a, b in ((dev.state.velocity, host.state.velocity), (dev.engine.ext_force, host.engine.ext_force)):
        assert np.abs(a - b).max() <= 1e-9 * np.abs(b).max()
    assert np.abs(host.engine.ext_force[:, 1]).max() > 0.1 * host.state.mass.max() * 9.81  # the gas carries weight
    for k in ("p", "u", "v", "w", "voidage"):
        b = getattr(host.gas.state, k)
        assert np.abs(getattr(dev.gas.state, k) - b).max() <= 1e-9 * np.abs(b).max(), k
    for a, b in zip((dev.gas.last_beta, *dev.gas._pressure_voidage), (host.gas.last_beta, *host.gas._pressure_voidage)):
        assert np.abs(a - b).max() <= 1e-9 * np.abs(b).max()
    if exchange == "cell":  # the particles' volume on the faces of the paired pressure term
        assert host.gas._pressure_voidage[1].min() < 0.9
    bal, ref = dev.gas.exchange_balance(), host.gas.exchange_balance()
    for k in ref:
        assert np.abs(bal[k] - ref[k]).max() <= 1e-9 * np.abs(ref[k]).max(), k


@pytest.mark.parametrize("exchange", ["cell", "cell_beta"])
def test_coupled3d_grid_is_sent_once_per_gas_step_and_after_a_restore(packing_case, tmp_path, exchange):
    """With ``drag_update = "substep"`` the "cell" and "cell_beta" forces are evaluated at every sub-step; the
    gas arrays they read change only with a gas step, a map or a restore (the coupling's ``gas_version``), and
    are sent to the device once per gas step. A restore in the middle of a gas step (new gas arrays) makes the
    next sub-step send them again, and the run then repeats the sub-steps it made from there bit for bit."""
    from fluidem import Simulation
    from fluidem.case import validate_case

    data, _ = _bed(packing_case, n=64)
    data["coupling"].update(momentum_exchange=exchange, drag_update="substep", gpu_exchange="device")
    sim = Simulation(validate_case({**data, "device": "gpu"}))
    sub = sim.gas.substeps
    assert sub == 4 and sim.gas._device is not None

    def sends(n):
        """Sub-steps one at a time; how many of them sent the gas pressure again."""
        out = 0
        for _ in range(n):
            before = sim.gas._device._sent.get(("gas", "p"))
            sim.advance(1)
            out += sim.gas._device._sent.get(("gas", "p")) != before
        return out

    sim.advance(sub)
    assert sends(2 * sub) == 2  # two gas steps of four sub-steps
    assert sends(2) == 1  # half a gas step: a checkpoint here, then the rest of the step
    path = tmp_path / "restart.h5"
    sim.save_checkpoint(path)
    assert sends(2) == 0
    ref = {k: np.array(getattr(sim.state, k)) for k in ("position", "velocity")}
    sim.advance(sub)  # another gas step: the gas changed
    sim.load_checkpoint(path)  # back to the middle of the step before
    assert sends(2) == 1  # the restored gas, sent again
    for k, b in ref.items():
        assert np.array_equal(getattr(sim.state, k), b), k
