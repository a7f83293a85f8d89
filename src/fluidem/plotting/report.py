"""One self-contained HTML page per run (``fluidem report``).

The page holds the case (``case.toml`` as written by the run), the summary table, for
built-in seed cases the table "quantity | published | this run" (``published.py``),
every figure that applies (PNG embedded as base64) and a note for each figure skipped.
It loads nothing from outside: no links, fonts, scripts or images from files or the
network. A small inline script marks ``<body data-images-total data-images-ok>`` once
the page has loaded, so a headless browser can confirm every image decoded.
"""
from __future__ import annotations

import base64
import html
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import CaseError
from . import style
from .compare import _fmt
from .figures import PlotOptions, render
from .published import comparison_rows
from .run import RunData

REPORT_DPI = 110

CSS = """
body { font-family: system-ui, -apple-system, "Segoe UI", Roboto, sans-serif; margin: 2em auto;
       max-width: 72em; padding: 0 1.5em; color: #1d1d1d; line-height: 1.45; }
h1 { font-size: 1.6em; margin-bottom: 0.2em; } h2 { font-size: 1.25em; margin-top: 1.8em;
     border-bottom: 1px solid #ddd; padding-bottom: 0.2em; }
.sub { color: #555; margin-top: 0; }
table { border-collapse: collapse; margin: 0.5em 0; font-size: 0.92em; }
th, td { border: 1px solid #d0d0d0; padding: 0.25em 0.6em; text-align: left; vertical-align: top; }
th { background: #f2f2f2; } td.num { text-align: right; font-variant-numeric: tabular-nums; }
pre { background: #f7f7f7; border: 1px solid #e0e0e0; padding: 0.8em; overflow-x: auto; font-size: 0.85em; }
figure { margin: 1.2em 0; } figure img { max-width: 100%; height: auto; border: 1px solid #eee; }
figcaption { color: #444; font-size: 0.9em; }
.note { color: #7a4b00; }
"""

# Records, once the page has loaded, how many images there are and how many decoded.
SCRIPT = """
window.addEventListener("load", function () {
  var imgs = Array.prototype.slice.call(document.images);
  var ok = imgs.filter(function (im) { return im.complete && im.naturalWidth > 0; }).length;
  document.body.setAttribute("data-images-total", String(imgs.length));
  document.body.setAttribute("data-images-ok", String(ok));
});
"""


@dataclass
class ReportResult:
    path: Path
    figures: list[str] = field(default_factory=list)
    skipped: list[tuple[str, str]] = field(default_factory=list)


def _flatten(data, prefix=""):
    out = {}
    if isinstance(data, dict):
        for k, v in data.items():
            out.update(_flatten(v, f"{prefix}{k}."))
    elif isinstance(data, list) and data and all(isinstance(x, dict) for x in data):
        for i, v in enumerate(data):
            out.update(_flatten(v, f"{prefix}{i}."))
    else:
        out[prefix[:-1]] = data
    return out


def builtin_differences(run: RunData) -> tuple[list[str], float | None] | None:
    """How the run's case differs from the built-in case of the same name (keys the built-in
    sets; time and output keys left out), and the built-in's end time; None when the case is
    not built in."""
    from ..case import builtin_cases

    path = builtin_cases().get(run.case_name)
    if path is None:
        return None
    try:
        builtin = tomllib.loads(Path(path).read_text())
    except (OSError, tomllib.TOMLDecodeError):
        return None
    ours = _flatten(run.case)
    diffs = []
    for key, value in _flatten(builtin).items():
        if key.split(".")[0] in ("time", "output", "description", "threads"):
            continue
        if ours.get(key) != value:
            diffs.append(f"{key} = {ours.get(key)!r} (built-in: {value!r})")
    end = builtin.get("time", {}).get("end")
    return diffs, (float(end) if isinstance(end, (int, float)) else None)


def figure_html(name: str, fig, caption: str) -> str:
    """A figure of a report page: the PNG embedded (the page stays one file), with its caption (HTML)."""
    data = base64.b64encode(style.png_bytes(fig, dpi=REPORT_DPI)).decode("ascii")
    e = html.escape
    return (f'<figure id="fig-{e(name)}"><img alt="{e(name)}" src="data:image/png;base64,{data}">'
            f"<figcaption><b>{e(name)}</b>{caption}</figcaption></figure>")


def skipped_html(skipped: list[tuple[str, str]]) -> list[str]:
    """The list of figures a page left out, each with its one-line reason (empty: none)."""
    if not skipped:
        return []
    e = html.escape
    return ["<p>Skipped:</p><ul>", *(f'<li class="note">{e(name)}: {e(why)}</li>' for name, why in skipped), "</ul>"]


def build_report(run: RunData, options: PlotOptions | None = None) -> tuple[str, ReportResult]:
    """The report page as HTML text, and what went into it."""
    options = options or PlotOptions()
    result = ReportResult(path=Path())
    e = html.escape
    summary = run.summary
    parts = [
        "<!DOCTYPE html>", '<html lang="en">', "<head>", '<meta charset="utf-8">',
        '<meta name="viewport" content="width=device-width, initial-scale=1">',
        f"<title>fluidem report: {e(run.name)}</title>", f"<style>{CSS}</style>", "</head>", "<body>",
        f"<h1>fluidem report: {e(run.name)}</h1>",
    ]
    status = summary.get("status", "?") if summary else "no summary.json"
    desc = run.case.get("description", "")
    parts.append(f'<p class="sub">case <b>{e(run.case_name or "?")}</b> · status <b>{e(str(status))}</b>'
                 + (f" · {e(str(desc))}" if desc else "") + "</p>")

    # published numbers first: the question a report of a seed case answers
    rows = comparison_rows(run.case_name, summary, run.case)
    if rows:
        parts.append("<h2>Published results</h2>")
        diff = builtin_differences(run)
        notes = []
        if diff is not None:
            changed, end = diff
            if changed:
                notes.append("This run differs from the built-in case in: " + "; ".join(changed) + ".")
            t = (summary or {}).get("sim_time_s")
            if end is not None and isinstance(t, (int, float)) and t < end * (1 - 1e-6):
                notes.append(f"This run stopped at t = {t:.4g} s; the built-in case runs to {end:g} s, "
                             "and the published values are for a full run (its end state, or Sun's 5–10 s means).")
        for n in notes:
            parts.append(f'<p class="note">{e(n)}</p>')
        parts.append("<table><tr><th>quantity</th><th>published</th><th>this run</th></tr>")
        for q, pub, ours in rows:
            parts.append(f"<tr><td>{e(q)}</td><td>{e(pub)}</td><td>{e(ours)}</td></tr>")
        parts.append("</table>")

    parts.append("<h2>Summary</h2>")
    if summary:
        parts.append("<table><tr><th>quantity</th><th>value</th></tr>")
        for k, v in summary.items():
            cls = ' class="num"' if isinstance(v, (int, float)) and not isinstance(v, bool) else ""
            parts.append(f"<tr><td>{e(str(k))}</td><td{cls}>{e(_fmt(v))}</td></tr>")
        parts.append("</table>")
    else:
        parts.append('<p class="note">The run has no readable summary.json (still running, or stopped '
                     "before its first summary).</p>")

    parts.append("<h2>Figures</h2>")
    with style.context():
        for spec, fig, why in render(run, options):
            if fig is None:
                result.skipped.append((spec.name, why))
                continue
            result.figures.append(spec.name)
            parts.append(figure_html(spec.name, fig, f": {e(spec.description)}"))
    if not result.figures:
        parts.append('<p class="note">No figure applies to this run.</p>')
    parts.extend(skipped_html(result.skipped))

    parts.append("<h2>Case</h2>")
    parts.append(f"<p>The case as resolved by the run (<code>{e(str(run.path / 'case.toml'))}</code>):</p>")
    parts.append(f"<pre>{e(run.case_text)}</pre>")
    parts.append(f"<script>{SCRIPT}</script>")
    parts.append("</body></html>")
    return "\n".join(parts) + "\n", result


def write_report(run: RunData, out_file: str | Path | None = None, options: PlotOptions | None = None) -> ReportResult:
    """Write the report of ``run`` to ``out_file`` (default ``RUN/report.html``), atomically."""
    from ..io.atomic import write_text_atomic

    out = Path(out_file) if out_file is not None else run.path / "report.html"
    if out.exists() and out.is_dir():
        raise CaseError(f"--out {str(out)!r} is a folder; give a file name such as report.html")
    text, result = build_report(run, options)
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        write_text_atomic(out, text)
    except OSError as err:
        raise CaseError(f"--out {str(out)!r}: cannot write the report: {err.strerror or err}") from None
    result.path = out
    return result

