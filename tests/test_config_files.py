"""Reading TOML files (:mod:`inskit.config_files`): what editors put in them."""

import pytest

from inskit.config_files import read_toml
from inskit.errors import ConfigError


def test_a_byte_order_mark_is_dropped(tmp_path):
    p = tmp_path / "c.toml"
    p.write_bytes(b"\xef\xbb\xbfname = \"x\"\r\n[imu]\r\nfile = \"a.csv\"\r\n")
    assert read_toml(p) == {"name": "x", "imu": {"file": "a.csv"}}


def test_a_file_that_is_not_utf8_names_its_line(tmp_path):
    """It was 'internal error: UnicodeDecodeError ...', exit 3."""
    p = tmp_path / "c.toml"
    p.write_bytes(b"name = \"x\"\n# caf\xe9 (latin-1)\n")
    with pytest.raises(ConfigError, match=r"c\.toml: line 2: byte 0xe9 is not UTF-8; a config file is UTF-8"):
        read_toml(p)


@pytest.mark.parametrize("text, field", [
    ("[imu]\nfile = \"a.csv\"\n[gnss]\nfile = \"g.csv\"\n[noise]\ngyro_arw_deg_sqrt_h = 1e300\n",
     "noise.gyro_arw_deg_sqrt_h"),
    ("[imu]\nfile = \"a.csv\"\nmount_rpy_deg = [0.0, -2e20, 0.0]\n[gnss]\nfile = \"g.csv\"\n", "imu.mount_rpy_deg"),
])
def test_a_setting_beyond_any_meaning_is_refused_by_name(tmp_path, text, field):
    """gyro_arw_deg_sqrt_h = 1e300 passed the model and overflowed when squared: 'internal error:
    OverflowError', exit 3."""
    from inskit.jobs.config import load_config

    p = tmp_path / "c.toml"
    p.write_text(text)
    with pytest.raises(ConfigError, match=rf"c\.toml: field '{field}': .* is beyond \+-1e\+12: no setting means"):
        load_config(p)


def test_a_scenario_speed_beyond_any_meaning_is_refused_by_name(tmp_path):
    from inskit.simulation.scenario import load_scenario

    p = tmp_path / "s.toml"
    p.write_text("name = \"s\"\n[start]\nlat_deg = 45\nlon_deg = 7\n[imu]\nrate_hz = 100\n[[segment]]\n"
                 "type = \"accelerate\"\nspeed_m_s = 1e200\nduration_s = 5\n")
    with pytest.raises(ConfigError, match=r"field 'segment\.0\.speed_m_s': .*1e\+200 is beyond"):
        load_scenario(p)


def test_a_misspelt_key_gets_the_nearest_known_one(tmp_path):
    """'Extra inputs are not permitted' alone did not say what was expected."""
    from inskit.jobs.config import load_config
    from inskit.simulation.scenario import load_scenario

    p = tmp_path / "c.toml"
    p.write_text("[imu]\nfile = \"a.csv\"\n[gnss]\nfile = \"g.csv\"\n[constraints]\nnhc_sigma_ms = 0.3\n")
    with pytest.raises(ConfigError, match=r"field 'constraints\.nhc_sigma_ms': Extra inputs are not permitted; did "
                                          r"you mean 'nhc_sigma_m_s'\?$"):
        load_config(p)
    p.write_text("[imu]\nfile = \"a.csv\"\nzzz = 1\n[gnss]\nfile = \"g.csv\"\n")
    with pytest.raises(ConfigError, match=r"field 'imu\.zzz': Extra inputs are not permitted; the keys here are "
                                          r"file, format, time_offset_s"):
        load_config(p)
    p.write_text("[imu]\nfile = \"a.csv\"\n[gnss]\nfile = \"g.csv\"\n[nosie]\nbias_tau_s = 3\n")
    with pytest.raises(ConfigError, match=r"field 'nosie': .*; did you mean 'noise'\?"):
        load_config(p)
    s = tmp_path / "s.toml"
    s.write_text("name = \"s\"\n[start]\nlat_deg = 45\nlon_deg = 7\n[imu]\nrate_hz = 100\n[[segment]]\n"
                 "type = \"static\"\nduraton_s = 5\n")
    with pytest.raises(ConfigError, match=r"field 'segment\.0\.duraton_s': .*; did you mean 'duration_s'\?"):
        load_scenario(s)


@pytest.mark.parametrize("line, field, said", [
    ('[constraints]\nrate_hz = "10"\n', "constraints.rate_hz", r'"10" is text; this setting takes a number \(without quotes\)'),
    ("[constraints]\nrate_hz = true\n", "constraints.rate_hz", r"true is a boolean; this setting takes a number"),
    ("[constraints]\nzupt = 1\n", "constraints.zupt", r"1 is a number; this setting takes true or false"),
    ('[constraints]\nnhc = "false"\n', "constraints.nhc", r'"false" is text; this setting takes true or false'),
    ('[constraints]\nnhc_lever_arm_b_m = [0, "0", 1]\n', "constraints.nhc_lever_arm_b_m", r'"0" is text'),
])
def test_a_value_of_the_wrong_kind_is_refused_not_coerced(tmp_path, line, field, said):
    """pydantic's lax mode took rate_hz = "10" as 10.0, rate_hz = true as 1.0 and nhc = "false" as False:
    a TOML slip ran silently."""
    from inskit.jobs.config import load_config

    p = tmp_path / "c.toml"
    p.write_text("[imu]\nfile = \"a.csv\"\n[gnss]\nfile = \"g.csv\"\n" + line)
    with pytest.raises(ConfigError, match=rf"c\.toml: field '{field}': {said}"):
        load_config(p)


def test_kinds_the_annotation_admits_still_pass(tmp_path):
    """Integers for floats, text for paths and literals, None-able and union fields stay as they were."""
    from inskit.jobs.config import load_config
    from inskit.simulation.scenario import load_scenario

    p = tmp_path / "c.toml"
    p.write_text("[imu]\nfile = \"a.csv\"\ntime_offset_s = 1\nmount_rpy_deg = [0, 1, 2.5]\n[gnss]\nfile = \"g.csv\"\n"
                 "quality = [1, 2]\n[constraints]\nrate_hz = 5\nzupt = false\n"
                 "[outages]\nprotocol = \"windows\"\nwindows_s = [[10, 20.5]]\n")
    cfg = load_config(p)
    assert cfg.imu.time_offset_s == 1.0 and cfg.constraints.rate_hz == 5.0 and cfg.constraints.zupt is False
    assert [list(w) for w in cfg.outages.windows_s] == [[10.0, 20.5]]
    p.write_text("name = \"s\"\n[start]\nlat_deg = 45\nlon_deg = 7\n[imu]\nrate_hz = 100\n[[segment]]\n"
                 "type = \"accelerate\"\nspeed_m_s = \"5\"\nduration_s = 5\n")
    with pytest.raises(ConfigError, match=r"field 'segment\.0\.speed_m_s': \"5\" is text"):
        load_scenario(p)


def test_a_scenario_sensor_override_table_is_checked_too(tmp_path):
    """[imu.gyro] noise = "0.1" was 'internal error: TypeError', noise = true became 1.0 and 1e300 passed."""
    from inskit.simulation.scenario import load_scenario

    base = ("name = \"s\"\n[start]\nlat_deg = 45\nlon_deg = 7\n[imu]\nrate_hz = 100\n[imu.gyro]\n{}\n"
            "[[segment]]\ntype = \"static\"\nduration_s = 5\n")
    p = tmp_path / "s.toml"
    for line, said in (('noise = "0.1"', r'noise = "0\.1": expected a number'),
                       ("noise = true", r"noise = true: expected a number"),
                       ('fixed_bias = ["1", 2, 3]', r'fixed_bias = "1": expected a number'),
                       ("noise = 1e300", r"noise = 1e\+300 is beyond")):
        p.write_text(base.format(line))
        with pytest.raises(ConfigError, match=rf"field 'imu\.gyro': {said}"):
            load_scenario(p)


def test_a_literal_of_the_wrong_kind_names_its_choices(tmp_path):
    from inskit.jobs.config import load_config

    p = tmp_path / "c.toml"
    p.write_text("[imu]\nfile = \"a.csv\"\nrepeated_rows = true\n[gnss]\nfile = \"g.csv\"\n")
    with pytest.raises(ConfigError, match=r"field 'imu\.repeated_rows': true is a boolean; this setting takes one "
                                          r"of \"keep\", \"drop\""):
        load_config(p)


EXAMPLES = __import__("pathlib").Path(__file__).resolve().parents[1] / "examples"


@pytest.mark.parametrize("example, kind", [("car.toml", "scenario"), ("drive_0708.toml", "config"),
                                           ("walk_0827_tight.toml", "config"), ("study_mc_mems.toml", "study"),
                                           ("study_outage_grades.toml", "study"), ("static.toml", "scenario")])
def test_each_example_is_recognised_as_its_kind(example, kind):
    from inskit.config_files import toml_kind

    assert toml_kind(read_toml(EXAMPLES / example, kind)) == kind


@pytest.mark.parametrize("example, asked, said", [
    ("car.toml", "study", "this is a scenario file, which `inskit simulate` takes, not a study file"),
    ("drive_0708.toml", "scenario", "this is a navigate configuration, which `inskit navigate` takes, not a scenario"),
    ("study_mc_mems.toml", "config", "this is a study file, which `inskit study` takes, not a navigate configuration"),
])
def test_another_commands_file_is_named_as_such(example, asked, said):
    """`inskit study examples/car.toml` said "field 'scenario': Field required (and 9 more)"; every command that
    reads a TOML file took another's for a broken one of its own."""
    with pytest.raises(ConfigError) as e:
        read_toml(EXAMPLES / example, asked)
    assert str(e.value).startswith(f"{EXAMPLES / example}: {said}"), str(e.value)


def test_a_file_of_no_known_kind_goes_to_the_model(tmp_path):
    """Neither kind recognised (or two at once): read as asked, so the model's own message names the field."""
    from inskit.config_files import toml_kind

    p = tmp_path / "c.toml"
    p.write_text('name = "x"\n')
    assert read_toml(p, "study") == {"name": "x"} and toml_kind({"name": "x"}) is None
    both = {"segment": [], "imu": {"file": "a.csv"}}
    assert toml_kind(both) is None


def test_a_folder_given_as_a_config_file_is_said_to_be_one(tmp_path):
    """inskit.navigate('examples') said 'examples: no such config file' of a folder that exists; now it says it is
    a folder and names TOML files in it."""
    (tmp_path / "full").mkdir()
    (tmp_path / "full" / "drive.toml").write_text('name = "d"\n')
    with pytest.raises(ConfigError, match=r"is a folder; expected a config file \(a \.toml file, e\.g\. drive\.toml in"):
        read_toml(tmp_path / "full")
    (tmp_path / "empty").mkdir()
    with pytest.raises(ConfigError, match=r"empty: is a folder; expected a scenario file \(a \.toml file\)$"):
        read_toml(tmp_path / "empty", "scenario")
    with pytest.raises(ConfigError, match="absent.toml: no such config file"):
        read_toml(tmp_path / "absent.toml")
