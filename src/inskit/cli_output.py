"""What every command prints: one JSON object on stdout (``--json``) or a
table, logs on stderr.  Shared by :mod:`inskit.cli` and its command groups."""

from __future__ import annotations

import json
import math
import sys
import time

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


def log_health(h):
    """A health verdict on stderr: the verdict, each reason, each warning."""
    log(f"health: {h['verdict']}")
    for line in h["reasons"]:
        log(f"  unhealthy: {line}")
    for line in h["warnings"]:
        log(f"  warning: {line}")


class LineProgress:
    """Progress for a stderr that is not a terminal (a log file, CI, a pipe):
    a plain line at most every ``every_s`` seconds, the first only after
    ``every_s`` (a short job prints none), with the count, the rate and the
    time left.  A terminal gets tqdm's bar instead (:func:`progress`)."""

    def __init__(self, total, desc, unit="it", initial=0, every_s=10.0, stream=None):
        self.total, self.desc, self.unit, self.n = total, desc, unit, initial
        self.every_s, self.stream = every_s, stream if stream is not None else sys.stderr
        self.t0 = self.last = time.monotonic()
        self.n0 = initial

    def update(self, n=1):
        self.n += n
        now = time.monotonic()
        if now - self.last >= self.every_s:
            self.last = now
            self.stream.write(self.line(now) + "\n")
            self.stream.flush()

    def line(self, now=None):
        """The progress line at time ``now`` (monotonic seconds)."""
        el = (time.monotonic() if now is None else now) - self.t0
        done = self.n - self.n0
        rate = done / el if el > 0 else 0.0
        text = f"{self.desc}: {self.n:,.0f}" + (f" of {self.total:,.0f}" if self.total else "") + f" {self.unit}s"
        text += f", {el:.0f} s"
        if self.total and rate > 0:
            text += f", about {max(self.total - self.n, 0) / rate:.0f} s left"
        return text

    def close(self):
        pass

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False


def progress(total, desc, unit="it", initial=0, **tqdm_kw):
    """A progress bar on stderr: tqdm's on a terminal, :class:`LineProgress`
    lines elsewhere (long work shows progress in a log too).  Use as a
    context manager; ``.update(n)``."""
    if sys.stderr.isatty():
        from tqdm import tqdm

        return tqdm(total=total, desc=desc, unit=unit, initial=initial, file=sys.stderr, **tqdm_kw)
    return LineProgress(total, desc, unit, initial)


#: plain JSON values (numpy, paths; non-finite floats as ``null``): :func:`inskit.files.plain_json`
jsonable = plain_json


def emit(obj, as_json, table=None):
    """Exactly one JSON object on stdout with ``as_json``, else the table."""
    if as_json:
        click.echo(json.dumps(jsonable(obj), allow_nan=False))
    elif table is not None:
        click.echo(table)


def reproduce_into(out_dir, force, job):
    """``job(folder)`` of a reproduction, run into ``out_dir`` as a set: a
    folder that already holds files refused before the work unless
    ``force`` (the user's fig6_accel_sweep.png was replaced without a word),
    the files written into a staging folder and moved into ``out_dir``
    together once the job is through (a failed or interrupted run leaves
    ``out_dir`` as it was: :func:`inskit.files.staged_tree`).  Returns the
    job's result with its paths in ``out_dir`` and the list of every file
    written (the summary's ``files``: a job's own lists left out its tables
    or the simulated files beside its figures)."""
    from pathlib import Path

    from .files import check_results_folder, relocated, staged_tree

    check_results_folder(out_dir, force)
    with staged_tree(out_dir) as tmp:
        res = job(tmp)
        written = sorted(str(p) for p in tmp.rglob("*") if p.is_file())
    return relocated(res, tmp, Path(out_dir)), relocated(written, tmp, Path(out_dir))
