"""The case-file reference, written from the pydantic schema of ``fluidem.case.Case``.

The schema is the only source: every key, its type, default, allowed values and description come
from the models and their ``Field`` declarations, so the page follows the schema without edits.

``case_reference_markdown()``
    the Markdown of the page ``reference/case.md``;
``schema_keys()``
    the set of dotted keys found by walking the schema (the first column of the page's tables).

Dotted keys follow the case file: ``particles.contact.restitution``; an array of tables adds ``[]``
(``particles.species[].diameter``); a table whose keys are names the user chooses (a ``dict``) adds
``.<name>`` (``gas.boundaries.<name>.kind``). A key whose value is either a number or a table
(a velocity ``1.8`` or ``{pulse = 2.5, ...}``) lists the table's keys below it
(``....interstitial.pulse``). A choice of models (a discriminated union, such as the contact law chosen
by ``model``) gets a section per model.

``registered_models_markdown(kind)``
    a table of the models a registry holds (contact laws, drag laws, gas boundary conditions): name,
    class, what its docstring says first, its keys and its reference test. A physics page places it with
    the comment ``<!-- registered: contact -->`` (``drag``, ``gas``), so a new model appears there without
    an edit to the page.

MkDocs runs this file as a hook (``hooks:`` in ``mkdocs.yml``): ``on_page_markdown`` (``render_page``)
replaces the content of ``reference/case.md`` with the generated page and each registry comment with
its table. The module needs no MkDocs (it imports the
standard library, pydantic and fluidem only), so tests import it directly, and
``python docs/hooks/case_reference.py`` prints the page.
"""
import collections.abc
import html
import inspect
import re
import types
import typing
from dataclasses import dataclass, field
from typing import Any, Literal, Optional, Union

from pydantic import BaseModel
from pydantic.fields import FieldInfo
from pydantic_core import PydanticUndefined

PAGE = "reference/case.md"  # the page whose content this hook writes (path under docs/)
ITEM = "[]"  # suffix of an array of tables: particles.species[].diameter
ENTRY = "<name>"  # key of a table whose keys the user names: gas.boundaries.<name>.kind

_MAX_HEADING = 6


# ------------------------------------------------------------------ reading annotations
@dataclass
class _Type:
    """What an annotation admits, reduced to what the reference shows."""

    kind: str  # "scalar", "model", "choice", "mixed", "array", "mapping"
    text: str = ""  # type as shown ("number", "[number, number]", ...)
    models: list = field(default_factory=list)  # "model": one; "choice", "mixed": the alternatives
    tag: str | None = None  # "choice": the key that selects the model
    element: Optional["_Type"] = None  # "array", "mapping": the type of an item or value
    choices: tuple = ()  # Literal values
    constraints: list = field(default_factory=list)  # annotated_types metadata found inside the annotation
    nullable: bool = False


def _is_model(tp) -> bool:
    return isinstance(tp, type) and issubclass(tp, BaseModel)


def _unwrap(tp) -> tuple[Any, list, str | None]:
    """Strip ``Annotated``: (type, metadata, discriminator)."""
    metadata: list = []
    discriminator = None
    while typing.get_origin(tp) is typing.Annotated:
        args = typing.get_args(tp)
        tp = args[0]
        for m in args[1:]:
            if isinstance(m, FieldInfo):
                metadata += list(m.metadata)
                if isinstance(m.discriminator, str):
                    discriminator = m.discriminator
            else:
                metadata.append(m)
    return tp, metadata, discriminator


def _union_args(tp) -> list | None:
    origin = typing.get_origin(tp)
    if origin is Union or origin is types.UnionType:
        return list(typing.get_args(tp))
    return None


def _tag_of(models: list, hint: str | None) -> str | None:
    """The key that selects one of ``models``: the given discriminator, else the ``Literal`` field all share."""
    if hint:
        return hint
    for name in models[0].model_fields:
        if all(name in m.model_fields and typing.get_origin(_unwrap(m.model_fields[name].annotation)[0]) is Literal
               for m in models):
            return name
    return None


def _literal_text(values: tuple) -> str:
    kinds = {type(v) for v in values}
    if kinds <= {str}:
        return "string"
    if kinds <= {bool}:
        return "boolean"
    if kinds <= {int}:
        return "integer"
    return "number" if kinds <= {int, float} else "value"


_SCALARS = {float: "number", int: "integer", bool: "boolean", str: "string"}


def _classify(tp, discriminator: str | None = None) -> _Type:
    tp, metadata, inner_discriminator = _unwrap(tp)
    discriminator = discriminator or inner_discriminator
    args = _union_args(tp)
    if args is not None:
        nullable = any(a is type(None) for a in args)
        parts = [_classify(a, discriminator) for a in args if a is not type(None)]
        if len(parts) == 1:
            part = parts[0]
            part.nullable = part.nullable or nullable
            part.constraints = metadata + part.constraints
            return part
        models = [p.models[0] for p in parts if p.kind == "model"]
        if len(models) == len(parts) and len(models) > 1:
            tag = _tag_of(models, discriminator)
            if tag is not None:
                return _Type("choice", "table", models=models, tag=tag, constraints=metadata, nullable=nullable)
        texts = []
        for p in parts:
            if p.kind == "model":
                keys = ", ".join(_key_name(n, f) for n, f in p.models[0].model_fields.items())
                texts.append(f"table `{{{keys}}}`")
            elif p.text not in texts:
                texts.append(p.text)
        sub = [m for p in parts if p.kind in ("model", "mixed", "choice") for m in p.models]
        return _Type("mixed", ", or ".join(texts), models=sub, constraints=metadata, nullable=nullable)
    if _is_model(tp):
        return _Type("model", "table", models=[tp], constraints=metadata)
    origin = typing.get_origin(tp)
    if tp is typing.Any:
        return _Type("scalar", "value", constraints=metadata)
    if origin is Literal:
        values = typing.get_args(tp)
        return _Type("scalar", _literal_text(values), choices=values, constraints=metadata)
    if origin is collections.abc.Callable or tp is collections.abc.Callable:
        return _Type("scalar", "function of time t [s] (Python only)", constraints=metadata)
    if origin in (list, tuple, set, frozenset, collections.abc.Sequence):
        items = typing.get_args(tp)
        if origin is tuple and items and items[-1] is not Ellipsis:  # fixed length: a value such as Vec3
            return _Type("scalar", "[" + ", ".join(_classify(a).text for a in items) + "]", constraints=metadata)
        element = _classify(items[0]) if items else _Type("scalar", "value")
        if element.kind in ("model", "choice"):
            return _Type("array", "array of tables", element=element, constraints=metadata)
        return _Type("scalar", f"array of {element.text}", constraints=metadata)
    if origin in (dict, collections.abc.Mapping):
        key_type, value_type = typing.get_args(tp) or (str, Any)
        element = _classify(value_type)
        if element.kind in ("model", "choice"):
            return _Type("mapping", "table of tables", element=element, constraints=metadata)
        return _Type("scalar", f"table of {element.text}", constraints=metadata)
    if tp in _SCALARS:
        return _Type("scalar", _SCALARS[tp], constraints=metadata)
    return _Type("scalar", getattr(tp, "__name__", str(tp)), constraints=metadata)


def _key_name(name: str, info: FieldInfo) -> str:
    return info.alias or name


# ------------------------------------------------------------------ values shown
def _value(v) -> str:
    """A value as written in a case file (TOML)."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, float):
        return repr(v)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{k} = {_value(x)}" for k, x in v.items()) + "}"
    return str(v)


def _constraint_text(c, unit: str = "item") -> str | None:
    symbols = (("gt", ">"), ("ge", "≥"), ("lt", "<"), ("le", "≤"))
    for attr, sym in symbols:
        if hasattr(c, attr) and type(c).__name__.lower() == attr:
            return f"{sym} {_value(getattr(c, attr))}"
    name = type(c).__name__
    if name == "MinLen":
        return f"at least {c.min_length} {unit}{'s' if c.min_length != 1 else ''}"
    if name == "MaxLen":
        return f"at most {c.max_length} {unit}{'s' if c.max_length != 1 else ''}"
    if name == "MultipleOf":
        return f"multiple of {_value(c.multiple_of)}"
    if isinstance(getattr(c, "pattern", None), str):  # pydantic's general metadata of Field(pattern=...)
        return f"matches `{c.pattern}`"
    return None


def _allowed(info: FieldInfo, t: _Type) -> str:
    parts = []
    if t.kind == "choice":
        parts.append(f"one model by `{t.tag}`, below")
    if t.choices:
        parts.append(", ".join(f"`{_value(v)}`" for v in t.choices))
    for c in list(info.metadata) + t.constraints:
        text = _constraint_text(c, "character" if t.text == "string" else "item")
        if text and text not in parts:
            parts.append(text)
    return "; ".join(parts)


def _default(info: FieldInfo, t: _Type) -> str:
    if info.default is PydanticUndefined and info.default_factory is None:
        return "required"
    try:
        if info.default_factory is not None:
            value = info.default_factory({}) if _factory_takes_data(info) else info.default_factory()
        else:
            value = info.default
    except Exception:  # a factory that needs the rest of the case: say so rather than guess
        return "computed"
    if value is None:
        return "not set"
    if isinstance(value, BaseModel):
        if t.kind == "choice" and t.tag and t.tag in type(value).model_fields:
            return f"`{_value(getattr(value, t.tag))}`"
        return "defaults below"
    return f"`{_value(value)}`"


def _factory_takes_data(info: FieldInfo) -> bool:
    flag = getattr(info, "default_factory_takes_data", None)
    if flag is not None:
        return bool(flag)
    try:
        return len(inspect.signature(info.default_factory).parameters) == 1
    except (TypeError, ValueError):
        return False


def _own_doc(model: type[BaseModel]) -> str:
    """The model's own docstring (not one inherited from ``BaseModel``)."""
    return inspect.cleandoc(model.__dict__.get("__doc__") or "")


def _docstring_entries(model: type[BaseModel]) -> dict[str, str]:
    """Descriptions given in a model's docstring, NumPy style (``name : type`` + indented text) or one line
    each (``name : text``); used for fields declared without ``description``."""
    doc = _own_doc(model)
    lines = doc.splitlines()
    out: dict[str, str] = {}
    head = re.compile(r"^(\w+(?:\s*,\s*\w+)*)\s+:\s*(.*)$")
    for k, line in enumerate(lines):
        m = head.match(line)
        if not m:
            continue
        body = []
        for nxt in lines[k + 1:]:
            if nxt.startswith((" ", "\t")) and nxt.strip():
                body.append(nxt.strip())
            else:
                break
        text = " ".join(body) if body else m.group(2)
        text = re.sub(r"\s*\((?:see )?(?:the )?module docstring\)", "", text)  # a pointer into the source
        if re.fullmatch(r'(?:"[^"]*"\s*\|?\s*)+', text):  # only the choices, which the table lists anyway
            text = ""
        for name in re.split(r"\s*,\s*", m.group(1)):
            out.setdefault(name, text)
    return out


def _first_paragraph(model: type[BaseModel] | None) -> str:
    doc = _own_doc(model) if model is not None else ""
    return " ".join(doc.split("\n\n", 1)[0].split())


def _cell(text: str) -> str:
    """Text safe inside a table cell; ``code spans`` are kept as they are."""
    pieces = re.split(r"(`[^`]*`)", text)
    out = []
    for p in pieces:
        if p.startswith("`") and p.endswith("`") and len(p) > 1:
            out.append(p.replace("|", "\\|"))
        else:
            text = html.escape(p, quote=False).replace("\n", " ")
            for ch in "\\|*_[]":  # Markdown punctuation: tables, emphasis, links
                text = text.replace(ch, "\\" + ch)
            out.append(text)
    return "".join(out)


def _description(text: str) -> str:
    """A description as Markdown: double backticks (reST literals) become code spans."""
    return _cell(re.sub(r"``([^`]+)``", r"`\1`", " ".join(text.split())))


# ------------------------------------------------------------------ walking the schema
@dataclass
class Row:
    key: str
    type: str
    default: str
    allowed: str
    description: str


@dataclass
class Section:
    """A heading, a paragraph, a table of rows, and the sections below it (the models of a choice)."""

    title: str
    level: int
    text: str = ""
    rows: list[Row] = field(default_factory=list)
    children: list["Section"] = field(default_factory=list)


def _fields(model: type[BaseModel]):
    notes = None
    for name, info in model.model_fields.items():
        description = info.description
        if not description:
            notes = _docstring_entries(model) if notes is None else notes
            description = notes.get(name, "")
        yield _key_name(name, info), info, description


def _walk_model(model: type[BaseModel], prefix: str, section: Section, stack: tuple, tag: str | None = None,
                tag_value: str | None = None) -> None:
    """Rows of every key of ``model`` under ``prefix`` into ``section``; choices become child sections."""
    if model in stack:  # a model that holds itself: list it once
        return
    stack = stack + (model,)
    fields = sorted(_fields(model), key=lambda f: f[0] != tag)  # the selecting key first
    for key, info, description in fields:
        path = f"{prefix}.{key}" if prefix else key
        if key == tag and tag_value is not None:
            section.rows.append(Row(path, "string", "required", f"`{_value(tag_value)}`",
                                    _description(description or "selects this model")))
            continue
        t = _classify(info.annotation, info.discriminator if isinstance(info.discriminator, str) else None)
        _add(path, info, t, _description(description or _first_paragraph(_target(t))), section, stack)


def _target(t: _Type) -> type[BaseModel] | None:
    """The one model a key holds (a table, or the items or values of a table array or mapping)."""
    if t.kind == "model":
        return t.models[0]
    if t.kind in ("array", "mapping") and t.element is not None and t.element.kind == "model":
        return t.element.models[0]
    return None


def _add(path: str, info: FieldInfo | None, t: _Type, description: str, section: Section, stack: tuple) -> None:
    known = {r.key for r in section.rows}
    if info is not None and path not in known:
        shown = t.text + (" (or not set)" if t.nullable and _default(info, t) != "not set" else "")
        section.rows.append(Row(path, _cell(shown), _default(info, t), _allowed(info, t), description))
    if t.kind == "model":
        _walk_model(t.models[0], path, section, stack)
    elif t.kind == "mixed":
        for model in t.models:
            _walk_model(model, path, section, stack)
    elif t.kind == "choice":
        section.children.append(_choice_section(path, t, section.level + 1, stack))
    elif t.kind in ("array", "mapping"):
        suffix = ITEM if t.kind == "array" else "." + ENTRY
        _add(path + suffix, None, t.element, "", section, stack)


def _choice_section(path: str, t: _Type, level: int, stack: tuple) -> Section:
    values = [m.model_fields[t.tag].default for m in t.models]
    listed = ", ".join(f"`{_value(v)}`" for v in values)
    sec = Section(f"`{path}`: one model, chosen by `{t.tag}`", level,
                  f"`{path}.{t.tag}` is one of {listed}; each model has its own keys, listed below.")
    for model, value in zip(t.models, values):
        sub = Section(f"`{path}` with `{t.tag} = {_value(value)}`", level + 1, _description(_first_paragraph(model)))
        _walk_model(model, path, sub, stack, tag=t.tag, tag_value=value)
        sec.children.append(sub)
    return sec


def _case_model() -> type[BaseModel]:
    from fluidem.case import Case

    return Case


def _sections(case: type[BaseModel] | None = None) -> list[Section]:
    """One section for the top-level values of the case and one per top-level table."""
    case = case or _case_model()
    top = Section("Top level", 2, "Keys outside any table, at the start of the case file.")
    out = [top]
    for key, info, description in _fields(case):
        t = _classify(info.annotation, info.discriminator if isinstance(info.discriminator, str) else None)
        if t.kind == "scalar" or (t.kind == "mixed" and not t.models):
            _add(key, info, t, _description(description), top, (case,))
            continue
        sec = Section(f"`{key}`", 2, _description(_first_paragraph(_target(t))))
        _add(key, info, t, _description(description or _first_paragraph(_target(t))), sec, (case,))
        out.append(sec)
    return out


def _all_rows(sections: list[Section]):
    for s in sections:
        yield from s.rows
        yield from _all_rows(s.children)


def schema_keys() -> set[str]:
    """Every dotted key of the case schema (the keys the reference lists)."""
    return {r.key for r in _all_rows(_sections())}


_INTRO = """\
# Case-file reference

<!-- generated by docs/hooks/case_reference.py from the pydantic schema fluidem.case.Case; do not edit -->

A case file is TOML; every quantity is in SI units, given in brackets in the descriptions ([m], [s], [Pa]).
This page is generated from the schema that validates case files (`fluidem.case.Case`), so it lists
exactly the keys that `fluidem run` accepts. An unknown key, a wrong type or a value outside its range
stops the run before anything is written, with a message that names the key and what is allowed.

How the dotted keys read:

- `particles.contact.restitution` is `restitution` in the table `[particles.contact]`, and
  `--set particles.contact.restitution=1.0` on the command line;
- `particles.species[].diameter` is a key of each `[[particles.species]]` table (an array of tables);
  `--set` takes the item's index: `--set particles.species.0.diameter=0.003`;
- `gas.boundaries.<name>.kind` is a key of a table whose name you choose, here a side:
  `[gas.boundaries.left]`;
- a key whose type is "number, or table" takes either a number or an inline table with the keys listed
  below it: `superficial = 1.8` or `superficial = {pulse = 2.5, start = 0.2, duration = 0.2}`;
- a table chosen among models (the contact law, the drag law, a gas boundary) has a section per model;
  its selecting key (`model`, `kind`) names the model, and each model accepts only its own keys.

"required" keys have no default; "not set" means the key may be left out and the description says
what is used then.
"""


def _render(section: Section, out: list[str]) -> None:
    out.append("#" * min(section.level, _MAX_HEADING) + " " + section.title)
    out.append("")
    if section.text:
        out += [section.text, ""]
    if section.rows:
        out.append("| key | type | default | allowed | description |")
        out.append("| --- | --- | --- | --- | --- |")
        for r in section.rows:
            out.append(f"| `{r.key}` | {r.type} | {r.default} | {r.allowed} | {r.description} |")
        out.append("")
    for child in section.children:
        _render(child, out)


def case_reference_markdown() -> str:
    """The Markdown of the case-file reference page."""
    out = [_INTRO]
    for s in _sections():
        _render(s, out)
    return "\n".join(out).rstrip() + "\n"


# ------------------------------------------------------------------ registered models
REGISTERED = re.compile(r"<!-- registered: (contact|drag|gas) -->")


def _registry(kind: str):
    if kind == "contact":
        from fluidem.particles.contact import contact_models

        return contact_models, "model"
    if kind == "drag":
        from fluidem.coupling.drag import drag_laws

        return drag_laws, "model"
    from fluidem.gas.boundaries import boundary_conditions

    return boundary_conditions, "kind"


def registered_models_markdown(kind: str) -> str:
    """A table of every model of the ``kind`` registry ("contact", "drag" or "gas")."""
    registry, tag = _registry(kind)
    rows = [f"| `{tag}` | class | what it is | keys | reference test |", "| --- | --- | --- | --- | --- |"]
    for name in registry.names():
        cls = registry.get(name)
        keys = ", ".join(f"`{k}`" for k in _fields_of(cls) if k != tag) or "none"
        test = getattr(cls, "reference_test", "") or "none"
        rows.append(f"| `{name}` | `{cls.__name__}` | {_description(_first_paragraph(cls))} | {keys} | `{test}` |")
    return "\n".join(rows) + "\n"


def _fields_of(cls) -> list[str]:
    return list(getattr(cls, "model_fields", {}))


def render_page(markdown: str, src_uri: str) -> str:
    """A page's Markdown as the site shows it: the generated reference for ``reference/case.md``, and each
    ``<!-- registered: KIND -->`` comment replaced by its table."""
    if src_uri == PAGE:
        return case_reference_markdown()
    return REGISTERED.sub(lambda m: registered_models_markdown(m.group(1)), markdown)


# ------------------------------------------------------------------ MkDocs hook
def on_page_markdown(markdown: str, page, config, files) -> str:
    """MkDocs hook: ``render_page``."""
    return render_page(markdown, page.file.src_uri)


if __name__ == "__main__":
    print(case_reference_markdown(), end="")
