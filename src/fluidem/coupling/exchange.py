"""Two-way coupling of the gas and the particles, one gas step DT at a time.

The stages of every gas step (every ``substeps`` DEM steps), in the order ``Simulation.step``
calls them (``map_to_grid``, ``exchange_coefficients``, ``advance_gas``, ``to_particles``,
``particle_substeps``):

1. particles → grid: voidage ε and cell-averaged solids velocity v_s (``VoidageMapping``,
   Sun 2007 eqs 34-35 / Hoomans 1996 eqs 49-50);
2. the interphase coefficient the gas takes, by ``coupling.momentum_exchange``:
   ``"particle"`` (default): each particle's drag coefficient K_p = β/(1 − ε) V_p at its own
   interpolated ε and slip (Sun 2007 eq. 29), summed onto the faces with the weights that
   interpolate the gas velocity to the particle (``_paired_kernels.deposit``);
   ``"cell"`` and ``"cell_beta"``: β per cell from the cell's ε and the slip |u_cell − v_s|
   (Sun 2007 eq. 33);
3. gas from t to t + DT with the implicit interphase term −β(u − v_s);
4. grid → particles (Hoomans 1996 eqs 40-41), the engine's ``ext_force`` becomes
   ``"particle"``: K_p (u_p − v_p) with the gas of t + DT, the same K_p and weights, so that
   the particles gain exactly the momentum the gas lost (Σ_f w_pf = 1);
   ``"cell"``: the cell's drag β V_cell (u_cell − v_s) shared in proportion to V_p, again
   exactly the gas's loss;
   ``"cell_beta"``: each particle's own drag β V_p/(1 − ε) (u − v_p) — as MFIX in Sun 2007,
   where "particle and gas drag agree only approximately" (the assumption after eq. 35);
   plus −V_p ∇p when enabled (Sun 2007 eq. 28);
5. the DEM sub-steps of DT (the engine's dt is DT / ceil(DT / dt_DEM)).

With ``coupling.boundary_faces = "fold"`` (default) the "particle" exchange hands no drag to a face
whose velocity the gas does not solve (a wall, an inflow): a particle in the half cell along it
exchanges with the first interior face (``_paired_kernels._face_axis``). With ``"exchange"``, and
in the "cell" exchange, drag on such a face is momentum exchanged with that boundary.
``exchange_balance`` reports the three sums. With ``pressure_gradient_force`` and
``pressure_pairing`` (defaults) the gas's pressure term is −ε_p,f ∇p with ε_p,f = 1 − (particle
volume deposited on the face as their ∇p is interpolated) / V_f, so that gas and particles share
−V_f ∇p exactly (``_paired_kernels.pressure_voidage``; ``exchange_balance`` reports both sides).

With ``drag_update = "substep"`` (the default) the drag follows the particles through the
sub-steps in the gas field of t + DT, which makes the pairing approximate: ``"particle"`` keeps
K_p, u_p and ∇p_p of the step and the engine evaluates K_p (u_p − v) − V_p ∇p_p at each
sub-step's own velocity v inside its one compiled call (engines with ``ext_damping``; the
others, and ``"cell"`` and ``"cell_beta"``, repeat step 4 before every sub-step with the current
positions and velocities, ``"cell_beta"`` re-evaluating β). ``"frozen"`` holds the force of
step 4 for the whole DT: then the particles gain exactly the momentum the gas lost. The phase within DT
is ``engine.steps % substeps``, so a run can stop (observers, checkpoints) after any DEM step
and continue exactly.

Every step above is one compiled call (``_voidage_kernels.map_solids``, ``_paired_kernels``,
``_exchange_kernels``), the drag law passed as its packed row; this module only hands
them arrays. With the particles on a GPU (``SoftSphereGPUEngine``) the per-particle parts of steps 1, 2
and 4 run there (``exchange_gpu.DeviceExchange``, where the options allow it: ``exchange_gpu.refusals``), and
only cell and face arrays cross between host and device.
"""
from __future__ import annotations

import math
import time

import numba
import numpy as np

from ..gas.solver import GasState
from ..gas import _layout as GL
from ..gas._operators import centre_to_x_faces, centre_to_y_faces
from . import _exchange_kernels as K
from . import _voidage_kernels as VK
from . import _paired_kernels as P
from . import interpolation as I

GAS_KEYS = ("p", "rho", "u", "v", "voidage")
_NO_TOTAL = np.empty((0, 3))  # ``_gas_forces`` without a total force to follow


def substeps_per_gas_step(gas_dt: float, dem_dt: float) -> int:
    """Number of DEM steps per gas step: ceil(DT / dt_DEM), tolerant of round-off in the ratio."""
    return max(1, math.ceil(gas_dt / dem_dt * (1.0 - 1e-9)))


def face_volumes(n, periodic, vol):
    """(nx + 1, ny) x-face and (nx, ny + 1) y-face control volumes [m³] for folded weights.

    n = (nx, ny), periodic = (px, py), vol = V_cell. A face's momentum control volume reaches from the
    centre before it to the centre after it (V_cell); along a non-periodic axis of two cells or more the
    half cell between the boundary face and the first centre has none of its own, and folding hands its
    particles to the first interior face (``_face_axis``), so that face's volume counts it too: 1.5 V_cell
    (2 V_cell for the one interior face of a two-cell axis). With it a face's β = Σ w K_p / V_f and solids
    fraction Σ w V_p / V_f are those of the region its particles come from (a uniform bed gives the same
    values on every face), and the pressure at the boundary is the first face's gradient extrapolated over
    that half cell (``analysis.fluidised.pressure_at_heights``)."""
    nx, ny = n
    out = []
    for shape, axis in (((nx + 1, ny), 0), ((nx, ny + 1), 1)):
        f = np.ones(shape)
        m = n[axis]
        if not periodic[axis] and m >= 2:
            lo = [slice(None), slice(None)]
            lo[axis] = 1
            hi = list(lo)
            hi[axis] = m - 1
            f[tuple(lo)] += 0.5
            f[tuple(hi)] += 0.5
        out.append(f * vol)
    return out[0], out[1]


class GasCoupling:
    """Owns the gas solver and state of a coupled run and drives ``engine`` through gas steps.

    Sets ``engine.dt`` to DT / substeps on construction. ``last_map`` is the ``SolidsMap`` of the
    last gas step (at construction: the initial one) and ``last_beta`` the cell β (nx, ny)
    [kg m^-3 s^-1] of that step (None before the first gas step of this object): the β the gas
    took ("cell", "cell_beta"), or Σ_{p in cell} K_p / V_cell ("particle", whose gas took the
    face values ``last_face_beta``, a pair of x- and y-face arrays); analyses may read them,
    never write them.
    """

    def __init__(self, case, engine):
        self.case, self.engine = case, engine
        self.section, self.options = case.gas, case.coupling
        self.solver = self.section.build(case.gravity)
        self.grid = self.solver.grid
        self.drag = self.options.drag
        self._law = self.drag.pack()  # the packed rows the kernels read: the particles' law, the gas's per cell
        self._gas_law = self.drag.gas_side().pack()
        self.mapping = self.options.voidage
        self.gas_dt = self.section.dt
        self.substeps = substeps_per_gas_step(self.gas_dt, engine.dt)
        engine.dt = self.gas_dt / self.substeps
        engine.time = engine.steps * engine.dt
        st = engine.state
        self._set_volumes()
        self.exchange = self.options.momentum_exchange
        # "substep" drag of the "particle" exchange: the engine evaluates K_p (u_p − v) − V_p ∇p at every
        # sub-step's own velocity (ext_force = K_p u_p − V_p ∇p, ext_damping = K_p), in its one compiled call
        self._split = (self.options.drag_update == "substep" and self.exchange == "particle"
                       and hasattr(engine, "ext_damping"))
        ipar = self.solver._ipar
        self._periodic = (bool(ipar[GL.I_PX]), bool(ipar[GL.I_PY]))
        gd = self.grid
        self._faces = tuple(np.zeros(gd.u_shape) for _ in range(2)) + tuple(np.zeros(gd.v_shape) for _ in range(2))
        self._kp = np.zeros(st.radius.shape)  # K_p of the "particle" exchange [kg/s]
        self._kp_cells = np.zeros(self.grid.shape)  # Σ K_p per cell of the last deposit [kg/s]
        # face β and u_s of the "particle" exchange, (x faces, y faces) each
        self._face_beta = (np.zeros(gd.u_shape), np.zeros(gd.v_shape))
        self._face_solids = (np.zeros(gd.u_shape), np.zeros(gd.v_shape))
        self._cell_inputs = None  # β, v_s,x, v_s,y per cell of the "cell" exchange
        self._fold = self.options.boundary_faces == "fold" and self.exchange == "particle"
        # the gas's pressure term paired with the particles' −V_p ∇p (CouplingSection.pressure_pairing)
        self._pair_pressure = (bool(self.options.pressure_pairing) and bool(self.options.pressure_gradient_force)
                               and self.exchange in ("particle", "cell"))
        self._pressure_voidage = (np.ones(gd.u_shape), np.ones(gd.v_shape))
        # face control volumes with the boundary half cells counted in the first interior faces
        self._face_volumes = face_volumes(gd.shape, self._periodic, gd.cell_volume)
        self._no_faces = np.zeros((0, 0))
        if hasattr(engine, "reorder_listeners"):  # per-particle arrays here follow the engine's renumbering
            engine.reorder_listeners.append(self._reorder)
        self._paired_ready = False  # K_p / cell inputs of a gas step at hand (else forces as "cell_beta")
        xc, yc = I._axes(self.grid, "centre")[:2]
        self._nodes = (xc, yc, self.grid.x_faces, self.grid.y_faces)  # interpolation nodes, Hoomans eqs 40-41
        self._gas_ok = None  # the gas arrays _check_gas found right
        # polydisperse drag (CouplingSection.polydisperse): 1/D̄ per cell of the gas step's map, (0, 0) for none
        self.polydisperse = self.options.resolved_polydisperse(2.0 * st.radius)
        self._inv_dbar = np.zeros(gd.shape if self.polydisperse == "sauter_y2" else (0, 0))
        self._device = None
        # changed by every gas step, map and restore: the GPU forces of the sub-steps send the grid only then
        self.gas_version = 0
        if hasattr(engine, "device_arrays"):  # particles on a GPU: the particle side there too, where it can
            from .exchange_gpu import device_exchange

            self._device = device_exchange(self)
        smap = self._map()
        self.state = self.solver.initial_state(voidage=smap.voidage, velocity=self.section.initial_velocity)
        self.gas_steps = 0
        self.courant_max = 0.0  # largest gas Courant number of the run's steps (StepInfo.courant) [-]
        self.engine_seconds = 0.0  # wall time in the particle engine's advance calls of this object [s] (a counter)
        self.last_info = None
        self.last_map = smap
        self.last_beta = None
        self.last_face_beta = None
        self.clipped = smap.clipped

    # ------------------------------------------------------------ pieces
    def _set_volumes(self) -> None:
        """V_p = π/6 d³ of the engine's particles, in their current numbering [m³]."""
        self.volume = math.pi / 6.0 * (2.0 * self.engine.state.radius) ** 3

    def _reorder(self, order) -> None:
        """The engine renumbered its particles (new k is former order[k]): so do the per-particle arrays here."""
        self._set_volumes()
        if self._kp.shape == order.shape:
            self._kp = self._kp[order]

    def _map(self):
        """particles → grid at the current positions: a ``SolidsMap`` (Sun 2007 eqs 34-35 / Hoomans eqs 49-50),
        and the cells' 1/D̄ of a polydisperse drag (DEM book 2012 eq. 10, ``voidage.sauter_inverse``)."""
        self.gas_version += 1  # the map's 1/D̄ changes what the gas force reads
        if self._device is not None:
            return self._device.map(self.mapping, self.grid)
        st = self._particles()
        if self._inv_dbar.shape[0] > 0:
            VK.sauter_inverse(st.position, st.radius, self.volume, self.grid.dx, self.grid.dy, self._inv_dbar)
        return self.mapping.map_particles(self.grid, st.position, st.radius, self.volume, st.velocity)

    def cell_beta(self, voidage, solids_u, solids_v) -> np.ndarray:
        """β per cell [kg m^-3 s^-1], (nx, ny): Σ_p β/(1 − ε)(ε, |u − v_s|, d_p) V_p / V_cell (Sun 2007 eq. 33)."""
        gd, gs = self.grid, self.state
        fields = [np.asarray(a, float) for a in (voidage, solids_u, solids_v)]
        if any(f.shape != gd.shape for f in fields):
            raise ValueError(f"voidage, solids_u, solids_v must have shape {gd.shape}; "
                             f"got {', '.join(str(f.shape) for f in fields)}")
        self._check_gas()
        beta = np.empty(gd.shape)
        if self._device is not None:  # the particles' sums on the GPU (exchange_gpu.DeviceExchange.cell_beta)
            bad = self._device.cell_beta(*fields, beta)
        else:
            st = self._particles()
            bad = K.cell_beta(self._gas_law, st.position, st.radius, self.volume, gs.u, gs.v, gs.rho, *fields,
                              self.solver.props.viscosity, self._inv_dbar, gd.dx, gd.dy, gd.cell_volume, beta)
        if bad:
            raise ValueError(f"cell β: drag arguments out of range for {bad} particles "
                             "(voidage must lie in (0, 1], gas density > 0)")
        return beta

    def particle_forces(self, out=None) -> np.ndarray:
        """Gas force on each particle [N], (N, 3): drag (Sun 2007 eq. 29) and, if enabled, −V_p ∇p (eq. 28).

        The gas fields are interpolated to the centres as ``interpolation.sample_gas`` does
        (Hoomans 1996 eqs 40-41) and the voidage clipped to [minimum_voidage, 1]. ``out``: an
        (N, 3) float64 array to write into (returned).
        """
        n = self.engine.state.position.shape[0]
        if out is None:
            out = np.empty((n, 3))
        elif out.shape != (n, 3) or out.dtype != np.float64:
            raise ValueError(f"out must be ({n}, 3) float64; got {out.shape} {out.dtype}")
        self._gas_forces(out, _NO_TOTAL)
        return out

    def _gas_forces(self, out, total, pressure=None) -> None:
        """``particle_forces`` into ``out``; ``total`` (N, 3) follows the change of ``out`` ((0, 3): none)."""
        st, gs, gd = self._particles(), self.state, self.grid
        self._check_gas()
        if out.shape != st.position.shape or total.shape[0] not in (0, out.shape[0]) or total.shape[1:] != (3,):
            raise ValueError(f"force arrays: out {out.shape}, total {total.shape}; expected (N, 3) with N = "
                             f"{st.position.shape[0]}")
        bad = K.gas_forces(self._law, st.position, st.velocity, st.radius, self.volume, gs.u, gs.v,
                           gs.voidage, gs.rho, gs.p, self.solver.props.viscosity, self._inv_dbar, *self._nodes,
                           gd.dx, gd.dy,
                           self.mapping.minimum_voidage,
                           bool(self.options.pressure_gradient_force if pressure is None else pressure),
                           bool(self.engine.dim2), out, total)
        if bad:
            raise ValueError(f"particle drag: arguments out of range for {bad} particles "
                             "(voidage must lie in (0, 1], gas density > 0)")

    def _particles(self):
        """The engine's particle state, checked against what the kernels index (N rows everywhere)."""
        st = self.engine.state
        n = st.position.shape[0]
        if self.volume.shape != (n,):  # particles added or removed since construction
            self._set_volumes()
        if st.position.shape != (n, 3) or st.velocity.shape != (n, 3) or st.radius.shape != (n,):
            raise ValueError(f"particle state: position, velocity (N, 3) and radius (N,) expected; got "
                             f"{st.position.shape}, {st.velocity.shape}, {st.radius.shape}")
        return st

    def _check_gas(self) -> None:
        """The kernels index the gas arrays by the grid's shape: refuse any other (e.g. a replaced ``state``).

        Arrays found right once are remembered (references, so that their identities stay theirs) and not
        checked again while the state holds the same objects: twice a gas step otherwise."""
        gd, gs = self.grid, self.state
        ok = self._gas_ok
        if ok is not None and ok[0] is gs.p and ok[1] is gs.rho and ok[2] is gs.voidage and ok[3] is gs.u \
                and ok[4] is gs.v:
            return
        for k, shape in (("p", gd.shape), ("rho", gd.shape), ("voidage", gd.shape), ("u", gd.u_shape),
                         ("v", gd.v_shape)):
            a = getattr(gs, k)
            if a.shape != shape or a.dtype != np.float64:
                raise ValueError(f"gas state {k}: expected {shape} float64, got {a.shape} {a.dtype}")
        self._gas_ok = (gs.p, gs.rho, gs.voidage, gs.u, gs.v)

    def gas_step(self) -> None:
        """The gas's part of one gas step (``Simulation.step``'s first four stages): ``map_to_grid``,
        ``exchange_coefficients``, ``advance_gas``, ``to_particles``."""
        smap = self.map_to_grid()
        self.advance_gas(smap, self.exchange_coefficients(smap))
        self.to_particles()

    def map_to_grid(self):
        """Stage 1: particles → grid at the current positions, the ``SolidsMap`` of this gas step."""
        smap = self._map()
        self.clipped = smap.clipped
        return smap

    def exchange_coefficients(self, smap) -> tuple:
        """Stage 2: the interphase coefficients the gas takes this step, (β, u_s, v_s, pressure voidage):
        from each particle's drag deposited on the faces ("particle"), or per cell (Sun 2007 eq. 33).

        ``last_beta`` of the "particle" exchange is Σ_{p in cell} K_p / V_cell (as Sun 2007 eq. 33 sums
        it; the cell of a particle is floor(x/dx), clipped), for output; the gas itself took the face values."""
        gd = self.grid
        if self.exchange == "particle":
            beta, us, vs = self._deposit(smap.voidage)
        else:
            cb = self.cell_beta(smap.voidage, smap.solids_u, smap.solids_v)
            self._cell_inputs = (cb, smap.solids_u, smap.solids_v)
            if self.exchange == "cell":
                bu, su, bv, sv = self._faces
                P.cell_faces(cb, smap.solids_u, smap.solids_v, *self._periodic, bu, su, bv, sv)
                beta, us, vs = (bu, bv), su, sv
            else:
                beta, us, vs = cb, smap.solids_u, smap.solids_v
        self.last_map = smap
        self.last_face_beta = beta if isinstance(beta, tuple) else None
        self.last_beta = self._kp_cells / gd.cell_volume if self.exchange == "particle" else self._cell_inputs[0]
        pv = None
        if self._pair_pressure:
            pv = self._pressure_voidage
            if self.exchange != "particle" and self._device is not None:  # "cell" with the particles on a GPU
                self._device.pressure_voidage(*pv)
            elif self.exchange != "particle":  # "particle": ``_deposit`` has filled them
                st = self._particles()
                P.pressure_voidage(st.position, self.volume, gd.dx, gd.dy, *self._periodic, *self._face_volumes,
                                   self.mapping.minimum_voidage, *pv)
        return beta, us, vs, pv

    def advance_gas(self, smap, coefficients) -> None:
        """Stage 3: the gas from t to t + DT with the implicit interphase term −β(u − u_s) (Hoomans 1996
        eqs 42-48)."""
        beta, us, vs, pv = coefficients
        t = self.gas_steps * self.gas_dt
        self.last_info = self.solver.advance(self.state, self.gas_dt, t, voidage=smap.voidage, beta=beta,
                                             solids_u=us, solids_v=vs, pressure_voidage=pv)
        self.courant_max = max(self.courant_max, self.last_info.courant)
        self.gas_steps += 1
        self.gas_version += 1
        self._paired_ready = True

    def to_particles(self) -> None:
        """Stage 4: grid → particles, the gas force of this step's exchange on each particle (Hoomans 1996
        eqs 40-41; Sun 2007 eqs 28-29): ``set_particle_forces``."""
        self.set_particle_forces()

    def particle_substeps(self, n: int) -> int:
        """Stage 5: up to ``n`` DEM sub-steps of the current gas step (n ≤ substeps − phase) in the engine;
        returns how many were taken. With ``drag_update = "substep"`` on an engine that cannot follow its drag
        itself (no ``ext_damping``, or the "cell" exchanges), one at a time, the gas force evaluated anew before
        each but the first of the gas step."""
        eng = self.engine
        if self.options.drag_update == "substep" and not self._split:
            if eng.steps % self.substeps > 0:
                self.set_particle_forces()
            n = 1
        t0 = time.perf_counter()
        eng.advance(n)
        self.engine_seconds += time.perf_counter() - t0
        return n

    def _deposit(self, voidage):
        """K_p and the face β, u_s of the "particle" exchange at the current particles and gas (step 2)."""
        if self._device is not None:
            self._check_gas()
            bad = self._device.deposit(voidage, self.state)
            if bad:
                raise ValueError(f"particle drag: arguments out of range for {bad} particles "
                                 "(voidage must lie in (0, 1], gas density > 0)")
            return self._face_beta, self._face_solids[0], self._face_solids[1]
        st, gs, gd = self._particles(), self.state, self.grid
        self._check_gas()
        if self._kp.shape != st.radius.shape:
            self._kp = np.zeros(st.radius.shape)
        au, bu_, av, bv_ = self._faces
        bad = P.deposit(self._law, st.position, st.velocity, st.radius, self.volume, gs.u, gs.v, voidage,
                        gs.rho, self.solver.props.viscosity, self._inv_dbar, gd.dx, gd.dy,
                        self.mapping.minimum_voidage,
                        *self._periodic, self._kp, au, bu_, av, bv_, self._kp_cells, gd.cell_volume,
                        *self._face_volumes, self._face_beta[0], self._face_solids[0], self._face_beta[1],
                        self._face_solids[1],
                        self._fold, *(self._pressure_voidage if self._pair_pressure else (self._no_faces,) * 2),
                        numba.get_num_threads() > 1)
        if bad:
            raise ValueError(f"particle drag: arguments out of range for {bad} particles "
                             "(voidage must lie in (0, 1], gas density > 0)")
        return self._face_beta, self._face_solids[0], self._face_solids[1]

    def set_particle_forces(self) -> None:
        """ext_force ← the gas force; the engine's stored total force (used by the next half kick) follows.

        One compiled pass: force += new − ext_force, ext_force = new, per particle. Drag arguments
        out of range raise ValueError after the pass (those particles' forces are then NaN).
        """
        eng = self.engine
        # the "particle" or "cell" exchange on the GPU once a gas step made its sums; "cell_beta" at any time (it
        # reads the gas alone: also before the first gas step and after a restore)
        if self._device is not None and (self._paired_ready or self.exchange == "cell_beta"):
            self._check_gas()
            if self.exchange == "cell":
                self._device.set_cell_forces(bool(self.options.pressure_gradient_force))
            else:
                self._device.set_forces(self._split, bool(self.options.pressure_gradient_force))
            return
        if self._split and self._paired_ready:
            st, gs, gd = self._particles(), self.state, self.grid
            self._check_gas()
            P.particle_forces_split(st.position, st.velocity, self.volume, self._kp, gs.u, gs.v, gs.p, gd.dx, gd.dy,
                                    *self._periodic, self._fold, bool(self.options.pressure_gradient_force),
                                    bool(eng.dim2),
                                    eng.ext_force, eng.ext_damping, st.force, numba.get_num_threads() > 1)
            return
        self._forces(eng.ext_force, eng.state.force)

    def _forces(self, out, total, pressure=None) -> None:
        """The gas force of this step's exchange into ``out`` (``total`` follows, or (0, 3))."""
        pressure = self.options.pressure_gradient_force if pressure is None else pressure
        if self.exchange == "cell_beta" or not self._paired_ready:
            self._gas_forces(out, total, pressure)
            return
        st, gs, gd = self._particles(), self.state, self.grid
        self._check_gas()
        if self.exchange == "particle":
            P.particle_forces(st.position, st.velocity, self.volume, self._kp, gs.u, gs.v, gs.p, gd.dx, gd.dy,
                              *self._periodic, self._fold, bool(pressure), bool(self.engine.dim2), out, total)
        else:
            P.cell_forces(st.position, st.velocity, self.volume, *self._cell_inputs, gs.u, gs.v, gs.p, gd.dx, gd.dy,
                          gd.cell_volume, *self._periodic, bool(pressure), bool(self.engine.dim2), out, total)

    def exchange_balance(self) -> dict[str, np.ndarray]:
        """Drag of the last gas step, (x, y) [N]: ``gas`` Σ over the faces the gas solves of
        V_f β_f (u_f − u_s,f) (what the gas lost), ``boundary`` the same over the other faces (wall,
        inflow: exchanged with the boundary), ``particles`` Σ_p of the particle drag (without −V_p ∇p).
        For ``"particle"`` and ``"cell"`` gas + boundary = particles to round-off, at the end of the
        gas step (before the DEM sub-steps move the particles). With ``pressure_pairing`` also
        ``pressure_gas``, Σ over the solved faces of (1 − ε_p,f) V_f ∇p_f (V_f of
        ``face_volumes``; the pressure force the gas gives up against a gas of voidage 1),
        and ``pressure_particles``, Σ_p V_p ∇p_p: equal to round-off."""
        gd, gs = self.grid, self.state
        if self.last_beta is None:
            raise RuntimeError("exchange_balance: no gas step taken yet")
        if self._device is not None:
            self._device.fetch_kp(self._kp)
        n = self.engine.state.position.shape[0]
        drag = np.zeros((n, 3))
        self._forces(drag, np.empty((0, 3)), pressure=False)
        beta = self.last_face_beta if self.last_face_beta is not None else self.last_beta
        if isinstance(beta, tuple):
            bu, bv = beta
        else:
            bu, bv = np.empty(gd.u_shape), np.empty(gd.v_shape)
            centre_to_x_faces(beta, self._periodic[0], bu)
            centre_to_y_faces(beta, self._periodic[1], bv)
        if self.exchange == "particle":  # V_f (β_f u − β_f u_s,f) = A_f u − B_f whatever the face volumes
            au, bu_, av, bv_ = self._faces
            fu, fv = au * gs.u - bu_, av * gs.v - bv_
        else:
            smap = self.last_map
            if self.exchange == "cell":
                _, su, _, sv = self._faces
            else:
                su, sv = np.empty(gd.u_shape), np.empty(gd.v_shape)
                centre_to_x_faces(smap.solids_u, self._periodic[0], su)
                centre_to_y_faces(smap.solids_v, self._periodic[1], sv)
            fu = gd.cell_volume * (bu * gs.u - bu * su)
            fv = gd.cell_volume * (bv * gs.v - bv * sv)
        solved_u = self.solver.ukind == GL.SOLVED
        solved_v = self.solver.vkind == GL.SOLVED
        copy_u = self.solver.ukind == GL.COPY
        copy_v = self.solver.vkind == GL.COPY
        gas = np.array([fu[solved_u].sum(), fv[solved_v].sum()])
        boundary = np.array([fu[~(solved_u | copy_u)].sum(), fv[~(solved_v | copy_v)].sum()])
        out = {"gas": gas, "boundary": boundary, "particles": drag[:, :2].sum(axis=0)}
        if self._pair_pressure:
            both = np.zeros((n, 3))
            self._forces(both, np.empty((0, 3)), pressure=True)
            out["pressure_particles"] = (drag - both)[:, :2].sum(axis=0)  # Σ_p V_p ∇p_p
            gx, gy = I.pressure_gradient(gd, gs.p, "copy", self._periodic)  # as ``_paired_kernels`` takes it
            eu, ev = self._pressure_voidage
            vu, vv = self._face_volumes
            out["pressure_gas"] = np.array([((1.0 - eu) * vu * gx)[solved_u].sum(),
                                            ((1.0 - ev) * vv * gy)[solved_v].sum()])
        return out

    # ------------------------------------------------------------ checkpoint
    def checkpoint_arrays(self) -> dict[str, np.ndarray]:
        out = {f"gas/{k}": v for k, v in self.state.arrays().items()}
        # the pressure-matrix factors the next step reuses: a resumed run goes on bit for bit (GasSolver)
        out.update({f"gas_solver/{k}": v for k, v in self.solver.checkpoint_arrays().items()})
        if self._paired_ready and self.exchange == "particle":
            if self._device is not None:
                self._device.fetch_kp(self._kp)
            out["coupling/kp"] = self._kp
        if self._paired_ready and self.exchange == "cell":
            out.update(zip(("coupling/cell_beta", "coupling/solids_u", "coupling/solids_v"), self._cell_inputs))
        if self._inv_dbar.shape[0] > 0:  # 1/D̄ of the gas step's map, which the sub-steps' forces read
            out["coupling/inv_dbar"] = self._inv_dbar
        return out

    def checkpoint_scalars(self) -> dict:
        return {"gas_steps": self.gas_steps, "gas_courant_max": self.courant_max}

    def restore(self, arrays: dict[str, np.ndarray], scalars: dict) -> None:
        self.state = GasState(**{k: np.ascontiguousarray(arrays[f"gas/{k}"], dtype=float) for k in GAS_KEYS})
        solver = {k.split("/", 1)[1]: v for k, v in arrays.items() if k.startswith("gas_solver/")}
        if solver:  # absent from checkpoints written before 2026-11-26: fresh factors
            self.solver.restore_factors(solver)
        self.gas_steps = int(scalars["gas_steps"])
        self.gas_version += 1
        self.courant_max = float(scalars.get("gas_courant_max", 0.0))  # absent from checkpoints before 2026-11-26
        self._set_volumes()  # the restored particles may be numbered otherwise than at construction
        self._paired_ready = False
        if self.exchange == "particle" and "coupling/kp" in arrays:
            self._kp = np.ascontiguousarray(arrays["coupling/kp"], dtype=float)
            self._paired_ready = True
            if self._device is not None:
                self._device.put_kp(self._kp)
        if self._inv_dbar.shape[0] > 0 and "coupling/inv_dbar" in arrays:
            self._inv_dbar = np.ascontiguousarray(arrays["coupling/inv_dbar"], dtype=float)
        if self.exchange == "cell" and "coupling/cell_beta" in arrays:
            self._cell_inputs = tuple(np.ascontiguousarray(arrays[f"coupling/{k}"], dtype=float)
                                      for k in ("cell_beta", "solids_u", "solids_v"))
            self._paired_ready = True
