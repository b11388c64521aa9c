import numpy as np
import pytest

from inskit import rotations as rot


def random_rpy(rng, n):
    return np.column_stack([rng.uniform(-np.pi, np.pi, n), rng.uniform(-1.5, 1.5, n), rng.uniform(-np.pi, np.pi, n)])


def test_euler_dcm_round_trip_single_and_batch(rng):
    rpy = random_rpy(rng, 500)
    C = rot.dcm_from_euler(rpy)
    assert C.shape == (500, 3, 3)
    assert np.allclose(rot.euler_from_dcm(C), rpy, atol=1e-12)
    assert rot.dcm_from_euler(rpy[0]).shape == (3, 3)
    assert np.allclose(rot.euler_from_dcm(C[0]), rpy[0])


def test_zyx_convention_by_hand():
    yaw = np.radians(30)
    C = rot.dcm_from_euler([0.0, 0.0, yaw])
    # body x (forward) with yaw 30 deg points north-east: [cos, sin, 0] in NED
    assert np.allclose(C @ [1, 0, 0], [np.cos(yaw), np.sin(yaw), 0])
    # positive pitch raises the nose: body x gets a negative down component
    assert (rot.dcm_from_euler([0, 0.1, 0]) @ [1, 0, 0])[2] < 0
    # positive roll lowers the right wing: body y gets a positive down component
    assert (rot.dcm_from_euler([0.1, 0, 0]) @ [0, 1, 0])[2] > 0


def test_quaternion_dcm_consistency(rng):
    rpy = random_rpy(rng, 300)
    q = rot.quat_from_euler(rpy)
    assert np.allclose(rot.dcm_from_quat(q), rot.dcm_from_euler(rpy), atol=1e-14)
    assert np.allclose(rot.quat_from_dcm(rot.dcm_from_quat(q)), rot.quat_normalize(q), atol=1e-13)
    # single
    assert np.allclose(rot.quat_from_dcm(rot.dcm_from_quat(q[3])), rot.quat_normalize(q[3]))


def test_quaternion_product_composes_like_dcm(rng):
    a, b = rot.quat_from_euler(random_rpy(rng, 2))
    assert np.allclose(rot.dcm_from_quat(rot.quat_multiply(a, b)), rot.dcm_from_quat(a) @ rot.dcm_from_quat(b))
    v = rng.normal(size=3)
    assert np.allclose(rot.quat_rotate(a, v), rot.dcm_from_quat(a) @ v)
    assert np.allclose(rot.quat_multiply(a, rot.quat_conjugate(a)), [1, 0, 0, 0])


def test_rotvec(rng):
    phi = rng.normal(size=(200, 3))
    phi *= (rng.uniform(0, np.pi - 1e-3, 200) / np.linalg.norm(phi, axis=1))[:, None]
    assert np.allclose(rot.rotvec_from_dcm(rot.dcm_from_rotvec(phi)), phi, atol=1e-10)
    # small angles and exact zero
    tiny = np.array([[1e-12, -2e-12, 3e-12], [0.0, 0.0, 0.0]])
    assert np.allclose(rot.rotvec_from_quat(rot.quat_from_rotvec(tiny)), tiny, atol=1e-24)
    # about z by 90 deg maps x to y
    assert np.allclose(rot.dcm_from_rotvec([0, 0, np.pi / 2]) @ [1, 0, 0], [0, 1, 0])
    # exp of skew: first order agreement
    d = np.array([1e-4, -2e-4, 3e-4])
    assert np.allclose(rot.dcm_from_rotvec(d), np.eye(3) + rot.skew(d), atol=1e-7)


def test_skew(rng):
    a, b = rng.normal(size=(2, 3))
    assert np.allclose(rot.skew(a) @ b, np.cross(a, b))
    assert rot.skew(rng.normal(size=(4, 3))).shape == (4, 3, 3)
    assert np.allclose(rot.unskew(rot.skew(a)), a)


def test_attitude_error_and_wrap():
    C = rot.dcm_from_euler([0.1, 0.2, 0.3])
    psi = np.array([1e-3, -2e-3, 5e-4])
    C_est = rot.dcm_from_rotvec(-psi) @ C
    assert np.allclose(rot.attitude_error(C_est, C), psi, atol=1e-9)
    assert rot.wrap_angle(3 * np.pi) == pytest.approx(np.pi)
    assert rot.wrap_angle(-0.5) == pytest.approx(-0.5)


def test_gimbal_lock_euler():
    C = rot.dcm_from_euler([0.3, np.pi / 2, 0.5])
    rpy = rot.euler_from_dcm(C)
    assert np.allclose(rot.dcm_from_euler(rpy), C, atol=1e-7)


def test_quaternion_euler_shortcuts_agree_with_the_dcm_path(rng):
    """quat_from_euler skips the normalisation and euler_from_quat the full
    DCM: still unit quaternions with q0 >= 0, the same angles as
    euler_from_dcm(dcm_from_quat(q)), gimbal lock and single rows included."""
    rpy = random_rpy(rng, 2000)
    q = rot.quat_from_euler(rpy)
    assert np.all(q[:, 0] >= 0.0)
    assert np.max(np.abs(np.linalg.norm(q, axis=1) - 1.0)) < 1e-15
    q_any = q * rng.choice([-1.0, 1.0], size=(len(q), 1))  # either sign of a quaternion, one rotation
    assert np.array_equal(rot.euler_from_quat(q_any), rot.euler_from_dcm(rot.dcm_from_quat(q_any)))
    locked = rot.quat_from_euler(np.array([[0.3, np.pi / 2, 0.5], [-0.2, -np.pi / 2, 2.0]]))
    e = rot.euler_from_quat(locked)
    assert np.allclose(e, rot.euler_from_dcm(rot.dcm_from_quat(locked)), atol=1e-12)
    assert np.allclose(rot.dcm_from_euler(e), rot.dcm_from_quat(locked), atol=1e-7)
    assert np.array_equal(rot.euler_from_quat(q[7]), rot.euler_from_quat(q[7:8])[0])
    assert rot.quat_from_euler(rpy[7]).shape == (4,)


def test_quat_blend_takes_the_short_way_and_stays_unit(rng):
    """Halfway between q and -q' (the same rotation as q', signs flipped) is halfway between the rotations;
    the ends are the samples; single and batched agree."""
    from inskit.rotations import dcm_from_quat, quat_blend, quat_from_rotvec, rotvec_from_dcm

    a, b = quat_from_rotvec(np.array([0.1, 0.0, 0.0])), quat_from_rotvec(np.array([0.3, 0.0, 0.0]))
    mid = quat_blend(a, -b, 0.5)
    assert np.linalg.norm(mid) == pytest.approx(1.0)
    assert rotvec_from_dcm(dcm_from_quat(mid)) == pytest.approx([0.2, 0.0, 0.0], abs=1e-12)
    assert quat_blend(a, -b, 0.0) == pytest.approx(a) and abs(quat_blend(a, b, 1.0) @ b) == pytest.approx(1.0)
    q0, q1 = rng.normal(size=(5, 4)), rng.normal(size=(5, 4))
    q0 /= np.linalg.norm(q0, axis=1, keepdims=True)
    q1 /= np.linalg.norm(q1, axis=1, keepdims=True)
    w = rng.uniform(size=5)
    batch = quat_blend(q0, q1, w)
    assert batch == pytest.approx(np.array([quat_blend(q0[k], q1[k], w[k]) for k in range(5)]))
