"""What a study is: a base case, the keys it varies with their values, the seeds, the end time; and
the members that follow from them, each a name (its folder) and the overrides of its case.

Plain Python, no Dask: ``StudyDefinition.build`` checks the input and validates every member's case
before anything is written (``CaseError`` naming the key, the value and the member), ``members()``
lists them in a fixed order, and ``to_toml`` / ``from_toml`` write and read ``study.toml``, which
``differences`` compares with the study a rerun asks for.
"""
from __future__ import annotations

import itertools
import math
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import tomli_w

from ..case import apply_overrides, parse_value, read_case_data, validate_case
from ..errors import CaseError

STUDY_FILE = "study.toml"
TABLE_FILE = "study.csv"
SEED_KEY = "particles.placement.seed"  # the seed of placement and size draws (``Placement.seed``)
SEED_LABEL = "seed"
COMBINES = ("product", "zip")
EXECUTION_KEYS = ("threads",)  # case keys that change how a member runs, not what it computes
MAX_ERRORS_SHOWN = 6


@dataclass(frozen=True)
class Member:
    """One run of a study: ``name`` is its folder under the study, ``overrides`` the dotted case keys it
    sets on top of the base case (the varied keys, then the seed key)."""

    name: str
    overrides: dict[str, Any]
    seed: int | None = None


def parse_vary(items: list[str]) -> dict[str, list]:
    """``["a.b=1,2,3", "c=x,y"]`` → ``{"a.b": [1, 2, 3], "c": ["x", "y"]}``.

    Values are read as ``--set`` reads them (TOML numbers, booleans, quoted strings, arrays; bare words
    are strings). The list is read as one TOML array where it is one (so ``[1,2],[3,4]`` gives two
    arrays), else split at the commas."""
    out: dict[str, list] = {}
    for item in items or []:
        if "=" not in item:
            raise CaseError(f"--vary {item!r}: expected KEY=V1,V2,..., e.g. --vary particles.contact.restitution=0.8,0.9")
        key, text = (s.strip() for s in item.split("=", 1))
        if not key:
            raise CaseError(f"--vary {item!r}: the key is empty")
        if key in out:
            raise CaseError(f"--vary {key}: given twice; give all its values in one --vary {key}=V1,V2,...")
        try:
            values = tomllib.loads(f"v = [{text}]")["v"]
        except tomllib.TOMLDecodeError:
            values = [parse_value(v.strip()) for v in text.split(",")]
        if not text or any(v == "" for v in values):
            raise CaseError(f"--vary {item!r}: give one or more values separated by commas, e.g. {key}=0.8,0.9")
        out[key] = values
    return out


def parse_seeds(text: str | int | list | None) -> list[int] | None:
    """``--seeds``: a count N (seeds 1..N) or a comma-separated list of seeds; None: the case's own seed."""
    if text is None:
        return None
    if isinstance(text, bool):
        raise CaseError(f"--seeds {text!r}: give a count, e.g. 3, or a list of seeds, e.g. 7,11,13")
    if isinstance(text, int):
        items: list = [text]
        count = True
    elif isinstance(text, (list, tuple)):
        items, count = list(text), False
    else:
        items = [s.strip() for s in str(text).split(",")]
        count = len(items) == 1
    try:
        values = [int(s) for s in items]
    except (TypeError, ValueError):
        raise CaseError(f"--seeds {text!r}: give a count, e.g. 3, or a list of whole numbers, e.g. 7,11,13") from None
    if count:
        if values[0] < 1:
            raise CaseError(f"--seeds {text!r}: a count of seeds is at least 1")
        return list(range(1, values[0] + 1))
    if len(set(values)) != len(values):
        raise CaseError(f"--seeds {text!r}: a seed is repeated")
    return values


def _same(a, b) -> bool:
    """Equal as case values: 1 and 1.0 alike, but true and 1 not."""
    if isinstance(a, bool) or isinstance(b, bool):
        return type(a) is type(b) and a == b
    return a == b


def format_value(value) -> str:
    """A value as it appears in a member's folder name: ``0.8``, ``0``, ``1e-05``, ``true``, ``hertz``."""
    if isinstance(value, bool):
        text = "true" if value else "false"
    elif isinstance(value, float):
        text = repr(value)
    elif isinstance(value, (list, tuple)):
        text = "-".join(format_value(v) for v in value)
    else:
        text = str(value)
    return re.sub(r"[^A-Za-z0-9.+\-]", "-", text) or "-"


def key_labels(keys: list[str]) -> dict[str, str]:
    """Short names of dotted keys for folder names: the last part, with more parts where two would clash
    (``particles.contact.friction`` → ``friction``)."""
    depth = {k: 1 for k in keys}
    while True:
        labels = {k: ".".join(k.split(".")[-depth[k]:]) for k in keys}
        clashes = [k for k in keys if list(labels.values()).count(labels[k]) > 1 and depth[k] < len(k.split("."))]
        if not clashes:
            return labels
        for k in clashes:
            depth[k] += 1


@dataclass
class StudyDefinition:
    """A study: what ``study.toml`` records and what a rerun must repeat.

    Parameters
    ----------
    case : the CASE argument (a built-in name or a TOML path) as given.
    base : the resolved base case as TOML data: the case with ``--set`` and the end time applied,
        every default filled in, without the execution keys (``threads``).
    vary : dotted key → its values, in the order given.
    seeds : the placement seeds (``particles.placement.seed``) each combination runs with; None: the
        case's own seed.
    combine : ``"product"`` (every combination) or ``"zip"`` (the i-th value of every key together).
    until : the end time of every member [s].
    """

    case: str
    base: dict
    vary: dict[str, list]
    seeds: list[int] | None = None
    combine: str = "product"
    until: float = 0.0
    threads: int = 1  # compute threads of each member (not part of the definition's identity)
    _members: list[Member] | None = field(default=None, repr=False, compare=False)

    # ------------------------------------------------------------ building
    @classmethod
    def build(cls, case, vary: dict[str, list], seeds: list[int] | None = None, combine: str = "product",
              until: float | None = None, overrides: dict[str, Any] | None = None,
              threads: int | None = None) -> "StudyDefinition":
        """Check the study and validate every member's case; raises ``CaseError`` (nothing is written).

        ``case`` is a built-in name, a TOML path or a ``fluidem.Case``; ``overrides`` are ``--set``'s
        dotted keys, applied to every member; ``threads`` the compute threads of each member (default:
        the case's ``threads`` key, else 1)."""
        from ..case import Case

        if combine not in COMBINES:
            raise CaseError(f"combine = {combine!r}: allowed are {', '.join(COMBINES)}")
        vary = {str(k): list(v) if isinstance(v, (list, tuple)) else [v] for k, v in (vary or {}).items()}
        if not vary and not seeds:
            raise CaseError("fluidem sweep needs at least one --vary KEY=V1,V2,... (or --seeds)")
        for key, values in vary.items():
            if not values:
                raise CaseError(f"--vary {key}: give at least one value")
            for i, a in enumerate(values):
                if any(_same(a, b) for b in values[:i]):
                    raise CaseError(f"--vary {key}: the value {a!r} is given twice")
        overrides = dict(overrides or {})
        for key in vary:
            if key in overrides:
                raise CaseError(f"--vary {key} and --set {key} both set this key; give it in one place")
            if key in EXECUTION_KEYS:
                raise CaseError(f"--vary {key}: the compute threads change how a member runs, not what it "
                                "computes; give --threads instead")
            if key == "time.end" and until is not None:
                raise CaseError("--vary time.end and --until both set the end time; give it in one place")
        if seeds is not None and (SEED_KEY in vary or SEED_KEY in overrides):
            raise CaseError(f"--seeds and a --vary/--set of {SEED_KEY} both set the placement seed; "
                            "give it in one place")
        if combine == "zip":
            lengths = {k: len(v) for k, v in vary.items()}
            if len(set(lengths.values())) > 1:
                raise CaseError("--zip pairs the i-th values of every --vary key, so each needs as many values; "
                                "given: " + ", ".join(f"{k} ({n})" for k, n in lengths.items()))
        if until is not None:
            if not (isinstance(until, (int, float)) and math.isfinite(until) and until > 0):
                raise CaseError(f"--until {until!r}: must be a positive number of simulated seconds")
            overrides["time.end"] = float(until)

        if isinstance(case, Case):
            data = case.model_dump(mode="json", exclude_none=True)
            case_arg = case.name
        else:
            data = read_case_data(case)
            case_arg = str(Path(case).resolve()) if Path(case).exists() else str(case)
        apply_overrides(data, overrides)
        base_case = validate_case(data)
        n_threads = threads if threads is not None else (base_case.threads or 1)
        if not (isinstance(n_threads, int) and n_threads >= 1):
            raise CaseError(f"--threads {n_threads!r}: give a whole number of at least 1")
        base = base_case.model_dump(mode="json", exclude_none=True)
        for key in EXECUTION_KEYS:
            base.pop(key, None)
        study = cls(case=case_arg, base=_toml_round_trip(base), vary=vary, seeds=seeds, combine=combine,
                    until=float(base_case.time.end), threads=int(n_threads))
        study._check_keys()
        study._check_members()
        return study

    def _check_keys(self) -> None:
        """Each varied value alone on the base case: an unknown key or a refused value names the key."""
        for key, values in self.vary.items():
            for value in values:
                try:
                    self.member_case({key: value})
                except CaseError as err:
                    raise CaseError(f"--vary {key}={format_value(value)}: {err}") from None

    def _check_members(self) -> None:
        """Every member's case (values that are fine alone may clash together)."""
        problems = []
        for m in self.members():
            try:
                self.member_case(m.overrides)
            except CaseError as err:
                problems.append(f"member {m.name}: {err}")
        if problems:
            more = len(problems) - MAX_ERRORS_SHOWN
            raise CaseError("\n".join(problems[:MAX_ERRORS_SHOWN]) + (f"\n... and {more} more members" if more > 0 else ""))

    # ------------------------------------------------------------ members
    @property
    def keys(self) -> list[str]:
        return list(self.vary)

    def combinations(self) -> list[tuple]:
        """The value tuples of the varied keys, in order (the product, or the zip, of the value lists)."""
        lists = list(self.vary.values())
        if not lists:
            return [()]
        if self.combine == "zip":
            return list(zip(*lists))
        return list(itertools.product(*lists))

    def members(self) -> list[Member]:
        """Every member, the varied keys' combinations in order with the seeds innermost."""
        if self._members is not None:
            return self._members
        labels = key_labels(self.keys)
        out = []
        for combo in self.combinations():
            for seed in (self.seeds if self.seeds is not None else [None]):
                overrides = dict(zip(self.keys, combo))
                parts = [f"{labels[k]}={format_value(v)}" for k, v in overrides.items()]
                if seed is not None:
                    overrides[SEED_KEY] = seed
                    parts.append(f"{SEED_LABEL}={seed}")
                out.append(Member(name="_".join(parts), overrides=overrides, seed=seed))
        names = [m.name for m in out]
        if len(set(names)) != len(names):
            dup = next(n for n in names if names.count(n) > 1)
            raise CaseError(f"two members would share the folder name {dup!r}; give values that differ "
                            "in their written form")
        self._members = out
        return out

    def member_case(self, overrides: dict[str, Any]):
        """The validated ``Case`` of a member (the base case with ``overrides`` and the member threads)."""
        data = _toml_round_trip(self.base)
        apply_overrides(data, {**overrides, "threads": self.threads})
        return validate_case(data)

    # ------------------------------------------------------------ study.toml
    def identity(self) -> dict:
        """What makes two studies the same study (a rerun must match it)."""
        return _toml_round_trip({"base_case": self.base, "vary": self.vary, "combine": self.combine,
                                 "until": self.until, **({"seeds": self.seeds} if self.seeds is not None else {})})

    def to_toml(self) -> str:
        from .. import __version__

        head = {"case": self.case, "case_name": self.base.get("name", ""), "combine": self.combine,
                "until": self.until}
        if self.seeds is not None:
            head.update(seeds=self.seeds, seed_key=SEED_KEY)
        head.update(threads=self.threads, fluidem_version=__version__)
        body = {"vary": self.vary,
                "members": [{"name": m.name, "overrides": m.overrides} for m in self.members()],
                "base_case": self.base}
        return ("# fluidem sweep: the study's definition. Each member is a run directory named in [[members]],\n"
                "# its case the base case with the member's overrides; study.csv has one row per member.\n"
                + tomli_w.dumps(head) + "\n" + tomli_w.dumps(body))

    @classmethod
    def from_toml(cls, text: str) -> "StudyDefinition":
        data = tomllib.loads(text)
        try:
            study = cls(case=str(data["case"]), base=data["base_case"], vary=dict(data.get("vary", {})),
                        seeds=data.get("seeds"), combine=data.get("combine", "product"), until=float(data["until"]),
                        threads=int(data.get("threads", 1)))
        except (KeyError, TypeError, ValueError) as err:
            raise CaseError(f"{STUDY_FILE}: not a fluidem study definition ({err})") from None
        members = data.get("members")
        if isinstance(members, list) and all(isinstance(m, dict) and "name" in m for m in members):
            study._members = [Member(name=str(m["name"]), overrides=dict(m.get("overrides", {})),
                                     seed=m.get("overrides", {}).get(SEED_KEY) if study.seeds is not None else None)
                              for m in members]
        return study

    def differences(self, other: "StudyDefinition") -> list[str]:
        """How ``other`` (the study found on disk) differs from this one, one line per item."""
        a, b = self.identity(), other.identity()
        out = []
        for key, what in (("vary", "--vary"), ("combine", "--zip"), ("seeds", "--seeds"), ("until", "--until")):
            if a.get(key) != b.get(key):
                out.append(f"{what}: {_show(b.get(key))} there, {_show(a.get(key))} now")
        if a["base_case"] != b["base_case"]:
            changed = _changed_keys(b["base_case"], a["base_case"])
            out.append("the base case (CASE and --set): " + "; ".join(changed[:MAX_ERRORS_SHOWN])
                       + ("; ..." if len(changed) > MAX_ERRORS_SHOWN else ""))
        return out


def _show(value) -> str:
    if value is None:
        return "none"
    if isinstance(value, dict):
        return ", ".join(f"{k}={','.join(format_value(v) for v in vs)}" for k, vs in value.items()) or "none"
    return str(value)


def _flat(data, prefix="") -> dict:
    out = {}
    if isinstance(data, dict):
        for k, v in data.items():
            out.update(_flat(v, f"{prefix}{k}."))
    elif isinstance(data, list) and data and all(isinstance(x, dict) for x in data):
        for i, v in enumerate(data):
            out.update(_flat(v, f"{prefix}{i}."))
    else:
        out[prefix[:-1]] = data
    return out


def _changed_keys(old: dict, new: dict) -> list[str]:
    a, b = _flat(old), _flat(new)
    return [f"{k} = {a.get(k, 'absent')!r} there, {b.get(k, 'absent')!r} now"
            for k in list(dict.fromkeys([*a, *b])) if a.get(k, "absent") != b.get(k, "absent")]


def _toml_round_trip(data: dict) -> dict:
    """``data`` as TOML would read it back (tuples → lists), so that written and fresh definitions compare."""
    return tomllib.loads(tomli_w.dumps(data))
