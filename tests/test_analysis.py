import numpy as np
import pytest

from inskit import analysis, earth
from inskit.errors import InputError
from inskit.types import NavSolution
from inskit.units import ARCMIN


def make(t, lla, yaw=0.0):
    n = len(t)
    return NavSolution.from_euler(t, np.tile(lla, (n, 1)), np.zeros((n, 3)), np.tile([0, 0, yaw], (n, 1)))


def test_known_offsets():
    ref = np.array([np.radians(40), np.radians(-105), 1600.0])
    t = np.arange(0.0, 10.0, 1.0)
    truth = make(t, ref)
    moved = earth.ned_to_lla([3.0, 4.0, -1.0], ref)
    sol = make(t, moved, yaw=np.radians(0.5))
    err = analysis.nav_error(sol, truth)
    assert np.allclose(err.pos_ned, [3.0, 4.0, -1.0], atol=1e-6)
    s = analysis.summarize(err)
    assert s["horizontal_m"]["rms"] == pytest.approx(5.0, abs=1e-6)
    assert s["yaw_arcmin"]["final"] == pytest.approx(30.0, rel=1e-9)
    assert s["roll_arcmin"]["max"] == pytest.approx(0.0, abs=1e-9)


def test_yaw_wraps():
    t = np.arange(3.0)
    ref = np.array([0.5, 0.5, 0.0])
    err = analysis.nav_error(make(t, ref, np.radians(179.9)), make(t, ref, np.radians(-179.9)))
    assert err.att_rpy[0, 2] / ARCMIN == pytest.approx(-12.0, abs=1e-6)


def test_no_overlap_is_an_error():
    ref = np.array([0.5, 0.5, 0.0])
    with pytest.raises(InputError, match="do not overlap"):
        analysis.nav_error(make(np.arange(3.0), ref), make(np.arange(3.0) + 100, ref))


def test_plot_writes_png(tmp_path):
    ref = np.array([0.5, 0.5, 0.0])
    t = np.arange(0.0, 5.0, 0.5)
    err = analysis.nav_error(make(t, ref), make(t, ref))
    p = analysis.plot_errors(err, tmp_path / "e.png")
    assert (tmp_path / "e.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert p == tmp_path / "e.png"
