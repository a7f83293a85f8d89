"""The particle side of the 3D gas coupling on the GPU, for a particle engine whose particles live there.

``gas_coupling3d`` builds the coupling of a case with a 3D gas grid: ``DeviceGasCoupling3D`` for an engine
that keeps its particles on the device (``SoftSphereGPUEngine``), ``exchange3d.GasCoupling3D`` otherwise.
``DeviceGasCoupling3D`` is ``GasCoupling3D`` with its per-particle stages handed to a ``DeviceExchange3D``
where every option of the coupling has a device kernel (``exchange_gpu.refusals``): the voidage map's deposit,
by centre or by the exact sphere-in-cell volume (``_voidage3d_cuda``), each particle's drag coefficient and
the face sums of the ``particle`` exchange on the x-, y- and z-faces (``_paired3d_cuda.deposit3d``), and the
gas force on each particle (``_paired3d_cuda.forces3d``, ``forces_split3d``). Per gas step only cell and face
arrays cross between host and device: the gas fields go to the device, the deposited sums come back, and the
host finishes them (the fraction over V_cell, ``_voidage3d_kernels.diffuse3d``, clipping and averages as
``_voidage3d_kernels.map_solids3d``; ``_paired3d_kernels._coefficients``, ``_voidage_of``). The gas solve
stays on the host. K_p stays on the device; it comes to the host for checkpoints and ``exchange_balance``.
The first map, at set-up, and the forces before the first gas step are the host's (the particles fetched
once).
"""
from __future__ import annotations

import logging

import numpy as np

from . import _paired3d_kernels as P3
from . import _voidage3d_kernels as VK3
from . import voidage as V
from .exchange3d import GasCoupling3D
from .exchange_gpu import DeviceExchange, refusals
from .voidage import SolidsMap


def gas_coupling3d(case, engine):
    """The coupling of ``case`` (a 3D gas grid) with ``engine``: on the GPU's particles where it has them."""
    if hasattr(engine, "device_arrays"):
        return DeviceGasCoupling3D(case, engine)
    return GasCoupling3D(case, engine)


def device_exchange3d(coupling):
    """A ``DeviceExchange3D`` for ``coupling`` where its engine keeps the particles on a GPU and
    ``exchange_gpu.refusals`` is empty, else None (the host path; the log says why)."""
    if not hasattr(coupling.engine, "device_arrays") or coupling.grid.dimensions != 3:
        return None
    why = refusals(coupling, dimensions=3)
    if why:
        logging.getLogger(__name__).info("gas coupling: the particle side runs on the host (%s)", "; ".join(why))
        return None
    return DeviceExchange3D(coupling)


class DeviceExchange3D(DeviceExchange):
    """Device arrays and launches of the 3D coupling's particle side (module docstring)."""

    @staticmethod
    def _kernel_modules():
        from . import _paired3d_cuda, _voidage3d_cuda

        return _paired3d_cuda, _voidage3d_cuda

    def _grid_arrays(self, gd) -> None:
        cuda = self._cuda
        # Σ V_p (or Σ V_pc), count, Σ w v_x, Σ w v_y, Σ w v_z
        self._cells = tuple(cuda.device_array(gd.shape) for _ in range(5))
        self._host_cells = tuple(np.empty(gd.shape) for _ in range(5))
        faces = [gd.face_shape(a) for a in range(3)]
        self._sums = {k: cuda.device_array(s) for k, s in (("AU", faces[0]), ("BU", faces[0]), ("AV", faces[1]),
                                                           ("BV", faces[1]), ("AW", faces[2]), ("BW", faces[2]),
                                                           ("KC", gd.shape), ("EU", faces[0]), ("EV", faces[1]),
                                                           ("EW", faces[2]))}
        self._gas = {k: cuda.device_array(s) for k, s in (("u", faces[0]), ("v", faces[1]), ("w", faces[2]),
                                                          ("voidage", gd.shape), ("rho", gd.shape),
                                                          ("p", gd.shape))}

    def _zero(self, a) -> None:
        threads = self._vc.THREADS
        self._vc.zero3[max(1, (a.size + threads - 1) // threads), threads](a)

    # ------------------------------------------------------------ stages
    def map(self, mapping, grid) -> SolidsMap:
        """particles → grid (``VoidageMapping.map_particles`` on the 3D grid, 'centroid' or 'volume'): the deposit
        on the device, the rest on the host as ``_voidage3d_kernels.map_solids3d`` does it."""
        shape = grid.shape
        solids, count, wvx, wvy, wvz = self._host_cells
        by_volume = mapping.velocity_weighting == "volume"
        px, py, pz = self.coupling._periodic
        if self.n:
            d = self.engine.device_arrays()
            for a in self._cells:
                self._zero(a)
            threads, vc = self._vc.THREADS, self._vc
            inv = (1.0 / grid.dx, 1.0 / grid.dy, 1.0 / grid.dz)
            if mapping.method == "volume":
                vc.volume_deposit3d[self._blocks(threads), threads](
                    d["position"], d["velocity"], d["radius"], float(grid.dx), float(grid.dy), float(grid.dz), *inv,
                    px, py, pz, by_volume, *self._cells)
            else:
                vc.centroid_deposit3d[self._blocks(threads), threads](
                    d["position"], d["velocity"], self._volume(), *inv, by_volume, *self._cells)
            for dev, host in zip(self._cells, self._host_cells):
                dev.copy_to_host(host)
        else:
            for a in self._host_cells:
                a[...] = 0.0
        if self._mixture:  # the polydisperse drag's 1/D̄ of this map (GasCoupling3D._map)
            self._sauter(grid)
        # as ``_voidage3d_kernels.deposit_solids3d``: the fraction over V_cell; the velocity weights are the
        # deposit (Sun 2007 eq. 35) or the counts (Hoomans 1996 eq. 50)
        wsum = solids.copy() if by_volume else count
        frac = solids / grid.cell_volume
        w = mapping.smoothing_width
        if w > 0.0:
            rx, ry, rz, steps = V._diffusion_steps3d(grid, w)
            VK3.diffuse3d(frac, rx, ry, rz, px, py, pz, steps, np.empty(shape))
        eps = 1.0 - frac
        low = eps < mapping.minimum_voidage
        eps[low] = mapping.minimum_voidage
        full = wsum > 0.0
        su, sv, sw = (np.divide(a, wsum, out=np.zeros(shape), where=full) for a in (wvx, wvy, wvz))
        return SolidsMap(eps, su, sv, int(np.count_nonzero(low)), sw)

    def deposit(self, voidage, gas) -> int:
        """K_p on the device and the coupling's face sums, β and u_s of the x-, y- and z-faces, Σ K_p per cell and
        the pressure voidage (``_paired3d_kernels.deposit3d``); returns the number of particles whose drag
        arguments are out of range."""
        cp, gd, s = self.coupling, self.coupling.grid, self._sums
        for a in s.values():
            self._zero(a)
        self._zero_bad()
        pair = bool(cp._pair_pressure)
        if self.n:
            d = self.engine.device_arrays()
            self._send(voidage=voidage, rho=gas.rho, u=gas.u, v=gas.v, w=gas.w)
            g, threads = self._gas, self._pc.THREADS
            self._pc.deposit3d[self._blocks(threads), threads](
                self.law, d["position"], d["velocity"], d["radius"], self._volume(), g["u"], g["v"], g["w"],
                g["voidage"], g["rho"], float(cp.solver.props.viscosity), self._send_inv_dbar(), float(gd.dx),
                float(gd.dy), float(gd.dz), float(cp.mapping.minimum_voidage), *cp._periodic, bool(cp._fold), self.kp,
                s["AU"], s["BU"], s["AV"], s["BV"], s["AW"], s["BW"], s["KC"], pair, s["EU"], s["EV"], s["EW"],
                self.bad)
        for k, host in zip(("AU", "BU", "AV", "BV", "AW", "BW", "KC"), (*cp._sums, cp._kp_cells)):
            s[k].copy_to_host(host)
        for a in range(3):
            P3._coefficients(cp._sums[2 * a], cp._sums[2 * a + 1], cp._face_volumes[a], cp._face_beta[a],
                             cp._face_solids[a])
        if pair:
            for k, e, vf in zip(("EU", "EV", "EW"), cp._pressure_voidage, cp._face_volumes):
                s[k].copy_to_host(e)
                P3._voidage_of(e, vf, cp.mapping.minimum_voidage)
        return int(self.bad.copy_to_host()[0])

    def set_forces(self, split: bool, pressure: bool) -> None:
        """The gas force of this step's K_p on each particle into the engine's ``ext_force`` (and with ``split``
        its ``ext_damping``), the engine's total force following (``_paired3d_kernels.particle_forces_split3d``
        or ``particle_forces3d``)."""
        if self.n == 0:
            return
        cp, gd, gs = self.coupling, self.coupling.grid, self.coupling.state
        d = self.engine.device_arrays()
        self._send(u=gs.u, v=gs.v, w=gs.w, p=gs.p)
        g, threads = self._gas, self._pc.THREADS
        args = (d["position"], d["velocity"], self._volume(), self.kp, g["u"], g["v"], g["w"], g["p"], float(gd.dx),
                float(gd.dy), float(gd.dz), *cp._periodic, bool(cp._fold), bool(pressure))
        if split:
            self._pc.forces_split3d[self._blocks(threads), threads](*args, d["ext_force"], d["ext_damping"],
                                                                    d["force"])
            self.engine.device_changed(("ext_force", "ext_damping", "force"))
        else:
            self._pc.forces3d[self._blocks(threads), threads](*args, d["ext_force"], d["force"])
            self.engine.device_changed(("ext_force", "force"))


class DeviceGasCoupling3D(GasCoupling3D):
    """``GasCoupling3D`` whose particle side runs on the GPU engine's device arrays (module docstring); with a
    refused option (``exchange_gpu.refusals``) it is ``GasCoupling3D`` itself, the particles fetched once a gas
    step. ``_device``: the ``DeviceExchange3D``, or None."""

    def __init__(self, case, engine):
        self._device = None  # the set-up's first map on the host
        super().__init__(case, engine)
        self._device = device_exchange3d(self)

    def _map(self):
        if self._device is not None:
            return self._device.map(self.mapping, self.grid)
        return super()._map()

    def _deposit(self, voidage):
        if self._device is None:
            return super()._deposit(voidage)
        self._check_gas()
        bad = self._device.deposit(voidage, self.state)
        if bad:
            raise ValueError(f"particle drag: arguments out of range for {bad} particles "
                             "(voidage must lie in (0, 1], gas density > 0)")
        return self._face_beta, self._face_solids

    def set_particle_forces(self) -> None:
        if self._device is not None and self._paired_ready:  # K_p of the step on the device
            self._check_gas()
            self._device.set_forces(self._split, bool(self.options.pressure_gradient_force))
            return
        super().set_particle_forces()

    def _fetch_kp(self) -> None:
        if self._device is not None and self._paired_ready:
            if self._kp.shape != (self._device.n,):
                self._kp = np.zeros(self._device.n)
            self._device.fetch_kp(self._kp)

    def exchange_balance(self) -> dict[str, np.ndarray]:
        self._fetch_kp()
        return super().exchange_balance()

    def checkpoint_arrays(self) -> dict[str, np.ndarray]:
        self._fetch_kp()
        return super().checkpoint_arrays()

    def restore(self, arrays: dict[str, np.ndarray], scalars: dict) -> None:
        super().restore(arrays, scalars)
        if self._device is not None and self._paired_ready:
            self._device.put_kp(self._kp)


__all__ = ["DeviceExchange3D", "DeviceGasCoupling3D", "device_exchange3d", "gas_coupling3d"]
