"""Gas fields in the run directory: ``gas.h5`` + ``gas.xdmf`` (``fluidem.io.gas_fields``).

Most tests drive ``GasFieldWriter`` with a stand-in for the simulation (a real ``GasState``
and ``StaggeredGrid`` with known values), so what is written is known exactly; the last
ones run a tiny coupled bed (60 particles, 6 x 24 cells, 0.02 s) to check the writer
against a real ``GasCoupling`` and across a resume.
"""
from __future__ import annotations

import shutil
import xml.etree.ElementTree as ET
from pathlib import Path
from types import SimpleNamespace

import h5py
import numpy as np
import pytest

from fluidem.gas.grid import StaggeredGrid
from fluidem.gas.solver import GasState
from fluidem.io.gas_fields import FIELDS, GasFieldWriter, read_gas_fields
from fluidem.schedule import EveryTime
from fluidem.simulation import Simulation

from _helpers.gas_fields import run_tiny_jet

NX, NY = 3, 5


# ---------------------------------------------------------------- a stand-in simulation
def fake_sim(t, step, seed=0, solids=True, beta="array"):
    """Object with what GasFieldWriter reads: time, steps, gas.state, gas.grid (+ last_map, last_beta)."""
    rng = np.random.default_rng(seed)
    grid = StaggeredGrid(cells=(NX, NY), size=(0.03, 0.1), depth=0.004)
    state = GasState(p=1e5 + rng.normal(size=grid.shape), rho=1.2 + 0.01 * rng.random(grid.shape),
                     u=rng.normal(size=grid.u_shape), v=rng.normal(size=grid.v_shape),
                     voidage=0.4 + 0.6 * rng.random(grid.shape))
    gas = SimpleNamespace(state=state, grid=grid)
    if solids:
        gas.last_map = SimpleNamespace(solids_u=rng.normal(size=grid.shape), solids_v=rng.normal(size=grid.shape))
    if beta == "array":
        gas.last_beta = rng.random(grid.shape) * 1e4
    elif beta == "none":
        gas.last_beta = None  # a coupling before its first gas step
    return SimpleNamespace(time=t, steps=step, gas=gas)


def expected_fields(sim) -> dict[str, np.ndarray]:
    """The cell-centred fields, computed cell by cell (the reference for the vectorised writer)."""
    st = sim.gas.state
    ux, uy = np.empty((NX, NY)), np.empty((NX, NY))
    for i in range(NX):
        for j in range(NY):
            ux[i, j] = 0.5 * (st.u[i, j] + st.u[i + 1, j])  # left and right x-faces of cell (i, j)
            uy[i, j] = 0.5 * (st.v[i, j] + st.v[i, j + 1])  # bottom and top y-faces
    out = {"voidage": st.voidage, "solids_fraction": 1.0 - st.voidage, "p": st.p, "rho": st.rho, "ux": ux, "uy": uy,
           "superficial_ux": st.voidage * ux, "superficial_uy": st.voidage * uy}
    if hasattr(sim.gas, "last_map"):
        out.update(solids_u=sim.gas.last_map.solids_u, solids_v=sim.gas.last_map.solids_v)
    if getattr(sim.gas, "last_beta", None) is not None:
        out["beta"] = sim.gas.last_beta
    return out


def write(tmp_path, sims):
    w = GasFieldWriter(tmp_path, EveryTime(0.01))
    for s in sims:
        w(s)
    return w


def test_values_written_are_values_read(tmp_path):
    sims = [fake_sim(0.01 * k, 10 * k, seed=k) for k in range(3)]
    write(tmp_path, sims)
    g = read_gas_fields(tmp_path)
    np.testing.assert_array_equal(g["time"], [0.0, 0.01, 0.02])
    np.testing.assert_array_equal(g["step"], [0, 10, 20])
    grid = sims[0].gas.grid
    np.testing.assert_array_equal(g["x"], grid.x_centres)
    np.testing.assert_array_equal(g["y"], grid.y_centres)
    np.testing.assert_array_equal(g["x_faces"], grid.x_faces)
    np.testing.assert_array_equal(g["y_faces"], grid.y_faces)
    for k, s in enumerate(sims):
        exp = expected_fields(s)
        assert set(exp) == set(g) - {"time", "step", "x", "y", "x_faces", "y_faces"}
        for name, value in exp.items():
            assert g[name].shape == (3, NX, NY)
            np.testing.assert_allclose(g[name][k], value, rtol=1e-15, atol=0, err_msg=name)
    # only some fields, on request
    assert set(read_gas_fields(tmp_path / "gas.h5", fields=["p"])) == {"time", "step", "x", "y", "x_faces",
                                                                       "y_faces", "p"}
    with pytest.raises(KeyError, match="unknown gas field"):
        read_gas_fields(tmp_path, fields=["pressure"])
    with pytest.raises(FileNotFoundError, match="no gas fields"):
        read_gas_fields(tmp_path / "elsewhere")


def test_datasets_are_stored_rows_of_y_with_x_fastest(tmp_path):
    """The XDMF/VTK order: dataset[j, i] is cell (i, j), so ParaView reads them without a transpose."""
    s = fake_sim(0.0, 0)
    write(tmp_path, [s])
    with h5py.File(tmp_path / "gas.h5") as f:
        d = np.asarray(f["snapshots/000000/voidage"])
        assert d.shape == (NY, NX)
        assert d[4, 1] == s.gas.state.voidage[1, 4]
        assert f.attrs["format"] == "fluidem-gas" and (f.attrs["nx"], f.attrs["ny"]) == (NX, NY)
        assert f["snapshots/000000/p"].attrs["units"] == "Pa"


def check_xdmf(run_dir: Path, nx: int, ny: int) -> list[float]:
    """Parse gas.xdmf and check it against gas.h5; returns the times it lists."""
    root = ET.parse(run_dir / "gas.xdmf").getroot()
    assert root.tag == "Xdmf" and root.get("Version") == "3.0"
    (collection,) = root.find("Domain").findall("Grid")
    assert (collection.get("GridType"), collection.get("CollectionType")) == ("Collection", "Temporal")
    times = []
    with h5py.File(run_dir / "gas.h5", "r") as f:

        def dataset(item, dims):
            assert item.get("Format") == "HDF" and item.get("Dimensions") == dims
            fname, path = item.text.strip().split(":", 1)
            assert fname == "gas.h5"
            assert path in f, path
            assert " ".join(map(str, f[path].shape)) == dims, (path, f[path].shape, dims)
            return path

        for grid in collection.findall("Grid"):
            assert grid.get("GridType") == "Uniform"
            times.append(float(grid.find("Time").get("Value")))
            topo = grid.find("Topology")
            assert (topo.get("TopologyType"), topo.get("Dimensions")) == ("2DRectMesh", f"{ny + 1} {nx + 1}")
            geo = grid.find("Geometry")
            assert geo.get("GeometryType") == "VXVY"
            vx, vy = geo.findall("DataItem")
            assert dataset(vx, f"{nx + 1}") == "/grid/x_faces"
            assert dataset(vy, f"{ny + 1}") == "/grid/y_faces"
            names = []
            for attr in grid.findall("Attribute"):
                assert (attr.get("Center"), attr.get("AttributeType")) == ("Cell", "Scalar")
                path = dataset(attr.find("DataItem"), f"{ny} {nx}")
                assert path.endswith("/" + attr.get("Name"))
                # 9 significant digits, as particles.xdmf writes them (ParaView matches the two by time)
                assert float(f[path.rsplit("/", 1)[0]].attrs["time"]) == pytest.approx(times[-1], rel=1e-9)
                names.append(attr.get("Name"))
            assert set(FIELDS) <= set(names)
    return times


def test_xdmf_is_well_formed_and_points_at_the_datasets(tmp_path):
    write(tmp_path, [fake_sim(0.005 * k, 5 * k, seed=k) for k in range(4)])
    assert check_xdmf(tmp_path, NX, NY) == [0.0, 0.005, 0.01, 0.015]


def test_optional_fields(tmp_path):
    """No last_map / last_beta: left out; a coupling whose last_beta is still None: β is NaN that snapshot."""
    bare = tmp_path / "bare"
    bare.mkdir()
    write(bare, [fake_sim(0.0, 0, solids=False, beta="absent")])
    g = read_gas_fields(bare)
    assert not {"solids_u", "solids_v", "beta"} & set(g)
    write(tmp_path, [fake_sim(0.0, 0, beta="none"), fake_sim(0.01, 10, seed=1)])
    g = read_gas_fields(tmp_path)
    assert np.isnan(g["beta"][0]).all() and np.isfinite(g["beta"][1]).all()
    check_xdmf(tmp_path, NX, NY)


def test_a_run_without_gas_writes_nothing(tmp_path):
    GasFieldWriter(tmp_path)(SimpleNamespace(time=0.0, steps=0, gas=None))
    assert not list(tmp_path.iterdir())


def test_truncate_after_drops_later_snapshots_and_writing_goes_on(tmp_path):
    w = write(tmp_path, [fake_sim(0.01 * k, 10 * k, seed=k) for k in range(4)])
    w.truncate_after(15)  # a checkpoint at step 15: snapshots of steps 20 and 30 are dropped
    g = read_gas_fields(tmp_path)
    np.testing.assert_array_equal(g["step"], [0, 10])
    assert check_xdmf(tmp_path, NX, NY) == [0.0, 0.01]
    later = fake_sim(0.025, 25, seed=9)
    w(later)
    g = read_gas_fields(tmp_path)
    np.testing.assert_array_equal(g["step"], [0, 10, 25])
    np.testing.assert_array_equal(g["p"][-1], later.gas.state.p)
    assert check_xdmf(tmp_path, NX, NY) == [0.0, 0.01, 0.025]
    GasFieldWriter(tmp_path / "none").truncate_after(0)  # no file yet: nothing to do


def test_the_index_kept_between_snapshots_is_the_files(tmp_path):
    """The writer keeps its index in memory (not read back per snapshot); it must equal the file's."""
    write(tmp_path, [fake_sim(0.01 * k, 10 * k, seed=k) for k in range(3)])
    kept = (tmp_path / "gas.xdmf").read_text()
    GasFieldWriter(tmp_path).finalize(None)  # the index rebuilt from gas.h5
    assert (tmp_path / "gas.xdmf").read_text() == kept
    GasFieldWriter(tmp_path)(fake_sim(0.03, 30, seed=5))  # a new writer on the file goes on after its last
    assert check_xdmf(tmp_path, NX, NY) == [0.0, 0.01, 0.02, 0.03]
    np.testing.assert_array_equal(read_gas_fields(tmp_path)["step"], [0, 10, 20, 30])


def test_a_snapshot_cut_off_by_a_crash_is_ignored_then_dropped(tmp_path):
    w = write(tmp_path, [fake_sim(0.0, 0), fake_sim(0.01, 10, seed=1)])
    with h5py.File(tmp_path / "gas.h5", "a") as f:  # what a kill during the third write leaves
        g = f.create_group("snapshots/000002")
        g.attrs.update(time=0.02, step=20)
        g["voidage"] = np.ones((NY, NX))
    assert len(read_gas_fields(tmp_path)["time"]) == 2
    w.finalize(None)
    assert check_xdmf(tmp_path, NX, NY) == [0.0, 0.01]
    w.truncate_after(100)
    with h5py.File(tmp_path / "gas.h5") as f:
        assert sorted(f["snapshots"]) == ["000000", "000001"]


def test_an_unreadable_file_is_set_aside_on_resume(tmp_path):
    (tmp_path / "gas.h5").write_bytes(b"not an HDF5 file")
    w = GasFieldWriter(tmp_path)
    with pytest.warns(RuntimeWarning, match="moved to gas.h5.unreadable"):
        w.truncate_after(10)
    assert (tmp_path / "gas.h5.unreadable").read_bytes() == b"not an HDF5 file"
    assert check_xdmf_empty(tmp_path)
    w(fake_sim(0.02, 20))
    assert check_xdmf(tmp_path, NX, NY) == [0.02]


def check_xdmf_empty(run_dir: Path) -> bool:
    root = ET.parse(run_dir / "gas.xdmf").getroot()
    (collection,) = root.find("Domain").findall("Grid")
    return collection.findall("Grid") == []


# ---------------------------------------------------------------- a real coupled run
def test_a_coupled_run_writes_its_gas_state(tmp_path):
    out = tmp_path / "run"
    sim = run_tiny_jet(out, until=0.01)
    g = read_gas_fields(out)
    np.testing.assert_allclose(g["time"], np.arange(6) * 0.002, atol=1e-12)  # t = 0 and every 2 ms
    st = sim.gas.state
    np.testing.assert_array_equal(g["voidage"][-1], st.voidage)
    np.testing.assert_array_equal(g["p"][-1], st.p)
    np.testing.assert_array_equal(g["ux"][-1], 0.5 * (st.u[:-1] + st.u[1:]))
    if getattr(sim.gas, "last_map", None) is not None:
        np.testing.assert_array_equal(g["solids_u"][-1], sim.gas.last_map.solids_u)
    if getattr(sim.gas, "last_beta", None) is not None:
        np.testing.assert_array_equal(g["beta"][-1], sim.gas.last_beta)
    assert np.ptp(g["voidage"][-1]) > 0.1  # a bed in the bottom cells, free gas above
    check_xdmf(out, 6, 24)


def test_resumed_run_rewrites_the_snapshots_after_its_checkpoint(tmp_path):
    whole = tmp_path / "whole"
    run_tiny_jet(whole)
    out = tmp_path / "run"
    run_tiny_jet(out, until=0.01)  # its last checkpoint: t = 0.01 s
    kept = tmp_path / "restart-at-0.01.h5"
    shutil.copy(out / "restart.h5", kept)
    sim = Simulation.resume(out)
    sim.observers["gas_fields"] = GasFieldWriter(out, EveryTime(0.002))
    sim.run(until=0.016)  # gas snapshots up to 0.016 s; then a "crash" loses the checkpoint made at the end
    shutil.copy(kept, out / "restart.h5")
    assert read_gas_fields(out)["time"][-1] == pytest.approx(0.016)

    again = Simulation.resume(out)
    writer = GasFieldWriter(out, EveryTime(0.002))
    writer.truncate_after(again.steps)  # what Simulation does for its own observers on resume
    np.testing.assert_allclose(read_gas_fields(out)["time"], np.arange(6) * 0.002, atol=1e-12)
    again.observers["gas_fields"] = writer
    again.run()
    g, ref = read_gas_fields(out), read_gas_fields(whole)
    np.testing.assert_array_equal(g["step"], ref["step"])
    np.testing.assert_allclose(g["time"], np.arange(11) * 0.002, atol=1e-12)
    # not bit for bit (tests/verification/test_coupled_restart.py says why), but to the gas tolerance
    np.testing.assert_allclose(g["p"], ref["p"], rtol=1e-9)
    np.testing.assert_allclose(g["voidage"], ref["voidage"], rtol=0, atol=1e-6)
    assert check_xdmf(out, 6, 24) == pytest.approx(list(np.arange(11) * 0.002), abs=1e-12)


def test_vtk_reads_the_index_in_the_x_y_plane(tmp_path):
    """Optional (needs the ``vtk`` wheel): VTK's XDMF reader, the one ParaView ships as "XDMF Reader",
    gives a rectilinear grid over the domain in the x-y plane with the cells in the right order."""
    pytest.importorskip("vtkmodules.vtkIOXdmf2")
    from vtkmodules.util.numpy_support import vtk_to_numpy
    from vtkmodules.vtkIOXdmf2 import vtkXdmfReader

    sims = [fake_sim(0.01 * k, 10 * k, seed=k) for k in range(2)]
    write(tmp_path, sims)
    reader = vtkXdmfReader()
    reader.SetFileName(str(tmp_path / "gas.xdmf"))
    reader.UpdateInformation()
    reader.UpdateTimeStep(0.01)
    grid = reader.GetOutputDataObject(0)
    assert grid.GetDimensions() == (NX + 1, NY + 1, 1)
    np.testing.assert_allclose(grid.GetBounds(), (0.0, 0.03, 0.0, 0.1, 0.0, 0.0))
    voidage = vtk_to_numpy(grid.GetCellData().GetArray("voidage"))
    np.testing.assert_array_equal(voidage.reshape(NY, NX).T, sims[1].gas.state.voidage)
