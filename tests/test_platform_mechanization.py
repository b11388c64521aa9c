"""Platform mechanizations (issue 10, part 1): perfect sensors, agreement with
strapdown, Schuler and Earth-rate oscillations against closed form."""

import numpy as np
import pytest

from inskit import earth
from inskit import rotations as rot
from inskit.errors import ConfigError
from inskit.platform import error_model as em
from inskit.platform.mechanization import mechanize_platform
from inskit.platform.sensors import InitialErrors, PlatformErrors
from inskit.platform.world import platform_truth
from inskit.simulation import (
    HarmonicTrajectory,
    StationaryTrajectory,
    ideal_imu,
    truth_solution,
)
from inskit.simulation.segments import SegmentTrajectory
from inskit.strapdown import mechanize
from inskit.units import ARCMIN, DEG_PER_HOUR

LAT50 = np.radians(50.0)
EPS = 0.01 * DEG_PER_HOUR


def position_error(sol, ref):
    """NED offsets [m] of ``sol`` from ``ref`` (same epochs)."""
    return earth.lla_to_ned(sol.lla, ref.lla[0]) - earth.lla_to_ned(ref.lla, ref.lla[0])


@pytest.fixture(scope="module")
def north_8h():
    traj = HarmonicTrajectory((LAT50, np.radians(30.0), 0.0), north=(0.0, 10.0, ()))
    return {m: platform_truth(traj, 8 * 3600.0, 2.0, earth_model=m) for m in ("wgs84", "sphere")}


@pytest.mark.parametrize("model", ["wgs84", "sphere"])
def test_semi_analytical_perfect_sensors_8h(north_8h, model):
    """Perfect instruments: the platform stays level to < 1e-9 rad and the
    position error below 1 m over 8 h moving north.  Both limits are the
    issue's; what is left is RK4 truncation at a 2 s step (about 1e-12 rad and
    micrometres), so a wrong Coriolis or transport term (cm/s of velocity,
    1e-7 rad of tilt within minutes) fails them by orders of magnitude."""
    truth = north_8h[model]
    run = mechanize_platform(truth, "semi-analytical")
    assert np.abs(run.tilt_enu).max() < 1e-9
    d = position_error(run.solution, truth.solution())
    assert np.abs(d).max() < 1.0
    # the gimbal angles are the body attitude (heading north, level)
    assert np.abs(rot.wrap_angle(run.gimbal_rpy - truth.solution().euler)).max() < 1e-9


@pytest.fixture(scope="module")
def manoeuvres_1h():
    tr = SegmentTrajectory((LAT50, np.radians(30.0), 100.0), 0.3, 0.0, 5.0)
    tr.static(60).accelerate(15.0, 60).cruise(600).turn(np.radians(90), rate=np.radians(1.0)).cruise(900)
    tr.turn(np.radians(-135), rate=np.radians(0.5)).climb(np.radians(3.0), 200)
    tr.cruise(3600.0 - tr.duration)
    return tr


def test_three_kinds_agree_with_strapdown_1h(manoeuvres_1h):
    """Semi-analytical, analytical and geometric platforms, and the strapdown
    NED mechanization of the same trajectory (ideal 10 Hz IMU, height held),
    agree to < 1 m over 1 h (issue limit; they agree to millimetres, so a
    sign slip in any frame conversion fails by far)."""
    tr = manoeuvres_1h
    truth = platform_truth(tr, 3600.0 - 1.0, 1.0)
    t = np.arange(0.0, 3599.0 + 1e-9, 0.1)
    imu = ideal_imu(tr, t)
    tt = truth_solution(tr, t)
    sd = mechanize(imu, tt.state(0), height="hold", height_ref=tt.lla[:, 2]).interpolate(truth.time)
    sols = {k: mechanize_platform(truth, k).solution for k in ("semi-analytical", "analytical", "geometric")}
    for k, s in sols.items():
        assert np.abs(position_error(s, sd)).max() < 1.0, k
        assert np.abs(position_error(s, truth.solution())).max() < 1.0, k
        att = rot.attitude_error(s.C_nb, sd.C_nb)
        assert np.abs(att).max() < 1e-5, k  # strapdown at 10 Hz through turns: arcsec level
    assert np.abs(position_error(sols["analytical"], sols["geometric"])).max() < 1.0


def _crossings(t, x):
    k = np.nonzero((x[:-1] > 0) != (x[1:] > 0))[0]
    return t[k] - x[k] * (t[k + 1] - t[k]) / (x[k + 1] - x[k])


def test_schuler_oscillation_against_closed_form():
    """East gyro drift 0.01 deg/h at rest (sphere): the tilt about east
    oscillates at the 84.4 min Schuler period with amplitude eps/w_s
    (0.134 arcmin), modulated at the Foucault rate.  Period and amplitude
    within 5 % (issue); measured agreement is 0.5 %."""
    truth = platform_truth(StationaryTrajectory((LAT50, 0.3, 0.0)), 8 * 3600.0, 5.0, earth_model="sphere")
    run = mechanize_platform(truth, errors=PlatformErrors(gyro_drift=(EPS, 0.0, 0.0)))
    cf = em.stationary_closed_form(truth.time, LAT50, (EPS, 0.0, 0.0))
    ws = np.sqrt(earth.GM / earth.R_SPHERE**3)
    assert 2 * np.pi / ws / 60 == pytest.approx(84.4, rel=0.002)  # g = GM/R^2 = 9.80 on the 6378 km sphere
    tilt = run.tilt_enu[:, 0]
    t = truth.time
    first6h = t < 6 * 3600  # before the Foucault envelope of this channel passes zero (7.8 h)
    period = 2 * np.mean(np.diff(_crossings(t[first6h], tilt[first6h])))
    assert period == pytest.approx(2 * np.pi / ws, rel=0.05)
    assert period / 60 == pytest.approx(84.4, rel=0.05)
    one = t < 2 * np.pi / ws
    assert np.abs(tilt[one]).max() == pytest.approx(EPS / ws, rel=0.05)
    assert np.abs(tilt[one]).max() / ARCMIN == pytest.approx(0.134, rel=0.05)  # SOURCES-NOTES §2.4
    for j in range(3):
        ref = cf["tilt_enu"][:, j]
        assert np.abs(run.tilt_enu[:, j] - ref).max() < 0.05 * np.abs(ref).max()
    # a wrong closed form (no Foucault modulation) misses by far more than 5 %
    no_foucault = EPS / ws * np.sin(ws * t)
    assert np.abs(tilt - no_foucault).max() > 0.2 * np.abs(no_foucault).max()


def test_earth_rate_oscillation_against_closed_form():
    """The same drift over 48 h: the latitude error follows the 24 h
    (sidereal) Earth-rate oscillation eps sin(U t)/U (amplitude 6.6e-4 rad,
    4.2 km) under the Schuler ripple.  Period and amplitude within 5 %."""
    truth = platform_truth(StationaryTrajectory((LAT50, 0.3, 0.0)), 48 * 3600.0, 10.0, earth_model="sphere")
    run = mechanize_platform(truth, errors=PlatformErrors(gyro_drift=(EPS, 0.0, 0.0)))
    t = truth.time
    dlat = run.solution.lla[:, 0] - truth.lla[::2, 0]
    cf = em.stationary_closed_form(t, LAT50, (EPS, 0.0, 0.0))
    ws = np.sqrt(earth.GM / earth.R_SPHERE**3)
    # remove the Schuler ripple with a moving mean over one Schuler period
    w = round(2 * np.pi / ws / truth.dt)
    slow = np.convolve(dlat, np.ones(w) / w, mode="same")
    core = slice(w, len(t) - w)
    cr = _crossings(t[core], slow[core])
    period = 2 * np.mean(np.diff(cr))
    assert period == pytest.approx(2 * np.pi / earth.OMEGA_IE, rel=0.05)
    assert np.abs(slow[core]).max() == pytest.approx(EPS / earth.OMEGA_IE, rel=0.05)
    assert np.abs(dlat - cf["d_lat"]).max() < 0.05 * np.abs(cf["d_lat"]).max()
    assert np.abs(run.solution.lla[:, 1] - truth.lla[::2, 1] - cf["d_lon"]).max() < 0.05 * np.abs(cf["d_lon"]).max()


def test_attitude_error_is_platform_tilt():
    """Semi-analytical: Euler angles from the gimbals, so the attitude error
    of the solution is the platform tilt (an initial tilt shows up 1:1)."""
    truth = platform_truth(StationaryTrajectory((LAT50, 0.3, 0.0), (0.1, -0.05, 1.0)), 600.0, 1.0)
    tilt0 = np.array([2.0, -1.0, 5.0]) * ARCMIN
    run = mechanize_platform(truth, initial=InitialErrors(tilt=tilt0))
    assert np.allclose(run.tilt_enu[0], tilt0, atol=1e-12)
    C_true = rot.dcm_from_quat(truth.q_nb[0])
    att = rot.attitude_error(run.solution.C_nb[0], C_true)  # NED
    assert np.allclose(att, [tilt0[1], tilt0[0], -tilt0[2]], atol=1e-12)


def test_analytical_and_geometric_platform_angles():
    """The analytical platform drifts from inertial axes by eps t; the angles
    between the geometric system's two platforms are latitude and hour angle
    lambda + U t."""
    truth = platform_truth(StationaryTrajectory((LAT50, 0.3, 0.0)), 3600.0, 10.0)
    eps = np.array([1.0, -2.0, 0.5]) * EPS
    ra = mechanize_platform(truth, "analytical", errors=PlatformErrors(gyro_drift=eps))
    drift = np.column_stack([ra.solution.extra[f"drift_{a}_rad"] for a in "xyz"])
    assert np.allclose(drift[-1], eps * 3600.0, rtol=1e-9, atol=1e-15)
    rg = mechanize_platform(truth, "geometric")
    x = rg.solution.extra
    assert np.allclose(x["p2_lat_rad"], LAT50, atol=1e-12)
    assert np.allclose(rot.wrap_angle(x["p2_hour_angle_rad"] - 0.3 - earth.OMEGA_IE * truth.time), 0.0, atol=1e-12)


def test_free_vertical_channel_is_unstable():
    """With the vertical channel free, a 100 micro-g vertical accelerometer
    error grows exponentially (time constant sqrt(R/2g), 9.5 min): after 1 h
    the height error far exceeds the b t^2/2 = 635 m of a flat Earth."""
    truth = platform_truth(StationaryTrajectory((LAT50, 0.3, 0.0)), 3600.0, 1.0)
    run = mechanize_platform(truth, errors=PlatformErrors(accel_bias=(0.0, 0.0, 1e-3)), vertical="free")
    dh = run.solution.lla[-1, 2] - truth.lla[-1, 2]
    assert dh > 10 * 0.5e-3 * 3600.0**2
    held = mechanize_platform(truth, errors=PlatformErrors(accel_bias=(0.0, 0.0, 1e-3)))
    assert np.abs(held.solution.lla[:, 2] - truth.lla[::2, 2]).max() < 1e-9


def test_bad_arguments():
    truth = platform_truth(StationaryTrajectory((LAT50, 0.3, 0.0)), 10.0, 1.0)
    with pytest.raises(ConfigError, match="`kind` must be one of"):
        mechanize_platform(truth, "strapdown")
    with pytest.raises(ConfigError, match="`earth` must be one of"):
        platform_truth(StationaryTrajectory((LAT50, 0.3, 0.0)), 10.0, 1.0, earth_model="flat")
    with pytest.raises(ConfigError, match="`gyro_drift` must be three"):
        PlatformErrors(gyro_drift=(1.0, 2.0))
    with pytest.raises(ConfigError, match="noise needs an `rng`"):
        mechanize_platform(truth, errors=PlatformErrors(gyro_noise=1e-6))
