"""Tightly coupled measurements: H against central finite differences of
their own innovations over the fullest layout, the Sagnac and clock models,
and per-satellite gating."""

import numpy as np
import pytest
from types import SimpleNamespace

from inskit import earth
from inskit import rotations as rot
from inskit.errors import InputError
from inskit.integration import SensorNoise, StateLayout, UpdateContext, ins_blocks
from inskit.integration.blocks import ReceiverClock, SystemTimeOffset
from inskit.integration.tight import OMEGA_E_GNSS, Pseudorange, PseudorangeRate, clock_from_ranges
from inskit.integration.measurements import numerical_jacobian

LAY = StateLayout(ins_blocks(SensorNoise(1e-3, 1e-2, 1e-5, 1e-4), scale_factors=True, lever_arm=True,
                             time_offset=True) + [ReceiverClock(), SystemTimeOffset("E")])
LEVER = np.array([0.9, -0.4, -1.3])
LLA = np.array([1e-3, 2e-3, 120.0])
# steps large enough that a 2e7 m range's rounding (ulp 3.7e-9 m) stays small against them
EPS = {"pos": 1.0, "vel": 1.0, "att": 3e-3, "bg": 1e-2, "ba": 1e-3, "sg": 1e-3, "sa": 1e-4, "lever": 0.1,
       "time_offset": 1e-3, "clock": 1.0, "isb_E": 1.0}
CLK = (1.2e5, -35.0)  # 0.4 ms of bias, -35 m/s of drift
ISB = 12.0


def context(dt=0.004):
    aux = LAY.initial_aux()
    aux[LAY.aux_slice("lever")] = LEVER
    aux[LAY.aux_slice("bg")] = [1e-3, -2e-3, 4e-3]
    aux[LAY.aux_slice("sg")] = [2e-3, -1e-3, 3e-3]
    aux[LAY.aux_slice("clock")] = CLK
    aux[LAY.aux_slice("isb_E")] = ISB
    C = rot.dcm_from_euler([0.05, -0.08, 2.3])
    rate = np.array([0.05, -0.1, 0.6])
    w_raw = rate * (1 + aux[LAY.aux_slice("sg")]) + aux[LAY.aux_slice("bg")]
    return UpdateContext(100.0, dt, LLA.copy(), np.array([12.0, -9.0, 0.3]), C, w_raw, LAY, aux)


def _sats(r_rx, n=6, seed=1):
    """Satellites 20,000 km up in various directions, moving at ~3.9 km/s."""
    rng = np.random.default_rng(seed)
    up = r_rx / np.linalg.norm(r_rx)
    out_p, out_v = [], []
    while len(out_p) < n:
        d = rng.normal(size=3)
        d /= np.linalg.norm(d)
        if d @ up < 0.3:
            continue
        p = r_rx + 2.0e7 * d
        v = np.cross(p, rng.normal(size=3))
        out_p.append(p)
        out_v.append(3.9e3 * v / np.linalg.norm(v))
    return np.array(out_p), np.array(out_v)


def table_for(r_rx, v_rx, t=100.0, n=6, systems="GGGGEE", noise=0.0, clk=CLK, isb=ISB):
    """A range table whose ranges a receiver at r_rx, v_rx (ECEF) would measure."""
    rs_rx, vs_rx = _sats(r_rx, n)  # satellite states in the frame of reception
    tau = np.linalg.norm(rs_rx - r_rx, axis=1) / 299792458.0
    ang = -OMEGA_E_GNSS * tau  # back into the frame of transmission

    def rot3(v):
        c, s = np.cos(ang), np.sin(ang)
        return np.stack([c * v[:, 0] + s * v[:, 1], -s * v[:, 0] + c * v[:, 1], v[:, 2]], axis=1)

    d = r_rx - rs_rx
    rng = np.linalg.norm(d, axis=1)
    u = d / rng[:, None]
    sys = np.array(list(systems[:n]))
    pr = rng + clk[0] + np.where(sys == "E", isb, 0.0) + noise
    rr = np.einsum("ij,ij->i", u, v_rx - vs_rx) + clk[1]
    return SimpleNamespace(time=np.full(n, t), epoch=np.zeros(n, int), sat=np.array([f"{s}{k:02d}" for k, s in
                           enumerate(sys, 1)]), sat_pos_e=rot3(rs_rx), sat_vel_e=rot3(vs_rx), travel_s=tau,
                           pseudorange_m=pr, sigma_pr_m=np.full(n, 3.0), range_rate_m_s=rr,
                           sigma_rr_m_s=np.full(n, 0.1))


def antenna(ctx):
    C_en = earth.dcm_en(ctx.lla[0], ctx.lla[1])
    w = ctx.omega_ib_b
    lev = ctx.estimate("lever")
    v_a = ctx.v_n + ctx.C_nb @ np.cross(w, lev)
    r = earth.lla_to_ecef(ctx.lla) + C_en @ (ctx.C_nb @ lev + v_a * ctx.dt)
    return r, C_en @ v_a


def fd_jacobian(meas, ctx, row=0):
    return numerical_jacobian(meas, ctx, row, EPS)


@pytest.mark.parametrize("kind", [Pseudorange, PseudorangeRate])
def test_H_matches_finite_differences_of_the_innovation(kind):
    """1e-6 relative to the row's largest entry (the central difference's
    third-order term: (3e-3)^2 / 6 of the attitude terms), plus the rounding of
    a 2e7 m range, 3.7e-9 m, over each column's step."""
    ctx = context()
    r, v = antenna(ctx)
    m = kind(table_for(r, v), lever_arm_b=LEVER)
    nu, H, R = m.linearize(ctx, 0)
    assert H.shape == (6, LAY.size) and R.shape == (6, 6)
    J = fd_jacobian(m, ctx)
    scale = np.abs(J).max(axis=1, keepdims=True)
    eps = np.concatenate([np.full(b.size, EPS[b.name]) for b in LAY.blocks])
    names = LAY.state_names()
    bad = [f"{m.name} row {i}, {names[j]}: H {H[i, j]:.6e}, finite differences {J[i, j]:.6e}"
           for i, j in np.argwhere(np.abs(H - J) > 2e-6 * scale + 4e-9 / eps[None, :])]
    assert not bad, "\n".join(bad)


@pytest.mark.parametrize("kind", [Pseudorange, PseudorangeRate])
def test_innovation_is_zero_at_the_truth_with_sagnac_and_clock(kind):
    """Ranges made in the frame of reception, stored in the frame of
    transmission: the plug-in's Sagnac rotation must bring them back (a
    missing rotation leaves up to ~30 m at 20,000 km).  The clock bias runs on
    with its drift over the extrapolation ``dt``."""
    ctx = context(dt=0.0)
    r, v = antenna(ctx)
    nu, _, _ = kind(table_for(r, v), lever_arm_b=LEVER).linearize(ctx, 0)
    assert np.abs(nu).max() < (1e-6 if kind is Pseudorange else 1e-9)
    ctx2 = context(dt=0.2)
    r2, v2 = antenna(ctx2)
    t = table_for(r2, v2, clk=(CLK[0] + 0.2 * CLK[1], CLK[1]))
    nu2, _, _ = kind(t, lever_arm_b=LEVER).linearize(ctx2, 0)
    assert np.abs(nu2).max() < 1e-6


def test_innovation_sign_is_estimate_minus_measurement():
    ctx = context(dt=0.0)
    r, v = antenna(ctx)
    t = table_for(r, v)
    t.pseudorange_m = t.pseudorange_m - 5.0  # measured shorter: the estimate's range is 5 m longer
    nu, _, _ = Pseudorange(t, lever_arm_b=LEVER).linearize(ctx, 0)
    assert np.allclose(nu, 5.0, atol=1e-6)


def test_clock_block_is_required_and_epochs_group_rows():
    ctx = context()
    r, v = antenna(ctx)
    t = table_for(r, v)
    lay = StateLayout(ins_blocks())
    aux = lay.initial_aux()
    c2 = UpdateContext(ctx.t, ctx.dt, ctx.lla, ctx.v_n, ctx.C_nb, ctx.omega_raw_b, lay, aux)
    with pytest.raises(InputError, match="clock"):
        Pseudorange(t).linearize(c2, 0)
    m = Pseudorange(t, time_offset_s=50.0)
    assert m.times().tolist() == [50.0] and m.rows().tolist() == [0]
    assert m.satellites(0) == t.sat.tolist()


def test_clock_from_ranges_with_one_satellite():
    r = earth.lla_to_ecef(LLA)
    v = np.array([3.0, -2.0, 1.0])
    t = table_for(r, v, n=1, systems="G")
    b, d, n = clock_from_ranges(t, 0, r, v)
    assert n == 1 and abs(b - CLK[0]) < 1e-6 and abs(d - CLK[1]) < 1e-9


def test_clock_estimate_runs_on_with_its_drift_between_updates():
    """The layout predicts the clock estimate by exp(F dt) = [[1, dt], [0, 1]]
    and holds every other estimate (a sensor bias's turn-on part)."""
    idx, F = LAY.estimate_dynamics()
    s = LAY.aux_slice("clock")
    assert idx.tolist() == [s.start, s.start + 1]
    assert np.array_equal(F, [[0.0, 1.0], [0.0, 0.0]])
