"""Every measurement's H against central finite differences of its own
innovation over the fullest layout (scale factors, lever arm, time offset,
mounting and a user block), and the two Jacobian defects found in review."""

import numpy as np
import pytest

from inskit import rotations as rot
from inskit.integration import (GnssPosition, GnssVelocity, Measurement, Mounting, NonHolonomic, SensorNoise,
                                StateBlock, StateLayout, UpdateContext, ZeroVelocity, ins_blocks)
from inskit.integration.measurements import ned_difference
from inskit.types import GnssData
from inskit.integration.measurements import numerical_jacobian

CLOCK = StateBlock("clock", ("bias", "drift"), "m", (10.0, 1.0), (0.1, 0.01), entries=((0, "clock", 1, 1.0),))
LAY = StateLayout(ins_blocks(SensorNoise(1e-3, 1e-2, 1e-5, 1e-4), scale_factors=True, lever_arm=True,
                             time_offset=True) + [CLOCK, Mounting()])
MOUNT = np.array([0.07, -0.035])  # an IMU 4 deg nose-down and 2 deg to the right of the vehicle
LEVER = np.array([0.9, -0.4, -1.3])  # a roof antenna, 1.6 m from the IMU
# near the equator, so that latitude's rounding (2e-19 rad) does not limit the differences
LLA = np.array([1e-3, 2e-3, 120.0])
EPS = {"pos": 1.0, "vel": 1e-2, "att": 1e-4, "bg": 1e-4, "ba": 1e-3, "sg": 1e-4, "sa": 1e-4, "lever": 1e-3,
       "time_offset": 1e-3, "clock": 1.0, "mounting": 1e-4}


def context(rate=(0.05, -0.1, 0.6), dt=0.004, offset=-0.26, layout=LAY):
    """An estimate in a 0.6 rad/s turn, 4 ms before the fix, with every block estimated."""
    aux = layout.initial_aux()
    if "mounting" in layout:
        aux[layout.aux_slice("mounting")] = MOUNT
    aux[LAY.aux_slice("lever")] = LEVER
    aux[LAY.aux_slice("time_offset")] = offset
    aux[LAY.aux_slice("bg")] = [1e-3, -2e-3, 4e-3]
    aux[LAY.aux_slice("sg")] = [2e-3, -1e-3, 3e-3]
    C = rot.dcm_from_euler([0.05, -0.08, 2.3])
    w_raw = np.asarray(rate) * (1 + aux[LAY.aux_slice("sg")]) + aux[LAY.aux_slice("bg")]
    return UpdateContext(100.0, dt, LLA.copy(), np.array([12.0, -9.0, 0.3]), C, w_raw, layout, aux)


def gnss_near(ctx, n=3):
    """Fixes a few metres from the predicted antenna."""
    lla = np.tile(ctx.lla, (n, 1)) + [[3e-7, -2e-7, 1.5]]
    return GnssData(ctx.t + np.arange(n), lla, np.full((n, 3), 0.5), np.tile([11.0, -8.5, 0.1], (n, 1)),
                    np.full((n, 3), 0.05))


def fd_jacobian(meas, ctx, row=0):
    return numerical_jacobian(meas, ctx, row, EPS)


def all_measurements(ctx):
    g = gnss_near(ctx)
    return [GnssPosition(g, lever_arm_b=LEVER), GnssVelocity(g, lever_arm_b=LEVER),
            ZeroVelocity([(0, 200)], 10.0, 0.02), NonHolonomic([(0, 200)], 10.0, 0.1)]


@pytest.mark.parametrize("which", range(4))
def test_H_matches_finite_differences_of_the_innovation(which):
    """1e-6 relative to the row's largest entry, plus 1e-9: the central
    difference's third-order term (eps^2 / 6: 2e-9 for the 1e-4 rad attitude
    step) and the rounding of position (1e-12 m over 1 m)."""
    ctx = context()
    m = all_measurements(ctx)[which]
    assert isinstance(m, Measurement)
    nu, H, R = m.linearize(ctx, 0)
    assert H.shape == (len(nu), LAY.size) and R.shape == (len(nu), len(nu))
    J = fd_jacobian(m, ctx)
    scale = np.abs(J).max(axis=1, keepdims=True)
    names = LAY.state_names()
    bad = [f"{m.name} row {i}, {names[j]}: H {H[i, j]:.6e}, finite differences {J[i, j]:.6e}"
           for i, j in np.argwhere(np.abs(H - J) > 1e-6 * scale + 1e-9)]
    assert not bad, "\n".join(bad)


def test_nhc_without_the_mounting_block_uses_the_imu_axes():
    """Without the block the constraint holds in the IMU's own axes (its H
    checked the same way), and with it the innovation is the vehicle's
    lateral and vertical velocity: ``v_b + [v_b x] m`` to first order, here
    0.07 rad of pitch on 15 m/s forward, about 1 m/s."""
    no_mount = StateLayout([b for b in LAY.blocks if b.name != "mounting"])
    ctx = context(layout=no_mount)
    m = NonHolonomic([(0, 200)], 10.0, 0.1)
    nu, H, _ = m.linearize(ctx, 0)
    J = numerical_jacobian(m, ctx, 0, EPS)
    assert np.allclose(H, J, rtol=0, atol=1e-6 * np.abs(J).max())
    v_b = ctx.C_nb.T @ ctx.v_n
    assert np.allclose(nu, v_b[1:3], atol=1e-12)
    nu_m, _, _ = m.linearize(context(), 0)
    first_order = v_b + np.cross(v_b, [0.0, MOUNT[0], MOUNT[1]])
    assert np.allclose(nu_m, first_order[1:3], atol=0.01 * np.linalg.norm(v_b) * np.abs(MOUNT).max())
    assert abs(nu_m[1] - nu[1]) > 0.9


@pytest.mark.parametrize("mounting", [True, False])
def test_nhc_lever_arm_takes_the_constraint_at_the_wheel_point(mounting):
    """With a lever arm the constraint holds at the wheel point, ``v_b +
    omega x l`` (here 0.6 rad/s of yaw on 1.2 m forward: 0.72 m/s more
    lateral velocity), and H, now with gyro bias and scale-factor columns,
    matches the finite differences with and without the mounting block."""
    lay = LAY if mounting else StateLayout([b for b in LAY.blocks if b.name != "mounting"])
    ctx = context(layout=lay)
    lev = np.array([1.2, -0.3, 0.8])
    m = NonHolonomic([(0, 200)], 10.0, 0.1, lever_arm_b=lev)
    assert m.compiled(lay) is not None  # compiled too (tests/test_integration_updates.py: the same nu, H, R)
    nu, H, _ = m.linearize(ctx, 0)
    J = numerical_jacobian(m, ctx, 0, EPS)
    scale = np.abs(J).max(axis=1, keepdims=True)
    assert np.all(np.abs(H - J) <= 1e-6 * scale + 1e-9)
    assert np.abs(H[:, lay.slice("bg")]).max() > 0.1 and np.abs(H[:, lay.slice("sg")]).max() > 0.01
    nu0, _, _ = NonHolonomic([(0, 200)], 10.0, 0.1).linearize(ctx, 0)
    if not mounting:
        assert np.allclose(nu - nu0, np.cross(ctx.omega_ib_b, lev)[1:3], atol=1e-12)
        assert abs((nu - nu0)[0] - 0.6 * 1.2 + 0.05 * 0.8) < 0.02


def test_gnss_position_error_block_adds_its_estimate_and_decays_between_fixes():
    """With a ``gnss_err`` block the prediction carries the fixes' correlated
    error: the innovation moves by its estimate, ``H_gnss_err = I`` (checked
    by finite differences), the compiled form stands down, and the estimate
    is predicted by its own decay, ``exp(-dt / tau)``."""
    from inskit.integration import GnssPositionError

    lay = StateLayout(list(LAY.blocks) + [GnssPositionError(0.03, 10.0)])
    ctx = context(layout=lay)
    g = gnss_near(ctx)
    m = GnssPosition(g, lever_arm_b=LEVER)
    nu0, _, _ = m.linearize(ctx, 0)
    ctx.aux[lay.aux_slice("gnss_err")] = [0.02, -0.01, 0.005]
    nu, H, _ = m.linearize(ctx, 0)
    assert np.allclose(nu - nu0, [0.02, -0.01, 0.005], atol=1e-12)
    assert np.array_equal(H[:, lay.slice("gnss_err")], np.eye(3))
    J = numerical_jacobian(m, ctx, 0, dict(EPS, gnss_err=1e-3))
    scale = np.abs(J).max(axis=1, keepdims=True)
    assert np.all(np.abs(H - J) <= 1e-6 * scale + 1e-9)
    assert m.compiled(lay) is not None and m.compiled(LAY) is not None  # compiled with the block too
    idx, F = lay.estimate_dynamics()
    assert list(idx) == list(range(lay.aux_slice("gnss_err").start, lay.aux_slice("gnss_err").stop))
    assert np.allclose(F, -np.eye(3) / 10.0)


def test_gnss_velocity_has_the_lever_arm_block():
    """Review defect 1: H had no lever-arm columns (omega x l_b is in h)."""
    ctx = context()
    J = fd_jacobian(GnssVelocity(gnss_near(ctx), lever_arm_b=LEVER), ctx)
    lev = LAY.slice("lever")
    assert np.abs(J[:, lev]).max() > 0.25  # ~ |omega| = 0.6 rad/s
    _, H, _ = GnssVelocity(gnss_near(ctx), lever_arm_b=LEVER).linearize(ctx, 0)
    assert np.allclose(H[:, lev], J[:, lev], atol=1e-9)


def test_gnss_position_offset_and_velocity_columns_follow_its_prediction():
    """Review defect 2: the prediction extrapolated with the IMU velocity while
    the offset column used the antenna velocity (0.2 m/s apart in this turn),
    and the (dt + offset) term on the velocity error was missing."""
    ctx = context()
    m = GnssPosition(gnss_near(ctx), lever_arm_b=LEVER)
    J = fd_jacobian(m, ctx)
    _, H, _ = m.linearize(ctx, 0)
    off, vel = LAY.slice("time_offset"), LAY.slice("vel")
    v_ant = ctx.v_n + ctx.C_nb @ np.cross(ctx.omega_ib_b, LEVER)
    assert np.linalg.norm(v_ant - ctx.v_n) > 0.2
    assert np.allclose(J[:, off].ravel(), v_ant, atol=1e-8)
    assert np.allclose(H[:, off].ravel(), v_ant, atol=1e-12)
    tau = ctx.dt + ctx.estimate("time_offset")[0]
    assert np.allclose(J[:, vel], tau * np.eye(3), atol=1e-8)
    assert np.allclose(H[:, vel], tau * np.eye(3), atol=1e-12)


def test_innovation_is_estimate_minus_measurement():
    ctx = context(rate=(0.0, 0.0, 0.0), dt=0.0, offset=0.0)
    g = gnss_near(ctx)
    nu, _, _ = GnssPosition(g, lever_arm_b=LEVER).linearize(ctx, 0)
    expect = ned_difference(ctx.lla, g.lla[0]) + ctx.C_nb @ LEVER
    assert np.allclose(nu, expect)
    assert nu[2] == pytest.approx(1.5 + (ctx.C_nb @ LEVER)[2])  # fix 1.5 m higher: estimate is below it


def test_ned_difference_wraps_longitude():
    a = np.array([0.1, np.pi - 1e-7, 0.0])
    b = np.array([0.1, -np.pi + 1e-7, 0.0])
    d = ned_difference(a, b)
    assert d[1] == pytest.approx(-2e-7 * 6378137.0 * np.cos(0.1), rel=1e-2)


def test_lever_arm_comes_from_the_block_when_estimated():
    ctx = context()
    g = gnss_near(ctx)
    nu1, _, _ = GnssPosition(g, lever_arm_b=np.zeros(3)).linearize(ctx, 0)  # the block's estimate wins
    nu2, _, _ = GnssPosition(g, lever_arm_b=LEVER).linearize(ctx, 0)
    assert np.allclose(nu1, nu2)
    small = StateLayout(ins_blocks())
    ctx2 = UpdateContext(ctx.t, ctx.dt, ctx.lla, ctx.v_n, ctx.C_nb, ctx.omega_raw_b, small, small.initial_aux())
    nu3, H3, _ = GnssPosition(g, lever_arm_b=LEVER).linearize(ctx2, 0)
    assert H3.shape == (3, 15)
    assert np.linalg.norm(nu3 - nu1) > 0.01  # no offset block: no offset, different bias
