"""Cross-validated tuning: validation outages avoid the protocol's, and the
ranking reflects what the validation outages show."""

import json

import pytest

from inskit.errors import ConfigError
from inskit.jobs import tune as T


def test_validation_windows_keep_clear_of_the_protocol():
    protocol = [(40.0, 54.75), (85.0, 99.75)]
    val = T.validation_windows(protocol, 0.0, 140.0, hold_s=10.0, reaid_s=10.0, start_after_s=60.0)
    assert val == [(64.75, 74.75), (109.75, 119.75)]
    for a, b in val:
        for pa, pb in protocol:
            assert b + 10.0 <= pa + 1e-9 or a - 10.0 >= pb - 1e-9  # 10 s of aiding on each side
    assert T.validation_windows([], 0.0, 100.0, 10.0, 5.0, 0.0) == [(5.0, 15.0), (25.0, 35.0), (45.0, 55.0),
                                                                    (65.0, 75.0), (85.0, 95.0)]
    assert T.validation_windows([(0.0, 100.0)], 0.0, 100.0) == []


def test_grid_parsing_and_snippet():
    g = T.parse_grid(["noise.bias_tau_s=300,1e5", "constraints.nhc=true,false", "earth.gravity=j2"])
    assert g == {"noise.bias_tau_s": [300, 1e5], "constraints.nhc": [True, False], "earth.gravity": ["j2"]}
    assert len(T.candidates(g)) == 4
    snip = T.toml_snippet({"noise.bias_tau_s": 300, "constraints.nhc": False})
    assert snip == ("# and remove from the config those it sets of (they serve what is switched off): "
                    "constraints.mounting, constraints.mounting_rw_deg_sqrt_h, constraints.nhc_lever_arm_b_m, "
                    "constraints.nhc_sigma_m_s, constraints.sigma_mounting_deg\n"
                    "[noise]\nbias_tau_s = 300\n[constraints]\nnhc = false\n")
    assert T.toml_snippet({"constraints.nhc": True}) == "[constraints]\nnhc = true\n"
    g = T.parse_grid(["constraints.nhc_lever_arm_b_m=[0,0,0], [0.06, 0, 0.81]"])
    assert g == {"constraints.nhc_lever_arm_b_m": [(0, 0, 0), (0.06, 0, 0.81)]}
    assert T.toml_snippet({"constraints.nhc_lever_arm_b_m": (0.06, 0, 0.81)}) == \
        "[constraints]\nnhc_lever_arm_b_m = [0.06, 0, 0.81]\n"
    for bad in (["nosuch.key=1"], ["noise.bias_tau_s"], ["outages.protocol=none"], ["noise.x=1", "noise.x=2"], []):
        with pytest.raises(ConfigError):
            T.parse_grid(bad)


def _sim_drive(tmp_path):
    """A 240 s simulated car (examples/car.toml) and a navigate config withholding 100..110 s."""
    from inskit.simulation.scenario import load_scenario, simulate
    from inskit.jobs.simulate import write_simulation
    from pathlib import Path

    ex = Path(__file__).resolve().parents[1] / "examples"
    text = (ex / "car.toml").read_text().replace('name = "car"', 'name = "car"\nduration_limit_s = 240.0', 1)
    (tmp_path / "car.toml").write_text(text)
    write_simulation(simulate(load_scenario(tmp_path / "car.toml"), seed=2), tmp_path, overwrite=True, plot=False)
    (tmp_path / "nav.toml").write_text(
        'name = "t"\n[imu]\nfile = "imu.csv"\n[gnss]\nfile = "gnss.csv"\nlever_arm_b_m = [0.0, 0.0, -1.2]\n'
        '[noise]\ngyro_arw_deg_sqrt_h = 0.15\naccel_vrw_m_s_sqrt_h = 0.06\n'
        '[outages]\nprotocol = "windows"\nwindows_s = [[100.0, 110.0]]\n[output]\nplots = false\n')
    return tmp_path / "nav.toml"


def test_tune_ranks_a_wrecked_setting_last(tmp_path):
    """On a simulated drive, a gyro noise 300x too small (the filter then
    trusts a drifting attitude) must score worse on the validation outages
    than the matched setting, and the protocol's windows stay withheld."""
    res = T.tune(_sim_drive(tmp_path), T.parse_grid(["noise.gyro_bias_sigma_deg_h=10,0.01"]), hold_s=15.0,
                 reaid_s=10.0, start_after_s=70.0, workers=1)
    assert res["windows_protocol_s"] == [(100.0, 110.0)]
    assert all(b <= 100.0 - 10.0 + 1e-9 or a >= 110.0 + 10.0 - 1e-9 for a, b in res["windows_validation_s"])
    ranked = [c["params"]["noise.gyro_bias_sigma_deg_h"] for c in res["candidates"]]
    assert ranked == [10, 0.01], res["candidates"]
    assert res["best_toml"].startswith("[noise]\ngyro_bias_sigma_deg_h = 10\n")
    json.dumps(res, allow_nan=False)


def test_a_candidate_with_gnss_nis_out_of_band_is_ranked_after_the_consistent_ones(tmp_path):
    """Fixes declared 30 m noisy (the simulated ones are 0.5 m horizontal,
    1 m vertical) drive the fixes' mean NIS per degree of freedom far below
    a third: that candidate is flagged inconsistent and ranked after the
    matched one whatever its score; the matched one's NIS is in band (the
    filter's noise matches the simulation's)."""
    res = T.tune(_sim_drive(tmp_path), T.parse_grid(["gnss.sigma_floor_m=30,0"]), hold_s=15.0, reaid_s=10.0,
                 start_after_s=70.0, workers=1)
    by = {c["params"]["gnss.sigma_floor_m"]: c for c in res["candidates"]}
    assert by[30]["gnss_mean_nis_per_dof"]["gnss_pos"] < 0.05 and not by[30]["consistent"]
    assert T.NIS_BAND[0] < by[0]["gnss_mean_nis_per_dof"]["gnss_pos"] < T.NIS_BAND[1] and by[0]["consistent"]
    assert [c["params"]["gnss.sigma_floor_m"] for c in res["candidates"]] == [0, 30]
    assert res["best"] == {"gnss.sigma_floor_m": 0} and res["warnings"] == []
    assert "inconsistent" in T.table_text(res)
    one = T.tune(tmp_path / "nav.toml", T.parse_grid(["gnss.sigma_floor_m=30"]), hold_s=15.0, reaid_s=10.0,
                 start_after_s=70.0, workers=1)
    assert one["warnings"] and "GNSS innovations" in one["warnings"][0]


def test_default_spacing_mimics_the_protocol():
    from inskit.jobs.outages import rtklibexplorer_outages

    w = rtklibexplorer_outages(0.0)
    hold, reaid = T.default_spacing(w)
    assert hold == pytest.approx(14.75) and reaid == pytest.approx(7.75, abs=1e-5)
    val = T.validation_windows(w, 0.0, 540.0, hold, reaid)
    assert len(val) == 11 and all(b - a == pytest.approx(14.75) for a, b in val)
    assert T.default_spacing([]) == (10.0, 10.0)


def test_a_candidate_the_config_refuses_is_named_before_the_search(tmp_path):
    """A grid value the config model refuses is a ConfigError naming the
    candidate (not the config file halfway through the runs)."""
    from pathlib import Path

    ex = Path(__file__).resolve().parents[1] / "examples"
    for spec, msg in (("constraints.nhc_sigma_m_s=abc,0.1", r"--grid candidate .*nhc_sigma_m_s.*abc"),
                      ("noise.nosuch=1", r"--grid candidate \{'noise.nosuch': 1\}"),
                      ("noise.gyro_arw_deg_sqrt_h=0.1,1.0", r"from_static = true")):
        with pytest.raises(ConfigError, match=msg):
            T.tune(ex / "drive_0708.toml", T.parse_grid([spec]), workers=1)
    with pytest.raises(ConfigError, match="the value 0.0 repeats 0"):
        T.parse_grid(["gnss.sigma_floor_m=0,0.0"])


def test_shifted_placements_keep_clear_of_the_protocol_and_the_ends():
    """--shifts 3 on the drive's spacing (hold 14.75 s, reaid 7.75 s): the validation outages move by -2.75, 0 and
    +2.75 s, each keeping 5 s of aiding from the protocol's windows and the ends of the fixes."""
    protocol = [(40.0 + 45 * k, 54.75 + 45 * k) for k in range(3)]
    val = T.validation_windows(protocol, 0.0, 160.0, hold_s=14.75, reaid_s=7.75, start_after_s=60.0)
    assert val == [(62.5, 77.25), (107.5, 122.25)]
    placed = T.shifted_windows(val, protocol, 0.0, 160.0, 7.75, 3)
    assert [d for d, _ in placed] == [-2.75, 0.0, 2.75]
    assert placed[1][1] == val
    for d, w in placed:
        assert len(w) == 2
        for a, b in w:
            assert all(b + 5.0 <= pa + 1e-9 or a - 5.0 >= pb - 1e-9 for pa, pb in protocol)
    assert T.shifted_windows(val, protocol, 0.0, 160.0, 7.75, 1) == [(0.0, val)]
    # an outage that would come within 5 s of the last fix is left out of that placement
    late = T.shifted_windows([(140.0, 150.0)], [], 0.0, 156.0, 7.0, 3)
    assert [len(w) for _, w in late] == [1, 1, 0]


def test_no_room_for_a_validation_outage_names_start_after_too():
    """On a log shorter than --start-after (60 s by default) the message told to shorten --hold or --reaid
    only, which cannot help."""
    from pathlib import Path

    ex = Path(__file__).resolve().parents[1] / "examples"
    with pytest.raises(ConfigError, match=r"no room for a validation outage of 10 s .* after the first 1e\+06 s of "
                                          r"the .* s of fixes; shorten --hold, --reaid or --start-after"):
        T.tune(ex / "drive_0708.toml", T.parse_grid(["constraints.nhc_sigma_m_s=0.1,0.3"]), hold_s=10.0,
               start_after_s=1e6, workers=1)


def test_shifts_with_no_room_to_move_keep_the_one_placement():
    """walk_0827: re-aiding 4.999999 s (fitted between the protocol's outages) is under the 5 s a shifted
    placement keeps, so every one of the three placements came out empty and tune said 'every candidate
    failed; first error: None'. With no room to move there is one placement, the validation outages as placed."""
    protocol = [(30.0, 40.0), (60.0, 70.0), (90.0, 100.0)]
    val = [(74.999999, 84.999999), (104.999999, 114.999999)]
    assert T.shifted_windows(val, protocol, 0.0, 133.75, 4.999999, 3) == [(0.0, val)]


def test_a_config_without_outages_tunes_and_an_unjudged_candidate_is_not_called_consistent(tmp_path):
    """Review of the consistency rule: with [outages] protocol = "none" the consistency run asked for
    protocol "windows" with no windows, which the config refuses (every such tune failed); and the
    uncoupled scheme, which has no GNSS innovations, counted as consistent (all() of nothing) and was
    recommended at 3.5 km over a closed loop at 1.7 m."""
    nav = _sim_drive(tmp_path)
    nav.write_text(nav.read_text().replace('[outages]\nprotocol = "windows"\nwindows_s = [[100.0, 110.0]]\n',
                                           '[outages]\nprotocol = "none"\n'))
    res = T.tune(nav, T.parse_grid(["filter.scheme=uncoupled,closed"]), hold_s=15.0, reaid_s=10.0,
                 start_after_s=70.0, workers=1)
    by = {c["params"]["filter.scheme"]: c for c in res["candidates"]}
    assert res["windows_protocol_s"] == [] and by["closed"]["consistent"]
    assert by["uncoupled"]["gnss_mean_nis_per_dof"] == {} and by["uncoupled"]["consistent"] is False
    assert res["best"] == {"filter.scheme": "closed"}
    assert "no GNSS NIS" in T.table_text(res)


def test_placements_that_withhold_the_same_fixes_run_once():
    """--shifts 45 on drive_0708 (4 Hz fixes, placements 0.125 s apart) ran 45 placements of which 11 withheld
    the very fixes of another: the same runs, their outages scored twice (495 'outages' for 374)."""
    import numpy as np

    t = np.arange(0.0, 200.0, 1.0)  # 1 Hz fixes: placements 0.125 s apart withhold the same ones by eights
    val = [(62.5, 77.25), (107.5, 122.25)]
    placed = T.shifted_windows(val, [(40.0, 54.75), (85.0, 99.75)], 0.0, 200.0, 7.75, 45)
    kept = T.distinct_placements(placed, t)
    from inskit.jobs.outages import withheld_mask

    keys = [tuple(np.flatnonzero(withheld_mask(t, w))) for _, w in kept]
    assert len(set(keys)) == len(kept) < len(placed)
    assert {tuple(np.flatnonzero(withheld_mask(t, w))) for _, w in placed} == set(keys)  # nothing lost
    assert T.distinct_placements([(0.0, val)], t) == [(0.0, val)]


def test_validation_outages_without_a_fix_between_them_are_refused():
    """--hold 1 --reaid 0 placed 339 one-second validation outages back to back (no fix between): each 'outage
    end' was the middle of one long outage (cv RMS 44.8 m), scored without a word."""
    import numpy as np

    t = np.arange(0.0, 100.0, 0.25)
    with pytest.raises(ConfigError, match=r"--reaid 0: the outages 60-61 s and 61-62 s .* no GNSS fix between them "
                                          r"\(fixes every 0\.25 s\)"):
        T.check_separated([(60.0, 61.0), (61.0, 62.0)], [(60.0, 61.0), (61.0, 62.0)], t, 0.0)
    with pytest.raises(ConfigError, match="no GNSS fix between"):  # flush against a protocol window
        T.check_separated([(40.0, 50.0), (50.1, 60.0)], [(50.1, 60.0)], t, 0.1)
    T.check_separated([(40.0, 50.0), (50.3, 60.0)], [(50.3, 60.0)], t, 0.3)  # one fix at 50.25 s between: two
    T.check_separated([(40.0, 50.0), (50.0, 60.0)], [], t, 0.0)  # the config's own windows: not tune's to judge
    from pathlib import Path

    ex = Path(__file__).resolve().parents[1] / "examples"
    with pytest.raises(ConfigError, match="no GNSS fix between them"):
        T.tune(ex / "drive_0708.toml", T.parse_grid(["constraints.nhc_sigma_m_s=0.2"]), hold_s=1.0, reaid_s=0.0,
               workers=1)


def test_a_boolean_and_a_number_are_not_a_repeat():
    """`--grid constraints.mounting=true,1` said 'a value is repeated' (True == 1 in Python): the 1 is a
    number where a boolean is wanted, which the config names per candidate."""
    assert T.parse_grid(["constraints.mounting=true,1"]) == {"constraints.mounting": [True, 1]}
    assert T.parse_grid(["constraints.v=[1,0],[true,0]"])["constraints.v"] == [(1, 0), (True, 0)]
    with pytest.raises(ConfigError, match=r"the value \[0,0,0\.0\] repeats \[0,0,0\]"):
        T.parse_grid(["constraints.nhc_lever_arm_b_m=[0,0,0],[0,0,0.0]"])
    with pytest.raises(ConfigError, match="the value TRUE repeats true"):
        T.parse_grid(["constraints.mounting=true,TRUE"])


def test_a_candidate_that_turns_a_switch_off_drops_the_keys_that_serve_it():
    """drive_0708 sets nhc_sigma_m_s and nhc_lever_arm_b_m for its constraint: a config that sets them with
    nhc = false is refused (they would be ignored), so --grid constraints.nhc=true,false refused its 'false'
    candidate.  The candidate now resets those keys to their defaults (what turning the switch off means) and
    loads; a key the candidate sets itself is kept (and refused, as the user asked for both)."""
    from pathlib import Path

    from inskit.jobs.config import load_config

    ex = Path(__file__).resolve().parents[1] / "examples" / "drive_0708.toml"
    cfg = load_config(ex, T.overrides_of({"constraints.nhc": False, "filter.scale_factors": False}))
    assert not cfg.constraints.nhc and not cfg.filter.scale_factors and not cfg.constraints.mounting
    assert cfg.constraints.nhc_sigma_m_s == 0.1 and tuple(cfg.constraints.nhc_lever_arm_b_m) == (0.0, 0.0, 0.0)
    assert load_config(ex, T.overrides_of({"constraints.nhc": True})).constraints.nhc_sigma_m_s == 0.2
    with pytest.raises(ConfigError, match=r"field 'constraints\.nhc_sigma_m_s'"):
        load_config(ex, T.overrides_of({"constraints.nhc": False, "constraints.nhc_sigma_m_s": 0.3}))
    # an uncoupled candidate (no filter) drops what only a filter fuses or estimates: drive_0708's GNSS error
    # states, its NHC settings and mounting (refused with the scheme, and so the candidate was)
    cfg = load_config(ex, T.overrides_of({"filter.scheme": "uncoupled"}))
    assert cfg.filter.scheme == "uncoupled" and cfg.gnss.error_sigma_m is None and not cfg.constraints.mounting


def test_a_candidate_that_calibrates_runs_calibrated(tmp_path):
    """``gnss.sigma_scale_search = "calibrate"`` (or a config with it) was
    ignored: each run went straight to the filter, and the two candidates of
    ``--grid gnss.sigma_scale_search=off,calibrate`` scored alike to the last
    digit.  A candidate now calibrates in each of its runs, as navigate does
    (on the fixes that run uses): its consistency run is the calibrated
    config's.  The fixes are written with the vertical sigma of the
    horizontal (the simulated vertical noise is twice it), so that every
    run, the validation runs with their outages too, has a shape to
    calibrate (with the right sigmas a run with the validation outages
    withheld may agree within the calibration's 5 % at once)."""
    import pandas as pd

    from inskit.jobs.config import load_config
    from inskit.jobs.navigate import calibrated_config, navigate, summary

    nav = _sim_drive(tmp_path)
    g = pd.read_csv(tmp_path / "gnss.csv")
    g["sigma_d_m"] = g["sigma_n_m"]
    g.to_csv(tmp_path / "gnss.csv", index=False)
    res = T.tune(nav, T.parse_grid(["gnss.sigma_scale_search=off,calibrate"]), hold_s=15.0, reaid_s=10.0,
                 start_after_s=70.0, workers=1)
    by = {c["params"]["gnss.sigma_scale_search"]: c for c in res["candidates"]}
    cal, extra = calibrated_config(load_config(nav, {"gnss": {"sigma_scale_search": "calibrate"}}))
    assert extra["gnss_axes_calibration"]["sigma_scale_ned"] != [1.0, 1.0, 1.0]  # the premise: it changes the run
    nis = {k: summary(navigate(c))["health"]["measurements"]["gnss_pos"] for k, c in
           (("calibrate", cal), ("off", load_config(nav)))}
    for k, m in nis.items():
        assert by[k]["gnss_mean_nis_per_dof"]["gnss_pos"] == pytest.approx(m["mean_nis"] / m["dof"], rel=1e-9), k
    assert by["calibrate"]["cv_rms_m"] != by["off"]["cv_rms_m"]
