"""inskit.jobs.simulate: the scenario plot."""

from types import SimpleNamespace

import numpy as np

from inskit.jobs import simulate as JS


def test_scenario_plot_does_not_join_the_yaw_across_its_wrap(tmp_path, monkeypatch):
    """scenario.png: a drive heading south (yaw near +-180 deg) is drawn as
    the heading it is, not as vertical lines swinging through the circle."""
    figs = []
    monkeypatch.setattr(JS, "save_figure", lambda fig, path, dpi=110: figs.append(fig))
    n = 1000
    t = np.arange(n) * 0.1
    yaw = np.radians((175.0 + 0.1 * t + 180.0) % 360.0 - 180.0)
    yaw[::7] = np.radians(-179.9)  # jitter about the wrap
    lla = np.column_stack([np.radians(40.0) - 1e-7 * t, np.full(n, np.radians(-105.0)), np.full(n, 1600.0)])
    truth = SimpleNamespace(time=t, lla=lla, v_n=np.tile([-10.0, 0.0, 0.0], (n, 1)),
                            euler=np.column_stack([0 * t, 0 * t, yaw]))
    sim = SimpleNamespace(truth=truth, gnss=SimpleNamespace(lla=lla[::10]), scenario=SimpleNamespace(name="south"))
    JS._plot(sim, tmp_path / "s.png")
    att = figs[0].axes[3]
    assert [ln.get_label() for ln in att.get_lines()] == ["roll", "pitch", "yaw"]
    _, y = att.get_lines()[2].get_data()
    ok = ~np.isnan(y)
    assert (np.abs(np.diff(y))[ok[1:] & ok[:-1]] < 180).all()
    assert ok.sum() == len(t[::10])  # every point plotted still drawn
