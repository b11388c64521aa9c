"""RTKLIB .pos writer and errors against a reference (inskit.gnss.solution).

The writer's output is read back by the repository's own RTKLIB reader
(:func:`inskit.io.rtklib.read_pos`), which parses RTKLIB's real files.
"""

import warnings
from pathlib import Path

import numpy as np
import pytest

from inskit import earth
from inskit.gnss.solution import errors_against, gpst_strings, write_pos
from inskit.gnss.time import gps_seconds
from inskit.io.rtklib import read_pos

DATA = Path(__file__).resolve().parent / "data" / "gnss"
ABPO_XYZ = np.array([4097216.6805, 4429119.0287, -2065771.3676])


def _spp(obs_name, nav_name):
    from inskit.gnss.rinex import read_nav, read_obs
    from inskit.gnss.spp import spp

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return spp(read_obs(DATA / obs_name), read_nav(DATA / nav_name))


@pytest.fixture(scope="module")
def walk():
    """40 epochs of the rtklibexplorer walk: positions and Doppler velocities."""
    return _spp("gnss_1730_first40.obs", "gnss_1730.nav")


@pytest.fixture(scope="module")
def abpo():
    """240 epochs of IGS ABPO: code only (no Doppler)."""
    return _spp("abpo0080_0000-0200.15o", "abpo0080.15n")


def test_gpst_strings():
    t = np.array([gps_seconds(2015, 1, 8, 0, 0, 0.0), gps_seconds(2025, 8, 28, 17, 30, 39.7485)])
    assert gpst_strings(t).tolist() == ["2015/01/08 00:00:00.000", "2025/08/28 17:30:39.748"]


def test_pos_round_trip_with_velocity(tmp_path, walk):
    p = write_pos(tmp_path / "walk.pos", walk, header_lines=("inp file  : gnss_1730_first40.obs",))
    text = p.read_text().splitlines()
    assert text[0].startswith("% program") and any(line.startswith("%  GPST") for line in text)
    g, week0 = read_pos(p, quality=(5,))
    assert week0 == int(walk.week[0]) and len(g) == 40
    # time tags to the millisecond, latitude/longitude to 1e-9 deg (0.1 mm), height to 0.1 mm
    np.testing.assert_allclose(g.time, walk.sow, atol=6e-4)
    np.testing.assert_allclose(np.degrees(g.lla[:, :2]), np.degrees(walk.lla[:, :2]), atol=1e-9)
    np.testing.assert_allclose(g.lla[:, 2], walk.lla[:, 2], atol=1e-4)
    np.testing.assert_allclose(g.sigma_ned, walk.sigma_enu[:, [1, 0, 2]], atol=1e-4)
    assert g.has_velocity
    v = walk.v_enu
    np.testing.assert_allclose(g.v_n, np.column_stack([v[:, 1], v[:, 0], -v[:, 2]]), atol=1e-5)
    np.testing.assert_allclose(g.sigma_v_ned, walk.sigma_v_enu[:, [1, 0, 2]], atol=1e-5)
    # RTKLIB's columns: Q = 5 and ns, the signed-root covariances keep their sign
    row = text[-1].split()
    assert row[5] == "5" and int(row[6]) == walk.n_sats[-1] == 4
    P = walk.cov_enu[-1]
    assert float(row[10]) == pytest.approx(np.sign(P[1, 0]) * np.sqrt(abs(P[1, 0])), abs=1e-4)


def test_pos_without_doppler_has_no_velocity_columns(tmp_path, abpo):
    p = write_pos(tmp_path / "abpo.pos", abpo)
    assert "vn(m/s)" not in p.read_text()
    g, _ = read_pos(p, quality=(5,))
    assert len(g) == 240 and not g.has_velocity
    # read back and scored: the same errors as the solution itself (to the 1e-9 deg rounding)
    e_back = earth.ecef_to_enu(earth.lla_to_ecef(g.lla), earth.ecef_to_lla(ABPO_XYZ))
    e_sol, _ = errors_against(abpo, ABPO_XYZ)
    assert np.abs(e_back - e_sol).max() < 1e-3


def test_unsolved_epochs_are_left_out_and_an_existing_file_is_replaced_whole(tmp_path, abpo):
    import dataclasses

    st = abpo.status.copy()
    st[:10] = 0
    sol = dataclasses.replace(abpo, status=st)
    p = tmp_path / "x.pos"
    p.write_text("old\n")
    write_pos(p, sol)
    g, _ = read_pos(p, quality=(5,))
    assert len(g) == 230 and "old" not in p.read_text()
    assert not list(tmp_path.glob(".part-*"))


def test_errors_against_a_known_offset(abpo):
    """Shift the reference 3 m north and 1 m up of the solution mean: the
    errors move by exactly that (ENU at the reference)."""
    _, s0 = errors_against(abpo, ABPO_XYZ)
    lla = earth.ecef_to_lla(ABPO_XYZ)
    shifted = earth.ned_to_ecef(np.array([3.0, 0.0, -1.0]), lla)
    enu, s1 = errors_against(abpo, shifted)
    np.testing.assert_allclose(np.array(s1["mean_enu_m"]) - s0["mean_enu_m"], [0.0, -3.0, -1.0], atol=1e-5)
    np.testing.assert_allclose(s1["std_enu_m"], s0["std_enu_m"], atol=1e-5)
    assert s1["epochs_solved"] == s1["epochs_total"] == 240
    h = np.hypot(enu[:, 0], enu[:, 1])
    assert s1["horizontal_rms_m"] == pytest.approx(np.sqrt(np.mean(h**2)))
    assert s1["max_horizontal_m"] == pytest.approx(h.max())
    # per-epoch references with NaN rows: those epochs are not scored
    ref = np.tile(ABPO_XYZ, (240, 1))
    ref[::2] = np.nan
    enu2, s2 = errors_against(abpo, ref)
    assert s2["epochs_solved"] == 120 and np.isnan(enu2[::2]).all()
    with pytest.raises(ValueError, match="shape"):
        errors_against(abpo, np.zeros((5, 3)))
