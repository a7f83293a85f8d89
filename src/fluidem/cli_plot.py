"""The ``fluidem plot | animate | compare | report`` subcommands.

``add_commands(subparsers)`` registers them on the main parser. Each handler returns an
exit status and raises ``CaseError`` for bad input (not a run directory, an unknown
colour mode, a time outside the run, …), which the main CLI turns into status 2 with
the message. A figure the run cannot have (no probes.csv, no snapshots, no gas) is
skipped with a one-line note, an INFO record of the ``fluidem.cli_plot`` logger that the
command shows on stderr (hidden by ``--quiet``); the command still succeeds. The files
written are the command's output, on stdout.
"""
from __future__ import annotations

import functools
import logging
from pathlib import Path

from ._log import command_logging
from .errors import CaseError

COLOR_CHOICES = ("height", "speed", "species", "nc")

log = logging.getLogger(__name__)


def _shows_notes(command):
    """Run ``command(args)`` with the ``fluidem`` logger shown on stderr, at INFO unless an enclosing
    ``fluidem.cli.main`` already chose the level: a handler called from a parser of its own still
    prints its notes."""

    @functools.wraps(command)
    def run(args) -> int:
        with command_logging():
            return command(args)

    return run


def _require_matplotlib(command: str) -> None:
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        raise CaseError(f"fluidem {command} needs matplotlib, a dependency of fluidem that is missing here: "
                        "pip install 'matplotlib>=3.7'") from None


def _note(command: str, name: str, why: str) -> None:
    log.info("fluidem %s: skipped %s: %s", command, name, why)


def _is_study(path) -> bool:
    from .plotting.study import is_study

    return is_study(path)


@_shows_notes
def cmd_plot(args) -> int:
    _require_matplotlib("plot")
    if _is_study(args.run):
        from .cli_plot_study import plot_study_command

        return plot_study_command(args)
    from .plotting.figures import PlotOptions, parse_names, parse_times, parse_window, plot_run
    from .plotting.run import RunData
    from .plotting.style import parse_formats

    run = RunData(args.run)
    options = PlotOptions(times=parse_times(args.times), color=args.color, bands=args.bands,
                          overlay=not args.no_overlay, window=parse_window(args.window))
    formats = parse_formats(args.format)
    only = parse_names(args.only)
    out = Path(args.out) if args.out else run.path / "figures"
    result = plot_run(run, out, options, formats, only)
    for name, why in result.skipped:
        _note("plot", name, why)
    for path in result.written:
        print(path)
    return 0


@_shows_notes
def cmd_animate(args) -> int:
    _require_matplotlib("animate")
    from .plotting.animate import animate_run
    from .plotting.run import RunData

    run = RunData(args.run)
    out = Path(args.out) if args.out else run.path / "figures" / f"snapshots_{args.color}.mp4"
    res = animate_run(run, out, color=args.color, fps=args.fps, height_px=args.height, bands=args.bands)
    print(f"{res.path}  ({res.frames} frames, {res.width}×{res.height} px, {res.fps:g} fps)")
    return 0


@_shows_notes
def cmd_compare(args) -> int:
    _require_matplotlib("compare")
    from .plotting.compare import compare_runs, parse_quantities
    from .plotting.run import RunData
    from .plotting.style import parse_formats

    runs = [RunData(p) for p in args.runs]
    formats = parse_formats(args.format)
    result = compare_runs(runs, Path(args.out), parse_quantities(args.quantity), formats)
    for note in result.notes:
        log.info("fluidem compare: %s", note)
    print(result.table)
    for path in result.written:  # the files written go to stderr: stdout holds the table alone
        log.info("%s", path)
    return 0


@_shows_notes
def cmd_report(args) -> int:
    _require_matplotlib("report")
    if _is_study(args.run):
        from .cli_plot_study import report_study_command

        return report_study_command(args)
    from .plotting.figures import PlotOptions
    from .plotting.report import write_report
    from .plotting.run import RunData

    run = RunData(args.run)
    result = write_report(run, args.out, PlotOptions(color=args.color))
    for name, why in result.skipped:
        _note("report", name, why)
    print(result.path)
    return 0


def add_commands(subparsers) -> None:
    """Register ``plot``, ``animate``, ``compare`` and ``report`` on an argparse subparsers object."""
    p = subparsers.add_parser(
        "plot", help="figures of a run (snapshots, energy, contacts, bed height, pressure, gas and force maps, …)",
        description="Write the figures that apply to a run directory. A figure whose quantity the run "
                    "lacks is skipped with a one-line note.")
    p.add_argument("run", metavar="RUN", help="run directory (made by `fluidem run --out RUN`), or a study folder "
                                              "(`fluidem sweep --out STUDY`): each summary scalar against the varied keys")
    p.add_argument("--times", metavar="T1,T2,...",
                   help="snapshot times [s] to draw (nearest snapshot each); default: 4 evenly spaced, "
                        "first and last included")
    p.add_argument("--color", choices=COLOR_CHOICES, default="height",
                   help="particle colour: band of initial height (Hoomans 1996 style), speed, species, or nc "
                        "(number of contacting particles N_c, Sun 2007 Figs 6/10) (default: height)")
    p.add_argument("--bands", type=int, default=6, help="number of initial-height bands (default 6)")
    p.add_argument("--format", default="png", metavar="FMT[,FMT]", help="png, svg and/or pdf (default png)")
    p.add_argument("--only", metavar="NAME[,NAME]",
                   help="only these figures: snapshots, energy, contacts, multicontact, bed_height, pressure, "
                        "voidage, solids_fraction, forces, segregation")
    p.add_argument("--window", metavar="T0,T1",
                   help="time window [s] of the time averages: gas and force maps, multicontact means "
                        "(default 5,10 when the run covers it, else the second half of the run)")
    p.add_argument("--no-overlay", action="store_true", help="draw the gas voidage maps without the particles")
    p.add_argument("--out", metavar="DIR", help="folder for the figures (default RUN/figures)")
    p.set_defaults(func=cmd_plot)

    a = subparsers.add_parser("animate", help="MP4 of a run's particle snapshots",
                              description="Write an MP4 with one frame per particle snapshot "
                                          "(needs imageio and imageio-ffmpeg).")
    a.add_argument("run", metavar="RUN", help="run directory")
    a.add_argument("--color", choices=COLOR_CHOICES, default="height", help="particle colour (default height)")
    a.add_argument("--bands", type=int, default=6, help="number of initial-height bands (default 6)")
    a.add_argument("--fps", type=float, default=20.0, help="frames per second (default 20)")
    a.add_argument("--height", type=int, default=640, help="frame height [px] (default 640; width follows)")
    a.add_argument("--out", metavar="FILE.mp4", help="output file (default RUN/figures/snapshots_<color>.mp4)")
    a.set_defaults(func=cmd_animate)

    c = subparsers.add_parser("compare", help="overlay probe traces of runs and tabulate their summaries",
                              description="Overlay probe traces of several runs (compare_probes.png) and "
                                          "print their summaries side by side (also compare_summary.csv).")
    c.add_argument("runs", metavar="RUN", nargs="+", help="run directories")
    c.add_argument("--quantity", metavar="COLUMN[,COLUMN]",
                   help="probe columns to overlay, e.g. kinetic_J,coordination (default: all the runs share)")
    c.add_argument("--format", default="png", metavar="FMT[,FMT]", help="png, svg and/or pdf (default png)")
    c.add_argument("--out", metavar="DIR", default="comparison", help="folder for the outputs (default ./comparison)")
    c.set_defaults(func=cmd_compare)

    r = subparsers.add_parser("report", help="one self-contained HTML page of a run",
                              description="Write one HTML page (no external files) with the case, the summary, "
                                          "published numbers for built-in seed cases, and every figure.")
    r.add_argument("run", metavar="RUN", help="run directory, or a study folder (`fluidem sweep --out STUDY`)")
    r.add_argument("--color", choices=COLOR_CHOICES, default="height", help="particle colour in the snapshots")
    r.add_argument("--out", metavar="FILE.html", help="output file (default RUN/report.html)")
    r.set_defaults(func=cmd_report)
