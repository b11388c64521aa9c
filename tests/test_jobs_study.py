"""Studies on Dask (inskit.jobs.study): results independent of the worker
count, resumable without repeating a finished run, bit for bit."""

from __future__ import annotations

import json
from pathlib import Path

import click
import numpy as np
import pandas as pd
import pytest
from click.testing import CliRunner

from inskit.cli_study import register
from inskit.errors import ConfigError
from inskit.jobs.study import load_spec, run_seed, run_study

CAR = Path(__file__).resolve().parents[1] / "examples" / "car.toml"
EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "study_outage_grades.toml"

#: 2 grades x 4 runs, first 100 s of the car drive (it starts moving at 60 s), 30 s outage from 70 s
TINY = f"""
scenario = "{CAR}"
kind = "sweep"
grades = ["tactical", "industrial-mems"]
runs = 4
seed = 3
duration_s = 100.0
[outage]
start_s = 65.0
length_s = 30.0
"""


def _spec(folder, text=TINY, name="tiny.toml"):
    p = Path(folder) / name
    p.write_text(text)
    return p


class _Killed(Exception):
    pass


def _stop_after(k):
    """A progress callback that stops the study after ``k`` runs are written."""

    def make(total, initial):
        seen = [0]

        def update(n):
            seen[0] += n
            if seen[0] >= k:
                raise _Killed

        return update

    return make


@pytest.fixture(scope="module")
def one_worker(tmp_path_factory):
    """The study run through the CLI on a local cluster of 1 worker."""
    d = tmp_path_factory.mktemp("study1")
    g = click.Group()
    register(g)
    r = CliRunner().invoke(g, ["study", str(_spec(d)), "--out", str(d / "out"), "--workers", "1", "--json"])
    assert r.exit_code == 0, r.output
    return d / "out", json.loads(r.stdout.strip().splitlines()[-1])


def test_seeds_are_spawned_children():
    # NEP 19: SeedSequence(base).spawn(n)[c].spawn(m)[r] has spawn_key (c, r)
    child = np.random.SeedSequence(7).spawn(3)[2].spawn(5)[4]
    assert run_seed(7, 2, 4) == int(child.generate_state(1, np.uint64)[0])
    seeds = {run_seed(7, c, r) for c in range(3) for r in range(50)}
    assert len(seeds) == 150


def test_cli_one_worker_ranks_grades(one_worker):
    out, res = one_worker
    runs = pd.read_parquet(out / "runs.parquet")
    assert len(runs) == 8 and res["runs_computed"] == 8 and res["execution"]["workers"] == 1
    assert list(zip(runs["case"], runs["run"])) == [(c, r) for c in range(2) for r in range(4)]
    # a tactical IMU (1 mg turn-on, 0.35 deg/h) coasts a 30 s outage within a few metres
    # (0.5 * 1e-3 g * 30^2 = 4.4 m at 1 sigma of the unestimated bias); the MEMS does worse
    rank = res["ranking"]
    assert [e["grade"] for e in rank] == ["tactical", "industrial-mems"]
    assert rank[0]["median"] < 10.0 and rank[1]["median"] > rank[0]["median"]
    # summary statistics are those of the run table
    summ = pd.read_parquet(out / "summary.parquet")
    for c in (0, 1):
        x = runs.loc[runs["case"] == c, "outage_end_horizontal_m"].to_numpy()
        row = summ[(summ["case"] == c) & (summ["figure"] == "outage_end_horizontal_m")].set_index("statistic")
        assert row.loc["count", "value"] == 4
        assert row.loc["p90", "value"] == np.percentile(x, 90)
        assert row.loc["median", "value"] == np.median(x)
    saved = json.loads((out / "summary.json").read_text())
    assert saved["ranking"] == json.loads(json.dumps(rank))
    assert (out / "study.png").stat().st_size > 5000


def test_two_workers_give_the_same_tables(one_worker, tmp_path):
    out1, _ = one_worker
    res = run_study(_spec(tmp_path), tmp_path / "out", workers=2)
    assert res["execution"]["workers"] == 2
    for name in ("runs.parquet", "summary.parquet"):
        pd.testing.assert_frame_equal(pd.read_parquet(out1 / name), pd.read_parquet(tmp_path / "out" / name))
        assert (out1 / name).read_bytes() == (tmp_path / "out" / name).read_bytes()


def test_interrupted_study_resumes_without_repeating(one_worker, tmp_path):
    out1, _ = one_worker
    spec = _spec(tmp_path)
    with pytest.raises(_Killed):
        run_study(spec, tmp_path / "out", workers=2, progress=_stop_after(2))
    done = pd.concat([pd.read_parquet(p) for p in (tmp_path / "out" / "runs").glob("part-*.parquet")])
    assert 2 <= len(done) < 8 and not (tmp_path / "out" / "runs.parquet").exists()
    res = run_study(spec, tmp_path / "out", workers=1)
    assert res["runs_computed"] == 8 - len(done) and res["runs_reused"] == len(done)
    for name in ("runs.parquet", "summary.parquet"):
        assert (out1 / name).read_bytes() == (tmp_path / "out" / name).read_bytes()
    # finished: a third run computes nothing (and starts no cluster)
    again = run_study(spec, tmp_path / "out")
    assert again["runs_computed"] == 0 and "workers" not in again["execution"]


def test_a_different_study_in_the_same_folder_is_refused(one_worker, tmp_path):
    out1, _ = one_worker
    spec = _spec(tmp_path, TINY.replace("runs = 4", "runs = 5"))
    with pytest.raises(ConfigError, match="different study"):
        run_study(spec, out1)


@pytest.mark.parametrize("text, match", [
    (TINY + "colour = 1\n", "colour"),
    (TINY.replace('kind = "sweep"', 'kind = "monte-carlo"'), "one grade"),
    (TINY.replace("start_s = 65.0", "start_s = 80.0"), "after the end"),
    (TINY.replace('"tactical"', '"military"'), "grades"),
    (TINY.replace("runs = 4", "runs = 0"), "runs"),
])
def test_bad_specs_are_config_errors(tmp_path, text, match):
    with pytest.raises(ConfigError, match=match):
        run_study(_spec(tmp_path, text), tmp_path / "out")


def test_example_spec_is_valid():
    spec, scenario = load_spec(EXAMPLE)
    assert scenario == CAR.resolve() and spec.outage.length_s == 60.0 and spec.kind == "sweep"
