"""Sensor error models: over 100 seeded runs the sample statistics of every
random term match the configured values within 15 % (issue 3 acceptance)."""

import numpy as np
import pytest

from inskit.errors import ConfigError
from inskit.simulation.sensors import (
    PRESETS,
    ImuErrors,
    TriadErrors,
    apply_imu_errors,
    preset,
    triad_from_datasheet,
)
from inskit.types import ImuData
from inskit.units import DEG, DEG_PER_HOUR, MICRO_G

RUNS = 100
DT = 0.01


def zero_imu(n):
    t = np.arange(n) * DT
    return ImuData(t, np.zeros((n, 3)), np.zeros((n, 3)))


def runs(errors, n):
    imu = zero_imu(n)
    out = []
    for seed in range(RUNS):
        m, draws = apply_imu_errors(imu, ImuErrors(errors, TriadErrors()), np.random.default_rng(seed))
        out.append((m.dtheta_b[1:] / DT, draws))
    return out


def test_turn_on_bias_spread():
    e = triad_from_datasheet("gyro", turn_on_bias=10.0)
    b = np.array([d["gyro_turn_on_bias"] for _, d in runs(e, 50)])
    assert b.std() == pytest.approx(10.0 * DEG_PER_HOUR, rel=0.15)
    assert abs(b.mean()) < 3 * 10.0 * DEG_PER_HOUR / np.sqrt(b.size)


def test_white_noise_density():
    e = triad_from_datasheet("gyro", noise=0.2)  # ARW 0.2 deg/sqrt(h)
    w = np.concatenate([x for x, _ in runs(e, 200)])
    density = w.std() * np.sqrt(DT)
    assert density == pytest.approx(0.2 * DEG / 60.0, rel=0.15)


def test_gauss_markov_sigma_and_correlation_time():
    e = triad_from_datasheet("accel", bias_instability=100.0, bias_instability_tau_s=2.0)
    xs = np.stack([x for x, _ in runs(e, 2000)])  # (runs, n, 3)
    assert xs.std() == pytest.approx(e.gm_sigma, rel=0.15)
    lag = int(2.0 / DT)
    rho = np.mean(xs[:, lag:] * xs[:, :-lag]) / np.mean(xs * xs)
    assert rho == pytest.approx(np.exp(-1.0), rel=0.15)


def test_rate_random_walk_growth():
    e = triad_from_datasheet("gyro", rate_random_walk=30.0)  # deg/h/sqrt(h)
    xs = np.stack([x for x, _ in runs(e, 1000)])
    t_end = 999 * DT
    k = 30.0 * DEG_PER_HOUR / 60.0
    assert xs[:, -1].std() == pytest.approx(k * np.sqrt(t_end), rel=0.15)


def test_deterministic_terms_exact():
    n = 1000
    t = np.arange(n) * DT
    w_true = np.tile([0.1, -0.2, 0.3], (n, 1))
    f_true = np.tile([0.0, 0.0, -9.8], (n, 1))
    imu = ImuData(t, w_true * DT, f_true * DT)
    rng = np.random.default_rng(3)
    g = triad_from_datasheet("gyro", fixed_bias=(1.0, 2.0, 3.0), scale_factor_ppm=1000, misalignment_mrad=1.0,
                             g_sensitivity=10.0, rng=rng)
    m, _ = apply_imu_errors(imu, ImuErrors(g, TriadErrors()), np.random.default_rng(0))
    M = np.eye(3) * 1.001 + np.asarray(g.misalignment) * (1 - np.eye(3))
    expect = w_true[0] @ M.T + np.array([1.0, 2.0, 3.0]) * DEG_PER_HOUR + g.g_sensitivity * f_true[0]
    assert np.allclose(m.dtheta_b[1:] / DT, expect, rtol=0, atol=1e-15)
    assert np.abs(np.asarray(g.misalignment)).max() > 0


def test_quantization_carries_the_remainder_and_saturation_clips():
    n = 10000
    t = np.arange(n) * DT
    imu = ImuData(t, np.full((n, 3), 1.234e-5), np.full((n, 3), 3.0 * DT))
    lsb = 1e-4
    e = TriadErrors(quantization=lsb)
    m, _ = apply_imu_errors(imu, ImuErrors(e, TriadErrors(saturation=2.0)), np.random.default_rng(0))
    q = m.dtheta_b[1:]
    assert np.allclose(q / lsb, np.round(q / lsb))  # every output is a whole number of LSBs
    assert abs(q.sum(axis=0) - imu.dtheta_b[1:].sum(axis=0)).max() <= lsb  # no drift
    assert np.allclose(m.dv_b[1:] / DT, 2.0)  # clipped at 2 m/s^2


def test_same_seed_same_numbers():
    e = preset("consumer-mems")
    imu = zero_imu(500)
    a, _ = apply_imu_errors(imu, e, np.random.default_rng(7))
    b, _ = apply_imu_errors(imu, e, np.random.default_rng(7))
    c, _ = apply_imu_errors(imu, e, np.random.default_rng(8))
    assert np.array_equal(a.dtheta_b, b.dtheta_b) and not np.array_equal(a.dtheta_b, c.dtheta_b)


def test_presets_units_at_the_edge():
    for name in PRESETS:
        p = preset(name)
        assert p.gyro.white_noise > 0 and p.accel.white_noise > 0
    hg = preset("tactical")
    assert hg.gyro.white_noise == pytest.approx(0.125 * DEG / 60)  # 0.125 deg/sqrt(h) in rad/sqrt(s)
    assert hg.accel.turn_on_bias_sigma == pytest.approx(1000 * MICRO_G)
    with pytest.raises(ConfigError, match="unknown IMU grade"):
        preset("military")


def test_preset_overrides_are_checked():
    p = preset("tactical", gyro={"noise": 0.2})
    assert p.gyro.white_noise == pytest.approx(0.2 * DEG / 60)
    with pytest.raises(ConfigError, match=r"^imu\.gyro: nois: unknown error term; the terms of a gyro are fixed_bias"):
        preset("tactical", gyro={"nois": 0.2})


@pytest.mark.parametrize("kind, terms, said", [
    ("gyro", {"bias_instability_tau_s": 0}, r"bias_instability_tau_s = 0: must be > 0 \[s\]"),
    ("gyro", {"bias_instability_tau_s": -10}, r"bias_instability_tau_s = -10: must be > 0 \[s\]"),
    ("gyro", {"fixed_bias": [1, 2]}, r"fixed_bias = \[1, 2\]: expected three finite numbers \[x, y, z\] \[deg/h\]"),
    ("gyro", {"fixed_bias": 1.0}, r"fixed_bias = 1\.0: expected three finite numbers"),
    ("gyro", {"noise": [1, 2, 3]}, r"noise = \[1, 2, 3\]: expected one finite number \[deg/sqrt\(h\)\]"),
    ("gyro", {"saturation": 0}, r"saturation = 0: must be > 0 \[deg/s\]"),
    ("accel", {"noise": -1}, r"noise = -1: must be >= 0 \[micro-g/sqrt\(Hz\)\]"),
    ("accel", {"turn_on_bias": -5}, r"turn_on_bias = -5: must be >= 0 \[micro-g\]"),
    ("accel", {"quantization": -1}, r"quantization = -1: must be >= 0 \[m/s\]"),
    ("accel", {"scale_factor_ppm": -2e6}, r"scale_factor_ppm = -2000000\.0: must be > -1e6 \[ppm\]"),
    ("accel", {"g_sensitivity": 3}, r"g_sensitivity: an accelerometer has no g-sensitivity"),
])
def test_preset_override_values_are_checked(kind, terms, said):
    """bias_instability_tau_s = 0 was 'internal error: ZeroDivisionError', -10 a NaN in every increment,
    fixed_bias = [1, 2] numpy's broadcast error, noise = -1 or saturation = 0 (every reading clipped to 0) were
    simulated without a word and an accelerometer's g_sensitivity was ignored."""
    with pytest.raises(ConfigError, match=rf"^imu\.{kind}: {said}"):
        preset("tactical", **{kind: terms})


def test_every_term_of_the_table_is_a_keyword_of_the_datasheet_conversion():
    """TRIAD_TERMS (the checks and docs/config.md) and triad_from_datasheet name the same terms, and the values
    the table allows convert: a term added to one and not the other would be refused or ignored."""
    import inspect

    from inskit.simulation.sensors import TRIAD_TERMS, triad_from_datasheet

    keywords = set(inspect.signature(triad_from_datasheet).parameters) - {"kind", "rng", "misalignment_mrad"}
    assert set(TRIAD_TERMS) == keywords
    e = preset("tactical", gyro={"fixed_bias": [1, -2, 3], "g_sensitivity": -3.0, "saturation": 100},
               accel={"fixed_bias": [0, 0, 50], "quantization": 1e-4, "bias_instability_tau_s": 60})
    assert e.gyro.fixed_bias == pytest.approx(np.array([1, -2, 3]) * DEG_PER_HOUR)
    assert e.accel.quantization == 1e-4 and e.accel.bias_instability_tau_s == 60


def test_compiled_gauss_markov_recursion_equals_scipy_lfilter():
    """The compiled AR(1) recursion is the filter scipy.signal.lfilter applies, to the bit."""
    from scipy.signal import lfilter

    from inskit.simulation.sensors import _ar1

    w = np.random.default_rng(1).standard_normal((20000, 3))
    phi = np.exp(-0.01 / 300.0)
    assert np.array_equal(_ar1(w, phi), lfilter([1.0], [1.0, -phi], w, axis=0))


def test_scale_and_misalignment_rows_are_the_matrix_product():
    """The scale-factor and misalignment matrix applied row by row (three column products, no BLAS) is ``x @ M.T``:
    to the last bit for a diagonal matrix (scale factors only, the presets), to 2 ulp with misalignment."""
    from inskit.simulation.sensors import _rows_times

    rng = np.random.default_rng(8)
    x = rng.standard_normal((1001, 3)) * [1e-3, 1.0, 10.0]
    diag = np.diag(1.0 + rng.standard_normal(3) * 1e-3)
    assert np.array_equal(_rows_times(x, diag), x @ diag.T)
    assert np.array_equal(_rows_times(x, np.eye(3)), x)
    full = diag + (1 - np.eye(3)) * rng.standard_normal((3, 3)) * 1e-3
    y = _rows_times(x, full)
    assert y.shape == (1001, 3)
    assert np.abs(y - x @ full.T).max() <= 4e-16 * np.abs(x).max(axis=1, keepdims=True).max()
