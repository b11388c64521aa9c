"""IMU gaps: found, bridged on the last rates, paid for in covariance,
recovered from GNSS, and reported."""

import numpy as np
import pytest

from inskit import earth
from inskit import rotations as rot
from inskit.integration.gaps import bridge_gaps, find_gaps, gap_process_noise
from inskit.integration import StateLayout, ins_blocks
from inskit.jobs.config import config_from_dict
from inskit.jobs.navigate import navigate
from inskit.simulation import ideal_imu, truth_solution
from inskit.simulation.gnss import GnssErrors, simulate_gnss
from inskit.simulation.segments import SegmentTrajectory
from inskit.types import ImuData


@pytest.fixture(scope="module")
def turn_with_gap():
    tr = SegmentTrajectory((np.radians(45.0), np.radians(7.0), 100.0), yaw0=0.2, speed0=12.0)
    tr.cruise(30).turn(np.radians(90), rate=np.radians(6.0)).cruise(60)   # the turn lasts 15 s from t = 30 s
    t = np.arange(0.0, tr.duration, 0.01)
    imu = ideal_imu(tr, t, nodes=3)
    keep = ~((t > 33.0) & (t <= 43.0))  # 10 s of rows lost in the middle of the turn
    gappy = ImuData(t[keep], imu.dtheta_b[keep], imu.dv_b[keep])
    gnss, _ = simulate_gnss(tr, 0.0, tr.duration, GnssErrors(rate_hz=1.0, white_h_m=0.3, white_v_m=0.5,
                                                              velocity_sigma_m_s=0.0), np.random.default_rng(3))
    return tr, t, gappy, gnss, truth_solution(tr, t)


def test_find_and_bridge(turn_with_gap):
    tr, t, gappy, gnss, truth = turn_with_gap
    gaps = find_gaps(gappy)
    assert len(gaps) == 1 and gaps[0].length_s == pytest.approx(10.01, abs=1e-6)
    b, bg = bridge_gaps(gappy, gaps)
    k = bg[0].row
    assert len(b) == len(t) and np.allclose(b.time, t)  # the rows are back on the grid
    assert np.diff(b.time).max() < 0.0101
    # the inserted rows turn at the last rate for the whole gap: 6 deg/s x 10 s
    turned = np.degrees(np.linalg.norm(b.dtheta_b[k:k + 1000].sum(axis=0)))
    assert turned == pytest.approx(60.0, rel=0.01)
    q = gap_process_noise(StateLayout(ins_blocks()), 10.0)
    assert np.sqrt(q[8]) == pytest.approx(np.radians(50.0)) and np.sqrt(q[3]) == pytest.approx(10.0)


def test_navigate_bridges_warns_and_recovers(turn_with_gap):
    tr, t, gappy, gnss, truth = turn_with_gap
    s0 = truth.state(0)
    cfg = config_from_dict({
        "imu": {"file": "unused.csv"}, "gnss": {"file": "unused.csv"},
        "init": {"mode": "given", "lat_deg": float(np.degrees(s0.lla[0])), "lon_deg": float(np.degrees(s0.lla[1])),
                 "height_m": float(s0.lla[2]), "v_ned_m_s": [float(x) for x in s0.v_n],
                 "rpy_deg": [float(x) for x in np.degrees(s0.euler)], "sigma_pos_m": 0.5, "sigma_vel_m_s": 0.1,
                 "sigma_roll_pitch_deg": 0.1, "sigma_yaw_deg": 0.5},
        "noise": {"from_static": False, "gyro_arw_deg_sqrt_h": 0.05, "accel_vrw_m_s_sqrt_h": 0.03,
                  "gyro_bias_sigma_deg_h": 1.0, "accel_bias_sigma_ug": 100.0},
        "constraints": {"zupt": False, "nhc": False}, "filter": {"scale_factors": False},
    })
    logs = []
    res = navigate(cfg, inputs=(gappy, gnss), log=logs.append)
    assert any("gap of 10.010 s" in m for m in logs)
    c = res.forward.counts["gnss_pos"]
    assert c["rejected"] <= 0.05 * (c["used"] + c["rejected"])
    from inskit.jobs.navigate import health

    h = health(res.forward, res.gaps)
    assert h["verdict"] == "unhealthy" and any("IMU gap" in r for r in h["reasons"])
    # 20 s after the gap the GNSS has brought position and heading back
    sol = res.forward.nav
    k = np.searchsorted(sol.time, 63.0)
    kt = np.searchsorted(truth.time, sol.time[k])
    d = earth.lla_to_ned(sol.lla[k], truth.lla[kt])
    yaw = np.degrees(rot.attitude_error(sol.C_nb[k], truth.C_nb[kt])[2])
    assert np.hypot(d[0], d[1]) < 2.0 and abs(yaw) < 1.0


def test_a_change_of_rate_is_reported_and_not_taken_for_gaps():
    """A logger that switches from 200 Hz to 20 Hz: every 50 ms interval is
    ten times the log's median, so a global-median rule bridged each as a
    gap; judged against the local rate, the change is one reported event, and
    a real 2 s gap inside the 20 Hz part is still found."""
    from inskit.integration.gaps import find_gaps, find_rate_changes
    from inskit.types import ImuData

    t = np.concatenate([np.arange(0.0, 60.0, 0.005), np.arange(60.0, 100.0, 0.05)])
    t = np.concatenate([t[t < 80.0], t[t >= 82.0]])  # 2 s missing at 80 s
    n = len(t)
    imu = ImuData(t, np.zeros((n, 3)), np.zeros((n, 3)))
    gaps = find_gaps(imu)
    assert len(gaps) == 1 and abs(gaps[0].start_s - 80.0) < 0.06 and abs(gaps[0].length_s - 2.05) < 0.06
    ch = find_rate_changes(imu)
    assert len(ch) == 1
    c = ch[0]
    assert abs(c.rate_before_hz - 200.0) < 1 and abs(c.rate_after_hz - 20.0) < 0.5 and 59.0 < c.t_s < 64.0


def test_a_gap_of_minutes_is_refused_by_its_times(turn_with_gap, capsys, tmp_path):
    """A GPS week rollover the time column missed (604800 s) was bridged
    (mechanize warned, then failed 'within 0.1 deg of a pole'): a gap beyond
    MAX_GAP_S is refused, naming the file's times on either side of it (a row
    number counted the rows the job kept, not the file's lines), by navigate and mechanize."""
    from inskit import io
    from inskit.cli import main
    from inskit.errors import InputError
    from inskit.integration.gaps import MAX_GAP_S, refuse_long_gaps

    tr, t, gappy, gnss, truth = turn_with_gap
    refuse_long_gaps(find_gaps(gappy))  # 10 s: bridged, not refused
    late = gappy.time.copy()
    k = 5000
    late[k:] += 604800.0
    broken = ImuData(late, gappy.dtheta_b, gappy.dv_b)
    with pytest.raises(InputError, match=f"a gap of 60480.*from {late[k - 1]:.4f} s to {late[k]:.4f} s "
                                         rf"\(the file's times\).*at most {MAX_GAP_S:g} s"):
        refuse_long_gaps(find_gaps(broken), "log.csv")
    with pytest.raises(InputError, match=f"from {late[k - 1] - 0.25:.4f} s to"):  # the reader's offset taken off
        refuse_long_gaps(find_gaps(broken), "log.csv", time_offset_s=0.25)
    io.write_imu(tmp_path / "imu.csv", broken)
    io.write_solution(tmp_path / "truth.csv", truth)
    with pytest.raises(SystemExit) as e:
        main(["mechanize", str(tmp_path / "imu.csv"), "--init-from", str(tmp_path / "truth.csv")])
    assert e.value.code == 2 and f"from {late[k - 1]:.4f} s to {late[k]:.4f} s" in capsys.readouterr().err


def test_a_lone_imu_spike_below_the_readers_limits_is_named(monkeypatch):
    """One gyro sample of 5000 deg/s (87 rad/s) in a drive, below the
    readers' 1000 rad/s limit, was integrated without a word: the run
    unhealthy, no row named (found by the review of navigate's inputs).
    Lone spikes are now listed with their times (block by block, the same
    across block edges) for navigate's and mechanize's warnings; a real
    bump's ringing (tens of deg/s from one sample to the next) is not one."""
    from inskit.integration import gaps as G

    n = 2000
    t = np.arange(n) * 0.01
    rng = np.random.default_rng(0)
    w = np.radians(50.0) * np.sign(rng.standard_normal((n, 3)))  # ringing at +-50 deg/s, sample to sample
    f = np.tile([0.0, 0.0, -9.81], (n, 1)) + rng.standard_normal((n, 3))
    w[700, 0], f[1500, 2] = 87.0, 60.0 * 9.80665  # a gyro spike, an accelerometer one (60 g beside 1 g)
    imu = ImuData(t, np.r_[np.zeros((1, 3)), w[1:] * 0.01], np.r_[np.zeros((1, 3)), f[1:] * 0.01])
    got = G.imu_spikes(imu)
    assert [(s["row"], s["sensor"]) for s in got] == [(700, "gyro"), (1500, "accel")]
    assert got[0]["value"] == pytest.approx(np.linalg.norm(w[700])) and got[0]["t_s"] == t[700]
    for block in (7, 700, 701):  # the spike at a block's first, last or inner row: the same
        monkeypatch.setattr(G, "SPIKE_BLOCK_ROWS", block)
        assert G.imu_spikes(imu) == got
    assert G.imu_spikes(ImuData(t, np.r_[np.zeros((1, 3)), np.radians(50.0) * 0.01 * np.ones((n - 1, 3))],
                                imu.dv_b)) == [got[1]]  # the ringing alone: no gyro spike
    msg = G.spikes_warning(got, "imu.csv")
    assert msg.startswith("IMU: imu.csv: 2 lone samples far beyond their neighbours (t = 7.000 s, gyro 87 rad/s "
                          "beside 1.51; t = 15.000 s, accel 60 g beside ") and "corrupt rows?" in msg, msg
    assert G.spikes_warning([], "imu.csv") is None
