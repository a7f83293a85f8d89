"""The ``fluidem`` command: run, cases, bench.

Bad input exits with status 2 and a message naming the key and value; nothing is
written. Ctrl-C stops a run at the next chunk with a checkpoint (exit 130); resume
with ``fluidem run --resume DIR``.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

EXIT_BAD_INPUT = 2


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
    from .simulation import Simulation, summary_json

    if args.resume:
        if args.case or args.set:
            from .errors import CaseError

            raise CaseError("--resume DIR continues a run as it was set up; give no CASE or --set with it")
        sim = Simulation.resume(args.resume, progress=not args.quiet, threads=args.threads)
        out = Path(args.resume)
    else:
        if not args.case:
            from .errors import CaseError

            raise CaseError("fluidem run needs a CASE (a built-in name, see `fluidem cases`, or a TOML path)")
        overrides = _parse_sets(args.set)
        if args.until is not None:
            overrides["time.end"] = args.until
        if args.threads is not None:
            overrides["threads"] = args.threads
        case = load_case(args.case, overrides)
        out = Path(args.out) if args.out else Path("runs") / f"{case.name}-{time.strftime('%Y%m%d-%H%M%S')}"
        sim = Simulation(case, out_dir=out, progress=not args.quiet)
    until = args.until if args.until is not None else sim.case.time.end
    if not args.quiet:
        print(f"fluidem: {sim.case.name}: {sim.engine.state.n} particles, dt = {sim.dt:.3g} s, "
              f"to t = {until:g} s, {sim.threads} thread(s) -> {out}",
              file=sys.stderr)
    try:
        summary = sim.run(until=until)
    except KeyboardInterrupt:
        print(f"fluidem: interrupted at t = {sim.time:.6g} s; checkpoint written. "
              f"Continue with: fluidem run --resume {out}", file=sys.stderr)
        return 130
    except FloatingPointError as err:
        print(f"fluidem: run failed: {err}", file=sys.stderr)
        return 1
    except OSError as err:
        print(f"fluidem: run stopped at t = {sim.time:.6g} s: {err}. The last checkpoint in {out} is intact; "
              f"free the space or fix the folder, then: fluidem run --resume {out}", file=sys.stderr)
        return 1
    print(summary_json(summary), end="")
    return 0


def cmd_cases(args) -> int:
    from .case import builtin_cases, load_case

    for name, path in sorted(builtin_cases().items()):
        print(f"{name:20s} {load_case(path).description}")
    return 0


def cmd_bench(args) -> int:
    from .bench import run_bench
    from .errors import CaseError

    if not args.coupled_until > 0:
        raise CaseError(f"bench --coupled-until = {args.coupled_until!r}: must be a positive number of simulated seconds")
    if not args.hard_until > 0:
        raise CaseError(f"bench --hard-until = {args.hard_until!r}: must be a positive number of simulated seconds")
    run_bench(sizes=args.sizes, threads=args.threads, steps=args.steps, as_json=args.json, gas=not args.no_gas,
              coupled=not args.no_coupled, coupled_until=args.coupled_until, hard_sphere=not args.no_hard_sphere,
              hard_until=args.hard_until)
    return 0


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="fluidem", description="Discrete-particle simulation of gas–solid flows.")
    p.add_argument("--version", action="store_true", help="print the version and exit")
    sub = p.add_subparsers(dest="command")

    r = sub.add_parser("run", help="run a case (built-in name or TOML path)",
                       description="Run a case. Output goes to a run directory: case.toml, summary.json, probes.csv, "
                                   "particles.h5 + particles.xdmf (ParaView), restart.h5.")
    r.add_argument("case", nargs="?", help="built-in case name (see `fluidem cases`) or a TOML file")
    r.add_argument("--until", type=float, help="simulated time to reach [s] (default: the case's time.end)")
    r.add_argument("--out", help="run directory (default runs/<case>-<timestamp>); must be new or empty")
    r.add_argument("--set", action="append", metavar="KEY=VALUE",
                   help="override a case key by dotted name, e.g. --set particles.contact.restitution=1.0")
    r.add_argument("--threads", type=int, help="compute threads (default: one per 1200 particles, at most all cores)")
    r.add_argument("--resume", metavar="DIR", help="continue a stopped run from DIR/restart.h5")
    r.add_argument("--quiet", action="store_true", help="no progress lines")
    r.set_defaults(func=cmd_run)

    c = sub.add_parser("cases", help="list built-in cases")
    c.set_defaults(func=cmd_cases)

    b = sub.add_parser("bench", help="throughput on standard problems (particle-steps per second)")
    b.add_argument("--sizes", default="10000,100000", help="dense-bed sizes, comma separated")
    b.add_argument("--threads", default="1,2", help="thread counts, comma separated")
    b.add_argument("--steps", type=int, default=0, help="timed steps per problem (default: about 5 s of work)")
    b.add_argument("--json", metavar="FILE", help="also write the results as JSON")
    b.add_argument("--no-gas", action="store_true", help="skip the gas-step timings")
    b.add_argument("--no-coupled", action="store_true", help="skip the coupled tsuji-jet timing")
    b.add_argument("--coupled-until", type=float, default=0.25, metavar="T",
                   help="simulated seconds of the coupled tsuji-jet timing (default 0.25)")
    b.add_argument("--no-hard-sphere", action="store_true", help="skip the hard-sphere hoomans-orifice timing")
    b.add_argument("--hard-until", type=float, default=0.1, metavar="T",
                   help="simulated seconds of the hoomans-orifice jet timed after its 0.5 s start-up (default 0.1)")
    b.set_defaults(func=cmd_bench)

    from .cli_plot import add_commands

    add_commands(sub)
    return p


def main(argv: list[str] | None = None) -> int:
    from .errors import CaseError

    parser = build_parser()
    args = parser.parse_args(argv)
    if args.version:
        from . import __version__

        print(__version__)
        return 0
    if not getattr(args, "func", None):
        parser.print_help()
        return EXIT_BAD_INPUT
    try:
        return args.func(args)
    except CaseError as err:
        print(f"fluidem: error: {err}", file=sys.stderr)
        return EXIT_BAD_INPUT


if __name__ == "__main__":
    sys.exit(main())
