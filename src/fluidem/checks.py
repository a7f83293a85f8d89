"""Health checks of a running simulation, made between compiled chunks of steps, and the ``[checks]`` section.

``Simulation.run`` calls ``RunChecks`` after every chunk, before any observer sees the state: particles that
left the domain, an overlap beyond ``checks.max_overlap``, a kinetic energy that jumped by orders of magnitude
with no source to feed it, non-finite particle or gas fields. A failed check raises ``RunFailure``, which
names the check, the particle (its id), where it is, when, and what to look at; the run ends with status
``failed`` and keeps its last good checkpoint. The checks are vectorised NumPy over the particles (and the
compiled contact statistics of ``analysis``), so they cost a small fraction of a chunk; they see the state at
the end of each chunk, not every step in it.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from pydantic import BaseModel, ConfigDict, Field

from ._checks_kernels import particle_scan

EARTH_GRAVITY = 9.81  # [m/s^2], the scale against which a case's gravity is called large in a hint
MOVING_FAST = 0.05  # a particle moving more than this many diameters per step is named in a hint [-]
_NO_WALLS = np.zeros((0, 3))
_NO_LOWER, _NO_UPPER = np.full(3, -math.inf), np.full(3, math.inf)


class ChecksSection(BaseModel):
    """Health checks made between compiled chunks of steps; a failed check stops the run with status
    ``failed``, its reason in summary.json and the last good checkpoint kept."""

    model_config = ConfigDict(extra="forbid", validate_assignment=True)

    enabled: bool = Field(True, description="make the domain, overlap and kinetic-energy checks (false: only "
                                            "non-finite values stop a run)")
    max_overlap: float = Field(
        0.3, gt=0.0, le=1.0,
        description="largest overlap of two soft spheres, or of a sphere and a wall, as a fraction of the smaller "
                    "diameter [-], in (0, 1]; beyond it the run fails (hard spheres do not overlap)")
    domain_margin: float = Field(
        1.0, ge=0.0,
        description="how far a particle's centre may lie beyond a wall plane, or outside the gas grid of a coupled "
                    "run, in its own diameters [-], >= 0; beyond it the run fails")
    kinetic_energy_jump: float = Field(
        1.0e3, gt=1.0,
        description="the run fails when the particles' kinetic energy (with rotation) grows within one chunk of "
                    "steps by more than this factor over the larger of its value before and the energy gravity, "
                    "the gas and moving walls could supply [-], > 1")


class RunFailure(FloatingPointError):
    """A run blew up: a health check failed (or the gas diverged, or hard spheres collapsed).

    ``check`` names it (``domain``, ``overlap``, ``kinetic_energy``, ``non_finite``, ``gas``, ``collisions``);
    ``time`` is the simulated time it was found [s] and ``last_good_time`` that of the last state that passed;
    ``particle_id``/``position`` [m] the particle concerned (None: none in particular); ``value``/``limit``
    the measured figure and its limit; ``hint`` what to check. ``record()`` is the ``failure`` entry of
    summary.json. A ``FloatingPointError``, as a non-finite state always was.
    """

    def __init__(self, check: str, message: str, time: float, hint: str = "", *, particle_id: int | None = None,
                 position=None, value: float | None = None, limit: float | None = None,
                 last_good_time: float | None = None):
        self.check, self.message, self.time, self.hint = check, message, float(time), hint
        self.particle_id = None if particle_id is None else int(particle_id)
        self.position = None if position is None else [float(x) for x in position]
        self.value = None if value is None else float(value)
        self.limit = None if limit is None else float(limit)
        self.last_good_time = None if last_good_time is None else float(last_good_time)
        self.checkpoint = None  # (path, time) of the last good checkpoint, set by the Simulation
        super().__init__(str(self))

    def __str__(self) -> str:
        text = f"{self.check} check failed at t = {self.time:.6g} s: {self.message}"
        if self.hint:
            text += f". Check: {self.hint}"
        if self.checkpoint is not None:
            path, t = self.checkpoint
            text += f". The last good checkpoint (t = {t:.6g} s) is kept in {path}"
        return text

    def record(self) -> dict:
        """The ``failure`` entry of summary.json."""
        out = {"check": self.check, "message": self.message, "hint": self.hint, "time_s": self.time,
               "last_good_time_s": self.last_good_time, "particle_id": self.particle_id,
               "position_m": self.position, "value": self.value, "limit": self.limit}
        if self.checkpoint is not None:
            out["checkpoint"], out["checkpoint_time_s"] = str(self.checkpoint[0]), self.checkpoint[1]
        return out


# ================================================================ the checks on arrays
class Scan(NamedTuple):
    """What one pass over the particles found (``_checks_kernels.particle_scan``; its docstring has the units).

    first_bad: the first particle with a non-finite position, velocity or spin (−1: none). kinetic: the
    kinetic energy with rotation [J]. excess: how far the centre furthest out of the domain lies beyond its
    limit [m] (> 0: out), excess_i its particle, excess_where the wall index (>= 0) or −1 − (2 axis + side)
    for a bound of the box (side 0 lower, 1 upper). wall_rel: the deepest particle–wall overlap over the
    particle's diameter (−inf without walls), wall_i, wall_w its particle and wall. height_lo, height_hi: the
    particles' range along ``up`` [m]. mass_total [kg].
    """

    first_bad: int
    kinetic: float
    excess: float
    excess_i: int
    excess_where: int
    wall_rel: float
    wall_i: int
    wall_w: int
    height_lo: float
    height_hi: float
    mass_total: float


def scan(position: np.ndarray, radius: np.ndarray, *, velocity=None, omega=None, mass=None, inertia=None,
         wall_point=None, wall_normal=None, lower=None, upper=None, up=None, margin: float = 1.0) -> Scan:
    """One compiled pass over the particles for the checks (see ``Scan``); arrays left out are zeros (no
    walls, no bounds, no gravity). A particle is out of the domain when its centre lies more than ``margin``
    of its diameters behind a wall plane (``wall_point``, inward ``wall_normal``, (W, 3) [m]) or outside the
    box [``lower``, ``upper``] ((3,) [m], ±inf: no bound on that side)."""
    n = position.shape[0]
    zeros3, zeros = np.zeros((n, 3)), np.zeros(n)
    no_walls = np.zeros((0, 3))
    inf = np.full(3, math.inf)
    out = particle_scan(position, zeros3 if velocity is None else velocity, zeros3 if omega is None else omega,
                        radius, zeros if mass is None else mass, zeros if inertia is None else inertia,
                        no_walls if wall_point is None else np.asarray(wall_point, float),
                        no_walls if wall_normal is None else np.asarray(wall_normal, float),
                        -inf if lower is None else np.asarray(lower, float),
                        inf if upper is None else np.asarray(upper, float),
                        np.zeros(3) if up is None else np.asarray(up, float), float(margin))
    return Scan(*out)


def largest_pair_overlap(position: np.ndarray, radius: np.ndarray, row_start: np.ndarray, partner: np.ndarray,
                         locate_above: float = 0.0, period: np.ndarray | None = None) -> tuple[float, int, int]:
    """The deepest overlap of two particles as a fraction of the smaller diameter: (fraction, i, j);
    (0, −1, −1) when no pair overlaps. The pairs are those of the contact list (``row_start``, ``partner``: CSR
    of the pairs that may touch), in one compiled pass; the pair (i, j) is looked for only when the fraction
    exceeds ``locate_above`` (else −1, −1). ``period`` (3,): the box length along each periodic axis (0, or None:
    none), offsets taken by nearest image there."""
    from .analysis._contacts_kernels import contact_counts

    if not partner.shape[0]:
        return 0.0, -1, -1
    period = np.zeros(3) if period is None else np.asarray(period, dtype=float)
    _, _, worst = contact_counts(position, radius, row_start, partner, period)
    if not worst > max(locate_above, 0.0):
        return max(float(worst), 0.0), -1, -1
    i = np.repeat(np.arange(position.shape[0]), np.diff(row_start))
    j = partner.astype(np.int64)
    r = position[i] - position[j]
    per = period > 0.0
    r[:, per] -= period[per] * np.round(r[:, per] / period[per])
    dist = np.linalg.norm(r, axis=1)
    rel = (radius[i] + radius[j] - dist) / (2.0 * np.minimum(radius[i], radius[j]))
    k = int(np.argmax(rel))
    return float(rel[k]), int(i[k]), int(j[k])


def kinetic_energies(mass, velocity, inertia, omega) -> np.ndarray:
    """(N,) kinetic energy of each particle, translation and rotation [J]."""
    return 0.5 * (mass * np.einsum("ij,ij->i", velocity, velocity) + inertia * np.einsum("ij,ij->i", omega, omega))


def energy_supply(mass_total: float, gravity: float, height: float, speed: float, duration: float) -> float:
    """The kinetic energy that sources could give the particles from rest within ``duration`` [s] [J]:
    a fall through ``height`` [m] (or free fall for ``duration``) under ``gravity`` [m/s^2], plus motion at
    ``speed`` [m/s], the largest of the gas and wall speeds: M (g H + (g t)²/2 + U²/2)."""
    return mass_total * (gravity * height + 0.5 * (gravity * duration) ** 2 + 0.5 * speed**2)


def kinetic_energy_jumped(now: float, before: float, supply: float, factor: float) -> bool:
    """True if ``now`` exceeds ``factor`` times the larger of ``before`` and ``supply`` [J] (never when both
    are zero: a state at rest with no source has no scale to compare with)."""
    scale = max(before, supply)
    return scale > 0.0 and now > factor * scale


# ================================================================ the checks of a run
class RunChecks:
    """The checks of one ``Simulation``: ``start()`` at the beginning of a run, then one call per chunk.

    Parameters
    ----------
    settings : ChecksSection
    engine : ParticleEngine
    coupling : GasCoupling or None
    """

    def __init__(self, settings: ChecksSection, engine, coupling=None):
        self.settings, self.engine, self.coupling = settings, engine, coupling
        self.seconds = 0.0  # wall time spent in the checks [s]
        self.calls = 0
        case = engine.case
        self.gravity = float(np.linalg.norm(engine.gravity))
        self.up = -engine.gravity / self.gravity if self.gravity > 0 else np.zeros(3)
        # bounds of the box: the gas grid of a coupled run (its non-periodic axes)
        self.lower = self.upper = None
        self._gas_speed = 0.0  # the largest gas speed at the last check [m/s]
        height = 0.0
        if coupling is not None:
            gd = coupling.grid
            periodic = tuple(coupling._periodic) + (True,) * (3 - len(coupling._periodic))  # 2D: z unbounded
            faces = (gd.x_faces, gd.y_faces, gd.z_faces if gd.dimensions == 3 else None)
            self.lower = np.array([-math.inf if periodic[a] else faces[a][0] for a in range(3)])
            self.upper = np.array([math.inf if periodic[a] else faces[a][-1] for a in range(3)])
            height = abs(float(np.array([f[-1] if f is not None else 0.0 for f in faces]) @ self.up))
        walls = engine.walls
        if walls.box_lower is not None:
            height = max(height, abs(float((walls.box_upper - walls.box_lower) @ self.up)))
        self.height = height
        self._lower = _NO_LOWER if self.lower is None else np.ascontiguousarray(self.lower, dtype=float)
        self._upper = _NO_UPPER if self.upper is None else np.ascontiguousarray(self.upper, dtype=float)
        self.wall_speed = _wall_speed(engine.wall_motion)
        self.moving_walls = bool(np.any(engine.wall_motion[:, 0] != 0))
        st = engine.state
        self.initial_speed = float(np.sqrt(np.max(np.einsum("ij,ij->i", st.velocity, st.velocity)))) \
            if st.n and engine.steps == 0 else None
        self.placement_velocity = tuple(case.particles.placement.velocity)
        self._ke_before = 0.0
        self._t_before = engine.time

    # ------------------------------------------------------------ driving
    def start(self) -> None:
        """Remember the state the run starts from (its kinetic energy and time)."""
        st = self.engine.state
        self._ke_before = float(np.sum(kinetic_energies(st.mass, st.velocity, st.inertia, st.omega))) if st.n else 0.0
        self._t_before = self.engine.time

    def __call__(self) -> None:
        """Check the state now; raise ``RunFailure`` on the first check that fails."""
        import time as _time

        t0 = _time.perf_counter()
        try:
            self._check(remember=True)
        finally:
            self.seconds += _time.perf_counter() - t0
            self.calls += 1

    def _check(self, remember: bool) -> None:
        """Raise the first failure of the state now; ``remember``: keep its kinetic energy and time as those of
        the last good state."""
        eng = self.engine
        st = eng.state
        if self.coupling is not None:
            self._gas_finite()
        if st.n == 0:
            return
        on = self.settings.enabled
        point, normal = self._walls() if on else (_NO_WALLS, _NO_WALLS)
        lower, upper = (self._lower, self._upper) if on else (_NO_LOWER, _NO_UPPER)
        sc = Scan(*particle_scan(st.position, st.velocity, st.omega, st.radius, st.mass, st.inertia, point, normal,
                                 lower, upper, self.up, self.settings.domain_margin))
        if sc.first_bad >= 0:
            raise self._non_finite(sc.first_bad)
        if on:
            if sc.excess > 0.0:
                raise self._domain(sc)
            if eng.contact_forces:  # soft spheres; hard spheres collide without overlap
                rel, i, j = largest_pair_overlap(st.position, st.radius, eng.row_start, eng.partner,
                                                 self.settings.max_overlap, eng.period)
                wall = None
                if sc.wall_rel > rel:
                    rel, i, j, wall = sc.wall_rel, sc.wall_i, -1, eng.walls.names[sc.wall_w]
                shapes = getattr(eng, "shapes", None)
                if shapes is not None and len(shapes):  # wall shapes: the deepest overlap of a particle with one
                    _, overlap, shape = shapes.contacts(st, eng.time)
                    k = int(np.argmax(overlap / st.radius))
                    if 0.5 * overlap[k] / st.radius[k] > rel:
                        rel, i, j, wall = 0.5 * float(overlap[k] / st.radius[k]), k, -1, shapes.names[shape[k]]
                if rel > self.settings.max_overlap:
                    raise self._overlap(rel, i, j, wall)
            supply = self._supply(sc)
            if kinetic_energy_jumped(sc.kinetic, self._ke_before, supply, self.settings.kinetic_energy_jump):
                raise self._energy(sc.kinetic, supply)
            if remember:
                self._ke_before = sc.kinetic
        if remember:
            self._t_before = eng.time

    def _walls(self) -> tuple[np.ndarray, np.ndarray]:
        """(points (W, 3) at the engine's time, normals (W, 3)) of the wall planes."""
        from .particles._softsphere_kernels import walls_now

        eng = self.engine
        if not self.moving_walls:
            return eng.wall_point0, eng.wall_normal
        return np.ascontiguousarray(walls_now(eng.wall_motion, eng.wall_point0, eng.time)[:, :3]), eng.wall_normal

    def _supply(self, sc: Scan) -> float:
        """``energy_supply`` now: a fall through the larger of the domain's height and the particles' span,
        at the largest of the gas and wall speeds, over the time since the last check."""
        height = max(self.height, sc.height_hi - sc.height_lo) if self.gravity > 0.0 else 0.0
        speed = max(self.wall_speed, self._gas_speed)
        return energy_supply(sc.mass_total, self.gravity, height, speed, self.engine.time - self._t_before)

    # ------------------------------------------------------------ failures
    def _failure(self, check, message, hint, k=None, **kw) -> RunFailure:
        st = self.engine.state
        if k is not None:
            kw.update(particle_id=int(st.ids[k]), position=st.position[k])
        return RunFailure(check, message, self.engine.time, hint, last_good_time=self._t_before, **kw)

    def _speed(self, k) -> float:
        v = self.engine.state.velocity[k]
        return float(math.sqrt(float(v @ v)))

    def _where(self, k) -> str:
        x = self.engine.state.position[k]
        return f"({x[0]:.4g}, {x[1]:.4g}, {x[2]:.4g}) m"

    def _non_finite(self, k) -> RunFailure:
        st = self.engine.state
        what = [name for name, a in (("position", st.position), ("velocity", st.velocity), ("spin", st.omega))
                if not np.isfinite(a[k]).all()]
        what = what or ["sum of position, velocity and spin (values near the largest float)"]
        n = int(np.count_nonzero(~np.isfinite(st.position).all(axis=1) | ~np.isfinite(st.velocity).all(axis=1)))
        message = (f"particle {int(st.ids[k])} has a non-finite {' and '.join(what)} ({n} particle(s) with "
                   f"non-finite position or velocity) after a chunk that began at t = {self._t_before:.6g} s")
        hints = ["the state blew up within one chunk of steps; probes.csv up to that time shows how it grew"]
        hints += self._cause_hints(None)
        return self._failure("non_finite", message, "; ".join(hints), k)

    def _domain(self, sc: Scan) -> RunFailure:
        st = self.engine.state
        k, excess, where = sc.excess_i, sc.excess, sc.excess_where
        d = 2.0 * float(st.radius[k])
        margin = self.settings.domain_margin
        if where >= 0:
            name = self.engine.walls.names[where]
            beyond = excess + margin * d
            message = (f"particle {int(st.ids[k])} at {self._where(k)}, moving at {self._speed(k):.4g} m/s, is "
                       f"{beyond:.4g} m beyond wall {name!r} "
                       f"(limit: checks.domain_margin = {margin:g} diameter(s), {margin * d:.4g} m)")
        else:
            axis, side = divmod(-1 - where, 2)
            names = (("left", "right"), ("bottom", "top"), ("back", "front"))
            message = (f"particle {int(st.ids[k])} at {self._where(k)}, moving at {self._speed(k):.4g} m/s, left "
                       f"the gas grid through its {names[axis][side]} side by {excess + margin * d:.4g} m (limit: checks.domain_margin = "
                       f"{margin:g} diameter(s), {margin * d:.4g} m)")
        tc = getattr(self.engine, "contact_time", None)
        tc = f"; contact time {tc:.4g} s" if tc else ""
        hints = [(f"the contacts (particles.contact, particles.wall_contact{tc}) must stop a particle at a wall "
                  "within a few steps: they are too soft, or the time step too long, for its speed")]
        hints += self._cause_hints(k)
        return self._failure("domain", message, "; ".join(hints), k, value=excess + margin * d, limit=margin * d)

    def _overlap(self, rel, i, j, wall) -> RunFailure:
        """The overlap failure of particle i with particle j (>= 0) or with the wall named ``wall``."""
        st = self.engine.state
        limit = self.settings.max_overlap
        other = (f"particle {int(st.ids[j])} by {rel:.4g} of the smaller diameter" if j >= 0 else
                 f"wall {wall!r} by {rel:.4g} of its diameter")
        message = f"particle {int(st.ids[i])} at {self._where(i)} overlaps {other} (limit: checks.max_overlap = {limit:g})"
        speed = self._speed(i) if j < 0 else float(np.linalg.norm(st.velocity[i] - st.velocity[j]))
        hints = [(f"the contacts are too soft for the loads and impact speeds (relative speed now {speed:.4g} m/s): "
                  "raise particles.contact.stiffness (youngs_modulus for Hertz laws; particles.wall_contact for "
                  "walls)")]
        model = getattr(self.engine.case.particles.contact, "model", "")
        if "hertz" in model:
            hints.append(f"the Hertz time step is set for time.impact_velocity = "
                         f"{self.engine.case.time.impact_velocity:g} m/s: set it to the largest impact speed")
        hints += self._cause_hints(i)
        return self._failure("overlap", message, "; ".join(hints), i, value=rel, limit=limit)

    def _energy(self, total, supply) -> RunFailure:
        st = self.engine.state
        k = int(np.argmax(kinetic_energies(st.mass, st.velocity, st.inertia, st.omega)))
        factor = self.settings.kinetic_energy_jump
        before = self._ke_before
        message = (f"the particles' kinetic energy rose from {before:.4g} J at t = {self._t_before:.6g} s to "
                   f"{total:.4g} J, above checks.kinetic_energy_jump = {factor:g} times the larger of its value "
                   f"before and {supply:.4g} J, what gravity, the gas and the walls could supply; particle "
                   f"{int(st.ids[k])} at {self._where(k)} has the most ({self._speed(k):.4g} m/s)")
        dt = self.engine.dt
        tc = getattr(self.engine, "contact_time", None)
        steps = f" ({tc / dt:.3g} steps per contact time)" if tc else ""
        hints = [(f"energy from nowhere is a numerical instability: the time step dt = {dt:.4g} s is too long for "
                  f"the contacts{steps}; leave time.dt unset (time.dt_fraction × contact time) or lower it")]
        hints += self._cause_hints(k)
        return self._failure("kinetic_energy", message, "; ".join(hints), k, value=total,
                             limit=factor * max(before, supply))

    def _gas_finite(self) -> None:
        """Raise if a gas field is not finite; keep the largest gas speed (``_gas_speed``) [m/s]."""
        gs = self.coupling.state
        u, v = float(np.abs(gs.u).max()), float(np.abs(gs.v).max())
        w = float(np.abs(gs.w).max()) if gs.w is not None else 0.0
        self._gas_speed = max(u, v, w)
        for name, value in (("p", float(np.sum(gs.p))), ("u", u), ("v", v), ("w", w)):  # NaN and inf carry to the sum, max
            if not math.isfinite(value):
                a = getattr(gs, name)
                cell = np.unravel_index(int(np.argmax(~np.isfinite(a))), a.shape)
                message = f"gas field {name} is not finite (first at index {tuple(int(c) for c in cell)})"
                raise self._gas(message)

    def _gas(self, message: str) -> RunFailure:
        st = self.engine.state
        hints = [(f"the gas time step gas.dt = {self.coupling.gas_dt:g} s must keep the Courant number below 1 "
                  "(0.5 with TVD convection): lower gas.dt or the inflow velocities")]
        k = None
        if st.n:
            v2 = np.einsum("ij,ij->i", st.velocity, st.velocity)
            k = int(np.argmax(np.where(np.isfinite(v2), v2, np.inf)))
            hints.append(f"particles far faster than the gas drive it: the fastest, particle {int(st.ids[k])}, "
                         f"moves at {self._speed(k):.4g} m/s")
            hints += self._cause_hints(None)
        return self._failure("gas", message, "; ".join(hints), k)

    def from_error(self, err: Exception) -> RunFailure:
        """A ``RunFailure`` for an error raised while stepping: hard spheres collapsed (``CollisionCascadeError``),
        or a gas step failed (``GasConvergenceError``, or the exchange refused the particles: ``ValueError``).

        A failed gas step is often the consequence of particles gone wrong (out of the grid, absurd speeds): when
        the state now fails a check, that failure is returned, with the gas's error added to its message."""
        from .particles.hardsphere import CollisionCascadeError

        if isinstance(err, CollisionCascadeError):
            return RunFailure("collisions", str(err), self.engine.time, last_good_time=self._t_before)
        text = str(err).split(": keep it below")[0]  # GasConvergenceError: _gas gives the Courant hint
        try:
            self._check(remember=False)
        except RunFailure as cause:
            cause.message += f"; then the gas step failed: {text}"
            return cause
        return self._gas(text if "gas step" in text else f"the gas–particle exchange failed: {text}")

    def _cause_hints(self, k) -> list[str]:
        """What in the case may have driven the blow-up: a long step for the particle's speed, large gravity,
        large initial velocities."""
        eng = self.engine
        out = []
        if k is not None:
            d = 2.0 * float(eng.state.radius[k])
            per_step = self._speed(k) * eng.dt / d
            if per_step > MOVING_FAST:
                out.append(f"at {self._speed(k):.4g} m/s it moves {per_step:.3g} diameters per time step "
                           f"(dt = {eng.dt:.4g} s)")
        if self.gravity > 100.0 * EARTH_GRAVITY:
            g = ", ".join(f"{x:g}" for x in eng.gravity)
            out.append(f"gravity = [{g}] m/s^2 is {self.gravity / EARTH_GRAVITY:.3g} times Earth's")
        if any(self.placement_velocity):
            v = ", ".join(f"{x:g}" for x in self.placement_velocity)
            out.append(f"the initial velocities (particles.placement.velocity = [{v}] m/s)")
        elif self.initial_speed:
            out.append(f"the initial velocities (up to {self.initial_speed:.4g} m/s at t = 0)")
        return out


def _wall_speed(motion: np.ndarray) -> float:
    """The largest speed of a moving wall [m/s] from the engine's (W, 6) motion table (``walls.WallSet.arrays``)."""
    from .particles._softsphere_kernels import CONSTANT_VELOCITY, OSCILLATING

    speed = 0.0
    for row in motion:
        if int(row[0]) == CONSTANT_VELOCITY:
            speed = max(speed, float(np.linalg.norm(row[1:4])))
        elif int(row[0]) == OSCILLATING:
            speed = max(speed, float(np.linalg.norm(row[1:4])) * 2.0 * math.pi * float(row[4]))
    return speed
