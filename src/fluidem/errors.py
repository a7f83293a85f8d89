"""Errors a user can act on: bad case input, unusable output folders."""


class CaseError(ValueError):
    """Bad input: the message names the key, the value and what is allowed."""
