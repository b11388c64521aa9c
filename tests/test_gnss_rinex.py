"""RINEX readers (inskit.gnss.rinex) and GPS time (inskit.gnss.time).

Truths used: values read by eye from the file text, the calendar (GPS week
of known dates), and a second implementation (georinex) on the RINEX 3 walk
file and on the navigation files.
"""

from __future__ import annotations

import gzip
import time
import warnings
from pathlib import Path

import numpy as np
import pytest

from inskit.errors import ConfigError, InputError
from inskit.gnss import from_week_sow, gps_seconds, read_nav, read_obs, week_sow
from inskit.gnss.time import to_datetime64

DATA = Path(__file__).resolve().parent / "data" / "gnss"
ABPO_OBS = DATA / "abpo0080_0000-0200.15o"
ABPO_NAV = DATA / "abpo0080.15n"
WALK_OBS = DATA / "gnss_1730_first40.obs"
WALK_NAV = DATA / "gnss_1730.nav"
BRDC_NAV = DATA / "BRDC00IGS_R_20201360000_01D_MN.rnx"
ABPO_FULL = Path(__file__).resolve().parents[1] / "data" / "abpo" / "abpo0080.15o.gz"  # bundled


# ------------------------------------------------------------------ GPS time
def test_gps_time_landmarks():
    # the GPS epoch itself, and GPS week 2381 starting on Sunday 2025-08-24
    assert gps_seconds(1980, 1, 6, 0, 0, 0.0) == 0.0
    week, sow = week_sow(gps_seconds(2025, 8, 28, 17, 30, 39.748))
    assert int(week) == 2381
    assert sow == pytest.approx(4 * 86400 + 17 * 3600 + 30 * 60 + 39.748, abs=1e-6)
    # 1999-08-22 was the first 10-bit week rollover (week 1024); 2019-04-07 the second (2048)
    assert week_sow(gps_seconds(1999, 8, 22))[0] == 1024
    assert week_sow(gps_seconds(2019, 4, 7))[0] == 2048
    # leap day handled: 2016-02-29 to 2016-03-01 is one day
    assert gps_seconds(2016, 3, 1) - gps_seconds(2016, 2, 29) == 86400.0


def test_week_sow_round_trip_vectorised():
    t = np.array([0.0, 1.5, 604799.25, 604800.0, 1.4e9 + 0.125])
    week, sow = week_sow(t)
    assert week.dtype.kind == "i"
    np.testing.assert_array_equal(from_week_sow(week, sow), t)
    assert np.all((sow >= 0) & (sow < 604800.0))
    # datetime64 helper agrees with numpy's own calendar
    assert to_datetime64(gps_seconds(2015, 1, 8, 1, 2, 3.5)) == np.datetime64("2015-01-08T01:02:03.5")


# ---------------------------------------------------------- RINEX 2 obs
def test_abpo_excerpt_epochs_sats_and_values_from_the_text():
    obs = read_obs(ABPO_OBS)
    assert obs.version == pytest.approx(2.11)
    assert obs.n_epoch == 240
    assert obs.time[0] == gps_seconds(2015, 1, 8, 0, 0, 0.0)
    assert obs.time[-1] == gps_seconds(2015, 1, 8, 1, 59, 30.0)
    assert np.all(np.diff(obs.time) == 30.0)
    assert obs.interval_s == 30.0
    np.testing.assert_array_equal(obs.approx_position_e, [4097216.6805, 4429119.0287, -2065771.3676])
    np.testing.assert_allclose(obs.header["antenna_delta_hen"], [0.0083, 0.0, 0.0])
    assert obs.header["receiver"] == "ASHTECH UZ-12"
    assert obs.systems() == {"G"}
    # RINEX 2 types mapped to RINEX 3 codes
    assert set(obs.obs) == {"L1C", "L2W", "C1W", "C2W", "C1C", "S1C", "S2W"}
    # first epoch line: ' 15  1  8  0  0  0.0000000  0  8G02G12G05G15G18G21G24G13'
    first = {s for s in obs.sats if np.isfinite(obs.obs["C1C"][0, obs.sat_index(s)])}
    assert first == {"G02", "G12", "G05", "G15", "G18", "G21", "G24", "G13"}
    g02 = obs.sat_index("G02")
    # '   4696590.44946   3668584.54746  25127563.5194   25127563.5384   25127564.975'
    # '        41.0004         37.0004'
    assert obs.obs["L1C"][0, g02] == 4696590.449
    assert obs.obs["L2W"][0, g02] == 3668584.547
    assert obs.obs["C1W"][0, g02] == 25127563.519
    assert obs.obs["C2W"][0, g02] == 25127563.538
    assert obs.obs["C1C"][0, g02] == 25127564.975
    assert obs.obs["S1C"][0, g02] == 41.0
    assert obs.obs["S2W"][0, g02] == 37.0
    assert obs.lli["L1C"][0, g02] == 4  # bit 2: anti-spoofing on (header comment)
    # second epoch, first satellite (G02): '   4794125.36746   3744585.77546  25146123.4794 ...'
    assert obs.obs["L1C"][1, g02] == 4794125.367 and obs.obs["C1W"][1, g02] == 25146123.479
    # the last line of the excerpt: '  -8243053.59347  -6378332.81347  23081325.0654 ...'
    rows = np.flatnonzero(obs.obs["L1C"][-1] == -8243053.593)
    assert rows.size == 1
    assert obs.obs["C1C"][-1, rows[0]] == 23081325.995
    assert obs.epoch_flag.tolist() == [0] * 240
    assert np.all(np.isnan(obs.clock_offset_s))


def test_systems_and_codes_filters():
    obs = read_obs(ABPO_OBS, codes=("C1C", "L1C"))
    assert set(obs.obs) == {"C1C", "L1C"}
    none = read_obs(ABPO_OBS, systems=("E",))
    assert none.sats == () and none.obs["C1C"].shape == (240, 0)
    with pytest.raises(InputError, match="G99"):
        obs.sat_index("G99")


def test_abpo_full_day_reads_fast():
    t0 = time.perf_counter()
    obs = read_obs(ABPO_FULL)
    dt = time.perf_counter() - t0
    assert obs.n_epoch == 2727  # README: 2727 epochs, some 30-s slots missing
    assert obs.time[-1] == gps_seconds(2015, 1, 8, 23, 59, 30.0)
    assert len(obs.sats) == 31
    assert dt < 3.0  # measured 0.13 s here (target 1.5 s); generous bound for a loaded machine


def test_rinex2_more_than_12_satellites_and_system_filter(tmp_path):
    # a synthetic epoch of 13 satellites (satellite list continued on a second line, RINEX 2.11
    # Table A2), the 13th a GLONASS one; records are the 8 of ABPO's first epoch, reused
    lines = ABPO_OBS.read_text().splitlines()
    header, records = lines[:27], lines[28:44]
    names = "G02G12G05G15G18G21G24G13G01G03G04G06"
    epoch = [" 15  1  8  0  0  0.0000000  0 13" + names, " " * 32 + "R07"]
    body = [records[2 * (k % 8) + j] for k in range(13) for j in range(2)]
    p = tmp_path / "many.15o"
    p.write_text("\n".join(header + epoch + body) + "\n")
    obs = read_obs(p)
    assert obs.n_epoch == 1 and len(obs.sats) == 12 and "R07" not in obs.sats
    src = read_obs(ABPO_OBS)
    for k in range(12):
        sat = names[3 * k:3 * k + 3]
        first = src.sats.index(names[3 * (k % 8):3 * (k % 8) + 3])
        assert obs.obs["C1C"][0, obs.sat_index(sat)] == src.obs["C1C"][0, first]
    with_glo = read_obs(p, systems=("G", "R"))
    assert with_glo.sats[-1] == "R07"
    assert with_glo.obs["C1C"][0, -1] == src.obs["C1C"][0, src.sats.index("G18")]  # record 13 = record 5


# ---------------------------------------------------------- RINEX 3 obs
def _georinex():
    gr = pytest.importorskip("georinex")
    return gr


def test_walk_rinex3_matches_georinex():
    gr = _georinex()
    obs = read_obs(WALK_OBS, systems=("G", "E", "S"))
    assert obs.n_epoch == 40
    assert obs.interval_s is None
    np.testing.assert_array_equal(obs.approx_position_e, [-1276965.2487, -4717231.7278, 4087230.1460])
    assert obs.obs["C1C"][0, obs.sat_index("G10")] == 20576396.770  # first satellite line
    assert obs.obs["D1C"][0, obs.sat_index("G10")] == 1064.326
    assert np.isnan(obs.obs["L2L"][0, obs.sat_index("G18")])          # blank field in the text
    # '   108129693.9341' : loss-of-lock digit 1 at the first epoch, blank (0) at the second
    assert obs.lli["L1C"][0, obs.sat_index("G10")] == 1
    assert obs.lli["L1C"][1, obs.sat_index("G10")] == 0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ref = gr.load(WALK_OBS)
    assert tuple(ref.sv.values.tolist()) == obs.sats
    dt_ns = (to_datetime64(obs.time) - ref.time.values).astype("timedelta64[ns]").astype(np.int64)
    # georinex truncates 39.748 s to 39.747999 s (whole microseconds); float64 seconds since 1980
    # resolve 0.24 us: agreement to 1 us plus that truncation
    assert np.max(np.abs(dt_ns)) <= 1000
    assert set(ref.data_vars) == set(obs.obs)
    for code in obs.obs:
        np.testing.assert_allclose(obs.obs[code], ref[code].values, rtol=0, atol=1e-3, equal_nan=True,
                                   err_msg=code)
        np.testing.assert_array_equal(np.isnan(obs.obs[code]), np.isnan(ref[code].values), err_msg=code)


def test_gzip_and_hatanaka_round_trip(tmp_path):
    hatanaka = pytest.importorskip("hatanaka")
    plain = read_obs(WALK_OBS)
    raw = WALK_OBS.read_bytes()
    gz = tmp_path / "walk.obs.gz"
    gz.write_bytes(gzip.compress(raw))
    crx = tmp_path / "walk.crx"
    crx.write_bytes(hatanaka.rnx2crx(raw))
    crxgz = tmp_path / "walk.crx.gz"
    crxgz.write_bytes(hatanaka.compress(raw, compression="gz"))
    assert b"COMPACT RINEX" in crx.read_bytes()[:200]
    for p in (gz, crx, crxgz):
        other = read_obs(p)
        assert other.sats == plain.sats
        np.testing.assert_array_equal(other.time, plain.time)
        for code in plain.obs:
            np.testing.assert_array_equal(other.obs[code], plain.obs[code], err_msg=f"{p.name} {code}")
    # RINEX 2 through Hatanaka too (the ABPO excerpt)
    crx2 = tmp_path / "abpo0080.15d"
    crx2.write_bytes(hatanaka.rnx2crx(ABPO_OBS.read_bytes()))
    np.testing.assert_array_equal(read_obs(crx2).obs["C1W"], read_obs(ABPO_OBS).obs["C1W"])


# ---------------------------------------------------------- epoch flags
def test_event_epochs_skipped_power_failure_kept(tmp_path):
    lines = WALK_OBS.read_text().splitlines()
    starts = [i for i, line in enumerate(lines) if line.startswith(">")]
    # flag 1 on the second epoch; a flag-4 block (2 header lines) inserted before the third
    second = starts[1]
    lines[second] = lines[second][:31] + "1" + lines[second][32:]
    event = ["> 2025 08 28 17 30 40.0000000  4  2",
             "this is a comment inside a special event                    COMMENT",
             "                                                            COMMENT"]
    lines[starts[2]:starts[2]] = event
    p = tmp_path / "events.obs"
    p.write_text("\n".join(lines) + "\n")
    obs = read_obs(p)
    assert obs.n_epoch == 40
    assert obs.skipped_events == 1
    assert obs.epoch_flag[1] == 1 and obs.epoch_flag[0] == 0
    np.testing.assert_array_equal(obs.obs["C1C"], read_obs(WALK_OBS).obs["C1C"])


# ---------------------------------------------------------- bad input
def test_truncated_obs_names_file_and_line(tmp_path):
    lines = ABPO_OBS.read_text().splitlines()
    p = tmp_path / "cut.15o"
    p.write_text("\n".join(lines[:40]) + "\n")  # header is 27 lines; epoch 1 (line 28) needs 1 + 8*2 lines
    with pytest.raises(InputError, match=r"cut\.15o: line 40: the file ends inside the epoch starting at line 28"):
        read_obs(p)
    lines3 = WALK_OBS.read_text().splitlines()
    p3 = tmp_path / "cut3.obs"
    p3.write_text("\n".join(lines3[:30]) + "\n")
    with pytest.raises(InputError, match=r"cut3\.obs: line 30: the file ends inside the epoch starting at line 25"):
        read_obs(p3)


def test_garbage_files_raise_input_error(tmp_path):
    junk = tmp_path / "junk.txt"
    junk.write_text("time,x,y\n1,2,3\n")
    with pytest.raises(InputError, match=r"junk\.txt: line 1: not a RINEX file"):
        read_obs(junk)
    with pytest.raises(InputError, match=r"junk\.txt: line 1"):
        read_nav(junk)
    lines = ABPO_OBS.read_text().splitlines()
    lines[29] = lines[29][:20] + "abc" + lines[29][23:]   # inside a number of the first record
    bad = tmp_path / "bad.15o"
    bad.write_text("\n".join(lines) + "\n")
    with pytest.raises(InputError, match=r"bad\.15o: line 30: columns 17-30: expected a number"):
        read_obs(bad)
    lines = ABPO_OBS.read_text().splitlines()
    lines[27] = "this is not an epoch line"
    bad.write_text("\n".join(lines) + "\n")
    with pytest.raises(InputError, match=r"line 28: expected an epoch line"):
        read_obs(bad)
    noend = tmp_path / "noend.15o"
    noend.write_text("\n".join(ABPO_OBS.read_text().splitlines()[:10]) + "\n")
    with pytest.raises(InputError, match="END OF HEADER"):
        read_obs(noend)
    with pytest.raises(InputError, match="not observation data"):
        read_obs(ABPO_NAV)
    with pytest.raises(InputError, match="cannot be read"):
        read_obs(tmp_path / "missing.obs")


def test_glonass_time_system_refused(tmp_path):
    text = WALK_OBS.read_text().replace(" 39.7480000     GPS         TIME OF FIRST OBS",
                                        " 39.7480000     GLO         TIME OF FIRST OBS")
    p = tmp_path / "glo.obs"
    p.write_text(text)
    with pytest.raises(InputError, match=r"glo\.obs: line 16: time system 'GLO' is not supported"):
        read_obs(p)


# ---------------------------------------------------------- navigation
_GEORINEX_NAMES = {
    "af0": "SVclockBias", "af1": "SVclockDrift", "af2": "SVclockDriftRate", "crs": "Crs", "dn": "DeltaN",
    "m0": "M0", "cuc": "Cuc", "e": "Eccentricity", "cus": "Cus", "sqrt_a": "sqrtA", "toe_sow": "Toe",
    "cic": "Cic", "omega0": "Omega0", "cis": "Cis", "i0": "Io", "crc": "Crc", "omega": "omega",
    "omega_dot": "OmegaDot", "idot": "IDOT", "svacc": "SVacc", "health": "health", "ttm": "TransTime",
}
_GEORINEX_GPS = {"iode": "IODE", "codes_l2": "CodesL2", "week": "GPSWeek", "l2p_flag": "L2Pflag",
                 "tgd": "TGD", "iodc": "IODC", "fit_h": "FitIntvl"}
_GEORINEX_GAL = {"iode": "IODnav", "data_source": "DataSrc", "week": "GALWeek", "svacc": "SISA",
                 "bgd_e5a_e1": "BGDe5a", "bgd_e5b_e1": "BGDe5b"}


def _compare_nav_with_georinex(path, nav):
    gr = _georinex()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ref = gr.load(path)
    compared = 0
    toc_ref = (ref.time.values - np.datetime64("1980-01-06T00:00:00", "ns")).astype(np.int64) / 1e9
    for sv in ref.sv.values:
        base = str(sv)[:3]
        if base[0] not in "GE":
            continue
        for k, t in enumerate(toc_ref):
            row = ref.sel(sv=sv).isel(time=k)
            if np.isnan(float(row["sqrtA"])):
                continue
            cand = np.flatnonzero((nav.sats == base) & (nav.toc == t))
            names = {**_GEORINEX_NAMES, **(_GEORINEX_GAL if base[0] == "E" else _GEORINEX_GPS)}
            # the record georinex kept among same-time duplicates: match on every value
            match = [j for j in cand if all(
                np.isclose(nav.params[ours][j], float(row[theirs]), rtol=1e-12, atol=0, equal_nan=True)
                for ours, theirs in names.items() if theirs in row)]
            assert match, f"{path.name}: no record of ours equals georinex's {sv} at toc {t}"
            compared += 1
    return compared


def test_nav_rinex2_abpo_matches_georinex():
    nav = read_nav(ABPO_NAV)
    assert len(nav) == 167 and set(nav.system) == {"G"}
    assert nav.iono_alpha is None and nav.iono_beta is None  # README: no ION ALPHA/BETA
    # first record, by eye: ' 2 15  1  8  2  0  0.0 5.405521951616D-04 2.273736754432D-12 ...'
    assert nav.sats[0] == "G02"
    assert nav.toc[0] == gps_seconds(2015, 1, 8, 2, 0, 0.0)
    assert nav.params["af0"][0] == 5.405521951616e-04
    assert nav.params["sqrt_a"][0] == 5.153748075485e03
    assert nav.params["tgd"][0] == -2.048909664154e-08
    assert nav.params["iodc"][0] == 49.0 and nav.params["fit_h"][0] == 4.0
    assert nav.toe[0] == from_week_sow(1826, 352800.0)
    assert np.all(np.isnan(nav.params["bgd_e5b_e1"]))
    n = _compare_nav_with_georinex(ABPO_NAV, nav)
    assert n >= 150  # georinex merges same-time duplicates; every record it keeps matches one of ours


def test_nav_rinex2_ion_alpha_beta(tmp_path):
    # RINEX 2.11 Table A3: 2X, 4D12.4 then the label in columns 61-80
    lines = ABPO_NAV.read_text().splitlines()
    alpha = "  " + "  0.1118D-07 -0.7451D-08 -0.5961D-07  0.1192D-06"
    beta = "  " + "  0.1167D+06 -0.2294D+06 -0.1311D+06  0.1049D+07"
    lines[1:1] = [alpha.ljust(60) + "ION ALPHA", beta.ljust(60) + "ION BETA"]
    p = tmp_path / "iono.15n"
    p.write_text("\n".join(lines) + "\n")
    nav = read_nav(p)
    np.testing.assert_array_equal(nav.iono_alpha, [0.1118e-07, -0.7451e-08, -0.5961e-07, 0.1192e-06])
    np.testing.assert_array_equal(nav.iono_beta, [0.1167e06, -0.2294e06, -0.1311e06, 0.1049e07])
    assert len(nav) == 167


def test_nav_rinex3_walk_skips_other_systems_with_a_warning():
    with pytest.warns(UserWarning, match=r"skipped 13 navigation records of other systems \(8 BeiDou, 5 SBAS\)"):
        nav = read_nav(WALK_NAV)
    assert nav.sats.tolist() == ["G32", "G23", "G10", "G27"]
    assert nav.skipped == {"S": 5, "C": 8}
    # '.344484578818D-03' style numbers (no leading zero)
    assert nav.params["af0"][0] == -0.344484578818e-03
    assert nav.toe[0] == from_week_sow(2381, 410400.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert _compare_nav_with_georinex(WALK_NAV, nav) == 4


def test_nav_galileo_records_and_iono_header():
    nav = read_nav(BRDC_NAV)
    assert nav.sats.tolist() == ["E24"] * 4
    np.testing.assert_array_equal(nav.params["data_source"], [258, 513, 516, 517])
    np.testing.assert_array_equal(nav.iono_alpha, [7.4506e-09, 2.2352e-08, -5.9605e-08, -1.1921e-07])
    np.testing.assert_array_equal(nav.iono_beta, [8.6016e04, 8.1920e04, -1.3107e05, -5.2429e05])
    # RINEX 3 writes the Galileo week continuous with GPS weeks: 2105 -> 2020-05-15 is in GPS week 2105
    assert nav.toe[0] == from_week_sow(2105, 432000.0) == gps_seconds(2020, 5, 15)
    assert nav.params["bgd_e5a_e1"][0] == 4.540197551250e-08
    assert nav.params["bgd_e5b_e1"][1] == 5.098991096020e-08
    assert np.all(np.isnan(nav.params["tgd"]))
    assert len(nav.records_for("E24")) == 4 and len(nav.records_for("E01")) == 0
    assert _compare_nav_with_georinex(BRDC_NAV, nav) >= 1


def test_nav_errors(tmp_path):
    lines = ABPO_NAV.read_text().splitlines()
    p = tmp_path / "cut.15n"
    p.write_text("\n".join(lines[:16]) + "\n")   # header 13 lines + 3 lines of the first record
    with pytest.raises(InputError, match=r"cut\.15n: line 16: the file ends inside the record starting at line 14"):
        read_nav(p)
    lines[14] = lines[14][:30] + "x.yz" + lines[14][34:]
    p.write_text("\n".join(lines) + "\n")
    with pytest.raises(InputError, match=r"cut\.15n: line 15: columns 23-41: expected a number"):
        read_nav(p)
    glo = tmp_path / "brdc.15g"
    glo.write_text("     2.01           G: GLONASS NAV DATA                     RINEX VERSION / TYPE\n"
                   "                                                            END OF HEADER\n")
    with pytest.raises(InputError, match="GLONASS is not supported"):
        read_nav(glo)
    with pytest.raises(ConfigError, match="not supported"):
        read_nav(ABPO_NAV, systems=("G", "R"))


def test_observed_satellites_of_other_systems_are_counted_in_one_warning(tmp_path):
    """A mixed file's GLONASS, BeiDou or QZSS satellites were left out without
    a word (spp said '3 satellites in m_mixed.obs' of a file with six); they
    are now counted as read_nav counts its skipped records."""
    lines = WALK_OBS.read_text().split("\n")
    swap = {"G18": "R18", "G27": "C27", "G32": "J02"}
    out = []
    for line in lines:
        out.append(swap.get(line[:3], line[:3]) + line[3:] if line[:3] in swap else line)
        if line[:1] == "G" and line[60:].strip() == "SYS / # / OBS TYPES":
            out += [s + line[1:] for s in "RCJ"]
    p = tmp_path / "mixed.obs"
    p.write_text("\n".join(out))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        obs = read_obs(p, systems=("G", "E"))
    said = [str(w.message) for w in caught if "skipped" in str(w.message)]
    assert len(said) == 1, said
    assert said[0].startswith(f"{p}: skipped ") and "1 BeiDou" in said[0] and "1 QZSS" in said[0]
    assert "1 GLONASS" in said[0] and "SBAS" in said[0] and "systems used: GPS, Galileo" in said[0]
    assert not {"R18", "C27", "J02"} & set(obs.sats)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        read_obs(WALK_OBS, systems=("G", "E", "S"))
    assert not [w for w in caught if "skipped" in str(w.message)]


@pytest.mark.parametrize("how", ["back", "repeat"])
def test_epochs_that_go_back_or_repeat_are_refused_naming_both_lines(tmp_path, how):
    """Epochs out of order or repeated (files spliced out of order or
    overlapping) were read as they came: spp solved them without a word and a
    tightly coupled run used a repeated epoch's ranges twice; now the reader
    names the line, both epochs and what was expected."""
    lines = WALK_OBS.read_text().split("\n")
    ep = [i for i, line in enumerate(lines) if line.startswith(">")]
    a, b, c = ep[5], ep[6], ep[7]
    # a repeat with other content: one observation changed in its last digit (an exact copy is dropped, below)
    changed = lines[a:b]
    changed[-1] = changed[-1][:16] + ("1" if changed[-1][16] != "1" else "2") + changed[-1][17:]
    body = lines[b:c] + lines[a:b] if how == "back" else lines[a:b] + changed
    p = tmp_path / "o.obs"
    p.write_text("\n".join(lines[:a] + body + lines[c:]))
    verb = "goes back from" if how == "back" else "repeats"
    other = r" with other content \(a copy identical line for line would be dropped\)" if how == "repeat" else ""
    with pytest.raises(InputError, match=rf"o.obs: line {a + 1 + (c - b) if how == 'back' else b + 1}: epoch "
                                         rf"2025-08-28 17:30:4\d\.\d+ {verb} the epoch at line {a + 1} "
                                         rf"\(2025-08-28 17:30:4\d\.\d+\){other}; expected epochs in increasing "
                                         "time order"):
        read_obs(p)


@pytest.mark.parametrize("src", [WALK_OBS, ABPO_OBS], ids=["rinex3", "rinex2"])
def test_an_exact_duplicate_epoch_is_dropped_with_a_warning(tmp_path, src):
    """An epoch repeated line for line (files spliced with an overlap) was
    refused ('line N: epoch ... repeats the epoch at line M'), though it
    carries nothing new; it is now dropped, the lines named in one warning,
    and the file reads as without the copies."""
    lines = src.read_text().split("\n")
    body = next(i for i, line in enumerate(lines) if "END OF HEADER" in line) + 1
    if src == WALK_OBS:
        ep = [i for i, line in enumerate(lines) if line.startswith(">")]
    else:
        ep = list(range(body, len(lines), 17))   # ABPO: 8 satellites of 2 lines after each epoch line
    a, b = ep[5], ep[6]
    out = lines[:b] + lines[a:b] + lines[a:b] + lines[b:]   # two copies of the 6th epoch after it
    p = tmp_path / "dup.obs"
    p.write_text("\n".join(out))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        obs = read_obs(p)
    said = [str(w.message) for w in caught if "dropped" in str(w.message)]
    ref = read_obs(src)
    # the 6th epoch's time, from its epoch line
    stamp, when = (("> 2025 08 28 17 30 40.9980000", "2025-08-28 17:30:40.998") if src == WALK_OBS else
                   (" 15  1  8  0  2 30.0000000", "2015-01-08 00:02:30.000"))
    assert lines[a].startswith(stamp)
    assert said == [f"{p}: dropped 2 epochs that repeat the epoch before them line for line (line {b + 1} repeats "
                    f"line {a + 1} ({when}); line {2 * b - a + 1} repeats line {a + 1} ({when})): files spliced "
                    "with an overlap?"], said
    np.testing.assert_array_equal(obs.time, ref.time)
    assert obs.sats == ref.sats
    for code in ref.obs:
        np.testing.assert_array_equal(obs.obs[code], ref.obs[code], err_msg=code)
        if code in (ref.lli or {}):
            np.testing.assert_array_equal(obs.lli[code], ref.lli[code], err_msg=code)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        read_obs(src)
    assert not [w for w in caught if "dropped" in str(w.message)]


@pytest.mark.parametrize("count", [7, 9])
def test_rinex2_epoch_count_against_its_satellite_list(tmp_path, count):
    """An epoch line whose satellite count disagrees with its list of 8 was
    reported lines further on, where the shifted records put a data line in
    place of an epoch line ("line 128: expected an epoch line ..., got
    '  -2473608.99647 ...'"); now the epoch line itself is named."""
    lines = ABPO_OBS.read_text().split("\n")
    k = next(i for i, line in enumerate(lines) if "END OF HEADER" in line) + 1 + 17 * 5   # the 6th epoch
    assert lines[k][29:32] == "  8"
    lines[k] = lines[k][:29] + f"{count:3d}" + lines[k][32:]
    p = tmp_path / "c.15o"
    p.write_text("\n".join(lines))
    with pytest.raises(InputError, match=rf"c.15o: line {k + 1}: the epoch announces {count} satellites \(columns "
                                         r"30-32\) but its satellite list \(columns 33-68\) holds 8"):
        read_obs(p)


def test_a_number_cut_short_is_refused_not_misread(tmp_path):
    """RINEX numbers are right-justified: a line cut inside a field was read
    as the digits left ('-1.164153218269D-0', a TGD of -1.16 s for -1.16e-8 s;
    a Doppler of -492 for -492.180) without a word; now the line, the columns
    and the field are named."""
    lines = ABPO_NAV.read_text().split("\n")
    body = next(i for i, line in enumerate(lines) if "END OF HEADER" in line) + 1
    k = body + 6                                   # broadcast orbit 6 of the first record: svacc health tgd iodc
    lines[k] = lines[k][:59]
    p = tmp_path / "cut.15n"
    p.write_text("\n".join(lines))
    with pytest.raises(InputError, match=rf"cut.15n: line {k + 1}: columns 42-60: the number '-?[\d.]+D-0' \(tgd \(GPS\) "
                                         r"/ bgd_e5a_e1 \(Galileo\), broadcast orbit 6 field 3\) does not end at column 60: the line is cut"):
        read_nav(p)
    lines = WALK_OBS.read_text().split("\n")
    k = next(i for i, line in enumerate(lines) if line.startswith(">")) + 1
    lines[k] = lines[k][:45]
    p = tmp_path / "cut.obs"
    p.write_text("\n".join(lines))
    with pytest.raises(InputError, match=rf"cut.obs: line {k + 1}: columns 36-49: .* \(observation D1C\) does not "
                                         "end at column 49"):
        read_obs(p)


@pytest.mark.parametrize("src", [WALK_OBS, ABPO_OBS], ids=["rinex3", "rinex2"])
def test_lower_case_system_letters_read_as_upper_case(tmp_path, src):
    """Satellite names with a lower-case system letter ('g05', 'e11', as some
    converters write) were taken for a system 'g' of their own (spp: the file
    holds 'g (g): 6 satellites') and a file written wholly in lower case was
    'not a RINEX file'; both now read as the upper-case file does."""
    lines = src.read_text().split("\n")
    body = next(i for i, line in enumerate(lines) if "END OF HEADER" in line) + 1
    if src == WALK_OBS:
        low = [line[:1].lower() + line[1:] if line[:1] in "GES" else line for line in lines[body:]]
    else:
        low = [line[:32] + line[32:].lower() if line[:1] == " " and line[3:4] == " " else line
               for line in lines[body:]]
    assert low != lines[body:]
    names = tmp_path / "names.obs"
    names.write_text("\n".join(lines[:body] + low))
    whole = tmp_path / "whole.obs"
    whole.write_text(src.read_text().lower())
    ref = read_obs(src, systems=("G", "E", "S"))
    for p in (names, whole):
        obs = read_obs(p, systems=("G", "E", "S"))
        assert obs.sats == ref.sats and obs.header["satellites_by_system"] == ref.header["satellites_by_system"]
        assert set(obs.obs) == set(ref.obs)
        np.testing.assert_array_equal(obs.time, ref.time)
        for code in ref.obs:
            np.testing.assert_array_equal(obs.obs[code], ref.obs[code], err_msg=f"{p.name} {code}")


def test_version_line_that_disagrees_with_the_observation_types_line_is_named(tmp_path):
    """A RINEX 3 version line over a RINEX 2 header and body was refused with
    "header has no 'SYS / # / OBS TYPES' line", without a line and without a
    word that the version line and the file disagree; now the message names
    both (and the reverse case, a RINEX 2 version line over a RINEX 3 file)."""
    p = tmp_path / "v3.15o"
    p.write_text(ABPO_OBS.read_text().replace("     2.11           OBSERVATION", "     3.04           OBSERVATION", 1))
    with pytest.raises(InputError, match=r"v3\.15o: line 13: the version line \(line 1\) says RINEX 3\.04 but the header "
                                         r"holds the RINEX 2 observation types line '# / TYPES OF OBSERV' here, and no "
                                         r"RINEX 3 'SYS / # / OBS TYPES' line; the first epoch line \(line 28\) is "
                                         r"written as RINEX 2 .*: the version line and the file's layout disagree"):
        read_obs(p)
    p = tmp_path / "v2.obs"
    p.write_text(WALK_OBS.read_text().replace("     3.04           OBSERVATION", "     2.11           OBSERVATION", 1))
    with pytest.raises(InputError, match=r"v2\.obs: line 13: the version line \(line 1\) says RINEX 2\.11 but the header "
                                         r"holds the RINEX 3 observation types line 'SYS / # / OBS TYPES' here.*line 25\) "
                                         r"is written as RINEX 3 \('>' in column 1\)"):
        read_obs(p)
    p = tmp_path / "none.15o"
    p.write_text("\n".join(line for line in ABPO_OBS.read_text().split("\n") if "TYPES OF OBSERV" not in line))
    with pytest.raises(InputError, match=r"none\.15o: lines 1-26: the header has no '# / TYPES OF OBSERV' line"):
        read_obs(p)
