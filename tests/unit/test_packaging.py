"""The installed package: one version (pyproject.toml's, read from the distribution metadata), the
``fluidem --version`` line, the files shipped beside the code (``py.typed``, the licence), the logger
the package reports through, and the case building blocks at top level, which build the same
``Case`` in Python as the TOML loader does.
"""
from __future__ import annotations

import importlib.metadata
import logging
import subprocess
import sys
import textwrap
import tomllib
from importlib import resources
from pathlib import Path

import pytest

import fluidem as fd
import fluidem.case
import fluidem.coupling.drag
import fluidem.particles.contact
from fluidem.cli import main

PYPROJECT = Path(fd.__file__).resolve().parents[2] / "pyproject.toml"


# ---------------------------------------------------------------- version
def test_version_is_the_distribution_version():
    assert fd.__version__ == importlib.metadata.version("fluidem")
    assert fd.__version__[0].isdigit(), fd.__version__  # not the "0+unknown" of an uninstalled tree


@pytest.mark.skipif(not PYPROJECT.is_file(), reason="installed without its source tree")
def test_version_is_the_one_in_pyproject():
    """The installed metadata was made from this pyproject.toml (reinstall after changing its version)."""
    project = tomllib.loads(PYPROJECT.read_text())["project"]
    assert "version" not in project.get("dynamic", [])
    assert fd.__version__ == project["version"]


def test_version_flag_in_process(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0
    out, err = capsys.readouterr()
    assert out == f"fluidem {fd.__version__}\n"
    assert err == ""


def test_version_flag_of_the_command(tmp_path):
    res = subprocess.run([sys.executable, "-m", "fluidem", "--version"], cwd=tmp_path, capture_output=True,
                         text=True, timeout=120)
    assert res.returncode == 0, res.stderr
    assert res.stdout == f"fluidem {importlib.metadata.version('fluidem')}\n"
    assert res.stderr == ""


# ---------------------------------------------------------------- files and metadata
def test_py_typed_is_in_the_installed_package():
    marker = resources.files("fluidem") / "py.typed"
    assert marker.is_file()


def test_licence_in_the_metadata():
    dist = importlib.metadata.distribution("fluidem")
    assert dist.metadata["License-Expression"] == "MIT"
    assert dist.metadata.get_all("License-File") == ["LICENSE"]
    if PYPROJECT.is_file():
        text = (PYPROJECT.parent / "LICENSE").read_text()
        assert text.startswith("MIT License")
        assert "Copyright (c) 2026 The fluidem developers" in text


def test_command_line_dependencies_are_core():
    """``pip install fluidem`` gives plot, compare and report: matplotlib is no extra; Numba is bounded
    below its next major (fluidem._numba_cache relies on its internals)."""
    core = [r for r in importlib.metadata.requires("fluidem") if "extra ==" not in r]
    names = {r.split(";")[0].split("<")[0].split(">")[0].split("=")[0].strip().lower(): r for r in core}
    assert "matplotlib" in names
    assert "<1" in names["numba"]
    extras = importlib.metadata.metadata("fluidem").get_all("Provides-Extra")
    assert {"test", "docs", "animate"} <= set(extras)


# ---------------------------------------------------------------- logger
def test_the_package_logger_has_a_null_handler_only():
    """A program importing fluidem sees nothing from it until it configures logging itself."""
    handlers = logging.getLogger("fluidem").handlers
    assert any(isinstance(h, logging.NullHandler) for h in handlers)
    assert all(isinstance(h, logging.NullHandler) for h in handlers), handlers


# ---------------------------------------------------------------- top-level API
BUILDING_BLOCKS = ["Case", "Particles", "Species", "Wall", "Time", "Output", "Placement"]


@pytest.mark.parametrize("name", BUILDING_BLOCKS)
def test_case_building_blocks_are_the_loaders_classes(name):
    assert getattr(fd, name) is getattr(fluidem.case, name)
    assert name in fd.__all__


def test_modules_and_functions_at_top_level():
    from fluidem.simulation import Simulation

    assert fd.contact is fluidem.particles.contact
    assert fd.drag is fluidem.coupling.drag
    assert fd.gas is sys.modules["fluidem.gas"]
    assert fd.contact.HertzMindlin is fd.contact.contact_models.get("hertz_mindlin")
    assert fd.contact.LinearSpringDashpot is fd.contact.contact_models.get("linear_spring_dashpot")
    assert fd.drag.Beetstra is fd.drag.drag_laws.get("beetstra")
    assert fd.Simulation is Simulation
    assert fd.load_case is fluidem.case.load_case
    assert callable(fd.Every) and callable(fd.EveryTime)
    assert {"contact", "drag", "gas", "Simulation", "load_case", "Every", "EveryTime", "__version__"} <= set(fd.__all__)
    assert "Simulation" in dir(fd)
    with pytest.raises(AttributeError, match="no_such_name"):
        fd.no_such_name  # noqa: B018


def _pour_in_python() -> fd.Case:
    """The built-in pour case built from the top-level objects, each table of pour.toml given to the
    class the loader builds it into."""
    data = tomllib.loads((resources.files("fluidem") / "cases" / "pour.toml").read_text())
    particles = dict(data.pop("particles"))
    contact = dict(particles.pop("contact"))
    law = {"linear_spring_dashpot": fd.contact.LinearSpringDashpot, "hertz_mindlin": fd.contact.HertzMindlin}
    case = fd.Case(
        name=data.pop("name"),
        description=data.pop("description"),
        particles=fd.Particles(
            dimensions=particles.pop("dimensions"),
            species=[fd.Species(**s) for s in particles.pop("species")],
            contact=law[contact.pop("model")](**contact),
            placement=fd.Placement(**particles.pop("placement"))),
        walls=[fd.Wall(**w) for w in data.pop("walls")],
        time=fd.Time(**data.pop("time")),
        output=fd.Output(**data.pop("output")))
    assert particles == {} and data == {}, f"pour.toml tables this builder does not give: {particles} {data}"
    return case


def test_a_case_built_in_python_equals_the_loaded_one():
    built = _pour_in_python()
    loaded = fd.load_case("pour")
    assert built.model_dump() == loaded.model_dump()
    assert built == loaded
    # the comparison sees every value: one changed key makes them differ
    assert built.with_overrides({"particles.contact.restitution": 0.8}).model_dump() != loaded.model_dump()
    assert built.model_dump()["particles"]["species"][0]["count"] == 500


def _docstring_example(marker: str) -> str:
    """The indented code block that follows ``marker`` in fluidem's module docstring."""
    lines = fd.__doc__.split(marker, 1)[1].splitlines()[1:]
    block = []
    for line in lines:
        if line.strip() and not line.startswith("    "):
            break
        block.append(line)
    return textwrap.dedent("\n".join(block)).strip()


def test_the_docstring_example_builds_the_pour_case():
    """The example in fluidem's module docstring runs and builds the built-in pour case (its description aside)."""
    code = _docstring_example("from the objects the TOML loader builds::")
    assert code.startswith("case = fd.Case(")
    scope = {"fd": fd}
    exec(code, scope)  # noqa: S102 - the documented example itself
    loaded = fd.load_case("pour")
    assert scope["case"].model_dump(exclude={"description"}) == loaded.model_dump(exclude={"description"})


def test_a_coupled_case_built_from_the_top_level_objects_equals_the_toml_one():
    """tsuji-jet-background's gas and coupling built in Python (fd.Gas, fd.gas.Inflow, fd.Coupling, fd.drag.Gidaspow)
    are the objects its TOML file gives."""
    import fluidem as fd

    ref = fd.load_case("tsuji-jet-background")
    inflow = fd.gas.Inflow(segments=[fd.gas.Segment(superficial=ref.gas.boundaries["bottom"].segments[0].superficial),
                                     fd.gas.Segment(superficial=39.0, start=0.07, end=0.08)])
    gas = fd.Gas(dt=ref.gas.dt, grid=fd.gas.Grid(cells=ref.gas.grid.cells, size=ref.gas.grid.size,
                                                 depth=ref.gas.grid.depth),
                 boundaries={"left": fd.gas.Wall(), "right": fd.gas.Wall(), "bottom": inflow,
                             "top": fd.gas.PressureOutlet()},
                 initial_velocity=ref.gas.initial_velocity)
    case = fd.Case(name=ref.name, description=ref.description, particles=ref.particles, walls=ref.walls,
                   time=ref.time, output=ref.output, gas=gas,
                   coupling=fd.Coupling(drag=fd.drag.Gidaspow(), voidage=fd.VoidageMapping(method="centroid")))
    assert case.model_dump() == ref.model_dump()
    assert case.to_toml() == ref.to_toml()
