"""An XDMF temporal collection that grows by one ``<Grid>`` per snapshot at constant cost.

The particle and gas writers each keep an index file (``particles.xdmf``, ``gas.xdmf``) that lists
every snapshot written so far, so ParaView can open a run while it goes on or after it stopped.
Rewriting the whole file at every snapshot costs O(snapshots) each time (at 400 snapshots of the
tsuji-jet-background case: 1 MB, 10–20 ms a snapshot, a few per cent of the run), so ``XdmfIndex`` writes the
file once and then appends: the new grid and the closing tags go in one write over the old
closing tags. A process killed between two snapshots leaves a complete, valid file; one write of a
few kilobytes to a regular file is not interrupted half-way by a signal. Whenever the file is not
as this object left it (missing, another size: a run resumed, another process), ``append`` writes
the whole document again from ``rewrite``'s list, atomically (``io/atomic.py``).
"""
from __future__ import annotations

import os
from pathlib import Path

from .atomic import atomic_path

HEADER = ('<?xml version="1.0" ?>\n<!DOCTYPE Xdmf SYSTEM "Xdmf.dtd" []>\n<Xdmf Version="3.0">\n  <Domain>\n'
          '   <Grid Name="{name}" GridType="Collection" CollectionType="Temporal">\n')
FOOTER = "   </Grid>\n  </Domain>\n</Xdmf>\n"


def drop_after(grp, step: int) -> None:
    """Delete the snapshot groups of ``grp`` (an open HDF5 group of snapshots, each with a ``step``
    attribute) written after ``step``: what a resumed run writes again."""
    for k in list(grp):
        if int(grp[k].attrs["step"]) > step:
            del grp[k]


def document(name: str, grids: list[str]) -> str:
    """The whole XDMF file: a temporal collection ``name`` of the ``<Grid>`` elements ``grids``."""
    return HEADER.format(name=name) + "".join(g + "\n" for g in grids) + FOOTER


class XdmfIndex:
    """The index file ``path``: a temporal collection named ``name``, appended to one grid at a time."""

    def __init__(self, path: Path, name: str):
        self.path = Path(path)
        self.name = name
        self._size: int | None = None  # the file's size as last written here; None: unknown, rewrite

    def rewrite(self, grids: list[str]) -> None:
        """Write the whole file with ``grids`` (atomically, without fsync: it is made again on resume)."""
        data = document(self.name, grids).encode()
        with atomic_path(self.path, durable=False) as tmp:
            Path(tmp).write_bytes(data)
        self._size = len(data)

    def sync(self) -> None:
        """fsync the file (at the end of a run: the appends themselves are not synced)."""
        if self.path.exists():
            fd = os.open(self.path, os.O_RDONLY)
            try:
                os.fsync(fd)
            finally:
                os.close(fd)

    def forget(self) -> None:
        """The file was written elsewhere (``truncate_after``): the next ``append`` writes it whole."""
        self._size = None

    def append(self, grid: str, all_grids) -> None:
        """Add ``grid`` at the end of the collection. ``all_grids()`` gives every grid, this one last, for
        when the file must be written whole (first call, or the file changed behind this object)."""
        footer = FOOTER.encode()
        try:
            size = self.path.stat().st_size
        except FileNotFoundError:
            size = None
        if self._size is None or size != self._size:
            self.rewrite(all_grids())
            return
        data = (grid + "\n").encode() + footer
        with open(self.path, "r+b", buffering=0) as f:  # unbuffered: one write call (os.pwrite is POSIX only)
            f.seek(self._size - len(footer))
            written = f.write(data)
        if written != len(data):  # not seen on a regular file; the whole file then, to be sure
            self.rewrite(all_grids())
            return
        self._size += len(data) - len(footer)
