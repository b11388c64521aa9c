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


def is_number(x) -> bool:
    """A real number (int or float, numpy's too), not a bool (``True`` is an
    int to Python) or a string: the test of an argument that must be one
    before its range is checked."""
    import numbers

    return isinstance(x, numbers.Real) and not isinstance(x, bool)
