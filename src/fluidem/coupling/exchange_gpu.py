"""The particle side of the 2D gas coupling on the GPU, for a particle engine whose particles live there.

``GasCoupling`` hands its per-particle stages to a ``DeviceExchange`` when the engine keeps its particles on
the device (``SoftSphereGPUEngine``) and every option of the coupling has a device kernel (``refusals``):
the voidage map's deposit by centre or by exact disc areas and the cells' Sauter sums of a polydisperse drag
(``_voidage_cuda``), each particle's drag coefficient and the face sums of the ``particle`` exchange
(``_paired_cuda.deposit``), and the gas force on each particle (``_paired_cuda.forces``, ``forces_split``); for
the ``cell`` exchange the cell β sums, the pressure voidage's face sums and each particle's share of its cell's
drag (``_cell_cuda``); for ``cell_beta`` the same cell β sums and each particle's own drag at the current gas
(``_cell_cuda.gas_forces``, the CPU's ``_exchange_kernels.gas_forces`` per particle). Per gas step only cell
and face arrays cross between host and device: the gas fields go to the device, the deposited sums come back,
and the host finishes them with the CPU's own kernels (``_voidage_kernels.finish_map``,
``_paired_kernels._face_coefficients``, ``_face_voidage``). K_p stays on the device; ``fetch_kp`` brings it to
the host for checkpoints and ``exchange_balance``.
"""
from __future__ import annotations

import numpy as np

from . import _paired_kernels as P
from . import _voidage_kernels as VK
from . import voidage as V
from .voidage import SolidsMap


def refusals(coupling, dimensions: int = 2) -> list[str]:
    """What in the coupling of a GPU engine keeps its particle side on the host, one line each (empty: the
    device exchange runs it). ``dimensions`` of the gas grid: in 3D both voidage methods ('centroid',
    'volume') have device kernels (``exchange3d_gpu``); every exchange ('particle', 'cell', 'cell_beta') has
    them on both grids (``_cell_cuda``, ``_cell3d_cuda``)."""
    opts, out = coupling.options, []
    if opts.gpu_exchange == "host":
        out.append("coupling.gpu_exchange = 'host'")
    if dimensions == 2 and coupling.mapping.method not in ("centroid", "area", "area_volume"):
        out.append(f"coupling.voidage.method = {coupling.mapping.method!r} (the device maps 'centroid', 'area' and "
                   "'area_volume' on a 2D grid)")
    return out


def sauter_finish(by_size, by_volume, out) -> float:
    """out ← 1/D̄ [1/m] of each cell from the device's sums (``_voidage_cuda.sauter_deposit``): Σ V_p/d_p / Σ V_p
    (DEM book 2012 two-phase chapter, eq. 10), a cell without particles taking the bed's value, as
    ``_voidage_kernels.sauter_inverse`` (and ``_voidage3d_kernels.sauter_inverse3d``) finish theirs; returns 1/D̄
    of the bed (0 without particles). by_size, by_volume, out : the grid's cell shape."""
    total_v = float(by_volume.sum())
    bed = float(by_size.sum()) / total_v if total_v > 0.0 else 0.0
    full = by_volume > 0.0
    np.divide(by_size, by_volume, out=out, where=full)
    out[~full] = bed
    return bed


def device_exchange(coupling):
    """A ``DeviceExchange`` for ``coupling`` where its engine keeps the particles on a GPU and ``refusals`` is
    empty, else None (the host path; the log says why)."""
    import logging

    if not hasattr(coupling.engine, "device_arrays") or coupling.grid.dimensions != 2:
        return None
    why = refusals(coupling)
    if why:
        logging.getLogger(__name__).info("gas coupling: the particle side runs on the host (%s)", "; ".join(why))
        return None
    return DeviceExchange(coupling)


class DeviceExchange:
    """Device arrays and launches of the coupling's particle side (module docstring)."""

    def __init__(self, coupling):
        from numba import cuda

        self._cuda = cuda
        self._pc, self._vc = self._kernel_modules()
        self.coupling = coupling
        engine = coupling.engine
        self.engine = engine
        gd = coupling.grid
        self.n = engine.state.n
        self.law = cuda.to_device(np.ascontiguousarray(coupling._law))
        self._volume_of = None
        self.volume = cuda.device_array(max(self.n, 1))
        self.kp = cuda.to_device(np.zeros(max(self.n, 1)))
        self.bad = cuda.to_device(np.zeros(1, dtype=np.int32))
        self._grid_arrays(gd)
        # the polydisperse drag's 1/D̄ per cell ((0, 0) or (0, 0, 0) for none) and the device's sums for it
        self._mixture = coupling._inv_dbar.shape[0] > 0
        self.inv_dbar = cuda.to_device(np.zeros(coupling._inv_dbar.shape))
        self._sauter_sums = tuple(cuda.device_array(gd.shape) for _ in range(2)) if self._mixture else ()
        self._host_sauter = tuple(np.empty(gd.shape) for _ in self._sauter_sums)
        # the "cell" exchange: Σ β/(1 − ε) V_p, Σ V_p by ``_cell``, and the cell β, u_s, v_s the forces share
        self._cellx = {k: cuda.device_array(gd.shape) for k in ("sum", "solids", "beta", "su", "sv")} \
            if coupling.exchange in ("cell", "cell_beta") else {}
        self.gas_law = cuda.to_device(np.ascontiguousarray(coupling._gas_law)) if self._cellx else None
        # the "cell_beta" forces' wall-extended fields (host, device) and interpolation nodes (``set_gas_forces``)
        self._fields = self._dev_fields = self._dev_nodes = None
        self._fields_key = None  # (the coupling's gas_version, pressure) of the fields on the device
        self._sent = {}  # (buffer tag, name) -> the gas_version its device copy holds (``_put``)

    @staticmethod
    def _kernel_modules():
        """The paired-exchange and voidage CUDA modules of the grid's dimension."""
        from . import _paired_cuda, _voidage_cuda

        return _paired_cuda, _voidage_cuda

    def _grid_arrays(self, gd) -> None:
        """The device cell, face-sum and gas arrays of the grid ``gd`` and the host copies of the cell sums."""
        cuda = self._cuda
        self._cells = tuple(cuda.device_array(gd.shape) for _ in range(4))  # Σ V_p, count, Σ w v_x, Σ w v_y
        self._host_cells = tuple(np.empty(gd.shape) for _ in range(4))
        self._sums = {k: cuda.device_array(s) for k, s in (("AU", gd.u_shape), ("BU", gd.u_shape), ("AV", gd.v_shape),
                                                           ("BV", gd.v_shape), ("KC", gd.shape), ("EU", gd.u_shape),
                                                           ("EV", gd.v_shape))}
        self._gas = {k: cuda.device_array(s) for k, s in (("u", gd.u_shape), ("v", gd.v_shape), ("voidage", gd.shape),
                                                          ("rho", gd.shape), ("p", gd.shape))}

    # ------------------------------------------------------------ helpers
    def _blocks(self, threads: int) -> int:
        return max(1, (self.n + threads - 1) // threads)

    def _zero(self, a) -> None:
        threads = self._vc.THREADS
        self._vc.zero[max(1, (a.size + threads - 1) // threads), threads](a)

    def _volume(self):
        """V_p on the device, sent again when the coupling has computed new volumes (``_set_volumes``)."""
        vol = self.coupling.volume
        if vol is not self._volume_of:
            self.volume.copy_to_device(np.ascontiguousarray(vol, dtype=float))
            self._volume_of = vol
        return self.volume

    def _sauter(self, grid) -> None:
        """coupling._inv_dbar ← 1/D̄ of each cell at the current particles (``voidage.sauter_inverse``): the sums on
        the device (``_voidage_cuda.sauter_deposit``, ``_voidage3d_cuda.sauter_deposit3d``), the ratio on the host
        (``sauter_finish``)."""
        if self.n:
            d = self.engine.device_arrays()
            for a in self._sauter_sums:
                self._zero(a)
            threads = self._vc.THREADS
            if grid.dimensions == 3:
                kernel, inv = self._vc.sauter_deposit3d, (1.0 / grid.dx, 1.0 / grid.dy, 1.0 / grid.dz)
            else:
                kernel, inv = self._vc.sauter_deposit, (1.0 / grid.dx, 1.0 / grid.dy)
            kernel[self._blocks(threads), threads](d["position"], d["radius"], self._volume(), *inv,
                                                   *self._sauter_sums)
            for dev, host in zip(self._sauter_sums, self._host_sauter):
                dev.copy_to_host(host)
        else:
            for a in self._host_sauter:
                a[...] = 0.0
        sauter_finish(*self._host_sauter, self.coupling._inv_dbar)

    def _send_inv_dbar(self, version=None):
        """The coupling's 1/D̄ per cell on the device (for ``deposit``), or the empty array of a monodisperse
        drag (``version``: as ``_put``)."""
        if self._mixture:
            self._put("inv_dbar", {"": self.inv_dbar}, version, {"": self.coupling._inv_dbar})
        return self.inv_dbar

    def _send(self, version=None, **fields) -> None:
        """Gas-grid arrays into the device buffers ``self._gas`` (``version``: as ``_put``)."""
        self._put("gas", self._gas, version, fields)

    def _put(self, tag, buffers, version, fields) -> None:
        """Copy each array of ``fields`` into ``buffers`` (device arrays by the same names). With ``version``
        (the coupling's ``gas_version``, which every gas step, map and restore changes) a buffer that already
        holds that version's array is left as it is: the forces of the sub-steps of one gas step send the grid
        once. A copy without a version (a stage's own inputs) is always made and matches no version."""
        for k, a in fields.items():
            key = (tag, k)
            if version is not None and self._sent.get(key) == version:
                continue
            buffers[k].copy_to_device(np.ascontiguousarray(a, dtype=float))
            self._sent[key] = version

    # ------------------------------------------------------------ stages
    def map(self, mapping, grid) -> SolidsMap:
        """particles → grid (``VoidageMapping.map_particles``, method 'centroid', 'area' or 'area_volume'): the
        deposit on the device (``_voidage_cuda.centroid_deposit``, ``area_deposit``), the rest on the host
        (``_voidage_kernels.finish_map``)."""
        shape = grid.shape
        eps, su, sv = np.empty(shape), np.empty(shape), np.empty(shape)
        solids, count, wvx, wvy = self._host_cells
        if self.n:
            d = self.engine.device_arrays()
            for a in self._cells:
                self._zero(a)
            threads = self._vc.THREADS
            by_volume = mapping.velocity_weighting == "volume"
            if mapping.method == "centroid":
                self._vc.centroid_deposit[self._blocks(threads), threads](
                    d["position"], d["velocity"], self._volume(), 1.0 / grid.dx, 1.0 / grid.dy, by_volume,
                    *self._cells)
            else:  # exact disc areas (Hoomans 1996 §3.4), 'area_volume' sharing V_p by them
                self._vc.area_deposit[self._blocks(threads), threads](
                    d["position"], d["velocity"], d["radius"], self._volume(), mapping.method == "area_volume",
                    float(grid.dx), float(grid.dy), by_volume, *self._cells)
            for dev, host in zip(self._cells, self._host_cells):
                dev.copy_to_host(host)
        else:
            for a in self._host_cells:
                a[...] = 0.0
            by_volume = False
        if self._mixture:  # the polydisperse drag's 1/D̄ of this map (GasCoupling._map)
            self._sauter(grid)
        # as ``_voidage_kernels.deposit_solids``: the fraction over V_cell (dx dy for 'area'); the velocity weights
        # are the counts (Hoomans 1996 eq. 50) or the deposit (Sun 2007 eq. 35)
        wsum = solids.copy() if by_volume else count
        frac = solids / V._norm(grid, mapping.method)
        w = mapping.smoothing_width
        rx, ry, steps = V._diffusion_steps(grid, w) if w > 0.0 else (0.0, 0.0, 0)
        clipped = VK.finish_map(frac, wsum, wvx, wvy, rx, ry, steps, mapping.to_3d, V.EQ49_FACTOR,
                                mapping.minimum_voidage, eps, su, sv)
        return SolidsMap(eps, su, sv, int(clipped))

    def deposit(self, voidage, gas) -> int:
        """K_p on the device and the coupling's face sums, β and u_s of the faces, Σ K_p per cell and the
        pressure voidage (``_paired_kernels.deposit``); returns the number of particles whose drag arguments
        are out of range."""
        cp, gd, s = self.coupling, self.coupling.grid, self._sums
        for a in s.values():
            self._zero(a)
        self._zero_bad()
        solids = bool(cp._pair_pressure)
        if self.n:
            d = self.engine.device_arrays()
            self._send(voidage=voidage, rho=gas.rho, u=gas.u, v=gas.v)
            g, threads = self._gas, self._pc.THREADS
            self._pc.deposit[self._blocks(threads), threads](
                self.law, d["position"], d["velocity"], d["radius"], self._volume(), g["u"], g["v"], g["voidage"],
                g["rho"], float(cp.solver.props.viscosity), self._send_inv_dbar(), float(gd.dx), float(gd.dy),
                float(cp.mapping.minimum_voidage), *cp._periodic, bool(cp._fold), self.kp, s["AU"], s["BU"], s["AV"],
                s["BV"], s["KC"], solids, s["EU"], s["EV"], self.bad)
        au, bu, av, bv = cp._faces
        for k, host in (("AU", au), ("BU", bu), ("AV", av), ("BV", bv), ("KC", cp._kp_cells)):
            s[k].copy_to_host(host)
        VU, VV = cp._face_volumes
        P._face_coefficients(au, bu, gd.cell_volume, VU, cp._fold, cp._face_beta[0], cp._face_solids[0])
        P._face_coefficients(av, bv, gd.cell_volume, VV, cp._fold, cp._face_beta[1], cp._face_solids[1])
        if solids:
            eu, ev = cp._pressure_voidage
            s["EU"].copy_to_host(eu)
            s["EV"].copy_to_host(ev)
            P._face_voidage(eu, VU, cp.mapping.minimum_voidage)
            P._face_voidage(ev, VV, cp.mapping.minimum_voidage)
        return int(self.bad.copy_to_host()[0])

    # ------------------------------------------------------------ the "cell" exchange
    def cell_beta(self, voidage, solids_u, solids_v, out) -> int:
        """out ← β per cell [kg m^-3 s^-1] of the "cell" exchange (``_exchange_kernels.cell_beta``, Sun 2007
        eq. 33): Σ β/(1 − ε) V_p of each cell on the device (``_cell_cuda.cell_beta_deposit``), / V_cell on the
        host; returns the number of particles whose drag arguments are out of range."""
        from . import _cell_cuda as CC

        cp, gd, gs, c = self.coupling, self.coupling.grid, self.coupling.state, self._cellx
        self._zero(c["sum"])
        self._zero_bad()
        if self.n:
            d = self.engine.device_arrays()
            self._send(voidage=voidage, rho=gs.rho, u=gs.u, v=gs.v)
            self._put("cell", c, None, {"su": solids_u, "sv": solids_v})
            g = self._gas
            CC.cell_beta_deposit[self._blocks(CC.THREADS), CC.THREADS](
                self.gas_law, d["position"], d["radius"], self._volume(), g["u"], g["v"], g["rho"], g["voidage"],
                c["su"], c["sv"], float(cp.solver.props.viscosity), self._send_inv_dbar(), float(gd.dx),
                float(gd.dy), c["sum"], self.bad)
        c["sum"].copy_to_host(out)
        out /= gd.cell_volume
        return int(self.bad.copy_to_host()[0])

    def pressure_voidage(self, eu, ev) -> None:
        """eu, ev ← the pressure voidage of the "cell" exchange (``_paired_kernels.pressure_voidage``): the face
        sums Σ w_pf V_p on the device (``_cell_cuda.pressure_deposit``), 1 − Σ/V_f clipped on the host."""
        from . import _cell_cuda as CC

        cp, gd, s = self.coupling, self.coupling.grid, self._sums
        self._zero(s["EU"])
        self._zero(s["EV"])
        if self.n:
            d = self.engine.device_arrays()
            CC.pressure_deposit[self._blocks(CC.THREADS), CC.THREADS](
                d["position"], self._volume(), float(gd.dx), float(gd.dy), *cp._periodic, s["EU"], s["EV"])
        s["EU"].copy_to_host(eu)
        s["EV"].copy_to_host(ev)
        VU, VV = cp._face_volumes
        P._face_voidage(eu, VU, cp.mapping.minimum_voidage)
        P._face_voidage(ev, VV, cp.mapping.minimum_voidage)

    def set_cell_forces(self, pressure: bool) -> None:
        """The "cell" exchange's gas force on each particle into the engine's ``ext_force``, its total force
        following (``_paired_kernels.cell_forces``): Σ V_p per cell (``_cell_cuda.cell_solids``), then each
        particle's share of its cell's drag (``_cell_cuda.forces``); the cell β, u_s, v_s of the gas step cross
        once."""
        from . import _cell_cuda as CC

        if self.n == 0:
            return
        cp, gd, gs, c = self.coupling, self.coupling.grid, self.coupling.state, self._cellx
        d = self.engine.device_arrays()
        self._put("cell", c, cp.gas_version, dict(zip(("beta", "su", "sv"), cp._cell_inputs)))
        self._send(cp.gas_version, u=gs.u, v=gs.v, p=gs.p)
        self._zero(c["solids"])
        blocks, threads, g = self._blocks(CC.THREADS), CC.THREADS, self._gas
        CC.cell_solids[blocks, threads](d["position"], self._volume(), float(gd.dx), float(gd.dy), c["solids"])
        CC.forces[blocks, threads](d["position"], self._volume(), c["solids"], c["beta"], c["su"], c["sv"], g["u"],
                                   g["v"], g["p"], float(gd.dx), float(gd.dy), float(gd.cell_volume), *cp._periodic,
                                   bool(pressure), d["ext_force"], d["force"])
        self.engine.device_changed(("ext_force", "force"))

    def set_gas_forces(self, pressure: bool) -> None:
        """The "cell_beta" exchange's gas force on each particle at the current gas into the engine's ``ext_force``,
        its total force following (``GasCoupling._gas_forces``): the wall-extended cell and face fields on the host
        (``_exchange_kernels.gas_force_fields``), each particle's drag and −V_p ∇p on the device
        (``_cell_cuda.gas_forces``). The fields are rebuilt and sent only when the gas, the map or the pressure flag
        changed since the last call (``gas_version``): with ``drag_update = "substep"`` once per gas step, not at
        every sub-step. Raises ValueError where drag arguments are out of range (those forces NaN, as on the
        host)."""
        from . import _cell_cuda as CC
        from . import _exchange_kernels as EK

        if self.n == 0:
            return
        cp, gd, gs = self.coupling, self.coupling.grid, self.coupling.state
        cp._check_gas()
        nx, ny = gd.shape
        key = (cp.gas_version, bool(pressure))
        if key != self._fields_key:
            f = self._fields = self._fields or {
                "cen": np.empty((nx + 2, ny + 2, 2)), "xfa": np.zeros((nx + 1, ny + 2, 2)),
                "yfa": np.zeros((nx + 2, ny + 1, 2)), "dbar": np.empty((nx + 2, ny + 2) if self._mixture else (0, 0))}
            EK.gas_force_fields(gs.u, gs.v, gs.voidage, gs.rho, gs.p, cp._inv_dbar, float(gd.dx), float(gd.dy),
                                bool(pressure), f["cen"], f["xfa"], f["yfa"], f["dbar"])
            if self._dev_fields is None:
                cuda = self._cuda
                self._dev_fields = {k: cuda.device_array(a.shape) for k, a in f.items()}
                self._dev_nodes = tuple(cuda.to_device(np.ascontiguousarray(a, dtype=float)) for a in cp._nodes)
            for k, a in f.items():
                if a.size:
                    self._dev_fields[k].copy_to_device(a)
            self._fields_key = key
        g = self._dev_fields
        self._zero_bad()
        d = self.engine.device_arrays()
        CC.gas_forces[self._blocks(CC.THREADS), CC.THREADS](
            self.law, d["position"], d["velocity"], d["radius"], self._volume(), g["cen"], g["xfa"], g["yfa"],
            g["dbar"], *self._dev_nodes, float(gd.dx), float(gd.dy), float(cp.solver.props.viscosity),
            float(cp.mapping.minimum_voidage), bool(pressure), bool(self.engine.dim2), d["ext_force"], d["force"],
            self.bad)
        self.engine.device_changed(("ext_force", "force"))
        bad = int(self.bad.copy_to_host()[0])
        if bad:
            raise ValueError(f"particle drag: arguments out of range for {bad} particles "
                             "(voidage must lie in (0, 1], gas density > 0)")

    def _zero_bad(self) -> None:
        self.bad.copy_to_device(np.zeros(1, dtype=np.int32))

    def set_forces(self, split: bool, pressure: bool) -> None:
        """The gas force of this step's K_p on each particle into the engine's ``ext_force`` (and with ``split``
        its ``ext_damping``), the engine's total force following (``_paired_kernels.particle_forces_split`` or
        ``particle_forces``); for the "cell_beta" exchange ``set_gas_forces``."""
        if self.coupling.exchange == "cell_beta":
            self.set_gas_forces(pressure)
            return
        if self.n == 0:
            return
        cp, gd, gs = self.coupling, self.coupling.grid, self.coupling.state
        d = self.engine.device_arrays()
        self._send(u=gs.u, v=gs.v, p=gs.p)
        g, threads = self._gas, self._pc.THREADS
        args = (d["position"], d["velocity"], self._volume(), self.kp, g["u"], g["v"], g["p"], float(gd.dx),
                float(gd.dy), *cp._periodic, bool(cp._fold), bool(pressure), bool(self.engine.dim2))
        if split:
            self._pc.forces_split[self._blocks(threads), threads](*args, d["ext_force"], d["ext_damping"], d["force"])
            self.engine.device_changed(("ext_force", "ext_damping", "force"))
        else:
            self._pc.forces[self._blocks(threads), threads](*args, d["ext_force"], d["force"])
            self.engine.device_changed(("ext_force", "force"))

    # ------------------------------------------------------------ K_p on the host
    def fetch_kp(self, out: np.ndarray) -> None:
        """out ← K_p of the last deposit [kg/s], (N,)."""
        if self.n:
            self.kp.copy_to_host(out)

    def put_kp(self, kp: np.ndarray) -> None:
        """K_p from the host (a checkpoint) onto the device."""
        if self.n:
            self.kp.copy_to_device(np.ascontiguousarray(kp, dtype=float))
