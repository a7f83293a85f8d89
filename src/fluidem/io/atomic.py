"""Atomic file replacement: write to a temporary sibling, fsync, then rename.

``durable=False`` leaves out the fsync: the rename still replaces the file in one step (a reader sees
the old or the new file, never a part), but after a crash of the operating system the new contents may
be lost. For indexes rewritten many times a run and made again from their data on resume (the XDMF
files): an fsync costs milliseconds, hundreds of times a run."""
from __future__ import annotations

import os
from contextlib import contextmanager
from pathlib import Path


@contextmanager
def atomic_path(path: Path, durable: bool = True):
    """Yield a temporary path; on success it replaces ``path`` in one rename (after an fsync if ``durable``)."""
    path = Path(path)
    tmp = path.with_name(path.name + ".tmp")
    try:
        yield tmp
        if durable:
            with open(tmp, "rb") as f:
                os.fsync(f.fileno())
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()


def write_text_atomic(path: Path, text: str, durable: bool = True) -> None:
    with atomic_path(path, durable) as tmp:
        Path(tmp).write_text(text)
