"""One self-contained HTML page per study (``fluidem report STUDY``).

The page holds the study's definition (case, varied keys and their values, seeds, end time), the
members' status counts and the errors of failed members, the table of members (varied values,
status and every summary scalar that differs between members), each scalar's figure against the
varied keys (PNG embedded as base64) and ``study.toml``. Like a run's report it loads nothing from
outside.
"""
from __future__ import annotations

import html
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import CaseError
from . import style
from .compare import _fmt
from .figures.study import render_study
from .report import CSS, SCRIPT, figure_html, skipped_html
from .study import StudyData

STUDY_CSS = ".scroll { overflow-x: auto; } td.failed { color: #a40000; }\n"


@dataclass
class StudyReportResult:
    path: Path
    figures: list[str] = field(default_factory=list)
    skipped: list[tuple[str, str]] = field(default_factory=list)


def build_study_report(study: StudyData) -> tuple[str, StudyReportResult]:
    """The report page of ``study`` as HTML text, and what went into it."""
    e = html.escape
    d = study.definition
    result = StudyReportResult(path=Path())
    counts = study.counts
    parts = [
        "<!DOCTYPE html>", '<html lang="en">', "<head>", '<meta charset="utf-8">',
        '<meta name="viewport" content="width=device-width, initial-scale=1">',
        f"<title>fluidem study: {e(study.name)}</title>", f"<style>{CSS}{STUDY_CSS}</style>", "</head>", "<body>",
        f"<h1>fluidem study: {e(study.name)}</h1>",
        f'<p class="sub">case <b>{e(str(d.base.get("name", d.case)))}</b> · {len(study.rows)} members · '
        + " · ".join(f"{n} {e(s)}" for s, n in counts.items() if n) + "</p>",
        "<h2>Definition</h2>", "<table><tr><th>item</th><th>value</th></tr>",
        f"<tr><td>case</td><td>{e(d.case)}</td></tr>",
        f"<tr><td>until</td><td class=\"num\">{d.until:g} s</td></tr>",
    ]
    for key, values in d.vary.items():
        parts.append(f"<tr><td>{e(key)}</td><td>{e(', '.join(_fmt(v) for v in values))}</td></tr>")
    if d.seeds is not None:
        parts.append(f"<tr><td>seeds (particles.placement.seed)</td><td>{e(', '.join(map(str, d.seeds)))}</td></tr>")
    parts.append(f"<tr><td>combination</td><td>{e(d.combine)}</td></tr>")
    parts.append(f"<tr><td>threads per member</td><td class=\"num\">{d.threads}</td></tr></table>")

    failed = [r for r in study.rows if r["status"] == "failed"]
    if failed:
        parts.append("<h2>Failed members</h2><table><tr><th>member</th><th>error</th></tr>")
        for r in failed:
            parts.append(f'<tr><td>{e(r["member"])}</td><td class="failed">{e(str(r["error"]))}</td></tr>')
        parts.append("</table>")

    varying = [s.name for s in study.scalars if not study.constant(s)]
    head = ["member", *study.keys, *(["seed"] if d.seeds is not None else []), "status", *varying]
    parts.append("<h2>Members</h2>")
    parts.append(f"<p>Summary scalars that differ between members; every column is in "
                 f"<code>{e(str(study.path / 'study.csv'))}</code>.</p>")
    parts.append('<div class="scroll"><table><tr>' + "".join(f"<th>{e(h)}</th>" for h in head) + "</tr>")
    for r in study.rows:
        cells = []
        for h in head:
            v = r.get(h)
            cls = ' class="num"' if isinstance(v, (int, float)) and not isinstance(v, bool) else ""
            cells.append(f"<td{cls}>{e(_fmt(v))}</td>")
        parts.append("<tr>" + "".join(cells) + "</tr>")
    parts.append("</table></div>")

    parts.append("<h2>Figures</h2>")
    with style.context():
        for name, fig, why in render_study(study):
            if fig is None:
                result.skipped.append((name, why))
                continue
            result.figures.append(name)
            parts.append(figure_html(name, fig, " against the varied keys (mean over the seeds)"))
    if not result.figures:
        parts.append('<p class="note">No figure: no summary scalar differs between completed members.</p>')
    parts.extend(skipped_html(result.skipped))
    parts.append("<h2>study.toml</h2>")
    parts.append(f"<pre>{e(study.definition_text)}</pre>")
    parts.append(f"<script>{SCRIPT}</script>")
    parts.append("</body></html>")
    return "\n".join(parts) + "\n", result


def write_study_report(study: StudyData, out_file: str | Path | None = None) -> StudyReportResult:
    """Write the report of ``study`` to ``out_file`` (default ``STUDY/report.html``), atomically."""
    from ..io.atomic import write_text_atomic

    out = Path(out_file) if out_file is not None else study.path / "report.html"
    if out.exists() and out.is_dir():
        raise CaseError(f"--out {str(out)!r} is a folder; give a file name such as report.html")
    text, result = build_study_report(study)
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        write_text_atomic(out, text)
    except OSError as err:
        raise CaseError(f"--out {str(out)!r}: cannot write the report: {err.strerror or err}") from None
    result.path = out
    return result
