"""NavSolution / ImuData / GnssData .to_dataframe() (issue 14 item 10): the column names of the files, units in
the names, the values converted at the edge (degrees) and nothing else changed."""

import numpy as np
import pandas as pd
import pytest

from inskit import io
from inskit.io.csv_formats import GNSS_COLUMNS, GNSS_VEL_COLUMNS, SOLUTION_COLUMNS
from inskit.io.parquet import NAVIGATION_COLUMNS
from inskit.simulation import StationaryTrajectory, ideal_imu
from inskit.types import GnssData, NavSolution
from inskit.units import G0


def _solution(n=5):
    t = np.arange(n) * 0.1
    lla = np.column_stack([np.full(n, np.radians(45.0)), np.radians(np.linspace(170.0, 190.0, n)), np.full(n, 100.0)])
    v = np.tile([1.0, 2.0, -0.5], (n, 1))
    rpy = np.radians(np.column_stack([np.full(n, 2.0), np.full(n, -3.0), np.linspace(10.0, 50.0, n)]))
    extra = {"sigma_n_m": np.full(n, 0.5), "bg_rad_s": np.zeros((n, 3))}
    return NavSolution.from_euler(t, lla, v, rpy, extra)


def test_solution_dataframe_has_the_file_columns_and_degrees(tmp_path):
    sol = _solution()
    df = sol.to_dataframe()
    assert list(df.columns[:10]) == SOLUTION_COLUMNS == list(NAVIGATION_COLUMNS)
    assert list(df.columns[10:]) == ["sigma_n_m", "bg_rad_s_0", "bg_rad_s_1", "bg_rad_s_2"]
    np.testing.assert_allclose(df.roll_deg, 2.0, atol=1e-12)
    np.testing.assert_allclose(df.pitch_deg, -3.0, atol=1e-12)
    np.testing.assert_allclose(df.yaw_deg, np.linspace(10.0, 50.0, 5), atol=1e-12)
    # longitude wrapped into (-180, 180] as the files hold it: 190 deg east is 170 deg west
    np.testing.assert_allclose(df.lon_deg, [170.0, 175.0, 180.0, -175.0, -170.0], atol=1e-12)
    assert df.vd_m_s.tolist() == [-0.5] * 5 and df.time_s.tolist() == sol.time.tolist()
    # the CSV and Parquet files of the same solution carry the same names, the same values
    io.write_solution(tmp_path / "s.csv", sol)
    io.write_solution(tmp_path / "s.parquet", sol)
    csv = pd.read_csv(tmp_path / "s.csv")
    assert list(csv.columns) == list(df.columns)
    np.testing.assert_allclose(csv.to_numpy(), df.to_numpy(), rtol=1e-14, atol=1e-12)
    pq = pd.read_parquet(tmp_path / "s.parquet")
    assert list(pq.columns) == list(df.columns)
    np.testing.assert_array_equal(pq.to_numpy(), df.to_numpy())


def test_imu_dataframe_increments_and_rates():
    """A level IMU at rest: specific force -g along body z, the increments as held."""
    imu = ideal_imu(StationaryTrajectory((np.radians(45.0), 0.0, 0.0)), np.arange(0.0, 1.0, 0.01), nodes=1)
    inc = imu.to_dataframe()
    assert list(inc.columns) == ["time_s", "dtheta_x_rad", "dtheta_y_rad", "dtheta_z_rad", "dv_x_m_s", "dv_y_m_s",
                                 "dv_z_m_s"]
    np.testing.assert_array_equal(inc.dv_z_m_s, imu.dv_b[:, 2])
    rates = imu.to_dataframe(rates=True)
    assert list(rates.columns) == ["time_s", "gyro_x_rad_s", "gyro_y_rad_s", "gyro_z_rad_s", "accel_x_m_s2",
                                   "accel_y_m_s2", "accel_z_m_s2"]
    assert rates.accel_z_m_s2.iloc[1:].to_numpy() == pytest.approx(-G0, rel=3e-3)  # normal gravity at 45 deg


def test_gnss_dataframe_has_the_file_columns(tmp_path):
    n = 3
    lla = np.column_stack([np.full(n, np.radians(-33.0)), np.full(n, np.radians(200.0)), np.full(n, 20.0)])
    g = GnssData(np.arange(n, dtype=float), lla, np.full((n, 3), 0.02))
    df = g.to_dataframe()
    assert list(df.columns) == GNSS_COLUMNS
    np.testing.assert_allclose(df.lon_deg, -160.0, atol=1e-12)
    gv = GnssData(g.time, lla, g.sigma_ned, np.ones((n, 3)), np.full((n, 3), 0.1))
    dfv = gv.to_dataframe()
    assert list(dfv.columns) == GNSS_COLUMNS + GNSS_VEL_COLUMNS
    io.write_gnss(tmp_path / "g.csv", gv)
    assert list(pd.read_csv(tmp_path / "g.csv").columns) == list(dfv.columns)
