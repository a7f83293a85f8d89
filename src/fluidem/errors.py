"""Errors a user can act on: bad case input, unusable output folders."""
from __future__ import annotations


class CaseError(ValueError):
    """Bad input: the message names the key, the value and what is allowed.

    ``problems`` (optional): the same as ``(key path, value, what is wrong)`` triples, the key path a tuple
    relative to the object that was being built (empty for the object as a whole), so that a caller that
    built it as part of a larger input can name the full key.
    """

    def __init__(self, message: str, problems: list[tuple[tuple, object, str]] | None = None):
        super().__init__(message)
        self.problems = problems


class CheckpointError(CaseError):
    """A checkpoint (or the ``case.toml``) of a run directory that cannot be used to resume the run.

    ``path``: the file; ``reason``: what is wrong with it, in words (``"missing"``, ``"not an HDF5 file
    or truncated (…)"``, ``"lacks the array 'gas/p'"``). A subclass of ``CaseError``, so the command line
    reports it in one line and exits with status 2.
    """

    def __init__(self, message: str, path=None, reason: str | None = None):
        super().__init__(message)
        self.path = path
        self.reason = reason
