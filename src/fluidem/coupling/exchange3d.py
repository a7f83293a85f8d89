"""Two-way coupling of a 3D gas grid (``GasSolver3D``) and 3D particles, one gas step DT at a time.

The stages of ``exchange.GasCoupling`` (read its module docstring) with a third axis:

1. particles → grid: voidage and solids velocity on the (nx, ny, nz) cells (``VoidageMapping`` with
   ``"centroid"`` or ``"volume"``: the exact volume of each sphere in each cell, ``_voidage3d_kernels``);
2. each particle's K_p = β/(1 − ε) V_p at its trilinearly interpolated ε and slip (Sun 2007 eq. 29),
   summed onto the x-, y- and z-faces with the weights that interpolate u, v and w to it
   (``_paired3d_kernels.deposit3d``): the gas takes β_f = A_f / V_f, u_s,f = B_f / A_f and, with
   ``pressure_pairing``, the pressure term's voidage 1 − Σ_p w_pf V_p / V_f;
3. gas from t to t + DT with the implicit −β(u − u_s);
4. grid → particles: K_p (u_p − v_p) − V_p ∇p_p with the same K_p and weights, so that the gas loses exactly
   the momentum (drag and pressure force) the particles gain;
5. the DEM sub-steps (``drag_update``: "substep" with K_p, u_p and ∇p_p of the step and each sub-step's own
   velocity, or "frozen").

``momentum_exchange`` "cell" and "cell_beta" (``_exchange3d_kernels``) have the meaning they have in 2D: β per
cell from the cell's ε and slip |u_c − v_s| (Sun 2007 eq. 33, u_c the centre mean of the cell's faces);
"cell" gives the gas β and u_s averaged onto the faces of the three axes and shares the cell's drag
β V_cell (u_c − v_s) among its particles in proportion to V_p (equal and opposite, with the pressure force
paired as in "particle"); "cell_beta" gives the gas the cell β (averaged onto the faces by the solver) and each
particle its own drag β V_p/(1 − ε)(u_p − v_p) at the trilinearly interpolated gas (``_paired3d_kernels.kp3d``,
boundary faces not folded), not paired (MFIX in Sun 2007). ``boundary_faces`` ("fold" or "exchange", of the
"particle" exchange), ``pressure_gradient_force``, ``pressure_pairing`` ("particle" and "cell") and the
polydisperse drag work as in 2D. ``face_volumes3d`` gives the face control volumes (1.5 V_cell for the first
interior faces along a non-periodic axis, which take in the boundary half cells).
"""
from __future__ import annotations

import numpy as np

from ..gas import _layout3d as L3
from ..gas.solver import GasState
from . import _exchange3d_kernels as X3
from . import _paired3d_kernels as P3
from . import _voidage3d_kernels as VK3
from .exchange import GasCoupling, substeps_per_gas_step

GAS_KEYS_3D = ("p", "rho", "u", "v", "w", "voidage")


def face_volumes3d(n, periodic, vol):
    """(x-face, y-face, z-face) control volumes [m³] of a 3D grid of ``n`` = (nx, ny, nz) cells of volume ``vol``:
    V_cell on every face, and along a non-periodic axis of two cells or more 1.5 V_cell on the first interior
    faces (1 and n − 1; 2 V_cell for the one interior face of a two-cell axis), whose control volumes take in
    the boundary half cells (``exchange.face_volumes``)."""
    out = []
    for a in range(3):
        shape = tuple(m + (1 if q == a else 0) for q, m in enumerate(n))
        f = np.ones(shape)
        m = n[a]
        if not periodic[a] and m >= 2:
            lo = [slice(None)] * 3
            lo[a] = 1
            hi = list(lo)
            hi[a] = m - 1
            f[tuple(lo)] += 0.5
            f[tuple(hi)] += 0.5
        out.append(f * vol)
    return tuple(out)


class GasCoupling3D(GasCoupling):
    """``GasCoupling`` of a case with a 3D gas grid and 3D particles (module docstring).

    ``last_map`` is the ``SolidsMap`` of the last gas step (with ``solids_w``), ``last_beta`` Σ_{p in cell} K_p /
    V_cell (nx, ny, nz) [kg m^-3 s^-1] of that step (the cell β of "cell" and "cell_beta") and ``last_face_beta``
    the (x, y, z) face β the gas took (None for "cell_beta", whose gas took the cell β).
    """

    def __init__(self, case, engine):
        self.case, self.engine = case, engine
        self.section, self.options = case.gas, case.coupling
        self.solver = self.section.build(case.gravity)
        self.grid = gd = self.solver.grid
        self.drag = self.options.drag
        self._law = self.drag.pack()
        self._gas_law = self.drag.gas_side().pack()  # the gas's law per cell ("cell", "cell_beta")
        self.mapping = self.options.voidage
        self.gas_dt = self.section.dt
        self.substeps = substeps_per_gas_step(self.gas_dt, engine.dt)
        engine.dt = self.gas_dt / self.substeps
        engine.time = engine.steps * engine.dt
        st = engine.state
        self._set_volumes()
        self.exchange = self.options.momentum_exchange
        paired = self.exchange == "particle"
        self._split = self.options.drag_update == "substep" and hasattr(engine, "ext_damping") and paired
        self._periodic = tuple(bool(x) for x in self.solver.periodic)
        self._fold = self.options.boundary_faces == "fold" and paired
        self._pair_pressure = (bool(self.options.pressure_pairing) and bool(self.options.pressure_gradient_force)
                               and self.exchange in ("particle", "cell"))
        shapes = [gd.face_shape(a) for a in range(3)]
        self._sums = tuple(np.zeros(shapes[a]) for a in range(3) for _ in range(2))  # A_x, B_x, A_y, B_y, A_z, B_z
        self._face_beta = tuple(np.zeros(s) for s in shapes)
        self._face_solids = tuple(np.zeros(s) for s in shapes)
        self._pressure_voidage = tuple(np.ones(s) for s in shapes)
        self._face_volumes = face_volumes3d(gd.shape, self._periodic, gd.cell_volume)
        self._kp = np.zeros(st.radius.shape)
        self._kp_cells = np.zeros(gd.shape)
        self._map_work = np.empty(0)  # scratch of the particles → grid map (``_voidage3d_kernels.volume_deposit``)
        self._valid = np.empty(st.radius.shape, np.bool_)  # scratch of ``_paired3d_kernels.deposit3d``
        self._cell_inputs = None
        if hasattr(engine, "reorder_listeners"):
            engine.reorder_listeners.append(self._reorder)
        self._paired_ready = False
        self._gas_ok = None
        # changed by every gas step, map and restore: the GPU forces of the sub-steps send the grid only then
        self.gas_version = 0
        self.polydisperse = self.options.resolved_polydisperse(2.0 * st.radius)
        self._inv_dbar = np.zeros(gd.shape if self.polydisperse == "sauter_y2" else (0, 0, 0))
        smap = self._map()
        self.state = self.solver.initial_state(voidage=smap.voidage, velocity=self.section.velocity)
        self.gas_steps = 0
        self.courant_max = 0.0
        self.engine_seconds = 0.0
        self.last_info = None
        self.last_map = smap
        self.last_beta = None
        self.last_face_beta = None
        self.clipped = smap.clipped

    # ------------------------------------------------------------ pieces
    def _map(self):
        """particles → grid at the current positions (``VoidageMapping.map_particles`` on the 3D grid), and the
        cells' 1/D̄ of a polydisperse drag (DEM book 2012 eq. 10)."""
        self.gas_version += 1
        st, gd = self._particles(), self.grid
        if self._inv_dbar.shape[0] > 0:
            VK3.sauter_inverse3d(st.position, st.radius, self.volume, gd.dx, gd.dy, gd.dz, self._inv_dbar)
        need = st.radius.shape[0] * VK3.volume_stride(st.radius, gd.dx, gd.dy, gd.dz, *gd.shape, *self._periodic)
        if self._map_work.shape[0] < need:
            self._map_work = np.empty(need)
        return self.mapping.map_particles(gd, st.position, st.radius, self.volume, st.velocity, self._periodic,
                                          self._map_work)

    def cell_beta(self, voidage, solids_u, solids_v, solids_w=None):
        """β per cell [kg m^-3 s^-1], (nx, ny, nz): Σ_p β/(1 − ε)(ε, |u_c − v_s|, d_p) V_p / V_cell (Sun 2007 eq. 33,
        ``_exchange3d_kernels.cell_beta3d``); solids_w None: 0."""
        gd = self.grid
        if solids_w is None:
            solids_w = np.zeros(gd.shape)
        fields = [np.ascontiguousarray(a, dtype=float) for a in (voidage, solids_u, solids_v, solids_w)]
        if any(f.shape != gd.shape for f in fields):
            raise ValueError(f"voidage, solids_u, solids_v, solids_w must have shape {gd.shape}; "
                             f"got {', '.join(str(f.shape) for f in fields)}")
        self._check_gas()
        beta = np.empty(gd.shape)
        bad = self._cell_beta_sums(fields, beta)
        if bad:
            raise ValueError(f"cell β: drag arguments out of range for {bad} particles "
                             "(voidage must lie in (0, 1], gas density > 0)")
        return beta

    def _cell_beta_sums(self, fields, beta) -> int:
        """beta ← the cell β of ``cell_beta`` from the checked cell fields (ε, u_s, v_s, w_s); returns the number of
        particles whose drag arguments are out of range."""
        gd, st, gs = self.grid, self._particles(), self.state
        return X3.cell_beta3d(self._gas_law, st.position, st.radius, self.volume, gs.u, gs.v, gs.w, gs.rho, *fields,
                              self.solver.props.viscosity, self._inv_dbar, gd.dx, gd.dy, gd.dz, gd.cell_volume, beta)

    def _cell_coefficients(self, smap) -> tuple:
        """Stage 2 of "cell" and "cell_beta": (β, u_s, pressure voidage or None), β and u_s per face ("cell",
        ``_exchange3d_kernels.cell_faces3d``) or per cell ("cell_beta", averaged onto the faces by the solver)."""
        gd = self.grid
        solids = (smap.solids_u, smap.solids_v, smap.solids_w)
        cb = self.cell_beta(smap.voidage, *solids)
        self._cell_inputs = (cb,) + tuple(solids)
        if self.exchange == "cell":
            X3.cell_faces3d(cb, *solids, *self._periodic, self._face_beta[0], self._face_solids[0],
                            self._face_beta[1], self._face_solids[1], self._face_beta[2], self._face_solids[2])
            beta, solids = self._face_beta, self._face_solids
        else:
            beta = cb
        self.last_map = smap
        self.last_face_beta = beta if isinstance(beta, tuple) else None
        self.last_beta = cb
        pv = None
        if self._pair_pressure:
            st = self._particles()
            pv = self._pressure_voidage
            X3.pressure_voidage3d(st.position, self.volume, gd.dx, gd.dy, gd.dz, *self._periodic, *self._face_volumes,
                                  self.mapping.minimum_voidage, *pv)
        return beta, solids, pv

    def _check_gas(self) -> None:
        """The kernels index the gas arrays by the grid's shape: refuse any other (checked once per set of arrays)."""
        gd, gs = self.grid, self.state
        arrays = tuple(getattr(gs, k) for k in GAS_KEYS_3D)
        ok = self._gas_ok
        if ok is not None and all(a is b for a, b in zip(ok, arrays)):
            return
        shapes = (gd.shape, gd.shape, gd.u_shape, gd.v_shape, gd.w_shape, gd.shape)
        for k, a, shape in zip(GAS_KEYS_3D, arrays, shapes):
            if not isinstance(a, np.ndarray) or a.shape != shape or a.dtype != np.float64:
                got = getattr(a, "shape", type(a).__name__)
                raise ValueError(f"gas state {k}: expected {shape} float64, got {got}")
        self._gas_ok = arrays

    def exchange_coefficients(self, smap) -> tuple:
        """Stage 2: (face β, face u_s, pressure voidage or None) of this gas step from each particle's drag
        deposited on the faces (``_paired3d_kernels.deposit3d``), or per cell ("cell", "cell_beta")."""
        if self.exchange != "particle":
            return self._cell_coefficients(smap)
        beta, solids = self._deposit(smap.voidage)
        self.last_map = smap
        self.last_face_beta = beta
        self.last_beta = self._kp_cells / self.grid.cell_volume
        return beta, solids, (self._pressure_voidage if self._pair_pressure else None)

    def advance_gas(self, smap, coefficients) -> None:
        """Stage 3: the gas from t to t + DT with the implicit interphase term −β(u − u_s)."""
        beta, solids, pv = coefficients
        t = self.gas_steps * self.gas_dt
        self.last_info = self.solver.advance(self.state, self.gas_dt, t, voidage=smap.voidage, beta=beta,
                                             solids_u=solids[0], solids_v=solids[1], solids_w=solids[2],
                                             pressure_voidage=pv)
        self.courant_max = max(self.courant_max, self.last_info.courant)
        self.gas_steps += 1
        self.gas_version += 1
        self._paired_ready = True

    def _deposit(self, voidage):
        st, gs, gd = self._particles(), self.state, self.grid
        self._check_gas()
        if self._kp.shape != st.radius.shape:
            self._kp = np.zeros(st.radius.shape)
        if self._valid.shape[0] < st.radius.shape[0]:
            self._valid = np.empty(st.radius.shape, np.bool_)
        bad = P3.deposit3d(self._law, st.position, st.velocity, st.radius, self.volume, gs.u, gs.v, gs.w, voidage,
                           gs.rho, self.solver.props.viscosity, self._inv_dbar, gd.dx, gd.dy, gd.dz,
                           self.mapping.minimum_voidage, *self._periodic, self._fold, self._kp, *self._sums,
                           self._kp_cells, *self._face_volumes, self._face_beta[0], self._face_solids[0],
                           self._face_beta[1], self._face_solids[1], self._face_beta[2], self._face_solids[2],
                           self._pair_pressure, *self._pressure_voidage, self._valid)
        if bad:
            raise ValueError(f"particle drag: arguments out of range for {bad} particles "
                             "(voidage must lie in (0, 1], gas density > 0)")
        return self._face_beta, self._face_solids

    def _kp_now(self) -> None:
        """K_p of every particle at the current gas and particles, without a deposit (forces before the first gas
        step of a run)."""
        st, gs, gd = self._particles(), self.state, self.grid
        self._check_gas()
        if self._kp.shape != st.radius.shape:
            self._kp = np.zeros(st.radius.shape)
        valid = np.empty(st.radius.shape, dtype=np.bool_)
        bad = P3.kp3d(self._law, st.position, st.velocity, st.radius, self.volume, gs.u, gs.v, gs.w, gs.voidage,
                      gs.rho, self.solver.props.viscosity, self._inv_dbar, gd.dx, gd.dy, gd.dz,
                      self.mapping.minimum_voidage, *self._periodic, self._fold, self._kp, valid)
        if bad:
            raise ValueError(f"particle drag: arguments out of range for {bad} particles "
                             "(voidage must lie in (0, 1], gas density > 0)")

    def _gas_forces(self, out, total, pressure=None) -> None:
        """The gas force on each particle at the current gas (K_p evaluated now) into ``out``."""
        if out.shape != self.engine.state.position.shape:
            raise ValueError(f"force arrays: out {out.shape}; expected (N, 3) with N = "
                             f"{self.engine.state.position.shape[0]}")
        self._kp_now()
        self._forces_with_kp(out, total, self.options.pressure_gradient_force if pressure is None else pressure)

    def _forces_with_kp(self, out, total, pressure) -> None:
        st, gs, gd = self._particles(), self.state, self.grid
        P3.particle_forces3d(st.position, st.velocity, self.volume, self._kp, gs.u, gs.v, gs.w, gs.p, gd.dx, gd.dy,
                             gd.dz, *self._periodic, self._fold, bool(pressure), out, total)

    def set_particle_forces(self) -> None:
        """ext_force ← the gas force (the engine's stored total force follows); with the split "substep" drag
        ext_force = K_p u_p − V_p ∇p_p and ext_damping = K_p."""
        eng = self.engine
        if self._split and self._paired_ready:
            st, gs, gd = self._particles(), self.state, self.grid
            self._check_gas()
            P3.particle_forces_split3d(st.position, st.velocity, self.volume, self._kp, gs.u, gs.v, gs.w, gs.p,
                                       gd.dx, gd.dy, gd.dz, *self._periodic, self._fold,
                                       bool(self.options.pressure_gradient_force), eng.ext_force, eng.ext_damping,
                                       st.force)
            return
        self._forces(eng.ext_force, eng.state.force)

    def _forces(self, out, total, pressure=None) -> None:
        pressure = self.options.pressure_gradient_force if pressure is None else pressure
        if self.exchange == "cell_beta" or not self._paired_ready:
            self._gas_forces(out, total, pressure)
            return
        self._check_gas()
        if self.exchange == "cell":
            st, gs, gd = self._particles(), self.state, self.grid
            X3.cell_forces3d(st.position, st.velocity, self.volume, *self._cell_inputs, gs.u, gs.v, gs.w, gs.p, gd.dx,
                             gd.dy, gd.dz, gd.cell_volume, *self._periodic, bool(pressure), out, total)
            return
        self._forces_with_kp(out, total, pressure)

    def exchange_balance(self) -> dict[str, np.ndarray]:
        """Momentum exchanged in the last gas step, (x, y, z) [N] (``GasCoupling.exchange_balance``): ``gas``
        Σ over the solved faces of A_f u_f − B_f = V_f β_f (u_f − u_s,f), ``boundary`` the same over the
        boundary faces the gas does not solve, ``particles`` Σ_p K_p (u_p − v_p); with ``pressure_pairing``
        also ``pressure_gas`` Σ over the solved faces of (1 − ε_p,f) V_f ∂p/∂x_f and ``pressure_particles``
        Σ_p V_p ∇p_p. gas + boundary = particles and pressure_gas = pressure_particles to round-off, at the end
        of the gas step ("particle" and "cell"; for "cell" and "cell_beta" the gas's side is V_cell β_f (u_f − u_s,f)
        with the face β and u_s it took, which "cell_beta" does not pair with the particles' drag)."""
        gd, gs = self.grid, self.state
        if self.last_beta is None:
            raise RuntimeError("exchange_balance: no gas step taken yet")
        n = self.engine.state.position.shape[0]
        drag = np.zeros((n, 3))
        self._forces(drag, np.empty((0, 3)), pressure=False)
        vel = (gs.u, gs.v, gs.w)
        K = self.solver.K
        gas, boundary, pgas = np.zeros(3), np.zeros(3), np.zeros(3)
        grads = self._face_gradients()
        for a in range(3):
            if self.exchange == "particle":
                f = self._sums[2 * a] * vel[a] - self._sums[2 * a + 1]
            elif self.exchange == "cell":
                b = self._face_beta[a]
                f = gd.cell_volume * (b * vel[a] - b * self._face_solids[a])
            else:  # the cell β and u_s as the solver put them on the faces
                b = self.solver._face("beta", self._cell_inputs[0], a)
                f = gd.cell_volume * (b * vel[a] - b * self.solver._face("solids", self._cell_inputs[1 + a], a))
            kind = K[(L3.K_KIND, a) + tuple(slice(0, m) for m in gd.face_shape(a))]
            solved = kind == L3.SOLVED
            copy = kind == L3.COPY
            gas[a] = f[solved].sum()
            boundary[a] = f[~(solved | copy)].sum()
            if self._pair_pressure:
                pgas[a] = ((1.0 - self._pressure_voidage[a]) * self._face_volumes[a] * grads[a])[solved].sum()
        out = {"gas": gas, "boundary": boundary, "particles": drag.sum(axis=0)}
        if self._pair_pressure:
            both = np.zeros((n, 3))
            self._forces(both, np.empty((0, 3)), pressure=True)
            out["pressure_particles"] = (drag - both).sum(axis=0)
            out["pressure_gas"] = pgas
        return out

    def _face_gradients(self) -> tuple:
        """∂p/∂x_a on the faces of each axis as the kernels take it (centred inside, wrapped across a periodic
        side, a wall face copying its interior neighbour)."""
        gd, p = self.grid, self.state.p
        out = []
        for a in range(3):
            g = np.zeros(gd.face_shape(a))
            n = gd.cells[a]
            if n >= 2:
                inner = [slice(None)] * 3
                inner[a] = slice(1, n)
                g[tuple(inner)] = np.diff(p, axis=a) / gd.spacing[a]
                first, last, one, before = ([slice(None)] * 3 for _ in range(4))
                first[a], last[a], one[a], before[a] = 0, n, 1, n - 1
                if self._periodic[a]:
                    lo, hi = [slice(None)] * 3, [slice(None)] * 3
                    lo[a], hi[a] = n - 1, 0
                    g[tuple(first)] = g[tuple(last)] = (p[tuple(hi)] - p[tuple(lo)]) / gd.spacing[a]
                else:
                    g[tuple(first)] = g[tuple(one)]
                    g[tuple(last)] = g[tuple(before)]
            out.append(g)
        return tuple(out)

    # ------------------------------------------------------------ checkpoint
    def checkpoint_arrays(self) -> dict[str, np.ndarray]:
        out = {f"gas/{k}": getattr(self.state, k) for k in GAS_KEYS_3D}
        out.update({f"gas_solver/{k}": v for k, v in self.solver.checkpoint_arrays().items()})
        if self._paired_ready and self.exchange == "particle":
            out["coupling/kp"] = self._kp
        if self._paired_ready and self.exchange == "cell":  # the cell β and u_s the sub-steps' forces read
            out.update(zip(("coupling/cell_beta", "coupling/solids_u", "coupling/solids_v", "coupling/solids_w"),
                           self._cell_inputs))
        if self._inv_dbar.shape[0] > 0:
            out["coupling/inv_dbar"] = self._inv_dbar
        return out

    def restore(self, arrays: dict[str, np.ndarray], scalars: dict) -> None:
        self.state = GasState(**{k: np.ascontiguousarray(arrays[f"gas/{k}"], dtype=float) for k in GAS_KEYS_3D})
        self._check_gas()
        solver = {k.split("/", 1)[1]: v for k, v in arrays.items() if k.startswith("gas_solver/")}
        if solver:
            self.solver.restore_factors(solver)
        self.gas_steps = int(scalars["gas_steps"])
        self.gas_version += 1
        self.courant_max = float(scalars.get("gas_courant_max", 0.0))
        self._set_volumes()
        self._paired_ready = False
        if self.exchange == "particle" and "coupling/kp" in arrays:
            self._kp = np.ascontiguousarray(arrays["coupling/kp"], dtype=float)
            self._paired_ready = True
        if self.exchange == "cell" and "coupling/cell_beta" in arrays:
            self._cell_inputs = tuple(np.ascontiguousarray(arrays[f"coupling/{k}"], dtype=float)
                                      for k in ("cell_beta", "solids_u", "solids_v", "solids_w"))
            self._paired_ready = True
        if self._inv_dbar.shape[0] > 0 and "coupling/inv_dbar" in arrays:
            self._inv_dbar = np.ascontiguousarray(arrays["coupling/inv_dbar"], dtype=float)


__all__ = ["GAS_KEYS_3D", "GasCoupling3D", "face_volumes3d"]
