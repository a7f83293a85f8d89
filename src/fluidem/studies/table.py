"""Where each member of a study stands, read from its run directory, and ``study.csv``, one row per member.

A member's state comes from its folder alone, so the table can be rebuilt at any time (after a crash
of the sweep too):

=============  ==============================================================================
status         the member's folder
=============  ==============================================================================
completed      ``summary.json`` with status ``completed``
failed         ``summary.json`` with any other final status (an error): its reason is the error
interrupted    a checkpoint (``restart.h5``) and ``case.toml`` without a final summary, or a
               summary with status ``interrupted`` / ``stopped``: resumed from the checkpoint
pending        no folder, or one without a checkpoint (started afresh)
=============  ==============================================================================

Columns of ``study.csv``: ``member`` (the folder name), the varied keys (dotted names), ``seed`` when
the study has seeds, ``status``, ``error``, then every scalar of the members' ``summary.json`` in the
order they first appear (a nested object's scalars as ``outer.inner``; lists are left out).
"""
from __future__ import annotations

import csv
import io
import json
from dataclasses import dataclass, field
from pathlib import Path

from ..io.atomic import write_text_atomic
from ..io.restart import RESTART_NAME
from ..io.summary import SUMMARY_FILE, read_summary, summary_json
from .definition import SEED_LABEL, TABLE_FILE, StudyDefinition

RESUMABLE = ("interrupted", "stopped", "running", "created")
STATUSES = ("completed", "failed", "interrupted", "pending")


@dataclass
class MemberState:
    """``status`` (one of ``STATUSES``), ``error`` (failed members) and the summary read (or {})."""

    status: str
    error: str = ""
    summary: dict = field(default_factory=dict)


def member_state(path: str | Path) -> MemberState:
    """The state of the member whose run directory is ``path`` (see the module's table)."""
    path = Path(path)
    resumable = (path / RESTART_NAME).is_file() and (path / "case.toml").is_file()
    summary: dict = {}
    if (path / SUMMARY_FILE).is_file():
        try:
            summary = read_summary(path)
        except (OSError, ValueError):
            summary = {}
    status = str(summary.get("status", "")) if summary else ""
    if status == "completed":
        return MemberState("completed", summary=summary)
    if status and status not in RESUMABLE:
        error = summary.get("error") or summary.get("reason") or status
        return MemberState("failed", error=str(error).removeprefix("error: "), summary=summary)
    if resumable:
        return MemberState("interrupted", summary=summary)
    return MemberState("pending")


def record_failure(path: str | Path, case_name: str, error: str) -> None:
    """Write a ``summary.json`` with status ``failed`` and ``error`` into the member's folder, unless the
    run already recorded its own failure there (a run that blew up writes its reason and its figures)."""
    path = Path(path)
    if member_state(path).status == "failed":
        return
    path.mkdir(parents=True, exist_ok=True)
    previous = {}
    try:
        previous = read_summary(path) if (path / SUMMARY_FILE).is_file() else {}
    except (OSError, ValueError):
        pass
    summary = {"case": case_name, **{k: v for k, v in previous.items() if k not in ("status", "error")},
               "status": "failed", "error": error}
    write_text_atomic(path / SUMMARY_FILE, summary_json(summary))


def _scalars(summary: dict, prefix: str = "") -> dict:
    out = {}
    for key, value in summary.items():
        if isinstance(value, dict):
            out.update(_scalars(value, f"{prefix}{key}."))
        elif value is None or isinstance(value, (bool, int, float, str)):
            out[f"{prefix}{key}"] = value
    return out


def study_rows(study: StudyDefinition, folder: str | Path) -> tuple[list[str], list[dict]]:
    """The columns and rows of ``study.csv`` for the study in ``folder``, read from the members' folders."""
    folder = Path(folder)
    rows, extra = [], []
    for member in study.members():
        state = member_state(folder / member.name)
        row = {"member": member.name}
        row.update({k: member.overrides.get(k) for k in study.keys})
        if study.seeds is not None:
            row[SEED_LABEL] = member.seed
        row.update(status=state.status, error=state.error)
        for key, value in _scalars(state.summary).items():
            if key in ("status", "error") or key in row:
                continue
            row[key] = value
            if key not in extra:
                extra.append(key)
        rows.append(row)
    columns = ["member", *study.keys, *([SEED_LABEL] if study.seeds is not None else []), "status", "error", *extra]
    return columns, rows


def _cell(value) -> str:
    if value is None:
        return ""
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, (list, dict)):
        return json.dumps(value)
    return str(value)


def table_text(columns: list[str], rows: list[dict]) -> str:
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(columns)
    for row in rows:
        writer.writerow([_cell(row.get(c)) for c in columns])
    return buf.getvalue()


def write_table(study: StudyDefinition, folder: str | Path) -> tuple[list[str], list[dict]]:
    """Rebuild ``study.csv`` in ``folder`` from the members' folders (atomically); returns its columns and rows."""
    columns, rows = study_rows(study, folder)
    write_text_atomic(Path(folder) / TABLE_FILE, table_text(columns, rows), durable=False)
    return columns, rows


def status_counts(rows: list[dict]) -> dict[str, int]:
    return {s: sum(1 for r in rows if r["status"] == s) for s in STATUSES}
