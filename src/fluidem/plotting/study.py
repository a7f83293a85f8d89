"""Read a study folder (``fluidem sweep --out STUDY``) for plotting: its definition and one row per member.

``StudyData(path)`` checks that ``path`` holds ``study.toml`` and raises ``CaseError`` otherwise. The
rows are read from the members' folders as ``study.csv`` is made (``studies.table.study_rows``), so a
study still running or stopped shows what is there now. ``scalars()`` lists the numeric summary
columns with their values per member; the figures draw each against the varied keys.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

from ..errors import CaseError
from ..studies.definition import SEED_LABEL, STUDY_FILE, StudyDefinition, format_value, key_labels
from ..studies.table import status_counts, study_rows

NOT_RESULTS = ("member", "status", "error", "case", SEED_LABEL)


def is_study(path: str | Path) -> bool:
    """Whether ``path`` is a study folder (it holds ``study.toml``)."""
    return (Path(path) / STUDY_FILE).is_file()


@dataclass
class Scalar:
    """One summary column of a study: ``values[i]`` of member ``i`` (NaN where the member has none);
    ``boolean`` when the summary holds true/false (drawn as 0/1, averaged to a fraction)."""

    name: str
    values: list[float]
    boolean: bool = False


class StudyData:
    """Read-only view of one study folder.

    Parameters
    ----------
    path : the study folder (``fluidem sweep --out STUDY``).
    """

    def __init__(self, path: str | Path):
        self.path = Path(path)
        if not self.path.is_dir():
            raise CaseError(f"study folder {str(path)!r} does not exist or is not a folder")
        definition = self.path / STUDY_FILE
        if not definition.is_file():
            raise CaseError(f"{str(path)!r} is not a study: it has no {STUDY_FILE} (made by `fluidem sweep`)")
        try:
            self.definition_text = definition.read_text()
            self.definition = StudyDefinition.from_toml(self.definition_text)
        except (OSError, UnicodeDecodeError, ValueError) as err:
            raise CaseError(f"{str(definition)!r} cannot be read: {err}") from None
        self.columns, self.rows = study_rows(self.definition, self.path)

    @property
    def name(self) -> str:
        return self.path.resolve().name or str(self.path)

    @property
    def keys(self) -> list[str]:
        """The varied keys, in the order given."""
        return self.definition.keys

    @property
    def labels(self) -> dict[str, str]:
        """Short names of the varied keys (as in the members' folder names)."""
        return key_labels(self.keys)

    @property
    def counts(self) -> dict[str, int]:
        return status_counts(self.rows)

    @cached_property
    def scalars(self) -> list[Scalar]:
        """Numeric (and true/false) summary columns, in table order, with a value in some member."""
        out = []
        for col in self.columns:
            if col in NOT_RESULTS or col in self.keys:
                continue
            raw = [r.get(col) if r["status"] == "completed" else None for r in self.rows]
            present = [v for v in raw if v is not None]
            if not present or not all(isinstance(v, (int, float)) for v in present):
                continue
            boolean = all(isinstance(v, bool) for v in present)
            values = [float(v) if v is not None else math.nan for v in raw]
            if all(not math.isfinite(v) for v in values):
                continue
            out.append(Scalar(col, values, boolean))
        return out

    def constant(self, scalar: Scalar) -> bool:
        """Whether every member with a value has the same one (nothing to draw against the keys)."""
        finite = {v for v in scalar.values if math.isfinite(v)}
        return len(finite) <= 1 and len(self.rows) > 1

    def level_labels(self, key: str) -> list[str]:
        return [format_value(v) for v in self.definition.vary[key]]

    def combination_of(self, row: dict) -> tuple:
        return tuple(row.get(k) for k in self.keys)
