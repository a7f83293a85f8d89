"""The [gas] section with a 3D grid: three cells entries build the 3D solver; a case with 2D particles refuses it."""
import pytest

from fluidem.case import load_case
from fluidem.errors import CaseError
from fluidem.gas import GasSection, GasSolver3D

GAS_3D = {
    "dt": 1e-4,
    "grid": {"cells": [6, 8, 5], "size": [0.06, 0.08, 0.05]},
    "properties": {"density": 1.2},
    "boundaries": {
        "left": {"kind": "wall"}, "right": {"kind": "wall"}, "front": {"kind": "free_slip"},
        "back": {"kind": "free_slip"}, "top": {"kind": "pressure_outlet"},
        "bottom": {"kind": "inflow", "voidage": 0.4, "superficial": 0.2,
                   "patches": [{"shape": "circle", "centre": [0.03, 0.025], "radius": 0.01, "interstitial": 3.0},
                               {"shape": "rectangle", "start": [0.0, 0.0], "end": [0.01, 0.05],
                                "superficial": {"pulse": 1.0, "start": 0.0, "duration": 0.1}}]},
    },
}


def test_three_cells_entries_build_the_3d_solver():
    section = GasSection.model_validate(GAS_3D)
    solver = section.build((0.0, -9.81, 0.0))
    assert isinstance(solver, GasSolver3D)
    assert solver.grid.cells == (6, 8, 5) and solver.grid.depth == 0.05
    assert solver.gravity == (0.0, -9.81, 0.0)
    state = solver.initial_state(velocity=section.velocity)
    info = solver.advance(state, section.dt, 0.0)
    assert info.converged and state.w.shape == (6, 8, 6)


@pytest.mark.parametrize("change, message", [
    ({"boundaries": {k: v for k, v in GAS_3D["boundaries"].items() if k != "back"}}, "missing side"),
    ({"grid": {"cells": [6, 8], "size": [0.06, 0.08]}}, "depth"),
    ({"grid": {"cells": [6, 8, 5], "size": [0.06, 0.08]}}, "one size per cells entry"),
    ({"grid": {"cells": [6, 8, 5], "size": [0.06, 0.08, 0.05], "depth": 0.01}}, "no depth of its own"),
    ({"linear_solver": "band"}, "2D block-tridiagonal"),
    ({"dt": 1e-2}, "Courant"),
])
def test_bad_3d_sections_are_refused_with_the_reason(change, message):
    with pytest.raises(Exception, match=message):
        GasSection.model_validate({**GAS_3D, **change})


def test_2d_sections_refuse_front_and_back():
    data = load_case("tsuji-jet").gas.model_dump(mode="json", exclude_none=True)
    data["boundaries"]["front"] = {"kind": "wall"}
    with pytest.raises(Exception, match="front and back are the z sides"):
        GasSection.model_validate(data)


def test_2d_particles_refuse_a_3d_gas_grid():
    case = load_case("tsuji-jet")
    data = case.model_dump(mode="json", exclude_none=True)
    data["gas"] = GAS_3D
    data["gravity"] = [0.0, -9.81, 0.0]
    from fluidem.case import validate_case

    with pytest.raises(CaseError, match="a 3D gas grid takes 3D particles"):
        validate_case(data)
