"""inskit allan's [noise] section: exactly NoiseSection keys (the emitted TOML
is parsed into the config model, so the keys cannot drift), and the values of
simulated static logs of known grade.

Tolerances from the Allan deviation's confidence: a point resting on ``K``
clusters has a relative sigma of ``1 / sqrt(2 (K - 1))`` (IEEE Std 952-1997
annex C), and the section's values are RMS (or geometric means) over three
axes."""

import math
import tomllib

import numpy as np
import pytest

from inskit.jobs.allan import allan_report
from inskit.jobs.config import NoiseSection
from inskit.jobs.noise import sensor_noise
from inskit.simulation.sensors import apply_imu_errors, preset
from inskit.types import ImuData
from inskit.units import MICRO_G

#: the industrial-MEMS preset (ADIS16495-1): ARW 0.09 deg/sqrt(h), VRW 0.008 m/s/sqrt(h), bias instability
#: B = 0.8 deg/h and 3.2 ug as first-order Gauss-Markov of correlation time 300 s and sigma 0.664 B / 0.6174
GM_SIGMA_DEG_H = 0.664 * 0.8 / 0.6174
GM_SIGMA_UG = 0.664 * 3.2 / 0.6174


def _static(hours, rate_hz, seed, **overrides):
    n = int(hours * 3600 * rate_hz)
    t = np.arange(n) / rate_hz
    imu, _ = apply_imu_errors(ImuData(t, np.zeros((n, 3)), np.zeros((n, 3))), preset("industrial-mems", **overrides),
                              np.random.default_rng(seed))
    return imu


def _parsed(rep):
    data = tomllib.loads(rep["noise_toml"])
    assert list(data) == ["noise"]
    n = NoiseSection.model_validate(data["noise"])  # strict: an unknown or contradictory key fails here
    assert set(data["noise"]) == set(rep["noise_section"]) and n.model_fields_set == set(data["noise"])
    for k, v in rep["noise_section"].items():
        assert getattr(n, k) == (pytest.approx(v, rel=1e-4) if isinstance(v, float) else v)
    return n


@pytest.fixture(scope="module")
def ten_hours():
    """10 h at 10 Hz: the bump peaks at 1.89 x 300 s = 570 s, where K = 63
    clusters (9 % per axis); the curve reaches 2000 s, past the bump.  In
    this draw an accelerometer curve ends flat by chance, on 18 clusters
    (17 % per point): before the fit asked the end to rise by 3 of those
    sigmas it read a rate random walk there, and the section came out
    random-walk."""
    return allan_report(_static(10.0, 10.0, seed=3))[1]


def test_gauss_markov_section_parses_and_recovers_the_grade(ten_hours):
    """White noise within 3 % (read over cluster times of 0.1 to 10 s, tens of
    thousands of clusters: 1 % per point); Gauss-Markov sigmas within 20 % (9 %
    per axis at the peak, RMS of three); correlation times within 0.6..1.5 x
    (the bump's top is flat: its Allan deviation is within 5 % of the peak
    from 1.07 to 3.3 tau, less than one point's 9 % scatter, so the peak's
    place is the least certain term)."""
    n = _parsed(ten_hours)
    assert n.gyro_bias_model == n.accel_bias_model == "gauss-markov"
    assert n.gyro_arw_deg_sqrt_h == pytest.approx(0.09, rel=0.03)
    assert n.accel_vrw_m_s_sqrt_h == pytest.approx(0.008, rel=0.03)
    assert n.gyro_bias_sigma_deg_h == pytest.approx(GM_SIGMA_DEG_H, rel=0.20)
    assert n.accel_bias_sigma_ug == pytest.approx(GM_SIGMA_UG, rel=0.20)
    assert 0.6 * 300 < n.gyro_tau_s() < 1.5 * 300 and 0.6 * 300 < n.accel_tau_s() < 1.5 * 300
    assert not ten_hours["notes"]
    assert ten_hours["navigate_noise_section"] == ten_hours["noise_section"]  # the older JSON name


def test_the_gauss_markov_bump_is_flat_topped():
    from inskit.analysis.allan import gm_avar

    tau = np.array([1.07, 1.89, 3.3]) * 300.0
    a = np.sqrt(gm_avar(tau, 1.0, 300.0))
    assert a[[0, 2]].min() > 0.95 * a[1]


def test_rate_random_walk_gives_a_random_walk_bias_section():
    """Accelerometers with a rate random walk of 30 ug/sqrt(h) and no bias
    instability, 3 h at 10 Hz: the +1/2 slope from 47 s (where it crosses the
    white noise) to the curve's end at 600 s (K = 18 clusters: 17 % per
    point) gives accel_bias_model = "random-walk" with K within 30 %; the
    filter's bias then drifts by that much in an hour."""
    rep = allan_report(_static(3.0, 10.0, seed=1, accel={"bias_instability": 0.0, "rate_random_walk": 30.0}))[1]
    n = _parsed(rep)
    assert n.accel_bias_model == "random-walk" and n.accel_bias_rrw_ug_sqrt_h == pytest.approx(30.0, rel=0.30)
    assert "accel_bias_sigma_ug" not in rep["noise_section"] and "accel_bias_tau_s" not in rep["noise_section"]
    s = sensor_noise(n)
    assert math.isinf(s.accel_bias_tau_s)
    assert s.accel_bias_sigma * math.sqrt(3600.0) == pytest.approx(n.accel_bias_rrw_ug_sqrt_h * MICRO_G)


def test_a_constant_axis_is_a_row_and_a_note_and_the_section_comes_from_the_other_axes():
    """A gyro z that reads 0 at rest: its row says constant (figures None), a note names it, and the gyro keys
    are the other two axes' (RMS of their white noise), parsed as a navigate section."""
    imu = _static(0.1, 100.0, seed=5)
    dth = imu.dtheta_b.copy()
    dth[:, 2] = 0.0
    fits, rep = allan_report(ImuData(imu.time, dth, imu.dv_b))
    z = rep["gyro"][2]
    assert z["constant"] is True and z["arw_deg_sqrt_h"] is None and z["bias_instability_resolved"] is None
    assert [x["constant"] for x in rep["gyro"][:2] + rep["accel"]] == [False] * 5
    assert any(n.startswith("gyro z: constant over the log") for n in rep["notes"])
    arw = math.sqrt((rep["gyro"][0]["arw_deg_sqrt_h"] ** 2 + rep["gyro"][1]["arw_deg_sqrt_h"] ** 2) / 2)
    assert rep["noise_section"]["gyro_arw_deg_sqrt_h"] == pytest.approx(arw, rel=1e-12)
    assert _parsed(rep).gyro_arw_deg_sqrt_h == pytest.approx(arw, rel=1e-4)
    assert "# note: gyro z: constant over the log" in rep["noise_toml"]


def test_a_rate_log_gives_the_figures_of_the_same_samples_as_increments(tmp_path):
    """`inskit allan` on a log of rates read them as point samples and integrated them with the trapezoid
    rule, which averages each sample with its neighbour: the same tactical static hour gave ARW 0.1224 and
    VRW 47.6 ug/rt(Hz) as rates against 0.1271 and 50.4 as increments (the simulated 0.125 and 50).  The
    rates are now the increments over their intervals (jobs.allan.read_static_log, in the command and in a
    study's Allan grade): one answer for one sensor."""
    import json

    from click.testing import CliRunner

    from inskit.cli import cli
    from inskit.jobs.study import AllanGrade, allan_grade

    imu = _static(600 / 3600, 100.0, 4)
    dv = imu.dv_b - np.r_[0.0, 0.0, 9.8] * 0.01  # gravity, for the unit check
    dv[0] = imu.dtheta_b[0] = 0.0  # the initial epoch
    imu = ImuData(imu.time, imu.dtheta_b, dv)
    w, f = imu.rates()
    inc = tmp_path / "increments.csv"
    rates = tmp_path / "rates.csv"
    cols = "time_s," + ",".join(f"{c}_{a}_{u}" for c, u in (("dtheta", "rad"), ("dv", "m_s")) for a in "xyz")
    np.savetxt(inc, np.column_stack([imu.time, imu.dtheta_b, imu.dv_b]), delimiter=",", header=cols,
               comments="", fmt="%.17g")
    cols = "time_s," + ",".join(f"{c}_{a}_{u}" for c, u in (("gyro", "rad_s"), ("accel", "m_s2")) for a in "xyz")
    np.savetxt(rates, np.column_stack([imu.time, w, f]), delimiter=",", header=cols, comments="", fmt="%.17g")
    def allan(path):  # the command, as a user runs it
        r = CliRunner().invoke(cli, ["allan", str(path), "--json"])
        assert r.exit_code == 0, r.output
        return json.loads(r.stdout)["noise_section"]

    a, b = allan(inc), allan(rates)
    assert a.keys() == b.keys()
    for k in a:  # the CSV's 17 digits aside (before: 4-5 %)
        assert a[k] == (b[k] if isinstance(b[k], str) else pytest.approx(b[k], rel=1e-4)), k
    ga, gb = (allan_grade(AllanGrade(allan=str(p)))[1]["from_fit"] for p in (inc, rates))
    for k in ga:
        assert ga[k] == pytest.approx(gb[k], rel=1e-4), k
