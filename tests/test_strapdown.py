"""Mechanizations against closed-form motion (issue 2 acceptance)."""

import numpy as np
import pytest

from inskit import earth
from inskit import rotations as rot
from inskit.jobs.demo import DEMO_TRAJECTORY
from inskit.errors import InputError
from inskit.simulation import ConingTrajectory, StationaryTrajectory, ideal_imu, truth_solution
from inskit.strapdown import NedIntegrator, mechanize
from inskit.types import ImuData
from inskit.units import ARCSEC, MICRO_G

LAT45 = np.radians(45.0)


def horizontal_error(sol, truth):
    d = earth.lla_to_ned(sol.lla, truth.lla[0]) - earth.lla_to_ned(truth.lla, truth.lla[0])
    return np.hypot(d[:, 0], d[:, 1]), d


def test_stationary_45N_one_hour_ideal():
    traj = StationaryTrajectory((LAT45, np.radians(10.0), 100.0), (0.02, -0.01, 1.0))
    t = np.arange(0.0, 3600.0 + 1e-9, 0.01)
    imu = ideal_imu(traj, t, nodes=1)  # constant rates: one node is exact
    truth = truth_solution(traj, t[[0, -1]])
    sol = mechanize(imu, truth.state(0), height="hold", height_ref=100.0)
    d = earth.lla_to_ned(sol.lla, truth.lla[0])
    assert np.hypot(d[:, 0], d[:, 1]).max() < 0.01  # < 1 cm
    att = rot.attitude_error(sol.C_nb, np.broadcast_to(truth.C_nb[0], sol.C_nb.shape))
    assert np.linalg.norm(att, axis=1).max() < 0.1 * ARCSEC


def test_schuler_oscillation_north_bias():
    """100 micro-g north accelerometer bias: north error = b/ws^2 (1 - cos ws t)."""
    lla = (LAT45, 0.0, 0.0)
    traj = StationaryTrajectory(lla)  # body axes = NED
    t = np.arange(0.0, 3 * 3600.0 + 1e-9, 0.01)
    imu = ideal_imu(traj, t, nodes=1)
    b = 100 * MICRO_G
    dv = imu.dv_b.copy()
    dv[1:, 0] += b * np.diff(t)
    sol = mechanize(ImuData(t, imu.dtheta_b, dv), truth_solution(traj, t[:1]).state(0),
                    height="hold", height_ref=0.0)
    north = earth.lla_to_ned(sol.lla, np.array(lla))[:, 0]
    rn, _ = earth.principal_radii(LAT45, 0.0)
    ws = np.sqrt(earth.gravity_down(LAT45, 0.0) / rn)
    wf = earth.OMEGA_IE * np.sin(LAT45)  # Foucault modulation of the Schuler loop
    closed = b / ws**2 * (1.0 - np.cos(ws * t) * np.cos(wf * t))
    # period from the zero crossings of the north velocity (every half period)
    vn = sol.v_n[:, 0]
    k = np.where((vn[1:-1] > 0) != (vn[2:] > 0))[0] + 1
    crossings = t[k] - vn[k] * (t[k + 1] - t[k]) / (vn[k + 1] - vn[k])
    period = 2.0 * np.mean(np.diff(np.concatenate([[0.0], crossings])))
    assert period == pytest.approx(2 * np.pi / ws, rel=0.005)
    first = t < 2 * np.pi / ws
    assert north[first].max() == pytest.approx(closed[first].max(), rel=0.03)
    assert north[first].max() == pytest.approx(2 * b / ws**2, rel=0.03)
    assert np.abs(north - closed).max() < 0.03 * closed.max()


def _coning_drift(step, coning):
    cone = ConingTrajectory((LAT45, 0.0, 0.0), (0.0, 0.0, 0.0), np.radians(1.0), 1.0)
    t = np.arange(0.0, 600.0 + 1e-9, step)
    imu = ideal_imu(cone, t, nodes=8)
    truth = truth_solution(cone, t[[0, -1]])
    sol = mechanize(imu, truth.state(0), coning=coning, height="hold", height_ref=0.0)
    return np.linalg.norm(rot.attitude_error(sol.C_nb[-1], truth.C_nb[-1]))


def test_coning_two_sample_correction():
    single = _coning_drift(0.01, False)
    two = _coning_drift(0.01, True)
    two_half = _coning_drift(0.005, True)
    assert single > 10 * two
    assert two > 10 * two_half  # fourth-order error: 16x expected


def test_coning_increments_closed_form():
    cone = ConingTrajectory((LAT45, 0.0, 0.0), (0.0, 0.0, 0.0), np.radians(1.0), 1.0)
    t = np.arange(0.0, 2.0, 0.01)
    # remove the Earth-rate part: at the equator pole-less check, compare the
    # quadrature of the coning rate alone with its closed-form integral
    kin_rate = lambda tt: cone.kinematics(tt).omega_nb_b  # noqa: E731
    x, w = np.polynomial.legendre.leggauss(8)
    a, b = t[:-1], t[1:]
    quad = sum(wi * kin_rate(0.5 * (a + b) + 0.5 * (b - a) * xi) for xi, wi in zip(x, w)) * 0.5 * (b - a)[:, None]
    assert np.allclose(quad, cone.coning_increment(a, b), atol=1e-16)


# the closed-form drive of the demo: turns, speed changes, climbs (sinusoids in closed form)
DYNAMIC = DEMO_TRAJECTORY


@pytest.fixture(scope="module")
def dynamic_run():
    t = np.arange(0.0, 600.0 + 1e-9, 0.01)
    imu = ideal_imu(DYNAMIC, t)
    truth = truth_solution(DYNAMIC, t)
    sols = {f: mechanize(imu, truth.state(0), frame=f) for f in ("ned", "wander", "ecef", "inertial")}
    return imu, truth, sols


def test_dynamic_trajectory_is_dynamic(dynamic_run):
    _, truth, _ = dynamic_run
    speed = np.linalg.norm(truth.v_n[:, :2], axis=1)
    assert speed.max() - speed.min() > 5.0  # speed changes
    assert np.ptp(truth.euler[:, 2]) > 1.0  # turns
    assert np.ptp(truth.lla[:, 2]) > 30.0  # climbs


@pytest.mark.parametrize("frame", ["ned", "wander", "ecef", "inertial"])
def test_dynamic_trajectory_each_frame_matches_truth(dynamic_run, frame):
    _, truth, sols = dynamic_run
    sol = sols[frame]
    d = earth.lla_to_ned(sol.lla, truth.lla[0]) - earth.lla_to_ned(truth.lla, truth.lla[0])
    assert np.linalg.norm(d, axis=1).max() < 0.05
    assert np.abs(sol.v_n - truth.v_n).max() < 1e-3
    assert np.linalg.norm(rot.attitude_error(sol.C_nb, truth.C_nb), axis=1).max() < 1 * ARCSEC


def test_dynamic_frames_agree_with_each_other(dynamic_run):
    _, truth, sols = dynamic_run
    ref = sols["ned"]
    for frame in ("wander", "ecef", "inertial"):
        d = earth.lla_to_ned(sols[frame].lla, truth.lla[0]) - earth.lla_to_ned(ref.lla, truth.lla[0])
        assert np.linalg.norm(d, axis=1).max() < 0.05, frame


def test_chunked_equals_whole(dynamic_run):
    imu, truth, sols = dynamic_run
    for frame in ("ned", "wander", "ecef", "inertial"):
        chunked = mechanize(imu.slice(0, 20001), truth.state(0), frame=frame, chunk_size=777)
        whole = sols[frame].slice(0, 20001)
        assert np.array_equal(chunked.lla, whole.lla), frame
        assert np.array_equal(chunked.q_nb, whole.q_nb), frame


def test_wander_azimuth_crosses_the_pole():
    """Start 5.5 km from the North Pole flying north at 100 m/s: the wander
    solution stays identical to the (singularity-free) ECEF one across the pole."""
    t = np.arange(0.0, 300.0 + 1e-9, 0.01)
    imu = ideal_imu(StationaryTrajectory((LAT45, 0.0, 0.0)), t, nodes=1)
    start = NavStateAt = truth_solution(StationaryTrajectory((np.radians(89.95), 0.3, 1000.0)), t[:1]).state(0)
    start = type(NavStateAt)(0.0, start.lla, [100.0, 0.0, 0.0], start.q_nb)
    wander = mechanize(imu, start, frame="wander")
    ecef = mechanize(imu, start, frame="ecef")
    assert np.degrees(wander.lla[:, 0]).max() > 89.999  # passed within 111 m of the pole
    assert wander.lla[-1, 0] < wander.lla[len(t) // 2, 0]  # and came down the other side
    r_w = earth.lla_to_ecef(wander.lla)
    r_e = earth.lla_to_ecef(ecef.lla)
    assert np.linalg.norm(r_w - r_e, axis=1).max() < 0.05
    # horizontal attitude agrees; heading near the pole is ill-conditioned only in NED terms
    att = rot.attitude_error(wander.C_nb[-1], ecef.C_nb[-1])
    assert np.linalg.norm(att) < 1e-5


def test_height_aid_converges_to_reference():
    traj = StationaryTrajectory((LAT45, 0.0, 50.0))
    t = np.arange(0.0, 200.0 + 1e-9, 0.01)
    imu = ideal_imu(traj, t, nodes=1)
    s0 = truth_solution(traj, t[:1]).state(0)
    start = type(s0)(0.0, s0.lla + [0, 0, 20.0], s0.v_n, s0.q_nb)  # 20 m wrong
    sol = mechanize(imu, start, height="aid", height_ref=50.0, height_time_constant=5.0)
    assert abs(sol.lla[-1, 2] - 50.0) < 0.01
    free = mechanize(imu, start)
    assert abs(free.lla[-1, 2] - 70.0) > 0.5  # the free channel diverges from 70 m


def test_streaming_rejects_overlap_and_bad_options():
    traj = StationaryTrajectory((LAT45, 0.0, 0.0))
    t = np.arange(0.0, 1.0, 0.01)
    imu = ideal_imu(traj, t, nodes=1)
    integ = NedIntegrator(truth_solution(traj, t[:1]).state(0))
    integ.run(imu.slice(0, 50))
    with pytest.raises(InputError, match="not after"):
        integ.run(imu.slice(40, 60))
    with pytest.raises(InputError, match="height"):
        NedIntegrator(truth_solution(traj, t[:1]).state(0), height="baro")
    with pytest.raises(InputError, match="external height"):
        mechanize(imu, truth_solution(traj, t[:1]).state(0), height="hold")
    with pytest.raises(InputError, match="frame"):
        mechanize(imu, truth_solution(traj, t[:1]).state(0), frame="body")


@pytest.mark.parametrize("frame", ["ned", "wander", "ecef", "inertial"])
def test_an_initial_state_before_the_imu_is_taken_only_when_row_0_can_cover_the_gap(frame):
    """A state 10 ms before an IMU whose row 0 is the initial epoch (zero increments) integrated that row as a
    measured interval, free fall (98.2 m for 100 m at the end of the car's run); 5 s early: -905 m.  Refused now,
    saying what to give; a row 0 of real increments one interval after the state (a file without the initial row)
    is still integrated, and matches the run from row 0's own state."""
    traj = StationaryTrajectory((LAT45, np.radians(10.0), 100.0), (0.02, -0.01, 1.0))
    t = np.arange(0.0, 10.0 + 1e-9, 0.01)
    imu = ideal_imu(traj, t, nodes=1)
    s0 = truth_solution(traj, t[:1]).state(0)
    for dt, said in ((0.01, r"whose increments are all zero: an initial epoch"),
                     (5.0, r"is 5 s before the IMU's first row .* longer than its sampling interval \(0\.01 s\)")):
        early = type(s0)(s0.time - dt, s0.lla, s0.v_n, s0.q_nb)
        with pytest.raises(InputError, match=said + r".*give the state at the IMU's first time, 0\.000000 s"):
            mechanize(imu, early, frame=frame)
    cover = ideal_imu(traj, t, nodes=1, t_before=-0.01)  # row 0: the increment over (-0.01, 0]
    early = type(s0)(-0.01, s0.lla, s0.v_n, s0.q_nb)
    a, b = mechanize(cover, early, frame=frame), mechanize(imu, s0, frame=frame)
    assert np.abs(earth.lla_to_ned(a.lla, b.lla[0]) - earth.lla_to_ned(b.lla, b.lla[0])).max() < 1e-6


@pytest.mark.parametrize("args, options, said", [
    ((), {"foo": 1}, r"^'foo': not an option of the ned mechanization, which takes coning, height, "
                     r"height_time_constant, gravity$"),
    ((), {"frame": "wander", "height": "hold"}, r"^'height': not an option of the wander mechanization, which "
                                                r"takes coning, alpha0, gravity; height and height_time_constant "
                                                r"are the NED frame's"),
    ((), {"coning": "no"}, r"^`coning` must be True or False, got str 'no'$"),
    ((), {"height_ref": 100.0}, r"^`height_ref` would be ignored: .* \(the height here is 'free'\)$"),
    ((), {"frame": "ecef", "height_ref": 100.0}, r"^`height_ref` would be ignored: .* \(the frame here is 'ecef'\)$"),
    ((), {"height": "aid", "height_ref": 1.0, "height_time_constant": "10"},
     r"^`height_time_constant` must be a finite number > 0 \[s\], got '10'$"),
    ((), {"frame": "wander", "alpha0": float("nan")}, r"^`alpha0` must be a finite wander angle \[rad\], got nan$"),
    ((), {"chunk_size": 0}, r"^`chunk_size` must be an integer >= 1 \(rows per compiled call\), got 0$"),
    (("imu.csv",), {}, r"^`imu` must be an ImuData \(a file: read it first, inskit\.read_imu\(path\)\), got str "
                       r"'imu\.csv'$"),
])
def test_mechanize_refuses_arguments_it_would_ignore_or_misread(args, options, said):
    """inskit.mechanize(imu, init, foo=1) and frame='wander' with height='hold' were TypeErrors out of the
    integrators, a file name for imu an AttributeError ('str' object has no attribute 'slice'); coning='no'
    compensated (a non-empty string is true) and a height_ref with height='free' or in another frame was
    ignored without a word."""
    traj = StationaryTrajectory((LAT45, 0.0, 0.0))
    t = np.arange(0.0, 1.0, 0.01)
    imu = args[0] if args else ideal_imu(traj, t, nodes=1)
    with pytest.raises(InputError, match=said):
        mechanize(imu, truth_solution(traj, t[:1]).state(0), **options)


def test_ned_refuses_the_poles_and_wander_carries_on():
    """Issue 12: mechanize from lat 90 wrote latitudes above 90 deg."""
    tr = StationaryTrajectory((np.radians(89.95), 0.3, 10.0))
    t = np.arange(0.0, 20.0, 0.01)
    imu = ideal_imu(tr, t, nodes=1)
    s0 = truth_solution(tr, t[:1]).state(0)
    with pytest.raises(InputError, match=r"within 0\.1 deg of a pole, .* use the wander-azimuth or ECEF frame "
                                         r"\(frame='wander' or 'ecef'; --frame wander\|ecef on the command line\)$"):
        mechanize(imu, s0)
    sol = mechanize(imu, s0, frame="wander")
    assert np.all(np.abs(sol.lla[:, 0]) <= np.pi / 2)
    assert abs(sol.lla[-1, 0] - s0.lla[0]) * 6.4e6 < 1e-3


@pytest.mark.parametrize("frame", ["ned", "wander", "ecef", "inertial"])
def test_every_frame_navigates_with_the_chosen_gravity_model(frame):
    """At rest at 1600 m for 600 s, IMU data made with the J2 model: every frame
    mechanized with "j2" stays within a centimetre; with the default normal
    gravity it drifts by metres (J2 - normal at 40 deg: 1.4e-5 m/s^2 north,
    4.8e-5 m/s^2 down, grown by the Schuler loop and the unstable height channel)."""
    traj = StationaryTrajectory((np.radians(40.0), np.radians(-105.0), 1600.0), (0.0, 0.0, 0.3))
    t = np.arange(0.0, 600.0 + 1e-9, 0.05)
    imu = ideal_imu(traj, t, nodes=1, gravity="j2")  # constant rates: one node is exact
    truth = truth_solution(traj, t[[0, -1]])
    sol = mechanize(imu, truth.state(0), frame=frame, gravity="j2")
    d = earth.lla_to_ned(sol.lla[-1], truth.lla[-1])
    assert np.hypot(d[0], d[1]) < 0.01 and abs(d[2]) < 0.01
    other = mechanize(imu, truth.state(0), frame=frame)
    d = earth.lla_to_ned(other.lla[-1], truth.lla[-1])
    assert np.hypot(d[0], d[1]) > 0.3 and abs(d[2]) > 5.0


def test_gravity_model_is_checked_and_named():
    s0 = truth_solution(StationaryTrajectory((LAT45, 0.0, 0.0)), np.array([0.0])).state(0)
    assert NedIntegrator(s0).gravity == "normal"
    assert NedIntegrator(s0, gravity="normal-simple").gravity == "normal-simple"
    with pytest.raises(InputError, match="gravity model 'egm96'"):
        NedIntegrator(s0, gravity="egm96")
