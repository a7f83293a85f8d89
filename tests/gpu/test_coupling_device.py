"""The particle side of the gas coupling on the GPU against the CPU kernels it mirrors.

``coupling._voidage_cuda.centroid_deposit`` against ``_voidage_kernels.deposit_solids``, and
``coupling._paired_cuda`` (``deposit``, ``forces_split``, ``forces``) against ``_paired_kernels``,
``coupling._cell_cuda.gas_forces`` (the "cell_beta" force) against ``_exchange_kernels.gas_forces``, on a small
random system: particles scattered over a 4 × 6 grid and a little beyond it, random gas fields, every
registered drag law, folded and unfolded boundary faces, a periodic axis.

Tolerances. Each particle's numbers (K_p, its force) come from the CPU's own source compiled for the device:
1e-13 relative (on a GPU a multiply and an add may be fused into one rounding; the simulator gives the CPU's
bits). The cell and face sums are added with atomics, in another order than the CPU's particle order: a sum of
M terms can then differ by about M ε of the sum of their magnitudes; with at most 60 terms per node and
ε = 2.2e-16, 1e-12 of the array's largest magnitude holds that with room.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from fluidem.coupling import _paired_kernels as P
from fluidem.coupling import _voidage_kernels as VK
from fluidem.coupling.drag import drag_laws
from fluidem.particles.softsphere_gpu import cuda_available

pytestmark = pytest.mark.skipif(not cuda_available(), reason="numba.cuda has no GPU or simulator in this process "
                                "(tests/unit/test_gpu_device.py runs these under NUMBA_ENABLE_CUDASIM=1)")

PER_PARTICLE_RTOL = 1e-13
SUM_RTOL = 1e-12
NX, NY, DX, DY = 4, 6, 0.01, 0.015
MU = 1.8e-5


def _system(seed=11, n=60):
    """Particles (some outside the grid), random gas fields, one cell of negative gas density (drag arguments
    out of range for the particles around it)."""
    rng = np.random.default_rng(seed)
    pos = np.zeros((n, 3))
    pos[:, 0] = rng.uniform(-0.1 * DX, (NX + 0.1) * DX, n)
    pos[:, 1] = rng.uniform(-0.1 * DY, (NY + 0.1) * DY, n)
    pos[:, 2] = 2e-3
    pos[:3, 0] = [0.0, NX * DX, 2 * DX]  # centres on faces
    pos[:3, 1] = [DY, 0.5 * DY, NY * DY]
    vel = rng.normal(0.0, 0.3, (n, 3))
    radius = rng.uniform(0.8e-3, 1.2e-3, n)
    volume = math.pi / 6.0 * (2.0 * radius) ** 3
    gas = {"u": rng.normal(1.0, 0.5, (NX + 1, NY)), "v": rng.normal(1.5, 0.5, (NX, NY + 1)),
           "voidage": rng.uniform(0.35, 1.05, (NX, NY)), "rho": rng.uniform(1.1, 1.3, (NX, NY)),
           "p": rng.normal(0.0, 50.0, (NX, NY))}
    gas["rho"][NX - 1, NY - 1] = -20.0
    return pos, vel, radius, volume, gas


def _dev(*arrays):
    from numba import cuda

    return [cuda.to_device(np.ascontiguousarray(a)) for a in arrays]


def _sum_close(a, b):
    scale = np.abs(a).max()
    assert np.abs(a - b).max() <= SUM_RTOL * scale if scale > 0 else np.array_equal(a, b)


@pytest.mark.parametrize("by_volume", [False, True])
def test_centroid_deposit_matches_cpu(by_volume):
    """Σ V_p, the velocity weights and the weighted velocities of each cell (Sun 2007 eqs 34-35, Hoomans 1996
    eq. 50), centres outside the grid in its edge cells, centres on faces in the CPU's cell."""
    from fluidem.coupling import _voidage_cuda as VC

    pos, vel, radius, volume, _ = _system()
    frac, wsum, wvx, wvy = (np.empty((NX, NY)) for _ in range(4))
    norm = DX * DY * 4e-3
    VK.deposit_solids(0, 1 if by_volume else 0, pos, radius, volume, vel, DX, DY, norm, frac, wsum, wvx, wvy)
    cells = _dev(*(np.zeros((NX, NY)) for _ in range(4)))
    d_pos, d_vel, d_vol = _dev(pos, vel, volume)
    VC.centroid_deposit[1, VC.THREADS](d_pos, d_vel, d_vol, 1.0 / DX, 1.0 / DY, by_volume, *cells)
    solids, count, gx, gy = (c.copy_to_host() for c in cells)
    assert count.sum() == pos.shape[0]
    _sum_close(frac, solids / norm)
    _sum_close(wsum, solids if by_volume else count)
    _sum_close(wvx, gx)
    _sum_close(wvy, gy)


def _discs(seed=7, n=60):
    """Discs of radius 0.8-6 mm on the 4 × 6 grid of 10 × 15 mm cells (up to 0.6 of a cell: across one face, two
    faces, a corner, several cells), centres a little beyond the grid (discs cut by its sides), some centres on
    faces and corners."""
    rng = np.random.default_rng(seed)
    pos, vel, _, _, _ = _system(seed, n)
    radius = rng.uniform(0.8e-3, 6e-3, n)
    pos[3:6, 0] = [DX, 2 * DX, 3 * DX]  # centres on corners
    pos[3:6, 1] = [DY, 3 * DY, 0.0]
    volume = math.pi / 6.0 * (2.0 * radius) ** 3
    return pos, vel, radius, volume


@pytest.mark.parametrize("method", ["area", "area_volume"])
@pytest.mark.parametrize("by_volume", [False, True])
def test_area_deposit_matches_cpu(method, by_volume):
    """The exact disc areas of each particle in every cell it overlaps (Hoomans 1996 §3.4; 'area_volume' its
    volume shared by them), the velocity weights by number (the centres, eq. 50) or by share (Sun 2007 eq. 35),
    parts outside the grid dropped: ``_voidage_cuda.area_deposit`` against ``_voidage_kernels.deposit_solids``."""
    from fluidem.coupling import _voidage_cuda as VC

    pos, vel, radius, volume = _discs()
    frac, wsum, wvx, wvy = (np.empty((NX, NY)) for _ in range(4))
    VK.deposit_solids(1 if method == "area" else 2, 1 if by_volume else 0, pos, radius, volume, vel, DX, DY, 1.0,
                      frac, wsum, wvx, wvy)
    cells = _dev(*(np.zeros((NX, NY)) for _ in range(4)))
    d_pos, d_vel, d_rad, d_vol = _dev(pos, vel, radius, volume)
    VC.area_deposit[1, VC.THREADS](d_pos, d_vel, d_rad, d_vol, method == "area_volume", DX, DY, by_volume, *cells)
    solids, count, gx, gy = (c.copy_to_host() for c in cells)
    inside = (frac.sum() < (np.pi * radius**2 if method == "area" else volume).sum() * (1.0 - 1e-3))
    assert inside  # some disc area lies outside the grid, and is dropped on both sides
    _sum_close(frac, solids)
    _sum_close(wsum, solids if by_volume else count)
    _sum_close(wvx, gx)
    _sum_close(wvy, gy)


def test_sauter_deposit_matches_cpu():
    """Σ V_p/d_p and Σ V_p of the centres in each cell, finished on the host into 1/D̄ (DEM book 2012 two-phase
    chapter, eq. 10): ``_voidage_cuda.sauter_deposit`` and ``exchange_gpu.sauter_finish`` against
    ``_voidage_kernels.sauter_inverse``; an empty cell takes the bed's value."""
    from fluidem.coupling import _voidage_cuda as VC
    from fluidem.coupling.exchange_gpu import sauter_finish

    pos, _, radius, volume = _discs(seed=3, n=20)
    expected = np.empty((NX, NY))
    bed = VK.sauter_inverse(pos, radius, volume, DX, DY, expected)
    sums = _dev(np.zeros((NX, NY)), np.zeros((NX, NY)))
    d_pos, d_rad, d_vol = _dev(pos, radius, volume)
    VC.sauter_deposit[1, VC.THREADS](d_pos, d_rad, d_vol, 1.0 / DX, 1.0 / DY, *sums)
    got = np.empty((NX, NY))
    by_size, by_volume = (a.copy_to_host() for a in sums)
    assert np.any(by_volume == 0.0)  # empty cells: the bed's value
    assert abs(sauter_finish(by_size, by_volume, got) - bed) <= PER_PARTICLE_RTOL * bed
    assert np.all(np.abs(got - expected) <= SUM_RTOL * np.abs(expected).max())


def _cpu_deposit(law, pos, vel, radius, volume, gas, px, py, fold, solids, inv_dbar=None):
    vu = np.full((NX + 1, NY), 1.5 * DX * DY * 4e-3)
    vv = np.full((NX, NY + 1), 1.5 * DX * DY * 4e-3)
    out = {k: np.zeros(s) for k, s in (("AU", vu.shape), ("BU", vu.shape), ("AV", vv.shape), ("BV", vv.shape),
                                       ("KC", (NX, NY)), ("bu", vu.shape), ("su", vu.shape), ("bv", vv.shape),
                                       ("sv", vv.shape))}
    eu, ev = (np.zeros(vu.shape), np.zeros(vv.shape)) if solids else (np.zeros((0, 0)), np.zeros((0, 0)))
    kp = np.zeros(pos.shape[0])
    bad = P.deposit(law, pos, vel, radius, volume, gas["u"], gas["v"], gas["voidage"], gas["rho"], MU,
                    np.zeros((0, 0)) if inv_dbar is None else inv_dbar, DX, DY, 0.3, px, py, kp, out["AU"], out["BU"], out["AV"], out["BV"], out["KC"],
                    DX * DY * 4e-3, vu, vv, out["bu"], out["su"], out["bv"], out["sv"], fold, eu, ev)
    # the pressure voidage before its last step (1 − E/V_f, clipped): the deposited E
    return kp, out, (eu, ev, vu, vv), bad


@pytest.mark.parametrize("law_name", drag_laws.names())
@pytest.mark.parametrize("px,fold,solids,mixture", [(False, True, True, False), (True, False, True, False),
                                                     (False, True, False, False), (False, True, True, True)])
def test_deposit_matches_cpu(law_name, px, fold, solids, mixture):
    """K_p of each particle (every registered drag law), the face sums A_f, B_f, Σ K_p per cell and the particle
    volume on the faces of the pressure term, against ``_paired_kernels.deposit``; out-of-range particles
    counted and given NaN as there. ``mixture``: the polydisperse drag, y = d/D̄ with 1/D̄ of the cells
    interpolated to the particle (DEM book 2012 eqs 10-12)."""
    from fluidem.coupling import _paired_cuda as PC

    pos, vel, radius, volume, gas = _system()
    law = drag_laws.get(law_name)().pack()
    inv_dbar = np.random.default_rng(4).uniform(300.0, 700.0, (NX, NY)) if mixture else np.zeros((0, 0))
    kp, out, (eu, ev, vu, vv), bad = _cpu_deposit(law, pos, vel, radius, volume, gas, px, False, fold, solids,
                                                  inv_dbar)
    assert 0 < bad < pos.shape[0] // 4
    if mixture:  # y ≠ 1 changes K_p (a law without a size correction excepted)
        mono = _cpu_deposit(law, pos, vel, radius, volume, gas, px, False, fold, solids)[0]
        assert not np.allclose(kp[~np.isnan(kp)], mono[~np.isnan(mono)], rtol=1e-3) or "total" in law_name
    sums = {k: np.zeros(s) for k, s in (("AU", vu.shape), ("BU", vu.shape), ("AV", vv.shape), ("BV", vv.shape),
                                        ("KC", (NX, NY)), ("EU", vu.shape), ("EV", vv.shape))}
    dsums = dict(zip(sums, _dev(*sums.values())))
    d_kp, d_bad = _dev(np.zeros(pos.shape[0]), np.zeros(1, dtype=np.int32))
    args = _dev(law, pos, vel, radius, volume, gas["u"], gas["v"], gas["voidage"], gas["rho"])
    PC.deposit[1, PC.THREADS](*args, MU, *_dev(inv_dbar), DX, DY, 0.3, px, False, fold, d_kp, dsums["AU"], dsums["BU"], dsums["AV"],
                              dsums["BV"], dsums["KC"], solids, dsums["EU"], dsums["EV"], d_bad)
    got = {k: a.copy_to_host() for k, a in dsums.items()}
    assert int(d_bad.copy_to_host()[0]) == bad
    gkp = d_kp.copy_to_host()
    assert np.array_equal(np.isnan(gkp), np.isnan(kp))
    ok = ~np.isnan(kp)
    assert np.all(np.abs(gkp[ok] - kp[ok]) <= PER_PARTICLE_RTOL * np.abs(kp[ok]))
    for k in ("AU", "BU", "AV", "BV", "KC"):
        _sum_close(out[k], got[k])
    if solids:  # the CPU turned its sums into 1 − E/V_f (clipped at 0.3): the same on the device's sums
        for e_cpu, e_dev, vf in ((eu, got["EU"], vu), (ev, got["EV"], vv)):
            P._face_voidage(e_dev, vf, 0.3)
            _sum_close(e_cpu, e_dev)


@pytest.mark.parametrize("split", [True, False])
@pytest.mark.parametrize("pressure,dim2", [(True, True), (False, False)])
def test_particle_forces_match_cpu(split, pressure, dim2):
    """The gas force of each particle from K_p (``forces_split`` / ``forces`` against
    ``_paired_kernels.particle_forces_split`` / ``particle_forces``), the engine's total force following."""
    from fluidem.coupling import _paired_cuda as PC

    pos, vel, radius, volume, gas = _system(seed=5)
    gas["rho"][:] = 1.2
    law = drag_laws.get("gidaspow")().pack()
    kp, *_ = _cpu_deposit(law, pos, vel, radius, volume, gas, False, True, True, True)
    rng = np.random.default_rng(2)
    ext, damp, total = rng.normal(size=(pos.shape[0], 3)), rng.uniform(size=pos.shape[0]), rng.normal(
        size=(pos.shape[0], 3))
    d_ext, d_damp, d_total = _dev(ext, damp, total)
    args = _dev(pos, vel, volume, kp, gas["u"], gas["v"], gas["p"])
    if split:
        P.particle_forces_split(pos, vel, volume, kp, gas["u"], gas["v"], gas["p"], DX, DY, False, True, True,
                                pressure, dim2, ext, damp, total)
        PC.forces_split[1, PC.THREADS](*args, DX, DY, False, True, True, pressure, dim2, d_ext, d_damp, d_total)
    else:
        P.particle_forces(pos, vel, volume, kp, gas["u"], gas["v"], gas["p"], DX, DY, False, True, True, pressure,
                          dim2, ext, total)
        PC.forces[1, PC.THREADS](*args, DX, DY, False, True, True, pressure, dim2, d_ext, d_total)
    for cpu, dev in ((ext, d_ext), (damp, d_damp), (total, d_total)):
        got = dev.copy_to_host()
        assert np.all(np.abs(got - cpu) <= PER_PARTICLE_RTOL * np.abs(cpu).max())


@pytest.mark.parametrize("mixture", [False, True])
def test_cell_beta_deposit_matches_cpu(mixture):
    """Σ β/(1 − ε) V_p of the particles centred in each cell over V_cell, β/(1 − ε) at the cell's ε, gas density
    and slip (Sun 2007 eq. 33; with ``mixture`` y = d/D̄ of the cell): ``_cell_cuda.cell_beta_deposit`` against
    ``_exchange_kernels.cell_beta``, out-of-range particles counted and left out as there."""
    from fluidem.coupling import _cell_cuda as CC
    from fluidem.coupling import _exchange_kernels as EK

    pos, vel, radius, volume, gas = _system()
    rng = np.random.default_rng(8)
    su, sv = rng.normal(0.0, 0.3, (NX, NY)), rng.normal(0.0, 0.3, (NX, NY))
    inv_dbar = rng.uniform(300.0, 700.0, (NX, NY)) if mixture else np.zeros((0, 0))
    law = drag_laws.get("beetstra")().pack()
    beta = np.empty((NX, NY))
    vc = DX * DY * 4e-3
    bad = EK.cell_beta(law, pos, radius, volume, gas["u"], gas["v"], gas["rho"], gas["voidage"], su, sv, MU, inv_dbar,
                       DX, DY, vc, beta)
    assert 0 < bad < pos.shape[0] // 4
    d_out, d_bad = _dev(np.zeros((NX, NY)), np.zeros(1, dtype=np.int32))
    args = _dev(law, pos, radius, volume, gas["u"], gas["v"], gas["rho"], gas["voidage"], su, sv)
    CC.cell_beta_deposit[1, CC.THREADS](*args, MU, *_dev(inv_dbar), DX, DY, d_out, d_bad)
    assert int(d_bad.copy_to_host()[0]) == bad
    _sum_close(beta, d_out.copy_to_host() / vc)


@pytest.mark.parametrize("px", [False, True])
def test_pressure_deposit_matches_cpu(px):
    """The particle volume on the faces of each particle's folded ∇p interpolation, finished into the pressure
    voidage 1 − Σ w V_p / V_f (clipped): ``_cell_cuda.pressure_deposit`` against
    ``_paired_kernels.pressure_voidage``."""
    from fluidem.coupling import _cell_cuda as CC

    pos, _, _, volume, _ = _system()
    volume = volume * 30.0  # faces filled past the clipping, some
    vu = np.full((NX + 1, NY), 1.5 * DX * DY * 4e-3)
    vv = np.full((NX, NY + 1), 1.5 * DX * DY * 4e-3)
    eu, ev = np.empty(vu.shape), np.empty(vv.shape)
    P.pressure_voidage(pos, volume, DX, DY, px, False, vu, vv, 0.3, eu, ev)
    assert eu.min() == 0.3 and np.any((eu > 0.3) & (eu < 1.0))  # clipped faces and others
    d_eu, d_ev = _dev(np.zeros(vu.shape), np.zeros(vv.shape))
    CC.pressure_deposit[1, CC.THREADS](*_dev(pos, volume), DX, DY, px, False, d_eu, d_ev)
    for cpu, dev, vf in ((eu, d_eu, vu), (ev, d_ev, vv)):
        got = dev.copy_to_host()
        P._face_voidage(got, vf, 0.3)
        _sum_close(cpu, got)


@pytest.mark.parametrize("pressure,px", [(True, False), (True, True), (False, False)])
def test_cell_forces_match_cpu(pressure, px):
    """Each particle's share V_p/Σ V_r of its cell's drag β V_c (u_c − u_s,c), minus V_p ∇p, the engine's total
    following: ``_cell_cuda.cell_solids`` and ``forces`` against ``_paired_kernels.cell_forces``."""
    from fluidem.coupling import _cell_cuda as CC

    pos, vel, radius, volume, gas = _system(seed=5)
    rng = np.random.default_rng(9)
    beta, su, sv = rng.uniform(0.0, 3e4, (NX, NY)), rng.normal(0.0, 0.3, (NX, NY)), rng.normal(0.0, 0.3, (NX, NY))
    ext, total = rng.normal(size=(pos.shape[0], 3)), rng.normal(size=(pos.shape[0], 3))
    d_ext, d_total = _dev(ext, total)
    vc = DX * DY * 4e-3
    P.cell_forces(pos, vel, volume, beta, su, sv, gas["u"], gas["v"], gas["p"], DX, DY, vc, px, False, pressure, True,
                  ext, total)
    d_pos, d_vol, d_solids = _dev(pos, volume, np.zeros((NX, NY)))
    CC.cell_solids[1, CC.THREADS](d_pos, d_vol, DX, DY, d_solids)
    _sum_close(np.bincount(np.minimum(np.maximum((pos[:, 0] / DX).astype(int), 0), NX - 1) * NY
                           + np.minimum(np.maximum((pos[:, 1] / DY).astype(int), 0), NY - 1), volume,
                           minlength=NX * NY).reshape(NX, NY), d_solids.copy_to_host())
    CC.forces[1, CC.THREADS](d_pos, d_vol, d_solids, *_dev(beta, su, sv, gas["u"], gas["v"], gas["p"]), DX, DY, vc,
                             px, False, pressure, d_ext, d_total)
    for cpu, dev in ((ext, d_ext), (total, d_total)):
        got = dev.copy_to_host()
        assert np.all(np.abs(got - cpu) <= PER_PARTICLE_RTOL * np.abs(cpu).max())


@pytest.mark.parametrize("pressure,mixture", [(True, False), (False, True)])
def test_gas_forces_match_cpu(pressure, mixture):
    """``_cell_cuda.gas_forces`` (the "cell_beta" exchange's force on each particle) against
    ``_exchange_kernels.gas_forces``: particles straddling cell faces and outside the grid, a polydisperse 1/D̄
    field, one cell of negative gas density (NaN forces, counted), total following ext."""
    from fluidem.coupling import _cell_cuda as CC
    from fluidem.coupling import _exchange_kernels as EK
    from fluidem.coupling import interpolation as I
    from fluidem.gas.grid import StaggeredGrid

    pos, vel, radius, volume, gas = _system(seed=13)
    law = drag_laws.get("gidaspow")().pack()
    rng = np.random.default_rng(4)
    inv_dbar = rng.uniform(800.0, 1200.0, (NX, NY)) if mixture else np.zeros((0, 0))
    grid = StaggeredGrid((NX, NY), (NX * DX, NY * DY))
    nodes = (*I._axes(grid, "centre")[:2], grid.x_faces, grid.y_faces)
    ext, total = rng.normal(size=(pos.shape[0], 3)), rng.normal(size=(pos.shape[0], 3))
    d_ext, d_total = _dev(ext, total)
    bad = EK.gas_forces(law, pos, vel, radius, volume, gas["u"], gas["v"], gas["voidage"], gas["rho"], gas["p"], MU,
                        inv_dbar, *nodes, DX, DY, 0.3, pressure, True, ext, total)
    assert 0 < bad < pos.shape[0] // 2
    cen, xfa, yfa = np.empty((NX + 2, NY + 2, 2)), np.zeros((NX + 1, NY + 2, 2)), np.zeros((NX + 2, NY + 1, 2))
    dbar = np.empty((NX + 2, NY + 2) if mixture else (0, 0))
    EK.gas_force_fields(gas["u"], gas["v"], gas["voidage"], gas["rho"], gas["p"], inv_dbar, DX, DY, pressure, cen,
                        xfa, yfa, dbar)
    d_bad = _dev(np.zeros(1, dtype=np.int32))[0]
    CC.gas_forces[1, CC.THREADS](*_dev(law, pos, vel, radius, volume, cen, xfa, yfa, dbar, *nodes), DX, DY, MU, 0.3,
                                 pressure, True, d_ext, d_total, d_bad)
    assert int(d_bad.copy_to_host()[0]) == bad
    for cpu, dev in ((ext, d_ext), (total, d_total)):
        got = dev.copy_to_host()
        assert np.array_equal(np.isnan(got), np.isnan(cpu))
        ok = ~np.isnan(cpu)
        assert np.all(np.abs(got[ok] - cpu[ok]) <= PER_PARTICLE_RTOL * np.abs(cpu[ok]).max())


def _bed(packing_case, coupling, n=150, two_species=False):
    """A 2D bed of n discs of 4 mm (3.6 mm with ``two_species``) on a 4 × 12 gas grid, gas from below, walls
    left and right, the coupling section ``coupling``."""
    case, _ = packing_case("linear_spring_dashpot", n=n, dimensions=2, speed=0.2, two_species=two_species)
    data = case.model_dump()
    width, height, depth = data["walls"][0]["upper"]
    data["walls"][0]["upper"] = [width, 3 * height, depth]
    data["time"]["dt"] = 2e-5
    data["gas"] = {"dt": 8e-5, "grid": {"cells": [4, 12], "size": [width, 3 * height], "depth": depth},
                   "boundaries": {"bottom": {"kind": "inflow", "superficial": 1.5}, "top": {"kind": "pressure_outlet"},
                                  "left": {"kind": "wall"}, "right": {"kind": "wall"}}}
    data["coupling"] = {"drag": "gidaspow", **coupling}
    return data, 3 * height


COUPLED_OPTIONS = {
    "area": ({"voidage": {"method": "area", "to_3d": True}}, False),
    "area_volume": ({"voidage": {"method": "area_volume", "velocity_weighting": "volume"}}, False),
    "sauter_y2": ({"polydisperse": "sauter_y2"}, True),
    "cell": ({"momentum_exchange": "cell"}, False),
    "cell_beta": ({"momentum_exchange": "cell_beta"}, False),
}


@pytest.mark.parametrize("option", list(COUPLED_OPTIONS))
def test_coupled_run_device_matches_host(packing_case, option):
    """The GPU engine with the coupling's particle side on the device (``gpu_exchange = "device"``) against the
    same run with it on the host ("host"), for each option the device took over: over three gas steps of four
    sub-steps the particles and the gas agree to round-off (``test_gpu_engine.test_coupled_run_matches_cpu``'s
    bounds, 1e-9: cell sums in another order, amplified by the contacts)."""
    from fluidem import Simulation
    from fluidem.case import validate_case

    coupling, two_species = COUPLED_OPTIONS[option]
    data, height = _bed(packing_case, coupling, two_species=two_species)
    runs = {}
    for mode in ("device", "host"):
        data["coupling"]["gpu_exchange"] = mode
        sim = Simulation(validate_case({**data, "device": "gpu"}))
        assert type(sim.engine).__name__ == "SoftSphereGPUEngine"
        sim.advance(3 * sim.gas.substeps)
        runs[mode] = sim
    dev, host = runs["device"], runs["host"]
    assert dev.gas._device is not None and host.gas._device is None
    assert dev.gas.substeps == host.gas.substeps == 4 and dev.gas.gas_steps == 3
    assert np.abs(dev.state.position - host.state.position).max() <= 1e-9 * height
    for a, b in ((dev.state.velocity, host.state.velocity), (dev.engine.ext_force, host.engine.ext_force)):
        assert np.abs(a - b).max() <= 1e-9 * np.abs(b).max()
    assert np.abs(host.engine.ext_force[:, 1]).max() > 0.1 * host.state.mass.max() * 9.81  # the gas carries weight
    for k in ("p", "u", "v", "voidage"):
        b = getattr(host.gas.state, k)
        assert np.abs(getattr(dev.gas.state, k) - b).max() <= 1e-9 * np.abs(b).max(), k
    assert np.abs(dev.gas.last_map.voidage - host.gas.last_map.voidage).max() <= SUM_RTOL
    if two_species:  # the polydisperse drag's 1/D̄ per cell of the last map, sizes 4 and 3.6 mm
        inv = host.gas._inv_dbar
        assert inv.shape == (4, 12) and 1 / 4e-3 < inv.max() <= 1 / 3.6e-3 * (1.0 + 1e-12)
        assert inv.min() >= 1 / 4e-3 * (1.0 - 1e-12) and np.any((inv > 250.001) & (inv < 277.7))  # mixed cells
        assert np.abs(dev.gas._inv_dbar - inv).max() <= SUM_RTOL * inv.max()
    assert dev.gas.last_map.voidage.min() < 0.9  # a bed, not a few grains


def test_cell_beta_fields_are_sent_once_per_gas_step_and_after_a_restore(packing_case, tmp_path):
    """With ``drag_update = "substep"`` the "cell_beta" forces are evaluated at every sub-step; their grid fields
    (``_exchange_kernels.gas_force_fields``, the device copies keyed by the coupling's ``gas_version``) change
    only with the gas, the map or a restore, and are built and sent once per gas step. A restore in the middle
    of a gas step (new gas arrays) makes the next sub-step build them again, and the run then repeats the
    sub-steps it made from there bit for bit."""
    from fluidem import Simulation
    from fluidem.case import validate_case

    data, _ = _bed(packing_case, {"momentum_exchange": "cell_beta", "drag_update": "substep"})
    data["coupling"]["gpu_exchange"] = "device"
    sim = Simulation(validate_case({**data, "device": "gpu"}))
    sub = sim.gas.substeps
    assert sub == 4

    def builds(n):
        """Sub-steps one at a time; how many of them sent new fields."""
        out = 0
        for _ in range(n):
            before = sim.gas._device._fields_key
            sim.advance(1)
            out += sim.gas._device._fields_key != before
        return out

    sim.advance(sub)
    assert builds(2 * sub) == 2  # two gas steps of four sub-steps
    assert builds(2) == 1  # half a gas step: a checkpoint here, then the rest of the step
    path = tmp_path / "restart.h5"
    sim.save_checkpoint(path)
    assert builds(2) == 0
    ref = {k: np.array(getattr(sim.state, k)) for k in ("position", "velocity")}
    sim.advance(sub)  # another gas step: the gas changed
    sim.load_checkpoint(path)  # back to the middle of the step before
    assert builds(2) == 1  # the restored gas's fields, sent again (on the device, as before the checkpoint)
    for k, b in ref.items():
        assert np.array_equal(getattr(sim.state, k), b), k
