"""Exceptions that carry a message meant for the user.

The CLI prints these as one line and exits non-zero; anything else is a bug.
"""


class InskitError(Exception):
    """Base class of errors caused by the user's input or configuration."""


class InputError(InskitError, ValueError):
    """Bad input data: a file, an array or an argument that cannot be used.

    The message names the file (or argument), the row or column, and what was
    expected.
    """


class ConfigError(InskitError, ValueError):
    """An impossible or inconsistent configuration."""
