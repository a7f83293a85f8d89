"""Figures of a study: each summary scalar against the varied keys, one figure per scalar.

The mean over the seeds is drawn (each seed as a small dot beside it); a true/false scalar is drawn
as the fraction of seeds where it holds. With one varied key: a line against it. With two: lines
against the first key, one per value of the second, and beside them a heat map over both. With more:
one such line panel per combination of the third and later keys. A ``--zip`` study varies its keys
together, so its members lie on one line, labelled with every key's value. Members that did not
complete have no value. A scalar that is the same in every member is skipped with a note.
"""
from __future__ import annotations

import itertools
import math
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ...errors import CaseError
from ...studies.definition import format_value
from .. import style
from ..study import Scalar, StudyData

MAX_PANELS = 12
PANEL_IN = (4.6, 3.3)


@dataclass
class StudyPlotResult:
    written: list[Path] = field(default_factory=list)
    skipped: list[tuple[str, str]] = field(default_factory=list)


def file_stem(column: str) -> str:
    return "study_" + re.sub(r"[^A-Za-z0-9_\-]", "_", column)


def parse_columns(study: StudyData, text: str | None) -> list[str] | None:
    """``--only`` of a study: summary columns, checked against those the study has."""
    if text is None:
        return None
    names = [n.strip() for n in str(text).split(",") if n.strip()]
    allowed = [s.name for s in study.scalars]
    for n in names:
        if n not in allowed:
            raise CaseError(f"--only {n!r}: not a numeric summary column of this study; allowed are "
                            + (", ".join(allowed) if allowed else "none (no member has completed)"))
    if not names:
        raise CaseError(f"--only {text!r}: give summary column names separated by commas, e.g. mean_bed_height_m")
    return names


def _numeric(values) -> bool:
    return all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in values)


def _positions(values: list) -> tuple[np.ndarray, list[str] | None]:
    """x positions of a key's values: the values themselves when numeric, else 0, 1, … with labels."""
    if _numeric(values):
        return np.asarray(values, float), None
    return np.arange(len(values), dtype=float), [format_value(v) for v in values]


def _groups(study: StudyData, scalar: Scalar) -> dict[tuple, list[float]]:
    """Combination of the varied values → the finite values of its members (one per seed)."""
    out: dict[tuple, list[float]] = {}
    for row, v in zip(study.rows, scalar.values):
        out.setdefault(study.combination_of(row), [])
        if math.isfinite(v):
            out[study.combination_of(row)].append(v)
    return out


def _mean(vals: list[float]) -> float:
    return float(np.mean(vals)) if vals else math.nan


def _ylabel(scalar: Scalar) -> str:
    if scalar.boolean:
        return f"{scalar.name.replace('_', ' ')}: fraction of members"
    return style.label(scalar.name)


def _line_panel(ax, study: StudyData, scalar: Scalar, groups: dict, fixed: dict, x_key: str | None,
                line_key: str | None) -> None:
    """Mean against ``x_key``, one line per value of ``line_key``, the other keys at ``fixed``."""
    labels = study.labels
    x_values = study.definition.vary[x_key] if x_key else [None]
    x, ticks = _positions(x_values)
    line_values = study.definition.vary[line_key] if line_key else [None]
    for k, lv in enumerate(line_values):
        means, dots_x, dots_y = [], [], []
        for xi, xv in zip(x, x_values):
            combo = dict(fixed)
            if x_key:
                combo[x_key] = xv
            if line_key:
                combo[line_key] = lv
            vals = groups.get(tuple(combo.get(key) for key in study.keys), [])
            means.append(_mean(vals))
            if len(vals) > 1:
                dots_x += [xi] * len(vals)
                dots_y += vals
        colour = style.LINE_COLOURS[k % len(style.LINE_COLOURS)]
        name = f"{labels[line_key]} = {format_value(lv)}" if line_key else None
        ax.plot(x, means, marker="o", color=colour, label=name)
        if dots_x:
            ax.plot(dots_x, dots_y, linestyle="none", marker=".", markersize=4, alpha=0.45, color=colour)
    if ticks is not None:
        ax.set_xticks(x, ticks)
    ax.set_xlabel(style.label(labels[x_key].split(".")[-1]) if x_key else "")
    ax.set_ylabel(_ylabel(scalar))
    if line_key:
        ax.legend(fontsize=7)
    if fixed:
        ax.set_title(", ".join(f"{labels[k]} = {format_value(v)}" for k, v in fixed.items()))


def _heat_map(fig, ax, study: StudyData, scalar: Scalar, groups: dict, x_key: str, y_key: str) -> None:
    xs, ys = study.definition.vary[x_key], study.definition.vary[y_key]
    grid = np.full((len(ys), len(xs)), np.nan)
    for i, yv in enumerate(ys):
        for j, xv in enumerate(xs):
            grid[i, j] = _mean(groups.get(tuple({x_key: xv, y_key: yv}.get(k) for k in study.keys), []))
    mesh = ax.imshow(grid, origin="lower", aspect="auto", cmap="viridis")
    finite = grid[np.isfinite(grid)]
    middle = 0.5 * (finite.min() + finite.max()) if finite.size else 0.0
    for i in range(len(ys)):
        for j in range(len(xs)):
            if np.isfinite(grid[i, j]):
                ax.text(j, i, f"{grid[i, j]:.3g}", ha="center", va="center", fontsize=7,
                        color="black" if grid[i, j] > middle else "white")
    ax.set_xticks(range(len(xs)), study.level_labels(x_key))
    ax.set_yticks(range(len(ys)), study.level_labels(y_key))
    ax.grid(False)
    labels = study.labels
    ax.set_xlabel(style.label(labels[x_key].split(".")[-1]))
    ax.set_ylabel(style.label(labels[y_key].split(".")[-1]))
    fig.colorbar(mesh, ax=ax, label=_ylabel(scalar))


def _zip_panel(ax, study: StudyData, scalar: Scalar, groups: dict) -> None:
    combos = study.definition.combinations()
    labels = study.labels
    x = np.arange(len(combos), dtype=float)
    means = [_mean(groups.get(c, [])) for c in combos]
    ax.plot(x, means, marker="o", color=style.LINE_COLOURS[0])
    for xi, c in zip(x, combos):
        vals = groups.get(c, [])
        if len(vals) > 1:
            ax.plot([xi] * len(vals), vals, linestyle="none", marker=".", markersize=4, alpha=0.45,
                    color=style.LINE_COLOURS[0])
    ax.set_xticks(x, ["\n".join(f"{labels[k]} = {format_value(v)}" for k, v in zip(study.keys, c)) for c in combos],
                  fontsize=7)
    ax.set_ylabel(_ylabel(scalar))


def draw_scalar(study: StudyData, scalar: Scalar):
    """The figure of one summary scalar against the varied keys."""
    groups = _groups(study, scalar)
    keys = study.keys
    if study.definition.combine == "zip" and len(keys) > 1:
        fig = style.new_figure(max(PANEL_IN[0], 0.9 * len(groups)), PANEL_IN[1] + 0.4)
        _zip_panel(fig.add_subplot(1, 1, 1), study, scalar, groups)
    elif not keys:  # seeds only: each member against its seed
        fig = style.new_figure(*PANEL_IN)
        ax = fig.add_subplot(1, 1, 1)
        seeds = [r.get("seed") for r in study.rows]
        ax.plot(seeds, scalar.values, marker="o", linestyle="none", color=style.LINE_COLOURS[0])
        ax.set_xticks(seeds, [str(s) for s in seeds])
        ax.set_xlabel("placement seed")
        ax.set_ylabel(_ylabel(scalar))
    elif len(keys) == 1:
        fig = style.new_figure(*PANEL_IN)
        _line_panel(fig.add_subplot(1, 1, 1), study, scalar, groups, {}, keys[0], None)
    elif len(keys) == 2:
        fig = style.new_figure(2 * PANEL_IN[0] + 0.6, PANEL_IN[1])
        _line_panel(fig.add_subplot(1, 2, 1), study, scalar, groups, {}, keys[0], keys[1])
        _heat_map(fig, fig.add_subplot(1, 2, 2), study, scalar, groups, keys[0], keys[1])
    else:
        rest = keys[2:]
        fixed = list(itertools.product(*(study.definition.vary[k] for k in rest)))[:MAX_PANELS]
        cols = min(3, len(fixed))
        rows = math.ceil(len(fixed) / cols)
        fig = style.new_figure(cols * PANEL_IN[0], rows * PANEL_IN[1])
        for n, values in enumerate(fixed):
            _line_panel(fig.add_subplot(rows, cols, n + 1), study, scalar, groups, dict(zip(rest, values)),
                        keys[0], keys[1])
    fig.suptitle(f"{scalar.name} ({study.name})", fontsize=9)
    return fig


def render_study(study: StudyData, only: list[str] | None = None):
    """Yield (column name, figure or None, why skipped) for each summary scalar of the study."""
    if not study.scalars:
        yield "study", None, "no member has completed yet"
        return
    for scalar in study.scalars:
        if only is not None and scalar.name not in only:
            continue
        if study.constant(scalar) and only is None:
            value = next((v for v in scalar.values if math.isfinite(v)), math.nan)
            yield scalar.name, None, f"the same in every member ({value:.6g})"
            continue
        yield scalar.name, draw_scalar(study, scalar), None


def plot_study(study: StudyData, out_dir: Path, formats=("png",), only: list[str] | None = None) -> StudyPlotResult:
    """Write the figure of each summary scalar of ``study`` into ``out_dir`` (``study_<column>.<fmt>``)."""
    result = StudyPlotResult()
    out_dir = Path(out_dir)
    with style.context():
        for name, fig, why in render_study(study, only):
            if fig is None:
                result.skipped.append((name, why))
                continue
            try:
                out_dir.mkdir(parents=True, exist_ok=True)
            except OSError as err:
                raise CaseError(f"--out {str(out_dir)!r}: cannot create the folder: {err.strerror or err}") from None
            result.written += style.save(fig, out_dir / file_stem(name), list(formats))
    return result
