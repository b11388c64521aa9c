"""The docs against the command line: every ``inskit`` command line that
README.md and the docs show names a command and options that exist, with
allowed values, and every bundled file or earlier command's output it reads is
there for a user who runs the lines in order from a fresh clone.

The figures the commands print are checked elsewhere: docs/api.md's blocks by
tests/test_api.py, docs/REPRODUCE.md by tests/test_jobs_reproduce_all.py,
docs/config.md by tests/test_jobs_config.py.
"""

from __future__ import annotations

import os
import re
import shlex
from pathlib import Path

import click
import pytest

from inskit.cli import cli

ROOT = Path(__file__).resolve().parents[1]
DOCS = ["README.md", "docs/guide.md", "docs/api.md", "docs/formats.md", "docs/config.md", "docs/gyrofree.md",
        "docs/platform.md", "docs/architecture.md", "docs/REPRODUCE.md"]
#: options of the ``python -m`` entry points the docs name, with the module that takes each
MODULE_OPTIONS = {"--list": "inskit/jobs/compile_cache.py", "--write": "inskit/jobs/config_doc.py",
                  "--check": "inskit/jobs/config_doc.py", "--write-docs": "inskit/jobs/reproduce_all.py"}
#: options whose value is a file or folder the command writes (every other path is read)
OUTPUTS = {"--out", "--plot", "--toml", "--per-epoch"}
#: the run's command lines are order-dependent in these docs: a line may read what an earlier one wrote
IN_ORDER = ["README.md", "docs/guide.md", "docs/gyrofree.md", "docs/platform.md"]


def _command_lines(doc):
    """The ``inskit ...`` lines of the shell blocks of ``doc``, backslash
    continuations joined and comments dropped, in order."""
    lines = []
    for block in re.findall(r"^```(?:sh|bash|console|shell)\n(.*?)^```", (ROOT / doc).read_text(), re.M | re.S):
        for line in block.replace("\\\n", " ").splitlines():
            line = line.strip().removeprefix("$ ")
            if line.startswith("inskit "):
                lines.append(" ".join(shlex.split(line, comments=True)))
    return lines


def _resolve(words):
    """(command, the words of its name, the rest) of ``inskit WORDS``."""
    cmd, name = cli, []
    while isinstance(cmd, click.Group) and words and words[0] in cmd.commands:
        name.append(words[0])
        cmd = cmd.commands[words[0]]
        words = words[1:]
    return cmd, name, words


def _options(cmd):
    opts = {"--help", "-h"}
    for p in cmd.params:
        opts.update(p.opts)
        opts.update(p.secondary_opts)
    return opts


def _all_options():
    found = set()

    def walk(c):
        found.update(_options(c))
        for sub in getattr(c, "commands", {}).values():
            walk(sub)
    walk(cli)
    return found


def _parse(cmd, rest):
    """(option, value or None) pairs and positional words of a command line."""
    by_opt = {o: p for p in cmd.params if isinstance(p, click.Option) for o in p.opts + p.secondary_opts}
    pairs, positional = [], []
    i = 0
    while i < len(rest):
        w = rest[i]
        if w.startswith("--"):
            opt, eq, val = w.partition("=")
            p = by_opt.get(opt)
            takes_value = p is not None and not p.is_flag and not p.count
            if takes_value and not eq and i + 1 < len(rest):
                val, i = rest[i + 1], i + 1
            pairs.append((opt, val if takes_value else None, p))
        else:
            positional.append(w)
        i += 1
    return pairs, positional


def _all_lines():
    return [(doc, line) for doc in DOCS for line in _command_lines(doc)]


def test_the_docs_show_command_lines():
    assert len(_command_lines("README.md")) >= 30 and len(_command_lines("docs/guide.md")) >= 15


@pytest.mark.parametrize(("doc", "line"), _all_lines(), ids=lambda v: v[:60] if isinstance(v, str) else None)
def test_every_command_line_names_a_command_and_its_options(doc, line):
    cmd, name, rest = _resolve(shlex.split(line)[1:])
    assert name, f"{doc}: `{line}` names no inskit command"
    assert not isinstance(cmd, click.Group), f"{doc}: `{line}`: `inskit {' '.join(name)}` needs a subcommand"
    pairs, _ = _parse(cmd, rest)
    for opt, val, p in pairs:
        assert p is not None or opt in ("--help", "-h"), \
            f"{doc}: `{line}`: `inskit {' '.join(name)}` has no option {opt}"
        if p is not None and isinstance(p.type, click.Choice) and val and "|" not in val:
            assert val in p.type.choices, f"{doc}: `{line}`: {opt} takes {p.type.choices}, not {val!r}"


@pytest.mark.parametrize("doc", DOCS)
def test_every_option_the_docs_name_exists(doc):
    """An ``--option`` anywhere in the text (prose too) is an option of some command."""
    known = _all_options()
    text = (ROOT / doc).read_text()
    for opt in sorted(set(re.findall(r"(?<![\w-])(--[a-z][a-z0-9-]*)", text))):
        if opt in MODULE_OPTIONS:
            assert f'"{opt}"' in (ROOT / "src" / MODULE_OPTIONS[opt]).read_text(), opt
        else:
            assert opt in known, f"{doc} names {opt}, an option of no inskit command"


def _navigate_out(config):
    from inskit.jobs.config import load_config

    cfg = load_config(ROOT / config)
    if cfg.output.dir is None:
        return Path("out") / cfg.name
    return Path(os.path.relpath(os.path.normpath(cfg.resolve(cfg.output.dir)), ROOT))


@pytest.mark.parametrize("doc", IN_ORDER)
def test_the_files_a_command_line_reads_are_bundled_or_written_by_an_earlier_line(doc):
    """Run in order from a fresh clone, each line finds what it reads: a bundled
    ``examples/`` or ``data/`` file, or an ``out/`` path an earlier line wrote
    (README's `inskit allan out/static/imu.csv` had no line that wrote it)."""
    written = []
    for line in _command_lines(doc):
        cmd, name, rest = _resolve(shlex.split(line)[1:])
        pairs, positional = _parse(cmd, rest)
        reads = list(positional) + [v for o, v, _ in pairs if v and o not in OUTPUTS]
        for word in reads:
            if word.startswith(("examples/", "data/")):
                assert (ROOT / word).exists(), f"{doc}: `{line}` reads {word}, which is not in the repository"
            elif word.startswith("out/"):
                assert any(Path(word) == w or w in Path(word).parents for w in written), \
                    f"{doc}: `{line}` reads {word}, which no earlier line of {doc} writes"
        outs = [Path(v) for o, v, _ in pairs if o in OUTPUTS and v]
        if name == ["navigate"] and "--out" not in [o for o, _, _ in pairs]:
            outs += [_navigate_out(w) for w in positional if w.startswith("examples/")]
        written += outs


def _missing_required(line):
    """The required options of ``inskit WORDS`` that the line does not give."""
    cmd, name, rest = _resolve(shlex.split(line)[1:])
    if not name or isinstance(cmd, click.Group):
        return []
    pairs, _ = _parse(cmd, rest)
    given = {o for o, _, _ in pairs}
    return [p.opts[0] for p in cmd.params
            if isinstance(p, click.Option) and p.required and not set(p.opts) & given]


@pytest.mark.parametrize(("doc", "line"), _all_lines(), ids=lambda v: v[:60] if isinstance(v, str) else None)
def test_every_command_line_gives_the_required_options(doc, line):
    assert not _missing_required(line), f"{doc}: `{line}` lacks {_missing_required(line)}"


def test_the_readme_figures_name_commands_that_run_as_written():
    """The command column of README's Measured table: each whole command
    (``... --smooth`` continues the row above) gives its required options
    (``inskit reproduce all --only odometer-study`` lacked ``--out``)."""
    rows = [r for r in (ROOT / "README.md").read_text().splitlines() if r.startswith("| ")]
    commands = [c for r in rows for c in re.findall(r"`(inskit [^`]+)`", r.rstrip(" |").rsplit(" | ", 1)[-1])]
    assert len(commands) >= 8
    for line in commands:
        assert not _missing_required(line), f"README.md: `{line}` lacks {_missing_required(line)}"
