"""The documentation's case-file reference and physics pages against the code they describe.

The reference page is written at build time by ``docs/hooks/case_reference.py`` from the pydantic schema.
Here its keys are compared with those of an independent walk of ``Case.model_json_schema()`` (pydantic's
JSON schema: ``$ref``/``$defs``, ``anyOf``/``oneOf``, ``items``, ``additionalProperties``), in both
directions, and a few rows are checked against the values declared in the schema. The physics pages must
name every registered contact law, drag law and gas boundary condition.
"""
from __future__ import annotations

import importlib.util
import re
import subprocess
import sys
from pathlib import Path

import pytest

from fluidem.case import Case
from fluidem.coupling.drag import drag_laws
from fluidem.gas.boundaries import boundary_conditions
from fluidem.particles.contact import contact_models

ROOT = Path(__file__).resolve().parents[2]
HOOK = ROOT / "docs" / "hooks" / "case_reference.py"
PHYSICS = ROOT / "docs" / "physics"


def _load_hook():
    spec = importlib.util.spec_from_file_location("fluidem_docs_case_reference", HOOK)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # as MkDocs loads its hooks
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def hook():
    return _load_hook()


@pytest.fixture(scope="module")
def markdown(hook):
    return hook.case_reference_markdown()


def _rows(markdown: str) -> dict[str, list[str]]:
    """Key → the table lines whose first cell is that key (a key of several models has several), with the
    Markdown escapes of the text (``\\_``, ``\\[``) undone."""
    out: dict[str, list[str]] = {}
    for line in markdown.splitlines():
        m = re.match(r"^\| `([^`]+)` \|", line)
        if m:
            out.setdefault(m.group(1), []).append(re.sub(r"\\([\\_*\[\]])", r"\1", line))
    return out


def json_schema_keys(item: str, entry: str) -> set[str]:
    """Dotted keys of the case schema from its JSON schema; ``item`` marks an array of tables, ``entry`` a
    table whose keys the user names (the reference's notation)."""
    schema = Case.model_json_schema()
    defs = schema.get("$defs", {})
    keys: set[str] = set()

    def walk(node: dict, prefix: str, refs: tuple) -> None:
        ref = node.get("$ref")
        if ref is not None:
            name = ref.rsplit("/", 1)[-1]
            if name in refs:  # a definition that holds itself
                return
            walk(defs[name], prefix, refs + (name,))
        for branch in node.get("anyOf", []) + node.get("oneOf", []) + node.get("allOf", []):
            walk(branch, prefix, refs)
        for name, sub in node.get("properties", {}).items():
            key = f"{prefix}.{name}" if prefix else name
            keys.add(key)
            walk(sub, key, refs)
        if isinstance(node.get("items"), dict):
            walk(node["items"], prefix + item, refs)
        if isinstance(node.get("additionalProperties"), dict):
            walk(node["additionalProperties"], f"{prefix}.{entry}", refs)

    walk(schema, "", ())
    return keys


def test_reference_lists_exactly_the_schema_keys(hook, markdown):
    expected = json_schema_keys(hook.ITEM, hook.ENTRY)
    listed = set(_rows(markdown))
    assert len(expected) > 100  # the walk reached the nested sections (the schema has over 150 keys)
    assert sorted(expected - listed) == [], "keys of the schema missing from the reference"
    assert sorted(listed - expected) == [], "keys in the reference that the schema does not have"
    assert hook.schema_keys() == expected


def test_reference_has_no_invented_keys(markdown):
    rows = _rows(markdown)
    for key in ("particles.species[].restitution",  # restitution exists, but not per species
                "particles.contact.stifness",
                "time.dt_fraction.value",
                "gas.boundaries.<name>.segments[].voidage"):  # voidage belongs to the inflow, not a segment
        assert key not in rows
        assert f"`{key}`" not in markdown


def test_reference_rows_carry_the_declared_values(markdown):
    rows = _rows(markdown)
    (dt_fraction,) = rows["time.dt_fraction"]
    assert "`0.02`" in dt_fraction and "≤ 0.1" in dt_fraction and "> 0.0" in dt_fraction
    assert "t_c" in dt_fraction  # the description
    (diameter,) = rows["particles.species[].diameter"]
    assert "| required |" in diameter and "> 0.0" in diameter and "[m]" in diameter
    (solver,) = rows["gas.linear_solver"]
    assert '`"auto"`' in solver and '`"multigrid"`' in solver
    (species,) = rows["particles.species"]
    assert "at least 1 item" in species
    # a key of a model in a choice: one row per model that has it
    assert len(rows["particles.contact.restitution"]) == len(contact_models.names())
    stiffness = rows["particles.contact.stiffness"]  # one row per model that has the key
    assert stiffness and all("| required |" in row and "[N/m]" in row for row in stiffness)


@pytest.mark.parametrize("key, registry", [("particles.contact.model", contact_models),
                                           ("coupling.drag.model", drag_laws),
                                           ("gas.boundaries.<name>.kind", boundary_conditions)])
def test_reference_has_a_section_per_registered_model(markdown, key, registry):
    rows = _rows(markdown)[key]
    chosen = sorted(re.search(r'\| `"([^"]+)"` \|', line).group(1) for line in rows)
    assert chosen == registry.names()


def test_generator_needs_no_mkdocs():
    code = ("import importlib.util, sys; "
            f"spec = importlib.util.spec_from_file_location('m', {str(HOOK)!r}); "
            "m = importlib.util.module_from_spec(spec); spec.loader.exec_module(m); "
            "m.case_reference_markdown(); "
            "assert not [n for n in sys.modules if n.split('.')[0] in ('mkdocs', 'mkdocstrings')], 'mkdocs imported'")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr


@pytest.mark.parametrize("page, kind, registry", [("contact.md", "contact", contact_models),
                                                  ("drag.md", "drag", drag_laws),
                                                  ("gas.md", "gas", boundary_conditions)])
def test_physics_pages_name_every_registered_model(hook, page, kind, registry):
    """Each physics page holds its registry's generated table, so a new model is listed without an edit."""
    raw = (PHYSICS / page).read_text()
    assert f"<!-- registered: {kind} -->" in raw
    text = hook.render_page(raw, f"physics/{page}")
    missing = [name for name in registry.names() if f"| `{name}` |" not in text]
    assert missing == [], f"docs/physics/{page} does not list {missing}"
    for name in registry.names():
        cls = registry.get(name)
        assert f"`{cls.__name__}`" in text and f"`{cls.reference_test}`" in text
