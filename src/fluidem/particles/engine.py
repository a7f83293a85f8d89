"""What every particle engine shares: set-up from a case, contact laws per pair and wall, restore, the
initial-overlap check, and the interface a ``Simulation`` drives.

An engine owns the particles (``state``, a ``ParticleState``), the walls and its own neighbour structure,
and advances them by whole steps of ``dt`` in compiled calls. ``Simulation`` and the coupling use only
what ``ParticleEngine`` declares here; what differs between the soft-sphere engine
(``softsphere.SoftSphereEngine``, Sun 2007 eqs 15–26) and the event-driven one
(``hardsphere.HardSphereEngine``, Hoomans 1996 §2.3–2.5) stays behind it, so that no caller asks which
engine it has. ``engine_for(case)`` picks the engine the case's contact law implies.
"""
from __future__ import annotations

from typing import ClassVar

import numpy as np

from ..errors import CaseError
from ..state import ParticleState
from .placement import place
from .walls import build_walls


class ParticleEngine:
    """Base of the particle engines.

    Attributes set here: ``case``, ``dim2`` (centres in the x–y plane), ``walls`` (``Walls``),
    ``wall_point0, wall_normal, wall_motion`` (their arrays), ``state``, ``inv_mass``, ``inv_inertia``
    (per particle [1/kg], [1/(kg m²)]), ``gravity`` (3,) [m/s²] and ``ext_force`` (N, 3) [N], the external
    (gas) force a coupling sets; ``period`` (3,) [m], the box length along each periodic axis (0 elsewhere),
    and ``periodic`` (any such axis). A subclass sets ``dt``, ``time``, ``steps``, ``rebuilds`` and the contact
    list ``row_start, partner`` (CSR of the pairs that may touch) and implements ``advance``,
    ``checkpoint_arrays``, ``checkpoint_scalars`` and ``restore``.
    """

    #: True if particles carry lasting contact forces between steps (soft spheres); False for instantaneous
    #: collisions, whose momentum passes as impulses (no contact force to show or average)
    contact_forces: ClassVar[bool] = True

    def __init__(self, case, state: ParticleState | None = None):
        self.case = case
        self.dim2 = case.particles.dimensions == 2
        self.walls = build_walls(case)
        self.wall_point0, self.wall_normal, self.wall_motion = self.walls.arrays()
        # periodic sides of the box (walls.periodic): its length along each periodic axis, 0 elsewhere
        self.period = self.walls.period.copy()
        self.periodic = bool(np.any(self.period > 0.0))
        if state is None:
            pos, vel, diam, spec = place(case, self.walls)
            dens = np.array([s.density for s in case.particles.species])
            state = ParticleState.create(pos, vel, diam, spec, dens)
        self.state = state
        self._derive_inverses()
        self.gravity = np.array(case.gravity, float)
        self.ext_force = np.zeros_like(state.position)

    # ------------------------------------------------------------ interface
    def advance(self, nsteps: int) -> None:
        """Run ``nsteps`` steps of ``dt``."""
        raise NotImplementedError

    def checkpoint_arrays(self) -> dict[str, np.ndarray]:
        """Every array needed to continue bit for bit (``state/…`` and ``engine/…`` keys)."""
        raise NotImplementedError

    def checkpoint_scalars(self) -> dict:
        """The scalars needed to continue bit for bit."""
        raise NotImplementedError

    def restore(self, arrays: dict[str, np.ndarray], scalars: dict) -> None:
        """Continue from ``checkpoint_arrays()``/``checkpoint_scalars()`` of an engine of the same case."""
        raise NotImplementedError

    def energies(self) -> dict[str, float]:
        """Kinetic, rotational and potential energy [J]; potential relative to the origin, −Σ m g·x."""
        st = self.state
        ke = 0.5 * float(np.sum(st.mass * np.einsum("ij,ij->i", st.velocity, st.velocity)))
        re = 0.5 * float(np.sum(st.inertia * np.einsum("ij,ij->i", st.omega, st.omega)))
        pe = -float(np.sum(st.mass * (st.position @ self.gravity)))
        return {"kinetic_J": ke, "rotational_J": re, "potential_J": pe}

    def bookkeeping(self) -> dict[str, float]:
        """Engine-specific running totals for the probes (energy dissipated in collisions, collision counts);
        empty where the engine keeps none."""
        return {}

    #: True where the engine can add and remove particles during a run (``replace_particles``)
    changes_population: ClassVar[bool] = False

    def replace_particles(self, keep: np.ndarray, added: ParticleState | None) -> None:
        """Keep the particles where ``keep`` (bool, (N,)) is true, in their order, and append ``added`` after them
        (inlets and outlets, ``particles/population.py``); between steps only."""
        raise CaseError(f"{type(self).__name__} cannot add or remove particles during a run (inlets, outlets)")

    def _replaced_state(self, keep: np.ndarray, added: ParticleState | None) -> ParticleState:
        """The state of ``replace_particles``: the kept rows, then ``added``'s."""
        st = self.state
        out = {}
        for k, a in st.arrays().items():
            a = a[keep]
            if added is not None:
                a = np.concatenate([a, getattr(added, k)])
            out[k] = np.ascontiguousarray(a)
        return ParticleState(**out)

    def summary_entries(self, wall_time: float, particle_time: float, energy0: float | None,
                        coupled: bool) -> dict:
        """Engine-specific figures of ``summary.json``, given the run's wall time and the part of it spent in
        this engine [s], the ``bookkeeping()["total_energy_J"]`` at t = 0 (None: none) and whether a gas acts."""
        return {}

    # ------------------------------------------------------------ set-up
    def _derive_inverses(self) -> None:
        """1/m and 1/I per particle, from the state."""
        self.inv_mass = 1.0 / self.state.mass
        self.inv_inertia = 1.0 / self.state.inertia

    def law_for_pair(self, a: int, b: int):
        """The contact law between species a and b: ``particles.contact`` with the ``pairs`` overrides."""
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

    def restore_state(self, arrays: dict[str, np.ndarray]) -> None:
        """Copy a checkpoint's ``state/…`` arrays into ``state`` (checkpoints from before ``ids`` existed:
        particles numbered as created) and derive 1/m and 1/I anew: the restored particles may be numbered
        otherwise than at construction (renumbered in cell order)."""
        for k, a in self.state.arrays().items():
            key = f"state/{k}"
            if key in arrays:
                a[...] = arrays[key]
            elif k == "ids":
                a[...] = np.arange(a.shape[0])
            elif k == "image":  # checkpoints from before periodic sides: no crossing counted
                a[...] = 0
            else:
                raise KeyError(key)
        self._derive_inverses()

    def check_initial_overlaps(self, tolerance: float = 1e-9) -> None:
        """Raise CaseError if two particles, or a particle and a wall, overlap at the start (by more than
        ``tolerance`` of their radii)."""
        st = self.state
        i, j = self._touching_pairs()
        if i.size:
            d = np.linalg.norm(self.minimum_image(st.position[i] - st.position[j]), axis=1)
            ov = st.radius[i] + st.radius[j] - d
            bad = np.flatnonzero(ov > tolerance * (st.radius[i] + st.radius[j]))
            if bad.size:
                k = bad[np.argmax(ov[bad])]
                raise CaseError(
                    f"particles.placement: initial particles overlap: {bad.size} pair(s), e.g. particles {i[k]} and "
                    f"{j[k]} by {ov[k]:.3g} m; particles must start apart")
        for plane in self.walls.planes:
            gap = (st.position - plane.point) @ plane.normal - st.radius
            bad = np.flatnonzero(gap < -tolerance * st.radius)
            if bad.size:
                raise CaseError(
                    f"particles.placement: initial particles cross wall {plane.name}: {bad.size} particle(s), e.g. "
                    f"particle {bad[0]} by {-gap[bad[0]]:.3g} m")

    def minimum_image(self, r: np.ndarray) -> np.ndarray:
        """Offsets r = x_i − x_j (…, 3) [m] as between nearest images across the periodic sides (r − L
        round(r / L) on each periodic axis, Allen & Tildesley 1987 eq. 1.9); r itself where none is periodic."""
        if not self.periodic:
            return r
        per = self.period > 0.0
        r = np.array(r, dtype=float)
        r[..., per] -= self.period[per] * np.round(r[..., per] / self.period[per])
        return r

    def _touching_pairs(self) -> tuple[np.ndarray, np.ndarray]:
        """(i, j) int64 arrays of the pairs whose spheres touch or overlap, each pair once."""
        raise NotImplementedError

    def positions_finite(self) -> bool:
        """True if every particle position is finite (an engine that keeps its particles elsewhere checks
        them there)."""
        return bool(np.isfinite(self.state.position).all())


def engine_for(case, state: ParticleState | None = None) -> ParticleEngine:
    """The particle engine for ``case`` (optionally starting from ``state``): the event-driven one when the
    contact law is instantaneous (``hard_sphere``), else the soft-sphere one, on the GPU where the case's
    ``device`` asks for it (``softsphere_gpu.choose_device``: a ``CaseError`` naming what the GPU engine
    does not support, or that no GPU is found, for ``device = "gpu"``)."""
    from .softsphere_gpu import choose_device

    if choose_device(case) == "gpu":
        from .softsphere_gpu import SoftSphereGPUEngine

        return SoftSphereGPUEngine(case, state=state)
    if case.particles.contact.instantaneous:
        from .hardsphere import HardSphereEngine

        return HardSphereEngine(case, state=state)
    from .softsphere import SoftSphereEngine

    return SoftSphereEngine(case, state=state)
