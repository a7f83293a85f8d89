"""Soft-sphere DEM engine: owns particle state, contact tables, walls and the Verlet list.

``SoftSphereEngine.advance(nsteps)`` runs that many DEM steps in one compiled call
(``_softsphere_kernels.advance``); all per-particle work happens there. The engine
can be used without a ``Simulation`` (tests drive it directly).
"""
from __future__ import annotations

import math

import numba
import numpy as np

from ..errors import CaseError
from ..state import ParticleState
from . import _softsphere_kernels as K
from ._neighbours_kernels import build_pairs, contacts_first
from .contact.base import N_SLOTS
from .placement import place
from .walls import build_walls

STABILITY_FRACTION = 0.1  # dt must stay below t_c / 10: at least ten steps per contact
# default renumbering in cell order (neighbours.reorder_interval): every 1000 steps, at the next list rebuild
# (as LAMMPS sorts its atoms), for beds of 1000 particles and more; smaller ones keep their numbering
REORDER_INTERVAL = 1000
REORDER_MIN_PARTICLES = 1000



def set_up_particles(engine, case, state: ParticleState | None) -> ParticleState:
    """The particle part of an engine's set-up, shared by the soft- and hard-sphere engines: the state
    (``state``, or placed by the case inside ``engine.walls``), inverse mass and inertia, gravity and a
    zero external force on ``engine``. Returns the state."""
    if state is None:
        pos, vel, diam, spec = place(case, engine.walls)
        dens = np.array([s.density for s in case.particles.species])
        state = ParticleState.create(pos, vel, diam, spec, dens)
    engine.state = state
    _derive_inverses(engine)
    engine.gravity = np.array(case.gravity, float)
    engine.ext_force = np.zeros_like(state.position)
    return state


def _derive_inverses(engine) -> None:
    """The engine's 1/m and 1/I per particle, from its state."""
    engine.inv_mass = 1.0 / engine.state.mass
    engine.inv_inertia = 1.0 / engine.state.inertia


def restore_state(engine, arrays: dict[str, np.ndarray]) -> None:
    """Copy a checkpoint's ``state/…`` arrays into ``engine.state`` (checkpoints from before ``ids`` existed:
    particles numbered as created) and derive 1/m and 1/I anew: the restored particles may be numbered
    otherwise than at construction (renumbered in cell order)."""
    state = engine.state
    for k, a in state.arrays().items():
        key = f"state/{k}"
        if key in arrays:
            a[...] = arrays[key]
        elif k == "ids":
            a[...] = np.arange(a.shape[0])
        else:
            raise KeyError(key)
    _derive_inverses(engine)


class SoftSphereEngine:
    """Velocity-Verlet soft-sphere DEM with cell + Verlet lists (Sun 2007 eqs 15–26)."""

    def __init__(self, case, state: ParticleState | None = None):
        self.case = case
        self.dim2 = case.particles.dimensions == 2
        self.walls = build_walls(case)
        st = set_up_particles(self, case, state)
        # linear drag coefficient c [kg/s] per particle: the external force is ext_force − c v, with v the
        # velocity where the force is evaluated (each sub-step); zero unless a coupling sets it
        self.ext_damping = np.zeros(st.n)
        self.pp, self.pw, self.contact_times = self._contact_tables()
        self.wall_point0, self.wall_normal, self.wall_motion = self.walls.arrays()
        self.wall_hist = np.zeros((st.n, len(self.walls.planes), 3))
        dmax = 2.0 * st.radius.max() if st.n else 0.0
        self.skin = case.neighbours.skin if case.neighbours.skin is not None else 0.25 * dmax
        self.dt = self._time_step()
        self.time = 0.0
        self.steps = 0
        self.rebuilds = 0
        self.reorder_interval = self._reorder_interval()
        self.last_reorder = 0  # step of the last renumbering in cell order (see advance)
        self.reorders = 0
        if self.reorder_interval > 0:
            self._renumber()
        self.ref_pos = st.position.copy()
        self.row_start, self.partner, self.slab_start, self.slab_members = build_pairs(
            st.position, st.radius, self.skin, self.dim2)
        self.hist = np.zeros((self.partner.shape[0], 3))
        contacts_first(st.position, st.radius, self.row_start, self.partner, self.hist)  # as every rebuild leaves it
        self._reach_walls()
        self.reorder_listeners = []  # callables f(order) told of each renumbering (new k is former order[k])
        self._compute_forces(update=False)

    # ------------------------------------------------------------ set-up
    def law_for_pair(self, a: int, b: int):
        p = self.case.particles
        law = p.contact
        names = (p.species[a].name, p.species[b].name)
        for pc in p.pairs:
            if sorted(pc.species) == sorted(names):
                law = type(law).model_validate({**law.model_dump(), **pc.changes()})
        return law

    def law_for_wall(self, plane, species: int):
        """Particle–wall law: wall_contact (or contact), then the wall's overrides, then wall_pairs."""
        p = self.case.particles
        law = p.wall_contact if p.wall_contact is not None else p.contact
        changes = dict(plane.source.contact.changes()) if plane.source.contact is not None else {}
        for wp in p.wall_pairs:
            if wp.species == p.species[species].name and wp.wall in (None, plane.source.name):
                changes.update(wp.changes())
        if changes:
            law = type(law).model_validate({**law.model_dump(), **changes})
        return law

    def _contact_tables(self):
        sp = self.case.particles.species
        ns, nw = len(sp), len(self.walls.planes)
        pp = np.zeros((ns, ns, N_SLOTS))
        pw = np.zeros((ns, max(nw, 1), N_SLOTS))
        st = self.state
        times = []
        v = self.case.time.impact_velocity
        # the lightest particle of each species sets the shortest contact time
        m_min = np.array([st.mass[st.species == k].min() if np.any(st.species == k) else np.inf for k in range(ns)])
        r_min = np.array([st.radius[st.species == k].min() if np.any(st.species == k) else np.inf for k in range(ns)])
        for a in range(ns):
            for b in range(ns):
                law = self.law_for_pair(a, b)
                pp[a, b] = law.pack(sp[a], sp[b])
                if np.isfinite(m_min[a]) and np.isfinite(m_min[b]):
                    m_eff = m_min[a] * m_min[b] / (m_min[a] + m_min[b])
                    r_eff = r_min[a] * r_min[b] / (r_min[a] + r_min[b])
                    times.append((law.contact_time(m_eff, r_eff, v, sp[a], sp[b]), f"species {sp[a].name}–{sp[b].name}"))
            for w, plane in enumerate(self.walls.planes):
                law = self.law_for_wall(plane, a)
                pw[a, w] = law.pack(sp[a], plane.source)
                if np.isfinite(m_min[a]):
                    times.append((law.contact_time(m_min[a], r_min[a], v, sp[a], plane.source),
                                  f"species {sp[a].name}–wall {plane.name}"))
        return pp, pw, times

    def _reach_walls(self) -> None:
        """The walls each particle can reach before the next list rebuild, from ``ref_pos`` (``K.near_walls``):
        made here at set-up and after a restore, by ``advance`` at each rebuild; derived, not checkpointed."""
        n, nw = self.state.n, self.wall_normal.shape[0]
        self.wall_touch = np.empty((n, nw), dtype=np.bool_)
        self.near_count = np.empty(n, dtype=np.int64)
        self.near_wall = np.empty((n, nw), dtype=np.int64)
        K.near_walls(self.ref_pos, self.state.radius, self.wall_motion, self.wall_point0, self.wall_normal, self.skin,
                     self.dim2, self.wall_hist, self.wall_touch, self.near_count, self.near_wall)

    def _renumber(self) -> None:
        """At set-up, before the list is made: number the particles in slab and cell order (as ``advance``
        does every ``reorder_interval`` steps); ``state.ids`` keep the particles' own numbers.

        A bed placed or loaded in any other order (a random fill, the tiles of the 100,000-sphere bench
        bed) would otherwise wait ``reorder_interval`` steps and a rebuild for it. The bench bed of 100,000
        spheres renumbered so: 2.9e6 → 3.0–3.8e6 particle-steps/s on one thread, 4.3e6 → 5.3–6.2e6 on two."""
        st = self.state
        no_list = (np.zeros(st.n + 1, dtype=np.int64), np.empty(0, dtype=np.int32), np.empty((0, 3)))
        K.reorder(st.position, st.velocity, st.omega, st.force, st.torque, st.radius, st.mass, st.inertia,
                  self.inv_mass, self.inv_inertia, st.species, st.ids, self.ext_force, self.ext_damping, self.wall_hist,
                  *no_list, self.skin, self.dim2)

    def _reorder_interval(self) -> int:
        """Steps between renumberings of the particles in cell order: the case's ``neighbours.reorder_interval``,
        or by default REORDER_INTERVAL from REORDER_MIN_PARTICLES particles on (0: never)."""
        k = self.case.neighbours.reorder_interval
        if k is not None:
            return int(k)
        return REORDER_INTERVAL if self.state.n >= REORDER_MIN_PARTICLES else 0

    def _time_step(self) -> float:
        t = self.case.time
        if not self.contact_times:
            return t.dt if t.dt is not None else 1e-4
        tc, what = min(self.contact_times)
        if not math.isfinite(tc):
            raise CaseError(f"particles.contact: the contact of {what} is overdamped (no rebound); lower the damping")
        self.contact_time, self.contact_time_of = tc, what
        if t.dt is None:
            return t.dt_fraction * tc
        limit = STABILITY_FRACTION * tc
        if t.dt > limit:
            raise CaseError(
                f"time.dt = {t.dt:.4g} s is above the stability limit {limit:.4g} s "
                f"(t_c/10 with the contact time t_c = {tc:.4g} s of {what}); use dt <= {limit:.4g} or leave dt unset "
                f"for t_c/50 (Sun 2007)"
            )
        return t.dt

    def check_initial_overlaps(self, tolerance: float = 1e-9) -> None:
        """Raise CaseError if two particles, or a particle and a wall, overlap at the start."""
        st = self.state
        rs, partner, _, _ = build_pairs(st.position, st.radius, 0.0, self.dim2)
        if partner.size:
            i = np.repeat(np.arange(st.n), np.diff(rs))
            d = np.linalg.norm(st.position[i] - st.position[partner], axis=1)
            ov = st.radius[i] + st.radius[partner] - d
            bad = np.flatnonzero(ov > tolerance * (st.radius[i] + st.radius[partner]))
            if bad.size:
                k = bad[np.argmax(ov[bad])]
                raise CaseError(
                    f"particles.placement: initial particles overlap: {bad.size} pair(s), e.g. particles {i[k]} and {partner[k]} by "
                    f"{ov[k]:.3g} m; particles must start apart"
                )
        for w, plane in enumerate(self.walls.planes):
            gap = (st.position - plane.point) @ plane.normal - st.radius
            bad = np.flatnonzero(gap < -tolerance * st.radius)
            if bad.size:
                raise CaseError(
                    f"particles.placement: initial particles cross wall {plane.name}: {bad.size} particle(s), e.g. particle {bad[0]} "
                    f"by {-gap[bad[0]]:.3g} m"
                )

    # ------------------------------------------------------------ stepping
    def _compute_forces(self, update: bool):
        st = self.state
        K.compute_forces(st.position, st.velocity, st.omega, st.radius, st.mass, st.species, self.pp, self.pw,
                         self.wall_motion, self.wall_point0, self.wall_normal, self.wall_hist, self.gravity,
                         self.ext_force, self.ext_damping, self.dim2, self.row_start, self.partner, self.hist, self.slab_start,
                         self.slab_members, self.time, self.dt, update, st.force, st.torque,
                         numba.get_num_threads())

    def external_force(self) -> np.ndarray:
        """The external (gas) force on each particle at the current velocity, ext_force − c v [N], (N, 3)."""
        return self.ext_force - self.ext_damping[:, None] * self.state.velocity

    def advance(self, nsteps: int) -> None:
        """Run ``nsteps`` DEM steps of ``self.dt`` in one compiled call."""
        if nsteps <= 0:
            return
        st = self.state
        (self.row_start, self.partner, self.hist, self.slab_start, self.slab_members, nreb, last_reorder,
         nreorder, order) = K.advance(
            st.position, st.velocity, st.omega, st.force, st.torque, st.radius, st.mass, self.inv_mass,
            self.inv_inertia, st.species, self.pp, self.pw, self.wall_motion, self.wall_point0, self.wall_normal,
            self.wall_hist, self.gravity, self.ext_force, self.ext_damping, self.dim2, self.row_start, self.partner, self.hist,
            self.slab_start, self.slab_members, self.ref_pos, self.skin, self.steps, self.dt, nsteps,
            numba.get_num_threads(), st.inertia, st.ids, self.reorder_interval, self.last_reorder,
            self.wall_touch, self.near_count, self.near_wall)
        self.steps += nsteps
        self.time = self.steps * self.dt
        self.rebuilds += nreb
        if nreorder:
            self.reorders += int(nreorder)
            self.last_reorder = int(last_reorder)
            for f in self.reorder_listeners:
                f(order)

    # ------------------------------------------------------------ checkpoint
    def checkpoint_arrays(self) -> dict[str, np.ndarray]:
        """Everything needed to continue bit-for-bit."""
        out = {f"state/{k}": v for k, v in self.state.arrays().items()}
        out.update({
            "engine/wall_hist": self.wall_hist, "engine/ref_pos": self.ref_pos, "engine/row_start": self.row_start,
            "engine/partner": self.partner, "engine/hist": self.hist, "engine/slab_start": self.slab_start,
            "engine/slab_members": self.slab_members, "engine/ext_force": self.ext_force,
            "engine/ext_damping": self.ext_damping,
        })
        return out

    def checkpoint_scalars(self) -> dict:
        return {"steps": self.steps, "dt": self.dt, "rebuilds": self.rebuilds, "last_reorder": self.last_reorder,
                "reorders": self.reorders}

    def restore(self, arrays: dict[str, np.ndarray], scalars: dict) -> None:
        restore_state(self, arrays)
        self.last_reorder = int(scalars.get("last_reorder", 0))
        self.reorders = int(scalars.get("reorders", 0))
        for k in ("wall_hist", "ref_pos", "ext_force"):
            getattr(self, k)[...] = arrays[f"engine/{k}"]
        self.ext_damping[...] = arrays.get("engine/ext_damping", 0.0)  # checkpoints before it existed: none
        for k in ("row_start", "partner", "hist", "slab_start", "slab_members"):
            setattr(self, k, np.ascontiguousarray(arrays[f"engine/{k}"]))
        self._reach_walls()
        self.dt = float(scalars["dt"])
        self.steps = int(scalars["steps"])
        self.rebuilds = int(scalars["rebuilds"])
        self.time = self.steps * self.dt
