"""``fluidem plot STUDY`` and ``fluidem report STUDY``: the branches of ``cli_plot``'s commands for a study
folder (one that holds ``study.toml``). Options that choose what a run's figures show (times, colours,
windows) do not apply to a study and are noted as ignored; ``--only`` names summary columns."""
from __future__ import annotations

import logging
from pathlib import Path

log = logging.getLogger("fluidem.cli_plot")

RUN_ONLY = (("times", None), ("window", None), ("no_overlay", False), ("color", "height"), ("bands", 6))


def _note_run_options(command: str, args) -> None:
    for name, default in RUN_ONLY:
        if getattr(args, name, default) != default:
            log.info("fluidem %s: --%s applies to a run's figures, not to a study; ignored", command,
                     name.replace("_", "-"))


def plot_study_command(args) -> int:
    from .plotting.figures.study import parse_columns, plot_study
    from .plotting.study import StudyData
    from .plotting.style import parse_formats

    study = StudyData(args.run)
    _note_run_options("plot", args)
    formats = parse_formats(args.format)
    only = parse_columns(study, args.only)
    out = Path(args.out) if args.out else study.path / "figures"
    result = plot_study(study, out, formats, only)
    for name, why in result.skipped:
        log.info("fluidem plot: skipped %s: %s", name, why)
    for path in result.written:
        print(path)
    return 0


def report_study_command(args) -> int:
    from .plotting.study import StudyData
    from .plotting.study_report import write_study_report

    study = StudyData(args.run)
    _note_run_options("report", args)
    result = write_study_report(study, args.out)
    for name, why in result.skipped:
        log.info("fluidem report: skipped %s: %s", name, why)
    print(result.path)
    return 0
