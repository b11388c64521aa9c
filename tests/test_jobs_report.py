"""The HTML run report (inskit.jobs.report), checked in a real headless
browser (Debian's chromium): it renders every figure with networking off, logs
no console error, fetches nothing, and its decimation keeps the extremes."""

import json
import os
import re
import shutil
import subprocess
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest

from inskit.errors import InputError
from inskit.jobs.report import build_report, decimate, envelope

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "drive_0708.toml"
CHROMIUM = shutil.which("chromium") or (
    "/usr/bin/chromium" if os.path.exists("/usr/bin/chromium") else None)
WIDTH, HEIGHT = 1280, 4400


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    """A real navigate run of the drive_0708 example (no PNG plots)."""
    from inskit.jobs import navigate as N
    from inskit.jobs.config import load_config

    cfg = load_config(EXAMPLE, {"output": {"plots": False}})
    res = N.navigate(cfg)
    out = tmp_path_factory.mktemp("run")
    N.write_outputs(res, out, N.summary(res))
    return out


@pytest.fixture(scope="module")
def report(run_dir):
    return build_report(run_dir)


def _chromium(url, tmp, *extra):
    if CHROMIUM is None:
        pytest.skip("Debian's chromium is not installed (CI installs it in .ci/run: apt-get install chromium)")
    args = [CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
            "--disable-background-networking", "--disable-component-update", "--disable-sync",
            f"--user-data-dir={tmp / 'profile'}", f"--window-size={WIDTH},{HEIGHT}",
            "--virtual-time-budget=10000", "--enable-logging=stderr", "--v=0", *extra, url]
    p = subprocess.run(args, capture_output=True, text=True, timeout=120)
    return p


def _console_errors(stderr):
    """Console errors in chromium's log: uncaught exceptions, console.error."""
    return [ln for ln in stderr.splitlines()
            if "Uncaught" in ln or ("CONSOLE" in ln and ("ERROR:" in ln or "error" in ln.lower().split("console")[0]))]


def _render(path, tmp, *extra):
    """Screenshot + DOM after the scripts ran; returns (rgb array, dom, errors)."""
    png = tmp / "shot.png"
    url = Path(path).resolve().as_uri()
    p1 = _chromium(url, tmp, f"--screenshot={png}", *extra)
    p2 = _chromium(url, tmp, "--dump-dom", *extra)
    assert png.exists(), p1.stderr[-2000:]
    import matplotlib.image as mpimg

    img = mpimg.imread(png)[..., :3]
    return img, p2.stdout, _console_errors(p1.stderr) + _console_errors(p2.stderr)


def _bands(dom):
    """Where the page says it drew each figure: name -> (top, height) [px]."""
    import re

    return {m[0]: (int(m[1]), int(m[2])) for m in
            re.findall(r'id="sec-(\w+)" data-top="(\d+)" data-height="(\d+)"', dom)}


def _check_figures(img, dom, plots):
    bands = _bands(dom)
    assert list(bands) == plots
    assert f'data-figures-drawn="{len(plots)}"' in dom
    for name, (top, h) in bands.items():
        assert top + h <= img.shape[0], f"{name} below the screenshot"
        band = img[top + 40: top + h - 10]
        ink = np.mean(np.any(band < 0.85, axis=2))
        colours = len(np.unique((band * 15).astype(np.uint8).reshape(-1, 3), axis=0))
        # plot lines, markers, axes and shaded outage windows: a blank band has ~0 ink and 1 colour
        assert ink > 0.01, f"{name}: band {top}..{top + h} px is blank ({ink:.4f} ink)"
        assert colours > 20, f"{name}: only {colours} colours"


def test_report_renders_in_headless_chromium(report, tmp_path):
    img, dom, errors = _render(report["report"], tmp_path)
    assert not errors, errors
    _check_figures(img, dom, report["plots"])


def test_report_renders_with_networking_off(report, tmp_path):
    img, dom, errors = _render(report["report"], tmp_path, "--proxy-server=127.0.0.1:9")
    assert not errors, errors
    _check_figures(img, dom, report["plots"])


def test_console_errors_are_caught(tmp_path):
    """The console check can fail: a page that throws is reported."""
    page = tmp_path / "bad.html"
    page.write_text("<html><body><p>x</p><script>throw new Error('boom-report-check');</script></body></html>")
    p = _chromium(page.resolve().as_uri(), tmp_path, f"--screenshot={tmp_path / 'bad.png'}")
    errors = _console_errors(p.stderr)
    assert any("boom-report-check" in e for e in errors)


class _Links(HTMLParser):
    def __init__(self):
        super().__init__()
        self.urls = []

    def handle_starttag(self, tag, attrs):
        for k, v in attrs:
            if k in ("src", "href", "srcset", "poster", "data") and v:
                self.urls.append((tag, k, v))


def test_report_is_self_contained_and_small(report, run_dir):
    text = Path(report["report"]).read_text()
    parser = _Links()
    parser.feed(text)
    remote = [u for u in parser.urls if u[2].strip().lower().startswith(("http:", "https:", "//"))]
    assert not remote, remote
    assert "<script src" not in text.lower()
    assert "url(http" not in text.lower().replace(" ", "")
    assert report["plots"] == ["track", "sigmas", "innovations", "estimates"]
    # plotly.js inlined gzip + base64 (1.8 MB for 4.6 MB): the smoothed drive_0708 page was 5.04 MB, now 2.2 MB
    assert report["bytes"] == Path(report["report"]).stat().st_size < 2.6e6
    assert "Copyright 2012-" not in text  # no plain copy of the bundle beside the packed one
    s = json.loads((run_dir / "summary.json").read_text())
    rms = s["outage_end_horizontal_rms_m"]
    assert 1.0 < rms < 3.0  # the drive's outage-end RMS (1.98 m with examples/drive_0708.toml)
    assert s["health"]["verdict"] in text and f"{rms:.3f}" in text  # verdict and outage-end RMS on the page


def test_report_works_without_innovations_and_config(run_dir, tmp_path):
    d = tmp_path / "bare"
    d.mkdir()
    for f in ("summary.json", "solution_forward.csv"):
        shutil.copy(run_dir / f, d / f)
    r = build_report(d, tmp_path / "bare.html")
    assert r["plots"] == ["track", "sigmas", "estimates"]
    text = Path(r["report"]).read_text()
    assert "config_used.json is not in the run folder" in text and "noise_used" in text


def test_not_a_run_folder(tmp_path):
    with pytest.raises(InputError, match="summary.json is missing") as e:
        build_report(tmp_path)
    assert str(tmp_path) in str(e.value)


def test_truncated_summary(run_dir, tmp_path):
    d = tmp_path / "cut"
    d.mkdir()
    text = (run_dir / "summary.json").read_text()
    (d / "summary.json").write_text(text[: len(text) // 2])
    shutil.copy(run_dir / "solution_forward.csv", d / "solution_forward.csv")
    with pytest.raises(InputError, match=r"summary.json: line \d+: not valid JSON"):
        build_report(d)


def test_decimate_keeps_extremes():
    rng = np.random.default_rng(1)
    n = 200_000
    y = rng.normal(size=n)
    y[123_457] = 50.0
    y[7] = -40.0
    z = np.cumsum(rng.normal(size=n))
    idx = decimate(n, [y, z], 5000)
    assert len(idx) <= 5000 and idx[0] == 0 and idx[-1] == n - 1
    assert 123_457 in idx and 7 in idx
    assert np.argmax(z) in idx and np.argmin(z) in idx
    assert np.all(np.diff(idx) > 0)


def test_envelope_keeps_extremes_and_gaps():
    t = np.arange(100_000) * 0.01
    y = np.sin(t)
    y[54_321] = 9.0
    y[(t > 300) & (t < 320)] = np.nan
    x0, dx, v = envelope(t, y, 600)
    assert len(v) == 1200
    assert np.nanmax(v) == 9.0 and np.nanmin(v) == pytest.approx(-1.0, abs=1e-6)
    k = int(np.nanargmax(v))
    assert abs(x0 + k * dx - t[54_321]) <= 2 * dx  # drawn within a bin of its time
    assert np.isnan(v[int((310 - x0) / dx)])  # a gap in the data stays a gap


def test_an_innovations_file_cut_mid_row_is_refused(run_dir, tmp_path):
    """innovations.csv cut short (head -c 3000) was plotted without a word."""
    d = tmp_path / "cut"
    d.mkdir()
    for f in ("summary.json", "solution_forward.csv"):
        shutil.copy(run_dir / f, d / f)
    (d / "innovations.csv").write_bytes((run_dir / "innovations.csv").read_bytes()[:3000])
    with pytest.raises(InputError, match=r"innovations\.csv: line \d+: empty field.*cut short"):
        build_report(d, tmp_path / "cut.html")
    assert not (tmp_path / "cut.html").exists()
    # a blank line before the empty field: the line an editor shows, not the one above it
    lines = (run_dir / "innovations.csv").read_text().splitlines(True)[:60]
    at = lines[0].strip().split(",").index("nu")
    lines[40] = ",".join(c if k != at else "" for k, c in enumerate(lines[40].split(",")))  # nu of line 41
    (d / "innovations.csv").write_text("".join(lines[:10] + ["\n"] + lines[10:]))
    with pytest.raises(InputError, match=r"innovations\.csv: line 42: empty field\(s\) in nu$"):
        build_report(d, tmp_path / "cut.html")


def test_an_innovations_file_cut_at_a_whole_field_or_line_is_refused(run_dir, tmp_path):
    """innovations.csv cut inside its last field (`head -c 100000`: '...,1,accept') parsed whole and the report
    plotted 151 s of a 549 s run without a word; cut at a line end it still did.  The missing line end, and a
    count of used updates below the summary's, are refused."""
    d = tmp_path / "cut"
    d.mkdir()
    for f in ("summary.json", "solution_forward.csv"):
        shutil.copy(run_dir / f, d / f)
    text = (run_dir / "innovations.csv").read_text()
    lines = text.splitlines(True)
    (d / "innovations.csv").write_text("".join(lines[:400])[:-3])  # the last field's end gone, no line end
    with pytest.raises(InputError, match=r"innovations\.csv: the last line has no line end: the file seems cut short"):
        build_report(d, tmp_path / "cut.html")
    (d / "innovations.csv").write_text("".join(lines[: len(lines) // 3]))
    with pytest.raises(InputError, match=r"innovations\.csv: holds \d+ used update\(s\) of \w+ where the run's "
                                         r"summary\.json counts \d+: the file seems cut short"):
        build_report(d, tmp_path / "cut.html")
    assert not (tmp_path / "cut.html").exists()
    (d / "innovations.csv").write_text(text)
    build_report(d, tmp_path / "whole.html")


def test_an_unreadable_fix_file_is_said_so_not_missing(run_dir, tmp_path):
    """The fix file the configuration names exists but cannot be read: the note said it 'was not found'; now it
    gives the reader's own message."""
    import json

    d = tmp_path / "badfix"
    shutil.copytree(run_dir, d)
    bad = tmp_path / "fixes.pos"
    bad.write_text("% not an RTKLIB solution\nthis is no fix\n")
    cfg = json.loads((d / "config_used.json").read_text())
    cfg["gnss"]["file"] = str(bad)
    (d / "config_used.json").write_text(json.dumps(cfg))
    text = Path(build_report(d, tmp_path / "r.html")["report"]).read_text()
    assert "the fix file named in the configuration could not be read (" in text and str(bad) in text
    assert "was not found from the run folder" not in text


def test_a_run_that_diverged_beyond_100_km_is_still_reported(run_dir, tmp_path):
    """A filter lost after every fix was refused wrote heights of 106 km;
    `inskit report` of that folder failed with 'height_m=106765.26 is beyond
    +-100 km of the ellipsoid ...; another unit or column?' (the check of a
    user's file) and no page; now the page shows the diverged run, while
    read_solution keeps refusing such a file by default."""
    import pandas as pd

    from inskit import io

    d = tmp_path / "lost"
    d.mkdir()
    for f in ("summary.json", "config_used.json", "innovations.csv"):
        shutil.copy(run_dir / f, d / f)
    sol = pd.read_csv(run_dir / "solution_forward.csv")
    n = len(sol)
    sol.loc[n // 2:, "height_m"] += np.linspace(0.0, 2.0e5, n - n // 2)
    sol.loc[n // 2:, "vd_m_s"] = -2.0e4  # beyond the escape speed
    sol.to_csv(d / "solution_forward.csv", index=False)
    with pytest.raises(InputError, match="beyond"):
        io.read_solution(d / "solution_forward.csv")
    r = build_report(d, tmp_path / "lost.html")
    assert r["plots"] == ["track", "sigmas", "innovations", "estimates"]


def _figure(run_dir, which):
    import plotly.graph_objects as go
    from plotly.subplots import make_subplots

    from inskit.jobs import report as R

    run = R._Run(run_dir)
    f = getattr(R, f"_fig_{which}")
    return (f(run, go) if which == "track" else f(run, go, make_subplots))[0], run


def test_estimates_named_and_tabled_in_the_units_they_are_drawn_in(run_dir):
    """The sensor-error figure drew the gyro biases in deg/h under legend
    entries named bg_x_rad_s, and the final-estimates table gave
    0.000506388 rad_s beside it; now the legend says 'gyro bias x' and the
    table deg/h, mg, %, deg."""
    import re

    from inskit.jobs.report import _estimates_table

    fig, run = _figure(run_dir, "estimates")
    shown = [t.name for t in fig.data if t.showlegend is not False]
    assert shown[:3] == ["gyro bias x", "gyro bias y", "gyro bias z"]
    assert not [n for n in shown if re.search(r"_(rad_s|m_s2)$|^(bg|ba|sg|sa)_", n)], shown
    s = json.loads((run_dir / "summary.json").read_text())
    table = _estimates_table(s)
    bg = s["final_estimates"]["bg"]["values"][0]
    assert f"<td class=l>gyro bias x</td><td class=l>bg[0]</td><td>{bg / np.pi * 180 * 3600:.4g}</td>" in table
    assert "rad_s" not in table and "m_s2" not in table and ">mg<" in table


def test_sigmas_span_decades_on_a_log_axis_and_the_gate_lines_have_room(run_dir):
    """Sigmas from 1 cm (aided) to 5 m (an outage's end) on a linear axis
    left the aided ones a line on zero; the innovation panels ended at the
    data, the +-3 gate line on the frame under the next panel's title."""
    fig, _ = _figure(run_dir, "sigmas")
    assert fig.layout.yaxis.type == "log" and "(log)" in fig.layout.yaxis.title.text  # position
    fig, _ = _figure(run_dir, "innovations")
    for ax in (fig.layout.yaxis, fig.layout.yaxis2):
        assert list(ax.autorangeoptions.include) == [-4.5, 4.5]


def test_innovations_thinned_keep_their_bulk_as_well_as_their_extremes():
    """26 000 fixes' innovations thinned to 2 000 points by bin minima and
    maxima only were two bands at +-2 sigma with nothing near zero (where
    most lie): a plot that showed a bimodal filter; now half the points are
    an even stride, the extremes still all kept."""
    from inskit.jobs.report import INNOVATION_POINTS, decimate_scatter

    z = np.random.default_rng(1).standard_normal(78_000)
    k = decimate_scatter(len(z), z, INNOVATION_POINTS)
    assert len(k) <= INNOVATION_POINTS and np.all(np.diff(k) > 0)
    assert z.argmax() in k and z.argmin() in k
    inner = np.mean(np.abs(z[k]) < 1.0)
    assert inner > 0.3, inner  # 68 % of the samples; the extremes alone give about 0


def test_track_draws_the_fixes_under_the_solution(run_dir):
    """The fixes' markers were added after the lines, so on a long drive
    the grey and orange dots covered the forward line and its red outage
    stretches; now every line is drawn after (over) every marker, and the
    legend still lists the lines first."""
    fig, _ = _figure(run_dir, "track")
    modes = [t.mode for t in fig.data]
    assert "markers" in modes and "lines" in modes
    assert modes.index("lines") > max(i for i, m in enumerate(modes) if m == "markers")
    names = [t.name for t in fig.data]
    if "RTS smoother" in names:  # under the forward filter and its outage stretches
        assert names.index("RTS smoother") < names.index("forward filter") < names.index("forward, in GNSS outage")
    ranked = sorted(fig.data, key=lambda t: t.legendrank)
    assert [t.name for t in ranked][:2] == ["forward filter", "forward, in GNSS outage"]


def test_dozens_of_reasons_are_folded_below_the_first_twelve(run_dir, tmp_path):
    """A lost filter's verdict held 46 reasons (a recovery each), listed one
    a line: the page's first screen and a half were the list, the figures
    below; now the first 12 are listed and the rest fold under 'N more
    reasons and warnings', every one still on the page."""
    from inskit.jobs.report import HEADER_ITEMS, _Run, _header

    run = _Run(run_dir)
    run.summary = dict(run.summary, health={"verdict": "unhealthy",
                                            "reasons": [f"nhc: recovered at t = {k}.0 s" for k in range(46)],
                                            "warnings": ["zupt: mean NIS 0.5"]})
    text = _header(run)
    head, _, folded = text.partition("<details>")
    assert head.count("<li>") == HEADER_ITEMS + 1  # the twelve and the fold's own line
    assert f"{47 - HEADER_ITEMS} more reasons and warnings" in folded
    assert all(f"recovered at t = {k}.0 s" in text for k in range(46)) and "zupt: mean NIS 0.5" in folded


def test_a_fit_to_the_fixes_is_in_cm_below_a_metre_and_in_m_above():
    """A lost filter's fit to the used fixes, 632 km, was shown as '63240570.38 cm' (a helper found it)."""
    from inskit.jobs.report import _fit_rows

    rows = {r[0].split(",")[1].strip(): r[1:] for r in _fit_rows({"gnss_on_horizontal_rms_m": 0.0047,
                                                                    "gnss_on_vertical_rms_m": 632405.7038})[:2]}
    assert rows["horizontal RMS (not an accuracy)"] == ("0.47", "cm")
    assert rows["vertical RMS (not an accuracy)"] == ("632405.704", "m")


def test_a_browser_without_decompression_streams_says_so_and_keeps_the_tables(report, tmp_path):
    """The figures need the browser to unpack plotly.js (DecompressionStream);
    one without it shows a note where each figure would be, no error, and
    the tables."""
    text = Path(report["report"]).read_text()
    old = tmp_path / "old_browser.html"
    old.write_text(text.replace("<head>", "<head><script>delete window.DecompressionStream;</script>", 1))
    _, dom, errors = _render(old, tmp_path)
    assert not errors, errors
    assert 'data-figures-drawn="0"' in dom
    assert dom.count("<p class=\"note\">This browser cannot unpack the figures") == len(report["plots"])
    assert "outage-end horizontal RMS" in dom


def test_the_report_is_written_under_an_html_name_only(run_dir, tmp_path):
    """`inskit report RUN --out x.txt` wrote the HTML page as x.txt; evaluate's --plot refuses a name its
    format does not match, and so does the report now (before any work)."""
    for name in ("x.txt", "x.csv", "x"):
        with pytest.raises(InputError, match=r"the report is an HTML page: its name must end in \.html"):
            build_report(run_dir, tmp_path / name)
        assert not (tmp_path / name).exists()


@pytest.mark.parametrize("edit, said", [
    (lambda s: s.update(health="x"), r"health is text \(\"x\"\) where navigate writes an object"),
    (lambda s: s.update(outage_table={}),
     r"outage_table is an object \(\{\}\) where navigate writes a list of outages"),
    (lambda s: s.update(outage_table=[1]), r"outage_table\[0\] is a number \(1\) where navigate writes an object"),
    (lambda s: s.update(first_fix_time_s="abc"), r"first_fix_time_s is text \(\"abc\"\) where navigate writes a "
                                                 r"number or null"),
    (lambda s: s["health"].update(measurements=[1]), r"health.measurements is a list"),
    (lambda s: s.update(measurements={"gnss_pos": 5}), r"measurements.gnss_pos is a number \(5\) where navigate "
                                                        r"writes an object"),
    (lambda s: s.update(final_estimates={"bg": {"values": ["a"]}}), r"final_estimates.bg.values is a list"),
])
def test_a_summary_of_another_shape_is_refused_naming_the_key(run_dir, tmp_path, edit, said):
    """A summary.json edited by hand (or damaged into other valid JSON) was an internal error ('str' object
    has no attribute 'get' for ``"health": "x"``; could not convert string to float for a text
    ``first_fix_time_s``) or a page without the outages (``"outage_table": {}``).  Now the key, what it
    holds and what navigate writes there are said, as for any damaged input."""
    d = tmp_path / "edited"
    shutil.copytree(run_dir, d)
    for f in d.glob("report*.html"):
        f.unlink()
    s = json.loads((d / "summary.json").read_text())
    edit(s)
    (d / "summary.json").write_text(json.dumps(s))
    with pytest.raises(InputError, match=rf"^{re.escape(str(d / 'summary.json'))}: {said}.*: a damaged or "
                                         r"hand-edited summary.json\? \(run navigate again to write it\)$"):
        build_report(d)


def test_a_smoothed_run_without_its_smoothed_solution_is_refused(run_dir, tmp_path):
    """A `navigate --smooth` folder copied without solution_smoothed.* gave a page of the forward filter alone
    under the smoother's key figures and outage table, without a word.  Now it is refused, as a missing
    forward solution is."""
    d = tmp_path / "cut"
    shutil.copytree(run_dir, d)
    for f in d.glob("report*.html"):
        f.unlink()
    s = json.loads((d / "summary.json").read_text())
    assert s["solution"] == "forward" and not list(d.glob("solution_smoothed.*"))
    s["solution"] = "smoothed"
    (d / "summary.json").write_text(json.dumps(s))
    with pytest.raises(InputError, match=r"solution_smoothed.parquet or .csv is missing, and summary.json says the "
                                         r"run was smoothed"):
        build_report(d)
