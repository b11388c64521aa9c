"""The fixes' noise shape, north, east, down: measured in every run
(``gnss_axes``), warned about when wrong, and calibrated
(``[gnss] sigma_scale_search = "calibrate"``, ``--calibrate-gnss-axes``).

A receiver's formal sigmas are often alike on every axis while its vertical
is the worse (RTKLIB's 0.99 cm on every axis of drive_0708, whose vertical
innovations are 1.5 times the horizontal for their sigmas).  A simulated
car whose fixes have 0.5 m of white noise horizontally and 1 m vertically,
written with a sigma of 0.5 m on every axis: the vertical is twice what
the file says, and the run must see it, say it, and the calibration must
find the factor 2 between the vertical and horizontal scales."""

import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from inskit.errors import InputError
from inskit.jobs.config import config_from_dict
from inskit.jobs.navigate import GNSS_AXES_WARN_RATIO, calibrate_gnss_axes, calibrated_config, navigate, summary
from inskit.jobs.reproduce_tight import BLOCKAGE_NAVIGATE
from inskit.jobs.simulate import write_simulation
from inskit.simulation.scenario import simulate
from scenarios import short_car, write_drive

ROOT = Path(__file__).resolve().parents[1]

CAR = short_car("axes car", [{"type": "static", "duration_s": 30.0},
                             {"type": "accelerate", "speed_m_s": 15.0, "duration_s": 8.0},
                             {"type": "turn", "angle_deg": 90.0, "radius_m": 40.0},
                             {"type": "cruise", "duration_s": 60.0},
                             {"type": "turn", "angle_deg": -180.0, "radius_m": 40.0},
                             {"type": "cruise", "duration_s": 60.0},
                             {"type": "turn", "angle_deg": 90.0, "radius_m": 40.0},
                             {"type": "cruise", "duration_s": 60.0}])
# the simulated fixes' white noise [m]: short_car's, 0.5 m horizontal and 1 m vertical
H_M, V_M = 0.5, 1.0


@pytest.fixture(scope="module")
def drive(tmp_path_factory):
    d = write_drive(tmp_path_factory.mktemp("axes"), CAR, seed=3)
    g = pd.read_csv(d / "gnss.csv")
    assert np.allclose(g[["sigma_n_m", "sigma_e_m", "sigma_d_m"]], [H_M, H_M, V_M])  # the premise
    g["sigma_d_m"] = H_M  # the file now says the vertical is as good as the horizontal
    g.to_csv(d / "gnss_flat.csv", index=False)
    return d


def config(d, gnss_file="gnss_flat.csv", **gnss):
    cfg = {k: (dict(v) if isinstance(v, dict) else v) for k, v in BLOCKAGE_NAVIGATE.items()}
    cfg.update(name="axes car", outages={"protocol": "none"})
    cfg["gnss"] = {**cfg["gnss"], "file": gnss_file, **gnss}
    return config_from_dict(cfg, base_dir=d, source=str(d))


def test_a_run_measures_each_axis_and_warns_of_a_vertical_noisier_than_its_sigmas(drive):
    s = summary(navigate(config(drive)))
    ax = s["gnss_axes"]
    assert ax["updates"] > 150 and ax["sigma_scale_ned"] == [1.0, 1.0, 1.0]
    assert ax["vertical_to_horizontal"] > GNSS_AXES_WARN_RATIO, ax
    warn = [w for w in s["health"]["warnings"] if w.startswith("GNSS: the fixes' vertical innovations")]
    assert len(warn) == 1 and "--calibrate-gnss-axes" in warn[0] and "sigma_scale_ned" in warn[0], warn


def test_the_right_sigmas_give_agreeing_axes_and_no_warning(drive):
    s = summary(navigate(config(drive, "gnss.csv")))
    r = s["gnss_axes"]["vertical_to_horizontal"]
    assert 1 / GNSS_AXES_WARN_RATIO < r < GNSS_AXES_WARN_RATIO, s["gnss_axes"]
    assert not [w for w in s["health"]["warnings"] if "innovations are" in w]


def test_the_calibration_finds_the_vertical_twice_the_horizontal(drive):
    """The scales' vertical-to-horizontal ratio is the truth's V_M / H_M = 2
    within 10 % (the filter's own share of each innovation, and 300 fixes'
    sampling, keep it from being exact); the runs converge within the 5 %
    tolerance, and the calibrated config's run no longer warns."""
    cfg = config(drive, sigma_scale_search="calibrate")
    log = []
    cal, extra = calibrated_config(cfg, log=log.append)
    scale = np.array(cal.gnss.sigma_scale_ned)
    runs = extra["gnss_axes_calibration"]["runs"]
    assert scale[0] == scale[1] and abs(scale[2] / scale[0] / (V_M / H_M) - 1) < 0.10, (scale, runs)
    assert abs(runs[-1]["vertical_to_horizontal"] - 1) <= 0.05 and len(runs) >= 2, runs
    assert runs[0]["sigma_scale_ned"] == [1.0, 1.0, 1.0] and list(scale) == extra["gnss_axes_calibration"][
        "sigma_scale_ned"]
    assert any("calibrate: [gnss] sigma_scale_ned" in m for m in log)
    s = summary(navigate(cal))
    assert not [w for w in s["health"]["warnings"] if "innovations are" in w]
    assert s["gnss_axes"]["sigma_scale_ned"] == list(scale)


def test_the_calibration_never_reads_the_withheld_fixes(drive):
    """The fixes withheld by the outage windows are not updates, so they
    cannot enter: the measured updates are those of a run with the windows."""
    cfg = config(drive)
    cfg_w = config_from_dict({**cfg.model_dump(mode="json", exclude_none=True),
                              "outages": {"protocol": "windows", "windows_s": [[60.0, 80.0], [150.0, 170.0]]}},
                             base_dir=drive, source=str(drive))
    _, runs = calibrate_gnss_axes(cfg_w, max_runs=1, tol=10.0)
    n_all = summary(navigate(cfg))["gnss_axes"]["updates"]
    assert runs[0]["updates"] < n_all - 30, (runs[0]["updates"], n_all)


def test_a_calibration_that_does_not_converge_says_so(drive):
    with pytest.raises(InputError, match="still differ by .* after 1 runs.*sigma_scale_ned by hand"):
        calibrate_gnss_axes(config(drive), max_runs=1)


def test_scales_must_be_positive_and_need_loose_coupling(drive):
    with pytest.raises(Exception, match="sigma_scale_ned"):
        config(drive, sigma_scale_ned=[1.0, 0.0, 1.0])
    with pytest.raises(Exception, match="sigma_scale_ned"):
        config(drive, sigma_scale_ned=[1.0, 1.0, float("nan")])
    with pytest.raises(Exception, match="sigma_scale_ned would be ignored: it describes fixes fused by loose"):
        config(drive, coupling="tight", obs="a.obs", nav="a.nav", sigma_scale_ned=[1.0, 1.0, 2.0])
    cfg = {k: (dict(v) if isinstance(v, dict) else v) for k, v in BLOCKAGE_NAVIGATE.items()}
    cfg.update(filter={"scheme": "uncoupled"}, constraints={"zupt": False, "nhc": False},
               gnss={"file": "gnss.csv", "sigma_scale_search": "calibrate"})
    with pytest.raises(Exception, match="sigma_scale_search would be ignored: the uncoupled scheme"):
        config_from_dict(cfg, base_dir=drive, source=str(drive))


def test_the_calibration_takes_fixes_solved_from_rinex(tmp_path):
    """Loose coupling on our own single-point fixes (``obs`` and ``nav``, no
    ``file``): the calibration read the inputs without the RINEX files and
    stopped with 'no GNSS fixes: give gnss.file, or gnss.obs and gnss.nav',
    both given.  It now solves them as the run does."""
    from inskit.simulation.scenario import load_scenario

    sc = load_scenario(ROOT / "examples" / "tc_blockage.toml").model_copy(update={"duration_limit_s": 140.0})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        write_simulation(simulate(sc, 1), tmp_path, overwrite=True, plot=False)
        cfg = config(tmp_path, gnss_file=None, obs="obs.rnx", nav="nav.rnx", systems=["G"])
        assert cfg.gnss.file is None  # the premise: the fixes are our single-point solution
        _, runs = calibrate_gnss_axes(cfg, max_runs=1, tol=10.0)
    assert runs[0]["updates"] > 100, runs


def test_the_calibration_measures_the_run_without_a_default_constraint_that_fails(tmp_path):
    """A ship (heave 1 m at 8 s) whose fixes' sigmas have the right shape
    (0.94 vertical to horizontal): the run drops the default non-holonomic
    constraint that does not hold (:func:`inskit.jobs.navigate.run`), but
    the calibration measured the filter still holding it, lost every 18 s
    (0.70), and shaped the sigmas to [1.10, 1.10, 0.77], which the run then
    warned of (1.34).  It now measures the run the config will make."""
    from inskit.jobs.navigate import run
    from inskit.simulation.scenario import load_scenario

    sc = load_scenario(ROOT / "examples" / "ship.toml").model_copy(update={"duration_limit_s": 300.0})
    write_simulation(simulate(sc, seed=0), tmp_path, plot=False)
    cfg = config_from_dict({"imu": {"file": "imu.csv"}, "gnss": {"file": "gnss.csv", "lever_arm_b_m": [-20.0, 0.0, -15.0],
                                                                 "sigma_scale_search": "calibrate"},
                            "output": {"plots": False}}, base_dir=tmp_path, source="ship")
    cal, extra = calibrated_config(cfg)
    r = extra["gnss_axes_calibration"]["runs"][0]["vertical_to_horizontal"]
    assert 1 / GNSS_AXES_WARN_RATIO < r < GNSS_AXES_WARN_RATIO, extra
    res = run(cal)
    s = summary(res)
    assert s["constraint_check"]["nhc"] == "dropped"  # the premise: the run drops it
    assert not [w for w in s["health"]["warnings"] if "innovations are" in w], s["gnss_axes"]


def test_a_calibration_on_too_few_fixes_is_refused(drive):
    """All but the first 12 s of fixes withheld: the calibration shaped the
    sigmas from the 5 fixes past the first 5 s, to a vertical 6.9 times the
    horizontal (the truth: 2), and took it; fixes whose updates all lie
    within 5 s of a break were 'none made'.  Fewer than 30 are refused,
    saying how many there were and why."""
    cfg = config(drive)
    few = config_from_dict({**cfg.model_dump(mode="json", exclude_none=True),
                            "outages": {"protocol": "windows", "windows_s": [[12.0, 235.0]]}},
                           base_dir=drive, source=str(drive))
    with pytest.raises(InputError, match=r"of the \d+ GNSS position updates the filter used, [0-9] are more than 5 s "
                                         r"after the first and after each break in them .* fewer than the 30"):
        calibrate_gnss_axes(few)
    gaps = config_from_dict({**cfg.model_dump(mode="json", exclude_none=True),
                             "outages": {"protocol": "windows",
                                         "windows_s": [[a, a + 3.0] for a in np.arange(4.0, 235.0, 6.0)]}},
                            base_dir=drive, source=str(drive))
    with pytest.raises(InputError, match=r"of the \d{2,} GNSS position updates the filter used, 0 are more than"):
        calibrate_gnss_axes(gaps)


def test_a_calibration_on_a_lost_filter_is_refused(drive):
    """IMU time tags taken 0.5 s late: the filter loses the fixes for
    stretches of refusals, and those it still accepts lie near its wrong
    track; their innovations are no measure of the fixes' noise, and the
    calibration says so instead of shaping the noise to them."""
    cfg = config(drive)
    late = cfg.model_copy(update={"imu": cfg.imu.model_copy(update={"time_offset_s": 0.5,
                                                                    "time_offset_search": "off"})})
    lost = summary(navigate(late))["health"]["measurements"]["gnss_pos"]["lost_stretches"]
    assert lost, "the premise: the late tags lose the filter"
    with pytest.raises(InputError, match=r"the filter lost the fixes over \d+ stretch\(es\) .*Mend the run first"):
        calibrate_gnss_axes(late)


def test_the_calibration_halves_its_step_once_it_overshoots(drive, monkeypatch):
    """Scripted measurements (vertical over horizontal 2.0, then 0.8, then
    0.99): the first step is the full :func:`axis_scale_step`; after the
    ratio crosses 1 each step is its square root (half in log scale), which
    keeps an oscillating fixed point from running the 5 runs out."""
    import inskit.jobs.navigate as N
    from inskit.analysis.consistency import axis_scale_step

    ratios = iter([2.0, 0.8, 0.99])
    seen = []

    class Run:
        forward = None

    def fake_axes(fw):
        r = next(ratios)
        rms = [0.5, 0.5, 0.5 * r]
        return {"normalized_innovation_rms_ned": rms, "horizontal": 0.5, "vertical": 0.5 * r,
                "vertical_to_horizontal": r, "updates": 100}

    monkeypatch.setattr(N, "run", lambda c, inputs=None: (seen.append(c.gnss.sigma_scale_ned), Run())[1])
    monkeypatch.setattr(N, "health", lambda fw: {"measurements": {}})
    monkeypatch.setattr(N, "gnss_axes", fake_axes)
    scale, runs = N.calibrate_gnss_axes(config(drive), inputs=("imu", "gnss", None))
    s1 = axis_scale_step([0.5, 0.5, 1.0])
    s2 = s1 * np.sqrt(axis_scale_step([0.5, 0.5, 0.4]))
    assert np.allclose(seen[1], s1) and np.allclose(seen[2], s2) and np.allclose(scale, s2), seen
    assert [r["vertical_to_horizontal"] for r in runs] == [2.0, 0.8, 0.99]


def test_a_calibration_with_no_horizontal_innovation_says_so(drive, monkeypatch):
    """Every horizontal innovation exactly 0 (fixes copied from the INS):
    the ratio is undefined, and the calibration says so rather than ending
    in a TypeError."""
    import inskit.jobs.navigate as N

    class Run:
        forward = None

    monkeypatch.setattr(N, "run", lambda c, inputs=None: Run())
    monkeypatch.setattr(N, "health", lambda fw: {"measurements": {}})
    monkeypatch.setattr(N, "gnss_axes", lambda fw: {"normalized_innovation_rms_ned": [0.0, 0.0, 0.5],
                                                    "horizontal": 0.0, "vertical": 0.5,
                                                    "vertical_to_horizontal": None, "updates": 100})
    with pytest.raises(InputError, match="horizontal innovations are all zero"):
        N.calibrate_gnss_axes(config(drive), inputs=("imu", "gnss", None))
