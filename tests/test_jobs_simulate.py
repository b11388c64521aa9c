"""inskit.jobs.simulate: the scenario plot."""

from pathlib import Path
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
    assert ok.sum() == n  # every point still drawn (too few to be thinned)


def test_scenario_track_is_drawn_over_thinned_fixes_with_a_legend(tmp_path, monkeypatch):
    """scenario.png of the car drive: its 1843 GNSS dots were drawn after
    the truth line and hid it whole (the panel was grey, 'dots: GNSS' in
    the title the only key); now the fixes lie under the line, at most
    MAX_FIX_DOTS of them, and a legend below the frame names both."""
    from matplotlib.colors import to_rgb

    from inskit.simulation.scenario import load_scenario, simulate

    sc = load_scenario(Path(__file__).resolve().parents[1] / "examples" / "car.toml")
    sim = simulate(sc.model_copy(update={"imu": sc.imu.model_copy(update={"rate_hz": 40.0})}), seed=1)
    # the fixes of a 4 h drive: ten copies of each
    many = SimpleNamespace(lla=np.repeat(sim.gnss.lla, 10, axis=0))
    figs = []
    monkeypatch.setattr(JS, "save_figure", lambda fig, path, dpi=110: figs.append(fig))
    JS._plot(SimpleNamespace(truth=sim.truth, gnss=many, scenario=sim.scenario), tmp_path / "s.png")
    fig = figs[0]
    fig.canvas.draw()
    track = fig.axes[0]
    dots, line = track.get_lines()
    assert dots.get_marker() == "." and len(dots.get_xdata()) <= JS.MAX_FIX_DOTS
    assert line.get_zorder() > dots.get_zorder()
    img = np.asarray(fig.canvas.buffer_rgba())[..., :3].astype(float) / 255.0
    b = track.get_window_extent()
    h = img.shape[0]
    panel = img[int(h - b.y1) + 2:int(h - b.y0) - 2, int(b.x0) + 2:int(b.x1) - 2]
    blue = int((np.abs(panel - to_rgb("tab:blue")).sum(axis=2) < 0.25).sum())
    grey = int((np.abs(panel - to_rgb("0.6")).sum(axis=2) < 0.1).sum())
    assert blue > grey, (blue, grey)  # the track shows; the dots beside it
    labels = [t.get_text() for t in track.get_legend().get_texts()]
    assert labels == ["truth", f"GNSS fixes ({len(many.lla)}, every 10th drawn)"]
    for ax in (track, fig.axes[3]):  # below the frame, over no line
        assert ax.get_legend().get_window_extent().y1 <= ax.get_window_extent().y0


def test_verify_at_rest_on_a_pole_mechanizes_in_the_wander_frame(tmp_path):
    """`inskit simulate --verify` of a log at rest on the north pole said 'use the wander-azimuth or ECEF frame
    (--frame wander|ecef)', an option simulate has not (and the truth at twice the rate was refused: its latitude
    interpolated to pi/2 + 2 ulp); near a pole the self-check now mechanizes in the wander-azimuth frame, elsewhere
    in NED as before."""
    from inskit.simulation.scenario import load_scenario

    p = tmp_path / "pole.toml"
    p.write_text("name = \"pole\"\n[start]\nlat_deg = 90\nlon_deg = 10\n[imu]\nrate_hz = 100\n[[segment]]\n"
                 "type = \"static\"\nduration_s = 10\n")
    v = JS.verify_ideal(load_scenario(p))
    assert list(v["frames"]) == ["wander"] and v["frames"]["wander"]["horizontal_max_m"] < 1e-6
    p.write_text(p.read_text().replace("lat_deg = 90", "lat_deg = 45"))
    assert list(JS.verify_ideal(load_scenario(p))["frames"]) == ["ned"]


def test_readings_clipped_at_the_imu_saturation_are_said(tmp_path, capsys):
    """A scenario at rest with ``[imu] accel = {saturation = 0.5}`` (g) wrote an IMU file whose every
    accelerometer reading was clipped to half of gravity, and said nothing: the summary was that of any run.
    Now `inskit simulate` warns (stderr and the JSON's warnings, :func:`JS.clipping_warnings`) how many rows
    the limit clipped and how far the motion went; a run within the limits has no warnings."""
    import json

    from inskit.cli import main

    base = ('name = "t"\n[start]\nlat_deg = 45\nlon_deg = 10\n[imu]\nrate_hz = 100\ngrade = "tactical"\n{}\n'
            '[[segment]]\ntype = "static"\nduration_s = 10\n')

    def run(name, extra):
        (tmp_path / f"{name}.toml").write_text(base.format(extra))
        try:
            main(["simulate", str(tmp_path / f"{name}.toml"), "--out", str(tmp_path / name), "--no-plot", "--json"])
        except SystemExit as exc:
            assert exc.code == 0
        cap = capsys.readouterr()
        return json.loads(cap.out)["warnings"], cap.err

    w, err = run("clip", "accel = {saturation = 0.5}")
    assert w == ["field 'imu.accel' (saturation, or the grade's): the limit of 0.5 g clipped the readings of 1000 of "
                 "1000 IMU rows (the run's specific force reaches 1 g on an axis): the IMU file holds the clipped "
                 "readings, and a navigation from it drifts while they last"]
    assert f"warning: {w[0]}" in err
    assert run("fine", "") == ([], "")
