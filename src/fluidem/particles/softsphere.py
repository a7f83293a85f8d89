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
from ._neighbours_kernels import (build_pairs, build_pairs_periodic, carry_history, contacts_first,
                                  contacts_first_periodic)
from ._population_kernels import drop_pairs
from .contact.base import N_SLOTS, ROLLING_HISTORY, uses_rolling_spring
from .engine import ParticleEngine
from .shapes import build_shapes

STABILITY_FRACTION = 0.1  # dt must stay below t_c / 10: at least ten steps per contact
# default renumbering in cell order (neighbours.reorder_interval): every 1000 steps, at the next list rebuild
# (as LAMMPS sorts its atoms), for beds of 1000 particles and more; smaller ones keep their numbering
REORDER_INTERVAL = 1000
REORDER_MIN_PARTICLES = 1000


def _history_width(table: np.ndarray, adhesive: bool) -> int:
    """History columns of the contacts of a packed table: 3 (tangential spring), 4 with an adhesive law's
    pull-off distance, 7 with an ``epsd`` law's rolling spring torque (columns 4-6)."""
    if uses_rolling_spring(table):
        return ROLLING_HISTORY + 3
    return 4 if adhesive else 3


class SoftSphereEngine(ParticleEngine):
    """Velocity-Verlet soft-sphere DEM with cell + Verlet lists (Sun 2007 eqs 15–26)."""

    def __init__(self, case, state: ParticleState | None = None):
        super().__init__(case, state)
        st = self.state
        # linear drag coefficient c [kg/s] per particle: the external force is ext_force − c v, with v the
        # velocity where the force is evaluated (each sub-step); zero unless a coupling sets it
        self.ext_damping = np.zeros(st.n)
        self.pp, self.pw, self.contact_times = self._contact_tables()
        self.shapes = build_shapes(case)  # wall shapes (polylines, polygons, cylinders, meshes)
        self.shape_table, shape_times = self.shapes.contact_table(self)
        self.contact_times += shape_times
        # an adhesive law keeps each formed contact's pull-off distance in a fourth history column, an epsd
        # rolling law its rolling spring torque in columns 4-6 (contact/base.py)
        self.wall_hist = np.zeros((st.n, len(self.walls.planes), _history_width(self.pw, self.wall_adhesive)))
        dmax = 2.0 * self.largest_radius  # of the particles there and of those inlets may insert
        self.skin = case.neighbours.skin if case.neighbours.skin is not None else 0.25 * dmax
        self._check_pull_off()
        self.box_lo = self.walls.period_lower.copy()
        if self.periodic:
            self._check_period(dmax)
            K.wrap_positions(st.position, st.position.copy(), st.image, self.period, self.box_lo)
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
        self.row_start, self.partner, self.slab_start, self.slab_members = self._build_pairs(self.skin)
        self.hist = np.zeros((self.partner.shape[0], _history_width(self.pp, self.pair_adhesive)))
        if self.periodic:
            contacts_first_periodic(st.position, st.radius, self.row_start, self.partner, self.hist, self.period)
        else:
            contacts_first(st.position, st.radius, self.row_start, self.partner, self.hist)  # as every rebuild leaves it
        self._reach_walls()
        self.shapes.setup(self)
        self.reorder_listeners = []  # callables f(order) told of each renumbering (new k is former order[k])
        self._compute_forces(update=False)
        if self.shapes.after_advance():  # a near list overflowed: wider lists, the first forces again
            self._compute_forces(update=False)

    # ------------------------------------------------------------ set-up
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
        r_max = np.array([st.radius[st.species == k].max() if np.any(st.species == k) else 0.0 for k in range(ns)])
        self._widen_for_inlets(m_min, r_min, r_max)
        self.largest_radius = float(r_max.max()) if ns else 0.0
        self.pair_adhesive = self.wall_adhesive = False
        self.pull_offs = []  # (largest pull-off distance [m], what) of each adhesive law
        for a in range(ns):
            for b in range(ns):
                law = self.law_for_pair(a, b)
                pp[a, b] = law.pack(sp[a], sp[b])
                if law.adhesive:
                    self.pair_adhesive = True
                    if r_max[a] > 0.0 and r_max[b] > 0.0:
                        r_eff = r_max[a] * r_max[b] / (r_max[a] + r_max[b])
                        self.pull_offs.append((law.pull_off_distance(r_eff, sp[a], sp[b]),
                                               f"species {sp[a].name}–{sp[b].name}"))
                if np.isfinite(m_min[a]) and np.isfinite(m_min[b]):
                    m_eff = m_min[a] * m_min[b] / (m_min[a] + m_min[b])
                    r_eff = r_min[a] * r_min[b] / (r_min[a] + r_min[b])
                    times.append((law.contact_time(m_eff, r_eff, v, sp[a], sp[b]), f"species {sp[a].name}–{sp[b].name}"))
            for w, plane in enumerate(self.walls.planes):
                law = self.law_for_wall(plane, a)
                pw[a, w] = law.pack(sp[a], plane.source)
                if law.adhesive:
                    self.wall_adhesive = True
                    if r_max[a] > 0.0:
                        self.pull_offs.append((law.pull_off_distance(r_max[a], sp[a], plane.source),
                                               f"species {sp[a].name}–wall {plane.name}"))
                if np.isfinite(m_min[a]):
                    times.append((law.contact_time(m_min[a], r_min[a], v, sp[a], plane.source),
                                  f"species {sp[a].name}–wall {plane.name}"))
        return pp, pw, times

    def _widen_for_inlets(self, m_min, r_min, r_max) -> None:
        """The smallest and largest radius (and smallest mass) of each species, widened in place to the sizes an
        inlet may insert (``SizeDistribution`` bounds; normal and lognormal clipped at 0.1 and 10 diameters), so
        that the step and the pull-off check hold for particles that arrive later."""
        sp = self.case.particles.species
        names = [s.name for s in sp]
        for inlet in self.case.inlets:
            k = names.index(inlet.species) if inlet.species is not None else 0
            d, dist = sp[k].diameter, sp[k].size_distribution
            lo = hi = d
            if dist is not None:
                lo = dist.min if dist.min is not None else 0.1 * d
                hi = dist.max if dist.max is not None else 10.0 * d
            r_min[k] = min(r_min[k], 0.5 * lo)
            r_max[k] = max(r_max[k], 0.5 * hi)
            m_min[k] = min(m_min[k], sp[k].density * math.pi / 6.0 * lo**3)

    def _check_period(self, dmax: float) -> None:
        """A periodic box must be at least twice the cut-off 2 R_max + skin long on each periodic axis, so that
        two particles interact through one image only (nearest image convention); refuse a shorter one."""
        need = 2.0 * (dmax + self.skin)
        for d in np.flatnonzero(self.period > 0.0):
            if self.period[d] < need:
                ax = "xyz"[d]
                raise CaseError(
                    f"walls: the box is periodic along {ax} with length {self.period[d]:.4g} m, below twice the "
                    f"neighbour cut-off (largest diameter {dmax:.4g} m + neighbours.skin {self.skin:.4g} m): "
                    f"{need:.4g} m; make the box longer along {ax} or the skin smaller")

    def _build_pairs(self, skin: float):
        """The half list and slabs around the current positions (``build_pairs``; by nearest image in a box
        with periodic sides, ``build_pairs_periodic``)."""
        st = self.state
        if self.periodic:
            return build_pairs_periodic(st.position, st.radius, skin, self.dim2, self.period, self.box_lo)
        return build_pairs(st.position, st.radius, skin, self.dim2, 0)  # the signature advance compiles

    def _check_pull_off(self) -> None:
        """An adhesive contact lasts until its pull-off distance, so the Verlet list must keep pairs (and the
        wall reach must keep walls) that far apart: refuse a skin below the largest pull-off distance."""
        if not self.pull_offs:
            return
        dist, what = max(self.pull_offs)
        if dist >= self.skin:
            raise CaseError(
                f"neighbours.skin = {self.skin:.4g} m is below the pull-off distance {dist:.4g} m of the adhesive "
                f"contact of {what}: a contact pulled apart would leave the neighbour list before it breaks; "
                f"set neighbours.skin above {dist:.4g} m")

    def _reach_walls(self) -> None:
        """The walls each particle can reach before the next list rebuild, from ``ref_pos`` (``K.near_walls``):
        made here at set-up and after a restore, by ``advance`` at each rebuild; derived, not checkpointed."""
        n, nw = self.state.n, self.wall_normal.shape[0]
        self.wall_touch = np.empty((n, nw), dtype=np.bool_)
        self.near_count = np.empty(n, dtype=np.int64)
        self.near_wall = np.empty((n, nw), dtype=np.int64)
        # one thread's range, [0, n], as advance passes ranges: the specialisation advance compiles anyway
        K.near_walls(self.ref_pos, self.state.radius, self.wall_motion, self.wall_point0, self.wall_normal, self.skin,
                     self.dim2, self.wall_hist, self.wall_touch, self.near_count, self.near_wall,
                     np.array([0, n], dtype=np.int64))

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
                  *no_list, self.skin, self.dim2, st.image)

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
        """As ``ParticleEngine.check_initial_overlaps``, and no particle across a wall shape."""
        super().check_initial_overlaps(tolerance)
        shapes = getattr(self, "shapes", None)  # the GPU engine, a subclass, has none
        if shapes is not None:
            shapes.check_overlaps(self.state, self.time, tolerance)

    def _touching_pairs(self) -> tuple[np.ndarray, np.ndarray]:
        st = self.state
        rs, partner, _, _ = self._build_pairs(0.0)
        return np.repeat(np.arange(st.n), np.diff(rs)), partner

    # ------------------------------------------------------------ stepping
    def _variants(self) -> tuple[bool, np.ndarray | None, tuple | None, bool | None]:
        """Whether the bed is flat 2D (``K.is_flat``: ``K.advance_flat`` and ``K.compute_forces_flat`` then),
        and ``period``, ``shapes`` and ``laws`` of the kernels, None where the run has none (no periodic side,
        no wall shape, no contact law with rolling friction or adhesion): they choose what Numba compiles, so
        that a run compiles only the kernel variants it uses."""
        st = self.state
        flat = bool(self.dim2 and K.is_flat(st.position, st.velocity, st.omega, self.hist))
        laws = True if K.extended(self.pp) or K.extended(self.pw) else None
        return (flat, self.period if self.periodic else None,
                self.shapes.kernel_arrays() if len(self.shapes) else None, laws)

    def _compute_forces(self, update: bool):
        st = self.state
        flat, period, shapes, laws = self._variants()
        args = (st.position, st.velocity, st.omega, st.radius, st.mass, st.species, self.pp, self.pw,
                self.wall_motion, self.wall_point0, self.wall_normal, self.wall_hist, self.gravity,
                self.ext_force, self.ext_damping, self.dim2, self.row_start, self.partner, self.hist, self.slab_start,
                self.slab_members, self.time, self.dt, update, st.force, st.torque,
                numba.get_num_threads(), period, shapes)
        if flat:
            K.compute_forces_flat(*args, laws)
        else:
            K.compute_forces(*args, None, laws)

    def external_force(self) -> np.ndarray:
        """The external (gas) force on each particle at the current velocity, ext_force − c v [N], (N, 3)."""
        return self.ext_force - self.ext_damping[:, None] * self.state.velocity

    def advance(self, nsteps: int) -> None:
        """Run ``nsteps`` DEM steps of ``self.dt`` in one compiled call."""
        if nsteps <= 0:
            return
        st = self.state
        flat, period, shapes, laws = self._variants()
        args = (st.position, st.velocity, st.omega, st.force, st.torque, st.radius, st.mass, self.inv_mass,
                self.inv_inertia, st.species, self.pp, self.pw, self.wall_motion, self.wall_point0, self.wall_normal,
                self.wall_hist, self.gravity, self.ext_force, self.ext_damping, self.dim2, self.row_start, self.partner,
                self.hist, self.slab_start, self.slab_members, self.ref_pos, self.skin, self.steps, self.dt, nsteps,
                numba.get_num_threads(), st.inertia, st.ids, self.reorder_interval, self.last_reorder,
                self.wall_touch, self.near_count, self.near_wall, period, self.box_lo, st.image, shapes)
        (self.row_start, self.partner, self.hist, self.slab_start, self.slab_members, nreb, last_reorder,
         nreorder, order) = K.advance_flat(*args, laws) if flat else K.advance(*args, None, laws)
        self.shapes.after_advance()
        self.steps += nsteps
        self.time = self.steps * self.dt
        self.rebuilds += nreb
        if nreorder:
            self.reorders += int(nreorder)
            self.last_reorder = int(last_reorder)
            for f in self.reorder_listeners:
                f(order)

    # ------------------------------------------------------------ inlets and outlets
    changes_population = True

    def replace_particles(self, keep: np.ndarray, added: ParticleState | None) -> None:
        """Keep the particles where ``keep`` is true and append ``added`` (``particles/population.py``), between
        steps: the contact list is built anew with the histories of the pairs that stay (``drop_pairs``, then
        ``carry_history`` as at a rebuild); the stored forces of the particles that stay are kept for the next
        half kick as the last step left them (a removed partner's contact acts on them for that half step), those
        of the new particles are their weight (they arrive without contacts; a coupling adds their gas force at
        its next gas step)."""
        st = self.state
        keep = np.asarray(keep, dtype=np.bool_)
        kept = np.flatnonzero(keep)
        new_index = np.full(st.n, -1, dtype=np.int64)
        new_index[kept] = np.arange(kept.size)
        n_add = 0 if added is None else added.n
        old = drop_pairs(self.row_start, self.partner, self.hist, new_index, kept.size + n_add)

        def grown(a):
            return np.ascontiguousarray(np.concatenate([a[keep], np.zeros((n_add,) + a.shape[1:])]))

        self.ext_force, self.ext_damping, self.wall_hist = grown(self.ext_force), grown(self.ext_damping), \
            grown(self.wall_hist)
        self.shapes.replace_particles(keep, added.ids if added is not None else np.zeros(0, np.int64))
        if added is not None:
            added.force[...] = added.mass[:, None] * self.gravity
            added.torque[...] = 0.0
        self.state = st = self._replaced_state(keep, added)
        self._derive_inverses()
        self.row_start, self.partner, self.slab_start, self.slab_members = self._build_pairs(self.skin)
        self.hist = carry_history(*old, self.row_start, self.partner)
        if self.periodic:
            contacts_first_periodic(st.position, st.radius, self.row_start, self.partner, self.hist, self.period)
        else:
            contacts_first(st.position, st.radius, self.row_start, self.partner, self.hist)
        self.ref_pos = st.position.copy()
        self.rebuilds += 1
        self._reach_walls()

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
        if len(self.shapes):
            out.update(self.shapes.checkpoint_arrays())
        return out

    def checkpoint_scalars(self) -> dict:
        return {"steps": self.steps, "dt": self.dt, "rebuilds": self.rebuilds, "last_reorder": self.last_reorder,
                "reorders": self.reorders}

    def restore(self, arrays: dict[str, np.ndarray], scalars: dict) -> None:
        self.restore_state(arrays)
        self.last_reorder = int(scalars.get("last_reorder", 0))
        self.reorders = int(scalars.get("reorders", 0))
        for k in ("wall_hist", "ref_pos", "ext_force"):
            getattr(self, k)[...] = arrays[f"engine/{k}"]
        self.ext_damping[...] = arrays.get("engine/ext_damping", 0.0)  # checkpoints before it existed: none
        for k in ("row_start", "partner", "hist", "slab_start", "slab_members"):
            setattr(self, k, np.ascontiguousarray(arrays[f"engine/{k}"]))
        self._reach_walls()
        self.shapes.restore(arrays)
        self.dt = float(scalars["dt"])
        self.steps = int(scalars["steps"])
        self.rebuilds = int(scalars["rebuilds"])
        self.time = self.steps * self.dt
