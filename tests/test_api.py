"""The Python face (issue 14 item 10): ``import inskit`` is cheap and lists its names, ``docs/api.md`` runs as
written (the bundled drive read, navigated, turned into a DataFrame and plotted), ``navigate`` writes only when
asked, and ``simulate`` / ``mechanize`` forward to the jobs the commands run."""

import json
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import inskit
from inskit.errors import InputError
from inskit.io.csv_formats import SOLUTION_COLUMNS

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "api.md"
HEAVY = ("numba", "scipy", "pandas", "matplotlib")


def _modules_after(code):
    r = subprocess.run([sys.executable, "-c", f"{code}; import sys, json; print(json.dumps(sorted(sys.modules)))"],
                       capture_output=True, text=True, check=True)
    return set(json.loads(r.stdout.splitlines()[-1]))


def test_import_inskit_pulls_in_no_heavy_library():
    loaded = _modules_after("import inskit; dir(inskit)")
    assert not loaded & set(HEAVY), sorted(loaded & set(HEAVY))
    # the CLI module (what `inskit --version` imports) neither: its cost is numpy and click
    loaded = _modules_after("import inskit.cli")
    assert not loaded & set(HEAVY), sorted(loaded & set(HEAVY))


def test_version_from_the_command_line():
    r = subprocess.run([sys.executable, "-m", "inskit.cli", "--version"], capture_output=True, text=True, check=False)
    assert r.returncode == 0 and r.stdout.strip() == f"inskit, version {inskit.__version__}"


def test_dir_lists_every_name_and_the_doc_describes_it():
    names = dir(inskit)
    text = DOC.read_text()
    for name in inskit.__all__:
        assert name in names
        assert getattr(inskit, name) is not None
        if name != "__version__":
            assert f"`{name}" in text or f" {name}" in text, f"docs/api.md does not mention {name}"
    assert {"io", "jobs", "strapdown"} <= set(names)
    assert inskit.io.read_imu is inskit.read_imu and inskit.read_truth is inskit.read_solution
    with pytest.raises(AttributeError, match="no attribute 'navigat'"):
        inskit.navigat  # noqa: B018


@pytest.fixture(scope="module")
def walkthrough(tmp_path_factory):
    """Every ```python block of docs/api.md, in order, in one namespace, from a folder that sees the
    repository's data/ and examples/ as the repository root does (the plot lands there, not in the tree)."""
    import os

    work = tmp_path_factory.mktemp("api_doc")
    for d in ("data", "examples"):
        (work / d).symlink_to(ROOT / d, target_is_directory=True)
    blocks = re.findall(r"```python\n(.*?)```", DOC.read_text(), re.DOTALL)
    assert len(blocks) >= 4
    ns = {}
    old = os.getcwd()
    os.chdir(work)
    try:
        for i, block in enumerate(blocks):
            exec(compile(block, f"docs/api.md block {i + 1}", "exec"), ns)  # noqa: S102
    finally:
        os.chdir(old)
    import matplotlib.pyplot as plt

    plt.close("all")
    return ns, work


def test_walkthrough_reads_the_bundled_drive(walkthrough):
    ns, _ = walkthrough
    assert len(ns["imu"]) == 54860 and len(ns["gnss"]) == 2197  # data/drive_0708/README.md
    assert ns["rates"].columns[0] == "time_s" and len(ns["rates"]) == len(ns["imu"])


def test_walkthrough_navigates_as_the_doc_says(walkthrough):
    """The prose: the verdict is healthy and the forward outage-end horizontal RMS is under 3 m."""
    ns, _ = walkthrough
    run = ns["run"]
    assert run.health["verdict"] == "healthy" and run.files == []
    assert run.summary["outage_end_horizontal_rms_m"] < 3.0
    assert len(run.summary["outage_table"]) == 11
    assert run.solution is run.forward and run.smoothed is None


def test_walkthrough_names_the_missing_time_offset(walkthrough):
    """The prose: without its -0.26 s the drive is unhealthy and the first reason names the offset."""
    ns, _ = walkthrough
    late = ns["late"]
    assert late.health["verdict"] == "unhealthy"
    assert late.health["reasons"][0].startswith("gnss_pos: the fixes fit an IMU time offset of -0.26")
    assert abs(late.summary["time_offset_check"]["best_s"] + 0.26) < 0.01


def test_walkthrough_dataframe_and_plot(walkthrough):
    ns, work = walkthrough
    df, run = ns["df"], ns["run"]
    assert list(df.columns[:10]) == SOLUTION_COLUMNS
    assert len(df) == len(run.solution) == run.summary["epochs"]
    np.testing.assert_allclose(df.lat_deg, np.degrees(run.solution.lla[:, 0]), rtol=1e-15)
    png = work / "drive_0708.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_navigate_writes_only_when_asked(walkthrough, tmp_path):
    """out_dir= writes what `inskit navigate` writes, summary.json last with the list; a folder holding results
    is refused unless overwrite=True.  Overrides change config sections (here: no plots, CSV only)."""
    ns, _ = walkthrough
    cfg = ns["run"].config
    out = tmp_path / "run"
    run = inskit.navigate(cfg, out_dir=out, output={"plots": False, "format": "csv"})
    names = sorted(p.name for p in out.iterdir())
    assert names == ["config_used.json", "innovations.csv", "solution_forward.csv", "summary.json"]
    s = json.loads((out / "summary.json").read_text())
    assert sorted(Path(f).name for f in s["files"]) == names and len(run.files) == 4
    # the same figures as the run that wrote nothing (the same config, the same engine)
    assert s["outage_end_horizontal_rms_m"] == pytest.approx(ns["run"].summary["outage_end_horizontal_rms_m"],
                                                             rel=1e-12)
    with pytest.raises(InputError, match=r"already holds results.*overwrite=True"):
        inskit.navigate(cfg, out_dir=out)
    assert run.config.output.plots is False and cfg.output.plots is True  # the override touched a copy


def test_navigate_never_overwrites_its_inputs_even_with_overwrite(walkthrough, tmp_path):
    """navigate(cfg, truth=run/solution_forward.csv, out_dir=run, overwrite=True) read the truth and replaced it
    with its own solution: the API checked no output against any input.  Refused before any work now, and the
    folder is left as it was."""
    ns, _ = walkthrough
    cfg = ns["run"].config
    out = tmp_path / "run"
    out.mkdir()
    truth = out / "solution_forward.csv"
    truth.write_text("mine\n")
    with pytest.raises(InputError, match=re.escape(f"{truth}: would overwrite an input of this run") +
                       r".*overwrite=True replaces results, never what the run reads: choose another out_dir"):
        inskit.navigate(cfg, out_dir=out, truth=truth, overwrite=True)
    assert truth.read_text() == "mine\n" and sorted(p.name for p in out.iterdir()) == ["solution_forward.csv"]


def test_navigate_config_forms_and_errors(tmp_path, monkeypatch):
    """A dict config starts its relative paths in the working directory; bad keys and files are named."""
    monkeypatch.chdir(tmp_path)
    with pytest.raises(InputError, match=re.escape(f"{tmp_path / 'imu.csv'}: no such file (field 'imu.file')")):
        inskit.navigate({"imu": {"file": "imu.csv"}, "gnss": {"file": "gnss.csv"}})
    (tmp_path / "imu.csv").write_text("time_s\n")
    (tmp_path / "gnss.csv").mkdir()  # a folder given as a file: named by its key, before anything is read
    with pytest.raises(InputError, match=re.escape(f"{tmp_path / 'gnss.csv'}: is a folder; expected a file "
                                                   "(field 'gnss.file')")):
        inskit.navigate({"imu": {"file": "imu.csv"}, "gnss": {"file": "gnss.csv"}})
    with pytest.raises(inskit.ConfigError, match=r"filter\.scheme"):
        inskit.navigate(ROOT / "examples" / "drive_0708.toml", filter={"scheme": "kalman"})
    with pytest.raises(InputError, match=r"expected a config file path, a dict or a NavigateConfig, got int"):
        inskit.navigate(3)


SCENARIO = """name = "still"
[start]
lat_deg = 45.0
lon_deg = 10.0
height_m = 100.0
[imu]
rate_hz = 100.0
[[segment]]
type = "static"
duration_s = 10.0
"""


def test_simulate_and_mechanize(tmp_path):
    """An ideal IMU at rest for 10 s, written and read back, mechanized from the truth: it stays put (ideal
    increments leave the integration error only, well under a millimetre)."""
    sc = tmp_path / "still.toml"
    sc.write_text(SCENARIO)
    sim = inskit.simulate(sc, out_dir=tmp_path / "sim")
    assert sorted(p.name for p in (tmp_path / "sim").iterdir()) == ["gnss.csv", "imu.csv", "truth.csv"]
    imu = inskit.read_imu(tmp_path / "sim" / "imu.csv")
    truth = inskit.read_truth(tmp_path / "sim" / "truth.csv")
    assert len(imu) == len(sim.imu) == 1001
    sol = inskit.mechanize(imu, truth.state(0))
    assert isinstance(sol, inskit.NavSolution)
    from inskit.analysis import nav_error

    err = nav_error(sol, truth)
    assert np.abs(err.pos_ned).max() < 1e-3


def test_arguments_of_the_wrong_type_are_named_before_any_work(tmp_path):
    """navigate(cfg, truth=3) and out_dir=3 were 'expected str, bytes or os.PathLike object, not int' after the
    whole run, smooth='no' smoothed (a non-empty string is true); simulate(sc, 1.5) was numpy's 'SeedSequence
    expects int', seed=-1 'expected non-negative integer', a dict scenario a TypeError from pathlib."""
    cfg = ROOT / "examples" / "drive_0708.toml"
    with pytest.raises(InputError, match=r"^truth must be a file path \(str or Path\) or a NavSolution, got int 3$"):
        inskit.navigate(cfg, truth=3)
    with pytest.raises(InputError, match=r"^out_dir must be a file path \(str or Path\), True or None, got int 3$"):
        inskit.navigate(cfg, out_dir=3)
    with pytest.raises(InputError, match=r"^smooth must be True or False, got 'no'$"):
        inskit.navigate(cfg, smooth="no")
    with pytest.raises(InputError, match=r"^log must be a function \(or None\), got str 'x'$"):
        inskit.navigate(cfg, log="x")
    sc = tmp_path / "still.toml"
    sc.write_text(SCENARIO)
    for seed, shown in ((1.5, "float 1.5"), ("1", "str '1'"), (-1, "-1"), (True, "bool True")):
        with pytest.raises(InputError, match=rf"^seed must be an integer >= 0 or a numpy\.random\.Generator, got "
                                             rf"{re.escape(shown)}$"):
            inskit.simulate(sc, seed)
    with pytest.raises(InputError, match=r"^scenario must be a file path \(str or Path\) or a Scenario, got dict"):
        inskit.simulate({"name": "still"})
    with pytest.raises(InputError, match=r"^truth_rate_hz must be a number \[Hz\] \(or None\), got str '10'$"):
        inskit.simulate(sc, truth_rate_hz="10")
    a, b = inskit.simulate(sc, np.int64(3)), inskit.simulate(str(sc), 3, truth_rate_hz=np.float64(100.0))
    np.testing.assert_array_equal(a.imu.dv_b, b.imu.dv_b)


def test_a_generator_seed_is_drawn_from_and_spawns_the_raw_gnss_child(tmp_path):
    """seed=numpy.random.Generator was let through and then failed on a [raw_gnss] scenario ('SeedSequence
    expects int or sequence of ints ... not Generator'); now a fresh default_rng(s) gives the numbers of seed=s,
    raw observations included, and a generator used twice gives another run (it advances)."""
    sc = tmp_path / "raw.toml"
    sc.write_text(SCENARIO.replace("rate_hz = 100.0", "rate_hz = 100.0\ngrade = \"tactical\"")
                  + "[raw_gnss]\nrate_hz = 1.0\n")

    def obs(sim):
        return np.concatenate([np.ravel(v) for _, v in sorted(sim.raw.obs.items())])

    by_int = inskit.simulate(sc, 3)
    g = np.random.default_rng(3)
    by_gen = inskit.simulate(sc, g)
    np.testing.assert_array_equal(by_gen.imu.dv_b, by_int.imu.dv_b)
    np.testing.assert_array_equal(by_gen.gnss.lla, by_int.gnss.lla)
    np.testing.assert_array_equal(obs(by_gen), obs(by_int))
    again = inskit.simulate(sc, g)
    assert not np.array_equal(again.imu.dv_b, by_int.imu.dv_b)
    assert not np.array_equal(obs(again), obs(by_int), equal_nan=True)
    with pytest.raises(InputError, match=r"^seed must be an integer >= 0 or a numpy\.random\.Generator, got "
                                         r"SeedSequence"):
        inskit.simulate(sc, np.random.SeedSequence(3))


def test_navigate_into_a_file_is_refused_before_the_run(tmp_path):
    """navigate(cfg, out_dir=<a file>) raised NotADirectoryError ('[Errno 20] Not a directory'), not an inskit
    error; now the InputError that names the file, before the filter runs."""
    f = tmp_path / "results"
    f.write_text("mine\n")
    with pytest.raises(InputError, match=rf"^{re.escape(str(f))}: is a file; expected an output folder$"):
        inskit.navigate(ROOT / "examples" / "drive_0708.toml", out_dir=f)
    with pytest.raises(InputError, match=rf"^{re.escape(str(f))}: is a file; expected an output folder \(so "
                                         rf"{re.escape(str(f / 'run'))} cannot be made\)$"):
        inskit.navigate(ROOT / "examples" / "drive_0708.toml", out_dir=f / "run")
    assert f.read_text() == "mine\n"


def test_simulate_refuses_file_options_without_a_folder(tmp_path):
    """simulate(sc, plot=True) or overwrite=True without out_dir wrote nothing and said nothing."""
    sc = tmp_path / "still.toml"
    sc.write_text(SCENARIO)
    for name in ("plot", "overwrite"):
        with pytest.raises(InputError, match=rf"^{name}=True would be ignored: without out_dir nothing is written"):
            inskit.simulate(sc, **{name: True})
    assert sorted(p.name for p in tmp_path.iterdir()) == ["still.toml"]
