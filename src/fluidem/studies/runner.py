"""``fluidem sweep`` and ``fluidem.sweep``: check a study, prepare its folder, run it on Dask.

The order is the promise that bad input writes nothing: the study and every member's case are
validated, the folder is checked (new, empty, or holding this same study), the cluster is reached,
and only then are ``study.toml`` and the members' folders written.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any

from ..errors import CaseError
from ..io.atomic import write_text_atomic
from .definition import STUDY_FILE, StudyDefinition
from .execution import CONNECT_TIMEOUT_S, INSTALL_HINT, Outcome, execute


def check_folder(study: StudyDefinition, folder: str | Path) -> bool:
    """Check that the study can go into ``folder``: new, empty, or holding the same study (a rerun).
    Returns whether it holds the study already; raises ``CaseError`` otherwise, writing nothing."""
    folder = Path(folder)
    if not folder.exists():
        return False
    if not folder.is_dir():
        raise CaseError(f"--out {str(folder)!r} is a file; give a folder for the study")
    definition = folder / STUDY_FILE
    if not definition.is_file():
        if any(folder.iterdir()):
            raise CaseError(f"--out {str(folder)!r} exists, is not empty and holds no study ({STUDY_FILE}); "
                            "choose another --out")
        return False
    try:
        there = StudyDefinition.from_toml(definition.read_text())
    except (OSError, UnicodeDecodeError, ValueError) as err:
        raise CaseError(f"{definition}: cannot be read as a study definition: {err}") from None
    changed = study.differences(there)
    if changed:
        raise CaseError(f"--out {str(folder)!r} holds a different study; a rerun into the same folder must repeat "
                        "its definition (or choose another --out):\n  " + "\n  ".join(changed))
    return True


def write_definition(study: StudyDefinition, folder: str | Path) -> None:
    folder = Path(folder)
    try:
        folder.mkdir(parents=True, exist_ok=True)
        text = study.to_toml()
        path = folder / STUDY_FILE
        if not path.is_file() or path.read_text() != text:  # a rerun of the same study leaves it as it was
            write_text_atomic(path, text)
    except OSError as err:
        raise CaseError(f"--out {str(folder)!r}: cannot write the study there: {err.strerror or err}") from None


def run_study(study: StudyDefinition, folder: str | Path, client=None, scheduler: str | None = None,
              workers: int | None = None, retry: bool = False,
              connect_timeout: float = CONNECT_TIMEOUT_S) -> Outcome:
    """Check ``folder``, then run the study there (``execution.execute``); ``study.toml`` is written once
    the cluster is reached."""
    if workers is not None and (not isinstance(workers, int) or workers < 1):
        raise CaseError(f"--workers {workers!r}: give a whole number of at least 1")
    if not (connect_timeout > 0):
        raise CaseError(f"--connect-timeout {connect_timeout!r}: give a positive number of seconds")
    check_folder(study, folder)
    return execute(study, folder, client=client, scheduler=scheduler, workers=workers, retry=retry,
                   connect_timeout=connect_timeout, on_connected=lambda: write_definition(study, folder))


def sweep(case, vary: dict[str, Any] | None = None, seeds: int | list[int] | None = None,
          until: float | None = None, out: str | Path = "study", client=None, *, combine: str = "product",
          overrides: dict[str, Any] | None = None, threads: int | None = None, workers: int | None = None,
          scheduler: str | None = None, retry: bool = False, connect_timeout: float = CONNECT_TIMEOUT_S):
    """Run a study on Dask and return its table (``study.csv``) as a pandas DataFrame.

    Parameters
    ----------
    case : a built-in case name, a TOML path or a ``fluidem.Case``.
    vary : dotted case key → list of values, e.g. ``{"particles.contact.restitution": [0.8, 0.9, 1.0]}``.
    seeds : a count N (placement seeds 1..N) or a list of seeds (``particles.placement.seed``); each
        combination runs once per seed. None: the case's own seed.
    until : end time of every member [s] (default the case's ``time.end``).
    out : the study folder; a rerun with the same arguments skips finished members and resumes
        interrupted ones.
    client : a ``distributed.Client`` to run on (left open); default: ``scheduler``, else a local cluster.
    combine : ``"product"`` (every combination) or ``"zip"`` (the i-th values together).
    overrides : dotted keys set on every member (what ``--set`` does).
    threads : compute threads of each member (default the case's ``threads``, else 1).
    workers : processes of the local cluster (default cores // threads).
    scheduler : address of a running Dask scheduler, e.g. ``"tcp://10.0.0.5:8786"``.
    retry : run failed members again.

    Returns
    -------
    pandas.DataFrame
        ``study.csv``: one row per member; a member that failed has status ``failed`` and its error.

    Raises
    ------
    CaseError
        Bad input: an unknown key, a refused value, another study in ``out``, an unreachable scheduler
        (nothing written).
    KeyboardInterrupt
        After Ctrl-C, once the running members wrote their checkpoints and the table is written.
    """
    from .definition import parse_seeds

    try:
        import pandas as pd
    except ImportError:
        raise ImportError(f"fluidem.sweep returns a pandas DataFrame, and pandas is not installed: {INSTALL_HINT}") from None
    study = StudyDefinition.build(case, vary or {}, parse_seeds(seeds), combine, until, overrides, threads)
    outcome = run_study(study, out, client=client, scheduler=scheduler, workers=workers, retry=retry,
                        connect_timeout=connect_timeout)
    if outcome.interrupted:
        raise KeyboardInterrupt
    return pd.DataFrame(outcome.rows, columns=outcome.columns)
