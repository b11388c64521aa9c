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


# --- selectable gravity models (issue 14 item 6) ---------------------------------------
MODELS = ("normal", "normal-simple", "j2")


def test_gravity_model_names_and_codes():
    for name, code in earth.GRAVITY_MODELS.items():
        assert earth.gravity_model_code(name) == code == earth.gravity_model_code(code)
        assert earth.gravity_model_name(code) == name
    assert earth.gravity_model_code("normal") == earth.GRAVITY_NORMAL == 0  # the kernels' default
    from inskit.errors import InputError

    for bad in ("egm2008", "Normal", 7, True, None):
        with pytest.raises(InputError, match="'normal', 'normal-simple', 'j2'"):
            earth.gravity_model_code(bad)


@pytest.mark.parametrize("model", ["normal", "normal-simple"])
def test_normal_models_give_the_published_wgs84_values_on_the_ellipsoid(model):
    # NIMA TR8350.2 table 3.4: gamma_e = 9.7803253359, gamma_p = 9.8321849378 m/s^2; on
    # the ellipsoid (h = 0) both normal models are Somigliana's formula, pointing straight down
    g = earth.gravity_n(np.array([0.0, np.pi / 2, -np.pi / 2]), 0.0, model)
    assert np.allclose(g[:, 2], [9.7803253359, 9.8321849378, 9.8321849378], rtol=0, atol=1e-9)
    assert np.abs(g[:, :2]).max() < 1e-15


def test_simple_model_is_the_full_one_without_its_second_order_and_north_terms():
    # NIMA TR8350.2 eq. 4-3: the full model's quadratic term is +3 gamma h^2 / a^2 (1.9e-6
    # m/s^2 at 1600 m), and its north component -8.08e-9 h sin(2 lat) (Titterton & Weston
    # eq. 3.90); the simple model keeps the first-order term alone, so the difference is
    # exactly those two terms (to rounding of 9.8 m/s^2)
    lat = np.radians(np.linspace(-80.0, 80.0, 17))
    h = 1600.0
    full, simple = earth.gravity_n(lat, h), earth.gravity_n(lat, h, "normal-simple")
    gamma = earth.somigliana(lat)
    assert np.allclose(full[:, 2] - simple[:, 2], 3 * gamma * h**2 / earth.A**2, rtol=1e-6, atol=1e-14)
    assert np.allclose(full[:, 0], -8.08e-9 * h * np.sin(2 * lat), rtol=1e-12)
    assert np.all(simple[:, :2] == 0.0)
    # its height coefficient is the free-air gradient, the 3.086e-6 1/s^2 that PSINS writes
    # as a constant: within 0.1 % from 30 to 50 deg (the coefficient varies 0.16 % pole to equator)
    mid = np.radians(np.linspace(30.0, 50.0, 5))
    grad = earth.gravity_down_simple_dh(mid, 0.0)
    assert np.allclose(grad, -3.086e-6, rtol=1e-3)


def test_j2_model_agrees_with_normal_gravity_to_a_few_milligal():
    # the GM + J2 field leaves out the normal potential's J4 term (J4 = -2.37e-6) and
    # higher: at most ~(n + 1) GM/a^2 |J4| = 5 * 9.80 * 2.37e-6 = 1.2e-4 m/s^2 (12 mGal, at
    # the poles), plus terms of order f J2 g ~ 4e-5; so < 1.5e-4 everywhere, and several mGal
    lat = np.radians(np.linspace(-89.0, 89.0, 90))
    for h in (0.0, 1600.0, 10000.0):
        d = earth.gravity_n(lat, h, "j2") - earth.gravity_n(lat, h)
        assert np.linalg.norm(d, axis=1).max() < 1.5e-4
        assert np.linalg.norm(d, axis=1).max() > 3e-5  # a real difference: the test can tell them apart
    # the NED form resolves the independent ECEF implementation (gravitation_ecef_j2 +
    # centrifugal) on the local axes, its east component zero (an axially symmetric field)
    rng = np.random.default_rng(4)
    lla = np.column_stack([rng.uniform(-1.5, 1.5, 40), rng.uniform(-3, 3, 40), rng.uniform(-100, 10000, 40)])
    g_e = earth.gravity_ecef_j2(earth.lla_to_ecef(lla))
    g_ned = np.einsum("nji,nj->ni", earth.dcm_en(lla[:, 0], lla[:, 1]), g_e)
    assert np.allclose(earth.gravity_n(lla[:, 0], lla[:, 2], "j2"), g_ned, rtol=0, atol=1e-13)


def test_j2_north_component_grows_with_height_as_the_normal_plumb_line_curves():
    # the north component of plumb-bob gravity above the ellipsoid is the curvature of the
    # normal plumb line, the classical 0.17'' per km sin(2 lat), i.e. g * 8.24e-7 rad/km =
    # -8.08e-9 h sin(2 lat) m/s^2 (Titterton & Weston eq. 3.90): 1.29e-5 m/s^2 at 1600 m,
    # 45 deg.  The J2 field, modelled independently, must show the same growth; 3 % of the
    # peak allows for the two-figure coefficient and the first-order-in-f form of the formula
    lat = np.radians(np.linspace(-85.0, 85.0, 35))
    h = 1600.0
    growth = earth.gravity_n(lat, h, "j2")[:, 0] - earth.gravity_n(lat, 0.0, "j2")[:, 0]
    expected = -8.08e-9 * h * np.sin(2 * lat)
    assert np.abs(growth - expected).max() < 0.03 * 8.08e-9 * h
    assert earth.gravity_n(np.radians(45.0), h)[0] == pytest.approx(-1.2928e-5, rel=1e-12)


@pytest.mark.parametrize("model", MODELS)
def test_compiled_selector_is_the_numpy_model(model):
    """What the kernels call (gravity_nd, gravity_ecef_model, gravity_down_dh_model,
    compiled) is what gravity_n gives, in NED and resolved in ECEF, with the height
    gradient its own derivative."""
    from numba import njit

    code = earth.gravity_model_code(model)

    @njit
    def compiled(lat, h, x, y, z, m):
        gn, gd = earth.gravity_nd(lat, h, m)
        return gn, gd, earth.gravity_ecef_model(x, y, z, m), earth.gravity_down_dh_model(lat, h, m)

    rng = np.random.default_rng(5)
    for lat, lon, h in zip(rng.uniform(-1.5, 1.5, 8), rng.uniform(-3, 3, 8), rng.uniform(-100, 9000, 8)):
        r = earth.lla_to_ecef([lat, lon, h])
        gn, gd, g_e, dgdh = compiled(lat, h, r[0], r[1], r[2], code)
        ref = earth.gravity_n(lat, h, model)
        assert gn == pytest.approx(ref[0], abs=1e-15) and gd == pytest.approx(ref[2], abs=1e-15)
        # ECEF: the same vector (the geodetic round trip costs ~1e-13 m/s^2 of the normal models)
        assert np.allclose(g_e, earth.dcm_en(lat, lon) @ ref, rtol=0, atol=1e-12)
        fd = (earth.gravity_n(lat, h + 50.0, model)[2] - earth.gravity_n(lat, h - 50.0, model)[2]) / 100.0
        # central difference over +-50 m: exact for the quadratic normal models, (50 m / a)^2 / 6
        # = 1e-11 relative for J2; rounding 10 * 2.2e-16 / 100 m is 7e-12 of the 3e-6 1/s^2 gradient
        assert dgdh == pytest.approx(fd, rel=1e-7)
