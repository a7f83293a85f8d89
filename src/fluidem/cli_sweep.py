"""The ``fluidem sweep`` subcommand: a study of one case over values of some of its keys, on Dask.

``add_command(subparsers)`` registers it on the main parser. Bad input (an unknown key, a value the
schema refuses for any member, a folder that holds another study, an unreachable scheduler) raises
``CaseError``: exit 2, nothing written. The study table (``study.csv``) goes to stdout; progress lines
to stderr through the logger ``fluidem.progress``. Exit status: 0 when every member completed, 1 when
some failed (their errors are in the table), 130 after Ctrl-C (finished members kept; rerun the same
command to go on).
"""
from __future__ import annotations

import logging
import signal


log = logging.getLogger("fluidem.cli")

EXAMPLE = ("fluidem sweep hoomans-orifice --vary particles.contact.restitution=0.8,0.9,0.95,1.0 "
           "--vary particles.contact.friction=0,0.1,0.3 --seeds 3 --until 1.5 --out studies/orifice")


def cmd_sweep(args) -> int:
    from .cli import _parse_sets
    from .studies import StudyDefinition, parse_seeds, parse_vary, run_study
    from .studies.execution import require_distributed
    from .studies.table import table_text

    study = StudyDefinition.build(args.case, parse_vary(args.vary), parse_seeds(args.seeds),
                                  "zip" if args.zip else "product", args.until, _parse_sets(args.set), args.threads)
    require_distributed()
    previous = signal.getsignal(signal.SIGTERM)

    def interrupt(signum, frame):  # a batch system's SIGTERM stops the study as Ctrl-C does
        raise KeyboardInterrupt

    signal.signal(signal.SIGTERM, interrupt)
    try:
        outcome = run_study(study, args.out, scheduler=args.scheduler, workers=args.workers, retry=args.retry,
                            connect_timeout=args.connect_timeout)
    finally:
        signal.signal(signal.SIGTERM, previous)
    print(table_text(outcome.columns, outcome.rows), end="")
    counts = outcome.counts
    if outcome.interrupted:
        log.warning("study stopped: %d of %d members done; continue with the same command", counts["completed"],
                    len(outcome.rows))
        return 130
    if counts["failed"]:
        log.error("%d of %d members failed (their errors are in %s/study.csv); rerun with --retry to run them again",
                  counts["failed"], len(outcome.rows), args.out)
        return 1
    return 0


def add_command(subparsers) -> None:
    """Register ``sweep`` on an argparse subparsers object."""
    s = subparsers.add_parser(
        "sweep", help="run a case over values of some of its keys (a study), on Dask",
        description="Run a case once per combination of the --vary values (and seed), each member a run "
                    "directory under --out, named for its values; study.csv has one row per member (the values, "
                    "status, error and every summary scalar), study.toml the definition. Rerun the same command "
                    "to skip finished members and resume interrupted ones. Example: " + EXAMPLE)
    s.add_argument("case", metavar="CASE", help="built-in case name (see `fluidem cases`) or a TOML file")
    s.add_argument("--vary", action="append", metavar="KEY=V1,V2,...",
                   help="a case key by dotted name and its values, e.g. --vary particles.contact.friction=0,0.1,0.3; "
                        "repeat for more keys (every combination, or --zip)")
    s.add_argument("--zip", action="store_true",
                   help="pair the i-th values of every --vary key instead of taking every combination")
    s.add_argument("--seeds", metavar="N|S1,S2,...",
                   help="run each combination with N placement seeds (1..N) or the seeds listed "
                        "(particles.placement.seed); default the case's own seed")
    s.add_argument("--until", type=float, help="simulated time every member reaches [s] (default: the case's time.end)")
    s.add_argument("--set", action="append", metavar="KEY=VALUE", help="override a case key in every member")
    s.add_argument("--out", required=True, metavar="STUDY", help="study folder (new, empty, or this study to go on)")
    s.add_argument("--threads", type=int, help="compute threads of each member (default the case's threads, else 1)")
    s.add_argument("--workers", type=int,
                   help="worker processes of the local Dask cluster (default: cores // threads)")
    s.add_argument("--scheduler", metavar="ADDRESS",
                   help="run on an existing Dask cluster, e.g. tcp://10.0.0.5:8786 (its workers must see --out "
                        "at the same path; start them with --nthreads 1)")
    s.add_argument("--connect-timeout", type=float, default=5.0, metavar="S",
                   help="seconds to wait for --scheduler (default 5)")
    s.add_argument("--retry", action="store_true", help="run failed members again (from the start)")
    s.set_defaults(func=cmd_sweep)
