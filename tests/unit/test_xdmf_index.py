"""The XDMF index that grows by one grid per snapshot (``fluidem.io.xdmf``)."""
from __future__ import annotations

import xml.etree.ElementTree as ET

from fluidem.io.xdmf import XdmfIndex, document


def grid(k: int) -> str:
    return f'    <Grid Name="g_{k:06d}" GridType="Uniform">\n      <Time Value="{0.01 * k:.9g}"/>\n    </Grid>'


def times(path) -> list[float]:
    root = ET.parse(path).getroot()
    return [float(t.get("Value")) for t in root.iter("Time")]


def test_appending_gives_the_whole_document_and_a_valid_file_after_each_grid(tmp_path):
    path = tmp_path / "x.xdmf"
    index = XdmfIndex(path, "things")
    grids = []
    for k in range(5):
        grids.append(grid(k))
        index.append(grids[-1], lambda: list(grids))
        assert path.read_text() == document("things", grids)
        assert times(path) == [0.01 * j for j in range(k + 1)]


def test_a_file_changed_behind_the_index_is_written_whole(tmp_path):
    path = tmp_path / "x.xdmf"
    index = XdmfIndex(path, "things")
    grids = [grid(0), grid(1)]
    index.rewrite(grids)
    path.write_text(document("things", grids[:1]))  # another writer (a resume) left one grid
    grids.append(grid(2))
    index.append(grids[-1], lambda: list(grids))
    assert path.read_text() == document("things", grids)
    path.unlink()  # removed: written whole again
    grids.append(grid(3))
    index.append(grids[-1], lambda: list(grids))
    assert times(path) == [0.0, 0.01, 0.02, 0.03]


def test_an_empty_collection_is_valid(tmp_path):
    path = tmp_path / "x.xdmf"
    XdmfIndex(path, "things").rewrite([])
    assert times(path) == [] and ET.parse(path).getroot().tag == "Xdmf"
