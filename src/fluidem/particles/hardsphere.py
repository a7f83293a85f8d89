"""Event-driven hard-sphere engine (Hoomans et al. 1996): owns particle state, collision laws and walls.

``HardSphereEngine.advance(nsteps)`` runs that many force steps DT in one compiled call
(``_hardsphere_kernels.advance``). Each step processes the binary collisions inside DT one at
a time in time order with free flight in between (eqs 30–32, Fig. 3), each by eqs 10–29, and
gives every velocity the impulse of gravity and the gas force, (g + F/m) DT (eqs 33–34):

* ``particles.force_step = "split"`` (the default): half of it before the collision sequence
  and half after (kick–drift–kick). Free flight is then exact (the parabola to round-off) and
  positions and velocities belong to the same instant.
* ``"hoomans"``: all of it before the sequence, as Hoomans 1996 (Fig. 7). Free flight gains
  ½ a DT t in position, and the energy of eq. 51 the offset ½ m g·DT v: −½ m g² DT t in free
  fall, the first-order error of §5.1.

Why "split" is the default: it keeps the paper's collision sequence. Inside the step the
velocities change only by collisions and the particles fly straight (§2.4, eqs 30–32), and the
collision-detection model is unchanged. More than that, under gravity alone the two steps give
the same trajectories, collision for collision: Hoomans' step n times is
K_DT/2 (K_DT/2 D K_DT/2)^n K_−DT/2 (K a kick, D the sequence), the split step started half a
kick later, with reported velocities half a kick apart
(``tests/verification/test_hardsphere_dynamics.py``). Only the instant at which the velocities
are reported differs, and with it the energy budget. With a gas force that changes from step
to step, Hoomans' step is the split step whose second half kick takes the next step's force;
the split step takes the step's own force for both halves (the next one is not known yet), so
the two then differ by O(DT²) in velocity per step. The built-in reproductions of the paper
(``hoomans-*``) keep ``"hoomans"``.

The interface is that of ``SoftSphereEngine`` so that ``Simulation``, the gas coupling
(``ext_force``) and checkpoints work unchanged; the engine also runs on its own.
"""
from __future__ import annotations

import numpy as np
from pydantic import ValidationError

from ..errors import CaseError
from ..state import ParticleState
from . import _hardsphere_kernels as K
from ._softsphere_kernels import wrap_positions
from .contact.base import N_SLOTS
from .contact.hard_sphere import HardSphere
from .engine import ParticleEngine
from .walls import build_walls

DEFAULT_DT = 1e-4  # s, Hoomans 1996 DT (Table 2, §5.1)
DEFAULT_SKIN_DIAMETERS = 0.5  # neighbour-list skin in largest diameters when neighbours.skin is not given


def workspace(n: int) -> tuple:
    """The work arrays of ``_hardsphere_kernels.advance`` for n particles, (P, Q, R, ev, ev_time, ncoll, T, X, F, M).
    The engine keeps them between calls: fresh ones would be fresh pages of memory, and their page faults cost
    more than a step of a small bed. P's rows start on 64-byte boundaries (one cache line each). M (2,) int64
    says whether R still holds what ``_set_reference`` makes of the ``ref_pos`` a call returned (M[0] = 1) and
    for which ``planar`` (M[1]): ``advance`` then skips it (a coupled run calls ``advance`` once per step, and R
    changes only at a list rebuild). A fresh workspace has M[0] = 0, so an engine that replaces ``ref_pos`` (a
    restore) makes a fresh one."""
    size = 1  # the smallest power of two >= n: the event tree's leaves
    while size < n:
        size *= 2
    buf = np.empty(K.P_ROW * n + 8)
    off = (-buf.ctypes.data % 64) // 8
    P = buf[off:off + K.P_ROW * n]
    return (P, np.empty((n, 8)), np.empty(K.R_ROW * n), np.empty((n, 2), np.int64), np.empty(n),
            np.empty(n, np.int64), np.empty(4 * size), np.empty((n, 3)), np.empty(n), np.zeros(2, np.int64))


class CollisionCascadeError(FloatingPointError):
    """More events in one step than ``max_events_per_step``: an inelastic collapse or a jammed cluster.

    A ``FloatingPointError`` so that ``Simulation.run`` records it as the run's error and
    keeps a consistent checkpoint (the engine is left at the start of the failing call).
    """


class HardSphereEngine(ParticleEngine):
    """Hard-sphere particles with instantaneous binary collisions (Hoomans 1996 §2.3–2.5).

    Attributes besides the soft-sphere interface (``case, dim2, walls, state, inv_mass,
    gravity, ext_force, wall_point0, wall_normal, wall_motion, dt, time, steps, rebuilds``):

    force_step : str, "split" or "hoomans" (``particles.force_step``; see the module docstring)
    collisions, wall_collisions : int, cumulative collision counts (wall ones included in the first)
    sticking_collisions : int, collisions of the sticking class (eq. 25)
    dissipated_normal_J, dissipated_tangential_J : float, sums of eq. 23 and of eqs 27/29 [J]
    remedy_count : int, collisions made elastic and frictionless by the TC model
    events : int, all processed events (collisions, stale predictions, list rebuilds)
    skin : float, neighbour-list skin [m]
    max_events_per_step : int, a step with more events raises ``CollisionCascadeError``
        (default 10⁶ + 10⁴ N: seconds of work, far above the 10–10³ collisions per particle and
        step of a settling bed)
    event_log, logged : collisions recorded after ``record_collisions(capacity)``
    row_start, partner, wall_hist, pw : what ``analysis.probes`` reads (no lasting contacts)
    """

    contact_forces = False  # collisions pass momentum as impulses

    def __init__(self, case, state: ParticleState | None = None):
        walls = build_walls(case)
        motion = walls.arrays()[2]
        for k, plane in enumerate(walls.planes):
            if int(motion[k, 0]) != 0:
                raise CaseError(
                    f"walls: wall {plane.source.name!r} moves ({plane.source.motion.kind}); the hard-sphere engine "
                    f"supports static walls only; remove its motion or use a soft-sphere contact model")
        super().__init__(case, state)
        st = self.state
        self.pp, self.pw = self._contact_tables()
        self.dt = case.time.dt if case.time.dt is not None else DEFAULT_DT
        self.force_step = case.particles.force_step
        dmax = 2.0 * float(st.radius.max()) if st.n else 0.0
        self.skin = case.neighbours.skin if case.neighbours.skin is not None else DEFAULT_SKIN_DIAMETERS * dmax
        if st.n and not self.skin > 0:
            raise CaseError("neighbours.skin must be positive for the hard-sphere engine")
        self.max_events_per_step = 1_000_000 + 10_000 * st.n
        self.box_lo = self.walls.period_lower.copy()
        if self.periodic:
            self._check_periodic(dmax)
            wrap_positions(st.position, st.position.copy(), st.image, self.period, self.box_lo)
        self._image_step = np.zeros((st.n, 3), np.int64)  # crossings of the periodic sides during one call
        self.time = 0.0
        self.steps = 0
        self.counters = np.zeros(K.N_COUNTERS, np.int64)
        self.energy = np.zeros(K.N_ENERGIES)
        self.last_collision = np.full(st.n, -np.inf)  # absolute time of each particle's last collision [s]
        self.ref_pos = st.position.copy()
        self.nbr_start, self.nbr = self._neighbours(self.skin)
        self.up_start, self.up = K.upper_half(self.nbr_start, self.nbr)  # derived: each pair once
        self.event_log = np.zeros((0, 5))  # see record_collisions()
        self._work = None  # the kernel's work arrays (K.workspace), made at the first step
        # what analysis/probes.py reads from a particle engine: no lasting contacts between hard spheres
        self.row_start = np.zeros(st.n + 1, np.int64)
        self.partner = np.zeros(0, np.int32)
        self.wall_hist = np.zeros((st.n, len(self.walls.planes), 3))
        self._update_force()

    # ------------------------------------------------------------ set-up
    def _contact_tables(self):
        """Packed hard-sphere rows per species pair (S, S, 8) and per species–wall plane (S, W, 8)."""
        sp = self.case.particles.species
        ns, nw = len(sp), len(self.walls.planes)
        pp = np.zeros((ns, ns, N_SLOTS))
        pw = np.zeros((ns, max(nw, 1), N_SLOTS))
        try:
            for a in range(ns):
                for b in range(ns):
                    pp[a, b] = self._hard(self.law_for_pair(a, b), f"species {sp[a].name}–{sp[b].name}").pack(
                        sp[a], sp[b])
                for w, plane in enumerate(self.walls.planes):
                    pw[a, w] = self._hard(self.law_for_wall(plane, a), f"species {sp[a].name}–wall {plane.name}").pack(
                        sp[a], plane.source)
        except ValidationError as err:
            bad = "; ".join(f"{'.'.join(str(x) for x in e['loc'])}: {e['msg']}" for e in err.errors())
            raise CaseError(f"particles.pairs / wall_pairs / walls.contact: invalid hard-sphere override ({bad}); "
                            f"hard spheres take restitution and friction only") from None
        return pp, pw

    @staticmethod
    def _hard(law, what):
        if not isinstance(law, HardSphere):
            raise CaseError(f"particles.contact: the law of {what} is {law.model!r}; the hard-sphere engine needs "
                            f"model = 'hard_sphere' for every pair and wall")
        return law

    def _check_periodic(self, dmax: float) -> None:
        """Periodic sides: a box at least twice the cut-off 2 R_max + skin long on each periodic axis, so that a
        pair meets through one image only (nearest image convention), and no gas (the coupling of a
        periodic hard-sphere bed is not implemented)."""
        axes = [a for a, length in zip("xyz", self.period) if length > 0.0]
        if self.case.gas is not None:
            raise CaseError(
                f"walls: a box with periodic = {axes} and a gas; the hard-sphere engine (particles.contact.model = "
                f"{self.case.particles.contact.model!r}) runs periodic sides without gas only; remove gas, remove "
                "periodic or use a soft-sphere contact model")
        need = 2.0 * (dmax + self.skin)
        for d in np.flatnonzero(self.period > 0.0):
            if self.period[d] < need:
                ax = "xyz"[d]
                raise CaseError(
                    f"walls: the box is periodic along {ax} with length {self.period[d]:.4g} m, below twice the "
                    f"neighbour cut-off (largest diameter {dmax:.4g} m + neighbours.skin {self.skin:.4g} m): "
                    f"{need:.4g} m; make the box longer along {ax} or the skin smaller")

    def _neighbours(self, skin: float) -> tuple[np.ndarray, np.ndarray]:
        """The full neighbour list of the current positions with cut-off R_i + R_j + skin (by nearest image
        across periodic sides; the search takes the centres wrapped into the box, where they lie only at a
        list rebuild)."""
        st = self.state
        if self.periodic:
            pos = st.position.copy()
            wrap_positions(pos, pos.copy(), np.zeros((st.n, 3), np.int64), self.period, self.box_lo)
            return K.build_neighbours_periodic(pos, st.radius, skin, self.dim2, self.period, self.box_lo)
        return K.build_neighbours(st.position, st.radius, skin, self.dim2)

    def _touching_pairs(self) -> tuple[np.ndarray, np.ndarray]:
        st = self.state
        rs, nbr = self._neighbours(0.0)
        i = np.repeat(np.arange(st.n), np.diff(rs))
        j = nbr.astype(np.int64)
        keep = i < j
        return i[keep], j[keep]

    def record_collisions(self, capacity: int) -> None:
        """Record the next ``capacity`` collisions in ``event_log`` (for tests and analysis).

        Rows: (absolute time [s], particle a, partner b (>= 0) or wall code −3 − w, E_n [J], E_t [J]).
        """
        self.event_log = np.zeros((int(capacity), 5))
        self.counters[K.C_LOGGED] = 0

    @property
    def logged(self) -> np.ndarray:
        """The recorded collisions so far (rows of ``event_log``)."""
        return self.event_log[: self.counters[K.C_LOGGED]]

    # ------------------------------------------------------------ stepping
    def _update_force(self) -> None:
        """state.force = m g + ext_force (the finite forces of eq. 34); no torques between collisions."""
        st = self.state
        K.set_forces(st.mass, self.gravity, self.ext_force, st.force, st.torque)

    def advance(self, nsteps: int) -> None:
        """Run ``nsteps`` force steps of ``self.dt`` in one compiled call."""
        if nsteps <= 0:
            return
        st = self.state
        if st.n == 0:
            self.steps += nsteps
            self.time = self.steps * self.dt
            return
        counters, energy = self.counters.copy(), self.energy.copy()
        info = np.zeros(3)
        if self._work is None or self._work[0].shape[0] != K.P_ROW * st.n:
            self._work = workspace(st.n)
            self._image_step = np.zeros((st.n, 3), np.int64)
        nbr_start, nbr, up_start, up, status = K.advance(
            st.position, st.velocity, st.omega, st.radius, self.inv_mass, self.inv_inertia, st.species, self.pp,
            self.pw, self.wall_point0, self.wall_normal, self.gravity, self.ext_force, self.dim2, self.nbr_start,
            self.nbr, self.up_start, self.up, self.ref_pos, self.skin, self.last_collision, self.steps, self.dt, nsteps,
            self.max_events_per_step, self.counters, self.energy, self.event_log, info, self._work,
            self.force_step == "split", self.period if self.periodic else None, self.box_lo, self._image_step)
        if self.periodic:
            if status == K.OK:  # a failed call left the positions as they were: its crossings do not count
                st.image += self._image_step
            self._image_step[...] = 0
        if status != K.OK:  # the kernel left the particle arrays as they were
            self.counters[...] = counters
            self.energy[...] = energy
            step = self.steps + int(info[0])
            tc = self.pp[0, 0, K.SLOT_COLLAPSE_TIME]
            raise CollisionCascadeError(
                f"hard-sphere engine: more than {self.max_events_per_step} events in step {step} "
                f"(t = {step * self.dt + info[1]:.6g} s): a collision cascade that does not end, typically in a "
                f"bed at rest without gas (see particles/contact/hard_sphere.py). "
                + ("The TC remedy is off: an inelastic collapse; try particles.contact.collapse_time = 1e-5. "
                   if tc == 0 else
                   f"The TC remedy is on (collapse_time = {tc:g} s): equal spheres jammed in a row between walls "
                   f"stay elastic under it; try collapse_time = 0. ")
                + f"A box width that is not a whole number of diameters, a size distribution or a smaller "
                  f"time.dt also help. The particles are left as they were at t = {self.time:.6g} s")
        self.nbr_start, self.nbr, self.up_start, self.up = nbr_start, nbr, up_start, up
        self.steps += nsteps
        self.time = self.steps * self.dt
        self._update_force()

    # ------------------------------------------------------------ counters and energies
    @property
    def collisions(self) -> int:
        return int(self.counters[K.C_COLLISIONS])

    @property
    def wall_collisions(self) -> int:
        return int(self.counters[K.C_WALL_COLLISIONS])

    @property
    def sticking_collisions(self) -> int:
        return int(self.counters[K.C_STICKING])

    @property
    def remedy_count(self) -> int:
        return int(self.counters[K.C_REMEDY])

    @property
    def events(self) -> int:
        return int(self.counters[K.C_EVENTS])

    @property
    def rebuilds(self) -> int:
        return int(self.counters[K.C_REBUILDS])

    @property
    def dissipated_normal_J(self) -> float:
        return float(self.energy[K.E_NORMAL])

    @property
    def dissipated_tangential_J(self) -> float:
        return float(self.energy[K.E_TANGENTIAL])

    def energies(self) -> dict[str, float]:
        """Kinetic, rotational, potential (−Σ m g·x, relative to the origin) and dissipated energy [J].

        Their sum is Hoomans' E_tot (1996 eq. 51), constant when no gas acts up to the error of the force
        step: in free flight none with ``force_step = "split"`` and ½ m g·DT (v − v_0) with ``"hoomans"``;
        each wall collision −(1 + e) m g·n y_mid with y_mid the mid-step gap on the straight path (the wall's
        impulse does work in a step that does not bend under gravity; at the floor of a bed at rest, at most
        ½ M g² DT per unit time, first order in DT for both steps).
        """
        e = super().energies()
        diss = self.dissipated_normal_J + self.dissipated_tangential_J
        return {**e, "dissipated_J": diss, "total_J": e["kinetic_J"] + e["rotational_J"] + e["potential_J"] + diss}

    def bookkeeping(self) -> dict[str, float]:
        """Hoomans 1996 eq. 51's energy housekeeping: dissipated energy (eqs 23, 27, 29), the total
        E_kin + E_pot + E_rot + E_dsp [J], and the collision counts."""
        e = self.energies()
        diss_n, diss_t = self.dissipated_normal_J, self.dissipated_tangential_J
        return {"dissipated_normal_J": diss_n, "dissipated_tangential_J": diss_t,
                "total_energy_J": e["kinetic_J"] + e["rotational_J"] + e["potential_J"] + diss_n + diss_t,
                "collisions": self.collisions, "wall_collisions": self.wall_collisions,
                "remedy_count": self.remedy_count}

    def summary_entries(self, wall_time: float, particle_time: float, energy0: float | None,
                        coupled: bool) -> dict:
        """Collisions (in all, per second of the run and per second of this engine), the TC remedy's uses, the
        energy dissipated, and without gas Hoomans 1996 eq. 51's relative energy error."""
        h = self.bookkeeping()
        out = {"collisions": h["collisions"], "wall_collisions": h["wall_collisions"],
               "collisions_per_s": h["collisions"] / wall_time if wall_time > 0 else None,
               "collisions_per_particle_s": h["collisions"] / particle_time if particle_time > 0 else None,
               "collapse_remedy_count": h["remedy_count"],
               "dissipated_energy_J": h["dissipated_normal_J"] + h["dissipated_tangential_J"]}
        if energy0 and not coupled:  # with gas, the gas does work on the particles
            # Hoomans 1996 eq. 51: relative error of E_kin + E_pot + E_rot + E_dsp
            out["energy_error_rel"] = abs(h["total_energy_J"] - energy0) / abs(energy0)
        return out

    # ------------------------------------------------------------ checkpoint
    def checkpoint_arrays(self) -> dict[str, np.ndarray]:
        """Everything needed to continue bit-for-bit."""
        out = {f"state/{k}": v for k, v in self.state.arrays().items()}
        out.update({
            "engine/ref_pos": self.ref_pos, "engine/nbr_start": self.nbr_start, "engine/nbr": self.nbr,
            "engine/last_collision": self.last_collision, "engine/counters": self.counters,
            "engine/energy": self.energy, "engine/ext_force": self.ext_force,
        })
        return out

    def checkpoint_scalars(self) -> dict:
        return {"steps": self.steps, "dt": self.dt, "rebuilds": self.rebuilds, "collisions": self.collisions,
                "skin": self.skin}

    def restore(self, arrays: dict[str, np.ndarray], scalars: dict) -> None:
        self.restore_state(arrays)
        for k in ("ref_pos", "last_collision", "ext_force", "counters", "energy"):
            getattr(self, k)[...] = arrays[f"engine/{k}"]
        self.nbr_start = np.ascontiguousarray(arrays["engine/nbr_start"], dtype=np.int64)
        self.nbr = np.ascontiguousarray(arrays["engine/nbr"], dtype=np.int32)
        self.up_start, self.up = K.upper_half(self.nbr_start, self.nbr)
        self._work = None  # its R derives from the former ref_pos (see K.workspace)
        self.counters[K.C_LOGGED] = 0
        self.event_log = np.zeros((0, 5))
        self.dt = float(scalars["dt"])
        self.skin = float(scalars.get("skin", self.skin))
        self.steps = int(scalars["steps"])
        self.time = self.steps * self.dt
        self._update_force()
