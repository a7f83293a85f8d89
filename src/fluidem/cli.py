"""The ``fluidem`` command: run, cases, bench (and plot, animate, compare, report from ``cli_plot``;
segregation from ``cli_segregation``).

Bad input exits with status 2 and a message naming the key and value; nothing is
written. Ctrl-C stops a run at the next chunk with a checkpoint (exit 130); resume
with ``fluidem run --resume DIR``.

A command's result goes to stdout (the summary JSON of ``run``, the list of ``cases``, the
table of ``bench``); diagnostics go through the ``fluidem`` logger to stderr (``_log``): the
start line and progress lines of a run at INFO, warnings as ``WARNING: ...``, errors as
``fluidem: error: ...``. ``--quiet`` (before or after the subcommand) keeps warnings and
errors only, ``--verbose`` adds DEBUG records.
"""
from __future__ import annotations

import argparse
import logging
import math
import sys
import time
from pathlib import Path

EXIT_BAD_INPUT = 2

log = logging.getLogger(__name__)


def _parse_sets(items: list[str]) -> dict:
    from .case import parse_value
    from .errors import CaseError

    out = {}
    for item in items or []:
        if "=" not in item:
            raise CaseError(f"--set {item!r}: expected key=value, e.g. --set particles.contact.restitution=1.0")
        k, v = item.split("=", 1)
        out[k.strip()] = parse_value(v.strip())
    return out


def cmd_run(args) -> int:
    from .case import load_case
    from .io.summary import summary_json
    from .errors import CaseError
    from .simulation import Simulation

    if args.until is not None and not (math.isfinite(args.until) and args.until > 0):
        raise CaseError(f"--until {args.until!r} (the time.end to reach): must be a finite positive number of "
                        "simulated seconds")
    if args.threads is not None and args.threads < 1:
        raise CaseError(f"--threads {args.threads}: must be at least 1")
    if args.resume:
        if args.case or args.set:
            raise CaseError("--resume DIR continues a run as it was set up; give no CASE or --set with it")
        sim = Simulation.resume(args.resume, progress=not args.quiet, threads=args.threads, until=args.until,
                                device=args.device)
        out = Path(args.resume)
    else:
        if not args.case:
            raise CaseError("fluidem run needs a CASE (a built-in name, see `fluidem cases`, or a TOML path)")
        overrides = _parse_sets(args.set)
        if args.until is not None:
            overrides["time.end"] = args.until
        if args.threads is not None:
            overrides["threads"] = args.threads
        if args.device is not None:
            overrides["device"] = args.device
        case = load_case(args.case, overrides)
        out = Path(args.out) if args.out else Path("runs") / f"{case.name}-{time.strftime('%Y%m%d-%H%M%S')}"
        sim = Simulation(case, out_dir=out, progress=not args.quiet)
    until = args.until if args.until is not None else sim.case.time.end
    log.info("fluidem: %s: %d particles, dt = %.3g s, to t = %g s, %d thread(s) -> %s",
             sim.case.name, sim.engine.state.n, sim.dt, until, sim.threads, out)
    try:
        summary = sim.run(until=until)
    except KeyboardInterrupt:
        log.warning("interrupted at t = %.6g s; checkpoint written. Continue with: fluidem run --resume %s",
                    sim.time, out)
        return 130
    except FloatingPointError as err:  # a blow-up (checks.RunFailure): summary.json says why, the checkpoint is kept
        log.error("run failed: %s", err)
        return 1
    except OSError as err:
        log.error("run stopped at t = %.6g s: %s. The last checkpoint in %s is intact; "
                  "free the space or fix the folder, then: fluidem run --resume %s", sim.time, err, out, out)
        return 1
    print(summary_json(summary), end="")
    sys.stdout.flush()
    log.info("%s", _next_steps(out, summary))
    return 0


def _next_steps(out: Path, summary: dict) -> str:
    """The closing lines of a run on stderr: where its outputs are and what to do with them."""
    files = [name for name in ("summary.json", "probes.csv", "particles.xdmf", "gas.xdmf", "restart.h5")
             if (out / name).exists()]
    wall = summary.get("wall_time_s")
    lines = [f"{summary.get('status', 'done')}: t = {summary.get('sim_time_s', 0.0):.6g} s"
             + (f" in {wall:.1f} s of wall time" if wall is not None else "") + f"; outputs in {out}/: "
             + ", ".join(files) + " (the .xdmf files open in ParaView, probes.csv in pandas)",
             f"  fluidem plot {out}      # figures of the run",
             f"  fluidem report {out}    # one HTML page with the figures and the summary"]
    if summary.get("status") == "stopped":
        lines.append(f"  fluidem run --resume {out}    # continue to the case's time.end")
    return "\n".join(lines)


def cmd_cases(args) -> int:
    from .case import builtin_cases, load_case
    from .estimate import human, wall_time_estimate

    for name, path in sorted(builtin_cases().items()):
        case = load_case(path)
        n = sum(s.count for s in case.particles.species)
        print(f"{name:24s} {case.description}")
        print(f"{'':24s} {n} particles, {case.time.end:g} s simulated, {human(wall_time_estimate(case))} on one core "
              f"(rough)")
    return 0


def cmd_bench(args) -> int:
    from .bench import run_bench
    from .errors import CaseError

    if not args.coupled_until > 0:
        raise CaseError(f"bench --coupled-until = {args.coupled_until!r}: must be a positive number of simulated seconds")
    if not args.hard_until > 0:
        raise CaseError(f"bench --hard-until = {args.hard_until!r}: must be a positive number of simulated seconds")
    if not args.hopper_until > 0:
        raise CaseError(f"bench --hopper-until = {args.hopper_until!r}: must be a positive number of simulated seconds")
    run_bench(sizes=args.sizes, threads=args.threads, steps=args.steps, as_json=args.json, gas=not args.no_gas,
              coupled=not args.no_coupled, coupled_until=args.coupled_until, hard_sphere=not args.no_hard_sphere,
              hard_until=args.hard_until, device=args.device, hopper=not args.no_hopper,
              hopper_until=args.hopper_until)
    return 0


def _add_verbosity(parser: argparse.ArgumentParser, defaults: bool) -> None:
    """``-q/--quiet`` and ``-v/--verbose`` on ``parser``. The main parser holds the defaults (False);
    each subcommand's copies default to nothing (``SUPPRESS``), so that a flag given before the
    subcommand is not reset by the subcommand's parser, and one given after it still counts."""
    default = False if defaults else argparse.SUPPRESS
    group = parser.add_mutually_exclusive_group()
    group.add_argument("-q", "--quiet", action="store_true", default=default,
                       help="warnings and errors only: no start line, progress lines or notes")
    group.add_argument("-v", "--verbose", action="store_true", default=default,
                       help="debug messages too")


def build_parser() -> argparse.ArgumentParser:
    from . import __version__

    p = argparse.ArgumentParser(prog="fluidem", description="Discrete-particle simulation of gas–solid flows.")
    p.add_argument("--version", action="version", version=f"%(prog)s {__version__}",
                   help="print the version and exit")
    _add_verbosity(p, defaults=True)
    sub = p.add_subparsers(dest="command")

    r = sub.add_parser("run", help="run a case (built-in name or TOML path)",
                       description="Run a case. Output goes to a run directory: case.toml, summary.json, probes.csv, "
                                   "particles.h5 + particles.xdmf (ParaView), restart.h5 + restart.prev.h5 (the newest "
                                   "checkpoint and the one before).")
    r.add_argument("case", nargs="?", help="built-in case name (see `fluidem cases`) or a TOML file")
    r.add_argument("--until", type=float, help="simulated time to reach [s] (default: the case's time.end)")
    r.add_argument("--out", help="run directory (default runs/<case>-<timestamp>); must be new or empty")
    r.add_argument("--set", action="append", metavar="KEY=VALUE",
                   help="override a case key by dotted name, e.g. --set particles.contact.restitution=1.0")
    r.add_argument("--threads", type=int, help="compute threads (default: one per 1200 particles, at most all cores)")
    r.add_argument("--device", choices=("cpu", "gpu", "auto"),
                   help="where the particle step runs (the case's device key; with --resume: continue there)")
    r.add_argument("--resume", metavar="DIR",
                   help="continue a stopped run from DIR/restart.h5 (DIR/restart.prev.h5 where that is damaged)")
    r.set_defaults(func=cmd_run)

    c = sub.add_parser("cases", help="list built-in cases: what each is, its particles, simulated length and a "
                                     "rough wall time")
    c.set_defaults(func=cmd_cases)

    b = sub.add_parser("bench", help="throughput on standard problems (particle-steps per second)")
    b.add_argument("--sizes", default=None,
                   help="dense-bed sizes, comma separated (default 10000,100000; with --device gpu 1e5,1e6,1e7)")
    b.add_argument("--device", choices=("cpu", "gpu"), default="cpu",
                   help="gpu: the dense-bed rows on the GPU engine only (default cpu: every problem on the CPU)")
    b.add_argument("--threads", default="1,2", help="thread counts, comma separated")
    b.add_argument("--steps", type=int, default=0, help="timed steps per problem (default: about 5 s of work)")
    b.add_argument("--json", metavar="FILE", help="also write the results as JSON")
    b.add_argument("--no-gas", action="store_true", help="skip the gas-step timings")
    b.add_argument("--no-coupled", action="store_true", help="skip the coupled tsuji-jet-background timing")
    b.add_argument("--coupled-until", type=float, default=0.25, metavar="T",
                   help="simulated seconds of the coupled tsuji-jet-background timing (default 0.25)")
    b.add_argument("--no-hard-sphere", action="store_true", help="skip the hard-sphere hoomans-orifice timing")
    b.add_argument("--hard-until", type=float, default=0.1, metavar="T",
                   help="simulated seconds of the hoomans-orifice jet timed after its 0.5 s start-up (default 0.1)")
    b.add_argument("--no-hopper", action="store_true", help="skip the discharging hopper-3d timing")
    b.add_argument("--hopper-until", type=float, default=0.05, metavar="T",
                   help="simulated seconds of the hopper-3d discharge timed after its 0.25 s start (default 0.05)")
    b.set_defaults(func=cmd_bench)

    from .cli_plot import add_commands
    from .cli_sweep import add_command as add_sweep

    add_sweep(sub)
    add_commands(sub)
    from .cli_segregation import add_command as add_segregation

    add_segregation(sub)
    for command in sub.choices.values():
        _add_verbosity(command, defaults=False)
    return p


def _versions() -> str:
    import platform

    import numba
    import numpy

    from . import __version__

    return f"fluidem {__version__}, Python {platform.python_version()}, NumPy {numpy.__version__}, Numba {numba.__version__}"


def main(argv: list[str] | None = None) -> int:
    """Run the ``fluidem`` command with ``argv`` (default ``sys.argv[1:]``); the exit status.

    Log records of the ``fluidem`` logger are shown on stderr while the command runs, at the
    level the flags choose (``_log.level_for``); usage errors and ``--version`` exit through
    argparse (``SystemExit``)."""
    from ._log import command_logging, level_for
    from .errors import CaseError

    parser = build_parser()
    args = parser.parse_args(argv)
    if args.quiet and args.verbose:
        parser.error("--quiet and --verbose exclude each other")
    if not getattr(args, "func", None):
        parser.print_help()
        return EXIT_BAD_INPUT
    with command_logging(level_for(args.quiet, args.verbose)):
        if log.isEnabledFor(logging.DEBUG):
            log.debug("%s; command: %s", _versions(), " ".join(sys.argv[1:] if argv is None else map(str, argv)))
        try:
            return args.func(args)
        except CaseError as err:
            log.error("%s", err)
            return EXIT_BAD_INPUT
        except BrokenPipeError:  # the reader of stdout went away (``fluidem cases | head``): stop quietly
            import os

            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
            return 0


if __name__ == "__main__":
    sys.exit(main())
