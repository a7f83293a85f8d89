"""Several runs side by side: probe traces overlaid, summaries in one table (``fluidem compare``).

``compare_runs`` writes ``compare_probes.<fmt>`` (one panel per quantity, one line per
run) and ``compare_summary.csv``; ``summary_table`` is the text table the command prints.
A quantity that some runs lack is drawn for the others and noted.
"""
from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import CaseError
from ..io.atomic import write_text_atomic
from . import style
from .run import RunData

NOT_QUANTITIES = ("time_s", "step")


@dataclass
class CompareResult:
    written: list[Path] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    table: str = ""


def run_labels(runs: list[RunData]) -> list[str]:
    """Legend labels: folder names, made unique with their parent folders where needed."""
    labels = [r.name for r in runs]
    for depth in (1, 2, 3):
        if len(set(labels)) == len(labels):
            break
        labels = ["/".join(r.path.resolve().parts[-1 - depth:]) for r in runs]
    if len(set(labels)) != len(labels):
        labels = [f"{lab} [{k + 1}]" for k, lab in enumerate(labels)]
    return labels


def parse_quantities(text: str | None) -> list[str] | None:
    if text is None:
        return None
    names = [q.strip() for q in str(text).split(",") if q.strip()]
    if not names:
        raise CaseError(f"--quantity {text!r}: give probe column names separated by commas, e.g. kinetic_J")
    return names


def choose_quantities(runs: list[RunData], requested: list[str] | None) -> list[str]:
    """The probe columns to overlay: ``requested`` (checked), else those all runs with probes share."""
    with_probes = [r for r in runs if r.lacks_probes() is None]
    columns = [[c for c in r.probe_columns() if c not in NOT_QUANTITIES] for r in with_probes]
    union = list(dict.fromkeys(c for cols in columns for c in cols))
    if requested is None:
        return [c for c in union if all(c in cols for cols in columns)]
    for q in requested:
        if q not in union:
            allowed = ", ".join(union) if union else "none (no run has a readable probes.csv)"
            raise CaseError(f"--quantity {q!r}: not a probe column of these runs; allowed are {allowed}")
    return list(dict.fromkeys(requested))


def compare_runs(runs: list[RunData], out_dir: Path, quantities: list[str] | None = None,
                 formats=("png",)) -> CompareResult:
    if len(runs) < 1:
        raise CaseError("fluidem compare needs at least one run directory")
    result = CompareResult()
    labels = run_labels(runs)
    chosen = choose_quantities(runs, quantities)
    for run, lab in zip(runs, labels):
        why = run.lacks_probes()
        if why is not None:
            result.notes.append(f"{lab}: no traces: {why}")
    out_dir = Path(out_dir)
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise CaseError(f"--out {str(out_dir)!r}: cannot create the folder: {err.strerror or err}") from None
    if chosen and any(r.lacks_probes() is None for r in runs):
        with style.context():
            fig = _overlay(runs, labels, chosen, result.notes)
            result.written += style.save(fig, out_dir / "compare_probes", list(formats))
    else:
        result.notes.append("compare_probes: skipped: no probe quantity common to these runs")
    keys, values = summary_columns(runs)
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["quantity", *labels])
    for k in keys:
        w.writerow([k, *(_raw(v.get(k)) for v in values)])
    path = out_dir / "compare_summary.csv"
    write_text_atomic(path, buf.getvalue())
    result.written.append(path)
    result.table = summary_table(runs, labels)
    return result


def _overlay(runs, labels, quantities, notes):
    w, h = style.TRACE_SIZE_IN
    fig = style.new_figure(w, 1.9 * len(quantities) + 0.9)
    axes = fig.subplots(len(quantities), 1, sharex=True, squeeze=False)[:, 0]
    for ax, q in zip(axes, quantities):
        for k, (run, lab) in enumerate(zip(runs, labels)):
            colour = style.LINE_COLOURS[k % len(style.LINE_COLOURS)]
            if run.lacks_probes(q) is not None:
                if run.lacks_probes() is None:
                    notes.append(f"{lab}: no {q} in probes.csv")
                continue
            p = run.probes
            ax.plot(p["time_s"], p[q], color=colour, label=lab)
        ax.set_ylabel(style.label(q))
    axes[-1].set_xlabel(style.label("time_s"))
    handles, labs = [], []
    for ax in axes:
        for hd, lb in zip(*ax.get_legend_handles_labels()):
            if lb not in labs:
                handles.append(hd)
                labs.append(lb)
    if handles:
        fig.legend(handles, labs, loc="outside upper center", ncols=min(len(labs), 3))
    return fig


def summary_columns(runs: list[RunData]) -> tuple[list[str], list[dict]]:
    values = [r.summary or {} for r in runs]
    keys = list(dict.fromkeys(k for v in values for k in v))
    return keys, values


def _raw(v) -> str:
    return "" if v is None else str(v)


def _fmt(v) -> str:
    if v is None:
        return "–"
    if isinstance(v, bool):
        return str(v).lower()
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return "nan" if math.isnan(v) else f"{v:.6g}"
    if isinstance(v, (list, tuple)):
        return ", ".join(_fmt(x) for x in v)
    return str(v)


def summary_table(runs: list[RunData], labels: list[str] | None = None) -> str:
    """The runs' summaries side by side as an aligned text table (one row per summary key)."""
    labels = labels or run_labels(runs)
    keys, values = summary_columns(runs)
    rows = [["quantity", *labels]] + [[k, *(_fmt(v.get(k)) if k in v else "–" for v in values)] for k in keys]
    for r, run in zip(range(len(runs)), runs):
        if run.summary is None:
            rows.append([f"(no summary.json in {labels[r]})", *([""] * len(runs))])
    widths = [max(len(row[c]) for row in rows) for c in range(len(rows[0]))]
    lines = []
    for i, row in enumerate(rows):
        lines.append("  ".join(cell.ljust(widths[c]) if c == 0 else cell.rjust(widths[c])
                               for c, cell in enumerate(row)).rstrip())
        if i == 0:
            lines.append("  ".join("-" * w for w in widths))
    return "\n".join(lines)
