"""Registry: name -> class lookup with helpful errors, and the contact-model registry the case schema uses."""
from __future__ import annotations

import pytest

from fluidem.case import load_case
from fluidem.errors import CaseError
from fluidem.particles.contact import ContactModel, contact_models
from fluidem.registry import Registry


@pytest.fixture
def widgets():
    reg = Registry("widget")

    @reg.register("spring")
    class Spring:
        pass

    @reg.register("sprocket")
    class Sprocket:
        pass

    @reg.register("axle")
    class Axle:
        pass

    return reg, {"spring": Spring, "sprocket": Sprocket, "axle": Axle}


def test_register_returns_the_class_unchanged_and_get_finds_it(widgets):
    reg, classes = widgets
    for name, cls in classes.items():
        assert reg.get(name) is cls
        assert name in reg
    assert "gear" not in reg
    assert dict(reg.items()) == classes


def test_names_are_sorted(widgets):
    reg, _ = widgets
    assert reg.names() == ["axle", "spring", "sprocket"]


def test_registering_a_name_twice_is_an_error(widgets):
    reg, _ = widgets
    with pytest.raises(ValueError, match="widget 'axle' is registered twice"):
        reg.register("axle")(object)
    # the first registration survives
    assert reg.get("axle").__name__ == "Axle"


def test_unknown_name_lists_allowed_names_and_suggests_the_closest(widgets):
    reg, _ = widgets
    with pytest.raises(KeyError) as info:
        reg.get("sprng")
    msg = str(info.value)
    assert "unknown widget 'sprng'" in msg
    assert "axle, spring, sprocket" in msg
    assert "did you mean 'spring'?" in msg


def test_unknown_name_without_a_close_match_has_no_suggestion(widgets):
    reg, _ = widgets
    with pytest.raises(KeyError) as info:
        reg.get("zzzzzzzz")
    assert "did you mean" not in str(info.value)
    assert "axle, spring, sprocket" in str(info.value)


def test_empty_registry():
    reg = Registry("drag law")
    assert reg.names() == []
    with pytest.raises(KeyError, match="unknown drag law 'ergun'"):
        reg.get("ergun")


# ---------------------------------------------------------------- the contact-model registry
def test_contact_registry_holds_the_built_in_models():
    assert {"linear_spring_dashpot", "hertz_mindlin"} <= set(contact_models.names())


@pytest.mark.parametrize("name", contact_models.names())
def test_registered_contact_model_is_consistent(name):
    """The registered name is the class's ``model`` tag, so a case file can select it by that name."""
    cls = contact_models.get(name)
    assert issubclass(cls, ContactModel)
    assert cls.model_fields["model"].default == name
    assert isinstance(cls.code, int) and cls.code > 0


def test_contact_model_codes_are_unique():
    codes = [contact_models.get(n).code for n in contact_models.names()]
    assert len(set(codes)) == len(codes)


@pytest.mark.parametrize("name", contact_models.names())
def test_case_schema_accepts_every_registered_contact_model(name):
    """Selecting a registered model by name must never be rejected as an unknown model
    (it may fail for missing parameters, which is fine here)."""
    try:
        load_case("pour", {"particles.contact": {"model": name}})
    except CaseError as err:
        assert "is not a known model" not in str(err)
        assert "missing key" in str(err) or "unknown key" in str(err)
