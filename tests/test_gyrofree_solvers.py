"""Closed-form and least-squares solvers (inskit.gyrofree.solvers)."""

import numpy as np
import pytest

from inskit.errors import InputError
from inskit.gyrofree.layout import ArrayLayout, six_layout, ten_layout
from inskit.gyrofree.model import ArrayErrors, simulate_array
from inskit.gyrofree.motion import ConstantRateMotion, HarmonicBodyMotion
from inskit.gyrofree.solvers import RateFilter, point_increments, solve, solve_closed_form, solve_least_squares
from inskit.types import ImuData

T1K = np.arange(0.0, 10.0, 1e-3)


def random_layout(rng, m=12):
    ax = rng.standard_normal((m, 3))
    return ArrayLayout(tuple(f"s{k}" for k in range(m)), rng.uniform(-0.2, 0.2, (m, 3)),
                       ax / np.linalg.norm(ax, axis=1, keepdims=True), "random12")


# Tolerances of the error-free cases.  Rounding in the sums of eq. 13-19 of
# outputs of ~50 m/s^2 is ~1e-14 m/s^2, i.e. ~1e-13 (rad/s)^2 on p^2 at
# d = 0.1 m.  The least-squares solver takes a small component from the
# products (error ~1e-13 / |omega|), so 1e-9 rad/s holds everywhere with three
# orders of margin.  The closed form takes magnitudes from eq. 14's square
# roots, as the source does: error ~1e-13 / (2|p|), within 1e-9 where
# |p| > 1e-4 rad/s and bounded by sqrt(1e-13) ~ 3e-7 at an exact zero.  A wrong
# sign or a wrong formula gives errors of the size of the rate (0.1-3 rad/s).
@pytest.mark.parametrize("seed", range(4))
def test_random_motions_error_free(seed):
    rng = np.random.default_rng(seed)
    mot = HarmonicBodyMotion.random(rng).motion(T1K)
    w = mot.omega_ib_b
    L = ten_layout(0.1)
    data = simulate_array(L, mot)
    ls = solve_least_squares(data, L, omega0=w[0])
    assert np.abs(ls.omega_ib_b - w).max() < 1e-9
    assert np.abs(ls.f_b - mot.f_b).max() < 1e-9
    assert np.abs(ls.omega_dot_ib_b[:, :2] - mot.omega_dot_ib_b[:, :2]).max() < 1e-9
    assert np.isnan(ls.omega_dot_ib_b[:, 2]).all()  # r_dot is not sensed by the ten layout
    cf = solve_closed_form(data, L, omega0=w[0])
    err = np.abs(cf.omega_ib_b - w)
    assert err[np.abs(w) > 1e-4].max() < 1e-9 and err.max() < 1e-6
    assert np.abs(cf.f_b - mot.f_b).max() < 1e-12
    # any layout that observes the rate: a random redundant one
    R = random_layout(rng)
    rs = solve_least_squares(simulate_array(R, mot), R, omega0=w[0])
    assert np.abs(rs.omega_ib_b - w).max() < 1e-9
    assert np.abs(rs.f_b - mot.f_b).max() < 1e-9
    assert np.abs(rs.omega_dot_ib_b - mot.omega_dot_ib_b).max() < 1e-8


ZC = HarmonicBodyMotion.zero_crossing()
T60 = np.arange(0.0, 60.0, 1e-3)


def sign_errors(est, w, floor):
    return int(np.sum((np.sign(est) != np.sign(w)) & (np.abs(w) > floor)))


def test_signs_through_zero_crossings_error_free():
    """p, q, r cross zero at different times over 60 s (sinusoids)."""
    mot = ZC.motion(T60)
    w = mot.omega_ib_b
    assert all((np.diff(np.sign(w[:, j])) != 0).sum() >= 4 for j in range(3))
    L = ten_layout(0.1)
    data = simulate_array(L, mot)
    for sol in (solve_closed_form(data, L, omega0=w[0]), solve_least_squares(data, L, omega0=w[0]),
                solve_closed_form(data, L, omega0=w[0], sign_rule="source")):
        assert sign_errors(sol.omega_ib_b, w, 1e-6) == 0
    ls = solve_least_squares(data, L, omega0=w[0])
    assert np.abs(ls.omega_ib_b - w).max() < 1e-9


def test_signs_through_zero_crossings_with_noise():
    """With 1e-4 m/s^2 noise per sample the robust rule (products pr, qr and
    the sign tracker) makes no sign error where a rate exceeds 3 sigma of its
    near-zero noise (sqrt(sigma(p^2)) ~ 0.016 rad/s at d = 0.1 m); the
    source's rule (eq. 15, divides by p) fails at p's zero crossings."""
    sigma = 1e-4
    mot = ZC.motion(T60)
    w = mot.omega_ib_b
    L = ten_layout(0.1)
    data = simulate_array(L, mot, ArrayErrors.build(10, noise_sigma=sigma), np.random.default_rng(5))
    floor = 3 * np.sqrt(sigma * np.sqrt(6) / 0.4)
    robust = solve_closed_form(data, L, omega0=w[0], noise_sigma=sigma)
    assert sign_errors(robust.omega_ib_b, w, floor) == 0
    lsf = solve_least_squares(data, L, omega0=w[0], rate_filter=RateFilter(sensor_noise=sigma))
    assert sign_errors(lsf.omega_ib_b, w, floor) == 0
    src = solve_closed_form(data, L, omega0=w[0], sign_rule="source")
    bad = np.isnan(src.omega_ib_b[:, 2]).sum() + sign_errors(src.omega_ib_b[:, 2], w[:, 2], floor)
    assert bad > 10
    with pytest.raises(InputError, match="divides by p"):
        src.imu()


def test_rate_filter_averages_the_noise():
    sigma = 1e-3
    mot = ZC.motion(T1K)
    w = mot.omega_ib_b
    L = ten_layout(0.1)
    data = simulate_array(L, mot, ArrayErrors.build(10, noise_sigma=sigma), np.random.default_rng(2))
    raw = solve_least_squares(data, L, omega0=w[0])
    filt = solve_least_squares(data, L, omega0=w[0], rate_filter=RateFilter(sensor_noise=sigma))
    rms = lambda s: np.sqrt(np.mean((s.omega_ib_b - w) ** 2))
    assert rms(filt) < 0.7 * rms(raw)
    # the filter's sigma describes its error (within a factor 2 in RMS)
    z = (filt.omega_ib_b - w) / filt.rate_sigma
    assert 0.5 < np.sqrt(np.mean(z**2)) < 2.0


def test_global_sign_is_unobservable_and_omega0_fixes_it():
    mot = ConstantRateMotion().motion(np.arange(0, 1, 1e-3))
    L = ten_layout()
    data = simulate_array(L, mot)
    with pytest.raises(InputError, match="omega0"):
        solve_closed_form(data, L)
    with pytest.raises(InputError, match="omega0"):
        solve_least_squares(data, L)
    for fn in (solve_closed_form, solve_least_squares):
        assert np.allclose(fn(data, L, omega0=[0.5, 1, 1]).omega_ib_b, [1, 2, 3], atol=1e-9)
        # omega and -omega give the same outputs: a wrong initial sign gives the mirror solution
        assert np.allclose(fn(data, L, omega0=[-1, -2, -3]).omega_ib_b, [-1, -2, -3], atol=1e-9)


def test_start_at_rest_needs_no_omega0():
    hm = HarmonicBodyMotion(tuple((0.0, [(1.0, 2 * np.pi * f, 0.0)]) for f in (0.2, 0.3, 0.5)),
                            ((1.0, []), (2.0, []), (-9.8, [])))
    mot = hm.motion(T1K)
    L = ten_layout()
    data = simulate_array(L, mot)
    assert np.abs(solve_least_squares(data, L).omega_ib_b - mot.omega_ib_b).max() < 1e-6
    assert sign_errors(solve_closed_form(data, L).omega_ib_b, mot.omega_ib_b, 1e-5) == 0


def test_rank_deficient_layouts_are_refused():
    data6 = simulate_array(six_layout(), ConstantRateMotion().motion(np.arange(0, 1, 0.01)))
    with pytest.raises(InputError, match="sign"):
        solve_least_squares(data6, six_layout())
    with pytest.raises(InputError, match="sign"):
        solve_closed_form(data6, six_layout())
    mags = solve_closed_form(data6, six_layout(), rate="magnitude")
    assert np.allclose(mags.omega_ib_b, [1, 2, 3], atol=1e-9) and not mags.signed
    with pytest.raises(InputError, match="magnitudes only"):
        mags.imu()
    cop = ArrayLayout(("a", "b", "c", "e"), [[0.1, 0, 0], [-0.1, 0, 0], [0, 0.1, 0], [0, -0.1, 0]], [[0, 0, 1]] * 4,
                      "coplanar")
    data = simulate_array(cop, ConstantRateMotion().motion(np.arange(0, 1, 0.01)))
    with pytest.raises(InputError, match="f_x, f_y"):
        solve_least_squares(data, cop, omega0=[1, 2, 3])
    with pytest.raises(InputError, match="closed form needs the source"):
        solve_closed_form(data, cop)


def test_solution_feeds_the_mechanizations(rng):
    mot = HarmonicBodyMotion.random(rng).motion(np.arange(0, 2, 0.01))
    L = ten_layout()
    sol = solve(simulate_array(L, mot), L, omega0=mot.omega_ib_b[0])
    assert sol.method == "closed-form/robust"
    for integ in ("cubic", "trapezoid"):
        imu = sol.imu(integ)
        assert isinstance(imu, ImuData) and len(imu) == len(mot)
        w, _ = imu.rates()
        assert np.abs(w[1:] - 0.5 * (mot.omega_ib_b[1:] + mot.omega_ib_b[:-1])).max() < 1e-3
    # the cubic increments integrate cubics exactly
    t = np.arange(0, 1, 0.1)
    y = np.column_stack([t**3, t**2, t])
    exact = np.zeros_like(y)
    exact[1:] = np.column_stack([np.diff(t**4 / 4), np.diff(t**3 / 3), np.diff(t**2 / 2)])
    assert np.abs(point_increments(t, y) - exact)[2:-1].max() < 1e-15
    assert sol.imu().dv_b.shape == (len(mot), 3)
    with pytest.raises(InputError, match="`method`"):
        solve(simulate_array(L, mot), L, method="magic")
