"""``inskit report``: the command over inskit.jobs.report (registered on a
bare click group, as inskit.cli will do)."""

import json
from pathlib import Path

import click
import pytest
from click.testing import CliRunner

from inskit.cli_report import register
from inskit.errors import InputError

def _group():
    g = click.Group()
    register(g)
    return g


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    """A small real run: the tightly coupled walk (about 5 s)."""
    from inskit.jobs import navigate as N
    from inskit.jobs.config import load_config

    root = Path(__file__).resolve().parents[1]
    cfg = load_config(root / "examples" / "walk_0827_tight.toml", {"output": {"plots": False}})
    res = N.navigate(cfg)
    out = tmp_path_factory.mktemp("walk")
    N.write_outputs(res, out, N.summary(res))
    return out


def test_report_json(run_dir, tmp_path):
    out = tmp_path / "r.html"
    r = CliRunner().invoke(_group(), ["report", str(run_dir), "--out", str(out), "--json"])
    assert r.exit_code == 0, r.output
    obj = json.loads(r.stdout)
    assert set(obj) == {"report", "bytes", "plots", "seconds"}
    assert obj["report"] == str(out) and obj["bytes"] == out.stat().st_size
    assert obj["plots"] == ["track", "sigmas", "innovations", "estimates"]
    text = out.read_text()
    assert "receiver clock bias" in text and "receiver clock drift" in text  # the walk's clock estimates
    # tight coupling never fuses the RTK fixes: they are scored as a reference, not as a fit
    assert "against the reference fixes (never fused)" in text and "fit to the used fixes" not in text
    assert "unhealthy" not in text
    assert '"customdata":["G' in text  # a range's innovation hovers with its satellite, not its row index


def test_report_default_path_and_table(run_dir):
    r = CliRunner().invoke(_group(), ["report", str(run_dir)])
    assert r.exit_code == 0, r.output
    assert (run_dir / "report.html").exists()
    assert r.stdout.startswith(f"report: {run_dir / 'report.html'}")


def test_report_not_a_run_folder(tmp_path):
    r = CliRunner().invoke(_group(), ["report", str(tmp_path)])
    assert r.exit_code != 0
    assert isinstance(r.exception, InputError) and "summary.json is missing" in str(r.exception)


def test_report_never_overwrites_the_run_or_a_users_file(run_dir, tmp_path):
    """`report RUN --out RUN/summary.json` replaced the run's summary with HTML
    (every later report then failed), and any existing file was replaced
    without a word; report had no --force."""
    summary = (run_dir / "summary.json").read_bytes()
    r = CliRunner().invoke(_group(), ["report", str(run_dir), "--out", str(run_dir / "summary.json"), "--force"])
    assert isinstance(r.exception, InputError) and "is an input of this command" in str(r.exception)
    assert (run_dir / "summary.json").read_bytes() == summary
    mine = tmp_path / "mine.html"
    mine.write_text("my notes")
    r = CliRunner().invoke(_group(), ["report", str(run_dir), "--out", str(mine)])
    assert isinstance(r.exception, InputError) and "already exists" in str(r.exception) and "--force" in str(
        r.exception)
    assert mine.read_text() == "my notes"
    r = CliRunner().invoke(_group(), ["report", str(run_dir), "--out", str(mine), "--force"])
    assert r.exit_code == 0, r.output
    assert mine.read_text().startswith("<!DOCTYPE html>")


def test_report_into_a_folder_not_there_yet(run_dir, tmp_path):
    """`report RUN --out new/r.html` built the page, then failed: 'new/r.html: could not be written (No such
    file or directory)'; the folder is now made before the work, as every other output's."""
    out = tmp_path / "new" / "deeper" / "r.html"
    r = CliRunner().invoke(_group(), ["report", str(run_dir), "--out", str(out), "--json"])
    assert r.exit_code == 0, r.output
    assert json.loads(r.stdout)["report"] == str(out) and out.read_text().startswith("<!DOCTYPE html>")
