"""Issue 14 item 4 acceptance: a simulated car with its IMU pitched 4 deg
and yawed 2 deg against the vehicle.  With ``[constraints] mounting = true``
the angles are estimated within 0.2 deg and the position error is within
20 % of the run with a perfectly mounted IMU; without, the health warnings
name the mounting.  A short drive here; the whole examples/car.toml drive
and the real drive_0708 with a wrong mount in the slow tests."""

import re
import warnings
from pathlib import Path

import numpy as np
import pytest

from inskit import analysis, io
from inskit.jobs.config import config_from_dict, load_config
from inskit.jobs.navigate import navigate, summary
from inskit.jobs.reproduce_tight import BLOCKAGE_NAVIGATE
from inskit.jobs.simulate import write_simulation
from inskit.rotations import dcm_from_euler, rotvec_from_dcm
from inskit.simulation.scenario import Scenario, load_scenario, simulate
from scenarios import short_car

ROOT = Path(__file__).resolve().parents[1]
MOUNT = (0.0, 4.0, 2.0)  # [imu] mount_rpy_deg convention: 4 deg nose-down, 2 deg to the left
SHORT = short_car("short car", [{"type": "static", "duration_s": 40.0},
                                {"type": "accelerate", "speed_m_s": 15.0, "duration_s": 10.0},
                                {"type": "cruise", "duration_s": 20.0},
                                {"type": "turn", "angle_deg": 90.0, "radius_m": 40.0},
                                {"type": "climb", "angle_deg": 3.0, "duration_s": 20.0},
                                {"type": "turn", "angle_deg": -90.0, "radius_m": 40.0},
                                {"type": "cruise", "duration_s": 40.0},
                                {"type": "turn", "angle_deg": 180.0, "radius_m": 40.0},
                                {"type": "cruise", "duration_s": 30.0},
                                {"type": "decelerate", "speed_m_s": 0.0, "duration_s": 10.0},
                                {"type": "static", "duration_s": 10.0}])


def run(sc, mount, mounting, out_dir, windows, seed=1):
    """Simulate ``sc`` with its IMU at ``mount`` and navigate it; the
    antenna lever arm is given in the IMU's axes (as measured on the IMU),
    so that the mounting is the only difference between runs of one seed.
    Returns (summary, horizontal RMS error against the truth [m])."""
    sc = sc.model_copy(update={"imu": sc.imu.model_copy(update={"mount_rpy_deg": tuple(mount)})})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        write_simulation(simulate(sc, seed=seed), out_dir, plot=False, overwrite=True)
    lever_b = dcm_from_euler(np.radians(mount)) @ np.asarray(sc.gnss.lever_arm_b_m, float)
    cfg = {k: (dict(v) if isinstance(v, dict) else v) for k, v in BLOCKAGE_NAVIGATE.items()}
    cfg.update(name=sc.name, gnss={"file": "gnss.csv", "lever_arm_b_m": lever_b.tolist()},
               constraints={"mounting": mounting}, outages={"protocol": "windows", "windows_s": windows})
    res = navigate(config_from_dict(cfg, base_dir=out_dir, source=str(out_dir)))
    err = analysis.nav_error(res.forward.nav, io.read_solution(out_dir / "truth.csv"))
    return summary(res), float(np.sqrt(np.mean(err.pos_ned[:, 0] ** 2 + err.pos_ned[:, 1] ** 2)))


def mounting_warnings(s):
    return [w for w in s["health"]["warnings"] if w.startswith("mounting:")]


@pytest.fixture(scope="module")
def short(tmp_path_factory):
    sc = Scenario.model_validate(SHORT)
    d = tmp_path_factory.mktemp("mount")
    return {label: run(sc, mount, on, d / label, [[150.0, 180.0]])
            for label, mount, on in (("perfect", (0.0, 0.0, 0.0), False), ("on", MOUNT, True),
                                     ("off", MOUNT, False))}


def test_mounting_states_estimate_the_angles_within_0_2_deg(short):
    s, _ = short["on"]
    rpy, sig = s["mounting_rpy_deg"], s["mounting_sigma_deg"]
    assert abs(rpy[1] - MOUNT[1]) < 0.2 and abs(rpy[2] - MOUNT[2]) < 0.2, rpy
    assert sig[0] is None and 0 < sig[1] < 0.1 and 0 < sig[2] < 0.1, sig  # roll is not estimated
    assert s["mount_rpy_deg_corrected"] == pytest.approx([0.0, rpy[1], rpy[2]], abs=1e-9)
    assert s["states"] == 23 and s["health"]["verdict"] == "healthy" and not mounting_warnings(s)
    assert s["mounting_check"] is None  # modelled: the estimate is reported instead


def test_position_error_matches_the_perfectly_mounted_run(short):
    """Within 20 % (0.29 m against 0.26 m for seed 1; seeds 2..5 gave
    0.93, 0.99, 0.78, 0.99 times the perfect run)."""
    (_, e_on), (_, e_perfect) = short["on"], short["perfect"]
    assert e_on <= 1.2 * e_perfect, (e_on, e_perfect)


def test_without_the_states_the_warning_names_the_pitch(short):
    s, e_off = short["off"]
    w = mounting_warnings(s)
    assert len(w) == 1 and "[constraints] mounting = true" in w[0], s["health"]["warnings"]
    m = re.search(r"pitch ([+-]\d+\.\d+) deg", w[0])
    assert abs(float(m.group(1)) - MOUNT[1]) < 0.5, w[0]
    assert e_off > 5 * short["perfect"][1]  # what the warning is about: the run is lost


def test_no_warning_on_the_perfectly_mounted_car(short):
    s, _ = short["perfect"]
    assert not mounting_warnings(s), s["health"]["warnings"]
    ev = s["mounting_check"]
    assert abs(ev["pitch_deg"]) < 0.2 and abs(ev["yaw_deg"]) < 0.2, ev


@pytest.mark.slow
def test_full_car_drive_acceptance(tmp_path):
    """examples/car.toml (32 min, four 60 s outages), seed 1: the mounting
    estimated within 0.2 deg (3.998, 2.012 deg), the horizontal RMS error
    within 20 % of the perfectly mounted run (0.820 m against 0.906 m; the
    perfect run with the states on: 0.812 m), and the warning without (the
    run off: 16.2 m)."""
    sc = load_scenario(ROOT / "examples" / "car.toml")
    win = [[300.0, 360.0], [700.0, 760.0], [1100.0, 1160.0], [1500.0, 1560.0]]
    r = {label: run(sc, mount, on, tmp_path / label, win)
         for label, mount, on in (("perfect", (0.0, 0.0, 0.0), False), ("perfect_on", (0.0, 0.0, 0.0), True),
                                  ("on", MOUNT, True), ("off", MOUNT, False))}
    rpy = r["on"][0]["mounting_rpy_deg"]
    assert abs(rpy[1] - MOUNT[1]) < 0.2 and abs(rpy[2] - MOUNT[2]) < 0.2, rpy
    assert abs(r["on"][1] / r["perfect"][1] - 1.0) <= 0.2, (r["on"][1], r["perfect"][1])
    assert abs(r["on"][1] / r["perfect_on"][1] - 1.0) <= 0.2, (r["on"][1], r["perfect_on"][1])
    assert mounting_warnings(r["off"][0]) and not mounting_warnings(r["perfect"][0])
    pr = r["perfect_on"][0]["mounting_rpy_deg"]
    assert abs(pr[1]) < 0.2 and abs(pr[2]) < 0.2


@pytest.mark.slow
def test_drive_0708_with_its_mount_pitch_3_8_deg_off():
    """The real drive with [imu] mount_rpy_deg pitch -2.99 deg instead of
    -6.79: with the mounting states the corrected mount comes back within
    0.2 deg of the configured one (-6.875 deg) and the forward outage-end
    RMS within 20 % of the run with the right mount (2.85 m against
    2.77 m); without them the run is lost and the warning names the
    pitch."""
    wrong = [180.0, -2.99, 185.35]
    out = {}
    for on in (True, False):
        cfg = load_config(ROOT / "examples" / "drive_0708.toml",
                          {"output": {"plots": False}, "imu": {"mount_rpy_deg": wrong},
                           "constraints": {"mounting": on}})
        out[on] = summary(navigate(cfg))
    m1 = out[True]["mount_rpy_deg_corrected"]
    assert abs(m1[1] - (-6.79)) < 0.2, m1
    assert out[True]["forward"]["outage_end_horizontal_rms_m"] <= 1.2 * 2.77
    assert out[True]["health"]["verdict"] == "healthy"
    w = mounting_warnings(out[False])
    assert w and re.search(r"pitch \+[1-5]\.\d+ deg", w[0]), out[False]["health"]["warnings"]


def run_axes(sc, mount, out_dir, vehicle_axes="find", seed=1):
    """Simulate ``sc`` with its IMU at ``mount`` and navigate it knowing
    nothing of the mount (the lever arm in the vehicle's axes, as a user
    measures it), mounting states on.  Returns (summary, horizontal RMS
    error against the truth [m])."""
    sc = sc.model_copy(update={"imu": sc.imu.model_copy(update={"mount_rpy_deg": tuple(mount)})})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        write_simulation(simulate(sc, seed=seed), out_dir, plot=False, overwrite=True)
    cfg = {k: (dict(v) if isinstance(v, dict) else v) for k, v in BLOCKAGE_NAVIGATE.items()}
    cfg["init"] = {**cfg["init"], "vehicle_axes": vehicle_axes}
    cfg.update(name=sc.name, constraints={"mounting": True},
               outages={"protocol": "windows", "windows_s": [[150.0, 180.0]]})
    res = navigate(config_from_dict(cfg, base_dir=out_dir, source=str(out_dir)))
    err = analysis.nav_error(res.forward.nav, io.read_solution(out_dir / "truth.csv"))
    return summary(res), float(np.sqrt(np.mean(err.pos_ned[:, 0] ** 2 + err.pos_ned[:, 1] ** 2)))


@pytest.mark.parametrize("mount", [(0.0, 0.0, 180.0), (0.0, 0.0, 90.0), (180.0, -6.8, 185.35)])
def test_an_imu_mounted_sideways_backwards_or_upside_down_is_found_and_rotated(mount, tmp_path):
    # before the check the heading from the track started 90 or 180 deg off: 1.4 km to 7.6 km of error,
    # 72-75 % of the fixes rejected, and no word of the mounting in the verdict
    sc = Scenario.model_validate(SHORT)
    s0, e0 = run_axes(sc, (0.0, 0.0, 0.0), tmp_path / "square")
    s, e = run_axes(sc, mount, tmp_path / "mounted")
    ax = s["startup"]["vehicle_axes"]
    assert ax["rotated"] and ax["upside_down"] == (abs(mount[0]) > 90)
    assert s["health"]["verdict"] == "healthy", s["health"]
    assert any(w.startswith("vehicle axes:") for w in s["health"]["warnings"])
    # the suggested mount is the true one but for the tilt the mounting states keep (pitch here)
    C = dcm_from_euler(np.radians(ax["mount_rpy_deg_suggested"])).T @ dcm_from_euler(np.radians(
        [mount[0], 0.0, mount[2]]))
    assert np.degrees(np.linalg.norm(rotvec_from_dcm(C))) < 1.0
    assert e < 1.2 * e0 + 0.05, (e, e0)  # as good as the square mount within 20 % (0.26-0.30 m measured)
    assert s0["startup"]["vehicle_axes"]["differ"] is False


def test_vehicle_axes_given_makes_a_mismatch_unhealthy_and_names_the_mount(tmp_path):
    s, _ = run_axes(Scenario.model_validate(SHORT), (0.0, 0.0, 90.0), tmp_path / "given", vehicle_axes="given")
    assert s["health"]["verdict"] == "unhealthy"
    msg = [r for r in s["health"]["reasons"] if r.startswith("vehicle axes:")]
    assert msg and "mount_rpy_deg = [" in msg[0] and "90.00]" in msg[0], s["health"]["reasons"]


def test_drive_0708_read_without_its_mount_is_found_upside_down_and_backwards():
    """docs/guide.md's figure: the bundled drive with [imu] mount_rpy_deg = 0.
    With its time tags smoothed ([imu] time_smoothing_samples = 11) the
    direction of travel is found 174.6 +- 0.6 deg off the x axis, the
    source's mount yaw (185.35 deg) within 0.2 deg; with the tags as logged
    it was 177.1 +- 1.2 deg, and taken as the right angle it lay within 3
    standard errors of ([180, 0, 179.79])."""
    cfg = load_config(ROOT / "examples" / "drive_0708.toml",
                      {"output": {"plots": False}, "imu": {"mount_rpy_deg": [0.0, 0.0, 0.0]}})
    s = summary(navigate(cfg))
    ax = s["startup"]["vehicle_axes"]
    assert ax["rotated"] and ax["upside_down"]
    assert ax["rotation_yaw_deg"] == pytest.approx(174.6, abs=0.1) and ax["travel_yaw_se_deg"] < 1.0
    assert ax["mount_rpy_deg_suggested"][:2] == pytest.approx([180.0, 0.0], abs=0.01)
    assert ax["mount_rpy_deg_suggested"][2] % 360.0 == pytest.approx(185.35, abs=0.2)
    assert s["health"]["verdict"] == "healthy"
    assert s["forward"]["outage_end_horizontal_rms_m"] == pytest.approx(2.02, abs=0.01)
