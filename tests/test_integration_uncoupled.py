"""The uncoupled scheme: GNSS resets the INS."""

import numpy as np
import pytest

from inskit import earth
from inskit.errors import InputError
from inskit.integration import run_uncoupled
from inskit.simulation import ideal_imu, truth_solution
from inskit.simulation.segments import SegmentTrajectory
from inskit.types import GnssData, ImuData

LEVER = np.array([0.5, 0.2, -1.0])


def setup(bias=0.0):
    tr = SegmentTrajectory((np.radians(30), np.radians(-5), 50.0), yaw0=1.0, speed0=10.0)
    tr.cruise(5).turn(np.radians(90), rate=np.radians(10)).cruise(20)
    t = np.arange(0.0, tr.duration, 0.01)
    truth = truth_solution(tr, t)
    imu = ideal_imu(tr, t, nodes=3)
    if bias:
        dv = imu.dv_b.copy()
        dv[1:, 0] += bias * np.diff(t)
        imu = ImuData(t, imu.dtheta_b, dv)
    tg = t[50::100] + 0.004  # fixes between IMU samples
    sol_t = truth_solution(tr, tg, with_rates=True)
    r = earth.lla_to_ecef(sol_t.lla) + np.einsum("nij,nj->ni", earth.dcm_en(sol_t.lla[:, 0], sol_t.lla[:, 1]),
                                                 np.einsum("nij,j->ni", sol_t.C_nb, LEVER))
    w_b = np.column_stack([sol_t.extra[f"w{a}_rad_s"] for a in "xyz"])
    v_ant = sol_t.v_n + np.einsum("nij,nj->ni", sol_t.C_nb, np.cross(w_b, LEVER))
    gnss = GnssData(tg, earth.ecef_to_lla(r), np.full((len(tg), 3), 0.01), v_ant, np.full((len(tg), 3), 0.01))
    return imu, truth, gnss


def test_resets_put_the_antenna_on_the_fixes():
    """With a 1 mg accelerometer bias the free INS drifts metres in 30 s.
    Position resets put the IMU back on the truth at every fix (the 4 ms
    extrapolation to the fix with a velocity error below 0.3 m/s: < 2 mm),
    while the velocity error, never reset, keeps growing between fixes."""
    imu, truth, gnss = setup(bias=1e-2)
    sol = run_uncoupled(imu, truth.state(0), gnss, lever_arm_b=LEVER, use_velocity=False)
    k = np.searchsorted(imu.time, gnss.time, side="right") - 1
    d = earth.lla_to_ned(sol.lla[k], truth.lla[k])
    assert np.hypot(d[:, 0], d[:, 1]).max() < 2e-3
    dv = np.linalg.norm(sol.v_n - truth.v_n, axis=1)
    assert dv[-1] > 0.2
    free = run_uncoupled(imu, truth.state(0), gnss, use=np.zeros(len(gnss), bool))
    df = earth.lla_to_ned(free.lla, truth.lla)
    assert np.hypot(df[:, 0], df[:, 1]).max() > 1.0


def test_position_and_velocity_resets_hold_the_whole_track():
    """Resetting velocity too, the 1 mg bias moves the IMU by at most
    b T^2 / 2 + (velocity extrapolation) ~ 5 mm between 1 s fixes."""
    imu, truth, gnss = setup(bias=1e-2)
    sol = run_uncoupled(imu, truth.state(0), gnss, lever_arm_b=LEVER, use_velocity=True)
    d = earth.lla_to_ned(sol.lla, truth.lla)
    assert np.hypot(d[:, 0], d[:, 1]).max() < 0.01


def test_velocity_reset_needs_velocity():
    imu, truth, gnss = setup()
    g = GnssData(gnss.time, gnss.lla, gnss.sigma_ned)
    with pytest.raises(InputError, match="no velocity"):
        run_uncoupled(imu, truth.state(0), g, use_velocity=True)


def test_uncoupled_mechanizes_with_the_chosen_gravity_model():
    from inskit.strapdown import mechanize

    imu, truth, gnss = setup()
    none = np.zeros(len(gnss), bool)
    for model in ("normal-simple", "j2"):
        free = run_uncoupled(imu, truth.state(0), gnss, use=none, gravity=model)
        assert np.array_equal(free.lla, mechanize(imu, truth.state(0), gravity=model).lla)
    assert not np.array_equal(free.lla, run_uncoupled(imu, truth.state(0), gnss, use=none).lla)
