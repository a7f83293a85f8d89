"""The wall shapes' triangles at each particle snapshot time (``shapes.h5`` + ``shapes.xdmf``): the index
parses as XML, lists the particle snapshots' times, and the triangles it points at are
``ShapeSet.world_triangles(t)`` at each of them (static shapes written once, moving ones per snapshot); a
resumed run leaves the same files as one made in one go."""
from __future__ import annotations

import xml.etree.ElementTree as ET

import h5py
import numpy as np
import pytest

from fluidem.case import validate_case
from fluidem.io.snapshots import snapshot_index
from fluidem.io.shapes_xdmf import moving_triangles

R = 0.02  # paddle half-width [m]


def _case(end=0.02):
    s = 0.04
    return validate_case({
        "name": "paddle", "gravity": [0.0, 0.0, -9.81],
        "particles": {"species": [{"name": "p", "diameter": 3e-3, "density": 2500.0, "count": 4}],
                      "contact": {"model": "linear_spring_dashpot", "stiffness": 2e3, "restitution": 0.6,
                                  "friction": 0.4},
                      "placement": {"method": "lattice", "region_lower": [-0.01, -0.01, 0.03],
                                    "region_upper": [0.01, 0.01, 0.04]}},
        "walls": [
            {"name": "floor", "kind": "polygon", "points": [[-s, -s, 0.0], [s, -s, 0.0], [s, s, 0.0], [-s, s, 0.0]]},
            {"name": "paddle", "kind": "polygon",
             "points": [[-R, 0.0, 0.005], [R, 0.0, 0.005], [R, 0.0, 0.02], [-R, 0.0, 0.02]],
             "motion": {"kind": "rotation", "axis_point": [0.0, 0.0, 0.0], "axis": [0.0, 0.0, 1.0],
                        "angular_velocity": 20.0}},
            {"name": "drum", "kind": "cylinder", "point": [0.0, 0.0, 0.0], "axis": [0.0, 0.0, 1.0], "radius": 0.035,
             "length": 0.05, "motion": {"kind": "oscillation", "amplitude": [0.0, 0.0, 0.001], "frequency": 20.0}},
        ],
        "time": {"end": end},
        "output": {"snapshot_interval": 0.005, "probe_interval": 0.005}})


def _read(run):
    """[(time, triangles (T_s + T_m, 3, 3) static first)] from shapes.xdmf and the datasets it names (the time
    as the snapshot's attribute holds it; the index's 9 digits must agree)."""
    root = ET.parse(run / "shapes.xdmf").getroot()
    temporal = root.find("Domain/Grid")
    assert temporal.get("CollectionType") == "Temporal"
    out = []
    with h5py.File(run / "shapes.h5", "r") as f:
        for grid in temporal.findall("Grid"):
            t = float(f["snapshots/" + grid.get("Name").removeprefix("shapes_")].attrs["time"])
            assert float(grid.find("Time").get("Value")) == pytest.approx(t, rel=1e-8, abs=1e-12)  # 9 digits
            parts = []
            for part in grid.findall("Grid"):
                topo = part.find("Topology")
                assert topo.get("TopologyType") == "Triangle"
                conn_item, pts_item = topo.find("DataItem"), part.find("Geometry/DataItem")
                conn = np.asarray(f[conn_item.text.split(":", 1)[1]])
                pts = np.asarray(f[pts_item.text.split(":", 1)[1]])
                assert conn.shape == tuple(int(v) for v in conn_item.get("Dimensions").split())
                assert pts.shape == tuple(int(v) for v in pts_item.get("Dimensions").split())
                assert conn.shape[0] == int(topo.get("NumberOfElements"))
                parts.append(pts[conn])
            out.append((t, np.concatenate(parts)))
    return out


def test_shape_triangles_at_each_snapshot(stopped_and_resumed, tmp_path):
    whole, first, again = stopped_and_resumed(_case(), 0.01)
    run = tmp_path / "run"
    shapes = again.engine.shapes
    moving = moving_triangles(shapes)
    assert moving.any() and (~moving).any()
    frames = _read(run)
    times = [t for _, t in snapshot_index(run)]
    assert [t for t, _ in frames] == pytest.approx(times, abs=1e-12), "one shape frame per particle snapshot"
    assert len(frames) >= 5
    for t, tri in frames:
        expected = shapes.world_triangles(t)
        np.testing.assert_array_equal(tri, np.concatenate([expected[~moving], expected[moving]]))
    with h5py.File(run / "shapes.h5", "r") as f:
        # the static triangles once, the moving ones at every snapshot
        assert f["static/points"].shape == (3 * int((~moving).sum()), 3)
        assert all(set(g) == {"points"} for g in f["snapshots"].values())
    # the moving shapes moved between the first and the last frame; a resumed run wrote what one run writes
    assert not np.array_equal(frames[0][1], frames[-1][1])
    assert (run / "shapes.xdmf").read_text().count("<Time ") == len(times)
