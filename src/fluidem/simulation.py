"""Simulation: the clock, the step loop, observers, run directory and checkpoints.

The case says *what*, ``Simulation.run(until=…)`` says *for how long*, observers
say *what to keep*. Observers are objects with ``schedule`` (``Every``/``EveryTime``),
``__call__(sim)`` and optionally ``finalize(sim)``; they read state, never write it.
"""
from __future__ import annotations

import logging
import math
import time as _time
from pathlib import Path

import numpy as np

from . import _threads
from .analysis import fluidised as F
from .analysis import mixing as M
from .analysis import probes as P
from .analysis.repose import drum_of as repose_drum_of, repose_probes, summary_entries as repose_summary
from .case import Case, validate_case
from .checks import RunChecks, RunFailure
from .errors import CaseError, CheckpointError
from .gas.solver import GasConvergenceError
from .io.atomic import write_text_atomic
from .io.gas_fields import GasFieldWriter
from .io.probes_csv import ProbeWriter
from .io.shapes_csv import ShapeWriter
from .io.shapes_xdmf import ShapeSnapshotWriter
from .io.restart import CHECKPOINT_NAMES, PREVIOUS_RESTART_NAME, RESTART_NAME, load_restart, save_restart
from .io.summary import finite, summary_json
from .io.snapshots import ParticleWriter
from .particles import engine_for
from .particles.hardsphere import CollisionCascadeError
from .schedule import EveryTime
from .state import ParticleState

log = logging.getLogger(__name__)

CHUNK_WALL_SECONDS = 0.25  # a compiled chunk should return to Python about this often (Ctrl-C, progress)
COMPILE_NOTICE_SECONDS = 3.0  # a first chunk still running after this long is compiling: say so
_kernels_ready = False  # a chunk has returned in this process: the kernels are compiled or loaded


def _mark_kernels_ready() -> None:
    global _kernels_ready
    _kernels_ready = True


def steps_to(until: float, dt: float) -> int:
    """The step count that reaches simulated time ``until`` with steps ``dt``: the first step at or after it
    (a run never stops short of the time asked; it overshoots by less than one step, and by nothing where
    ``until`` is a multiple of ``dt`` to a millionth of a step)."""
    return int(math.ceil(until / dt - 1e-6))


def seconds_since_process_start() -> float | None:
    """Wall seconds since this process started (Linux /proc); None elsewhere."""
    import os

    try:
        ticks = os.sysconf("SC_CLK_TCK")
        with open("/proc/self/stat") as f:
            start = int(f.read().rsplit(")", 1)[1].split()[19]) / ticks
        with open("/proc/uptime") as f:
            uptime = float(f.read().split()[0])
        return uptime - start
    except (OSError, ValueError, IndexError):
        return None


class Checkpointer:
    """Observer writing ``restart.h5`` atomically, the checkpoint before it kept as ``restart.prev.h5``
    (``Simulation.save_checkpoint``)."""

    def __init__(self, out_dir: Path, schedule):
        self.path = Path(out_dir) / RESTART_NAME
        self.schedule = schedule
        self.last_time: float | None = None  # simulated time of the checkpoint this object last wrote [s]

    def __call__(self, sim) -> None:
        sim.save_checkpoint(self.path)
        self.last_time = sim.time


class Progress:
    """Reports simulated time, wall time, ETA and particle-steps/s every ``interval`` wall seconds, at INFO on
    the logger ``fluidem.progress`` (the command line shows it on stderr; ``--quiet`` hides it)."""

    def __init__(self, interval: float = 2.0, logger: logging.Logger | None = None):
        self.interval = interval
        self.logger = logger or logging.getLogger("fluidem.progress")
        self._last = None

    def maybe(self, sim, until: float, force: bool = False) -> None:
        now = _time.perf_counter()
        if self._last is None:
            self._last = now
        if not force and now - self._last < self.interval:
            return
        self._last = now
        wall = now - sim._run_wall_start
        # rate and ETA from the chunks after the first (whose wall time holds the kernels' compilation)
        warm = now - sim._warm_wall_start if sim._warm_wall_start is not None else 0.0
        done = sim.time - sim._warm_time_start if sim._warm_time_start is not None else 0.0
        left = until - sim.time
        if done > 0 and warm > 0:
            eta = f"ETA {max(warm / done * left, 0.0):7.1f} s"
            rate = f"{sim._warm_particle_steps / warm:.3g} particle-steps/s"
        else:
            eta, rate = "ETA       ?  ", "(first chunk)"
        self.logger.info(f"t = {sim.time:.4f} / {until:.4f} s   wall {wall:7.1f} s   {eta}   {rate}")


class Simulation:
    """A run of a case: owns the engine and clock; optional run directory ``out_dir``.

    ``resume=True`` continues from the newest usable checkpoint of ``out_dir``: ``restart.h5``, or
    ``restart.prev.h5`` with a warning when ``restart.h5`` is missing or damaged (``checkpoint_used``
    names the file); ``CheckpointError`` when neither can be used, with nothing in ``out_dir`` changed.
    ``until`` (default the case's ``time.end``) is then where the resumed run is to go, and a checkpoint
    already there is refused (CaseError) before any file of the run directory is touched.
    """

    def __init__(self, case: Case, out_dir: str | Path | None = None, resume: bool = False, progress: bool = False,
                 until: float | None = None):
        self.case = case
        self.out_dir = Path(out_dir) if out_dir is not None else None
        self.threads = _threads.set_threads(case.threads, sum(s.count for s in case.particles.species))
        self.checkpoint_used: Path | None = None  # the checkpoint a resumed run continued from
        # the step of out_dir/restart.h5 as this object last wrote or read it; None: no file, or a damaged one
        # (which the next checkpoint replaces without keeping it as restart.prev.h5)
        self._checkpoint_step: int | None = None
        scalars = None
        if resume:
            if self.out_dir is None:
                raise CaseError("resume=True needs the run directory out_dir")
            scalars = self._open_checkpoint()
            self._check_resume_target(scalars, until)
        else:
            self.engine = engine_for(case)
            self.engine.check_initial_overlaps()
            # the engine's total energy at t = 0 where it books it (hard spheres: Hoomans 1996 eq. 51's balance)
            self.energy0 = self.engine.bookkeeping().get("total_energy_J")
            self.gas = self._gas_coupling(self.engine)
        self.population = self._population()  # inlets and outlets; None without
        self.checks = RunChecks(case.checks, self.engine, self.gas)  # between chunks, before the observers
        self.observers: dict = {}
        self.progress = Progress(case.output.progress_interval) if progress else None
        self.status = "created"
        self.wall_time = 0.0
        # wall time of run() in the particle engine, in the rest of the coupled steps and in the observers [s],
        # summed over runs and resumes as wall_time is (``time_split``)
        self.particle_seconds = 0.0
        self.gas_seconds = 0.0
        self.output_seconds = 0.0
        self.particle_steps = 0
        # wall time and particle steps of run() after its first chunk (the kernels' compilation left out), summed
        # over runs and resumes: the summary's particle_steps_per_s
        self.warm_seconds = 0.0
        self.warm_particle_steps = 0
        self._warm_wall_start = self._warm_time_start = None
        self._warm_particle_steps = 0
        self._summary_extra: dict = {}
        self.startup_s: float | None = None  # process start → first compiled chunk done
        if self.out_dir is not None:
            self._prepare_run_directory(resume)
            self._default_observers()
        if scalars is not None:
            self._restore_run(scalars)
            # the outputs up to the checkpoint's step stay: its observers fired before the checkpoint was
            # written. At step 0, ``run`` fires every observer again, so nothing stays (t = 0 once). A row at
            # the checkpoint's step that its schedule does not fall on is the end-of-run output of a run
            # stopped there (``run``): it goes, so that a resumed run's outputs are an uninterrupted run's.
            for obs in self.observers.values():
                if hasattr(obs, "truncate_after"):
                    on_schedule = self.steps > 0 and obs.schedule.next_step(self.steps - 1, self.dt) == self.steps
                    obs.truncate_after(self.steps if on_schedule else self.steps - 1)

    def _gas_coupling(self, engine):
        """The two-way coupling of a case with a gas (gas steps of DT, DEM sub-steps within); None without."""
        if self.case.gas is None:
            return None
        if self.case.gas.grid.dimensions == 3:
            from .coupling.exchange3d_gpu import gas_coupling3d  # the GPU engine's particle side on the device

            return gas_coupling3d(self.case, engine)
        from .coupling.exchange import GasCoupling

        return GasCoupling(self.case, engine)

    def _population(self):
        """The case's inlets and outlets (``particles.population.Population``); None where it has neither."""
        if not (self.case.inlets or self.case.outlets):
            return None
        from .particles.population import Population

        if not self.engine.changes_population:
            raise CaseError(f"inlets/outlets: the {type(self.engine).__name__} cannot add or remove particles "
                            "during a run; use the soft-sphere engine on the CPU (device = 'cpu')")
        return Population(self.case, self.engine, self.gas.substeps if self.gas is not None else 1)

    def _change_population(self) -> None:
        """The inlets' and outlets' insertions and removals due now (``run``, between compiled chunks)."""
        pop = self.population
        if pop is None or self.steps < pop.next_step(self.dt):
            return
        if pop.apply(self.steps, self.dt, self.time):
            if self.gas is not None:
                self.gas._set_volumes()
            self.checks.start()  # the kinetic energy the next check compares with: that of the new particles

    def _open_checkpoint(self) -> dict:
        """Build the engine (and gas) from the newest usable checkpoint of ``out_dir``; its scalars.

        ``restart.h5`` first, then ``restart.prev.h5``; a checkpoint that cannot be read or does not fit
        the case (an array missing, another shape) is passed over with a warning. ``CheckpointError``
        naming each file and what is wrong with it when none is usable; nothing is written here."""
        problems: list[CheckpointError] = []
        for name in CHECKPOINT_NAMES:
            path = self.out_dir / name
            try:
                arrays, scalars, _ = load_restart(path)
                self._build_from_checkpoint(path, arrays, scalars)
            except CheckpointError as err:
                problems.append(err)
                continue
            self.checkpoint_used = path
            self._checkpoint_step = self.steps if name == RESTART_NAME else None
            if problems:
                log.warning("%s: %s; resuming from the previous checkpoint %s at t = %.6g s (step %d) instead. "
                            "Outputs after that time are dropped and computed again; the next checkpoint "
                            "replaces %s", problems[0].path, problems[0].reason, path, self.time, self.steps,
                            RESTART_NAME)
            return scalars
        if all(p.reason == "missing" for p in problems):
            raise CheckpointError(f"--resume {self.out_dir}: no checkpoint there ({' nor '.join(CHECKPOINT_NAMES)}); "
                                  f"a run writes its first one at t = 0, so this one stopped before it or is not a "
                                  f"run directory. Start the run again with `fluidem run` and a new --out",
                                  path=self.out_dir, reason="missing")
        lines = "; ".join(f"{p.path}: {p.reason}" for p in problems)
        raise CheckpointError(f"--resume {self.out_dir}: no usable checkpoint, so the run cannot be resumed "
                              f"({lines}). Nothing was changed in {self.out_dir}; start the run again with "
                              f"`fluidem run` and a new --out", path=self.out_dir,
                              reason="no usable checkpoint")

    def _build_from_checkpoint(self, path: Path, arrays: dict, scalars: dict) -> None:
        """Engine and gas coupling of the case, continued from a checkpoint's arrays and scalars; a
        ``CheckpointError`` when they do not fit the case (an array missing or of another shape)."""
        from dataclasses import fields

        def unusable(reason):
            return CheckpointError(f"checkpoint {path}: {reason}", path=path, reason=reason)

        required = [f"state/{f.name}" for f in fields(ParticleState) if f.name != "ids"]
        missing = [k for k in required if k not in arrays]
        if missing:
            raise unusable(f"lacks the array{'s' if len(missing) > 1 else ''} {', '.join(missing)}")
        try:
            state = ParticleState(**{k[len("state/"):]: v.copy() for k, v in arrays.items() if k.startswith("state/")})
            engine = engine_for(self.case, state=state)  # the restart file holds every particle
            # the engine's total energy at t = 0 where it books it (hard spheres: Hoomans 1996 eq. 51's balance);
            # a checkpoint's own value, where it has one, replaces it (``_restore_run``)
            energy0 = engine.bookkeeping().get("total_energy_J")
            gas = self._gas_coupling(engine)
            engine.restore(arrays, scalars)
            if gas is not None:
                gas.restore(arrays, scalars)
        except KeyError as err:
            key = err.args[0] if err.args else "?"
            what = "array" if "/" in str(key) else "value"
            no_gas = str(key).startswith("gas/") and not any(k.startswith("gas/") for k in arrays)
            hint = " (it holds no gas arrays: a checkpoint of a run without gas?)" if no_gas else ""
            raise unusable(f"lacks the {what} {key!r} this case needs{hint}") from None
        except (ValueError, TypeError, IndexError) as err:
            raise unusable(f"does not fit this case ({err})") from None
        self.engine, self.energy0, self.gas = engine, energy0, gas

    # ------------------------------------------------------------ clock
    @property
    def dt(self) -> float:
        return self.engine.dt

    @property
    def steps(self) -> int:
        """DEM steps taken since t = 0."""
        return self.engine.steps

    @property
    def time(self) -> float:
        return self.engine.time

    @property
    def state(self):
        return self.engine.state

    # ------------------------------------------------------------ run directory
    def _check_resume_target(self, scalars: dict, until: float | None) -> None:
        """CaseError if the checkpoint ``scalars`` are already at or past ``until`` (default ``time.end``):
        a resume there would take no step."""
        steps, dt = int(scalars.get("steps", 0)), float(scalars.get("dt", 0.0))
        target = self.case.time.end if until is None else until
        if dt > 0 and steps_to(target, dt) <= steps:
            asked = f"--until {target:g}" if until is not None else f"its time.end = {target:g} s"
            raise CaseError(f"--resume {self.out_dir}: the run is already at t = {steps * dt:.6g} s >= {asked}; "
                            f"give a later --until to continue it")

    def _prepare_run_directory(self, resume: bool) -> None:
        out = self.out_dir
        if resume:
            return
        if out.exists() and not out.is_dir():
            raise CaseError(f"output folder {str(out)!r} is a file")
        if out.exists() and any(out.iterdir()):
            raise CaseError(f"output folder {str(out)!r} exists and is not empty; choose another --out or --resume it")
        try:
            out.mkdir(parents=True, exist_ok=True)
            probe = out / ".write-test"
            probe.write_text("")
            probe.unlink()
        except OSError as err:
            raise CaseError(f"output folder {str(out)!r} is not writable: {err.strerror or err}") from None
        case = self.case.model_copy(deep=True)
        case.time.dt = self.engine.dt
        write_text_atomic(out / "case.toml", case.to_toml())

    def _default_observers(self) -> None:
        o = self.case.output
        end = self.case.time.end
        extra = {"contacts": lambda s: F.contact_numbers(s.engine).astype(np.int32)}
        # the contact force (particles, plane walls, wall shapes) in coupled runs and in runs with wall shapes;
        # hard spheres: collisions are impulses, no contact force to show
        if (self.gas is not None or len(getattr(self.engine, "shapes", ()))) and self.engine.contact_forces:
            extra["contact_force"] = lambda s: F.contact_force(s.engine)
        if self.gas is not None:
            extra["gas_force"] = lambda s: F.gas_force(s.engine)
        self.observers["snapshots"] = ParticleWriter(self.out_dir, EveryTime(o.snapshot_interval or end / 100),
                                                     extra_fields=extra)
        if self.gas is not None:  # gas fields at the particle snapshot times, written before the checkpoint
            self.observers["gas_fields"] = GasFieldWriter(self.out_dir, EveryTime(o.snapshot_interval or end / 100))
        probes = [lambda s: P.energies(s.engine), lambda s: s.engine.bookkeeping(), lambda s: P.contacts(s.engine),
                  F.bed_probes]
        if self.population is not None:  # particle count, each inlet's and outlet's running count and mass
            probes.append(lambda s: s.population.probes())
        if len(self.case.particles.species) > 1:  # per-species heights, segregation and mixing indices
            probes.append(M.mixing_probes)
        drum = repose_drum_of(self.case)
        if drum is not None:  # a rotating drum: the angle of repose of its free surface
            probes.append(lambda s: repose_probes(s, drum))
        self.observers["probes"] = ProbeWriter(self.out_dir, probes, EveryTime(o.probe_interval or end / 1000))
        if len(getattr(self.engine, "shapes", ())):  # wall shapes: their loads and poses, shapes.csv
            self.observers["shapes"] = ShapeWriter(self.out_dir, EveryTime(o.probe_interval or end / 1000))
            # and their triangles at the particle snapshot times, shapes.h5 + shapes.xdmf
            self.observers["shape_snapshots"] = ShapeSnapshotWriter(self.out_dir,
                                                                    EveryTime(o.snapshot_interval or end / 100))
        self.observers["checkpoint"] = Checkpointer(self.out_dir, EveryTime(o.checkpoint_interval or end / 10))

    # ------------------------------------------------------------ stepping
    def step(self) -> None:
        """Advance by one gas step DT (without gas: by one DEM step dt); no observers.

        Order of one gas step (``coupling.exchange.GasCoupling`` holds each stage)::

            map_to_grid            particles → voidage ε and solids velocity per cell    Sun 2007 eqs 34-35;
                                                                                         Hoomans 1996 eqs 49-50
            exchange_coefficients  the gas's interphase β from each particle's drag      Sun 2007 eqs 29, 33
                                   (or per cell), pressure voidage of each face
            advance_gas            pressure correction, gas t → t + DT                   Hoomans 1996 eqs 42-48
            to_particles           drag and −V_p ∇p on each particle                     Sun 2007 eqs 28-29;
                                                                                         Hoomans 1996 eqs 40-41
            particle_substeps      the DEM sub-steps dt = DT / substeps, one compiled    Sun 2007 eqs 15-26;
                                   call (hard spheres: force steps with collisions)      Hoomans 1996 §2.4

        ``run`` then calls each observer whose schedule fires; observers read the state, never write it.
        A run stopped within a gas step (``steps % substeps > 0``) finishes that gas step's sub-steps only.
        """
        n = 1 if self.gas is None else self.gas.substeps - self.engine.steps % self.gas.substeps
        self.advance(n)

    def advance(self, nsteps: int = 1) -> None:
        """Advance ``nsteps`` DEM steps (any number: gas steps at multiples of ``substeps``, in the order of
        ``step``); no observers."""
        eng, cpl = self.engine, self.gas
        if cpl is None:
            eng.advance(nsteps)
        else:
            left = nsteps
            while left > 0:
                phase = eng.steps % cpl.substeps
                if phase == 0:  # a gas step begins: stages 1-4 of ``step``
                    smap = cpl.map_to_grid()
                    coefficients = cpl.exchange_coefficients(smap)
                    cpl.advance_gas(smap, coefficients)
                    cpl.to_particles()
                left -= cpl.particle_substeps(min(left, cpl.substeps - phase))
        self.particle_steps += nsteps * eng.state.n

    def run(self, until: float | None = None) -> dict:
        """Advance to simulated time ``until`` (default the case's end), firing observers; returns the summary."""
        until = self.case.time.end if until is None else until
        if not math.isfinite(until):
            raise CaseError(f"until = {until!r}: must be a finite number of simulated seconds")
        target = steps_to(until, self.dt)
        self._run_wall_start = _time.perf_counter()
        self._run_time_start = self.time
        self._run_particle_steps = 0
        self._warm_wall_start = self._warm_time_start = None  # set when the first chunk has returned
        self._warm_particle_steps = 0
        warm_steps0 = self.warm_particle_steps
        wall0, warm0 = self.wall_time, self.warm_seconds
        nxt = {k: o.schedule.next_step(self.steps, self.dt) for k, o in self.observers.items()}
        fired = dict.fromkeys(self.observers, -1)  # the step each observer last wrote at
        if self.steps == 0:
            self._change_population()  # an inlet starting at t = 0 fills before the first output
            t0 = _time.perf_counter()
            for k, obs in self.observers.items():
                obs(self)
                fired[k] = 0
            self.output_seconds += _time.perf_counter() - t0
        chunk = 64
        self.checks.start()
        self.status = "running"
        self._stop_requested = False
        handlers = self._install_signal_handlers()
        try:
            while self.steps < target:
                if self._stop_requested:
                    raise KeyboardInterrupt
                self._change_population()
                events = [self.population.next_step(self.dt)] if self.population is not None else []
                stop = min([target, self.steps + chunk] + list(nxt.values()) + events)
                t0 = _time.perf_counter()
                engine0 = self.gas.engine_seconds if self.gas is not None else 0.0
                n = stop - self.steps
                notice = None
                if not _kernels_ready:  # a first chunk that takes long is compiling: say so, once
                    import threading

                    notice = threading.Timer(COMPILE_NOTICE_SECONDS, log.info, (
                        "compiling the kernels (the first run after an install or an update; later runs load "
                        "them from the cache in seconds)...",))
                    notice.daemon = True
                    notice.start()
                try:
                    self.advance(n)  # GasConvergenceError, CollisionCascadeError: handled below as a failure
                except ValueError as err:  # the gas exchange refused the particles (e.g. out of the grid)
                    if self.gas is None:
                        raise
                    raise self.checks.from_error(err) from None
                finally:
                    if notice is not None:
                        notice.cancel()
                _mark_kernels_ready()
                if self.startup_s is None:
                    self.startup_s = seconds_since_process_start()
                self._run_particle_steps += n * self.engine.state.n
                spent = _time.perf_counter() - t0
                if self.gas is not None:
                    engine = self.gas.engine_seconds - engine0
                    self.particle_seconds += engine
                    self.gas_seconds += spent - engine
                else:
                    self.particle_seconds += spent
                # aim for CHUNK_WALL_SECONDS per compiled call
                if spent > 0:
                    chunk = int(min(max(1, n * CHUNK_WALL_SECONDS / spent), 4 * chunk + 1))
                self.checks()  # RunFailure; no observer (the checkpoint) sees a state that fails
                self.wall_time = wall0 + _time.perf_counter() - self._run_wall_start
                t0 = _time.perf_counter()
                for k, obs in self.observers.items():
                    if self.steps >= nxt[k]:
                        obs(self)
                        fired[k] = self.steps
                        nxt[k] = obs.schedule.next_step(self.steps, self.dt)
                self.output_seconds += _time.perf_counter() - t0
                now = _time.perf_counter()
                if self._warm_wall_start is None:  # the first chunk is done: rates count from here
                    self._warm_wall_start, self._warm_time_start = now, self.time
                else:
                    self._warm_particle_steps += n * self.engine.state.n
                    self.warm_seconds = warm0 + now - self._warm_wall_start
                    self.warm_particle_steps = warm_steps0 + self._warm_particle_steps
                if self.progress is not None:
                    self.progress.maybe(self, until)
        except KeyboardInterrupt:
            self.status = "interrupted"
            self._finish(interrupted=True)
            raise
        except (RunFailure, GasConvergenceError, CollisionCascadeError) as err:
            failure = self.checks.from_error(err) if not isinstance(err, RunFailure) else err
            self.wall_time = wall0 + _time.perf_counter() - self._run_wall_start
            self._fail(failure)
            raise failure from None
        except FloatingPointError as err:
            self.status = f"error: {err}"
            self._finish(interrupted=True)
            raise
        except OSError as err:
            # e.g. a full disk while writing output: the last checkpoint was replaced atomically, so it is
            # intact; try to record the state, but never hide the original error
            self.status = f"error: {err}"
            try:
                # keep the last good checkpoint: resuming from it rewrites the outputs that failed
                self._finish(interrupted=True, checkpoint=False)
            except OSError:
                pass
            raise
        finally:
            self._restore_signal_handlers(handlers)
        # the end time's probe row, snapshot and gas fields, where the schedule did not fall on it (the
        # checkpoint is written by _finish)
        t0 = _time.perf_counter()
        for k, obs in self.observers.items():
            if k != "checkpoint" and fired[k] != self.steps:
                obs(self)
        self.output_seconds += _time.perf_counter() - t0
        self.wall_time = wall0 + _time.perf_counter() - self._run_wall_start
        if self.progress is not None:
            self.progress.maybe(self, until, force=True)
        self.status = "completed" if self.time >= self.case.time.end - 0.5 * self.dt else "stopped"
        return self._finish()

    def _install_signal_handlers(self):
        """Ctrl-C / SIGTERM set a flag; the loop stops between compiled chunks with a checkpoint."""
        import signal
        import threading

        if threading.current_thread() is not threading.main_thread():
            return None

        def request_stop(signum, frame):
            self._stop_requested = True

        old = {}
        for sig in (signal.SIGINT, signal.SIGTERM):
            old[sig] = signal.signal(sig, request_stop)
        return old

    @staticmethod
    def _restore_signal_handlers(old) -> None:
        import signal

        for sig, h in (old or {}).items():
            signal.signal(sig, h)

    def _fail(self, failure: RunFailure) -> None:
        """End a run that blew up: status ``failed``, the failure in summary.json, the outputs written so far
        kept and the last good checkpoint left as it is (the broken state is never written to it)."""
        self.status = "failed"
        ck = self.observers.get("checkpoint")
        if ck is not None and ck.path.exists():
            failure.checkpoint = (ck.path, ck.last_time if ck.last_time is not None else self._run_time_start)
        self._summary_extra["failure"] = failure.record()
        try:
            with np.errstate(all="ignore"):  # figures of a broken state: NaN and inf become null
                self._finish(interrupted=True, checkpoint=False)
        except OSError:  # e.g. a full disk: the failure itself is what the caller must see
            pass
        except Exception:  # noqa: BLE001 - a figure the broken state cannot give; keep what says why it failed
            if self.out_dir is not None:
                minimal = {"case": self.case.name, "status": self.status, "sim_time_s": self.time,
                           "wall_time_s": self.wall_time, "n_particles": self.engine.state.n, "steps": self.steps,
                           "dt_s": self.dt, **self._summary_extra}
                write_text_atomic(self.out_dir / "summary.json", summary_json(finite(minimal)))

    def _finish(self, interrupted: bool = False, checkpoint: bool = True) -> dict:
        if checkpoint and self.out_dir is not None and "checkpoint" in self.observers:
            self.save_checkpoint(self.out_dir / RESTART_NAME)
        for obs in self.observers.values():
            if hasattr(obs, "finalize"):
                obs.finalize(self)
        summary = self.summary()
        if self.out_dir is not None:
            write_text_atomic(self.out_dir / "summary.json", summary_json(summary))
        return summary

    # ------------------------------------------------------------ results
    def summary(self) -> dict:
        """The run's figures (``summary.json``); a quantity that is undefined (NaN, e.g. the multicontact
        ratio of a bed with no contacts) is None (JSON null)."""
        return finite(self._summary())

    def _summary(self) -> dict:
        eng = self.engine
        c = P.contacts(eng)
        e = P.energies(eng)
        out = {
            "case": self.case.name,
            "status": self.status,
            "sim_time_s": self.time,
            "wall_time_s": self.wall_time,
            "n_particles": eng.state.n,
            # after the first chunk of each run (the compilation): the engine's own speed
            "particle_steps_per_s": (self.warm_particle_steps / self.warm_seconds if self.warm_seconds > 0 else
                                     self.particle_steps / self.wall_time if self.wall_time > 0 else None),
            "steps": self.steps,
            "dt_s": self.dt,
            "contact_time_s": getattr(eng, "contact_time", None),
            "neighbour_rebuilds": eng.rebuilds,
            "threads": self.threads,
            "startup_s": self.startup_s,
            **self.time_split(),
            "check_time_s": self.checks.seconds,  # the health checks of this process's runs (not over resumes)
            "coordination_number": c["coordination"],
            "max_overlap_rel": c["max_overlap_rel"],
            "kinetic_energy_J": e["kinetic_J"],
            "mean_bed_height_m": self.mean_height(),
            "bed_surface_height_m": self.bed_surface_height(),
        }
        if self.case.particles.dimensions == 2:
            out["packing_fraction"] = P.surface_packing_fraction(eng)
        out.update(eng.summary_entries(self.wall_time, out["particle_time_s"], self.energy0, self.gas is not None))
        if self.gas is not None:
            out.update(gas_dt_s=self.gas.gas_dt, gas_steps=self.gas.gas_steps, dem_substeps=self.gas.substeps,
                       gas_courant_max=self.gas.courant_max)
            out["multicontact_ratio"] = F.multicontact_ratio(F.contact_numbers(eng))
            gd = self.gas.grid
            if gd.dimensions == 3:  # along gravity, the pressure averaged over each layer of cells
                axis = F.up_axis(gd, eng.gravity)
                out["pressure_drop_bed_Pa"] = F.pressure_drop(gd, self.gas.state.p, gd.size[axis], axis)
            else:
                out["pressure_drop_bed_Pa"] = F.pressure_drop(gd, self.gas.state.p, gd.y_centres[-1] + 0.5 * gd.dy)
            if eng.contact_forces and gd.dimensions == 2:  # Sun 2007 Figs 7/12: cell contact force over gas force
                out["contact_drag_ratio_max"] = F.largest_force_ratio(self.gas.grid, eng)  # NaN → null below
            if self.out_dir is not None:
                out.update(F.time_averages(self.out_dir / "probes.csv", self.time))
        if self.population is not None:
            out.update(self.population.summary())
        drum = repose_drum_of(self.case)
        if drum is not None:
            out.update(repose_summary(self, drum))
        out.update(self._summary_extra)
        return out

    def time_split(self) -> dict:
        """Where the wall time of ``run`` went, summed over its calls and resumes [s]: ``particle_time_s`` in the
        particle engine's compiled calls, ``gas_time_s`` in the rest of the coupled steps (voidage map,
        drag, gas solve), ``output_time_s`` in the observers; the rest of ``wall_time_s`` is the loop's own."""
        return {"particle_time_s": self.particle_seconds, "gas_time_s": self.gas_seconds,
                "output_time_s": self.output_seconds}

    def heights(self) -> np.ndarray | None:
        """Centre heights above the floor [m], (N,): along −g from the wall box's lower corner (else the origin);
        None without gravity."""
        g = self.engine.gravity
        gn = np.linalg.norm(g)
        if gn == 0:
            return None
        up = -g / gn
        floor = float(self.engine.walls.box_lower @ up) if self.engine.walls.box_lower is not None else 0.0
        return self.engine.state.position @ up - floor

    def mean_height(self) -> float:
        """Mean centre height above the floor [m] (``mean_bed_height_m``; Sun 2007 Fig. 9): not a surface."""
        h = self.heights()
        return float("nan") if h is None or h.size == 0 else float(np.mean(h))

    def bed_surface_height(self) -> float:
        """Height of the bed surface above the floor [m] (``analysis.fluidised.bed_surface_height``)."""
        h = self.heights()
        if h is None:
            return float("nan")
        return F.bed_surface_height(h, self.engine.state.radius, self.case.particles.dimensions == 2)

    # ------------------------------------------------------------ checkpoints
    def save_checkpoint(self, path: Path) -> None:
        """Write a checkpoint to ``path`` atomically. The run directory's ``restart.h5`` keeps the checkpoint
        before it as ``restart.prev.h5`` when this one is of a later step (one of the same step, as at the
        end of a run after the periodic one, replaces it alone)."""
        path = Path(path)
        previous = None
        own = self.out_dir is not None and path == self.out_dir / RESTART_NAME
        if own and self._checkpoint_step is not None and self._checkpoint_step < self.steps:
            previous = self.out_dir / PREVIOUS_RESTART_NAME
        scalars = dict(self.engine.checkpoint_scalars(), wall_time=self.wall_time, particle_steps=self.particle_steps,
                       warm_seconds=self.warm_seconds, warm_particle_steps=self.warm_particle_steps,
                       particle_seconds=self.particle_seconds, gas_seconds=self.gas_seconds,
                       output_seconds=self.output_seconds)
        if self.energy0 is not None:
            scalars["energy0"] = self.energy0
        if self.population is not None:
            scalars.update(self.population.checkpoint_scalars())
        arrays = self.engine.checkpoint_arrays()
        if self.gas is not None:
            arrays = {**arrays, **self.gas.checkpoint_arrays()}
            scalars.update(self.gas.checkpoint_scalars())
        save_restart(path, arrays, scalars, self.case.to_toml(), previous=previous)
        if own:
            self._checkpoint_step = self.steps

    def load_checkpoint(self, path: Path) -> None:
        """Continue from the checkpoint ``path`` (``CheckpointError`` when it cannot be read)."""
        arrays, scalars, _ = load_restart(path)
        self._restore(arrays, scalars)

    def _restore(self, arrays, scalars) -> None:
        self.engine.restore(arrays, scalars)
        if self.gas is not None:
            self.gas.restore(arrays, scalars)
        self._restore_run(scalars)

    def _restore_run(self, scalars) -> None:
        """The run's own figures from a checkpoint's scalars (wall and split times, particle steps, E_0)."""
        self.wall_time = float(scalars.get("wall_time", 0.0))
        for k in ("particle_seconds", "gas_seconds", "output_seconds"):  # absent from checkpoints before 2026-11-26
            setattr(self, k, float(scalars.get(k, 0.0)))
        self.particle_steps = int(scalars.get("particle_steps", 0))
        self.warm_seconds = float(scalars.get("warm_seconds", 0.0))  # absent from checkpoints before 2026-11-27
        self.warm_particle_steps = int(scalars.get("warm_particle_steps", 0))
        if "energy0" in scalars:
            self.energy0 = float(scalars["energy0"])
        if self.population is not None:
            self.population.restore(scalars)

    @classmethod
    def resume(cls, out_dir: str | Path, progress: bool = False, threads: int | None = None,
               until: float | None = None, device: str | None = None) -> "Simulation":
        """Continue the run in ``out_dir`` from its last checkpoint (optionally with another thread count, or on
        another device: a checkpoint of either soft-sphere engine continues on the other) to ``until``
        (default the case's ``time.end``; CaseError if the checkpoint is already there)."""
        out_dir = Path(out_dir)
        if not (out_dir / "case.toml").exists():
            raise CaseError(f"--resume {out_dir}: not a run directory (no case.toml)")
        case = read_run_case(out_dir / "case.toml")
        if threads is not None:
            case.threads = threads
        if device is not None:
            case.device = device
        return cls(case, out_dir=out_dir, resume=True, progress=progress, until=until)


def read_run_case(path: Path) -> Case:
    """The case of a run directory from its ``case.toml``; ``CheckpointError`` naming the file and what is
    wrong with it (not text, not TOML, not a valid case) where it cannot be used."""
    import tomllib

    path = Path(path)
    note = (f"the run cannot be resumed without it (each checkpoint keeps a copy of the case in its "
            f"attribute case_toml, e.g. {path.with_name(RESTART_NAME)})")

    def unusable(reason):
        sep = "\n" if "\n" in reason else "; "  # a case's list of problems: the note on a line of its own
        return CheckpointError(f"{path}: {reason}{sep}{note}", path=path, reason=reason)

    try:
        text = path.read_bytes().decode("utf-8")
    except UnicodeDecodeError as err:
        raise unusable(f"not a text file (byte 0x{err.object[err.start]:02x} at position {err.start} "
                       f"is not UTF-8)") from None
    except OSError as err:
        raise unusable(f"cannot be read ({err.strerror or err})") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise unusable(f"not valid TOML ({err})") from None
    try:
        return validate_case(data)
    except CaseError as err:
        raise unusable(f"not a valid case: {err}") from None
