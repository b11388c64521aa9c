"""Reading TOML files and turning pydantic validation errors into one line.

Shared by the ``navigate`` configuration and the simulation scenarios.
"""

from __future__ import annotations

import tomllib
from pathlib import Path

from pydantic import ValidationError

from .errors import ConfigError


def read_toml(path, kind="config"):
    """The parsed TOML of ``path``; a missing file or bad syntax is a ConfigError."""
    path = Path(path)
    if not path.is_file():
        raise ConfigError(f"{path}: no such {kind} file")
    try:
        return tomllib.loads(path.read_text())
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{path}: not valid TOML ({exc})") from None


def validation_message(source, exc: ValidationError):
    """``source: field 'a.b': what is wrong (and N more)``."""
    errors = exc.errors()
    e = errors[0]
    where = ".".join(str(x) for x in e["loc"]) or "(top level)"
    more = f" (and {len(errors) - 1} more)" if len(errors) > 1 else ""
    return f"{source}: field '{where}': {e['msg']}{more}"
