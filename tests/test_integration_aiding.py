"""Odometer, GNSS speed-and-course and height plug-ins: H against central
finite differences of their own innovations over the fullest layout, zero
innovation at the truth, the sign of the scale factor, the low-speed skip,
and the height measurement's offset column."""

import numpy as np
import pytest

from inskit import rotations as rot
from inskit.errors import InputError
from inskit.integration import (HeightBias, Measurement, Mounting, SensorNoise, StateLayout, UpdateContext,
                                ins_blocks)
from inskit.integration.aiding import GnssSpeedCourse, Height, Odometer, OdometerScale, course_speed_to_ne
from inskit.integration.measurements import numerical_jacobian

LAY = StateLayout(ins_blocks(SensorNoise(1e-3, 1e-2, 1e-5, 1e-4), scale_factors=True, lever_arm=True)
                  + [OdometerScale(), Mounting()])
MOUNT = np.array([0.07, -0.035])         # the IMU 4 deg nose-down and 2 deg to the right of the vehicle
LEVER = np.array([0.9, -0.4, -1.3])      # roof antenna
ODO_LEVER = np.array([-1.4, 0.0, 0.35])  # rear-axle centre behind and below the IMU
LLA = np.array([1e-3, 2e-3, 120.0])
EPS = {"pos": 1.0, "vel": 1e-2, "att": 1e-4, "bg": 1e-4, "ba": 1e-3, "sg": 1e-4, "sa": 1e-4, "lever": 1e-3,
       "odo_scale": 1e-4, "mounting": 1e-4}
K_ODO = 0.004


def context(rate=(0.05, -0.1, 0.6), v_n=(12.0, -9.0, 0.3), mount=(0.0, 0.0)):
    """An estimate in a 0.6 rad/s turn with every block estimated (the
    mounting at ``mount``)."""
    aux = LAY.initial_aux()
    aux[LAY.aux_slice("mounting")] = mount
    aux[LAY.aux_slice("lever")] = LEVER
    aux[LAY.aux_slice("bg")] = [1e-3, -2e-3, 4e-3]
    aux[LAY.aux_slice("sg")] = [2e-3, -1e-3, 3e-3]
    aux[LAY.aux_slice("odo_scale")] = K_ODO
    C = rot.dcm_from_euler([0.05, -0.08, 2.3])
    w_raw = np.asarray(rate) * (1 + aux[LAY.aux_slice("sg")]) + aux[LAY.aux_slice("bg")]
    return UpdateContext(100.0, 0.004, LLA.copy(), np.asarray(v_n, float), C, w_raw, LAY, aux)


def wheel_velocity_b(ctx, lever=ODO_LEVER):
    return ctx.C_nb.T @ ctx.v_n + np.cross(ctx.omega_ib_b, lever)


def antenna_velocity(ctx):
    return ctx.v_n + ctx.C_nb @ np.cross(ctx.omega_ib_b, LEVER)


def fd_jacobian(meas, ctx, row=0):
    return numerical_jacobian(meas, ctx, row, EPS)


def measurements(ctx):
    v_o = wheel_velocity_b(ctx)
    z = (1 + K_ODO) * v_o[0] + 0.3
    v_a = antenna_velocity(ctx)
    sp, co = np.hypot(v_a[0], v_a[1]) + 0.2, np.arctan2(v_a[1], v_a[0]) + 0.01
    return [Odometer([100.0], [z], 0.05, lever_arm_b=ODO_LEVER),
            Odometer([100.0], [z], 0.05, lever_arm_b=ODO_LEVER, with_nhc=True),
            GnssSpeedCourse([100.0], [sp], [co], 0.1, 0.01, lever_arm_b=LEVER)]


@pytest.mark.parametrize("mount", [(0.0, 0.0), tuple(MOUNT)])
@pytest.mark.parametrize("which", range(3))
def test_H_matches_finite_differences_of_the_innovation(which, mount):
    """1e-6 relative to the row's largest entry, plus 1e-9: the central
    difference's third-order term (eps^2 / 6 = 2e-9 of the 1e-4 rad attitude
    step); every h here is smooth (rotations and products), no rounding step."""
    ctx = context(mount=mount)
    m = measurements(ctx)[which]
    assert isinstance(m, Measurement)
    nu, H, R = m.linearize(ctx, 0)
    assert H.shape == (len(nu), LAY.size) and R.shape == (len(nu), len(nu))
    J = fd_jacobian(m, ctx)
    scale = np.abs(J).max(axis=1, keepdims=True)
    names = LAY.state_names()
    bad = [f"{m.name} row {i}, {names[j]}: H {H[i, j]:.6e}, finite differences {J[i, j]:.6e}"
           for i, j in np.argwhere(np.abs(H - J) > 1e-6 * scale + 1e-9)]
    assert not bad, "\n".join(bad)


def test_odometer_couples_into_scale_gyro_and_not_the_gnss_lever():
    """The columns that make the odometer useful have the sizes physics gives
    them: d h / d s is the forward wheel speed (~ 15 m/s here); the forward
    part of omega x l is ``w_y l_z - w_z l_y``, so with ``d omega / d b_g =
    -I / (1 + s_g)`` the gyro-bias row is ``-(1 + s) [0, l_z, -l_y] / (1 + s_g)``
    (the wheel 1.4 m behind the IMU on the centre line: only the pitch rate
    moves it forward, through its 0.35 m drop); nothing on the antenna's
    lever arm."""
    ctx = context()
    _, H, _ = measurements(ctx)[0].linearize(ctx, 0)
    v_o = wheel_velocity_b(ctx)
    assert H[0, LAY.slice("odo_scale")][0] == pytest.approx(v_o[0], rel=1e-12)
    assert abs(v_o[0]) > 10.0
    assert np.all(H[0, LAY.slice("lever")] == 0.0)
    sg = 1 + ctx.estimate("sg")
    expect = -(1 + K_ODO) * np.array([0.0, ODO_LEVER[2], -ODO_LEVER[1]]) / sg
    assert np.allclose(H[0, LAY.slice("bg")], expect, rtol=1e-12, atol=1e-15)


def test_odometer_innovation_is_zero_at_the_truth_and_signed_by_the_scale():
    """A sensor reading (1 + k) times the true wheel speed, with the
    estimate s = k, leaves no innovation; an estimate with s = 0 predicts
    k v too little (innovation -k v: estimate minus measurement)."""
    ctx = context()
    v_o = wheel_velocity_b(ctx)
    z = (1 + K_ODO) * v_o[0]
    nu, _, R = Odometer([100.0], [z], 0.05, lever_arm_b=ODO_LEVER, with_nhc=True).linearize(ctx, 0)
    assert np.abs(nu - [0.0, v_o[1], v_o[2]]).max() < 1e-12
    assert R[0, 0] == pytest.approx(0.05**2) and R[1, 1] == pytest.approx(0.1**2)
    small = StateLayout(ins_blocks())
    c2 = UpdateContext(ctx.t, ctx.dt, ctx.lla, ctx.v_n, ctx.C_nb, ctx.omega_raw_b, small, small.initial_aux())
    nu2, H2, _ = Odometer([100.0], [z], 0.05, lever_arm_b=ODO_LEVER).linearize(c2, 0)
    v2 = c2.C_nb.T @ c2.v_n + np.cross(c2.omega_ib_b, ODO_LEVER)  # no gyro estimates in this layout
    assert H2.shape == (1, 15)
    assert nu2[0] == pytest.approx(v2[0] - z, abs=1e-12)


def test_speed_course_covariance_is_the_propagated_one():
    """Monte Carlo of (speed, course) draws against the closed form: at 10 m/s,
    0.2 m/s along track and 10 m/s * 0.02 rad = 0.2 m/s across; with 0.05
    m/s along and 0.3 m/s across, rotated by the course."""
    rng = np.random.default_rng(3)
    s, c, ss, sc = 10.0, np.radians(30.0), 0.05, 0.03
    v, P = course_speed_to_ne(s, c, ss, sc)
    draws_s = s + ss * rng.standard_normal(200_000)
    draws_c = c + sc * rng.standard_normal(200_000)
    vd = np.stack([draws_s * np.cos(draws_c), draws_s * np.sin(draws_c)], axis=1)
    Pd = np.cov(vd.T)
    # sampling error of a variance over 2e5 draws: sqrt(2 / 2e5) = 0.3 %; plus the second-order term
    assert np.allclose(Pd, P, rtol=0.02, atol=2e-4 * np.abs(P).max())
    assert np.allclose(v, [s * np.cos(c), s * np.sin(c)])
    w, U = np.linalg.eigh(P)
    assert np.allclose(np.sqrt(w), [ss, s * sc])


def test_speed_course_skips_slow_rows_and_wraps_nowhere():
    """Below max(0.5 m/s, 3 sigma) the course is meaningless: the row is
    skipped.  A course of 359.9 deg and one of -0.1 deg are the same velocity
    (no wrapping problem in the north/east form)."""
    ctx = context(rate=(0.0, 0.0, 0.0), v_n=(10.0, -0.01745, 0.0))
    m = GnssSpeedCourse([1.0, 2.0, 3.0, 4.0], [0.4, 0.8, 10.0, 10.0], [0.0, 0.0, np.radians(359.9), -0.001745],
                        0.3, 0.01, lever_arm_b=LEVER)
    assert m.linearize(ctx, 0) is None  # 0.4 < 0.9
    assert m.linearize(ctx, 1) is None  # 0.8 < 3 * 0.3
    n2, _, _ = m.linearize(ctx, 2)
    n3, _, _ = m.linearize(ctx, 3)
    assert np.allclose(n2, n3, atol=1e-5) and np.abs(n2).max() < 1e-3


def test_invalid_inputs_raise_input_errors():
    with pytest.raises(InputError, match="sigma_m_s"):
        Odometer([0.0, 1.0], [1.0, 2.0], 0.0)
    with pytest.raises(InputError, match="speed_m_s"):
        Odometer([0.0, 1.0], [1.0, np.nan], 0.1)
    with pytest.raises(InputError, match="strictly increase"):
        Odometer([1.0, 1.0], [1.0, 2.0], 0.1)
    with pytest.raises(InputError, match=">= 0"):
        GnssSpeedCourse([0.0], [-1.0], [0.0], 0.1, 0.01)
    with pytest.raises(InputError, match="lever_arm_b"):
        Odometer([0.0], [1.0], 0.1, lever_arm_b=(1.0, 2.0))


def test_scale_block_is_a_named_random_walk():
    b = OdometerScale(0.02, 1e-5)
    assert b.name == "odo_scale" and b.size == 1 and b.has_estimate
    assert b.sigma0[0] == 0.02 and b.psd[0] == pytest.approx(1e-10) and b.transition() == []
    assert b.estimate_names() == ["odo_scale"] and b.sigma_names() == ["sigma_odo_scale"]
    est = b.estimate0.copy()
    b.feedback(est, np.array([0.003]))
    assert est[0] == pytest.approx(-0.003)  # closed loop: estimate -= dx


def test_odometer_without_the_mounting_block():
    """The IMU's forward axis taken for the vehicle's: H checked as above,
    and the prediction the same as with a zero mounting estimate."""
    small = StateLayout([b for b in LAY.blocks if b.name != "mounting"])
    ctx = context()
    c2 = UpdateContext(ctx.t, ctx.dt, ctx.lla, ctx.v_n, ctx.C_nb, ctx.omega_raw_b, small,
                       np.delete(ctx.aux, LAY.aux_slice("mounting")))
    for m in measurements(ctx)[:2]:
        nu, H, _ = m.linearize(c2, 0)
        J = fd_jacobian(m, c2)
        assert np.allclose(H, J, rtol=0, atol=1e-6 * np.abs(J).max() + 1e-9)
        nu0, H0, _ = m.linearize(ctx, 0)
        assert np.allclose(nu, nu0, atol=1e-12)
        assert np.allclose(H, np.delete(H0, LAY.slice("mounting"), axis=1), atol=1e-12)


def test_odometer_with_the_true_mounting_sees_no_innovation():
    """A vehicle driving straight ahead at 15 m/s with its IMU mounted 4 deg
    nose-down and 2 deg to the right (``[imu] mount_rpy_deg`` convention): in
    the IMU's axes the wheel moves 1 m/s up and 0.5 m/s sideways, but with
    the mounting estimate at the truth the wheel speed and both zero rows
    match; with no mounting estimate the zero rows see those velocities."""
    from inskit.integration.blocks import mounting_dcm

    C_vb = mounting_dcm(*MOUNT)[0]
    assert np.allclose(C_vb, rot.dcm_from_euler([0.0, *MOUNT]).T)
    C_nv = rot.dcm_from_euler([0.0, 0.02, 0.8])
    v_n = C_nv @ [15.0, 0.0, 0.0]
    C_nb = C_nv @ C_vb
    aux = LAY.initial_aux()
    aux[LAY.aux_slice("mounting")] = MOUNT
    aux[LAY.aux_slice("odo_scale")] = K_ODO
    ctx = UpdateContext(100.0, 0.0, LLA.copy(), v_n, C_nb, np.zeros(3), LAY, aux)
    odo = Odometer([100.0], [(1 + K_ODO) * 15.0], 0.05, with_nhc=True)
    nu, _, _ = odo.linearize(ctx, 0)
    assert np.abs(nu).max() < 1e-12
    aux[LAY.aux_slice("mounting")] = 0.0
    nu0, _, _ = odo.linearize(ctx, 0)
    v_b = C_nb.T @ v_n
    assert np.allclose(nu0[1:], v_b[1:], atol=1e-12)
    assert v_b[2] == pytest.approx(-15.0 * np.sin(MOUNT[0]), rel=1e-3)  # nose-down: the IMU sees itself climb
    assert v_b[1] == pytest.approx(15.0 * np.sin(MOUNT[1]) * np.cos(MOUNT[0]), rel=1e-3)  # yawed right: drifts left


# --- height (barometer, profile) -----------------------------------------------------------
HLAY = StateLayout(ins_blocks(SensorNoise(1e-3, 1e-2, 1e-5, 1e-4), scale_factors=True, lever_arm=True)
                   + [HeightBias(20.0, "random-walk", rw=0.03)])
BARO_LEVER = np.array([0.6, -0.3, -0.8])  # in the dashboard, above and ahead of the IMU


def height_context(dt=0.004, bias=7.5):
    aux = HLAY.initial_aux()
    aux[HLAY.aux_slice("height_bias")] = bias
    C = rot.dcm_from_euler([0.05, -0.08, 2.3])
    return UpdateContext(100.0, dt, LLA.copy(), np.array([12.0, -9.0, 0.3]), C, np.array([0.05, -0.1, 0.6]),
                         HLAY, aux)


def test_height_H_matches_finite_differences_and_is_zero_at_the_truth():
    """H against central differences over the fullest layout (same tolerance
    as above); at the truth (the sensor point's height, the state carried
    over dt, plus the offset) the innovation is 0; the offset enters with +1,
    the IMU height with -1 (error states estimate - truth, x_pos_d = -dh)."""
    ctx = height_context()
    cl = ctx.C_nb @ BARO_LEVER
    z = LLA[2] - 0.3 * ctx.dt - cl[2] + 7.5
    m = Height([100.0], [z], 0.5, lever_arm_b=BARO_LEVER)
    assert isinstance(m, Measurement) and m.name == "height"
    nu, H, R = m.linearize(ctx, 0)
    assert abs(nu[0]) < 1e-9 and R[0, 0] == pytest.approx(0.25)
    J = numerical_jacobian(m, ctx, 0, {**EPS, "height_bias": 1e-2})
    assert np.allclose(H, J, rtol=1e-6, atol=1e-9), (H, J)
    assert H[0, HLAY.slice("height_bias")][0] == 1.0 and H[0, HLAY.slice("pos")][2] == -1.0
    assert H[0, HLAY.slice("vel")][2] == pytest.approx(-ctx.dt)
    assert np.any(H[0, HLAY.slice("att")] != 0)  # the lever arm couples the tilt in
    # without the offset block the measurement is the plain height, its column absent
    lay = StateLayout(ins_blocks())
    ctx0 = UpdateContext(100.0, 0.0, LLA.copy(), np.zeros(3), np.eye(3), np.zeros(3), lay, lay.initial_aux())
    nu0, H0, _ = Height([100.0], [118.0], 1.0).linearize(ctx0, 0)
    assert nu0[0] == pytest.approx(2.0) and np.count_nonzero(H0) == 1


def test_height_refuses_bad_inputs():
    with pytest.raises(InputError, match="sigma_m"):
        Height([0.0, 1.0], [1.0, 2.0], 0.0)
    with pytest.raises(InputError, match="height_m"):
        Height([0.0, 1.0], [1.0, np.inf], 0.5)
    with pytest.raises(InputError, match="strictly increase"):
        Height([1.0, 0.5], [1.0, 2.0], 0.5)

