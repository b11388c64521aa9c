"""``inskit spp`` (inskit.cli_gnss) and its job (inskit.jobs.spp).

The command is mounted on a bare click group the way ``inskit.cli``
registers it (``register(cli)``); the subprocess cases run it through
``inskit.cli.main`` to check the one-line errors and exit status 2.
"""

import json
import subprocess
import sys
from pathlib import Path

import click
import numpy as np
import pytest
from click.testing import CliRunner

from inskit.cli_gnss import register
from inskit.errors import InputError
from inskit.jobs.spp import run_spp, spp_throughput

DATA = Path(__file__).resolve().parent / "data" / "gnss"
OBS = DATA / "abpo0080_0000-0200.15o"
NAV = DATA / "abpo0080.15n"
ABPO_XYZ = (4097216.6805, 4429119.0287, -2065771.3676)
HARNESS = ("import sys\nfrom inskit import cli as C\nfrom inskit.cli_gnss import register\n"
           "register(C.cli)\nC.main(sys.argv[1:])\n")
KEYS = {"epochs_total", "epochs_solved", "epochs_excluded_sats", "horizontal_rms_m", "rms_3d_m", "mean_enu_m",
        "std_enu_m", "hdop_median", "n_sats_median", "seconds", "files"}


def group():
    g = click.Group()
    register(g)
    return g


def invoke(*args):
    return CliRunner().invoke(group(), ["spp", *map(str, args)])


def inskit(*args):
    return subprocess.run([sys.executable, "-c", HARNESS, "spp", *map(str, args)], capture_output=True, text=True,
                          check=False)


def test_json_summary_and_files(tmp_path):
    from inskit.io.csv_formats import read_gnss
    from inskit.io.rtklib import read_pos

    r = invoke(OBS, NAV, "--reference", "header", "--out", tmp_path / "o", "--json")
    assert r.exit_code == 0, r.output
    s = json.loads(r.stdout)                                    # exactly one JSON object, nothing else
    assert KEYS <= set(s)
    assert s["epochs_total"] == s["epochs_solved"] == 240
    # the header position is the surveyed one: the same figures as tests/test_gnss_spp.py's excerpt test
    assert s["horizontal_rms_m"] < 2.0 and s["rms_3d_m"] < 6.0
    np.testing.assert_allclose(s["reference_e"], ABPO_XYZ)
    names = sorted(Path(f).name for f in s["files"])
    assert names == ["spp.pos", "spp_epochs.csv", "spp_solution.csv", "summary.json"]
    g, _ = read_pos(tmp_path / "o" / "spp.pos", quality=(5,))
    fixes = read_gnss(tmp_path / "o" / "spp_solution.csv")
    assert len(g) == len(fixes) == 240
    np.testing.assert_allclose(fixes.time, g.time, atol=1e-3)    # both GPS seconds of week
    np.testing.assert_allclose(fixes.lla[:, 2], g.lla[:, 2], atol=1e-4)
    assert json.loads((tmp_path / "o" / "summary.json").read_text())["epochs_solved"] == 240
    epochs = (tmp_path / "o" / "spp_epochs.csv").read_text().splitlines()
    assert len(epochs) == 241 and "err_n_m" in epochs[0] and "status" in epochs[0]
    # an earlier run's files are not overwritten without --force
    r = invoke(OBS, NAV, "--out", tmp_path / "o")
    assert isinstance(r.exception, InputError) and "already exists" in str(r.exception)
    r = invoke(OBS, NAV, "--out", tmp_path / "o", "--force", "--json")
    assert r.exit_code == 0 and json.loads(r.stdout)["horizontal_rms_m"] is None   # no reference this time


def test_table_output_and_explicit_reference():
    r = invoke(OBS, NAV, "--reference", ",".join(map(str, ABPO_XYZ)), "--systems", "G", "--mask", "15")
    assert r.exit_code == 0, r.output
    assert "North" in r.stdout and "horizontal RMS" in r.stdout and "240 of 240 epochs solved" in r.stdout
    assert not r.stdout.lstrip().startswith("{")


def test_user_errors_are_one_line_with_exit_2(tmp_path):
    missing = tmp_path / "nope.15o"
    r = inskit(missing, NAV, "--json")
    assert r.returncode == 2 and r.stdout == ""
    assert r.stderr.count("\n") == 1 and "nope.15o" in r.stderr
    garbage = tmp_path / "garbage.15o"
    garbage.write_text("this is not a RINEX file\n" * 20)
    r = inskit(garbage, NAV, "--json")
    assert r.returncode == 2 and r.stdout == "" and r.stderr.count("\n") == 1 and "garbage.15o" in r.stderr
    r = inskit(OBS, NAV, "--reference", "1,2", "--json")
    assert r.returncode == 2 and "--reference" in r.stderr
    r = inskit(OBS, NAV, "--systems", "G,R")
    assert r.returncode == 2 and "--systems" in r.stderr


def test_job_refuses_a_reference_off_the_earth_and_bad_models():
    with pytest.raises(InputError, match="not on the Earth"):
        run_spp(OBS, NAV, reference=(1.0, 2.0, 3.0))
    with pytest.raises(ValueError, match="--iono"):
        run_spp(OBS, NAV, iono="nequick")


@pytest.mark.parametrize("mask", ["-5", "-0.5", "90", "120"])
def test_the_mask_takes_the_range_and_the_message_of_the_config(tmp_path, mask):
    """spp --mask took [-5, 90), the navigate config's [gnss] mask_deg (and the scenario's [raw_gnss]
    mask_deg, which took -5 too) [0, 90), each with its own words: now one range, one message."""
    from inskit.errors import ConfigError
    from inskit.jobs.config import config_from_dict
    from inskit.simulation.scenario import load_scenario

    r = inskit(OBS, NAV, "--mask", mask, "--json")
    assert r.returncode == 2 and r.stdout == "" and r.stderr.count("\n") == 1, r.stderr
    said = r.stderr.strip().removeprefix("inskit: error: --mask: ")
    assert said.startswith(f"{float(mask):g} is outside [0, 90) degrees: an elevation mask is"), r.stderr
    with pytest.raises(ConfigError) as e:
        config_from_dict({"imu": {"file": "i.csv"}, "gnss": {"coupling": "tight", "obs": "o", "nav": "n",
                                                            "mask_deg": float(mask)}}, source="c.toml")
    assert str(e.value) == f"c.toml: field 'gnss.mask_deg': {said}"
    sc = tmp_path / "s.toml"
    sc.write_text(f'name = "s"\n[start]\nlat_deg = 1\nlon_deg = 2\n[raw_gnss]\nmask_deg = {mask}\n'
                  '[[segment]]\ntype = "static"\nduration_s = 1\n')
    with pytest.raises(ConfigError) as e:
        load_scenario(sc)
    assert str(e.value) == f"{sc}: field 'raw_gnss.mask_deg': {said}"


def test_the_mask_from_the_horizon_up_is_taken():
    r = invoke(OBS, NAV, "--mask", "0", "--json")
    assert r.exit_code == 0, r.output
    assert json.loads(r.stdout)["epochs_solved"] == 240


def test_throughput_figure():
    """A benchmark figure, not a timing test: the dict is well formed."""
    b = spp_throughput(OBS, NAV, repeats=2)
    assert b["epochs"] == 240 and b["repeats"] == 2
    assert b["epochs_per_s_min"] <= b["epochs_per_s"] <= b["epochs_per_s_max"]


def test_health_verdict_counts_the_lost_epochs():
    from inskit.jobs.spp import spp_health

    base = {"epochs_total": 1000, "epochs_unsolved": 0, "epochs_flagged": 0, "epochs_excluded_sats": 0,
            "rms_residual_median_m": 1.0, "hdop_median": 1.0}
    assert spp_health(base) == {"verdict": "healthy", "reasons": [], "warnings": []}
    few = spp_health({**base, "epochs_unsolved": 50, "epochs_excluded_sats": 3})
    assert few["verdict"] == "healthy" and len(few["warnings"]) == 2 and "5.0 %" in few["warnings"][0]
    many = spp_health({**base, "epochs_flagged": 101})
    assert many["verdict"] == "unhealthy" and "101 of 1000 epochs (10.1 %) flagged" in many["reasons"][0]
    off = spp_health({**base, "rms_residual_median_m": 40.0, "hdop_median": 8.0})
    assert off["verdict"] == "healthy" and len(off["warnings"]) == 2
    # walk_0827 with four satellites at every epoch: 'healthy', 'raim' on and residuals of 1e-23 m, yet no epoch
    # could be checked; said now
    bare = spp_health({**base, "epochs_solved": 1000, "epochs_without_redundancy": 1000})
    assert bare["warnings"] == ["1000 of 1000 solved epochs (100.0 %) had no redundant range (as many satellites as "
                                "unknowns): the residual test and the satellite exclusion could not run there, so "
                                "their fixes are unchecked (their residuals are zero by construction)"]


def test_a_high_mask_run_is_unhealthy_and_strict_exits_3():
    good = inskit(OBS, NAV, "--reference", "header", "--json")
    assert good.returncode == 0 and json.loads(good.stdout)["health"]["verdict"] == "healthy"
    # a 40 deg mask leaves ABPO fewer than four satellites at many epochs
    r = inskit(OBS, NAV, "--mask", "40", "--strict", "--json")
    s = json.loads(r.stdout)  # still one JSON object
    assert r.returncode == 3, r.stderr
    assert s["health"]["verdict"] == "unhealthy" and s["epochs_unsolved"] > 0.1 * s["epochs_total"]
    assert "unhealthy:" in r.stderr


def test_a_receiver_clock_reset_is_named(tmp_path):
    """spp solves each epoch's clock on its own, so a 1 ms receiver clock
    reset costs nothing, but it was not said; now it is a note."""
    from test_jobs_navigate import _step_codes

    _step_codes(DATA / "gnss_1730_first40.obs", tmp_path / "o.obs", 20, -299792.458)
    s = run_spp(tmp_path / "o.obs", DATA / "gnss_1730.nav", systems="G")
    assert s["epochs_solved"] == 40
    assert any("clock jumps 1 time (-1.000 ms" in n and "o.obs" in n for n in s["notes"]), s["notes"]


def test_satellites_without_ephemeris_are_a_health_warning():
    """The walk excerpt's navigation file lacks every Galileo satellite and
    five GPS ones it observes: said in the notes, the summary and the health
    warnings (it was said nowhere)."""
    s = run_spp(DATA / "gnss_1730_first40.obs", DATA / "gnss_1730.nav")
    lost = s["satellites_without_ephemeris"]
    assert {"E07", "E26", "G18"} <= set(lost) and not {"G10", "G23", "G27", "G32"} & set(lost)
    assert any("without a usable ephemeris" in w and "E07" in w for w in s["health"]["warnings"])
    assert any("no record in the navigation file" in n for n in s["notes"])


def test_reproduce_tight_coupling_refuses_a_seed_the_walk_would_ignore(tmp_path, capsys):
    """`reproduce tight-coupling --experiment walk --seed 7` ran with the seed ignored (the walk is a real
    log); refused now, naming what it seeds, before anything is written."""
    from inskit.cli import main

    with pytest.raises(SystemExit) as exc:
        main(["reproduce", "tight-coupling", "--out", str(tmp_path / "tw"), "--experiment", "walk", "--seed", "7"])
    assert exc.value.code == 2
    assert "--seed would be ignored: it seeds the simulated blockage drive" in capsys.readouterr().err
    assert not (tmp_path / "tw").exists()


def test_a_moving_receiver_scored_against_one_reference_point_is_said(tmp_path):
    """`inskit spp obs.rnx nav.rnx --reference header` of a simulated drive (raw GNSS of a car at 15 m/s)
    printed 'horizontal RMS 1758.87 m, max horizontal 2977.10 m' as the fixes' errors, without a word: the
    header's APPROX POSITION is where the drive starts, and the errors were the car's travel.  Now a
    health warning says the receiver moves (its median Doppler speed, the fixes' spread); a static
    receiver (ABPO) is not warned."""
    from inskit import api

    scen = tmp_path / "drive.toml"
    scen.write_text('name = "drive"\n[start]\nlat_deg = 40\nlon_deg = -105\nheight_m = 1600\nspeed_m_s = 15\n'
                    '[imu]\nrate_hz = 10\n[raw_gnss]\n[[segment]]\ntype = "cruise"\nduration_s = 60\n')
    api.simulate(str(scen), 1, out_dir=tmp_path / "sim")
    s = run_spp(tmp_path / "sim" / "obs.rnx", tmp_path / "sim" / "nav.rnx", reference="header")
    m = s["reference_motion"]
    assert m["median_speed_m_s"] == pytest.approx(15.0, abs=0.5) and m["spread_m"] > 300.0
    said = [w for w in s["health"]["warnings"] if w.startswith("the receiver moves (median Doppler speed ")]
    assert len(said) == 1 and said[0].endswith("the errors against the one --reference point measure its travel, "
                                               "not the fixes' accuracy; score a moving receiver against its own "
                                               "track"), s["health"]["warnings"]
    still = run_spp(OBS, NAV, reference="header")
    assert still["reference_motion"]["spread_m"] < 10.0
    assert not [w for w in still["health"]["warnings"] if "receiver moves" in w]
    assert run_spp(OBS, NAV)["reference_motion"] is None
