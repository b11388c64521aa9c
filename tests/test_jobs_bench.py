"""The kernel figures of inskit bench run what they say: the drive filter jobs are the navigate bench drive's
dynamic car, every fix used, the 4 Hz job with four times the fixes."""

import pytest

from inskit.jobs import bench as B


@pytest.mark.slow
def test_drive_filter_jobs_run_the_dynamic_drive(tmp_path, monkeypatch):
    monkeypatch.setenv("INSKIT_BENCH_CACHE", str(tmp_path))
    jobs = B._drive_filter_jobs(quick=True)
    n = jobs.pop("epochs")
    assert n == 600 * 200
    one, four = (jobs[k]() for k in ("lc_drive_epochs_per_s", "lc_drive_4hz_epochs_per_s"))
    for out in (one, four):
        assert out.counts["gnss_pos"]["rejected"] == 0 and out.counts["nhc"]["used"] >= 5990
        assert out.counts["zupt"]["used"] > 0  # the car stands still at its start
    assert 3.9 < four.counts["gnss_pos"]["used"] / one.counts["gnss_pos"]["used"] < 4.1
    assert (one.nav.v_n[:, :2] ** 2).sum(axis=1).max() > 100.0  # it drives (over 10 m/s), not a static log
