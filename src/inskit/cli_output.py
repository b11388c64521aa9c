"""What every command prints: one JSON object on stdout (``--json``) or a
table, logs on stderr.  Shared by :mod:`inskit.cli` and its command groups."""

from __future__ import annotations

import json
import math

import click

from .files import plain_json
from .units import MAX_RATE_HZ


#: the type of every ``--seed``: NumPy seeds are integers >= 0 (a negative one was an internal error, exit 3)
SEED = click.IntRange(min=0)


def _refuse_non_finite(param_type, value, param, ctx):
    if isinstance(value, float) and not math.isfinite(value):
        param_type.fail(f"{value} is not a finite number (expected one, e.g. 10 or 2.5)", param, ctx)
    return value


class FiniteFloat(click.types.FloatParamType):
    """A float option that refuses nan and inf (click takes both; '--from nan' then read as a time
    'outside the data')."""

    name = "float"

    def convert(self, value, param, ctx):
        return _refuse_non_finite(self, super().convert(value, param, ctx), param, ctx)


class FiniteFloatRange(click.FloatRange):
    """:class:`click.FloatRange` that refuses nan and inf (nan passes click's bounds: every comparison is
    false)."""

    def convert(self, value, param, ctx):
        v = click.types.FloatParamType.convert(self, value, param, ctx)
        _refuse_non_finite(self, v, param, ctx)
        return super().convert(v, param, ctx)


#: the type of every float option
FINITE = FiniteFloat()


class RateHz(FiniteFloatRange):
    """A rate option [Hz]: finite, > 0 and at most :data:`inskit.units.MAX_RATE_HZ` (the cap of a
    scenario's ``[imu] rate_hz``); without the cap ``--rate 1e7`` grew to 24 GB before the system killed
    it."""

    name = "float"

    def __init__(self):
        super().__init__(min=0.0, min_open=True, max=MAX_RATE_HZ)

    def convert(self, value, param, ctx):
        v = click.types.FloatParamType.convert(self, value, param, ctx)
        _refuse_non_finite(self, v, param, ctx)
        if not 0.0 < v <= MAX_RATE_HZ:
            self.fail(f"{v:g} Hz is not a rate within (0, {MAX_RATE_HZ:g}] Hz (every rate is capped at "
                      f"{MAX_RATE_HZ:g} Hz, as a scenario's [imu] rate_hz)", param, ctx)
        return v


#: the type of every rate option [Hz] (``--rate``, ``--truth-rate``, ``--output-rate``)
RATE_HZ = RateHz()


def log(msg):
    """A log line on stderr."""
    click.echo(msg, err=True)


#: plain JSON values (numpy, paths; non-finite floats as ``null``): :func:`inskit.files.plain_json`
jsonable = plain_json


def emit(obj, as_json, table=None):
    """Exactly one JSON object on stdout with ``as_json``, else the table."""
    if as_json:
        click.echo(json.dumps(jsonable(obj), allow_nan=False))
    elif table is not None:
        click.echo(table)
