"""Atomic file replacement: write to a temporary sibling, fsync, then rename.

``durable=False`` leaves out the fsync: the rename still replaces the file in one step (a reader sees
the old or the new file, never a part), but after a crash of the operating system the new contents may
be lost. For indexes rewritten many times a run and made again from their data on resume (the XDMF
files): an fsync costs milliseconds, hundreds of times a run.

``previous`` keeps the file being replaced: just before the new file takes its name, the old one is
renamed to ``previous`` (replacing what was there). At every moment ``path`` or ``previous`` holds the
last complete file, and ``previous`` the one before once both renames are done; a failed write (a full
disk) happens before either rename and leaves both as they were."""
from __future__ import annotations

import os
from contextlib import contextmanager
from pathlib import Path


@contextmanager
def atomic_path(path: Path, durable: bool = True, previous: Path | None = None):
    """Yield a temporary path; on success it replaces ``path`` in one rename (after an fsync if ``durable``).

    With ``previous``, the file ``path`` held until now (if any) is first renamed to ``previous``; with
    ``durable`` the folder is synced after the renames too."""
    path = Path(path)
    tmp = path.with_name(path.name + ".tmp")
    try:
        yield tmp
        if durable:
            with open(tmp, "rb") as f:
                os.fsync(f.fileno())
        if previous is not None and path.exists():
            os.replace(path, previous)
        os.replace(tmp, path)
        if durable and previous is not None:
            _sync_folder(path.parent)
    finally:
        if tmp.exists():
            tmp.unlink()


def _sync_folder(folder: Path) -> None:
    """fsync a folder, so that renames in it survive a crash of the operating system (POSIX; elsewhere
    nothing)."""
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def write_text_atomic(path: Path, text: str, durable: bool = True) -> None:
    with atomic_path(path, durable) as tmp:
        Path(tmp).write_text(text)
