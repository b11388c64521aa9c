"""The install-time warm-up (:mod:`inskit.jobs.compile_cache`): every
command it runs is one the CLI accepts as written (a renamed option would
make the warm-up fail at install, and the command it stood for compile at
its user's first run again)."""

from pathlib import Path

import click
import pytest

from inskit.cli import cli
from inskit.jobs import compile_cache as W


def _commands(tmp_path):
    return [(label, args) for g in W.steps(tmp_path) for label, args in g]


def test_every_warm_up_command_parses(tmp_path):
    cmds = _commands(tmp_path)
    assert len(cmds) >= 20
    families = {str(a[0]) if a[0] not in ("platform", "gyrofree") else f"{a[0]} {a[1]}" for _, a in cmds}
    # the command families of the README's list whose kernels are compiled
    assert {"navigate", "simulate", "mechanize", "align", "allan", "schemes", "spp", "evaluate",
            "platform simulate", "platform integrate", "gyrofree simulate", "gyrofree navigate"} <= families
    for label, args in cmds:
        words = [str(a) for a in args]
        ctx = cli.make_context("inskit", list(words), resilient_parsing=False)
        sub = ctx.command.get_command(ctx, words[0])
        rest = words[1:]
        if isinstance(sub, click.Group):
            sub_ctx = sub.make_context(words[0], list(rest))
            sub, rest = sub.get_command(sub_ctx, rest[0]), rest[1:]
        assert sub is not None, label
        try:
            sub.make_context(words[0], list(rest))
        except click.exceptions.BadParameter as exc:  # a path that does not exist yet is fine here
            assert "does not exist" in str(exc), (label, exc)
        except click.UsageError as exc:
            pytest.fail(f"{label}: {' '.join(words)}: {exc}")


def test_the_inputs_it_names_are_in_the_repository(tmp_path):
    """The bundled files the warm-up reads (examples and data) exist; the
    others are made by an earlier command of its group."""
    made = set()
    for g in W.steps(tmp_path):
        for label, args in g:
            for a in args:
                if isinstance(a, Path) and not str(a).startswith(str(tmp_path)):
                    assert a.is_file(), (label, a)
            made.add(label)
    assert made
