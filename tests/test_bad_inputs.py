"""Issue 12 acceptance: every bad input, seen as a user sees it.

Each test runs the command a user types (``inskit.cli.main``, in process) on
a broken input and asserts three things: the exit code (2 for the user's
mistake, never 3, which means a bug in inskit), the one-line message (it names
the file and the line or the field, and says what was expected) and what is
on disk afterwards (no partial file under a final name, nothing overwritten).

The unit tests of the readers are elsewhere (tests/test_io.py,
tests/test_jobs_config.py, tests/test_gnss_rinex.py); here the end-to-end
path is checked once per case, on a 52 s simulated drive (20 s static, a 90
deg turn, cruise) made by the simulator in a module fixture.
"""

from __future__ import annotations

import gzip
import json
import os
import re
import shutil
from pathlib import Path

import numpy as np
import pytest

from inskit.units import G0

GNSS_DATA = Path(__file__).resolve().parent / "data" / "gnss"
OBS = GNSS_DATA / "abpo0080_0000-0200.15o"
NAV = GNSS_DATA / "abpo0080.15n"

SCENARIO = """name = "drive"
[start]
lat_deg = 45
lon_deg = 7
height_m = 300
[imu]
rate_hz = 100
grade = "industrial-mems"
[gnss]
rate_hz = 1
white_h_m = 0.5
white_v_m = 1.0
[[segment]]
type = "static"
duration_s = 20
[[segment]]
type = "accelerate"
speed_m_s = 10
duration_s = 5
[[segment]]
type = "turn"
angle_deg = 90
radius_m = 30
[[segment]]
type = "cruise"
duration_s = 20
"""


def run(capsys, *argv):
    """``inskit ARGV`` in process: (exit code, stdout, stderr)."""
    from inskit.cli import main

    old = np.geterr()
    try:
        with pytest.raises(SystemExit) as exc:
            main([str(a) for a in argv])
    finally:
        np.seterr(**old)  # main() silences numpy for the user; not for the other tests
    out, err = capsys.readouterr()
    return exc.value.code, out, err


def refused(result, *needles):
    """Exit 2, nothing on stdout, exactly one line ``inskit: error: ...``
    holding every needle (plain substrings), no traceback, no numpy repr."""
    code, out, err = result
    assert code == 2, err
    assert out == ""
    assert err.count("\n") == 1 and err.startswith("inskit: error: "), err
    for n in needles:
        assert n in err, f"{n!r} not in {err!r}"
    assert "Traceback" not in err and "np.float64" not in err
    return err


def empty_or_absent(folder):
    """Nothing under a final name: the folder is absent or empty."""
    folder = Path(folder)
    return not folder.exists() or not any(folder.iterdir())


@pytest.fixture(scope="module")
def sim(tmp_path_factory):
    """A simulated drive: imu.csv (increments), gnss.csv, truth.csv."""
    from inskit.cli import cli

    d = tmp_path_factory.mktemp("bad_inputs")
    (d / "s.toml").write_text(SCENARIO)
    cli.main(["simulate", str(d / "s.toml"), "--out", str(d / "sim"), "--no-plot"], standalone_mode=False)
    return d / "sim"


@pytest.fixture(scope="module")
def rates(sim):
    """The drive's IMU as rates [rad/s, m/s^2]: (time, w_b, f_b) without the first row."""
    import pandas as pd

    df = pd.read_csv(sim / "imu.csv")
    t = df["time_s"].to_numpy()
    dt = np.diff(t)[:, None]
    w = df[[f"dtheta_{a}_rad" for a in "xyz"]].to_numpy()[1:] / dt
    f = df[[f"dv_{a}_m_s" for a in "xyz"]].to_numpy()[1:] / dt
    return t[1:], w, f


def write_rates(path, t, w, f, gunit="rad_s", aunit="m_s2"):
    cols = ["time_s"] + [f"gyro_{a}_{gunit}" for a in "xyz"] + [f"accel_{a}_{aunit}" for a in "xyz"]
    np.savetxt(path, np.column_stack([t, w, f]), delimiter=",", header=",".join(cols), comments="", fmt="%.12g")
    return path


def lines_of(path):
    return Path(path).read_text().splitlines(True)


def navigate(capsys, sim, tmp_path, imu=None, gnss=None, *extra):
    return run(capsys, "navigate", "--imu", imu or sim / "imu.csv", "--gnss", gnss or sim / "gnss.csv",
               "--out", tmp_path / "nav", "--no-plots", *extra)


# --- 1. missing columns ---------------------------------------------------------------
def test_missing_columns(capsys, sim, tmp_path):
    rows = lines_of(sim / "imu.csv")
    bad = tmp_path / "imu.csv"
    bad.write_text("".join(",".join(r.rstrip("\n").split(",")[:-1]) + "\n" for r in rows))  # no dv_z_m_s
    err = refused(navigate(capsys, sim, tmp_path, imu=bad), str(bad), "no complete set of IMU columns",
                  "dv_{x,y,z}_m_s", "found time_s,")
    assert "dv_z_m_s" not in err.split("found")[1]
    assert empty_or_absent(tmp_path / "nav")
    g = tmp_path / "gnss.csv"
    g.write_text(lines_of(sim / "gnss.csv")[0].replace("sigma_d_m", "sigma_down") + "".join(lines_of(sim / "gnss.csv")[1:]))
    refused(navigate(capsys, sim, tmp_path, gnss=g), str(g), "missing column(s) sigma_d_m", "found time_s")
    assert empty_or_absent(tmp_path / "nav")


# --- 2. wrong units ---------------------------------------------------------------------
def test_accelerations_in_g_under_an_m_s2_header(capsys, sim, rates, tmp_path):
    t, w, f = rates
    bad = write_rates(tmp_path / "imu_g.csv", t, w, f / G0)  # values in g, header says m/s^2
    refused(navigate(capsys, sim, tmp_path, imu=bad), str(bad), "column 'accel_x_m_s2'",
            "looks like values in g", "rename the columns accel_*_g")
    assert empty_or_absent(tmp_path / "nav")
    # the same numbers under the right header are read (and navigate)
    good = write_rates(tmp_path / "imu_ok.csv", t, w, f / G0, aunit="g")
    code, out, err = navigate(capsys, sim, tmp_path, good, None, "--json")
    assert code == 0, err
    assert json.loads(out)["epochs"] == len(t)


def test_deg_s_under_a_rad_s_header_in_a_turn(capsys, sim, rates, tmp_path):
    t, w, f = rates
    bad = write_rates(tmp_path / "imu_deg.csv", t, np.degrees(w), f)  # the 90 deg turn: 13 deg/s for 7 s
    refused(navigate(capsys, sim, tmp_path, imu=bad), str(bad), "column 'gyro_x_rad_s'",
            "looks like values in deg/s", "gyro_*_deg_s")
    assert empty_or_absent(tmp_path / "nav")
    # mechanize says the same before writing anything
    out = tmp_path / "sol.csv"
    refused(run(capsys, "mechanize", bad, "--init", "45,7,300,0,0,0,0,0,0", "--out", out), "looks like values in deg/s")
    assert not out.exists()


# --- 3. time going back, repeated --------------------------------------------------------
@pytest.mark.parametrize("kind", ["back", "repeated"])
def test_time_going_back_or_repeated(capsys, sim, tmp_path, kind):
    rows = lines_of(sim / "imu.csv")
    i = 1000  # data row 999 sits on line 1001 (the header is line 1)
    cells = rows[i].split(",")
    prev_t = rows[i - 1].split(",")[0]
    cells[0] = prev_t if kind == "repeated" else str(float(prev_t) - 0.5)
    rows[i] = ",".join(cells)
    bad = tmp_path / "imu.csv"
    bad.write_text("".join(rows))
    expected = (f"line {i + 1}: duplicate timestamp time_s=" if kind == "repeated"
                else f"line {i + 1}: time_s={float(prev_t) - 0.5!r} goes back in time from line {i}")
    refused(navigate(capsys, sim, tmp_path, imu=bad), str(bad), expected)
    assert empty_or_absent(tmp_path / "nav")


def test_gnss_times_in_milliseconds_are_named(capsys, sim, tmp_path):
    """Fixes with time_s in ms (the IMU reader refuses an IMU log in ms, not fixes): navigate said only
    'overlaps 1 used GNSS fix(es) ... (mismatched time bases, or logs of different runs?)'.  Fixes with
    velocity are refused by the reader, which sees them move 1000 times slower than their velocity says;
    without velocity navigate's span test names the unit."""
    rows = lines_of(sim / "gnss.csv")
    bad = tmp_path / "gnss.csv"
    bad.write_text(rows[0] + "".join(",".join([repr(1000.0 * float(r.split(",")[0]))] + r.split(",")[1:])
                                     for r in rows[1:]))
    refused(navigate(capsys, sim, tmp_path, gnss=bad), str(bad), "its positions move 1",
            "times slower than its velocity columns say", "the time column holds milliseconds, not seconds")
    assert empty_or_absent(tmp_path / "nav")
    bad.write_text("".join(",".join(r.rstrip("\n").split(",")[:7]) + "\n" for r in bad.read_text().splitlines(True)))
    refused(navigate(capsys, sim, tmp_path, gnss=bad), "overlaps 1 used GNSS fix(es)", "; the fixes span 51000 s, "
            "986.3 times the IMU log's 51.71 s: is the fixes' time column in milliseconds (times must be seconds)?")
    assert empty_or_absent(tmp_path / "nav")


# --- 4. NaN and inf cells -----------------------------------------------------------------
@pytest.mark.parametrize("cell, shown", [("nan", "'nan'"), ("", "is empty"), ("inf", "has inf"),
                                         ("-1e999", "has '-1e999'"), ("1,2e-3", None)])
def test_nan_and_inf_cells(capsys, sim, tmp_path, cell, shown):
    rows = lines_of(sim / "imu.csv")
    cells = rows[500].rstrip("\n").split(",")
    cells[3] = cell  # dtheta_z_rad of line 501
    rows[500] = ",".join(cells) + "\n"
    bad = tmp_path / "imu.csv"
    bad.write_text("".join(rows))
    r = navigate(capsys, sim, tmp_path, imu=bad)
    if shown is None:  # a decimal comma makes one column too many: refused, not read shifted
        refused(r, str(bad), "line 501")
    else:
        refused(r, str(bad), "line 501: column 'dtheta_z_rad'", shown, "expected a finite number")
    assert empty_or_absent(tmp_path / "nav")


def test_a_blank_line_does_not_shift_the_line_of_a_later_message(capsys, sim, tmp_path):
    """The parsers skip a blank line: a NaN on line 501 after a blank line 300 was said to be on line 500."""
    rows = lines_of(sim / "imu.csv")
    cells = rows[499].rstrip("\n").split(",")
    cells[3] = "nan"  # dtheta_z_rad of the row shown on line 501 once the blank line is in
    rows[499] = ",".join(cells) + "\n"
    rows.insert(299, "\n")
    bad = tmp_path / "imu.csv"
    bad.write_text("".join(rows))
    assert bad.read_text().splitlines()[500].split(",")[3] == "nan"
    refused(navigate(capsys, sim, tmp_path, imu=bad), str(bad), "line 501: column 'dtheta_z_rad' has 'nan'")
    assert empty_or_absent(tmp_path / "nav")


def test_nan_in_a_gnss_file_and_a_solution(capsys, sim, tmp_path):
    rows = lines_of(sim / "gnss.csv")
    rows[10] = rows[10].replace(rows[10].split(",")[2], "NaN", 1)
    g = tmp_path / "gnss.csv"
    g.write_text("".join(rows))
    refused(navigate(capsys, sim, tmp_path, gnss=g), str(g), "line 11: column 'lon_deg'", "expected a finite number")
    rows = lines_of(sim / "truth.csv")
    rows[7] = rows[7].replace(rows[7].split(",")[3], "inf", 1)  # height_m
    t = tmp_path / "truth.csv"
    t.write_text("".join(rows))
    refused(run(capsys, "evaluate", sim / "truth.csv", t), str(t), "line 8: column 'height_m' has inf")


# --- 5. a gap in the IMU log: a warning, a health verdict, not an error --------------------------
def test_gap_in_the_imu_log_is_warned_and_judged(capsys, sim, tmp_path):
    rows = lines_of(sim / "imu.csv")
    t = np.array([float(r.split(",")[0]) for r in rows[1:]])
    keep = ~((t > 26.0) & (t <= 29.0))  # 3 s missing in the turn
    gap = tmp_path / "imu_gap.csv"
    gap.write_text(rows[0] + "".join(r for r, k in zip(rows[1:], keep) if k))
    code, out, err = navigate(capsys, sim, tmp_path, gap, None, "--json")
    assert code == 0, err
    assert re.search(r"warning: the IMU log has a gap of 3\.0\d* s at t = 26\.0", err), err
    s = json.loads(out)
    assert s["health"]["verdict"] == "unhealthy"
    assert any("IMU gap of 3.0" in x for x in s["health"]["reasons"])
    assert len(s["imu_gaps"]) == 1 and abs(s["imu_gaps"][0]["length_s"] - 3.01) < 1e-6  # 26.00 -> 29.01
    assert (tmp_path / "nav" / "summary.json").exists()
    # --strict makes the verdict the exit code (3), after writing every file
    code, out, err = navigate(capsys, sim, tmp_path, gap, None, "--force", "--strict")
    assert code == 3 and "health: unhealthy" in err
    assert json.loads((tmp_path / "nav" / "summary.json").read_text())["health"]["verdict"] == "unhealthy"
    # mechanize integrates through it, but says so
    code, out, err = run(capsys, "mechanize", gap, "--init", "45,7,300,0,0,0,0,0,0", "--json")
    assert code == 0 and re.search(r"gap of 3\.0\d* s at t = 26\.0", err), err


# --- 6. truncated and garbage CSV ---------------------------------------------------------------
def test_truncated_csv(capsys, sim, tmp_path):
    text = (sim / "imu.csv").read_text()
    cut = text[: text.index("\n", len(text) // 2) + 12]  # the last line stops after a few characters
    bad = tmp_path / "imu.csv"
    bad.write_text(cut)
    n_lines = cut.count("\n") + 1
    refused(navigate(capsys, sim, tmp_path, imu=bad), str(bad), f"line {n_lines}: has ",
            " fields, the header names 7: column", "is missing; expected a finite number; it is the last line and has "
            "no line end: the file seems cut short")
    assert empty_or_absent(tmp_path / "nav")
    # a header and nothing else
    bad.write_text(text.splitlines()[0] + "\n")
    refused(navigate(capsys, sim, tmp_path, imu=bad), str(bad), "has a header but no data rows")
    bad.write_text("")
    refused(navigate(capsys, sim, tmp_path, imu=bad), str(bad), "the file is empty")


@pytest.mark.parametrize("content, expected", [
    (bytes(range(256)) * 40, "line 1 holds NUL (zero) bytes, which no text holds: not a text file"),
    (b"\x89PNG\r\n\x1a\n" + np.random.default_rng(0).bytes(3000), "line 4 holds NUL (zero) bytes"),
    (b"<html><body>404 not found</body></html>\n", "has a header but no data rows"),
    ("time_s,dtheta_x_rad\n\u00e9t\u00e9,\u2603\n".encode(), "line 2: column 'time_s' has '\u00e9t\u00e9'"),
])
def test_garbage_csv(capsys, sim, tmp_path, content, expected):
    bad = tmp_path / "imu.csv"
    bad.write_bytes(content)
    refused(navigate(capsys, sim, tmp_path, imu=bad), str(bad), expected)
    assert empty_or_absent(tmp_path / "nav")
    out = tmp_path / "sol.csv"
    refused(run(capsys, "mechanize", bad, "--init", "45,7,300,0,0,0,0,0,0", "--out", out), str(bad), expected)
    assert not out.exists()


def test_a_file_saved_as_utf16_or_damaged_by_zero_bytes_is_named_as_such(capsys, sim, tmp_path):
    """Windows PowerShell's '>' saves UTF-16: navigate said 'not a readable CSV file ('utf-8' codec can't
    decode byte 0xff in position 0: invalid start byte)'.  A block of NUL bytes inside a truth file (a
    logger that lost power) was scored: pandas read '0.0123<NUL...>45' as 0.0123."""
    bad = tmp_path / "imu.csv"
    bad.write_bytes((sim / "imu.csv").read_text().replace("\n", "\r\n").encode("utf-16"))
    refused(navigate(capsys, sim, tmp_path, imu=bad), str(bad), "is UTF-16 text", "save it as UTF-8")
    assert empty_or_absent(tmp_path / "nav")
    lines = lines_of(sim / "truth.csv")
    lines[1000] = lines[1000][:30] + "\0" * 512 + lines[1000][30:]
    truth = tmp_path / "truth.csv"
    truth.write_text("".join(lines))
    refused(run(capsys, "evaluate", sim / "truth.csv", truth), str(truth), "line 1001 holds NUL (zero) bytes",
            "damaged in writing")


# --- 7. gzip under a .csv name, truncated gzip -------------------------------------------------------
def test_gzip_under_a_csv_name_is_read(capsys, sim, tmp_path):
    z = tmp_path / "imu.csv"
    z.write_bytes(gzip.compress((sim / "imu.csv").read_bytes()))
    code, out, err = run(capsys, "mechanize", z, "--init", "45,7,300,0,0,0,0,0,0", "--json")
    assert code == 0, err
    assert json.loads(out)["epochs"] == len(lines_of(sim / "imu.csv")) - 1
    data = z.read_bytes()
    z.write_bytes(data[: len(data) // 2])  # a download cut short
    refused(run(capsys, "mechanize", z, "--init", "45,7,300,0,0,0,0,0,0"), str(z), "a damaged gzip file", "cut short")
    z.write_bytes(data[:10] + bytes(b ^ 0x5A for b in data[10:]))  # corrupt data after a good gzip header
    refused(run(capsys, "mechanize", z, "--init", "45,7,300,0,0,0,0,0,0"), str(z), "a damaged gzip file",
            "its data is corrupt")  # was zlib's 'Error -3 while decompressing data', exit 3 (a bug)


# --- 8. semicolons -------------------------------------------------------------------------------------
def test_semicolon_separated_csv_gets_a_hint(capsys, sim, tmp_path):
    bad = tmp_path / "imu.csv"
    bad.write_text((sim / "imu.csv").read_text().replace(",", ";"))
    refused(navigate(capsys, sim, tmp_path, imu=bad), str(bad), "separated by ';'", "comma-separated")
    assert empty_or_absent(tmp_path / "nav")


# --- 9. TOML: NaN, wrong types, unknown keys ---------------------------------------------------------------
def config(tmp_path, sim, text):
    p = tmp_path / "c.toml"
    p.write_text(f'[imu]\nfile = "{sim / "imu.csv"}"\n[gnss]\nfile = "{sim / "gnss.csv"}"\n'
                 f'[output]\ndir = "{tmp_path / "nav"}"\nplots = false\n' + text)
    return p


@pytest.mark.parametrize("text, needles", [
    ("[noise]\ngyro_arw_deg_sqrt_h = nan\n", ["field 'noise.gyro_arw_deg_sqrt_h'", "not a finite number"]),
    ("[noise]\naccel_vrw_m_s_sqrt_h = -inf\n", ["field 'noise.accel_vrw_m_s_sqrt_h'", "not a finite number"]),
    ("[constraints]\nrate_hz = \"ten\"\n", ["field 'constraints.rate_hz'", "number"]),
    ("[filter]\nscheme = 3\n", ["field 'filter.scheme'"]),
    ("[filter]\nschme = \"open\"\n", ["field 'filter.schme'", "xtra"]),
    ("[nosie]\ngyro_arw_deg_sqrt_h = 0.1\n", ["field 'nosie'"]),
    ("[noise\n", ["not valid TOML", "line"]),
])
def test_bad_toml(capsys, sim, tmp_path, text, needles):
    cfg = config(tmp_path, sim, text)
    before = cfg.read_bytes()
    refused(run(capsys, "navigate", cfg), str(cfg), *needles)
    assert cfg.read_bytes() == before
    assert not (tmp_path / "nav").exists()  # refused before the output folder is made


# --- 10. impossible configuration ------------------------------------------------------------------------
@pytest.mark.parametrize("text, needles", [
    ('[init]\nmode = "given"\nlat_deg = 95\nlon_deg = 7\nheight_m = 300\nrpy_deg = [0, 0, 0]\n',
     ["field 'init'", "lat_deg 95", "outside [-90, 90]"]),
    ("[noise]\ngyro_arw_deg_sqrt_h = -0.3\n", ["field 'noise.gyro_arw_deg_sqrt_h'", "greater than 0"]),
    ("[init]\nsigma_pos_m = 0\n", ["field 'init.sigma_pos_m'", "greater than 0"]),
    # an angle beyond a full turn: a typo (370 for 37.0), taken modulo 360 without a word
    ("", ["field 'imu.mount_rpy_deg'", "pitch 370 is outside [-360, 360] degrees", "a typo"]),
    ('[init]\nmode = "given"\nlat_deg = 45\nlon_deg = 7\nheight_m = 300\nrpy_deg = [0, 0, -400]\n',
     ["field 'init.rpy_deg'", "yaw -400 is outside [-360, 360] degrees"]),
    ('[init]\nmode = "given"\nlat_deg = 45\nlon_deg = 700\nheight_m = 300\nrpy_deg = [0, 0, 0]\n',
     ["field 'init.lon_deg'", "700 is outside [-180, 360] degrees"]),
    # a height beyond 100 km, as the height log's readings: a pressure in Pa, millimetres, past the Earth's centre
    ('[init]\nmode = "given"\nlat_deg = 45\nlon_deg = 7\nheight_m = 300000\nrpy_deg = [0, 0, 0]\n',
     ["field 'init.height_m'", "300000 m is beyond +-100 km of the ellipsoid", "expected a height in metres"]),
    ("[height]\nheight_m = 101325\n", ["field 'height.height_m'", "101325 m is beyond +-100 km"]),
])
def test_impossible_navigate_configuration(capsys, sim, tmp_path, text, needles):
    cfg = config(tmp_path, sim, text)
    if "imu.mount_rpy_deg" in needles[0]:
        cfg.write_text(cfg.read_text().replace("[gnss]", "mount_rpy_deg = [0, 370, 0]\n[gnss]", 1))
    refused(run(capsys, "navigate", cfg), str(cfg), *needles)
    assert not (tmp_path / "nav").exists()


@pytest.mark.parametrize("argv, needles", [
    (["align", "{imu}", "--lat", "45", "--mount-rpy", "0,370,0"],
     ["--mount-rpy: pitch 370 is outside [-360, 360] degrees", "a typo"]),
    (["mechanize", "{imu}", "--init", "45,7,300,0,0,0,0,0,400", "--out", "{out}"],
     ["--init: yaw 400 is outside [-360, 360] degrees"]),
])
def test_an_angle_beyond_a_full_turn_on_the_command_line(capsys, sim, tmp_path, argv, needles):
    """The command-line angles are held to the config keys' range: a typo (370 for 37.0) was taken modulo 360."""
    out = tmp_path / "sol.csv"
    refused(run(capsys, *[a.format(imu=sim / "imu.csv", out=out) for a in argv]), *needles)
    assert not out.exists()


@pytest.mark.parametrize("argv, needles", [
    (["mechanize", "{imu}", "--init", "45,7,1e9,0,0,0,0,0,0", "--out", "{out}"],
     ["--init: height_m 1e+09 m is beyond +-100 km of the ellipsoid", "expected a height in metres"]),
    (["mechanize", "{imu}", "--init", "45,7,-1e7,0,0,0,0,0,0", "--out", "{out}"],
     ["--init: height_m -1e+07 m is beyond +-100 km"]),
    (["mechanize", "{imu}", "--init-from", "{truth}", "--height", "hold", "--height-ref", "101325", "--out", "{out}"],
     ["--height-ref: 101325 m is beyond +-100 km of the ellipsoid: a pressure or another unit?"]),
])
def test_a_height_beyond_100_km_on_the_command_line(capsys, sim, tmp_path, argv, needles):
    """`mechanize --height hold --height-ref 101325` (a pressure in Pa) held the height at 101 km and exit 0,
    `--init 45,7,-1e7,...` started 3600 km past the Earth's centre: the constant height was taken unchecked
    where a height log holding the same number is refused."""
    out = tmp_path / "sol.csv"
    refused(run(capsys, *[a.format(imu=sim / "imu.csv", truth=sim / "truth.csv", out=out) for a in argv]), *needles)
    assert not out.exists()


@pytest.mark.parametrize("old, new, needles", [
    ("lat_deg = 45", "lat_deg = 95", ["field 'start.lat_deg'", "less than or equal to 90"]),
    ("white_h_m = 0.5", "white_h_m = -0.5", ["field 'gnss.white_h_m'", "greater than or equal to 0"]),
    ("rate_hz = 100", "rate_hz = nan", ["field 'imu.rate_hz'", "not a finite number"]),
    # a key its segment type would ignore, both of a pair, a speed change the wrong way, a climb that is none
    ('type = "cruise"\nduration_s = 20', 'type = "cruise"\nduration_s = 20\nradius_m = 5',
     ["segment 4 (cruise): radius_m is not a key of a cruise segment", "takes duration_s"]),
    ("radius_m = 30", "radius_m = 30\nrate_deg_s = 1", ["segment 3 (turn): give rate_deg_s or radius_m, not both"]),
    ('type = "accelerate"', 'type = "decelerate"',
     ["segment 2 (decelerate): speed_m_s 10 is not below the current speed 0 m/s"]),
    ('type = "cruise"\nduration_s = 20', 'type = "climb"\nangle_deg = 200\nduration_s = 20',
     ["segment 4 (climb): angle_deg 200", "|angle_deg| must be below 90"]),
    # an outage window that is none; motion faster than the IMU samples
    ("white_v_m = 1.0", "white_v_m = 1.0\noutages_s = [[20, 10]]",
     ["field 'gnss.outages_s'", "window 1 [20, 10] ends before it starts"]),
    ('type = "cruise"\nduration_s = 20', 'type = "coning"\namplitude_deg = 1\nfrequency_hz = 200\nduration_s = 2',
     ["segment 4 (coning): frequency_hz 200 Hz is at or above the Nyquist frequency", "imu.rate_hz 100"]),
    ('[[segment]]\ntype = "static"', ('[[vibration]]\ntarget = "down"\namplitude = 0.001\nfrequency_hz = 60\n'
                                      '[[segment]]\ntype = "static"'),
     ["vibration 1 (down, sinusoidal): frequency_hz 60 Hz", "Nyquist"]),
    # angles beyond a full turn (a turn's angle_deg is a heading change and may be more)
    ("grade = \"industrial-mems\"", "grade = \"industrial-mems\"\nmount_rpy_deg = [370, 0, 0]",
     ["field 'imu.mount_rpy_deg'", "roll 370 is outside [-360, 360] degrees"]),
    ("height_m = 300", "height_m = 300\nyaw_deg = 450", ["field 'start.yaw_deg'", "450 is outside [-360, 360]"]),
    ("lon_deg = 7", "lon_deg = -190", ["field 'start.lon_deg'", "-190 is outside [-180, 360]"]),
    ("height_m = 300", "height_m = 300000", ["field 'start.height_m'", "300000 m is beyond +-100 km"]),
    ('type = "cruise"\nduration_s = 20', 'type = "roll"\namplitude_deg = 3600\nduration_s = 20',
     ["field 'segment.3.amplitude_deg'", "3600 is outside [-360, 360]"]),
    ('[[segment]]\ntype = "static"', ('[[vibration]]\ntarget = "yaw"\namplitude = 500\nfrequency_hz = 1\n'
                                      '[[segment]]\ntype = "static"'),
     ["vibration 1 (yaw, sinusoidal): amplitude 500 is outside [-360, 360] degrees"]),
])
def test_impossible_scenario(capsys, tmp_path, old, new, needles):
    sc = tmp_path / "s.toml"
    sc.write_text(SCENARIO.replace(old, new, 1))
    refused(run(capsys, "simulate", sc, "--out", tmp_path / "o", "--no-plot"), str(sc), *needles)
    assert empty_or_absent(tmp_path / "o")


def test_impossible_command_line_values(capsys, sim, tmp_path):
    out = tmp_path / "sol.csv"
    refused(run(capsys, "mechanize", sim / "imu.csv", "--init", "95,7,300,0,0,0,0,0,0", "--out", out), "latitude")
    assert not out.exists()
    refused(run(capsys, "navigate", "--imu", sim / "imu.csv", "--gnss", sim / "gnss.csv", "--lever-arm", "0,0",
                "--out", tmp_path / "nav"), "--lever-arm", "expected 3 finite")
    assert empty_or_absent(tmp_path / "nav")
    # a non-finite number is refused by the option's name, not by the config field it would set
    refused(run(capsys, "navigate", "--imu", sim / "imu.csv", "--gnss", sim / "gnss.csv", "--lever-arm", "nan,0,0",
                "--out", tmp_path / "nav"), "--lever-arm", "'nan,0,0'")
    refused(run(capsys, "mechanize", sim / "imu.csv", "--init", "45,7,300,0,0,0,0,0,inf", "--out", out),
            "--init", "finite")
    assert empty_or_absent(tmp_path / "nav") and not out.exists()


@pytest.mark.parametrize("method", ["accel", "gyro", "fine"])
def test_an_option_the_method_would_ignore_is_refused(capsys, sim, method):
    """`align IMU --lat 45 --method fine --m 0.5` ran the fine alignment and said nothing of the blending gain
    it had been given (--m is read by --method blend only), as mechanize refuses --height-ref with --height free."""
    refused(run(capsys, "align", sim / "imu.csv", "--lat", "45", "--method", method, "--m", "0.5"),
            f"--m 0.5 would be ignored: it is the blending gain of --method blend, and --method {method} blends "
            "nothing; drop --m, or give --method blend")


# --- 11. results already there, --out equal to an input, unwritable output --------------------------------
def test_force_never_turns_an_input_into_an_output(capsys, sim, tmp_path):
    """`spp OBS NAV --out D --force` with OBS = D/spp.pos replaced the
    observations by the solution; `gyrofree navigate D/rates.csv --out D
    --force` replaced the array by the rates.  --force lifts only the
    refusal of an existing file, never that of an input."""
    import gzip
    import shutil

    root = Path(__file__).resolve().parents[1]
    d = tmp_path / "spp"
    d.mkdir()
    obs = d / "spp.pos"
    with gzip.open(root / "data" / "abpo" / "abpo0080.15o.gz") as f, open(obs, "wb") as g:
        shutil.copyfileobj(f, g)
    size = obs.stat().st_size
    refused(run(capsys, "spp", obs, root / "data" / "abpo" / "abpo0080.15n.gz", "--out", d, "--force"),
            "spp.pos", "is an input of this command")
    assert obs.stat().st_size == size
    g = tmp_path / "gf"
    assert run(capsys, "gyrofree", "simulate", "source003", "--out", g, "--rate", "100")[0] == 0
    shutil.copy(g / "array.csv", g / "rates.csv")
    before = (g / "rates.csv").read_bytes()
    refused(run(capsys, "gyrofree", "navigate", g / "rates.csv", "--out", g, "--force", "--init-from",
                g / "truth.csv"), "rates.csv", "is an input of this command")
    assert (g / "rates.csv").read_bytes() == before


def test_report_never_writes_over_the_fix_file_it_reads(capsys, sim, tmp_path):
    """`report RUN --out GNSS.csv --force`, GNSS.csv the fix file the run's
    configuration names (the report reads it for the track), replaced the
    user's fixes by the HTML page: only the run folder's own files counted
    as inputs."""
    gnss = tmp_path / "gnss.csv"
    shutil.copy(sim / "gnss.csv", gnss)
    before = gnss.read_bytes()
    assert navigate(capsys, sim, tmp_path, None, gnss)[0] == 0
    refused(run(capsys, "report", tmp_path / "nav", "--out", gnss, "--force"), str(gnss),
            "is an input of this command")
    assert gnss.read_bytes() == before
    assert not (tmp_path / "nav" / "report.html").exists()


def test_an_output_folder_with_results_needs_force(capsys, sim, tmp_path):
    code, _, err = navigate(capsys, sim, tmp_path)
    assert code == 0, err
    summary = tmp_path / "nav" / "summary.json"
    before = {p.name: p.read_bytes() for p in (tmp_path / "nav").iterdir()}
    refused(navigate(capsys, sim, tmp_path), str(tmp_path / "nav"), "already holds results", "--force")
    assert {p.name: p.read_bytes() for p in (tmp_path / "nav").iterdir()} == before
    assert json.loads(summary.read_text())["files"]
    # simulate refuses to overwrite its own earlier files
    sc = tmp_path / "s.toml"
    sc.write_text(SCENARIO)
    assert run(capsys, "simulate", sc, "--out", tmp_path / "sim", "--no-plot")[0] == 0
    before = {p.name: p.read_bytes() for p in (tmp_path / "sim").iterdir()}
    refused(run(capsys, "simulate", sc, "--out", tmp_path / "sim", "--no-plot", "--seed", "1"),
            "refusing to overwrite")
    assert {p.name: p.read_bytes() for p in (tmp_path / "sim").iterdir()} == before


def test_out_equal_to_an_input(capsys, sim, tmp_path):
    imu = tmp_path / "imu.csv"
    shutil.copy(sim / "imu.csv", imu)
    before = imu.read_bytes()
    refused(run(capsys, "mechanize", imu, "--init", "45,7,300,0,0,0,0,0,0", "--out", imu, "--force"),
            str(imu), "is an input of this command")
    assert imu.read_bytes() == before
    # navigate into the folder that holds its inputs under the names it writes
    d = tmp_path / "run"
    d.mkdir()
    shutil.copy(sim / "gnss.csv", d / "solution_forward.csv")
    refused(run(capsys, "navigate", "--imu", imu, "--gnss", d / "solution_forward.csv", "--out", d, "--force",
                "--no-plots"), str(d / "solution_forward.csv"), "would overwrite an input")
    assert (d / "solution_forward.csv").read_bytes() == (sim / "gnss.csv").read_bytes()
    assert sorted(p.name for p in d.iterdir()) == ["solution_forward.csv"]


@pytest.mark.parametrize("role, name", [("gnss", "innovations.csv"), ("truth", "solution_forward.csv"),
                                        ("truth", "solution_smoothed.parquet"), ("gnss", "config_used.json"),
                                        ("gnss", "track.png"), ("previous", "gnss_old.csv")])
def test_navigate_never_overwrites_any_of_its_inputs_even_with_force(capsys, sim, tmp_path, role, name):
    """`inskit navigate --gnss run/innovations.csv --truth run/solution_forward.csv --out run --force` read the
    fixes and the truth and then replaced both with its own innovations and solution: only five names (the
    solutions and summary.json) were checked against the IMU, fixes and RINEX files, not the innovations,
    config_used.json, the plots or report.html, nor the truth, odometer, height or speed-and-course files,
    nor the files --force removes as an earlier run's.  Every output, and every file --force would clear,
    is checked against every input now."""
    d = tmp_path / "run"
    d.mkdir()
    gnss, truth = sim / "gnss.csv", None
    if role == "previous":  # an earlier run there listed the file this run now reads
        (d / "summary.json").write_text(json.dumps({"files": [str(d / name)]}))
        shutil.copy(sim / "gnss.csv", d / name)
        gnss = d / name
    elif role == "gnss":
        shutil.copy(sim / "gnss.csv", d / name)
        gnss = d / name
    else:
        shutil.copy(sim / "truth.csv", d / name)
        truth = d / name
    before = {p.name: p.read_bytes() for p in d.iterdir()}
    extra = ("--truth", truth) if truth is not None else ()
    refused(run(capsys, "navigate", "--imu", sim / "imu.csv", "--gnss", gnss, "--out", d, "--force", *extra),
            str(d / name), "would overwrite an input of this run", "--force replaces results, never what the run "
            "reads")
    assert {p.name: p.read_bytes() for p in d.iterdir()} == before


@pytest.mark.skipif(os.name != "posix" or os.geteuid() == 0, reason="root writes into a read-only folder")
def test_read_only_output_folder(capsys, sim, tmp_path):
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o555)
    try:
        refused(run(capsys, "navigate", "--imu", sim / "imu.csv", "--gnss", sim / "gnss.csv", "--out", ro / "nav",
                    "--no-plots"), str(ro / "nav"), "not writable")
        assert not (ro / "nav").exists()
    finally:
        ro.chmod(0o755)


def test_output_folder_under_a_file(capsys, sim, tmp_path):
    """Runs as root too: a folder cannot be made under a regular file."""
    f = tmp_path / "afile"
    f.write_text("mine\n")
    refused(run(capsys, "navigate", "--imu", sim / "imu.csv", "--gnss", sim / "gnss.csv", "--out", f / "nav",
                "--no-plots"), f"{f}: is a file; expected an output folder (so {f / 'nav'} cannot be made)")
    assert f.read_text() == "mine\n"
    refused(run(capsys, "mechanize", sim / "imu.csv", "--init", "45,7,300,0,0,0,0,0,0", "--out", f / "sol.csv"),
            "is a file; expected an output folder")
    # simulate checked its folder only once the simulation was done: '[Errno 20] Not a directory'
    (tmp_path / "s.toml").write_text(SCENARIO)
    refused(run(capsys, "simulate", tmp_path / "s.toml", "--out", f / "sim", "--no-plot"),
            f"{f}: is a file; expected an output folder")
    # a config's [output] dir that is a file: '[Errno 20] Not a directory' from listing it
    (tmp_path / "nav.toml").write_text(f'[imu]\nfile = "{sim / "imu.csv"}"\n[gnss]\nfile = "{sim / "gnss.csv"}"\n'
                                       f'[output]\ndir = "{f}"\n')
    refused(run(capsys, "navigate", tmp_path / "nav.toml", "--no-plots"), f"{f}: is a file; expected an output folder")
    assert f.read_text() == "mine\n"


def test_an_output_file_under_a_file_is_refused_before_the_work(capsys, sim, tmp_path):
    """An output file (not folder) under a regular file: evaluate --plot said '[Errno 20] Not a directory:
    .../.part-123-x.png' after the work, its --per-epoch file already written; --per-epoch '[Errno 17] File
    exists'; allan --plot and report --out the same.  Now refused first, naming the file in the way."""
    f = tmp_path / "afile"
    f.write_text("mine\n")
    truth = sim / "truth.csv"
    pe = tmp_path / "err.csv"
    for argv, name in ((["evaluate", truth, truth, "--per-epoch", pe, "--plot", f / "x.png"], "x.png"),
                       (["evaluate", truth, truth, "--per-epoch", f / "x.csv"], "x.csv"),
                       (["allan", sim / "imu.csv", "--plot", f / "x.png"], "x.png")):
        refused(run(capsys, *argv), f"{f}: is a file; expected an output folder (so {f / name} cannot be written)")
    assert not pe.exists() and f.read_text() == "mine\n"
    assert navigate(capsys, sim, tmp_path)[0] == 0
    refused(run(capsys, "report", tmp_path / "nav", "--out", f / "r.html"),
            f"{f}: is a file; expected an output folder (so {f / 'r.html'} cannot be written)")


def test_unsupported_plot_extension_is_a_user_error(capsys, sim, tmp_path):
    plot = tmp_path / "err.xyz"
    refused(run(capsys, "evaluate", sim / "truth.csv", sim / "truth.csv", "--plot", plot), str(plot),
            "unsupported plot format '.xyz'", ".png")
    assert not plot.exists()


# --- 12. RINEX: truncated, garbage (inskit spp) -----------------------------------------------------------
def spp(capsys, obs, nav, out):
    return run(capsys, "spp", obs, nav, "--out", out)


def test_truncated_rinex_obs(capsys, tmp_path):
    lines = OBS.read_text().splitlines(True)
    # cut inside the satellite lines of an epoch: the epoch line promises more than the file holds
    epoch = next(i for i, s in enumerate(lines) if re.match(r"^ 15  1  8  1 30  0\.0000000  0", s))
    cut = tmp_path / "cut.15o"
    cut.write_text("".join(lines[: epoch + 3]))
    err = refused(spp(capsys, cut, NAV, tmp_path / "o"), str(cut), "the file ends inside the epoch",
                  "satellite records", "truncated file?")
    assert f"line {epoch + 3}: " in err and f"starting at line {epoch + 1}" in err, err
    assert empty_or_absent(tmp_path / "o")
    # a header cut before END OF HEADER
    cut.write_text("".join(lines[:10]))
    refused(spp(capsys, cut, NAV, tmp_path / "o"), str(cut), "END OF HEADER")
    assert empty_or_absent(tmp_path / "o")


def test_truncated_rinex_nav(capsys, tmp_path):
    lines = NAV.read_text().splitlines(True)
    head = next(i for i, s in enumerate(lines) if "END OF HEADER" in s)
    cut = tmp_path / "cut.15n"
    cut.write_text("".join(lines[: head + 1 + 8 * 20 + 3]))  # 20 whole records and 3 lines of the 21st
    refused(spp(capsys, OBS, cut, tmp_path / "o"), str(cut), f"line {head + 1 + 8 * 20 + 3}: the file ends "
            f"inside the record starting at line {head + 1 + 8 * 20 + 1} (expected 8 lines)")
    assert empty_or_absent(tmp_path / "o")


@pytest.mark.parametrize("content", [b"this is not a RINEX file\n" * 30, bytes(range(256)) * 8, b""])
def test_garbage_rinex(capsys, tmp_path, content):
    bad = tmp_path / "bad.15o"
    bad.write_bytes(content)
    for obs, nav in ((bad, NAV), (OBS, bad)):
        refused(spp(capsys, obs, nav, tmp_path / "o"), str(bad), "line 1: not a RINEX file",
                "'RINEX VERSION / TYPE'")
    assert empty_or_absent(tmp_path / "o")


def test_an_elevation_mask_below_the_horizon_is_refused_as_the_config_refuses_it(capsys, sim, tmp_path):
    """spp --mask -5 was taken, [gnss] mask_deg = -5 refused in other words: one range [0, 90), one message."""
    said = "-5 is outside [0, 90) degrees: an elevation mask is an elevation from the horizon"
    refused(run(capsys, "spp", OBS, NAV, "--mask", "-5", "--out", tmp_path / "o"), f"--mask: {said}")
    assert empty_or_absent(tmp_path / "o")
    cfg = config(tmp_path, sim, "")
    cfg.write_text(cfg.read_text().replace(f'[gnss]\nfile = "{sim / "gnss.csv"}"',
                                           f'[gnss]\ncoupling = "tight"\nobs = "{OBS}"\nnav = "{NAV}"\nmask_deg = -5'))
    refused(run(capsys, "navigate", cfg), str(cfg), f"field 'gnss.mask_deg': {said}")


@pytest.mark.parametrize("address, said", [
    ("foo", "missing port number"), ("tcp://host:99999", "port 99999 is outside 1..65535"),
    ("tcp://:8786", "no host"), ("tcp://host:abc", "its port is not a number")])
def test_a_scheduler_address_that_names_no_scheduler_is_refused_before_anything_is_written(
        capsys, tmp_path, address, said):
    """`study SPEC --out D --scheduler foo` was 'internal error: ValueError: missing port number in address
    'foo'' (exit 3), after D/study.json was written; port 99999 waited 20 s to say it could not connect."""
    spec = tmp_path / "study.toml"
    spec.write_text(f'scenario = "{Path(__file__).resolve().parents[1] / "examples" / "car.toml"}"\n'
                    'kind = "monte-carlo"\nruns = 2\nduration_s = 100.0\n')
    refused(run(capsys, "study", spec, "--out", tmp_path / "out", "--scheduler", address),
            f"--scheduler {address}: not a scheduler address ({said}", "tcp://host:8786")
    assert empty_or_absent(tmp_path / "out")


def test_click_usage_errors_are_exit_2_too(capsys, sim):
    """Not an inskit message but click's (usage + error), still exit 2 and no traceback."""
    from inskit.cli import main

    with pytest.raises(SystemExit) as e:
        main(["mechanize", str(sim / "imu.csv"), "--frame", "polar"])
    err = capsys.readouterr().err
    assert e.value.code == 2 and "Invalid value for '--frame'" in err and "Traceback" not in err


# --- 13. a full disk, an interrupt: no partial file under a final name ------------------------------------
@pytest.mark.parametrize("failure", ["disk full", "ctrl-c"])
def test_a_write_that_fails_halfway_leaves_no_partial_file(capsys, sim, tmp_path, monkeypatch, failure):
    """The innovations file (written after the forward solution) fails half
    written: its name never appears, nor the summary.json that marks a complete run."""
    import errno

    import pyarrow.csv as pcsv

    real = pcsv.write_csv  # the vectorised writer of inskit.files.write_csv_fast

    def failing(table, out, *a, **k):
        if "innovations" in str(getattr(out, "name", "")):
            out.write(b"time_s,half a line")
            if failure == "disk full":
                raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
            raise KeyboardInterrupt
        return real(table, out, *a, **k)

    monkeypatch.setattr(pcsv, "write_csv", failing)
    code, _, err = navigate(capsys, sim, tmp_path)
    nav = tmp_path / "nav"  # the run's files land as a set: none of them, and no folder the run made
    names = sorted(p.name for p in nav.iterdir()) if nav.exists() else []
    assert names == [], names
    assert not [n for n in names if n.startswith(".part-")]
    if failure == "disk full":
        assert code == 2 and err.count("\n") == 1, err
        assert f"{tmp_path / 'nav' / 'innovations.csv'}: could not be written (No space left on device)" in err
    else:
        assert code == 130 and err.strip() == "inskit: aborted", err


# --- 14. defects the property tests found (tests/test_property_readers.py), seen from the CLI --------------
def test_a_repeated_line_in_a_nav_record_is_refused_not_read_shifted(capsys, tmp_path):
    """A record of 9 lines used to be read as its first 8: sqrt(A) came from
    the line above (M0 = -1.81) and the orbit was silently wrong."""
    lines = NAV.read_text().splitlines(True)
    head = next(i for i, s in enumerate(lines) if "END OF HEADER" in s)
    bad = tmp_path / "dup.15n"
    bad.write_text("".join(lines[: head + 3] + lines[head + 2:]))  # line 2 of the first record, twice
    refused(spp(capsys, OBS, bad, tmp_path / "o"), str(bad), f"line {head + 10}: the record starting at line "
            f"{head + 2} has 9 lines, expected 8", "repeated")
    assert empty_or_absent(tmp_path / "o")
    blank = tmp_path / "blank.15n"
    rec = lines[head + 3]
    lines[head + 3] = rec[:60] + " " * 19 + rec[79:]  # sqrt(A) of the first record left blank
    blank.write_text("".join(lines))
    refused(spp(capsys, OBS, blank, tmp_path / "o"), str(blank), f"line {head + 2}: ", "sqrt")


@pytest.mark.parametrize("where", ["observation", "clock"])
def test_an_infinite_or_garbled_rinex_field_names_its_line(capsys, tmp_path, where):
    """'1E999' in an observation was read as inf; junk in the receiver-clock
    field of an epoch line was a bare ValueError (exit 3)."""
    lines = (GNSS_DATA / "gnss_1730_first40.obs").read_text().splitlines(True)
    ep = next(i for i, s in enumerate(lines) if s.startswith(">"))
    if where == "observation":
        s = lines[ep + 1]
        lines[ep + 1] = s[:3] + "         1E999" + s[17:]  # the first observation field (F14.3)
        needle = f"line {ep + 2}: columns 4-17: expected a finite number"
    else:
        s = lines[ep].rstrip("\n").ljust(56)
        lines[ep] = s[:41] + "  \x00garbage\x00    " + s[56:] + "\n"
        needle = f"line {ep + 1}: columns 42-56: expected the receiver clock offset (a finite number) or blanks"
    bad = tmp_path / "bad.obs"
    bad.write_text("".join(lines))
    refused(spp(capsys, bad, GNSS_DATA / "gnss_1730.nav", tmp_path / "o"), str(bad), needle)
    assert empty_or_absent(tmp_path / "o")


def test_an_rtklib_pos_latitude_beyond_the_pole_is_refused(capsys, sim, tmp_path):
    """read_pos accepted latitude 91 deg (and inf, reported without the file name)."""
    pos = tmp_path / "sol.pos"
    head = "%  GPST                  latitude(deg) longitude(deg)  height(m)   Q  ns   sdn(m)   sde(m)   sdu(m)\n"
    row = "2025/08/27 17:30:{s:06.3f}   {lat}  7.0000000  300.000   1   8   0.0100   0.0100   0.0300\n"
    for lat, shown in (("91.0000000", "'91.0000000'; expected a value in [-90, 90] degrees"),
                       ("inf", "'inf'; expected a finite number")):
        pos.write_text(head + "".join(row.format(s=float(i), lat=lat if i == 2 else "45.0000000") for i in range(5)))
        refused(run(capsys, "navigate", "--imu", sim / "imu.csv", "--gnss", pos, "--gnss-format", "rtklib-pos",
                    "--out", tmp_path / "nav", "--no-plots"), str(pos), "line 4: column 'latitude(deg)' has " + shown)
        assert empty_or_absent(tmp_path / "nav")


def test_rtklib_pos_rows_without_their_header_are_named_as_such(capsys, sim, tmp_path):
    """navigate --gnss rows.pos (the default [gnss] format "inskit") said 'missing column(s) time_s, lat_deg,
    ...; found 2025/08/27 17:30:00.000 45.0000000 7.0000000 ...; the file looks like the 'rtklib-pos' format',
    and with --gnss-format rtklib-pos 'not an RTKLIB .pos file'."""
    pos = tmp_path / "rows.pos"
    row = "2025/08/27 17:30:{s:06.3f}   45.0000000  7.0000000  300.000   1   8   0.0100   0.0100   0.0300   0.0000" \
          "   0.0000   0.0000   0.00    0.0\n"
    pos.write_text("".join(row.format(s=float(i)) for i in range(5)))
    for fmt in ((), ("--gnss-format", "rtklib-pos")):
        err = refused(run(capsys, "navigate", "--imu", sim / "imu.csv", "--gnss", pos, *fmt, "--out", tmp_path / "nav",
                          "--no-plots"), str(pos), "holds RTKLIB .pos solution rows ('2025/08/27 17:30:00.000' ...) "
                      "but no '%' column header line above them", "if the times are GPST, put RTKLIB's header line "
                      "for these 15 fields first: '%  GPST  latitude(deg)")
        assert ("then set [gnss] format = \"rtklib-pos\"" in err) == (not fmt)
        assert empty_or_absent(tmp_path / "nav")


def test_rates_near_the_float_limit_do_not_slip_past_the_unit_check(capsys, sim, rates, tmp_path):
    """Gyro values of 1e300 under a rad/s header overflowed the norm to inf;
    the NaN percentiles then passed every rule and the log was accepted."""
    t, w, f = rates
    w = w.copy()
    w[:, 0] = 1e300
    bad = write_rates(tmp_path / "imu_huge.csv", t, w, f)
    refused(navigate(capsys, sim, tmp_path, imu=bad), str(bad), "column 'gyro_x_rad_s': angular rates reach 1e+300 "
            "rad/s")
    assert empty_or_absent(tmp_path / "nav")


def test_an_outage_window_with_no_fix_in_it_is_reported(capsys, sim, tmp_path):
    """A window past the end of the GNSS file withholds nothing: the run says
    which outage was not scored and why, in its warnings and its JSON."""
    code, out, err = navigate(capsys, sim, tmp_path, None, None, "--outages", "windows:20-30,9000-9010", "--json")
    assert code == 0, err
    s = json.loads(out)
    assert [u["k"] for u in s["outages_unscored"]] == [1] and s["outages"] == 1
    assert any(w.startswith("outage 1 (9000.00 .. 9010.00 s after the first fix) not scored: the GNSS file holds "
                            "no fix") for w in s["health"]["warnings"]), s["health"]["warnings"]


@pytest.mark.parametrize("kind", ["speed_course_too_slow", "height_around_the_imu", "speed_course_withheld"])
def test_an_aiding_log_that_makes_no_update_is_warned_naming_the_file(capsys, sim, tmp_path, kind):
    """A speed-and-course or height log that overlapped the IMU's span but made 0 updates (every reading
    too slow for a course, on either side of the IMU log, withheld in an outage) left a run called healthy
    without a word, as if the log had been used."""
    import pandas as pd

    from inskit import io

    tr = io.read_solution(sim / "truth.csv")
    t = np.arange(tr.time[0], tr.time[-1], 0.1)
    v = tr.interpolate(t).v_n
    sc = pd.DataFrame({"time_s": t, "speed_m_s": np.hypot(v[:, 0], v[:, 1]),
                       "course_deg": np.degrees(np.arctan2(v[:, 1], v[:, 0])) % 360.0,
                       "sigma_speed_m_s": 0.05, "sigma_course_deg": 1.0})
    log = tmp_path / "aid.csv"
    gnss = 'speed_course = "aid.csv"\n'
    if kind == "speed_course_too_slow":
        sc.to_csv(log, index=False)
        gnss += "speed_course_min_speed_m_s = 20\n"
        extra, why = "", "slower than 20 m/s, below which a course means nothing"
    elif kind == "speed_course_withheld":
        sc[(sc.time_s > 12) & (sc.time_s < 48)].to_csv(log, index=False)
        extra, why = "[outages]\nprotocol = \"windows\"\nwindows_s = [[10, 50]]\n", "withheld inside the outage"
    else:
        pd.DataFrame({"time_s": [t[0] - 100.0, t[-1] + 100.0], "height_m": [300.0, 300.0]}).to_csv(log, index=False)
        gnss, extra, why = "", "[height]\nfile = \"aid.csv\"\nsigma_m = 1\n", "2 outside the span the filter runs over"
    cfg = config(tmp_path, sim, extra)
    cfg.write_text(cfg.read_text().replace("[output]", gnss + "[output]", 1))
    code, out, err = run(capsys, "navigate", cfg, "--json")
    assert code == 0, err
    what = "speed and course" if kind.startswith("speed_course") else "height"
    said = [w for w in json.loads(out)["health"]["warnings"] if w.startswith(f"{log}: the {what} log made no update")]
    assert len(said) == 1 and why in said[0] and said[0].endswith("the run is as if it had none"), said
    assert f"warning: {said[0]}" in err


def test_an_outage_protocol_that_scores_nothing_is_unhealthy(capsys, sim, tmp_path):
    """Every window past the fixes: no outage figure at all, so the verdict is
    unhealthy (and --strict exits 3), not a healthy run with null figures."""
    code, out, err = navigate(capsys, sim, tmp_path, None, None, "--outages", "windows:9000-9010", "--json",
                              "--strict")
    s = json.loads(out)
    assert code == 3 and s["outages"] == 0 and s["health"]["verdict"] == "unhealthy"
    assert any("scored no outage" in r for r in s["health"]["reasons"]), s["health"]


@pytest.mark.parametrize("argv, needle", [
    (["study", "examples/car.toml", "--out", "{out}"], "this is a scenario file, which `inskit simulate` takes"),
    (["simulate", "examples/drive_0708.toml", "--out", "{out}"],
     "this is a navigate configuration, which `inskit navigate` takes"),
    (["navigate", "examples/study_mc_mems.toml", "--out", "{out}"], "this is a study file, which `inskit study` takes"),
])
def test_another_commands_toml_file_is_named_as_such(capsys, tmp_path, argv, needle):
    """`inskit study examples/car.toml` said "field 'scenario': Field required (and 9 more)"."""
    root = Path(__file__).resolve().parents[1]
    out = tmp_path / "out"
    args = [str(root / a) if a.startswith("examples/") else a.format(out=out) for a in argv]
    refused(run(capsys, *args), needle)
    assert not out.exists()
