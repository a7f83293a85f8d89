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
"""
from __future__ import annotations

import math

import numpy as np

from ..gas.solver import GasState
from . import interpolation as I

GAS_KEYS = ("p", "rho", "u", "v", "voidage")


def substeps_per_gas_step(gas_dt: float, dem_dt: float) -> int:
    """Number of DEM steps per gas step: ceil(DT / dt_DEM), tolerant of round-off in the ratio."""
    return max(1, math.ceil(gas_dt / dem_dt * (1.0 - 1e-9)))


class GasCoupling:
    """Owns the gas solver and state of a coupled run and drives ``engine`` through gas steps.

    Sets ``engine.dt`` to DT / substeps on construction.
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
        smap = self._map()
        self.state = self.solver.initial_state(voidage=smap.voidage, velocity=self.section.initial_velocity)
        self.gas_steps = 0
        self.last_info = None
        self.clipped = smap.clipped

    # ------------------------------------------------------------ pieces
    def _map(self):
        st = self.engine.state
        return self.mapping.map(self.grid, st.position, 2.0 * st.radius, st.velocity)

    def cell_beta(self, voidage, solids_u, solids_v) -> np.ndarray:
        """β per cell [kg m^-3 s^-1], (nx, ny): Σ_p β/(1 − ε)(ε, |u − v_s|, d_p) V_p / V_cell (Sun 2007 eq. 33)."""
        gd, st, gs = self.grid, self.engine.state, self.state
        nx, ny = gd.shape
        uc = 0.5 * (gs.u[:-1] + gs.u[1:])
        vc = 0.5 * (gs.v[:, :-1] + gs.v[:, 1:])
        slip = np.hypot(uc - solids_u, vc - solids_v)
        i = np.clip((st.position[:, 0] / gd.dx).astype(np.int64), 0, nx - 1)
        j = np.clip((st.position[:, 1] / gd.dy).astype(np.int64), 0, ny - 1)
        coef = self.drag.beta_per_solids(voidage[i, j], slip[i, j], 2.0 * st.radius, gs.rho[i, j],
                                         self.solver.props.viscosity) * self.volume
        beta = np.bincount(i * ny + j, weights=coef, minlength=nx * ny).reshape(nx, ny) / gd.cell_volume
        return beta

    def particle_forces(self) -> np.ndarray:
        """Gas force on each particle [N], (N, 3): drag (Sun 2007 eq. 29) and, if enabled, −V_p ∇p (eq. 28)."""
        st = self.engine.state
        s = I.sample_gas(self.grid, self.state, st.position)
        rho = I.interpolate(self.grid, self.state.rho, st.position, "centre", "copy")
        ug = np.zeros_like(st.velocity)
        ug[:, 0], ug[:, 1] = s["u"], s["v"]
        eps = np.clip(s["voidage"], self.mapping.minimum_voidage, 1.0)
        force = self.drag.particle_force(eps, ug, st.velocity, 2.0 * st.radius, rho, self.solver.props.viscosity)
        if self.options.pressure_gradient_force:
            force[:, 0] -= self.volume * s["dpdx"]
            force[:, 1] -= self.volume * s["dpdy"]
        if self.engine.dim2:
            force[:, 2] = 0.0
        return force

    def gas_step(self) -> None:
        """Steps 1-3 of the module docstring: map, advance the gas by DT, set the particle forces."""
        smap = self._map()
        self.clipped = smap.clipped
        beta = self.cell_beta(smap.voidage, smap.solids_u, smap.solids_v)
        t = self.gas_steps * self.gas_dt
        self.last_info = self.solver.advance(self.state, self.gas_dt, t, voidage=smap.voidage, beta=beta,
                                             solids_u=smap.solids_u, solids_v=smap.solids_v)
        self.gas_steps += 1
        self.set_particle_forces()

    def set_particle_forces(self) -> None:
        """ext_force ← the gas force; the engine's stored total force (used by the next half kick) follows."""
        eng = self.engine
        new = self.particle_forces()
        eng.state.force += new - eng.ext_force
        eng.ext_force[...] = new

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
