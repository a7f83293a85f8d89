"""Two-way coupling of the gas and the soft-sphere particles, one gas step DT at a time.

At the start of every gas step (every ``substeps`` DEM steps):

1. particles → grid: voidage ε and cell-averaged solids velocity v_s (``VoidageMapping``,
   Sun 2007 eqs 34-35 / Hoomans 1996 eqs 49-50);
2. gas from t to t + DT with the implicit interphase term −β(u − v_s), β cell-averaged with
   the cell's ε, the slip |u_cell − v_s| and each particle's diameter (Sun 2007 eq. 33);
3. grid → particles: gas velocity, voidage, density and pressure gradient at each centre
   (Hoomans 1996 eqs 40-41); the engine's ``ext_force`` becomes the drag
   β V_p/(1 − ε) (u − v_p) (Sun 2007 eq. 29) plus −V_p ∇p when enabled (Sun 2007 eq. 28);
4. the DEM sub-steps of DT (the engine's dt is DT / ceil(DT / dt_DEM)).

With ``drag_update = "substep"`` step 3 is repeated before every sub-step with the current
positions and velocities in the gas field of t + DT. The gas sees the drag through β only,
so, as in Sun 2007 (the assumption after eq. 35), particle and gas drag agree only
approximately. The phase within DT is ``engine.steps % substeps``, so a run can stop
(observers, checkpoints) after any DEM step and continue exactly.

Steps 1 and 3 and the β of step 2 are one compiled call each (``_voidage_kernels.map_solids``,
``_exchange_kernels.cell_beta``, ``_exchange_kernels.gas_forces``), the drag law chosen by its
integer code; this module only hands them arrays.
"""
from __future__ import annotations

import math

import numpy as np

from ..gas.solver import GasState
from . import _exchange_kernels as K
from . import interpolation as I

GAS_KEYS = ("p", "rho", "u", "v", "voidage")
_NO_TOTAL = np.empty((0, 3))  # ``_gas_forces`` without a total force to follow


def substeps_per_gas_step(gas_dt: float, dem_dt: float) -> int:
    """Number of DEM steps per gas step: ceil(DT / dt_DEM), tolerant of round-off in the ratio."""
    return max(1, math.ceil(gas_dt / dem_dt * (1.0 - 1e-9)))


class GasCoupling:
    """Owns the gas solver and state of a coupled run and drives ``engine`` through gas steps.

    Sets ``engine.dt`` to DT / substeps on construction. ``last_map`` is the ``SolidsMap`` of the
    last gas step (at construction: the initial one) and ``last_beta`` the cell β (nx, ny)
    [kg m^-3 s^-1] that step gave the gas (None before the first gas step of this object);
    analyses may read both, never write them.
    """

    def __init__(self, case, engine):
        self.case, self.engine = case, engine
        self.section, self.options = case.gas, case.coupling
        self.solver = self.section.build(case.gravity)
        self.grid = self.solver.grid
        self.drag = self.options.drag_law()
        self.mapping = self.options.voidage
        self.gas_dt = self.section.dt
        self.substeps = substeps_per_gas_step(self.gas_dt, engine.dt)
        engine.dt = self.gas_dt / self.substeps
        engine.time = engine.steps * engine.dt
        st = engine.state
        self.volume = math.pi / 6.0 * (2.0 * st.radius) ** 3
        xc, yc = I._axes(self.grid, "centre")[:2]
        self._nodes = (xc, yc, self.grid.x_faces, self.grid.y_faces)  # interpolation nodes, Hoomans eqs 40-41
        smap = self._map()
        self.state = self.solver.initial_state(voidage=smap.voidage, velocity=self.section.initial_velocity)
        self.gas_steps = 0
        self.last_info = None
        self.last_map = smap
        self.last_beta = None
        self.clipped = smap.clipped

    # ------------------------------------------------------------ pieces
    def _map(self):
        """particles → grid at the current positions: a ``SolidsMap`` (Sun 2007 eqs 34-35 / Hoomans eqs 49-50)."""
        st = self._particles()
        return self.mapping.map_particles(self.grid, st.position, st.radius, self.volume, st.velocity)

    def cell_beta(self, voidage, solids_u, solids_v) -> np.ndarray:
        """β per cell [kg m^-3 s^-1], (nx, ny): Σ_p β/(1 − ε)(ε, |u − v_s|, d_p) V_p / V_cell (Sun 2007 eq. 33)."""
        gd, st, gs = self.grid, self._particles(), self.state
        fields = [np.asarray(a, float) for a in (voidage, solids_u, solids_v)]
        if any(f.shape != gd.shape for f in fields):
            raise ValueError(f"voidage, solids_u, solids_v must have shape {gd.shape}; "
                             f"got {', '.join(str(f.shape) for f in fields)}")
        self._check_gas()
        beta = np.empty(gd.shape)
        bad = K.cell_beta(self.drag.code, st.position, st.radius, self.volume, gs.u, gs.v, gs.rho, *fields,
                          self.solver.props.viscosity, gd.dx, gd.dy, gd.cell_volume, beta)
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

    def _gas_forces(self, out, total) -> None:
        """``particle_forces`` into ``out``; ``total`` (N, 3) follows the change of ``out`` ((0, 3): none)."""
        st, gs, gd = self._particles(), self.state, self.grid
        self._check_gas()
        if out.shape != st.position.shape or total.shape[0] not in (0, out.shape[0]) or total.shape[1:] != (3,):
            raise ValueError(f"force arrays: out {out.shape}, total {total.shape}; expected (N, 3) with N = "
                             f"{st.position.shape[0]}")
        bad = K.gas_forces(self.drag.code, st.position, st.velocity, st.radius, self.volume, gs.u, gs.v,
                           gs.voidage, gs.rho, gs.p, self.solver.props.viscosity, *self._nodes, gd.dx, gd.dy,
                           self.mapping.minimum_voidage, bool(self.options.pressure_gradient_force),
                           bool(self.engine.dim2), out, total)
        if bad:
            raise ValueError(f"particle drag: arguments out of range for {bad} particles "
                             "(voidage must lie in (0, 1], gas density > 0)")

    def _particles(self):
        """The engine's particle state, checked against what the kernels index (N rows everywhere)."""
        st = self.engine.state
        n = st.position.shape[0]
        if self.volume.shape != (n,):  # particles added or removed since construction
            self.volume = math.pi / 6.0 * (2.0 * st.radius) ** 3
        if st.position.shape != (n, 3) or st.velocity.shape != (n, 3) or st.radius.shape != (n,):
            raise ValueError(f"particle state: position, velocity (N, 3) and radius (N,) expected; got "
                             f"{st.position.shape}, {st.velocity.shape}, {st.radius.shape}")
        return st

    def _check_gas(self) -> None:
        """The kernels index the gas arrays by the grid's shape: refuse any other (e.g. a replaced ``state``)."""
        gd, gs = self.grid, self.state
        for k, shape in (("p", gd.shape), ("rho", gd.shape), ("voidage", gd.shape), ("u", gd.u_shape),
                         ("v", gd.v_shape)):
            a = getattr(gs, k)
            if a.shape != shape or a.dtype != np.float64:
                raise ValueError(f"gas state {k}: expected {shape} float64, got {a.shape} {a.dtype}")

    def gas_step(self) -> None:
        """Steps 1-3 of the module docstring: map, advance the gas by DT, set the particle forces."""
        smap = self._map()
        self.clipped = smap.clipped
        beta = self.cell_beta(smap.voidage, smap.solids_u, smap.solids_v)
        self.last_map, self.last_beta = smap, beta
        t = self.gas_steps * self.gas_dt
        self.last_info = self.solver.advance(self.state, self.gas_dt, t, voidage=smap.voidage, beta=beta,
                                             solids_u=smap.solids_u, solids_v=smap.solids_v)
        self.gas_steps += 1
        self.set_particle_forces()

    def set_particle_forces(self) -> None:
        """ext_force ← the gas force; the engine's stored total force (used by the next half kick) follows.

        One compiled pass: force += new − ext_force, ext_force = new, per particle. Drag arguments
        out of range raise ValueError after the pass (those particles' forces are then NaN).
        """
        eng = self.engine
        self._gas_forces(eng.ext_force, eng.state.force)

    # ------------------------------------------------------------ stepping
    def advance(self, nsteps: int) -> None:
        """Advance the coupled system by ``nsteps`` DEM steps (any number; gas steps at multiples of substeps)."""
        eng = self.engine
        left = nsteps
        while left > 0:
            phase = eng.steps % self.substeps
            if phase == 0:
                self.gas_step()
            if self.options.drag_update == "substep":
                if phase > 0:
                    self.set_particle_forces()
                n = 1
            else:
                n = min(left, self.substeps - phase)
            eng.advance(n)
            left -= n

    # ------------------------------------------------------------ checkpoint
    def checkpoint_arrays(self) -> dict[str, np.ndarray]:
        return {f"gas/{k}": v for k, v in self.state.arrays().items()}

    def checkpoint_scalars(self) -> dict:
        return {"gas_steps": self.gas_steps}

    def restore(self, arrays: dict[str, np.ndarray], scalars: dict) -> None:
        self.state = GasState(**{k: np.ascontiguousarray(arrays[f"gas/{k}"], dtype=float) for k in GAS_KEYS})
        self.gas_steps = int(scalars["gas_steps"])
