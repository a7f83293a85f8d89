"""Every registered model names the test that checks it against an analytic result or a published number
(``reference_test``), and that test exists and is about it: adding a model without its reference test
fails here."""
import re
from pathlib import Path

import pytest

from fluidem.coupling.drag import drag_laws
from fluidem.gas.boundaries import boundary_conditions
from fluidem.particles.contact import contact_models

TESTS = Path(__file__).resolve().parents[1]
REGISTRIES = {"contact model": contact_models, "drag law": drag_laws, "gas boundary condition": boundary_conditions}


def _test_modules() -> dict[str, str]:
    """{test function name: source of the modules defining it} over tests/ (unit, verification, validation)."""
    found: dict[str, str] = {}
    for path in TESTS.rglob("test_*.py"):
        text = path.read_text(encoding="utf-8")
        for name in re.findall(r"^def (test_\w+)\(", text, re.MULTILINE):
            found[name] = found.get(name, "") + text
    return found


MODULES = _test_modules()
MODELS = [(kind, name) for kind, reg in REGISTRIES.items() for name in reg.names()]


def missing_reference(kind: str, name: str, cls) -> str | None:
    """What is wrong with the reference test of a registered model, or None."""
    test = getattr(cls, "reference_test", "")
    if not test:
        return f"{kind} {name!r} ({cls.__module__}.{cls.__name__}) sets no reference_test"
    if test not in MODULES:
        return f"{kind} {name!r}: its reference_test {test!r} is no test function under tests/"
    source = MODULES[test]
    if f'"{name}"' not in source and f"{cls.__name__}(" not in source:
        return f"{kind} {name!r}: the module of {test!r} names neither {name!r} nor {cls.__name__}("
    return None


@pytest.mark.parametrize("kind, name", MODELS, ids=[f"{k}:{n}" for k, n in MODELS])
def test_registered_model_names_an_existing_reference_test_about_it(kind, name):
    problem = missing_reference(kind, name, REGISTRIES[kind].get(name))
    assert problem is None, problem


def test_a_model_without_a_reference_test_is_caught():
    class Unchecked:  # what a new model file without its test would register
        reference_test = ""

    class Misnamed:
        reference_test = "test_that_does_not_exist"

    class Unrelated:
        reference_test = "test_a_model_without_a_reference_test_is_caught"

    assert "sets no reference_test" in missing_reference("drag law", "unchecked", Unchecked)
    assert "is no test function" in missing_reference("drag law", "misnamed", Misnamed)
    assert "names neither" in missing_reference("drag law", "zz" + "unrelated", Unrelated)
