"""What every command prints: one JSON object on stdout (``--json``) or a
table, logs on stderr.  Shared by :mod:`inskit.cli` and its command groups."""

from __future__ import annotations

import json
import math
from pathlib import Path

import click
import numpy as np


#: the type of every ``--seed``: NumPy seeds are integers >= 0 (a negative one was an internal error, exit 3)
SEED = click.IntRange(min=0)


def log(msg):
    """A log line on stderr."""
    click.echo(msg, err=True)


def jsonable(x):
    """Plain JSON values for numpy scalars and arrays, paths, and non-finite
    floats (``null``: NaN is not JSON)."""
    if isinstance(x, dict):
        return {str(k): jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [jsonable(v) for v in x]
    if isinstance(x, np.ndarray):
        return jsonable(x.tolist())
    if isinstance(x, (np.floating, float)):
        x = float(x)
        return x if math.isfinite(x) else None
    if isinstance(x, (np.integer, np.bool_)):
        return x.item()
    if isinstance(x, Path):
        return str(x)
    return x


def emit(obj, as_json, table=None):
    """Exactly one JSON object on stdout with ``as_json``, else the table."""
    if as_json:
        click.echo(json.dumps(jsonable(obj), allow_nan=False))
    elif table is not None:
        click.echo(table)
