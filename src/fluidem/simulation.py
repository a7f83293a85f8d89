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
from .analysis import probes as P
from .case import Case, validate_case
from .checks import RunChecks, RunFailure
from .errors import CaseError
from .gas.solver import GasConvergenceError
from .io.atomic import write_text_atomic
from .io.gas_fields import GasFieldWriter
from .io.probes_csv import ProbeWriter
from .io.restart import RESTART_NAME, load_restart, save_restart
from .io.summary import finite, summary_json
from .io.snapshots import ParticleWriter
from .particles import engine_for
from .particles.hardsphere import CollisionCascadeError
from .schedule import EveryTime
from .state import ParticleState

CHUNK_WALL_SECONDS = 0.25  # a compiled chunk should return to Python about this often (Ctrl-C, progress)


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
    """Observer writing ``restart.h5`` atomically."""

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
        done = sim.time - sim._run_time_start
        left = until - sim.time
        eta = wall / done * left if done > 0 else math.nan
        rate = sim._run_particle_steps / wall if wall > 0 else 0.0
        self.logger.info(f"t = {sim.time:.4f} / {until:.4f} s   wall {wall:7.1f} s   ETA {eta:7.1f} s   "
                         f"{rate:.3g} particle-steps/s")


class Simulation:
    """A run of a case: owns the engine and clock; optional run directory ``out_dir``.

    ``resume=True`` continues from ``out_dir/restart.h5``.
    """

    def __init__(self, case: Case, out_dir: str | Path | None = None, resume: bool = False, progress: bool = False):
        self.case = case
        self.out_dir = Path(out_dir) if out_dir is not None else None
        self.threads = _threads.set_threads(case.threads, sum(s.count for s in case.particles.species))
        restart = None
        if resume:
            if self.out_dir is None or not (self.out_dir / RESTART_NAME).exists():
                raise CaseError(f"--resume {self.out_dir}: no {RESTART_NAME} there")
            restart = load_restart(self.out_dir / RESTART_NAME)
            state = ParticleState(**{k[len("state/"):]: v.copy() for k, v in restart[0].items() if k.startswith("state/")})
            self.engine = engine_for(case, state=state)  # the restart file holds every particle
        else:
            self.engine = engine_for(case)
            self.engine.check_initial_overlaps()
        # the engine's total energy at t = 0 where it books it (hard spheres: Hoomans 1996 eq. 51's balance)
        self.energy0 = self.engine.bookkeeping().get("total_energy_J")
        self.gas = None
        if case.gas is not None:  # two-way coupled run: gas steps of DT, DEM sub-steps within
            from .coupling.exchange import GasCoupling

            self.gas = GasCoupling(case, self.engine)
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
        self._summary_extra: dict = {}
        self.startup_s: float | None = None  # process start → first compiled chunk done
        if self.out_dir is not None:
            self._prepare_run_directory(resume)
            self._default_observers()
            if restart is not None:
                self._restore(*restart[:2])
                for obs in self.observers.values():
                    if hasattr(obs, "truncate_after"):
                        obs.truncate_after(self.steps)

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
        if self.gas is not None:
            if self.engine.contact_forces:  # hard spheres: collisions are impulses, no contact force to show
                extra["contact_force"] = lambda s: F.contact_force(s.engine)
            extra["gas_force"] = lambda s: F.gas_force(s.engine)
        self.observers["snapshots"] = ParticleWriter(self.out_dir, EveryTime(o.snapshot_interval or end / 100),
                                                     extra_fields=extra)
        if self.gas is not None:  # gas fields at the particle snapshot times, written before the checkpoint
            self.observers["gas_fields"] = GasFieldWriter(self.out_dir, EveryTime(o.snapshot_interval or end / 100))
        probes = [lambda s: P.energies(s.engine), lambda s: s.engine.bookkeeping(), lambda s: P.contacts(s.engine),
                  F.bed_probes]
        self.observers["probes"] = ProbeWriter(self.out_dir, probes, EveryTime(o.probe_interval or end / 1000))
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
        target = int(round(until / self.dt))
        self._run_wall_start = _time.perf_counter()
        self._run_time_start = self.time
        self._run_particle_steps = 0
        wall0 = self.wall_time
        nxt = {k: o.schedule.next_step(self.steps, self.dt) for k, o in self.observers.items()}
        if self.steps == 0:
            t0 = _time.perf_counter()
            for obs in self.observers.values():
                obs(self)
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
                stop = min([target, self.steps + chunk] + list(nxt.values()))
                t0 = _time.perf_counter()
                engine0 = self.gas.engine_seconds if self.gas is not None else 0.0
                n = stop - self.steps
                try:
                    self.advance(n)  # GasConvergenceError, CollisionCascadeError: handled below as a failure
                except ValueError as err:  # the gas exchange refused the particles (e.g. out of the grid)
                    if self.gas is None:
                        raise
                    raise self.checks.from_error(err) from None
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
                        nxt[k] = obs.schedule.next_step(self.steps, self.dt)
                self.output_seconds += _time.perf_counter() - t0
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
            "particle_steps_per_s": self.particle_steps / self.wall_time if self.wall_time > 0 else None,
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
        }
        if self.case.particles.dimensions == 2:
            out["packing_fraction"] = P.surface_packing_fraction(eng)
        out.update(eng.summary_entries(self.wall_time, out["particle_time_s"], self.energy0, self.gas is not None))
        if self.gas is not None:
            out.update(gas_dt_s=self.gas.gas_dt, gas_steps=self.gas.gas_steps, dem_substeps=self.gas.substeps,
                       gas_courant_max=self.gas.courant_max)
            out["multicontact_ratio"] = F.multicontact_ratio(F.contact_numbers(eng))
            out["pressure_drop_bed_Pa"] = F.pressure_drop(self.gas.grid, self.gas.state.p,
                                                          self.gas.grid.y_centres[-1] + 0.5 * self.gas.grid.dy)
            if eng.contact_forces:  # Sun 2007 Figs 7/12: cell contact force over gas force, end state
                out["contact_drag_ratio_max"] = F.largest_force_ratio(self.gas.grid, eng)  # NaN → null below
            if self.out_dir is not None:
                out.update(F.time_averages(self.out_dir / "probes.csv", self.time))
        out.update(self._summary_extra)
        return out

    def time_split(self) -> dict:
        """Where the wall time of ``run`` went, summed over its calls and resumes [s]: ``particle_time_s`` in the
        particle engine's compiled calls, ``gas_time_s`` in the rest of the coupled steps (voidage map,
        drag, gas solve), ``output_time_s`` in the observers; the rest of ``wall_time_s`` is the loop's own."""
        return {"particle_time_s": self.particle_seconds, "gas_time_s": self.gas_seconds,
                "output_time_s": self.output_seconds}

    def mean_height(self) -> float:
        g = self.engine.gravity
        gn = np.linalg.norm(g)
        if gn == 0:
            return float("nan")
        up = -g / gn
        st = self.engine.state
        floor = float(self.engine.walls.box_lower @ up) if self.engine.walls.box_lower is not None else 0.0
        return float(np.mean(st.position @ up) - floor)

    # ------------------------------------------------------------ checkpoints
    def save_checkpoint(self, path: Path) -> None:
        scalars = dict(self.engine.checkpoint_scalars(), wall_time=self.wall_time, particle_steps=self.particle_steps,
                       particle_seconds=self.particle_seconds, gas_seconds=self.gas_seconds,
                       output_seconds=self.output_seconds)
        if self.energy0 is not None:
            scalars["energy0"] = self.energy0
        arrays = self.engine.checkpoint_arrays()
        if self.gas is not None:
            arrays = {**arrays, **self.gas.checkpoint_arrays()}
            scalars.update(self.gas.checkpoint_scalars())
        save_restart(path, arrays, scalars, self.case.to_toml())

    def load_checkpoint(self, path: Path) -> None:
        arrays, scalars, _ = load_restart(path)
        self._restore(arrays, scalars)

    def _restore(self, arrays, scalars) -> None:
        self.engine.restore(arrays, scalars)
        if self.gas is not None:
            self.gas.restore(arrays, scalars)
        self.wall_time = float(scalars.get("wall_time", 0.0))
        for k in ("particle_seconds", "gas_seconds", "output_seconds"):  # absent from checkpoints before 2026-11-26
            setattr(self, k, float(scalars.get(k, 0.0)))
        self.particle_steps = int(scalars.get("particle_steps", 0))
        if "energy0" in scalars:
            self.energy0 = float(scalars["energy0"])

    @classmethod
    def resume(cls, out_dir: str | Path, progress: bool = False, threads: int | None = None) -> "Simulation":
        """Continue the run in ``out_dir`` from its last checkpoint (optionally with another thread count)."""
        import tomllib

        out_dir = Path(out_dir)
        if not (out_dir / "case.toml").exists():
            raise CaseError(f"--resume {out_dir}: not a run directory (no case.toml)")
        case = validate_case(tomllib.loads((out_dir / "case.toml").read_text()))
        if threads is not None:
            case.threads = threads
        return cls(case, out_dir=out_dir, resume=True, progress=progress)
