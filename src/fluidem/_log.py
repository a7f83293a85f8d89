"""How the ``fluidem`` command shows the package's log records: one handler on stderr.

Library code reports through ``logging.getLogger("fluidem")`` or its children (``fluidem.progress``
for the progress lines of a run, ``fluidem.cli`` for the command's own notes); the package adds only
a ``NullHandler`` to that logger, so a program that imports fluidem decides what it sees. The command
line installs ``CommandHandler`` for the time of a command (``command_logging``) and words each
record by its level, without timestamps::

    DEBUG      DEBUG: fluidem.cli: message       (shown with --verbose)
    INFO       message                          (progress lines, notes; hidden by --quiet)
    WARNING    WARNING: message
    ERROR      fluidem: error: message           (as argparse words its own usage errors)
"""
from __future__ import annotations

import logging
import sys
from collections.abc import Iterator
from contextlib import contextmanager

LOGGER_NAME = "fluidem"


class CommandFormatter(logging.Formatter):
    """Plain one-line records: the message alone at INFO, prefixed by its level otherwise."""

    def formatMessage(self, record: logging.LogRecord) -> str:  # noqa: N802 - logging's name
        message = record.getMessage()
        if record.levelno >= logging.ERROR:
            return f"fluidem: error: {message}"
        if record.levelno >= logging.WARNING:
            return f"WARNING: {message}"
        if record.levelno >= logging.INFO:
            return message
        return f"DEBUG: {record.name}: {message}"

    def format(self, record: logging.LogRecord) -> str:
        text = self.formatMessage(record)
        if record.exc_info:
            text = f"{text}\n{self.formatException(record.exc_info)}"
        return text


class CommandHandler(logging.StreamHandler):
    """A stream handler that writes to whatever ``sys.stderr`` is when a record is emitted (so that
    output redirected after the handler was made, as ``contextlib.redirect_stderr`` does, is followed)."""

    def __init__(self) -> None:
        super().__init__(sys.stderr)
        self.setFormatter(CommandFormatter())

    @property
    def stream(self):
        return sys.stderr

    @stream.setter
    def stream(self, value) -> None:  # StreamHandler.__init__ and setStream assign it; sys.stderr wins
        pass


def level_for(quiet: bool = False, verbose: bool = False) -> int:
    """The ``fluidem`` logger's level for the command's flags: WARNING with ``--quiet`` (warnings and
    errors only), DEBUG with ``--verbose``, INFO otherwise."""
    if quiet:
        return logging.WARNING
    if verbose:
        return logging.DEBUG
    return logging.INFO


@contextmanager
def command_logging(level: int | None = None) -> Iterator[logging.Logger]:
    """Show the ``fluidem`` logger's records on stderr at ``level`` (default INFO) inside the block.

    Adds one ``CommandHandler`` to the logger and sets its level; both are undone on leaving. Inside a
    block that already installed one (a command handler called by ``fluidem.cli.main``) it changes
    nothing, so the outer block's level holds. Yields the ``fluidem`` logger.
    """
    logger = logging.getLogger(LOGGER_NAME)
    if any(isinstance(h, CommandHandler) for h in logger.handlers):
        yield logger
        return
    handler = CommandHandler()
    previous = logger.level
    logger.addHandler(handler)
    logger.setLevel(logging.INFO if level is None else level)
    try:
        yield logger
    finally:
        logger.removeHandler(handler)
        logger.setLevel(previous)
