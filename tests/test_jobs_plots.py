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


def _drawn(monkeypatch, f, res, tmp_path):
    """The matplotlib figure plot function ``f`` draws of ``res``, drawn (not saved)."""
    figs = []
    monkeypatch.setattr(PL, "save_figure", lambda fig, path, dpi=110: figs.append(fig))
    f(PL._Context(res), tmp_path / "x.png", PL._plt())
    figs[0].canvas.draw()
    return figs[0]


def _with_outlier(run):
    """The run with one used fix moved 1 km north and its update refused by the gate
    (its normalised innovation -1000 in north), as a run with a 1 km outlier makes."""
    from types import SimpleNamespace

    import numpy as np

    from inskit.types import GnssData

    g = run.gnss
    lla = g.lla.copy()
    k = int(np.flatnonzero(run.used)[400])
    lla[k, 0] += 1000.0 / 6.37e6
    inn = {n: dict(v) for n, v in run.forward.innovations.items()}
    p = inn["gnss_pos"]
    j = int(np.argmin(np.abs(p["t"] - g.time[k])))
    p["accepted"] = np.asarray(p["accepted"], bool).copy()
    p["accepted"][j] = False
    p["nu"] = p["nu"].copy()
    p["nu"][j] = (-1000.0 * p["sigma"][j, 0], 0.0, 0.0)
    fwd = SimpleNamespace(solution=run.forward.solution, innovations=inn)
    res = SimpleNamespace(**{a: getattr(run, a) for a in ("smoothed", "config", "windows", "used", "settings")},
                          forward=fwd, gnss=GnssData(g.time, lla, g.sigma_ned))
    return res, g.time[k] - g.time[0]


def _tick_labels_apart(ax):
    """No two y tick labels of ``ax`` overlap on the drawn figure."""
    boxes = sorted((t.get_window_extent() for t in ax.get_yticklabels() if t.get_text()), key=lambda b: b.y0)
    return all(b.y0 >= a.y1 - 0.5 for a, b in zip(boxes, boxes[1:]))


def test_errors_plot_shows_a_1_km_outlier_whole_the_rest_readable_and_marks_it_rejected(run, tmp_path, monkeypatch):
    """errors.png of a run with one fix 1 km off: the north axis held +-1080 m
    linearly, so the metre-level errors and sigmas of every other fix were a
    flat line at zero, and nothing said the fix was refused; now the axis is
    symmetric-log (linear within the typical errors), its extremes inside the
    frame, the rejected fix a red x named in the legend, with the 3-sigma
    envelope and the outage shading."""
    import numpy as np

    res, t_out = _with_outlier(run)
    fig = _drawn(monkeypatch, PL._errors, res, tmp_path)
    north = fig.axes[0]
    assert north.get_yscale() == "symlog"
    lo, hi = north.get_ylim()
    assert lo < -1000.0 and hi > 1000.0
    assert north.yaxis.get_transform().linthresh <= 20.0  # the rest stays linear and readable
    assert _tick_labels_apart(north)
    labels = [t.get_text() for t in north.get_legend().get_texts()]
    assert any(s.startswith("fix rejected by the gate (1)") for s in labels), labels
    assert {"forward - GNSS", "forward ±3σ", "GNSS outage (fixes withheld)"} <= set(labels), labels
    marks = [ln for ln in north.get_lines() if ln.get_marker() == "x"]
    assert len(marks) == 1 and np.allclose(marks[0].get_xdata(), [t_out])
    for ax in fig.axes[1:]:  # the other axes: linear as before, the worst error whole
        assert ax.get_yscale() == "linear"
    assert north.get_legend().get_window_extent().y0 >= north.get_window_extent().y1 - 1  # above, hiding nothing


def test_errors_plot_of_an_ordinary_run_stays_linear(run, tmp_path, monkeypatch):
    fig = _drawn(monkeypatch, PL._errors, run, tmp_path)
    assert [ax.get_yscale() for ax in fig.axes] == ["linear"] * 3


def test_innovations_plot_marks_rejected_updates_names_components_and_keeps_the_extreme_inside(
        run, tmp_path, monkeypatch):
    """innovations.png: a refused update was drawn like an accepted one, the
    rows were 'component 0/1/2', and on the symlog axis of a -1000 sigma
    innovation the point sat on the frame, the tick labels 10^0, 0 and -10^0
    on top of each other; now the refused update is a red x in the legend,
    the rows are named, the extreme lies inside and the ticks are apart."""
    res, _ = _with_outlier(run)
    fig = _drawn(monkeypatch, PL._innovations, res, tmp_path)
    ax = fig.axes[0]  # gnss_pos
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert {"north", "east", "down", "rejected (1 update)", "±3", "GNSS outage (fixes withheld)"} <= set(labels)
    assert ax.get_yscale() == "symlog" and ax.get_ylim()[0] < -1000.0 * 1.2
    assert _tick_labels_apart(ax)
    assert ax.get_legend().get_window_extent().x0 >= ax.get_window_extent().x1  # beside, hiding no point
    nhc = fig.axes[[a.get_ylabel().split("\n")[0] for a in fig.axes].index("nhc")]
    assert {"lateral (body y)", "vertical (body z)"} <= {t.get_text() for t in nhc.get_legend().get_texts()}


def test_biases_plot_in_datasheet_units(run, tmp_path, monkeypatch):
    """biases.png was in deg/s and m/s^2 while the report shows deg/h and mg,
    its legend inside the frame over a bias line and the outage shading unnamed."""
    import numpy as np

    from inskit.units import DEG_PER_HOUR

    fig = _drawn(monkeypatch, PL._biases, run, tmp_path)
    assert [ax.get_ylabel() for ax in fig.axes] == ["gyro bias [deg/h]", "accel bias [mg]"]
    y = fig.axes[0].get_lines()[0].get_ydata()
    assert np.isclose(y[-1], run.forward.solution.extra["bg_x_rad_s"][-1] / DEG_PER_HOUR)
    for ax in fig.axes:
        assert ax.get_legend().get_window_extent().x0 >= ax.get_window_extent().x1
        assert [t.get_text() for t in ax.get_legend().get_texts()] == ["x", "y", "z", "GNSS outage (fixes withheld)"]


def test_track_legend_hides_no_part_of_the_track_and_tick_labels_do_not_collide(run, tmp_path, monkeypatch):
    """track.png: the legend sat inside the frame over the end of a long
    north-south track, and the frame of such a track, narrowed to keep the
    scales equal, ran its east tick labels into each other."""
    from types import SimpleNamespace

    import numpy as np

    from inskit.types import GnssData

    g = run.gnss
    lla = g.lla.copy()
    lla[:, 0] += np.linspace(0, 10000.0 / 6.37e6, len(lla))  # a 10 km stretch north
    res = SimpleNamespace(**{a: getattr(run, a) for a in ("forward", "smoothed", "config", "windows", "used")},
                          gnss=GnssData(g.time, lla, g.sigma_ned))
    fig = _drawn(monkeypatch, PL._track, res, tmp_path)
    ax = fig.axes[0]
    frame = ax.get_window_extent()
    assert ax.get_legend().get_window_extent().y1 <= frame.y0  # below the frame
    boxes = sorted((t.get_window_extent() for t in ax.get_xticklabels() if t.get_text()), key=lambda b: b.x0)
    assert all(b.x0 >= a.x1 for a, b in zip(boxes, boxes[1:]))


def _long_innovations(run, hours=4.0):
    """``run`` with the innovations of a long log: fixes at 1 Hz (one of them
    refused, 9 sigma off in down) and the NHC at 10 Hz, every component
    spread alike (unit normal) so that none should hide another."""
    from types import SimpleNamespace

    import numpy as np

    rng = np.random.default_rng(3)
    t0 = run.gnss.time[0]
    t1 = t0 + np.arange(0.0, hours * 3600.0, 1.0)
    t10 = t0 + np.arange(0.0, hours * 3600.0, 0.1)
    pos = {"t": t1, "nu": rng.standard_normal((len(t1), 3)), "sigma": np.ones((len(t1), 3)),
           "nis": np.ones(len(t1)), "accepted": np.ones(len(t1), bool), "dof": np.full(len(t1), 3)}
    pos["nu"][5000] = (0.5, -0.2, 9.0)
    pos["accepted"][5000] = False
    nhc = {"t": t10, "nu": rng.standard_normal((len(t10), 2)), "sigma": np.ones((len(t10), 2)),
           "nis": np.ones(len(t10)), "accepted": np.ones(len(t10), bool), "dof": np.full(len(t10), 2)}
    nhc["nu"][77_777, 0] = -6.5  # the worst lateral innovation, once in 144 000
    fwd = SimpleNamespace(solution=run.forward.solution, innovations={"gnss_pos": pos, "nhc": nhc})
    return SimpleNamespace(forward=fwd, gnss=run.gnss, config=run.config, windows=[], used=run.used,
                           smoothed=None, settings=run.settings)


def test_innovations_plot_of_a_long_log_shows_every_component_thinned(run, tmp_path, monkeypatch):
    """innovations.png of a 4 h log: the components were drawn one after the
    other, all 14 400 fixes (144 000 NHC updates) each, so down covered north
    and east (the NHC's vertical its lateral) and the panel showed one colour;
    now each component is thinned to its bulk and its extremes and all are
    drawn in one shuffled order: each colour shows, the worst points are
    drawn, the refused fix is marked and every entry is in the legend."""
    import numpy as np
    from matplotlib.colors import to_rgb

    res = _long_innovations(run)
    fig = _drawn(monkeypatch, PL._innovations, res, tmp_path)
    img = np.asarray(fig.canvas.buffer_rgba())[..., :3].astype(float) / 255.0
    colours = [to_rgb(c) for c in ("tab:blue", "tab:orange", "tab:green")]
    h = img.shape[0]
    for ax, n_comp, what in zip(fig.axes, (3, 2), ("gnss_pos", "nhc")):
        b = ax.get_window_extent()
        panel = img[int(h - b.y1) + 2:int(h - b.y0) - 2, int(b.x0) + 2:int(b.x1) - 2]
        near = [int((np.abs(panel - c).sum(axis=2) < 0.25).sum()) for c in colours[:n_comp]]
        share = np.array(near) / sum(near)
        assert share.min() > 0.5 / n_comp, (what, share)  # no component covered by another
        labels = [t.get_text() for t in ax.get_legend().get_texts()]
        assert labels[:n_comp] == list(PL.COMPONENTS[what])[:n_comp] and "±3" in labels, labels
        drawn = np.concatenate([c.get_offsets() for c in ax.collections if len(c.get_offsets())])
        assert len(drawn) <= n_comp * PL.MAX_SCATTER_POINTS  # thinned: 14 400 x 3 and 144 000 x 2 rows
    gnss, nhc = fig.axes[0], fig.axes[1]
    assert "rejected (1 update)" in [t.get_text() for t in gnss.get_legend().get_texts()]
    marks = [ln for ln in gnss.get_lines() if ln.get_marker() == "x"]
    assert len(marks) == 1 and 9.0 in marks[0].get_ydata()
    assert -6.5 in np.concatenate([c.get_offsets()[:, 1] for c in nhc.collections])  # the worst one drawn
    assert nhc.get_ylim()[0] < -6.5 and gnss.get_ylim()[1] > 9.0


def test_biases_plot_keeps_a_one_sample_spike_of_a_long_run(run, tmp_path, monkeypatch):
    """biases.png drew every n-th row of the solution (an even stride), so a
    one-row transient of an estimate between two kept rows was not drawn;
    now each bin keeps its minimum and maximum."""
    from types import SimpleNamespace

    import numpy as np

    from inskit.units import DEG_PER_HOUR

    sol = run.forward.solution
    n = len(sol.time)
    assert n > 4 * PL.MAX_LINE_POINTS  # thinned
    extra = dict(sol.extra)
    k = n // 2 + 1
    extra["bg_z_rad_s"] = extra["bg_z_rad_s"].copy()
    extra["bg_z_rad_s"][k] = 900.0 * DEG_PER_HOUR
    fwd = SimpleNamespace(solution=SimpleNamespace(time=sol.time, extra=extra, lla=sol.lla), innovations={})
    res = SimpleNamespace(**{a: getattr(run, a) for a in ("smoothed", "config", "windows", "used", "gnss")},
                          forward=fwd)
    fig = _drawn(monkeypatch, PL._biases, res, tmp_path)
    z = fig.axes[0].get_lines()[2]
    assert len(z.get_xdata()) <= PL.MAX_LINE_POINTS and np.isclose(np.max(z.get_ydata()), 900.0)
