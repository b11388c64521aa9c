"""Allan deviation: recovery of simulated noise terms (issue 3 acceptance)."""

import numpy as np
import pytest

from inskit.analysis.allan import allan_deviation, allan_imu, fit_allan, gm_avar
from inskit.errors import InputError
from inskit.simulation.sensors import ImuErrors, apply_imu_errors, triad_from_datasheet
from inskit.types import ImuData
from inskit.units import DEG, DEG_PER_HOUR, MICRO_G


def test_white_noise_slope_and_level():
    rng = np.random.default_rng(0)
    dt, n = 0.01, 200_000
    N = 1e-3
    inc = rng.standard_normal(n) * N * np.sqrt(dt)
    tau, a = allan_deviation(inc, dt)
    ok = tau < 100
    assert np.allclose(a[ok] * np.sqrt(tau[ok]), N, rtol=0.1)


def test_gm_allan_formula_peak():
    tau = np.logspace(-1, 3, 2000)
    a = np.sqrt(gm_avar(tau, 1.0, 10.0))
    assert a.max() == pytest.approx(0.6174, rel=2e-3)
    assert tau[np.argmax(a)] == pytest.approx(18.9, rel=0.02)


@pytest.fixture(scope="module")
def three_hours():
    n = int(3 * 3600 * 100)
    t = np.arange(n) * 0.01
    ideal = ImuData(t, np.zeros((n, 3)), np.zeros((n, 3)))
    g = triad_from_datasheet("gyro", noise=0.1, bias_instability=1.0, bias_instability_tau_s=100.0)
    a = triad_from_datasheet("accel", noise=50.0, bias_instability=20.0, bias_instability_tau_s=100.0)
    imu, _ = apply_imu_errors(ideal, ImuErrors(g, a), np.random.default_rng(2026))
    return allan_imu(imu)


def test_gyro_arw_and_bias_instability_recovered(three_hours):
    for f in three_hours["gyro_fit"]:
        assert f.white / (DEG / 60.0) == pytest.approx(0.1, rel=0.10)
        assert f.bias_instability / DEG_PER_HOUR == pytest.approx(1.0, rel=0.25)


def test_accel_vrw_and_bias_instability_recovered(three_hours):
    for f in three_hours["accel_fit"]:
        assert f.white / MICRO_G == pytest.approx(50.0, rel=0.10)
        assert f.bias_instability / MICRO_G == pytest.approx(20.0, rel=0.25)


def test_fit_reports_rate_random_walk_when_present():
    tau = np.logspace(-2, 3.5, 60)
    K = 1e-5
    a = np.sqrt(1e-6 / tau + K**2 * tau / 3)
    f = fit_allan(tau, a)
    assert f.rate_random_walk == pytest.approx(K, rel=0.1)
    assert f.white == pytest.approx(1e-3, rel=0.1)


def test_pure_white_noise_invents_no_bias_instability():
    """Issue 12: one million samples of white noise gave an invented bias
    instability; now the white level is right and the bias is flagged as an
    unresolved upper bound."""
    from inskit.analysis.allan import allan_imu
    from inskit.types import ImuData

    rng = np.random.default_rng(0)
    n, dt = 400_000, 0.01
    t = np.arange(n) * dt
    N = 102e-6 * 9.80665
    dv = np.tile([0.0, 0.0, -9.80665 * dt], (n, 1)) + rng.normal(0, N * np.sqrt(dt), (n, 3))
    dth = rng.normal(0, 1e-4 * np.sqrt(dt), (n, 3))
    dth[0] = dv[0] = 0.0
    r = allan_imu(ImuData(t, dth, dv))
    for f in r["accel_fit"]:
        assert f.white == pytest.approx(N, rel=0.05)
        assert not f.bias_resolved


def test_short_and_moving_logs_are_refused():
    from inskit.analysis.allan import allan_imu
    from inskit.errors import InputError
    from inskit.types import ImuData

    t = np.arange(0.0, 0.5, 0.01)
    z = np.zeros((len(t), 3))
    with pytest.raises(InputError, match="at least 100 s"):
        allan_imu(ImuData(t, z, z))
    t = np.arange(0.0, 300.0, 0.01)
    dv = np.tile([0.0, 0.0, -0.0980665], (len(t), 1))
    dv[len(t) // 2:, 0] += 0.02  # 2 m/s^2 forward from half way: driving off
    with pytest.raises(InputError, match="not static"):
        allan_imu(ImuData(t, np.zeros_like(dv), dv))



def test_a_gyro_spike_is_named_at_its_time_in_readable_numbers():
    """One gyro sample of 1e300 rad (a corrupt row) was said as 'around t = 102.0 s' (the time where the
    accelerometers' noise peaked, not the spike's) with a rate of 300 digits; now the window of the channel
    furthest beyond its own limit is named, and the figures have 3 significant digits."""
    from inskit.errors import InputError

    rng = np.random.default_rng(2)
    t = np.arange(0.0, 200.0 + 1e-9, 0.01)
    dth = 1e-7 * rng.standard_normal((len(t), 3))
    dv = np.tile([0.0, 0.0, -0.0980665], (len(t), 1)) + 1e-5 * rng.standard_normal((len(t), 3))
    dth[0] = dv[0] = 0.0
    dth[7000, 0] = 1e300
    with pytest.raises(InputError, match=r"^the log is not static \(around t = 69\.0 s its 1 s mean specific force "
                                         r"moves [0-9.e-]+ m/s\^2, its rate 5\.73e\+301 deg/s from the median; at "
                                         r"rest they stay within 0\.2 m/s\^2 and 1 deg/s\)"):
        allan_imu(ImuData(t, dth, dv))


def test_an_irregular_log_names_its_worst_step():
    from inskit.errors import InputError

    t = np.arange(0.0, 300.0, 0.01)
    t[15000:] += 7.5  # a gap of 7.5 s after 150 s
    dv = np.tile([0.0, 0.0, -0.0980665], (len(t), 1))
    with pytest.raises(InputError, match=r"regularly sampled log .*: a step of 7\.51 s at t = 149\.990 s, the "
                                         r"median 0\.01 s\)"):
        allan_imu(ImuData(t, np.zeros_like(dv), dv))


@pytest.mark.parametrize("rows", [1, 50])
def test_a_log_of_too_few_samples_states_the_minimum(rows):
    """A two-line file (`head -2 imu.csv`: one sample) was an internal error (a maximum of no time steps);
    50 samples over 490 s are long enough but too few."""
    from inskit.errors import InputError

    t = np.arange(rows) * 10.0
    z = np.zeros((rows, 3))
    with pytest.raises(InputError, match=rf"the log has {rows} sample\(s\); an Allan deviation needs a static log "
                                         r"of at least 101 samples and 100 s"):
        allan_imu(ImuData(t, z, z))


def _static_log(seconds=300.0, rate_hz=100.0, seed=4):
    n = int(seconds * rate_hz)
    t = np.arange(n) / rate_hz
    g = triad_from_datasheet("gyro", noise=0.1, bias_instability=1.0, bias_instability_tau_s=20.0)
    a = triad_from_datasheet("accel", noise=50.0, bias_instability=20.0, bias_instability_tau_s=20.0)
    ideal = ImuData(t, np.zeros((n, 3)), np.tile([0.0, 0.0, -9.80665 / rate_hz], (n, 1)))
    return apply_imu_errors(ideal, ImuErrors(g, a), np.random.default_rng(seed))[0]


def test_a_constant_channel_is_named_and_left_unfitted():
    """gyro z = 0 everywhere (a stuck or coarsely quantised axis) was an internal error in fit_allan (the
    log of a zero deviation); an accelerometer stuck on exactly one reading likewise, though its curve is
    rounding noise, not zero.  The other channels are fitted as without it."""
    imu = _static_log()
    ref = allan_imu(imu)
    dth, dv = imu.dtheta_b.copy(), imu.dv_b.copy()
    dth[:, 2] = 0.0
    dv[1:, 0] = 0.0123  # stuck: the same increment every sample
    r = allan_imu(ImuData(imu.time, dth, dv))
    assert r["constant"] == ["gyro z", "accel x"]
    assert r["gyro_fit"][2] is None and r["accel_fit"][0] is None
    assert not r["gyro_adev"][:, 2].any() and not r["accel_adev"][:, 0].any()
    assert r["gyro_fit"][:2] == ref["gyro_fit"][:2] and r["accel_fit"][1:] == ref["accel_fit"][1:]


def test_a_channel_varying_by_rounding_only_is_constant():
    """An ideal simulated IMU at rest varies in its last digits (3e-12 of the increment through a CSV): allan
    fitted that rounding and wrote gyro_arw_deg_sqrt_h = 3.9e-15 into the [noise] section as if measured.
    A spread within 1e-9 of the increment is constant; the noise of a real log is not."""
    imu = _static_log()
    dth, dv = imu.dtheta_b.copy(), imu.dv_b.copy()
    dth[1:, 0] = 5.156e-7 * (1.0 + 3e-12 * np.sin(np.arange(len(dth) - 1)))  # earth rate, rounding-level wiggle
    r = allan_imu(ImuData(imu.time, dth, dv))
    assert r["constant"] == ["gyro x"] and r["gyro_fit"][0] is None
    assert allan_imu(imu)["constant"] == []


@pytest.mark.parametrize("sensor", ["gyro", "accel"])
def test_three_constant_axes_of_a_sensor_are_refused_naming_it(sensor):
    from inskit.errors import InputError

    imu = _static_log()
    dth, dv = imu.dtheta_b.copy(), imu.dv_b.copy()
    (dth if sensor == "gyro" else dv)[1:] = 0.0
    with pytest.raises(InputError, match=rf"{sensor} x, y, z are constant over the log .*no {sensor} noise is "
                                         "measurable"):
        allan_imu(ImuData(imu.time, dth, dv))


def test_fit_allan_refuses_a_zero_curve():
    from inskit.errors import InputError

    tau = np.logspace(-2, 2, 30)
    with pytest.raises(InputError, match="a constant signal has none: its deviation is zero"):
        fit_allan(tau, np.zeros_like(tau))


@pytest.mark.parametrize("args, kwargs, said", [
    ((1000, 0.01), {"min_clusters": 0}, r"^min_clusters must be an integer >= 1 \(the fewest clusters the longest "
                                        r"cluster time rests on\), got 0$"),
    ((1000, 0.01), {"min_clusters": -1}, r"^min_clusters must be an integer >= 1 .*, got -1$"),
    ((1000, 0.01), {"min_clusters": 1.5}, r"^min_clusters must be an integer >= 1 .*, got 1\.5$"),
    ((1000, 0.01), {"min_clusters": 500}, r"^1000 samples are too few for an Allan deviation with min_clusters = "
                                          r"500 \(at least 3 x 500 = 1500\)$"),
    ((1000, 0.01), {"taus_per_decade": -3}, r"^taus_per_decade must be a finite number > 0, got -3$"),
    ((1000, 0.0), {}, r"^dt must be the sample interval, a finite number > 0 \[s\], got 0\.0$"),
    ((1000, -0.01), {}, r"^dt must be the sample interval, .* got -0\.01$"),
    ((1000, float("nan")), {}, r"^dt must be the sample interval, .* got nan$"),
    (("nan", 0.01), {}, r"^increments hold a NaN or infinite value \(row 500\): an Allan deviation of it is NaN$"),
    (("3d", 0.01), {}, r"^increments must have shape \(n,\) or \(n, k\), got \(250, 2, 2\)$"),
])
def test_allan_deviation_refuses_arguments_that_are_no_curve(args, kwargs, said):
    """min_clusters = 0 was a ZeroDivisionError, taus_per_decade = -3 numpy's 'Number of samples, -4, must be
    non-negative', a 3-D array a vstack error; min_clusters = -1, dt <= 0 or NaN and a NaN increment gave a curve
    (negative cluster times, NaN) without a word; too short a log for the clusters asked did not say which."""
    x = np.random.default_rng(0).standard_normal(1000) * 1e-3
    data, dt = args
    if data == "nan":
        x[500] = np.nan
    elif data == "3d":
        x = x.reshape(-1, 2, 2)
    with pytest.raises(InputError, match=said):
        allan_deviation(x, dt, **kwargs)


def test_fit_allan_refuses_curves_of_two_lengths_or_bad_cluster_times():
    """fit_allan(tau, adev[:-1]) was numpy's 'distances must match the length of the corresponding dimension'."""
    tau, adev = allan_deviation(np.random.default_rng(0).standard_normal(1000) * 1e-3, 0.01)
    with pytest.raises(InputError, match=r"^tau and adev must be two \(m,\) arrays of the same length .* got "
                                         r"shapes \(15,\) and \(14,\)$"):
        fit_allan(tau, adev[:-1])
    with pytest.raises(InputError, match=r"^tau must be the cluster times \[s\]: finite, > 0 and increasing$"):
        fit_allan(-tau, adev)


def test_plot_names_the_fitted_terms_in_both_panels(monkeypatch, tmp_path):
    """allan.png drew the white-noise, Gauss-Markov and rate-random-walk fits
    as dotted, dashed and dash-dot lines that only the gyro panel's title
    named (the accelerometer panel's three styles unexplained); now each
    panel's legend names them beside the axes' colours."""
    from inskit.analysis import allan as A

    figs = []
    monkeypatch.setattr(A, "save_figure", lambda fig, path, dpi=110: figs.append(fig))
    A.plot_allan(allan_imu(_static_log()), tmp_path / "a.png", title="log")
    for ax in figs[0].axes:
        labels = [t.get_text() for t in ax.get_legend().get_texts()]
        assert {"x", "y", "z", "measured", "white-noise fit", "Gauss-Markov fit"} <= set(labels), labels
        styles = {ln.get_linestyle() for ln in ax.get_lines() if len(ln.get_xdata())}
        named = {"-": "measured", ":": "white-noise fit", "--": "Gauss-Markov fit", "-.": "rate-random-walk fit"}
        assert {named[s] for s in styles} <= set(labels)  # every style drawn is named
