"""Inlets and outlets: particles added at a rate in insertion regions and removed in removal regions.

``Population`` holds the case's ``[[inlets]]`` and ``[[outlets]]`` and changes the engine's particles at their
scheduled steps (``Simulation.run`` calls ``apply`` between compiled chunks, at gas-step boundaries in coupled
runs). An inlet inserts, every ``interval`` seconds from ``start``, the particles its rate gives over the next
interval, drawn from its species' size distribution and placed at random in its box without overlap with each
other or with the particles there (``_population_kernels.insert_fill``); what a crowded box cannot take is
carried to the next insertion. An outlet removes, every ``interval``, the particles whose centre lies in its
box or behind its plane. Counts and masses go to the probes and the summary; the events are numbered by step,
so a run gives the same particles whatever its chunks, threads or resumes.
"""
from __future__ import annotations

import math
import zlib

import numpy as np

from ..state import ParticleState
from ._population_kernels import insert_fill
from .placement import species_diameters

MAX_TRIES = 200  # random places tried for each new particle before the rest wait for the next insertion
OUTLET_INTERVAL = 1e-3  # [s] between removals


def _safe(name: str) -> str:
    return "".join(c if c.isalnum() or c in "-_" else "_" for c in name)


class _Inlet:
    def __init__(self, spec, species_index, species, z0, end):
        self.spec, self.k, self.species = spec, species_index, species
        self.lower = np.array(spec.lower, float)
        self.upper = np.array(spec.upper, float)
        self.z0 = z0
        self.stop = min(spec.stop, end) if spec.stop is not None else end
        self.count = 0
        self.mass = 0.0
        self.events = 0  # insertions done

    def due_time(self) -> float:
        return self.spec.start + self.events * self.spec.interval

    def owed(self) -> bool:
        """True while the insertions up to ``stop`` fell short of what the rate asks (a crowded box)."""
        horizon = self.stop - self.spec.start
        if self.spec.rate is not None:
            return self.count < int(math.floor(self.spec.rate * horizon + 1e-9))
        m_mean = self.species.density * math.pi / 6.0 * self.species.diameter**3
        return self.spec.mass_rate * horizon - self.mass >= 0.5 * m_mean

    def active(self) -> bool:
        """Insertions are due: until ``stop`` (and ``total``), and after it while the box still owes some."""
        if self.spec.total is not None and self.count >= self.spec.total:
            return False
        return self.due_time() <= self.stop + 1e-12 or self.owed()


class Population:
    """The inlets and outlets of a case and their running totals."""

    def __init__(self, case, engine, gas_substeps: int = 1):
        self.case, self.engine = case, engine
        self.substeps = gas_substeps
        species = case.particles.species
        names = [s.name for s in species]
        self.densities = np.array([s.density for s in species])
        dim2 = case.particles.dimensions == 2
        self.dim2 = dim2
        end = case.time.end
        self.inlets = []
        self._check_periodic_sides(case, engine)
        for spec in case.inlets:
            k = names.index(spec.species) if spec.species is not None else 0
            z0 = self._plane_z(spec) if dim2 else 0.0
            self.inlets.append(_Inlet(spec, k, species[k], z0, end))
        self.outlets = list(case.outlets)
        self.out_count = {o.name: 0 for o in self.outlets}
        self.out_mass = {o.name: 0.0 for o in self.outlets}
        self.out_first = {o.name: None for o in self.outlets}  # (time, mass) at the first and last removal
        self.out_last = {o.name: None for o in self.outlets}
        self.outlet_events = 0
        st = engine.state
        self.next_id = int(st.ids.max()) + 1 if st.n else 0
        self.deficit_warned = False

    @staticmethod
    def _check_periodic_sides(case, engine) -> None:
        """An inlet's box keeps one largest diameter from a periodic side: the insertion checks overlaps inside
        the box and beside it, not with the images across the side."""
        period = getattr(engine, "period", None)
        if period is None or not np.any(period > 0.0):
            return
        lo = engine.box_lo
        gap = 2.0 * engine.largest_radius
        for j, spec in enumerate(case.inlets):
            for d in np.flatnonzero(period > 0.0):
                if spec.lower[d] < lo[d] + gap or spec.upper[d] > lo[d] + period[d] - gap:
                    from ..errors import CaseError

                    ax = "xyz"[d]
                    raise CaseError(
                        f"inlets.{j} ({spec.name!r}): lower {ax} = {spec.lower[d]:g}, upper {ax} = {spec.upper[d]:g} m "
                        f"reaches within one largest diameter ({gap:.4g} m) of the periodic sides at {lo[d]:g} and "
                        f"{lo[d] + period[d]:g} m; keep the insertion box from {lo[d] + gap:.4g} to "
                        f"{lo[d] + period[d] - gap:.4g} m along {ax}")

    def _plane_z(self, spec) -> float:
        """2D: the z of the particles' centres (the engine's particles, else the middle of the walls' box, else
        of the inlet's box)."""
        st = self.engine.state
        if st.n:
            return float(st.position[0, 2])
        walls = self.engine.walls
        if walls.box_lower is not None:
            return 0.5 * float(walls.box_lower[2] + walls.box_upper[2])
        return 0.5 * (spec.lower[2] + spec.upper[2])

    # ------------------------------------------------------------ schedule
    def _step_of(self, t: float, dt: float) -> int:
        """The first step at or after time t, at a gas-step boundary in a coupled run."""
        s = int(math.ceil(t / dt - 1e-6))
        q = self.substeps
        return -(-s // q) * q

    def next_step(self, dt: float) -> int:
        """The step of the next insertion or removal (a very large number when none is left)."""
        steps = [self._step_of(i.due_time(), dt) for i in self.inlets if i.active()]
        if self.outlets:
            steps.append(self._step_of(self.outlet_events * OUTLET_INTERVAL, dt))
        return min(steps) if steps else 2**62

    def apply(self, step: int, dt: float, time: float) -> bool:
        """Every insertion and removal due at ``step``; True if the particles changed."""
        st = self.engine.state
        keep = np.ones(st.n, dtype=np.bool_)
        changed = False
        if self.outlets and self._step_of(self.outlet_events * OUTLET_INTERVAL, dt) <= step:
            changed |= self._remove(keep, time)
            while self._step_of(self.outlet_events * OUTLET_INTERVAL, dt) <= step:
                self.outlet_events += 1
        added = []
        for inlet in self.inlets:
            while inlet.active() and self._step_of(inlet.due_time(), dt) <= step:
                new = self._insert(inlet, keep, added)
                if new is not None:
                    added.append(new)
                inlet.events += 1
        if added:
            added_state = _concat(added)
            changed = True
        else:
            added_state = None
        if changed:
            self.engine.replace_particles(keep, added_state)
        return changed

    # ------------------------------------------------------------ outlets
    def _remove(self, keep: np.ndarray, time: float) -> bool:
        st = self.engine.state
        any_removed = False
        for o in self.outlets:
            if o.kind == "box":
                lo, hi = np.array(o.lower), np.array(o.upper)
                hit = np.all((st.position >= lo) & (st.position <= hi), axis=1)
            else:
                nrm = np.array(o.normal, float)
                nrm /= np.linalg.norm(nrm)
                hit = (st.position - np.array(o.point)) @ nrm < 0.0
            hit &= keep
            m = int(np.count_nonzero(hit))
            if m:
                any_removed = True
                keep &= ~hit
                self.out_count[o.name] += m
                self.out_mass[o.name] += float(st.mass[hit].sum())
                if self.out_first[o.name] is None:
                    self.out_first[o.name] = (time, self.out_mass[o.name])
                self.out_last[o.name] = (time, self.out_mass[o.name])
        return any_removed

    # ------------------------------------------------------------ inlets
    def _insert(self, inlet: _Inlet, keep: np.ndarray, added: list) -> ParticleState | None:
        spec = inlet.spec
        t_event = inlet.due_time()
        horizon = min(t_event + spec.interval, inlet.stop) - spec.start
        seed = zlib.crc32(f"{spec.seed}:{inlet.events}".encode()) & 0x7FFFFFFF
        rng = np.random.default_rng(seed)
        rho = self.densities[inlet.k]
        if spec.rate is not None:
            want = int(math.floor(spec.rate * horizon + 1e-9)) - inlet.count
            if spec.total is not None:
                want = min(want, spec.total - inlet.count)
            if want <= 0:
                return None
            diam = species_diameters(inlet.species, want, rng)
        else:
            left = spec.mass_rate * horizon - inlet.mass
            m_mean = rho * math.pi / 6.0 * inlet.species.diameter**3
            if left < 0.5 * m_mean:
                return None
            guess = int(1.5 * left / m_mean) + 8
            diam = species_diameters(inlet.species, guess, rng)
            cum = np.cumsum(rho * math.pi / 6.0 * diam**3)
            take = int(np.searchsorted(cum, left + 0.5 * m_mean, side="right"))
            if spec.total is not None:
                take = min(take, spec.total - inlet.count)
            diam = diam[:take]
            if take <= 0:
                return None
        order = np.argsort(-diam, kind="stable")
        diam = diam[order]
        st = self.engine.state
        old_pos = [st.position[keep]] + [a.position for a in added]
        old_rad = [st.radius[keep]] + [a.radius for a in added]
        pos, placed = insert_fill(np.ascontiguousarray(np.concatenate(old_pos)), np.concatenate(old_rad),
                                  0.5 * diam, inlet.lower, inlet.upper, self.dim2, inlet.z0, seed, MAX_TRIES)
        if placed < diam.size and not self.deficit_warned:
            import logging

            logging.getLogger(__name__).warning(
                "inlet %r: only %d of %d particles found room in its box at t = %.4g s; the rest wait for the next "
                "insertion (a larger box or a shorter interval spreads them)", spec.name, placed, diam.size, t_event)
            self.deficit_warned = True
        if placed == 0:
            return None
        pos, diam = pos[:placed], diam[:placed]
        vel = np.tile(np.array(spec.velocity, float), (placed, 1))
        if self.dim2:
            vel[:, 2] = 0.0
        new = ParticleState.create(pos, vel, diam, np.full(placed, inlet.k, dtype=np.int64), self.densities)
        new.ids = np.arange(self.next_id, self.next_id + placed, dtype=np.int64)
        self.next_id += placed
        inlet.count += placed
        inlet.mass += float(new.mass.sum())
        return new

    # ------------------------------------------------------------ output
    def probes(self, sim=None) -> dict[str, float]:
        """Probe columns: the particle count, and each inlet's and outlet's running count and mass."""
        out = {"n_particles": float(self.engine.state.n)}
        for i in self.inlets:
            out[f"inlet_{_safe(i.spec.name)}_count"] = float(i.count)
            out[f"inlet_{_safe(i.spec.name)}_mass_kg"] = i.mass
        for o in self.outlets:
            out[f"outlet_{_safe(o.name)}_count"] = float(self.out_count[o.name])
            out[f"outlet_{_safe(o.name)}_mass_kg"] = self.out_mass[o.name]
        return out

    def summary(self) -> dict:
        """Summary entries: totals per inlet and outlet, and each outlet's mass flow rate [kg/s] between its
        first and its last removal (None before two removals at different times)."""
        out = {}
        for i in self.inlets:
            out[f"inlet_{_safe(i.spec.name)}_count"] = i.count
            out[f"inlet_{_safe(i.spec.name)}_mass_kg"] = i.mass
        for o in self.outlets:
            out[f"outlet_{_safe(o.name)}_count"] = self.out_count[o.name]
            out[f"outlet_{_safe(o.name)}_mass_kg"] = self.out_mass[o.name]
            first, last = self.out_first[o.name], self.out_last[o.name]
            rate = None
            if first is not None and last[0] > first[0]:
                rate = (last[1] - first[1]) / (last[0] - first[0])
            out[f"outlet_{_safe(o.name)}_mass_rate_kg_s"] = rate
        return out

    # ------------------------------------------------------------ checkpoint
    def checkpoint_scalars(self) -> dict:
        return {"population": {
            "next_id": self.next_id, "outlet_events": self.outlet_events,
            "inlets": {i.spec.name: [i.count, i.mass, i.events] for i in self.inlets},
            "outlets": {o.name: [self.out_count[o.name], self.out_mass[o.name], self.out_first[o.name],
                                 self.out_last[o.name]] for o in self.outlets}}}

    def restore(self, scalars: dict) -> None:
        p = scalars.get("population")
        if p is None:
            return
        self.next_id = int(p["next_id"])
        self.outlet_events = int(p["outlet_events"])
        for i in self.inlets:
            if i.spec.name in p["inlets"]:
                c, m, e = p["inlets"][i.spec.name]
                i.count, i.mass, i.events = int(c), float(m), int(e)
        for o in self.outlets:
            if o.name in p["outlets"]:
                c, m, first, last = p["outlets"][o.name]
                self.out_count[o.name], self.out_mass[o.name] = int(c), float(m)
                self.out_first[o.name] = tuple(first) if first is not None else None
                self.out_last[o.name] = tuple(last) if last is not None else None


def _concat(states: list[ParticleState]) -> ParticleState:
    return ParticleState(**{k: np.ascontiguousarray(np.concatenate([getattr(s, k) for s in states]))
                            for k in states[0].arrays()})
