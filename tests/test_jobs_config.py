"""The navigate configuration: the generated reference is current and
complete, keys that would be ignored are errors naming the key, the CLI's
--outages spec maps onto [outages], and [output] dir is relative to the
config file."""

import re
from pathlib import Path

import pytest
from click.testing import CliRunner

from inskit.errors import ConfigError, InputError
from inskit.jobs import config_doc
from inskit.jobs.config import NavigateConfig, config_from_dict, load_config, outages_from_spec

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "config.md"
LOOSE = {"imu": {"file": "imu.csv"}, "gnss": {"file": "gnss.csv"}}
TIGHT = {"imu": {"file": "imu.csv"}, "gnss": {"coupling": "tight", "obs": "a.obs", "nav": "a.nav"}}
RINEX_LOOSE = {"imu": {"file": "imu.csv"}, "gnss": {"obs": "a.obs", "nav": "a.nav"}}


def _cfg(base, **sections):
    data = {k: dict(v) for k, v in base.items()}
    for k, v in sections.items():
        data[k] = {**data.get(k, {}), **v}
    return config_from_dict(data, source="c.toml")


# --- the generated reference ------------------------------------------------------
def test_docs_config_md_is_fresh():
    fresh = config_doc.render()
    assert DOC.is_file() and DOC.read_text() == fresh, (
        f"docs/config.md is stale: regenerate it with `{config_doc.REGENERATE}` from the repository root")


def test_every_key_has_a_meaning():
    assert config_doc.missing_meanings() == [], "give these fields a description= (scenario: SCENARIO_MEANINGS)"


def _section_keys(text, heading):
    """The keys of the table under ``heading`` (up to the next heading)."""
    part = text.split(f"\n{heading}\n", 1)[1].split("\n#", 1)[0]
    return [line.split("`")[1] for line in part.splitlines() if line.startswith("| `")]


@pytest.mark.parametrize("name", ["imu", "gnss", "noise", "init", "constraints", "filter", "outages", "output"])
def test_every_navigate_key_is_documented_in_its_section(name):
    model = NavigateConfig.model_fields[name].annotation
    assert _section_keys(config_doc.render(), f"### `[{name}]`") == list(model.model_fields)


def test_scenario_sections_including_raw_gnss_are_documented():
    from inskit.simulation.scenario import BlockageSpec, RawGnssSection

    text = config_doc.render()
    # the blockage windows are their own array of tables
    assert _section_keys(text, "### `[raw_gnss]`") == [k for k in RawGnssSection.model_fields if k != "blockage"]
    assert _section_keys(text, "### `[[raw_gnss.blockage]]`") == list(BlockageSpec.model_fields)
    for heading in ("### `[start]`", "### `[[segment]]`", "### `[[vibration]]`"):
        assert heading in text


def test_study_file_keys_are_documented():
    """The study keys (kind, runs, seed, duration_s, [outage], [[filter]],
    grades and the fitted grade's table) were only in the examples' comments."""
    from inskit.jobs.study import AllanGrade, FilterCase, OutageSpec, StudySpec

    text = config_doc.render().split("## Study files (`inskit study`)", 1)[1]
    top = [k for k, f in StudySpec.model_fields.items() if config_doc.submodel(f.annotation)[0] is None]
    assert _section_keys(text, "### Top level") == top
    assert _section_keys(text, "### `[outage]`") == list(OutageSpec.model_fields)
    assert _section_keys(text, "### `[[filter]]`") == list(FilterCase.model_fields)
    assert _section_keys(text, "### A grade fitted to a static log (`grades` entry `{allan = ...}`)") == list(
        AllanGrade.model_fields)


def test_rows_carry_unit_default_bounds_and_allowed_values():
    from inskit.jobs.config import GnssSection, NoiseSection, OutagesSection

    noise = {r["key"]: r for r in config_doc.rows(NoiseSection)}
    assert noise["gyro_arw_deg_sqrt_h"]["unit"] == "deg/sqrt(h)"
    assert noise["accel_vrw_m_s_sqrt_h"]["unit"] == "m/s/sqrt(h)"
    assert noise["accel_bias_sigma_ug"]["unit"] == "micro-g"
    assert noise["scale_factor_rw_ppm_sqrt_s"]["unit"] == "ppm/sqrt(s)"
    assert noise["bias_tau_s"]["default"] == "`300.0`" and noise["bias_tau_s"]["allowed"] == "> 0"
    gnss = {r["key"]: r for r in config_doc.rows(GnssSection)}
    assert gnss["mask_deg"]["unit"] == "deg" and gnss["mask_deg"]["allowed"] == ">= 0, < 90"
    assert gnss["coupling"]["allowed"] == '`"loose"`, `"tight"`'
    assert gnss["clock_h_2"]["unit"] == "1/s"  # no suffix: the [unit] of the description
    assert gnss["file"]["default"] == "unset" and gnss["file"]["type"] == "path (optional)"
    out = {r["key"]: r for r in config_doc.rows(OutagesSection)}
    assert out["windows_s"]["type"] == "array of [number, number]" and out["windows_s"]["unit"] == "s"


def test_check_mode_reports_a_stale_file(tmp_path, capsys):
    p = tmp_path / "config.md"
    p.write_text("# old\n")
    assert config_doc.main(["--check", str(p)]) == 1
    assert config_doc.REGENERATE in capsys.readouterr().err
    assert config_doc.main(["--write", str(p)]) == 0
    assert config_doc.main(["--check", str(p)]) == 0


# --- keys that would be ignored are errors -------------------------------------------
def test_examples_and_the_blockage_configs_still_load():
    load_config(ROOT / "examples" / "drive_0708.toml")
    load_config(ROOT / "examples" / "walk_0827_tight.toml")
    from inskit.jobs.reproduce_tight import BLOCKAGE_NAVIGATE

    config_from_dict(BLOCKAGE_NAVIGATE)
    config_from_dict({**BLOCKAGE_NAVIGATE, "gnss": {**BLOCKAGE_NAVIGATE["gnss"], "coupling": "tight",
                                                    "obs": "obs.rnx", "nav": "nav.rnx", "systems": ["G"]}})


def test_windows_without_the_windows_protocol(tmp_path):
    p = tmp_path / "c.toml"
    p.write_text('[imu]\nfile = "a.csv"\n[gnss]\nfile = "b.csv"\n[outages]\nwindows_s = [[15, 25]]\n')
    with pytest.raises(ConfigError, match=r"c\.toml: field 'outages\.windows_s': windows_s is given but "
                                          r"protocol = \"none\", which would ignore it; set protocol = \"windows\""):
        load_config(p)
    with pytest.raises(ConfigError, match=r"field 'outages\.windows_s': .*protocol = \"rtklibexplorer\""):
        _cfg(LOOSE, outages={"protocol": "rtklibexplorer", "windows_s": [[15, 25]]})


def test_outage_windows_are_numbered_in_time_order():
    """``--outages windows:900-960,300-330`` kept the order given: the
    outage table's k = 0 was the later window."""
    from inskit.jobs.config import outages_from_spec

    w = _cfg(LOOSE, outages={"protocol": "windows", "windows_s": [[900, 960], [300, 330]]}).outages.windows_s
    assert w == [(300.0, 330.0), (900.0, 960.0)]
    assert _cfg(LOOSE, outages=outages_from_spec("windows:900-960,300-330")).outages.windows_s == w


def test_windows_protocol_with_no_windows():
    with pytest.raises(ConfigError, match=r"c\.toml: field 'outages\.windows_s': protocol = \"windows\" needs "
                                          r"windows_s.*e\.g\. windows_s = \[\[15, 25\], \[30, 40\]\]"):
        _cfg(LOOSE, outages={"protocol": "windows"})
    assert _cfg(LOOSE, outages={"protocol": "windows", "windows_s": [[15, 25]]}).outages.windows_s == [(15.0, 25.0)]


def test_keep_satellites_without_windows_or_without_tight_coupling():
    with pytest.raises(ConfigError, match=r"field 'outages\.keep_satellites': keep_satellites = 2 needs outage "
                                          r"windows"):
        _cfg(TIGHT, outages={"keep_satellites": 2})
    with pytest.raises(ConfigError, match=r"field 'outages\.keep_satellites': .*only tight coupling fuses"):
        _cfg(LOOSE, outages={"protocol": "rtklibexplorer", "keep_satellites": 2})
    cfg = _cfg(TIGHT, outages={"protocol": "windows", "windows_s": [[10, 20]], "keep_satellites": 2})
    assert cfg.outages.keep_satellites == 2


@pytest.mark.parametrize("key, value", [("obs", "a.obs"), ("mask_deg", 15.0), ("systems", ["G"]),
                                        ("iono", "none"), ("use_doppler", False), ("doppler_sigma_scale", 2.5)])
def test_rinex_and_tight_keys_with_loose_coupling_on_a_file(key, value):
    with pytest.raises(ConfigError, match=rf"c\.toml: field 'gnss\.{key}': gnss\.{key} would be ignored: with "
                                          r"coupling = \"loose\" and gnss\.file given"):
        _cfg(LOOSE, gnss={key: value})


def test_a_default_value_written_out_is_not_an_error():
    # decided: only a change from the default is refused (it would change nothing, used or not)
    assert _cfg(LOOSE, gnss={"mask_deg": 10.0, "systems": ["G", "E"], "use_doppler": True}).gnss.mask_deg == 10.0


def test_tight_keys_with_loose_coupling_from_rinex():
    # obs, nav, mask_deg ... serve our own single-point fixes here; the pseudorange-update keys do not
    assert _cfg(RINEX_LOOSE, gnss={"mask_deg": 15.0, "systems": ["G"]}).gnss.mask_deg == 15.0
    with pytest.raises(ConfigError, match=r"field 'gnss\.clock_h0': gnss\.clock_h0 would be ignored: it "
                                          r"configures the pseudorange and Doppler updates of tight coupling"):
        _cfg(RINEX_LOOSE, gnss={"clock_h0": 1e-20})


def test_loose_keys_with_tight_coupling():
    with pytest.raises(ConfigError, match=r"field 'gnss\.use_velocity': gnss\.use_velocity, "
                                          r"gnss\.velocity_delay_s would be ignored: they describe fixes fused by "
                                          r"loose coupling"):
        _cfg(TIGHT, gnss={"use_velocity": True, "velocity_delay_s": 0.1})


def test_gnss_systems_empty_or_repeated_are_refused_naming_the_key():
    # an empty list reached the range table as "no code 'C1C' in the observations (have )"
    with pytest.raises(ConfigError, match=r"field 'gnss\.systems': List should have at least 1 item"):
        _cfg(TIGHT, gnss={"systems": []})
    with pytest.raises(ConfigError, match=r"field 'gnss\.systems': each system once: \['G', 'E', 'G'\] lists "
                                          r"\['G'\] twice"):
        _cfg(TIGHT, gnss={"systems": ["G", "E", "G"]})


def test_gnss_error_tau_needs_its_sigma():
    assert _cfg(LOOSE, gnss={"error_sigma_m": 0.03, "error_tau_s": 5.0}).gnss.error_tau_s == 5.0
    with pytest.raises(ConfigError, match=r"field 'gnss\.error_tau_s': gnss\.error_tau_s would be ignored"):
        _cfg(LOOSE, gnss={"error_tau_s": 5.0})
    with pytest.raises(ConfigError, match=r"gnss\.error_sigma_m would be ignored: it describes fixes fused by"):
        _cfg(TIGHT, gnss={"error_sigma_m": 0.03})


def test_file_keys_without_a_file():
    with pytest.raises(ConfigError, match=r"field 'gnss\.format': gnss\.format would be ignored: it describes how "
                                          r"gnss\.file is read, and no `file` is given"):
        _cfg(TIGHT, gnss={"format": "rtklib-pos"})


def test_init_keys_of_the_other_mode():
    with pytest.raises(ConfigError, match=r"field 'init\.lat_deg': init\.lat_deg, init\.rpy_deg would be ignored: "
                                          r"mode \"static-then-track\""):
        _cfg(LOOSE, init={"lat_deg": 45.0, "rpy_deg": [0, 0, 90]})
    given = {"mode": "given", "lat_deg": 45.0, "lon_deg": 7.0, "height_m": 300.0, "rpy_deg": [0, 0, 90]}
    with pytest.raises(ConfigError, match=r"field 'init\.heading_speed_m_s': .*mode is \"given\""):
        _cfg(LOOSE, init={**given, "heading_speed_m_s": 1.0})
    assert _cfg(LOOSE, init=given).init.lat_deg == 45.0


# --- [noise]: bias models, correlation times, turn-on sigmas ---------------------------
def test_bias_tau_shorthand_sets_both_and_a_specific_key_wins_where_the_shorthand_is_not_given():
    n = _cfg(LOOSE, noise={"bias_tau_s": 120.0}).noise
    assert n.gyro_tau_s() == n.accel_tau_s() == 120.0
    n = _cfg(LOOSE, noise={"accel_bias_tau_s": 60.0}).noise
    assert (n.gyro_tau_s(), n.accel_tau_s()) == (300.0, 60.0)
    n = _cfg(LOOSE, noise={"bias_tau_s": 120.0, "gyro_bias_tau_s": 120.0}).noise  # the same value twice: fine
    assert (n.gyro_tau_s(), n.accel_tau_s()) == (120.0, 120.0)


def test_bias_tau_shorthand_and_a_different_specific_key_are_an_error():
    with pytest.raises(ConfigError, match=r"field 'noise\.accel_bias_tau_s': noise\.accel_bias_tau_s = 30 "
                                          r"contradicts the shorthand noise\.bias_tau_s = 300"):
        _cfg(LOOSE, noise={"bias_tau_s": 300.0, "accel_bias_tau_s": 30.0})


def test_random_walk_biases_and_their_keys():
    n = _cfg(LOOSE, noise={"gyro_bias_model": "random-walk", "gyro_bias_rrw_deg_h_sqrt_h": 2.0}).noise
    assert n.gyro_tau_s() == float("inf") and n.accel_tau_s() == 300.0
    with pytest.raises(ConfigError, match=r"field 'noise\.gyro_bias_rrw_deg_h_sqrt_h': gyro_bias_model = "
                                          r"\"random-walk\" needs noise\.gyro_bias_rrw_deg_h_sqrt_h"):
        _cfg(LOOSE, noise={"gyro_bias_model": "random-walk"})
    with pytest.raises(ConfigError, match=r"field 'noise\.accel_bias_tau_s': noise\.accel_bias_tau_s would be "
                                          r"ignored: it describes a Gauss-Markov bias"):
        _cfg(LOOSE, noise={"accel_bias_model": "random-walk", "accel_bias_rrw_ug_sqrt_h": 20.0,
                           "accel_bias_tau_s": 100.0})
    with pytest.raises(ConfigError, match=r"field 'noise\.accel_bias_sigma_ug': .*would be ignored"):
        _cfg(LOOSE, noise={"accel_bias_model": "random-walk", "accel_bias_rrw_ug_sqrt_h": 20.0,
                           "accel_bias_sigma_ug": 5.0})
    with pytest.raises(ConfigError, match=r"field 'noise\.gyro_bias_rrw_deg_h_sqrt_h': .*would be ignored: it is the "
                                          r"strength of a random-walk bias and gyro_bias_model = \"gauss-markov\""):
        _cfg(LOOSE, noise={"gyro_bias_rrw_deg_h_sqrt_h": 2.0})
    both = {"gyro_bias_model": "random-walk", "gyro_bias_rrw_deg_h_sqrt_h": 2.0, "accel_bias_model": "random-walk",
            "accel_bias_rrw_ug_sqrt_h": 20.0}
    with pytest.raises(ConfigError, match=r"field 'noise\.bias_tau_s': .*both biases are random walks"):
        _cfg(LOOSE, noise={**both, "bias_tau_s": 100.0})
    assert _cfg(LOOSE, noise={**both, "bias_tau_s": 300.0}).noise.gyro_tau_s() == float("inf")  # the default: fine


@pytest.mark.parametrize("key", ["gyro_bias_tau_s", "accel_bias_tau_s", "bias_tau_s", "gyro_turn_on_bias_deg_h"])
@pytest.mark.parametrize("value", [0.0, -5.0])
def test_non_positive_times_and_sigmas_name_their_key(key, value):
    with pytest.raises(ConfigError, match=rf"c\.toml: field 'noise\.{key}': .*greater than 0"):
        _cfg(LOOSE, noise={key: value})


def test_a_random_walk_time_constant_is_a_model_not_an_infinite_tau(tmp_path):
    p = tmp_path / "c.toml"
    p.write_text('[imu]\nfile = "a.csv"\n[gnss]\nfile = "b.csv"\n[noise]\nbias_tau_s = inf\n')
    with pytest.raises(ConfigError, match=r"field 'noise\.bias_tau_s'.*finite"):
        load_config(p)


def test_turn_on_bias_in_noise_or_init_but_not_both():
    from inskit.jobs.noise import turn_on_sigmas
    from inskit.units import DEG, MILLI_G

    assert turn_on_sigmas(_cfg(LOOSE)) == pytest.approx((0.05 * DEG, 0.05))  # the [init] defaults
    cfg = _cfg(LOOSE, noise={"gyro_turn_on_bias_deg_h": 360.0, "accel_turn_on_bias_mg": 2.0})
    assert turn_on_sigmas(cfg) == pytest.approx((0.1 * DEG, 2.0 * MILLI_G))  # 360 deg/h = 0.1 deg/s
    assert turn_on_sigmas(_cfg(LOOSE, init={"sigma_accel_bias_m_s2": 0.2})) == pytest.approx((0.05 * DEG, 0.2))
    with pytest.raises(ConfigError, match=r"field 'noise\.gyro_turn_on_bias_deg_h': noise\.gyro_turn_on_bias_deg_h "
                                          r"and init\.sigma_gyro_bias_deg_s both give the turn-on bias sigma"):
        _cfg(LOOSE, noise={"gyro_turn_on_bias_deg_h": 360.0}, init={"sigma_gyro_bias_deg_s": 0.1})
    with pytest.raises(ConfigError, match=r"field 'noise\.accel_turn_on_bias_mg'"):
        _cfg(LOOSE, noise={"accel_turn_on_bias_mg": 2.0}, init={"sigma_accel_bias_m_s2": 0.05})


# --- [height] --------------------------------------------------------------------------
def test_height_section_is_documented():
    from inskit.jobs.config import HeightSection

    assert _section_keys(config_doc.render(), "### `[height]`") == list(HeightSection.model_fields)


def test_height_needs_a_file_or_a_constant_and_refuses_ignored_keys():
    with pytest.raises(ConfigError, match=r"\[height\] needs file .* or height_m .*exactly one"):
        _cfg(LOOSE, height={})
    with pytest.raises(ConfigError, match=r"exactly one"):
        _cfg(LOOSE, height={"file": "baro.csv", "height_m": 10.0})
    with pytest.raises(ConfigError, match=r"field 'height\.time_offset_s': .*would be ignored"):
        _cfg(LOOSE, height={"height_m": 0.0, "time_offset_s": 0.2})
    with pytest.raises(ConfigError, match=r"field 'height\.bias_sigma0_m': height\.bias_sigma0_m would be ignored: "
                                          r"it describes the estimated offset, and estimate_bias = false"):
        _cfg(LOOSE, height={"height_m": 0.0, "estimate_bias": False, "bias_sigma0_m": 3.0})
    with pytest.raises(ConfigError, match=r"field 'height\.bias_tau_s': bias_model = \"gauss-markov\" needs"):
        _cfg(LOOSE, height={"file": "b.csv", "bias_model": "gauss-markov"})
    with pytest.raises(ConfigError, match=r"field 'height\.bias_tau_s': .*would be ignored"):
        _cfg(LOOSE, height={"file": "b.csv", "bias_tau_s": 600.0})
    with pytest.raises(ConfigError, match=r"field 'height\.bias_rw_m_sqrt_h': .*would be ignored: bias_model = "
                                          r"\"constant\""):
        _cfg(LOOSE, height={"file": "b.csv", "bias_model": "constant", "bias_rw_m_sqrt_h": 1.0})
    with pytest.raises(ConfigError, match=r"field 'height': \[height\] would be ignored: the uncoupled scheme"):
        _cfg(LOOSE, height={"file": "b.csv"}, filter={"scheme": "uncoupled"})
    # the uncoupled scheme resets the INS to each fix: what only a filter fuses or estimates is refused, named
    for sect, kv, key in (("gnss", {"use_velocity": True}, "gnss.use_velocity"),
                          ("gnss", {"error_sigma_m": 0.03}, "gnss.error_sigma_m"),
                          ("filter", {"time_offset": True}, "filter.time_offset"),
                          ("constraints", {"rate_hz": 5.0}, "constraints.rate_hz")):
        over = {"filter": {"scheme": "uncoupled"}}
        over[sect] = {**over.get(sect, {}), **kv}
        with pytest.raises(ConfigError, match=rf"field '{re.escape(key)}': {re.escape(key)} would be ignored: the "
                                              r"uncoupled scheme resets the INS to each position fix"):
            _cfg(LOOSE, **over)
    assert _cfg(LOOSE, filter={"scheme": "uncoupled"}).filter.scheme == "uncoupled"
    # --calibrate-time-offset fits the filter's innovations: with no filter it ended in "internal error: KeyError"
    with pytest.raises(ConfigError, match=r"field 'imu\.time_offset_search': .*uncoupled scheme has no filter"):
        _cfg(LOOSE, filter={"scheme": "uncoupled"}, imu={"time_offset_search": "calibrate"})
    assert _cfg(LOOSE, filter={"scheme": "uncoupled"}, imu={"time_offset_search": "off"}).imu.time_offset_search == "off"
    h = _cfg(LOOSE, height={"file": "b.csv", "bias_model": "gauss-markov", "bias_tau_s": 600.0}).height
    assert h.bias_tau_s == 600.0 and h.estimate_bias


def test_first_row_only_for_increment_files():
    """Issue 14 item 11: [imu] first_row describes the first row of an increment file; the rtklibexplorer log
    holds rates, so a value other than the default there would be ignored."""
    assert _cfg(LOOSE).imu.first_row == "initial"
    assert _cfg(LOOSE, imu={"first_row": "increment"}).imu.first_row == "increment"
    with pytest.raises(ConfigError, match=r"field 'imu\.first_row': applies to increment files .*rtklibexplorer log "
                                          r"holds rates"):
        _cfg(LOOSE, imu={"format": "rtklibexplorer", "first_row": "discard"})
    with pytest.raises(ConfigError, match=r"imu\.first_row"):
        _cfg(LOOSE, imu={"first_row": "first"})


def test_per_axis_white_noise_needs_the_static_measurement():
    assert _cfg(LOOSE).noise.from_static_per_axis is False
    assert _cfg(LOOSE, noise={"from_static_per_axis": True}).noise.from_static_per_axis is True
    with pytest.raises(ConfigError, match=r"field 'noise\.from_static_per_axis': .*from_static = false measures "
                                          r"none"):
        _cfg(LOOSE, noise={"from_static_per_axis": True, "from_static": False})


# --- --outages on the command line -------------------------------------------------
def test_mounting_keys_need_the_mounting_and_a_lateral_constraint():
    with pytest.raises(ConfigError, match=r"c\.toml: field 'constraints\.sigma_mounting_deg': "
                       r"constraints\.sigma_mounting_deg would be ignored: .*mounting = true"):
        _cfg(LOOSE, constraints={"sigma_mounting_deg": 2.0})
    with pytest.raises(ConfigError, match=r"field 'constraints\.mounting': .*neither constraints\.nhc nor "
                       r"odometer\.with_nhc"):
        _cfg(LOOSE, constraints={"mounting": True, "nhc": False}, odometer={"file": "odo.csv"})
    with pytest.raises(ConfigError, match=r"field 'constraints\.mounting': .*the uncoupled scheme has none"):
        _cfg(LOOSE, constraints={"mounting": True}, filter={"scheme": "uncoupled"})
    c = _cfg(LOOSE, constraints={"mounting": True, "nhc": False, "sigma_mounting_deg": 2.0},
             odometer={"file": "odo.csv", "with_nhc": True})
    assert c.constraints.mounting and c.constraints.sigma_mounting_deg == 2.0
    assert not _cfg(LOOSE).constraints.mounting  # off by default


def test_outages_spec_parsing():
    assert outages_from_spec("windows:15-25,30-40") == {"protocol": "windows", "windows_s": [[15.0, 25.0],
                                                                                            [30.0, 40.0]]}
    assert outages_from_spec(" windows: 0.5 - 10 ") == {"protocol": "windows", "windows_s": [[0.5, 10.0]]}
    assert outages_from_spec("rtklibexplorer") == {"protocol": "rtklibexplorer", "windows_s": []}
    assert outages_from_spec("none") == {"protocol": "none", "windows_s": [], "keep_satellites": 0}


@pytest.mark.parametrize("spec", ["windows", "windows:", "windows:15-", "windows:15-25,", "windows:25-15",
                                  "windows:15..25", "windows:-5-10", "windows:a-b", "rtk", "None"])
def test_malformed_outages_spec_is_an_input_error_with_an_example(spec):
    with pytest.raises(InputError, match=r"--outages: .*e\.g\. windows:15-25,30-40"):
        outages_from_spec(spec)


class _Stop(Exception):
    pass


@pytest.fixture
def captured(monkeypatch):
    """Replace the navigate job by one that records the config and stops."""
    import inskit.jobs.navigate as N

    seen = []

    def fake(cfg, **kw):
        seen.append(cfg)
        raise _Stop

    monkeypatch.setattr(N, "navigate", fake)
    return seen


def _config(tmp_path, text=""):
    p = tmp_path / "cfg" / "c.toml"
    p.parent.mkdir(exist_ok=True)
    p.write_text('[imu]\nfile = "imu.csv"\n[gnss]\nfile = "gnss.csv"\n' + text)
    return p


@pytest.mark.parametrize("spec, protocol, windows", [
    ("windows:15-25,30-40", "windows", [(15.0, 25.0), (30.0, 40.0)]),
    ("rtklibexplorer", "rtklibexplorer", []),
    ("none", "none", []),
])
def test_cli_outages_map_onto_the_config(tmp_path, captured, spec, protocol, windows):
    from inskit.cli import cli

    cfg_file = _config(tmp_path, '[outages]\nprotocol = "windows"\nwindows_s = [[1, 2]]\n')
    r = CliRunner().invoke(cli, ["navigate", str(cfg_file), "--outages", spec, "--out", str(tmp_path / "o")])
    assert isinstance(r.exception, _Stop), r.output
    assert captured[0].outages.protocol == protocol and captured[0].outages.windows_s == windows


def test_cli_malformed_outages(tmp_path, captured):
    from inskit.cli import cli

    r = CliRunner().invoke(cli, ["navigate", str(_config(tmp_path)), "--outages", "windows:25-15",
                                 "--out", str(tmp_path / "o")])
    assert isinstance(r.exception, InputError) and not captured
    assert "--outages: the window '25-15' must end after it starts" in str(r.exception)
    assert "e.g. windows:15-25,30-40" in str(r.exception)


def test_cli_malformed_outages_is_one_line_and_exit_2(tmp_path, capsys):
    from inskit.cli import main

    with pytest.raises(SystemExit) as e:
        main(["navigate", str(_config(tmp_path)), "--outages", "sometimes", "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert e.value.code == 2 and err.count("\n") == 1
    assert err.startswith("inskit: error: --outages: 'sometimes' is not an outage protocol")


# --- [output] dir ------------------------------------------------------------------
def test_output_dir_is_relative_to_the_config_file(tmp_path, captured, monkeypatch):
    from inskit.cli import cli

    cwd = tmp_path / "elsewhere"
    cwd.mkdir()
    monkeypatch.chdir(cwd)
    cfg_file = _config(tmp_path, '[output]\ndir = "results/run1"\n')
    r = CliRunner().invoke(cli, ["navigate", str(cfg_file)])
    assert isinstance(r.exception, _Stop), r.output
    assert (cfg_file.parent / "results" / "run1").is_dir()  # the output folder was checked writable there
    assert not (cwd / "results").exists()


# --- [earth] gravity -----------------------------------------------------------------
def test_earth_gravity_key_default_choices_and_errors():
    assert _cfg(LOOSE).earth.gravity == "normal"
    assert _cfg(LOOSE, earth={"gravity": "normal-simple"}).earth.gravity == "normal-simple"
    with pytest.raises(ConfigError, match=r"c.toml: .*earth.gravity.*'normal', 'normal-simple' or 'j2'"):
        _cfg(LOOSE, earth={"gravity": "egm96"})
    with pytest.raises(ConfigError, match="earth"):
        _cfg(LOOSE, earth={"model": "j2"})
    assert _section_keys(config_doc.render(), "### `[earth]`") == ["gravity"]


@pytest.mark.parametrize("flag, expected", [(None, "j2"), ("normal-simple", "normal-simple")])
def test_cli_gravity_overrides_the_config(tmp_path, captured, flag, expected):
    from inskit.cli import cli

    cfg_file = _config(tmp_path, '[earth]\ngravity = "j2"\n')
    args = ["navigate", str(cfg_file), "--out", str(tmp_path / "o")] + (["--gravity", flag] if flag else [])
    r = CliRunner().invoke(cli, args)
    assert isinstance(r.exception, _Stop), r.output
    assert captured[0].earth.gravity == expected


def test_contradictions_between_sections_are_refused_when_the_config_is_read():
    """Refused by the config model, naming the key, not at run time after the start-up."""
    with pytest.raises(ConfigError, match=r"field 'odometer\.with_nhc': .*turn constraints\.nhc off"):
        _cfg(LOOSE, odometer={"file": "odo.csv", "with_nhc": True})
    assert _cfg(LOOSE, odometer={"file": "odo.csv", "with_nhc": True}, constraints={"nhc": False}).odometer.with_nhc
    with pytest.raises(ConfigError, match=r"field 'filter\.scheme': the uncoupled scheme .* no tight form"):
        _cfg(TIGHT, filter={"scheme": "uncoupled"})


@pytest.mark.parametrize("windows, msg", [([[-5.0, 2.0]], "starts before the first GNSS epoch"),
                                          ([[1.0, 2.0], [1.5, 3.0]], "overlap")])
def test_outage_windows_in_the_file_follow_the_cli_rules(windows, msg):
    with pytest.raises(ConfigError, match=rf"field 'outages\.windows_s'.*{msg}"):
        _cfg(LOOSE, outages={"protocol": "windows", "windows_s": windows})


@pytest.mark.parametrize("name", ["", "../../esc", "/tmp/abs", "a/b", ".hidden", " lead", "c:d"])
def test_a_run_name_is_a_plain_folder_name(tmp_path, name):
    """name = "" wrote the run into out/ itself and "../../esc" outside it:
    the default output folder is out/<name>, so the name is one folder."""
    p = tmp_path / "c.toml"
    p.write_text(f'name = "{name}"\n[imu]\nfile = "imu.csv"\n[gnss]\nfile = "gnss.csv"\n')
    with pytest.raises(ConfigError, match="field 'name': .* is not a plain folder name"):
        load_config(p)


def test_the_output_rate_is_capped_as_every_rate():
    """`[output] rate_hz = 1e300` made t * rate overflow to inf: the CSV kept its first row only."""
    from inskit.units import MAX_RATE_HZ

    assert _cfg(LOOSE, output={"rate_hz": MAX_RATE_HZ}).output.rate_hz == MAX_RATE_HZ
    with pytest.raises(ConfigError, match=r"c\.toml: field 'output\.rate_hz': .*less than or equal to 10000"):
        _cfg(LOOSE, output={"rate_hz": 1e300})


# --- angles ----------------------------------------------------------------------------
@pytest.mark.parametrize("section, key, value, shown", [
    ("imu", "mount_rpy_deg", [0.0, 370.0, 0.0], "pitch 370"),
    ("imu", "mount_rpy_deg", [-360.5, 0.0, 0.0], "roll -360.5"),
    ("init", "yaw_deg", 725.0, "725"),
])
def test_an_angle_beyond_a_full_turn_is_refused_naming_the_field_and_the_value(section, key, value, shown):
    """[imu] mount_rpy_deg = [0, 370, 0] was taken (the rotation of 10 deg): 370 is a typo or another unit."""
    with pytest.raises(ConfigError, match=rf"^c\.toml: field '{section}\.{key}': {shown} is outside \[-360, 360\] "
                                          r"degrees: no angle needs more than a full turn either way \(a typo"):
        _cfg(LOOSE, **{section: {key: value}})


def test_angles_up_to_a_full_turn_either_way_are_taken_and_documented():
    cfg = _cfg(LOOSE, imu={"mount_rpy_deg": [-360.0, 359.9, 360.0]})
    assert cfg.imu.mount_rpy_deg == (-360.0, 359.9, 360.0)
    given = {"mode": "given", "lat_deg": 45.0, "height_m": 0.0}
    assert _cfg(LOOSE, init={**given, "lon_deg": 359.0, "rpy_deg": [0.0, -90.0, 360.0]}).init.rpy_deg[2] == 360.0
    with pytest.raises(ConfigError, match=r"field 'init\.rpy_deg': yaw 361 is outside \[-360, 360\]"):
        _cfg(LOOSE, init={**given, "lon_deg": 7.0, "rpy_deg": [0.0, 0.0, 361.0]})
    with pytest.raises(ConfigError, match=r"field 'init\.lon_deg': -180\.5 is outside \[-180, 360\] degrees"):
        _cfg(LOOSE, init={**given, "lon_deg": -180.5, "rpy_deg": [0.0, 0.0, 0.0]})
    from inskit.jobs.config import ImuSection, InitSection

    assert {r["key"]: r for r in config_doc.rows(ImuSection)}["mount_rpy_deg"]["allowed"] == ">= -360.0, <= 360.0"
    init = {r["key"]: r for r in config_doc.rows(InitSection)}
    assert init["rpy_deg"]["allowed"] == init["yaw_deg"]["allowed"] == ">= -360.0, <= 360.0"
    assert init["lon_deg"]["allowed"] == ">= -180.0, <= 360.0"


def test_a_section_that_is_no_table_is_said_beside_an_override():
    """config_from_dict({'imu': 3}, overrides={'imu': {...}}) was Python's "TypeError: 'int' object is not a
    mapping" (a helper found it); a config that is no dict at all likewise."""
    with pytest.raises(ConfigError, match=r"config: section 'imu' is int 3; expected a table of keys"):
        config_from_dict({"imu": 3}, overrides={"imu": {"file": "a.csv"}})
    with pytest.raises(ConfigError, match=r"config: a configuration is a dict of sections .*got list"):
        config_from_dict([("imu", {})])


# --- keys a switched-off feature would ignore (an adversarial review: each ran with exit 0 and the results of
# the run without the key) ----------------------------------------------------------------------------------
@pytest.mark.parametrize("sections, field, why", [
    ({"gnss": {"velocity_delay_s": 0.1}}, "gnss.velocity_delay_s", r"use_velocity = false .*use_velocity = true"),
    ({"gnss": {"velocity_sigma_scale": 2.0}}, "gnss.velocity_sigma_scale", r"use_velocity = false"),
    ({"gnss": {"quality": [1]}}, "gnss.quality", r"format = \"inskit\" has no quality column.*\"rtklib-pos\""),
    ({"init": {"sigma_lever_arm_m": 0.5}}, "init.sigma_lever_arm_m", r"filter\.lever_arm = false .*= true"),
    ({"init": {"sigma_time_offset_s": 0.1}}, "init.sigma_time_offset_s", r"filter\.time_offset = false"),
    ({"noise": {"time_offset_rw_s_sqrt_s": 1e-4}}, "noise.time_offset_rw_s_sqrt_s", r"filter\.time_offset = false"),
    ({"init": {"sigma_scale_factor": 0.01}, "filter": {"scale_factors": False}}, "init.sigma_scale_factor",
     r"filter\.scale_factors = false"),
    ({"noise": {"scale_factor_rw_ppm_sqrt_s": 5.0}, "filter": {"scale_factors": False}},
     "noise.scale_factor_rw_ppm_sqrt_s", r"filter\.scale_factors = false"),
    ({"constraints": {"zupt": False, "zupt_sigma_m_s": 0.05}}, "constraints.zupt_sigma_m_s", r"zupt = false"),
    ({"constraints": {"nhc": False, "nhc_sigma_m_s": 0.3}}, "constraints.nhc_sigma_m_s", r"nhc = false"),
    ({"constraints": {"nhc": False, "nhc_lever_arm_b_m": [0.1, 0.0, 0.8]}}, "constraints.nhc_lever_arm_b_m",
     r"nhc = false"),
    ({"constraints": {"nhc": False, "zupt": False, "rate_hz": 5.0}}, "constraints.rate_hz", r"apply neither"),
    ({"noise": {"from_static_per_axis": True}, "init": {"mode": "in-motion"}}, "noise.from_static_per_axis",
     r"init\.mode = \"in-motion\" has none"),
    ({"noise": {"from_static_per_axis": True},
      "init": {"mode": "given", "lat_deg": 45.0, "lon_deg": 7.0, "height_m": 300.0, "rpy_deg": [0, 0, 90]}},
     "noise.from_static_per_axis", r"init\.mode = \"given\" has none"),
])
def test_a_key_of_a_switched_off_feature_is_refused_naming_it(sections, field, why):
    with pytest.raises(ConfigError, match=rf"^c\.toml: field '{re.escape(field)}': {re.escape(field)}.* would be "
                                          rf"ignored: .*{why}"):
        _cfg(LOOSE, **sections)


def test_the_same_keys_with_their_feature_on_or_at_their_defaults_load():
    assert _cfg(LOOSE, gnss={"use_velocity": True, "velocity_delay_s": 0.1}).gnss.velocity_delay_s == 0.1
    assert _cfg(LOOSE, gnss={"format": "rtklib-pos", "quality": [1]}).gnss.quality == [1]
    assert _cfg(LOOSE, gnss={"quality": [1, 2], "velocity_sigma_scale": 1.0}).gnss.quality == [1, 2]  # defaults
    assert _cfg(LOOSE, init={"sigma_lever_arm_m": 0.5}, filter={"lever_arm": True}).init.sigma_lever_arm_m == 0.5
    assert _cfg(LOOSE, init={"sigma_time_offset_s": 0.1}, noise={"time_offset_rw_s_sqrt_s": 1e-4},
                filter={"time_offset": True}).filter.time_offset
    assert _cfg(LOOSE, init={"sigma_scale_factor": 0.01}).init.sigma_scale_factor == 0.01  # scale_factors: default on
    assert _cfg(LOOSE, constraints={"nhc": False, "zupt_sigma_m_s": 0.05, "rate_hz": 5.0}).constraints.rate_hz == 5.0
    assert _cfg(LOOSE, constraints={"zupt": False, "nhc_sigma_m_s": 0.3}).constraints.nhc_sigma_m_s == 0.3
    # "auto" measures on the static start when the log starts at rest
    assert _cfg(LOOSE, noise={"from_static_per_axis": True}, init={"mode": "auto"}).noise.from_static_per_axis
    assert _cfg(LOOSE, noise={"from_static_per_axis": True},
                init={"mode": "static-then-track"}).noise.from_static_per_axis


def test_every_navigate_example_loads():
    """The examples that are navigate configs (not scenarios or studies) still load under the rules."""
    import tomllib

    loaded = []
    for f in sorted((ROOT / "examples").glob("*.toml")):
        data = tomllib.loads(f.read_text())
        if "imu" in data and "gnss" in data and "segment" not in data and "study" not in data:
            load_config(f)
            loaded.append(f.name)
    assert {"drive_0708.toml", "walk_0827.toml", "walk_0827_tight.toml"} <= set(loaded)


def test_an_override_that_switches_a_feature_off_names_the_key_left_on(tmp_path):
    """An override (the CLI's, the API's) whose switch leaves a key of the file unused is refused like the file
    would be, naming the key (inskit tune's candidates reset such keys: tests/test_jobs_tune.py)."""
    with pytest.raises(ConfigError, match=r"drive_0708\.toml: field 'constraints\.nhc_sigma_m_s': .*nhc = false"):
        load_config(ROOT / "examples" / "drive_0708.toml", {"constraints": {"nhc": False}})


# --- [output] columns: checked when the config is loaded ----------------------------------------------------
def test_output_columns_typo_is_refused_when_the_config_is_loaded(tmp_path):
    p = _config(tmp_path, '[output]\ncolumns = ["bogus"]\n')
    with pytest.raises(ConfigError, match=r"c\.toml: field 'output\.columns': 'bogus' is neither a group \(all, "
                                          r"navigation, .*\) nor a column of the solution of this configuration; "
                                          r"its columns are time_s, .*sg_x"):
        load_config(p)
    # a column of an estimated state this configuration does not have
    with pytest.raises(ConfigError, match=r"field 'output\.columns': 'lever_x_m' is neither"):
        _cfg(LOOSE, output={"columns": ["navigation", "lever_x_m"]})
    assert _cfg(LOOSE, output={"columns": ["navigation", "lever_x_m"]},
                filter={"lever_arm": True}).output.columns == ["navigation", "lever_x_m"]
    assert _cfg(LOOSE, output={"columns": "sigma"}).output.columns == ["sigma"]
    tight = _cfg(TIGHT, output={"columns": ["clock_bias_m", "isb_E_m", "clock_drift_m_s"]})
    assert tight.output.columns[1] == "isb_E_m"
    with pytest.raises(ConfigError, match=r"field 'output\.columns': 'isb_E_m' is neither"):
        _cfg(TIGHT, gnss={"systems": ["G"]}, output={"columns": ["isb_E_m"]})


def test_output_columns_typo_is_refused_by_navigate_before_any_data_is_read(tmp_path, captured):
    from inskit.cli import cli

    p = _config(tmp_path, '[output]\ncolumns = ["navigation", "bogus"]\n')  # imu.csv and gnss.csv do not exist
    r = CliRunner().invoke(cli, ["navigate", str(p), "--out", str(tmp_path / "o")])
    assert isinstance(r.exception, ConfigError) and not captured
    assert "field 'output.columns': 'bogus' is neither" in str(r.exception) and str(p) in str(r.exception)


# --- outage windows: said where they came from -----------------------------------------------------------------
def test_overlapping_windows_of_the_command_line_are_said_of_outages(tmp_path, captured):
    from inskit.cli import cli

    r = CliRunner().invoke(cli, ["navigate", str(_config(tmp_path)), "--outages", "windows:15-25,20-40",
                                 "--out", str(tmp_path / "o")])
    assert isinstance(r.exception, InputError) and not captured
    msg = str(r.exception)
    assert msg.startswith("--outages windows:15-25,20-40: outage windows [15, 25] and [20, 40] overlap"), msg
    assert "c.toml" not in msg and "windows_s" not in msg
    with pytest.raises(InputError, match=r"^--outages windows:15-25,25-40: outage windows \[15, 25\] and \[25, 40\] "
                                         r"touch: .*merge them into \[15, 40\]"):
        outages_from_spec("windows:15-25,25-40")


def test_touching_windows_in_the_file_are_refused_when_it_is_loaded(tmp_path):
    p = _config(tmp_path, '[outages]\nprotocol = "windows"\nwindows_s = [[100, 110], [110, 120]]\n')
    with pytest.raises(ConfigError, match=r"c\.toml: field 'outages\.windows_s': outage windows \[100, 110\] and "
                                          r"\[110, 120\] touch: they are one outage.*merge them into \[100, 120\]"):
        load_config(p)


@pytest.mark.parametrize("text", ["[100.0, 110.0]", "100.0", "[[100, 110, 120]]", "[[100, 110], 120]"])
def test_windows_that_are_no_list_of_pairs_say_what_is_expected(tmp_path, text):
    p = _config(tmp_path, f'[outages]\nprotocol = "windows"\nwindows_s = {text}\n')
    with pytest.raises(ConfigError, match=r"c\.toml: field 'outages\.windows_s': .* windows_s is a list of \[start, "
                                          r"end\] pairs in seconds after the first GNSS epoch, e\.g\. windows_s = "
                                          r"\[\[100, 110\]"):
        load_config(p)


@pytest.mark.parametrize("section, key, value, shown", [
    ("gnss", "lever_arm_b_m", [1e12, 0.0, 0.0], "x (forward) 1e+12 m"),
    ("gnss", "lever_arm_b_m", [0.0, -1500, 0.0], "y (right) -1500 m"),
    ("constraints", "nhc_lever_arm_b_m", [0.0, 0.0, 2000.0], "z (down) 2000 m"),
    ("odometer", "lever_arm_b_m", [5000.0, 0.0, 0.0], "x (forward) 5000 m"),
    ("height", "lever_arm_b_m", [0.0, 0.0, -790.5e3], "z (down) -790500 m"),
])
def test_a_lever_arm_beyond_a_kilometre_is_refused_naming_the_key(section, key, value, shown):
    """`inskit navigate --lever-arm 1e12,0,0` ran the filter and ended in 'innovation covariance is not
    positive definite: the filter diverged' (the 'non-holonomic constraint does not hold' retry before it),
    naming no setting; 1e7 m ran to an unhealthy verdict blamed on lost fixes.  Every lever arm of the config
    is held to +-1 km (millimetres under the metre key are caught from 1 m on)."""
    data = {"imu": {"file": "imu.csv"}, "gnss": {"file": "gnss.csv"}}
    if section in ("odometer", "height"):
        data[section] = {"file": f"{section}.csv"}
    data.setdefault(section, {})[key] = value
    with pytest.raises(ConfigError, match=rf"c\.toml: field '{section}\.{key}': {re.escape(shown)} is beyond "
                                          r"\+-1000 m: no vehicle carries its sensors that far apart"):
        config_from_dict(data, source="c.toml")
    data[section][key] = [999.0, -0.05, 0.79]  # within the bound: taken
    assert tuple(getattr(getattr(config_from_dict(data, source="c.toml"), section), key)) == (999.0, -0.05, 0.79)


@pytest.mark.parametrize("quality, why", [([], "an empty list keeps no fix"), ([1, 7], "no .pos row has Q = 7"),
                                          ([0], "no .pos row has Q = 0")])
def test_a_quality_list_that_can_keep_no_fix_is_refused_at_load(quality, why):
    """`[gnss] quality = []` (or [7]) loaded, and the run failed on reading the file with '... no rows with
    quality Q in []', which blamed the .pos file for the setting.  RTKLIB's flags are 1 to 6."""
    data = {"imu": {"file": "imu.csv"}, "gnss": {"file": "g.pos", "format": "rtklib-pos", "quality": quality}}
    with pytest.raises(ConfigError, match=rf"c\.toml: field 'gnss\.quality': expected one or more of RTKLIB's quality "
                                          rf"flags Q, 1 to 6 .*, got {re.escape(str(quality))}: {why}$"):
        config_from_dict(data, source="c.toml")
    data["gnss"]["quality"] = [1, 2, 5]
    assert config_from_dict(data, source="c.toml").gnss.quality == [1, 2, 5]
