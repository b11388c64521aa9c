import numpy as np
import pytest

from inskit import earth


def test_radii_at_landmarks():
    rn, re = earth.principal_radii(0.0)
    assert rn == pytest.approx(earth.A * (1 - earth.E2), rel=1e-14)
    assert re == pytest.approx(earth.A, rel=1e-14)
    rn, re = earth.principal_radii(np.pi / 2)
    # at the pole both radii equal a^2 / b
    assert rn == pytest.approx(earth.A**2 / earth.B, rel=1e-9)
    assert re == pytest.approx(earth.A**2 / earth.B, rel=1e-9)


def test_somigliana_equator_and_pole():
    assert earth.somigliana(0.0) == pytest.approx(earth.GAMMA_E, abs=1e-12)
    assert earth.somigliana(np.pi / 2) == pytest.approx(earth.GAMMA_P, abs=1e-9)
    # 45 deg: the textbook value 9.806199 m/s^2
    assert earth.somigliana(np.radians(45)) == pytest.approx(9.806199, abs=2e-6)


def test_free_air_gradient():
    # d gamma / dh is about -3.086e-6 1/s^2 near the surface
    lat = np.radians(45)
    grad = (earth.gravity_down(lat, 100.0) - earth.gravity_down(lat, 0.0)) / 100.0
    assert grad == pytest.approx(-3.086e-6, rel=3e-3)


def test_normal_gravity_vs_j2_field():
    # the GM+J2 field leaves out J4 and higher (relative size ~1e-5 of g): it agrees
    # with Somigliana normal gravity to 1.5e-4 m/s^2 everywhere, 1.2e-4 at the poles
    rng = np.random.default_rng(1)
    lla = np.column_stack([rng.uniform(-1.5, 1.5, 50), rng.uniform(-3, 3, 50), rng.uniform(-100, 10000, 50)])
    r = earth.lla_to_ecef(lla)
    diff = np.linalg.norm(earth.gravity_ecef(r) - earth.gravity_ecef_j2(r), axis=1)
    assert diff.max() < 1.5e-4
    assert diff.max() > 1e-5  # and the test can tell the two fields apart
    # and the normal field points down the ellipsoid normal with magnitude gamma_d
    g_n = np.einsum("nji,nj->ni", earth.dcm_en(lla[:, 0], lla[:, 1]), earth.gravity_ecef(r))
    assert np.allclose(g_n[:, 2], earth.gravity_down(lla[:, 0], lla[:, 2]), atol=1e-12)
    assert np.abs(g_n[:, 1]).max() < 1e-12


def test_lla_ecef_round_trip(rng):
    lla = np.column_stack([rng.uniform(-np.pi / 2, np.pi / 2, 1000), rng.uniform(-np.pi, np.pi, 1000),
                           rng.uniform(-5000, 1e6, 1000)])
    lla[:3, 0] = [np.pi / 2, -np.pi / 2, 0.0]
    back = earth.ecef_to_lla(earth.lla_to_ecef(lla))
    assert np.abs(back[:, 0] - lla[:, 0]).max() < 1e-13
    assert np.abs(back[:, 2] - lla[:, 2]).max() < 1e-6
    ok = np.abs(np.cos(lla[:, 0])) > 1e-9
    dlon = np.angle(np.exp(1j * (back[ok, 1] - lla[ok, 1])))
    assert np.abs(dlon).max() < 1e-12


def test_known_ecef_point():
    # a point on the equator/prime meridian and one on the pole
    assert np.allclose(earth.lla_to_ecef([0, 0, 0]), [earth.A, 0, 0], atol=1e-9)
    assert np.allclose(earth.lla_to_ecef([np.pi / 2, 0, 0]), [0, 0, earth.B], atol=1e-4)


def test_ned_enu_offsets():
    ref = np.array([np.radians(40), np.radians(-105), 1600.0])
    p = np.array([[100.0, -50.0, 3.0], [0.0, 0.0, 0.0]])
    back = earth.lla_to_ned(earth.ned_to_lla(p, ref), ref)
    assert np.allclose(back, p, atol=1e-6)  # a micrometre
    # 1 m north is 1/(R_N+h) rad of latitude
    rn, _ = earth.principal_radii(ref[0], ref[2])
    lla = earth.ned_to_lla([1.0, 0.0, 0.0], ref)
    assert (lla[0] - ref[0]) * rn == pytest.approx(1.0, rel=1e-6)
    assert np.allclose(earth.ecef_to_enu(earth.ned_to_ecef(p, ref), ref), p[:, [1, 0, 2]] * [1, 1, -1])


def test_dcm_en_orthonormal_and_down_is_normal():
    C = earth.dcm_en(np.radians([10.0, -70.0]), np.radians([20.0, 170.0]))
    assert np.allclose(C @ np.swapaxes(C, -1, -2), np.eye(3), atol=1e-15)
    assert np.allclose(np.linalg.det(C), 1.0)
    up = -C[0, :, 2]
    r = earth.lla_to_ecef([np.radians(10), np.radians(20), 0.0])
    # geodetic normal is not radial, but within 0.2 deg of it
    assert np.degrees(np.arccos(up @ r / np.linalg.norm(r))) < 0.2


def test_rates():
    w = earth.rate_ie_n(np.radians(45))
    assert np.linalg.norm(w) == pytest.approx(earth.OMEGA_IE)
    assert w[2] < 0  # Earth rate points up in the northern hemisphere (D negative)
    rn, re = earth.principal_radii(0.0, 0.0)
    rho = earth.rate_en_n(0.0, 0.0, [10.0, 20.0, 0.0])
    assert np.allclose(rho, [20.0 / re, -10.0 / rn, 0.0])


def test_spherical_variant():
    assert earth.R_SPHERE == 6378000.0
    assert earth.gravity_spherical(0.0) == pytest.approx(earth.GM / 6378000.0**2)
