"""The simulated odometer study on examples/car.toml (32 min, four 60 s
outages while driving): the odometer bridges outages far better than NHC
alone, and the filter finds the simulated scale error."""

import pytest

from inskit.errors import ConfigError
from inskit.jobs.odometer_study import DEFAULT_SCENARIO, odometer_study, odometer_study_table
from inskit.simulation.scenario import load_scenario


@pytest.fixture(scope="module")
def study():
    return odometer_study(seed=1)


def test_odometer_cuts_the_outage_errors(study):
    """Without wheel speed the along-track error of a 60 s MEMS outage grows
    with the velocity error (0.1 m/s for 60 s gives 6 m); with it only the
    heading error times the distance and k's residual remain.  Seeds 1-6 of
    this study gave RMS outage-end errors 3.3-5.3 m without and 0.4-1.1 m
    with (ratios 3.7 to 10): the bound below is a factor 2, and 2 m with."""
    s = study["summary"]
    assert len(study["outages"]) == 4
    assert s["with"]["outage_end_horizontal_rms_m"] < 0.5 * s["without"]["outage_end_horizontal_rms_m"]
    assert s["with"]["outage_end_horizontal_rms_m"] < 2.0
    assert s["with"]["outage_worst_horizontal_rms_m"] < 2.0
    for r in study["outages"]:
        for label in ("with", "without"):
            e = r[label]
            assert e["worst_horizontal_m"] >= e["end_horizontal_m"] - 1e-12
    # with GNSS on both runs follow the fixes (0.5 m white + 0.3 m correlated horizontal noise)
    assert s["with"]["gnss_on_horizontal_rms_m"] < 1.0 and s["without"]["gnss_on_horizontal_rms_m"] < 1.0


def test_scale_error_is_estimated_within_its_sigma(study):
    """k = 0.005 is recovered within 3 sigma (sigma ~ 4e-5 after 30 min: 0.05
    m/s noise over ~1.8e4 readings against ~0.5 m GNSS fixes) and within
    2e-4 absolute; its sigma shrank from the 0.01 prior by over 50 times."""
    k = study["odo_scale"]
    assert abs(k["estimate"] - k["true"]) < 3 * k["sigma"] + 1e-6
    assert abs(k["estimate"] - 0.005) < 2e-4
    assert k["sigma"] < 0.01 / 50
    assert k["sigma_at_first_outage"] > k["sigma"]
    c = study["measurements"]["with"]["odometer"]
    assert c["used"] > 18000 and c["rejected"] < 10  # 0.9999 gate over 1.8e4 updates: ~2 expected


def test_table_prints_every_outage(study):
    text = odometer_study_table(study)
    assert text.count("\n") >= 8
    for r in study["outages"]:
        assert f"{r['start_s']:7.1f}" in text
    assert "odometer scale: true 0.00500" in text


def test_bad_inputs_raise_config_errors():
    sc = load_scenario(DEFAULT_SCENARIO)
    ideal = sc.model_copy(update={"imu": sc.imu.model_copy(update={"grade": "ideal"})})
    with pytest.raises(ConfigError, match="grade"):
        odometer_study(ideal)
    lev = sc.model_copy(update={"imu": sc.imu.model_copy(update={"lever_arm_b_m": (0.1, 0.0, 0.0)})})
    with pytest.raises(ConfigError, match="lever_arm"):
        odometer_study(lev)
    with pytest.raises(ConfigError, match="outages"):
        odometer_study(sc, outages=[(100.0, 90.0)])
