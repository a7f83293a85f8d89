"""Gas fields of a 3D grid in gas.h5 + gas.xdmf: (nz, ny, nx) datasets indexed as a 3DRectMesh, read back
as (T, nx, ny, nz); the 2D output is unchanged (``test_gas_fields.py``)."""
import xml.etree.ElementTree as ET
from types import SimpleNamespace

import h5py
import numpy as np

from fluidem.gas import GasProperties, GasSolver, StaggeredGrid, Wall
from fluidem.io.gas_fields import (
    GasFieldWriter,
    cell_fields,
    read_gas_fields,
    read_gas_grid,
)


def test_3d_fields_are_written_as_a_3d_rectilinear_grid(tmp_path):
    grid = StaggeredGrid(cells=(3, 4, 5), size=(0.3, 0.4, 0.5))
    solver = GasSolver(grid, GasProperties(density=1.2), {s: Wall() for s in grid.sides})
    state = solver.initial_state(voidage=0.7, pressure=1e5)
    state.w[:] = np.arange(state.w.size).reshape(state.w.shape)  # a field with a direction to check
    writer = GasFieldWriter(tmp_path)
    for k in range(2):
        writer(SimpleNamespace(gas=SimpleNamespace(grid=grid, state=state), time=0.1 * k, steps=10 * k))
    writer.finalize(None)
    with h5py.File(tmp_path / "gas.h5") as f:
        assert f.attrs["nz"] == 5 and f["snapshots/000000/uz"].shape == (5, 4, 3)  # x fastest
        assert np.allclose(f["grid/z_faces"][:], np.linspace(0.0, 0.5, 6))
    g = read_gas_fields(tmp_path)
    uz = 0.5 * (state.w[:, :, :-1] + state.w[:, :, 1:])
    assert g["uz"].shape == (2, 3, 4, 5) and np.array_equal(g["uz"][1], uz)
    assert np.array_equal(g["voidage"][0], np.full((3, 4, 5), 0.7))
    assert np.allclose(g["z"], grid.z_centres) and g["time"].tolist() == [0.0, 0.1]
    assert read_gas_grid(tmp_path)["nz"] == 5
    root = ET.parse(tmp_path / "gas.xdmf").getroot()
    grids = root.findall("./Domain/Grid/Grid")
    assert len(grids) == 2
    topo = grids[0].find("Topology")
    assert topo.get("TopologyType") == "3DRectMesh" and topo.get("Dimensions") == "6 5 4"
    geo = grids[0].find("Geometry")
    assert geo.get("GeometryType") == "VXVYVZ"
    assert [d.text.split(":")[-1] for d in geo] == ["/grid/x_faces", "/grid/y_faces", "/grid/z_faces"]
    assert [d.get("Dimensions") for d in geo] == ["4", "5", "6"]
    names = {a.get("Name"): a.find("DataItem").get("Dimensions") for a in grids[0].findall("Attribute")}
    assert names["uz"] == "5 4 3" and "superficial_uz" in names and "ux" in names


def test_cell_fields_of_a_2d_state_have_no_z_fields():
    grid = StaggeredGrid(cells=(3, 4), size=(0.3, 0.4), depth=0.01)
    solver = GasSolver(grid, GasProperties(density=1.2), {s: Wall() for s in grid.sides})
    fields = cell_fields(solver.initial_state())
    assert "uz" not in fields and fields["p"].shape == (3, 4)
