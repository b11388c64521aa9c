"""inskit.jobs.plots: the run's four PNG files, drawn in two processes on Linux, the same bytes as drawn in one,
and none missing when the second process fails."""

import os
import sys

import pytest

from inskit.jobs import plots as PL
from inskit.jobs.config import load_config
from inskit.jobs.navigate import navigate
from pathlib import Path

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "drive_0708.toml"
NAMES = ["track.png", "errors.png", "innovations.png", "biases.png"]


@pytest.fixture(scope="module")
def run():
    return navigate(load_config(EXAMPLE, {"output": {"plots": False}}))


def test_two_processes_draw_the_same_files_as_one(run, tmp_path):
    one, two = tmp_path / "one", tmp_path / "two"
    one.mkdir()
    two.mkdir()
    assert [p.name for p in PL.plot_all(run, one, parallel=False)] == NAMES
    assert [p.name for p in PL.plot_all(run, two, parallel=True)] == NAMES
    for n in NAMES:
        a, b = (one / n).read_bytes(), (two / n).read_bytes()
        assert a[:8] == b"\x89PNG\r\n\x1a\n" and a == b, n
    assert sorted(os.listdir(two)) == sorted(NAMES)  # no temporary file left behind


@pytest.mark.skipif(not sys.platform.startswith("linux") or (os.cpu_count() or 1) < 2, reason="drawn in one process")
def test_a_failing_second_process_leaves_no_plot_missing(run, tmp_path, monkeypatch):
    parent = os.getpid()
    real = PL._biases

    def fails_in_the_child(c, path, plt):
        if os.getpid() != parent:
            raise RuntimeError("child fails")
        return real(c, path, plt)

    monkeypatch.setattr(PL, "PLOTS", PL.PLOTS[:3] + (("biases.png", fails_in_the_child),))
    files = PL.plot_all(run, tmp_path, parallel=True)
    assert [f.name for f in files] == NAMES and all(f.is_file() and f.stat().st_size > 1000 for f in files)
    assert sorted(os.listdir(tmp_path)) == sorted(NAMES)


def test_a_failing_plot_of_the_parent_is_raised_and_the_child_reaped(run, tmp_path, monkeypatch):
    def broken(c, path, plt):
        raise RuntimeError("parent's plot fails")

    forked = []
    real_fork = os.fork

    def fork():
        pid = real_fork()
        if pid:
            forked.append(pid)
        return pid

    monkeypatch.setattr(PL, "PLOTS", (("track.png", broken),) + PL.PLOTS[1:])
    monkeypatch.setattr(os, "fork", fork)
    with pytest.raises(RuntimeError, match="parent's plot fails"):
        PL.plot_all(run, tmp_path, parallel=True)
    if forked:  # the child was waited for: no zombie left behind
        with pytest.raises(ChildProcessError):
            os.waitpid(forked[0], os.WNOHANG)


def test_errors_plot_draws_no_line_across_a_gap_of_the_fixes(run, tmp_path, monkeypatch):
    """errors.png: where the GNSS file has no fix for 30 s, nothing was
    measured, and no line joins the errors on either side."""
    from types import SimpleNamespace

    import numpy as np

    from inskit.types import GnssData

    g = run.gnss
    t0 = g.time[0]
    keep = ~((g.time - t0 > 60.0) & (g.time - t0 < 90.0))
    res = SimpleNamespace(**{k: getattr(run, k) for k in ("forward", "smoothed", "config", "windows")},
                          gnss=GnssData(g.time[keep], g.lla[keep], g.sigma_ned[keep]), used=run.used[keep])
    figs = []
    monkeypatch.setattr(PL, "save_figure", lambda fig, path, dpi=110: figs.append(fig))
    PL._errors(PL._Context(res), tmp_path / "errors.png", PL._plt())
    for ax in figs[0].axes:
        for ln in ax.get_lines():
            x, y = ln.get_data()
            inside = (x > 61.0) & (x < 89.0)
            assert inside.any() and np.isnan(y[inside]).all()
