"""The particle side of the 3D gas coupling on the GPU, for a particle engine whose particles live there.

``gas_coupling3d`` builds the coupling of a case with a 3D gas grid: ``DeviceGasCoupling3D`` for an engine
that keeps its particles on the device (``SoftSphereGPUEngine``), ``exchange3d.GasCoupling3D`` otherwise.
``DeviceGasCoupling3D`` is ``GasCoupling3D`` with its per-particle stages handed to a ``DeviceExchange3D``
where every option of the coupling has a device kernel (``exchange_gpu.refusals``): the voidage map's deposit,
by centre or by the exact sphere-in-cell volume (``_voidage3d_cuda``), each particle's drag coefficient and
the face sums of the ``particle`` exchange on the x-, y- and z-faces (``_paired3d_cuda.deposit3d``), and the
gas force on each particle (``_paired3d_cuda.forces3d``, ``forces_split3d``); for the ``cell`` exchange the
cell β sums, the pressure voidage's face sums and each particle's share of its cell's drag, for ``cell_beta``
the cell β sums and each particle's K_p evaluated at every force (``_cell3d_cuda``).
Per gas step only cell and face arrays cross between host and device: the gas fields go to the device, the
deposited sums come back, and the host finishes them (the fraction over V_cell, ``_voidage3d_kernels.
diffuse3d``, clipping and averages as ``_voidage3d_kernels.map_solids3d``; ``_paired3d_kernels._coefficients``,
``_voidage_of``; the cell β over V_cell and ``_exchange3d_kernels.cell_faces3d``). The gas solve stays on the
host. K_p stays on the device; it comes to the host for checkpoints and ``exchange_balance``.
The first map, at set-up, and the forces before the first gas step are the host's (the particles fetched
once).
"""
from __future__ import annotations

import logging

import numpy as np

from . import _exchange3d_kernels as X3
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

    def __init__(self, coupling):
        super().__init__(coupling)
        if self._cellx:  # the "cell" exchanges' u_s of the third axis
            self._cellx["sw"] = self._cuda.device_array(coupling.grid.shape)
        self._valid = self._cuda.device_array(max(self.n, 1), dtype=np.bool_)  # scratch of ``kp_now3d``

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

    # ------------------------------------------------------------ the "cell" and "cell_beta" exchanges
    def cell_beta(self, voidage, solids_u, solids_v, solids_w, out) -> int:
        """out ← β per cell [kg m^-3 s^-1] of the "cell" exchange (``_exchange3d_kernels.cell_beta3d``, Sun 2007
        eq. 33): Σ β/(1 − ε) V_p of each cell on the device (``_cell3d_cuda.cell_beta_deposit3d``), / V_cell on
        the host; returns the number of particles whose drag arguments are out of range."""
        from . import _cell3d_cuda as C3

        cp, gd, gs, c = self.coupling, self.coupling.grid, self.coupling.state, self._cellx
        self._zero(c["sum"])
        self._zero_bad()
        if self.n:
            d = self.engine.device_arrays()
            self._send(voidage=voidage, rho=gs.rho, u=gs.u, v=gs.v, w=gs.w)
            self._put("cell", c, None, {"su": solids_u, "sv": solids_v, "sw": solids_w})
            g = self._gas
            C3.cell_beta_deposit3d[self._blocks(C3.THREADS), C3.THREADS](
                self.gas_law, d["position"], d["radius"], self._volume(), g["u"], g["v"], g["w"], g["rho"],
                g["voidage"], c["su"], c["sv"], c["sw"], float(cp.solver.props.viscosity), self._send_inv_dbar(),
                float(gd.dx), float(gd.dy), float(gd.dz), c["sum"], self.bad)
        c["sum"].copy_to_host(out)
        out /= gd.cell_volume
        return int(self.bad.copy_to_host()[0])

    def pressure_voidage(self, eu, ev, ew) -> None:
        """eu, ev, ew ← the pressure voidage of the "cell" exchange (``_exchange3d_kernels.pressure_voidage3d``):
        the face sums Σ w_pf V_p on the device (``_cell3d_cuda.pressure_deposit3d``), max(1 − Σ/V_f, ε_min) on the
        host (``_paired3d_kernels._voidage_of``)."""
        from . import _cell3d_cuda as C3

        cp, gd, s = self.coupling, self.coupling.grid, self._sums
        for k in ("EU", "EV", "EW"):
            self._zero(s[k])
        if self.n:
            d = self.engine.device_arrays()
            C3.pressure_deposit3d[self._blocks(C3.THREADS), C3.THREADS](
                d["position"], self._volume(), float(gd.dx), float(gd.dy), float(gd.dz), *cp._periodic, s["EU"],
                s["EV"], s["EW"])
        for k, e, vf in zip(("EU", "EV", "EW"), (eu, ev, ew), cp._face_volumes):
            s[k].copy_to_host(e)
            P3._voidage_of(e, vf, cp.mapping.minimum_voidage)

    def set_cell_forces(self, pressure: bool) -> None:
        """The "cell" exchange's gas force on each particle into the engine's ``ext_force``, its total force
        following (``_exchange3d_kernels.cell_forces3d``): Σ V_p per cell (``_cell3d_cuda.cell_solids3d``), then
        each particle's share of its cell's drag (``_cell3d_cuda.cell_forces3d``); the cell β and u_s of the gas
        step cross once a call."""
        from . import _cell3d_cuda as C3

        if self.n == 0:
            return
        cp, gd, gs, c = self.coupling, self.coupling.grid, self.coupling.state, self._cellx
        d = self.engine.device_arrays()
        self._put("cell", c, cp.gas_version, dict(zip(("beta", "su", "sv", "sw"), cp._cell_inputs)))
        self._send(cp.gas_version, u=gs.u, v=gs.v, w=gs.w, p=gs.p)
        self._zero(c["solids"])
        blocks, threads, g = self._blocks(C3.THREADS), C3.THREADS, self._gas
        C3.cell_solids3d[blocks, threads](d["position"], self._volume(), float(gd.dx), float(gd.dy), float(gd.dz),
                                          c["solids"])
        C3.cell_forces3d[blocks, threads](d["position"], self._volume(), c["solids"], c["beta"], c["su"], c["sv"],
                                          c["sw"], g["u"], g["v"], g["w"], g["p"], float(gd.dx), float(gd.dy),
                                          float(gd.dz), float(gd.cell_volume), *cp._periodic, bool(pressure),
                                          d["ext_force"], d["force"])
        self.engine.device_changed(("ext_force", "force"))

    def set_kp_forces(self, pressure: bool) -> int:
        """The "cell_beta" exchange's gas force on each particle, K_p evaluated now (``GasCoupling3D._gas_forces``):
        K_p at the current gas and particles (``_cell3d_cuda.kp_now3d``, as ``_paired3d_kernels.kp3d``), then
        K_p (u_p − v_p) − V_p ∇p_p into ``ext_force``, the total force following (``_paired3d_cuda.forces3d``,
        boundary faces not folded). Returns the number of particles whose drag arguments are out of range (their
        forces then left as they were, as the host raises before its forces)."""
        from . import _cell3d_cuda as C3

        if self.n == 0:
            return 0
        cp, gd, gs = self.coupling, self.coupling.grid, self.coupling.state
        d = self.engine.device_arrays()
        self._send(cp.gas_version, u=gs.u, v=gs.v, w=gs.w, voidage=gs.voidage, rho=gs.rho, p=gs.p)
        self._zero_bad()
        g, threads = self._gas, C3.THREADS
        blocks = self._blocks(threads)
        C3.kp_now3d[blocks, threads](
            self.law, d["position"], d["velocity"], d["radius"], self._volume(), g["u"], g["v"], g["w"], g["voidage"],
            g["rho"], float(cp.solver.props.viscosity), self._send_inv_dbar(cp.gas_version), float(gd.dx),
            float(gd.dy), float(gd.dz), float(cp.mapping.minimum_voidage), *cp._periodic, bool(cp._fold), self.kp,
            self._valid,
            self.bad)
        bad = int(self.bad.copy_to_host()[0])
        if bad:
            return bad
        self._pc.forces3d[blocks, threads](d["position"], d["velocity"], self._volume(), self.kp, g["u"], g["v"],
                                           g["w"], g["p"], float(gd.dx), float(gd.dy), float(gd.dz), *cp._periodic,
                                           bool(cp._fold), bool(pressure), d["ext_force"], d["force"])
        self.engine.device_changed(("ext_force", "force"))
        return 0


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
            self.gas_version += 1
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

    def _cell_beta_sums(self, fields, beta) -> int:
        if self._device is None:
            return super()._cell_beta_sums(fields, beta)
        return self._device.cell_beta(*fields, beta)  # the particles' sums on the GPU

    def _cell_coefficients(self, smap) -> tuple:
        """``GasCoupling3D._cell_coefficients`` with the particles' sums on the device: the cell β (``cell_beta``)
        and the pressure voidage (``DeviceExchange3D.pressure_voidage``); the face β and u_s of "cell" from the
        cell arrays on the host (``_exchange3d_kernels.cell_faces3d``)."""
        if self._device is None:
            return super()._cell_coefficients(smap)
        solids = (smap.solids_u, smap.solids_v, smap.solids_w)
        cb = self.cell_beta(smap.voidage, *solids)
        self._cell_inputs = (cb,) + tuple(solids)
        beta, face_solids = cb, solids
        if self.exchange == "cell":
            beta, face_solids = fb, fs = self._face_beta, self._face_solids
            X3.cell_faces3d(cb, *solids, *self._periodic, fb[0], fs[0], fb[1], fs[1], fb[2], fs[2])
        self.last_map = smap
        self.last_face_beta = beta if isinstance(beta, tuple) else None
        self.last_beta = cb
        pv = None
        if self._pair_pressure:
            pv = self._pressure_voidage
            self._device.pressure_voidage(*pv)
        return beta, face_solids, pv

    def set_particle_forces(self) -> None:
        # K_p or the cell inputs of the step on the device; "cell_beta" at any time (it reads the gas alone: also
        # before the first gas step and after a restore)
        if self._device is not None and (self._paired_ready or self.exchange == "cell_beta"):
            self._check_gas()
            if self.exchange == "cell":
                self._device.set_cell_forces(bool(self.options.pressure_gradient_force))
            elif self.exchange == "cell_beta":
                bad = self._device.set_kp_forces(bool(self.options.pressure_gradient_force))
                if bad:
                    raise ValueError(f"particle drag: arguments out of range for {bad} particles "
                                     "(voidage must lie in (0, 1], gas density > 0)")
            else:
                self._device.set_forces(self._split, bool(self.options.pressure_gradient_force))
            return
        super().set_particle_forces()

    def _fetch_kp(self) -> None:
        if self._device is not None and self._paired_ready and self.exchange == "particle":
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
        if self._device is not None and self._paired_ready and self.exchange == "particle":
            self._device.put_kp(self._kp)


__all__ = ["DeviceExchange3D", "DeviceGasCoupling3D", "device_exchange3d", "gas_coupling3d"]
