"""Filter consistency on seeded Monte Carlo runs (issue 4 acceptance):
average NEES of position, velocity and attitude inside the 95 % chi-square
band, sensor-bias errors inside 3 sigma, for tactical and MEMS grades."""

from pathlib import Path

import numpy as np
import pytest

from inskit.integration import InitialUncertainty
from inskit.jobs.montecarlo import compare_schemes, consistency_errors, matched_settings, monte_carlo
from inskit.simulation.gnss import GnssErrors
from inskit.simulation.scenario import build_trajectory, load_scenario
from inskit.simulation.segments import SegmentTrajectory
from inskit.simulation.sensors import preset

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def drive():
    """3.5 min: static start, accelerations, turns both ways, a climb."""
    tr = SegmentTrajectory((np.radians(45), np.radians(7), 300.0), yaw0=0.3)
    tr.static(30).accelerate(15, 10).cruise(20).turn(np.radians(90), rate=np.radians(9)).accelerate(8, 5)
    tr.turn(np.radians(-135), rate=np.radians(12)).climb(np.radians(3), 20).accelerate(20, 8)
    tr.turn(np.radians(60), rate=np.radians(6)).cruise(30).turn(np.radians(-90), rate=np.radians(9)).cruise(40)
    return tr


GNSS = GnssErrors(rate_hz=1.0, white_h_m=1.0, white_v_m=2.0, velocity_sigma_m_s=0.0)
INIT = {
    "tactical": InitialUncertainty(pos_m=(1.0, 1.0, 2.0), vel_m_s=0.1, roll_pitch_rad=np.radians(0.2),
                                   yaw_rad=np.radians(1.0)),
    "industrial-mems": InitialUncertainty(pos_m=(1.0, 1.0, 2.0), vel_m_s=0.1, roll_pitch_rad=np.radians(1.0),
                                          yaw_rad=np.radians(3.0)),
}


def check(res):
    for block in ("pos", "vel", "att"):
        lo, hi = res["band"][block]
        anees = res["anees"][block]
        assert lo <= anees.mean() <= hi, (block, anees.mean(), (lo, hi))
        # and at most epochs, not only on average
        assert ((anees >= lo) & (anees <= hi)).mean() > 0.6, block
    z = res["bias_normalized"]
    assert (np.abs(z) < 3).mean() >= 0.97
    assert 0.6 < np.sqrt(np.mean(z**2)) < 1.3


@pytest.mark.parametrize("grade", ["tactical", "industrial-mems"])
def test_nees_consistency_50_runs(grade):
    res = monte_carlo(drive(), 100.0, consistency_errors(preset(grade)), GNSS, INIT[grade], runs=50, seed=0,
                      gate_probability=None)
    assert res["runs"] == 50
    check(res)


@pytest.mark.slow
@pytest.mark.parametrize("grade", ["tactical", "industrial-mems"])
def test_nees_consistency_car_scenario(grade):
    sc = load_scenario(EXAMPLES / "car.toml")
    tr = build_trajectory(sc, np.random.default_rng(0))
    res = monte_carlo(tr, 100.0, consistency_errors(preset(grade)), GNSS, INIT[grade], runs=50, seed=0,
                      duration=600.0, gate_probability=None)
    check(res)


def test_closed_loop_beats_open_loop_and_uncoupled_through_an_outage():
    sc = load_scenario(EXAMPLES / "car.toml")
    rows = {r["scheme"]: r for r in compare_schemes(sc, (1200.0, 1260.0), seed=1)}
    c, o, u = rows["closed"], rows["open"], rows["uncoupled"]
    # source 004: the closed loop keeps its corrections through an outage
    assert c["outage_end_horizontal_m"] < 20.0
    assert c["outage_end_horizontal_m"] < 0.1 * o["outage_end_horizontal_m"]
    assert o["outage_end_horizontal_m"] < u["outage_end_horizontal_m"]
    assert c["gnss_on_horizontal_rms_m"] < 1.0


def test_time_offset_state_estimates_gnss_latency():
    """GNSS fixes stamped 0.2 s late (latency): the state converges to -0.2 s."""
    from inskit.integration import GnssPosition, run_filter
    from inskit.jobs.montecarlo import matched_settings, perturbed_start
    from inskit.simulation import ideal_imu, truth_solution
    from inskit.simulation.gnss import simulate_gnss
    from inskit.simulation.sensors import apply_imu_errors

    tr = drive()
    t = np.arange(0.0, tr.duration, 0.01)
    rng = np.random.default_rng(11)
    errs = consistency_errors(preset("tactical"))
    imu, _ = apply_imu_errors(ideal_imu(tr, t, nodes=3), errs, rng)
    g = GnssErrors(rate_hz=5.0, white_h_m=0.02, white_v_m=0.04, velocity_sigma_m_s=0.0, latency_s=0.2)
    gnss, _ = simulate_gnss(tr, t[0], t[-1], g, rng)
    from dataclasses import replace

    settings = matched_settings(errs, replace(INIT["tactical"], time_offset_s=0.3), gate_probability=None,
                                time_offset=True)
    start = perturbed_start(truth_solution(tr, t[:1]).state(0), matched_settings(errs, INIT["tactical"]), rng)
    out = run_filter(imu, start, [GnssPosition(gnss)], settings)
    assert out.estimate("time_offset")[-1, 0] == pytest.approx(-0.2, abs=0.01)
    assert out.solution.extra["time_offset_s"][-1] == out.estimate("time_offset")[-1, 0]  # the named column


def test_run_once_is_picklable_and_any_map_gives_the_same_figures():
    """run_once(spec, seed) -> a small result; a process pool's map gives the
    builtin map's numbers bit for bit, whatever the order of completion."""
    import pickle
    from concurrent.futures import ProcessPoolExecutor

    from inskit.jobs.montecarlo import ConsistencySpec, reduce_runs, run_once

    tr = SegmentTrajectory((np.radians(45), np.radians(7), 300.0), yaw0=0.3)
    tr.static(5).accelerate(10, 5).turn(np.radians(90), rate=np.radians(9)).cruise(10)
    settings = matched_settings(consistency_errors(preset("tactical")), INIT["tactical"], gate_probability=None,
                                smoother_node_s=0.0)
    spec = ConsistencySpec(tr, 100.0, consistency_errors(preset("tactical")), GNSS, settings)
    one = run_once(spec, 3)
    spec.prepared()  # the ideal IMU and truth (MBs) stay behind: the pickled spec is small
    assert len(pickle.dumps(one)) < 20_000 and len(pickle.dumps(spec)) < 500_000
    serial = [run_once(spec, s) for s in range(4)]
    with ProcessPoolExecutor(2) as ex:
        parallel = list(ex.map(run_once, [spec] * 4, range(4)))
    a, b = reduce_runs(serial), reduce_runs(parallel[::-1])
    for blk in ("pos", "vel", "att"):
        assert np.array_equal(a["anees"][blk], b["anees"][blk])
    assert np.array_equal(a["bias_normalized"], b["bias_normalized"])


@pytest.mark.parametrize("outage", [(1.0, 1e6), (-5.0, 10.0)])
def test_an_outage_beyond_the_scenario_is_refused(outage):
    """`inskit schemes --outage 100,130` on a 52 s scenario was 'internal error: IndexError', exit 3."""
    from inskit.errors import InputError

    sc = load_scenario(EXAMPLES / "static.toml")
    with pytest.raises(InputError, match=r"--outage .*: the outage must lie within the scenario .*, 0\.\."):
        compare_schemes(sc, outage)


def test_an_early_outage_still_has_gnss_on_figures_or_says_there_are_none():
    """`inskit schemes --outage 20,30` gave NaN for the GNSS-on RMS (the window was 60 s to the
    outage start). GNSS on is now the time after 60 s outside the outage and its 60 s of
    re-convergence; where the scenario leaves none the figure is None, shown as n/a."""
    from inskit.simulation.scenario import build_trajectory

    sc = load_scenario(EXAMPLES / "static.toml")
    end = build_trajectory(sc, np.random.default_rng(0)).duration
    rows = compare_schemes(sc, (20.0, 30.0), seed=1, schemes=("closed",))
    assert np.isfinite(rows[0]["gnss_on_horizontal_rms_m"]) and rows[0]["gnss_on_horizontal_rms_m"] < 2.0
    rows = compare_schemes(sc, (20.0, end - 30.0), seed=1, schemes=("closed",))
    assert rows[0]["gnss_on_horizontal_rms_m"] is None
    assert np.isfinite(rows[0]["outage_end_horizontal_m"])


def test_schemes_on_an_ideal_imu_run():
    """static.toml with `grade = "ideal"` (the scenario's default grade): `inskit schemes` printed 'initial
    uncertainty gyro_bias must be > 0, got 0.0' (the matched filter's initial bias sigma is the sensor's,
    zero for an ideal IMU); it is floored as the filter's noise is, and every scheme runs."""
    sc = load_scenario(EXAMPLES / "static.toml")
    sc = sc.model_copy(update={"imu": sc.imu.model_copy(update={"grade": "ideal"})})
    rows = compare_schemes(sc, (20.0, 30.0), seed=1)
    assert [r["scheme"] for r in rows] == ["uncoupled", "open", "closed"]
    assert all(np.isfinite(r["outage_end_horizontal_m"]) for r in rows)


def test_the_gnss_on_figure_leaves_out_the_scenarios_own_outages_too():
    """tc_blockage has 120 s blockages of its own: they were counted as GNSS on (closed loop 49.6 m,
    uncoupled 766 m)."""
    sc = load_scenario(EXAMPLES / "tc_blockage.toml")
    rows = {r["scheme"]: r for r in compare_schemes(sc, (60.0, 100.0), seed=0)}
    assert rows["closed"]["gnss_on_horizontal_rms_m"] < 2.0 and rows["uncoupled"]["gnss_on_horizontal_rms_m"] < 3.0


@pytest.mark.parametrize("duration", [0.05, 1.0, 1.99])
def test_a_consistency_run_too_short_for_a_gnss_update_is_refused_stating_the_minimum(duration):
    """`inskit consistency car.toml --duration 0.05` was 'internal error: IndexError' (no update node: an
    empty float index); 1 s gave the same (the fix at the start is the initial epoch)."""
    from inskit.errors import InputError
    from inskit.jobs.montecarlo import consistency_study, min_consistency_duration_s

    assert min_consistency_duration_s() == 2.0
    sc = load_scenario(EXAMPLES / "car.toml")
    with pytest.raises(InputError, match=rf"^--duration must be at least 2 s, got {duration} \(a GNSS update at 1 "
                                         r"Hz after the start: the NEES is taken at the updates\)$"):
        consistency_study(sc, "tactical", 2, duration)
    res = consistency_study(sc, "tactical", 2, 2.0)  # the minimum runs
    assert res["duration_s"] == 1.0 and np.isfinite(res["anees"]["pos"]["mean"])  # its one update


def test_a_run_without_an_update_is_an_input_error_not_an_index_error():
    from inskit.errors import InputError
    from inskit.jobs.montecarlo import ConsistencySpec, run_once

    sc = load_scenario(EXAMPLES / "car.toml")
    tr = build_trajectory(sc, np.random.default_rng(0))
    errors = consistency_errors(preset("tactical"))
    init = InitialUncertainty(pos_m=(1.0, 1.0, 2.0), vel_m_s=0.1, roll_pitch_rad=0.01, yaw_rad=0.02)
    spec = ConsistencySpec(tr, 100.0, errors, GnssErrors(velocity_sigma_m_s=0.0),
                           matched_settings(errors, init, smoother_node_s=0.0), duration=0.5)
    with pytest.raises(InputError, match=r"holds no GNSS update after its start .*it needs at least 2 s"):
        run_once(spec, 0)


def test_a_consistency_run_of_too_many_imu_samples_is_refused_naming_the_duration():
    from inskit.errors import InputError
    from inskit.jobs.montecarlo import consistency_study

    sc = load_scenario(EXAMPLES / "car.toml")
    fast = sc.model_copy(update={"imu": sc.imu.model_copy(update={"rate_hz": 1e4})})
    with pytest.raises(InputError, match=r"^--duration 1842\.1 s at the scenario's \[imu\] rate_hz = 10000 Hz: "
                                         r"18,420,999 IMU samples per run, more than the 10,000,000 one simulation "
                                         r"holds; give a shorter --duration$"):
        consistency_study(fast, "tactical", 2)


@pytest.mark.parametrize("outage", [(20.2, 20.5), (20.0, 20.0 + 1e-9)])
def test_an_outage_between_two_fixes_withholds_nothing_and_is_refused(outage):
    """`inskit schemes --outage 100.2,100.5` (1 Hz fixes) withheld no fix and reported the GNSS-on error as
    the error 'at the outage end'; (20, 20 + 1e-9) holds the fix at 20 s and is an outage."""
    from inskit.errors import InputError

    sc = load_scenario(EXAMPLES / "static.toml")
    if outage[1] - outage[0] < 1e-6:
        assert compare_schemes(sc, outage, schemes=("closed",))[0]["outage_end_horizontal_m"] >= 0
        return
    with pytest.raises(InputError, match=r"--outage 20\.2,20\.5: holds no GNSS fix of the scenario 'static' \(fixes "
                                         r"at 1 Hz.*withholds nothing"):
        compare_schemes(sc, outage)


def test_an_outage_inside_the_scenarios_own_outage_withholds_nothing():
    """tc_blockage removes the fixes of 150-270 s itself: an --outage inside it withholds none."""
    from inskit.errors import InputError
    from inskit.simulation.gnss import fix_times
    from inskit.simulation.scenario import gnss_errors

    sc = load_scenario(EXAMPLES / "tc_blockage.toml")
    a, b = gnss_errors(sc).outages[0]
    t = fix_times(0.0, b + 10.0, gnss_errors(sc))
    assert t[0] == 0.0 and not np.any((t >= a) & (t <= b)) and np.any(t > b)
    with pytest.raises(InputError, match="holds no GNSS fix"):
        compare_schemes(sc, (a + 1.5, b - 1.5))


def _summary(mean, inside, above, within=0.99, rms=1.0):
    block = {"mean": mean, "band_95": [2.36, 3.72], "fraction_of_epochs_inside": inside,
             "fraction_of_epochs_above": above, "fraction_of_epochs_below": 1.0 - inside - above}
    return {"anees": {"pos": dict(block), "vel": dict(block), "att": dict(block)},
            "bias_within_3_sigma": within, "bias_rms_normalized": rms}


def test_the_consistency_verdict_follows_the_tests_criteria():
    from inskit.jobs.montecarlo import consistency_verdict

    assert consistency_verdict(_summary(3.0, 0.9, 0.05)) == {"verdict": "consistent", "reasons": []}
    v = consistency_verdict(_summary(4.5, 0.4, 0.55))  # NEES above the band: covariance too small
    assert v["verdict"] == "inconsistent" and len(v["reasons"]) == 3 and "optimistic" in v["reasons"][0]
    v = consistency_verdict(_summary(2.0, 0.3, 0.0))  # below the band: covariance too large
    assert "pessimistic" in v["reasons"][0]
    v = consistency_verdict(_summary(3.0, 0.9, 0.05, rms=0.4))
    assert v["verdict"] == "inconsistent" and v["reasons"] == [v["reasons"][0]] and "pessimistic" in v["reasons"][0]
    assert consistency_verdict(_summary(3.0, 0.9, 0.05, within=0.9))["verdict"] == "inconsistent"


def test_consistency_says_which_grades_the_filter_is_consistent_with():
    from inskit.jobs.montecarlo import consistency_study

    sc = load_scenario(EXAMPLES / "car.toml")
    ok = consistency_study(sc, "tactical", 10, duration=120.0, seed=0)
    assert ok["verdict"] == "consistent", ok["reasons"]
    # a consumer gyro's 1 deg/s turn-on bias with GNSS position alone: the heading error leaves the
    # small-angle error model within a minute and the filter diverges, optimistic
    bad = consistency_study(sc, "consumer-mems", 5, duration=120.0, seed=0)
    assert bad["verdict"] == "inconsistent"
    assert bad["anees"]["att"]["mean"] > 10 * bad["anees"]["att"]["band_95"][1]
    assert any(r.startswith("att:") and "optimistic" in r for r in bad["reasons"])


@pytest.mark.parametrize("outage", [(0.0, 10.0), (0.5, 10.0), (1.0, 10.0)])
def test_an_outage_before_any_fix_reaches_the_filters_is_refused(outage):
    """`inskit schemes car.toml --outage 0,1842` (and 0,60) printed the three schemes' outage-end errors,
    identical to the last digit (714635.54 m each), and exit 0: no fix had reached any filter (the one at
    the first epoch is the initial state's), so each coasted from the same start and nothing was compared."""
    from inskit.errors import InputError

    sc = load_scenario(EXAMPLES / "static.toml")
    with pytest.raises(InputError, match=rf"^--outage {outage[0]:g},10: no GNSS fix of the scenario 'static' "
                                         r"reaches the filters before it \(the first after the start is at 1 s; "
                                         r"fixes at 1 Hz.*comparing nothing; start the outage after a fix$"):
        compare_schemes(sc, outage)
    rows = {r["scheme"]: r for r in compare_schemes(sc, (1.5, 10.0), seed=1, schemes=("uncoupled", "closed"))}
    assert rows["uncoupled"]["outage_end_horizontal_m"] != rows["closed"]["outage_end_horizontal_m"]


@pytest.mark.parametrize("runs, match", [(1, r"^--runs must be at least 2, got 1$"),
                                         (1_000_001, r"^--runs must be at most 1,000,000, got 1,000,001 ")])
def test_consistency_runs_are_bounded_as_a_studys(runs, match):
    """`inskit consistency --runs 100000000` started a run of years under a progress bar; the bound is a study's."""
    from inskit.errors import InputError
    from inskit.jobs.montecarlo import consistency_study

    with pytest.raises(InputError, match=match):
        consistency_study(load_scenario(EXAMPLES / "car.toml"), "tactical", runs, 2.0)


def test_schemes_near_a_pole_are_refused_naming_the_scenario_not_an_option_it_lacks():
    """`inskit schemes` of a scenario at 89.95 deg said 'use the wander-azimuth or ECEF frame (--frame
    wander|ecef)', an option schemes has not (the uncoupled INS's words); at 90 deg 'degrees where radians are
    expected?'.  Now the job says where the scenario comes near the pole and why its schemes cannot run there."""
    from inskit.errors import InputError

    sc = load_scenario(EXAMPLES / "static.toml")
    for lat, shown in ((89.95, "89.9500"), (-90.0, "-90.0000")):
        near = sc.model_copy(update={"start": sc.start.model_copy(update={"lat_deg": lat})})
        which = "north" if lat > 0 else "south"
        with pytest.raises(InputError, match=rf"^scenario 'static' comes within 0\.1 deg of the {which} pole "
                                             rf"\(latitude {shown} deg at t = 0 s\), where the three schemes' NED "
                                             r"mechanization and filters are singular$"):
            compare_schemes(near, (20.0, 30.0))
