"""Case schema: built-in cases load, --set overrides, TOML round trip, and error messages that name
the key, the value and what is allowed."""
from __future__ import annotations

import copy
import tomllib

import pytest

import fluidem
from fluidem.case import (
    Case,
    apply_overrides,
    builtin_cases,
    load_case,
    parse_value,
    read_case_data,
    validate_case,
)
from fluidem.errors import CaseError
from fluidem.particles.contact import contact_models

BUILTIN = sorted(builtin_cases())


def case_error(name_or_data, overrides=None) -> str:
    """The message of the CaseError that loading raises (fails the test if none is raised)."""
    with pytest.raises(CaseError) as info:
        if isinstance(name_or_data, dict):
            data = copy.deepcopy(name_or_data)
            if overrides:
                apply_overrides(data, overrides)
            validate_case(data)
        else:
            load_case(name_or_data, overrides)
    return str(info.value)


# A case that exercises most optional sections, for the round trip.
RICH = {
    "name": "rich",
    "description": "3D, two species, Hertz-Mindlin, pair and wall overrides, moving wall",
    "particles": {
        "dimensions": 3,
        "species": [
            {"name": "glass", "diameter": 0.002, "density": 2500.0, "count": 50,
             "size_distribution": {"kind": "uniform", "min": 0.0018, "max": 0.0022}},
            {"name": "steel", "diameter": 0.003, "density": 7800.0, "count": 10,
             "youngs_modulus": 2.0e11, "poisson_ratio": 0.29,
             "size_distribution": {"kind": "lognormal", "std": 0.1}},
        ],
        "contact": {"model": "hertz_mindlin", "youngs_modulus": 1.0e8, "poisson_ratio": 0.25,
                    "restitution": 0.8, "friction": 0.4},
        "pairs": [{"species": ["glass", "steel"], "restitution": 0.7}],
        "placement": {"method": "lattice", "spacing": 1.1, "seed": 7, "velocity": [0.0, 0.0, -0.1],
                      "region_lower": [0.0, 0.0, 0.0], "region_upper": [0.03, 0.03, 0.03]},
    },
    "walls": [
        {"name": "box", "kind": "box", "lower": [0.0, 0.0, 0.0], "upper": [0.03, 0.03, 0.06], "open_top": True,
         "contact": {"friction": 0.1}},
        {"name": "piston", "kind": "plane", "point": [0.0, 0.0, 0.05], "normal": [0.0, 0.0, -1.0],
         "motion": {"kind": "oscillation", "amplitude": [0.0, 0.0, 0.001], "frequency": 50.0, "phase": 0.5}},
    ],
    "time": {"end": 0.1, "dt_fraction": 0.01},
    "neighbours": {"skin": 0.0005},
    "output": {"snapshot_interval": 0.01, "probe_interval": 0.001, "checkpoint_interval": 0.05},
    "threads": 1,
}


# ---------------------------------------------------------------- built-in cases
def test_there_is_at_least_the_pour_case():
    assert "pour" in BUILTIN


@pytest.mark.parametrize("name", BUILTIN)
def test_builtin_case_loads(name):
    case = load_case(name)
    assert isinstance(case, Case)
    assert case.description.strip(), "built-in cases need a description for `fluidem cases`"
    assert case.name == name  # run folders and `fluidem run NAME` agree
    assert case.time.end > 0
    assert sum(s.count for s in case.particles.species) > 0
    # the same file loaded by path gives the same case
    assert load_case(builtin_cases()[name]) == case


def test_public_surface():
    assert fluidem.load_case is load_case
    assert fluidem.Case is Case
    assert issubclass(fluidem.CaseError, ValueError)


def test_pour_defaults_resolved():
    case = load_case("pour")
    assert case.particles.dimensions == 2
    assert case.gravity == (0.0, -9.81, 0.0)  # 2D default: along -y
    assert case.particles.contact.model == "linear_spring_dashpot"
    assert case.particles.placement.method == "random"


def test_force_step_defaults_to_split_and_hoomans_is_for_hard_spheres_only():
    assert load_case("pour").particles.force_step == "split"  # velocity Verlet is a split step
    assert load_case("hoomans-pour").particles.force_step == "hoomans"  # the paper's reproductions keep its step
    assert load_case("pour", {"particles.contact": {"model": "hard_sphere", "restitution": 0.9, "friction": 0.3}}
                     ).particles.force_step == "split"
    msg = case_error("pour", {"particles.force_step": "hoomans"})
    assert "force_step" in msg and "hard_sphere" in msg and "velocity Verlet" in msg
    assert "force_step" in case_error("hoomans-pour", {"particles.force_step": "leapfrog"})


# ---------------------------------------------------------------- overrides
def test_override_nested_key():
    case = load_case("pour", {"particles.contact.restitution": 1.0})
    assert case.particles.contact.restitution == 1.0
    assert load_case("pour").particles.contact.restitution == 0.9  # the built-in file is untouched


def test_override_list_index():
    case = load_case("pour", {"particles.species.0.count": 10, "particles.species.0.diameter": 0.003})
    assert case.particles.species[0].count == 10
    assert case.particles.species[0].diameter == 0.003


def test_override_creates_missing_sections_and_keys():
    case = load_case("pour", {"neighbours.skin": 0.001, "output.checkpoint_interval": 0.1,
                              "particles.placement.region_lower": [0.0, 0.1, 0.0]})
    assert case.neighbours.skin == 0.001
    assert case.output.checkpoint_interval == 0.1
    assert case.particles.placement.region_lower == (0.0, 0.1, 0.0)


def test_override_replaces_a_whole_section():
    case = load_case("pour", {"particles.contact": {"model": "hertz_mindlin", "youngs_modulus": 7e10}})
    assert case.particles.contact.model == "hertz_mindlin"
    assert case.particles.contact.youngs_modulus == 7e10


def test_with_overrides_equals_load_case_with_overrides():
    ov = {"particles.contact.friction": 0.1, "time.end": 0.2, "particles.species.0.count": 20}
    assert load_case("pour").with_overrides(ov) == load_case("pour", ov)


def test_with_overrides_leaves_the_original_unchanged():
    case = load_case("pour")
    case.with_overrides({"particles.contact.friction": 0.0})
    assert case.particles.contact.friction == 0.3


@pytest.mark.parametrize("text, value", [
    ("1.0", 1.0), ("1e-3", 1e-3), ("-0.004", -0.004), ("3", 3), ("true", True),
    ("[0.0, 1.0, 2.0]", [0.0, 1.0, 2.0]), ('"hertz_mindlin"', "hertz_mindlin"), ("hertz_mindlin", "hertz_mindlin"),
    ("{ model = 'x' }", {"model": "x"}),
])
def test_parse_value_reads_toml_values_and_bare_words(text, value):
    got = parse_value(text)
    assert got == value and type(got) is type(value)


# ---------------------------------------------------------------- TOML round trip
@pytest.mark.parametrize("name", BUILTIN)
def test_to_toml_round_trip_builtin(name):
    case = load_case(name)
    again = validate_case(tomllib.loads(case.to_toml()))
    assert again == case
    assert again.to_toml() == case.to_toml()


def test_to_toml_round_trip_rich_case(tmp_path):
    case = validate_case(copy.deepcopy(RICH))
    text = case.to_toml()
    assert validate_case(tomllib.loads(text)) == case
    path = tmp_path / "rich.toml"
    path.write_text(text)
    assert load_case(path) == case


def test_to_toml_round_trip_after_overrides():
    case = load_case("pour", {"particles.contact.restitution": 1.0, "time.dt": 1e-5, "particles.species.0.count": 9})
    assert validate_case(tomllib.loads(case.to_toml())) == case


# ---------------------------------------------------------------- error messages
def test_errors_are_case_errors_not_pydantic_errors():
    with pytest.raises(CaseError) as info:
        load_case("pour", {"particles.contact.restitution": 2.0})
    assert "pydantic" not in str(info.value).lower()
    assert "errors.pydantic.dev" not in str(info.value)


def test_unknown_key_is_named_and_allowed_keys_listed():
    msg = case_error("pour", {"particles.contact.stifness": 800.0})
    assert "unknown key 'particles.contact.stifness'" in msg
    assert "800" in msg
    for allowed in ("stiffness", "restitution", "friction", "damping", "model"):
        assert allowed in msg


@pytest.mark.parametrize("key, some_allowed", [
    ("foo", ["particles", "walls", "time", "output"]),
    ("particles.foo", ["species", "contact", "placement", "dimensions"]),
    ("particles.species.0.colour", ["diameter", "density", "count"]),
    ("walls.0.colour", ["kind", "lower", "upper", "motion"]),
    ("time.stop", ["end", "dt"]),
])
def test_unknown_key_anywhere(key, some_allowed):
    msg = case_error("pour", {key: 1})
    assert f"unknown key {key!r}" in msg
    assert "allowed keys:" in msg
    for k in some_allowed:
        assert k in msg


def test_unknown_key_in_hertz_mindlin_lists_its_own_keys():
    msg = case_error("pour", {"particles.contact": {"model": "hertz_mindlin", "youngs_modulus": 1e9, "stiffness": 3.0}})
    assert "unknown key 'particles.contact.stiffness'" in msg
    assert "youngs_modulus" in msg and "poisson_ratio" in msg


def test_negative_diameter_names_key_and_value():
    msg = case_error("pour", {"particles.species.0.diameter": -0.004})
    assert "particles.species.0.diameter" in msg
    assert "-0.004" in msg
    assert "greater than 0" in msg


def test_restitution_above_one_names_key_value_and_limit():
    msg = case_error("pour", {"particles.contact.restitution": 1.5})
    assert "particles.contact.restitution" in msg
    assert "1.5" in msg
    assert "less than or equal to 1" in msg


def test_restitution_of_one_is_allowed():
    assert load_case("pour", {"particles.contact.restitution": 1.0}).particles.contact.restitution == 1.0


def test_unknown_contact_model_lists_allowed_models():
    msg = case_error("pour", {"particles.contact.model": "hookean"})
    assert "particles.contact" in msg
    assert "hookean" in msg
    for name in contact_models.names():
        assert name in msg


def test_contact_without_model_lists_allowed_models():
    msg = case_error("pour", {"particles.contact": {"stiffness": 800.0}})
    assert "particles.contact" in msg and "model" in msg
    for name in contact_models.names():
        assert name in msg


@pytest.mark.parametrize("path, key", [
    (("time", "end"), "time.end"),
    (("particles", "contact", "stiffness"), "particles.contact.stiffness"),
    (("particles", "species", 0, "density"), "particles.species.0.density"),
])
def test_missing_required_key_is_named(path, key):
    data = read_case_data("pour")
    node = data
    for p in path[:-1]:
        node = node[p]
    del node[path[-1]]
    msg = case_error(data)
    assert f"missing key {key!r}" in msg


def test_several_errors_are_all_reported():
    msg = case_error("pour", {"particles.contact.restitution": 1.5, "particles.species.0.diameter": -1.0})
    assert "particles.contact.restitution" in msg
    assert "particles.species.0.diameter" in msg


def test_wrong_type_names_key_and_value():
    msg = case_error("pour", {"particles.contact.restitution": "abc"})
    assert "particles.contact.restitution" in msg and "'abc'" in msg


def test_model_level_check_names_the_section():
    msg = case_error("pour", {"particles.species.0.size_distribution": {"kind": "uniform", "min": 0.005, "max": 0.003}})
    assert "particles.species.0.size_distribution" in msg
    assert "0.005" in msg and "0.003" in msg


def test_2d_case_with_gravity_along_z_is_rejected():
    msg = case_error("pour", {"gravity": [0.0, 0.0, -9.81]})
    assert "gravity" in msg and "2D" in msg


@pytest.mark.parametrize("overrides, fragment", [
    ({"particles.species.3.diameter": 1.0}, "list index below 1"),
    ({"particles.species.x.diameter": 1.0}, "list index below 1"),
])
def test_bad_override_paths_are_case_errors(overrides, fragment):
    msg = case_error("pour", overrides)
    assert fragment in msg
    assert next(iter(overrides)) in msg


def test_override_into_a_new_unknown_section_names_its_top():
    msg = case_error("pour", {"particles.species.0.x.y.z": 1.0})
    assert "unknown key 'particles.species.0.x'" in msg


def test_override_through_a_value_is_a_case_error():
    msg = case_error("pour", {"time.end.x": 1})
    assert "'time.end' is a value, not a section" in msg


def test_override_two_levels_through_a_value_names_the_value():
    msg = case_error("pour", {"time.end.x.y": 1})
    assert "--set time.end.x.y" in msg
    assert "'time.end' is a value, not a section" in msg


def test_unknown_case_name_lists_builtins():
    msg = case_error("no-such-case")
    assert "no-such-case" in msg
    for name in BUILTIN:
        assert name in msg


def test_invalid_toml_file(tmp_path):
    p = tmp_path / "bad.toml"
    p.write_text("[particles\nx = 1\n")
    msg = case_error(str(p))
    assert str(p) in msg and "TOML" in msg
