import json
import subprocess
import sys

import pytest


@pytest.mark.slow
def test_reproduce_alignment_ga_command(tmp_path):
    r = subprocess.run([sys.executable, "-m", "inskit.cli", "reproduce", "alignment-ga", "--out", str(tmp_path),
                        "--json"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    d = json.loads(r.stdout)
    assert all("published" in e and "ours" in e for e in d["entries"])
    assert len(d["figures"]) == 4
    assert all(c["J_relative_difference"] < 0.01 for c in d["ga_checks"])


def test_reproduce_sweeps_qualitative_claims():
    from inskit.jobs.reproduce_alignment import sweep

    s6 = sweep("accel", n=4, ga_every=10)
    s7 = sweep("gyro", n=4, ga_every=10)
    assert all(abs(r["m"] - 1.0) < 1e-6 for r in s6[1:])  # fig. 6: m = 1
    assert all(abs(r["m"]) < 1e-6 for r in s7[1:])  # fig. 7: m = 0
    assert max(abs(r["alpha"]) + abs(r["beta"]) for r in s7) < 1e-9  # roll/pitch ignore the gyros
