"""Figures, animations, comparisons and reports of run directories.

What ``fluidem plot | animate | compare | report`` call; usable from Python too::

    from fluidem.plotting import RunData, PlotOptions, plot_run, write_report
    run = RunData("runs/pour")                       # CaseError if not a run directory
    plot_run(run, "runs/pour/figures", PlotOptions(color="speed"))
    write_report(run)                                # runs/pour/report.html

Modules: ``run`` (a run directory, read through ``fluidem.io``), ``style`` (one look, units in
labels), ``figures`` (the registry of figures, one module per family: each says what it needs
and draws itself), ``animate`` (MP4), ``compare`` (several runs), ``report`` (HTML),
``published`` (published numbers of the seed cases). Needs the ``plot`` extra (matplotlib);
``animate`` also needs the ``animate`` extra (imageio, imageio-ffmpeg). Matplotlib is
imported only when a figure is drawn, and pyplot never.
"""
from .animate import animate_run
from .compare import compare_runs, summary_table
from .figures import PlotOptions, figures, plot_run, render
from .published import PUBLISHED, comparison_rows
from .report import build_report, write_report
from .run import RunData, Unavailable

__all__ = ["RunData", "Unavailable", "PlotOptions", "figures", "plot_run", "render", "animate_run",
           "compare_runs", "summary_table", "build_report", "write_report", "PUBLISHED", "comparison_rows"]
