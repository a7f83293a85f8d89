"""StaggeredGrid: geometry, index layout, and the cell flags of Hoomans 1996 Table 1."""
import numpy as np
import pytest

from fluidem.errors import CaseError
from fluidem.gas import (CORNER, FREE_SLIP, INFLOW, INTERIOR, NO_SLIP, OUTFLOW, PERIODIC, PRESSURE, FreeSlip, Inflow,
                         Outflow, Periodic, PressureOutlet, StaggeredGrid, Wall)


def test_geometry_of_the_hoomans_grid():
    g = StaggeredGrid(cells=(15, 25), size=(0.15, 0.5), depth=0.004)  # Hoomans 1996 Table 2
    assert (g.nx, g.ny) == (15, 25)
    assert g.dx == pytest.approx(0.01) and g.dy == pytest.approx(0.02)
    assert g.cell_volume == pytest.approx(0.01 * 0.02 * 0.004)
    assert g.area_x == pytest.approx(0.02 * 0.004) and g.area_y == pytest.approx(0.01 * 0.004)
    assert g.shape == (15, 25) and g.u_shape == (16, 25) and g.v_shape == (15, 26)
    np.testing.assert_allclose(g.x_centres[[0, -1]], [0.005, 0.145])
    np.testing.assert_allclose(g.y_faces[[0, -1]], [0.0, 0.5])
    X, Y = g.centres()
    assert X.shape == g.shape and X[3, 0] == pytest.approx(0.035) and Y[0, 3] == pytest.approx(0.07)


@pytest.mark.parametrize("kwargs, key", [
    ({"cells": (0, 5), "size": (1.0, 1.0)}, "cells"),
    ({"cells": (2.5, 5), "size": (1.0, 1.0)}, "cells"),
    ({"cells": (2, 5, 3), "size": (1.0, 1.0)}, "cells"),
    ({"cells": (2, 5), "size": (1.0, -1.0)}, "size"),
    ({"cells": (2, 5), "size": (1.0, 1.0), "depth": 0.0}, "depth"),
])
def test_bad_grids_are_case_errors_naming_the_key(kwargs, key):
    with pytest.raises(CaseError, match=f"gas.grid.{key}"):
        StaggeredGrid(**kwargs)


def test_flag_matrix_of_the_standard_set_up():
    """Hoomans 1996 Fig. 6: inflow at the bottom, walls at the sides, prescribed pressure on top."""
    g = StaggeredGrid(cells=(3, 2), size=(0.03, 0.02))
    fl = g.cell_flags({"left": Wall(), "right": FreeSlip(), "bottom": Inflow(superficial=1.0), "top": PressureOutlet()})
    expected_printed = np.array([  # y upwards, as in the grid.py docstring
        [CORNER, PRESSURE, PRESSURE, PRESSURE, CORNER],
        [NO_SLIP, INTERIOR, INTERIOR, INTERIOR, FREE_SLIP],
        [NO_SLIP, INTERIOR, INTERIOR, INTERIOR, FREE_SLIP],
        [CORNER, INFLOW, INFLOW, INFLOW, CORNER],
    ])
    np.testing.assert_array_equal(fl.T[::-1], expected_printed)
    assert fl.dtype == np.int8
    assert (INTERIOR, FREE_SLIP, NO_SLIP, INFLOW, PRESSURE, OUTFLOW, CORNER) == (1, 2, 3, 4, 5, 6, 7)  # Table 1
    fl = g.cell_flags({"left": Periodic(), "right": Periodic(), "bottom": Wall(), "top": Outflow()})
    assert np.all(fl[0, 1:-1] == PERIODIC) and np.all(fl[1:-1, -1] == OUTFLOW)


@pytest.mark.parametrize("boundaries, message", [
    ({"left": Wall(), "right": Wall(), "bottom": Wall()}, r"side\(s\) \['top'\] missing"),
    ({"left": Wall(), "right": Wall(), "bottom": Wall(), "top": Wall(), "front": Wall()}, "unknown side"),
    ({"left": Wall(), "right": "wall", "bottom": Wall(), "top": Wall()}, "gas.boundaries.right"),
    ({"left": Periodic(), "right": Wall(), "bottom": Wall(), "top": Wall()}, "periodic sides come in pairs"),
])
def test_bad_boundary_sets_are_case_errors(boundaries, message):
    with pytest.raises(CaseError, match=message):
        StaggeredGrid(cells=(2, 2), size=(1.0, 1.0)).cell_flags(boundaries)
