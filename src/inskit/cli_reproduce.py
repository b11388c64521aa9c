"""Command line of ``inskit reproduce all``: a thin layer over
:func:`inskit.jobs.reproduce_all.run_all`.

Wiring into :mod:`inskit.cli` (done there, not here)::

    from .cli_reproduce import register
    register(reproduce)

Conventions of :mod:`inskit.cli`: ``--json`` prints exactly one JSON object on
stdout, logs go to stderr, user errors raise :class:`~inskit.errors.InputError`
or :class:`~inskit.errors.ConfigError` (``inskit.cli.main`` turns them into
one line and exit status 2).
"""

from __future__ import annotations

import sys

import click

from .cli_output import emit as _emit
from .cli_output import log as _log


@click.command("all")
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False),
              help="Output folder: REPORT.md, report.html (self-contained), reproduce.json and one folder of "
                   "figures per experiment.")
@click.option("--only", metavar="A,B", help="Run only these experiments (comma-separated names).")
@click.option("--force", is_flag=True, help="Write into a folder that is not an earlier reproduce all's although it "
              "holds files of the report's names (REPORT.md, report.html, reproduce.json) or an experiment's "
              "folder, replacing them.")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object on stdout.")
def reproduce_all(out_dir, only, force, as_json):
    """Every published experiment and every measured README claim, one report.

    Each experiment runs through the job of its own command; every quantity
    gets published (or claimed) against ours, a stated tolerance and a
    verdict: pass, differs (a published figure we do not reproduce, with the
    reason in the note), fail, or info (machine-dependent, not judged).

    Exit status: 0 when every experiment passes (differs and info included),
    1 when any experiment fails (a quantity outside its tolerance, or an
    error); the table and the JSON name the failures.
    """
    from .jobs.reproduce_all import fmt, run_all

    res = run_all(out_dir, only=only, log=_log, force=force)
    lines = [f"{'experiment':<22}{'verdict':<9}{'pass':>5}{'differs':>8}{'fail':>5}{'info':>5}{'seconds':>9}"]
    for e in res["experiments"]:
        c = e["counts"]
        lines.append(f"{e['name']:<22}{e['verdict']:<9}{c['pass']:>5}{c['differs']:>8}{c['fail']:>5}{c['info']:>5}"
                     f"{e['seconds']:>9.1f}")
        for q in e["quantities"]:
            if q["verdict"] == "fail":
                lines.append(f"    FAIL {q['quantity']}: ours {fmt(q['ours'])}, reference {fmt(q['reference'])} "
                             f"+- {fmt(q['tolerance'])} {q['unit']}")
        if e["error"]:
            lines.append(f"    ERROR {e['error']}")
    lines.append(f"total {res['seconds']:.0f} s; failed: {', '.join(res['failed']) or 'none'}")
    lines.append("report: " + ", ".join(res["files"]))
    summary = {"experiments": [{k: v for k, v in e.items() if k != "extra"} for e in res["experiments"]],
               "failed": res["failed"], "seconds": res["seconds"], "files": res["files"]}
    _emit(summary, as_json, "\n".join(lines))
    if res["failed"]:
        sys.exit(1)


def register(reproduce_group):
    """Add ``all`` to the ``reproduce`` group."""
    reproduce_group.add_command(reproduce_all, "all")


__all__ = ["register", "reproduce_all"]
