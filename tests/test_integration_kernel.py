"""The compiled propagation: F against finite differences of the compiled NED
step, the sparse covariance step against the dense formula, and the sparse
pattern against every entry F can take."""

import numpy as np
import pytest

from inskit import earth
from inskit import rotations as rot
from inskit.integration import SensorNoise, StateBlock, StateLayout, ins_blocks
from inskit.integration import _kernel as K
from inskit.strapdown.kernels import ned_step

CLOCK = StateBlock("clock", ("bias", "drift"), "m", (10.0, 1.0), (0.1, 0.01), entries=((0, "clock", 1, 1.0),))


def fullest_layout(gauss_markov=True):
    noise = SensorNoise(1e-3, 1e-2, 1e-5, 1e-4, 300.0 if gauss_markov else np.inf)
    return StateLayout(ins_blocks(noise, scale_factors=True, lever_arm=True, time_offset=True) + [CLOCK])


LAY = fullest_layout()
F_B = np.array([0.8, -0.4, -9.7])       # corrected specific force [m/s^2]
W_B = np.array([0.02, -0.03, 0.1])      # corrected body rate [rad/s]: a turning, climbing vehicle
V_N = np.array([15.0, -8.0, 0.5])
Q_NB = rot.quat_from_euler([0.1, -0.05, 2.0])
AUX = LAY.initial_aux()
AUX[LAY.aux_slice("bg")] = [1e-4, -2e-4, 3e-4]
AUX[LAY.aux_slice("ba")] = [0.01, -0.02, 0.03]
AUX[LAY.aux_slice("sg")] = [1e-3, -2e-3, 5e-4]
AUX[LAY.aux_slice("sa")] = [2e-3, 1e-3, -1e-3]
# central-difference steps per block: large enough to beat rounding, small
# enough that the third-order term (eps^2 / 6 relative) stays below 1e-7
EPS = {"pos": 100.0, "vel": 0.1, "att": 1e-3, "bg": 1e-3, "ba": 1e-2, "sg": 3e-4, "sa": 3e-4, "lever": 1e-2,
       "time_offset": 1e-3, "clock": 1.0}


def _raw(dt):
    """Raw increments that the filter's corrections turn into W_B dt, F_B dt."""
    s = LAY.aux_slice
    return (W_B * dt * (1 + AUX[s("sg")]) + AUX[s("bg")] * dt, F_B * dt * (1 + AUX[s("sa")]) + AUX[s("ba")] * dt)


def _step(lla, v, q, aux, dt, gravity=0):
    """One filter propagation step of the navigation state (the filter's own code)."""
    dth_raw, dv_raw = _raw(dt)
    dth, dv, w, f = np.empty(3), np.empty(3), np.empty(3), np.empty(3)
    K.correct_increments(K.sensor_corrections(LAY.kernel_index(), aux), dth_raw, dv_raw, dt, dth, dv, w, f)
    lla, v, q = lla.copy(), v.copy(), q.copy()
    ned_step(dth, dv, dt, lla, v, q, np.zeros(11), True, 0, 0.0, np.zeros(2), gravity)
    return lla, v, q


def _nav_error(lla, v, q, lla_t, v_t, q_t):
    """Error state of the navigation blocks, in the filter's definitions (the
    small-offset position form that ``apply_correction`` inverts)."""
    rn, re = earth.principal_radii(lla_t[0], lla_t[2])
    e = np.empty(9)
    e[0:3] = [(lla[0] - lla_t[0]) * rn, (lla[1] - lla_t[1]) * re * np.cos(lla_t[0]), -(lla[2] - lla_t[2])]
    e[3:6] = v - v_t
    e[6:9] = rot.attitude_error(rot.dcm_from_quat(q), rot.dcm_from_quat(q_t))
    return e


def _phi_fd(lla0, dt, eps, gravity=0):
    """Rows pos, vel, att of the one-step transition, by central differences:
    the estimate is the truth plus an error (the filter's correction with its
    sign reversed, and the estimates of the other blocks plus their error)."""
    n = LAY.size
    truth = _step(lla0, V_N, Q_NB, AUX, dt, gravity)
    Phi = np.zeros((9, n))
    for j in range(n):
        col = []
        for s in (1.0, -1.0):
            dx = np.zeros(n)
            dx[j] = s * eps[j]
            lla, v, q = np.empty(3), np.empty(3), np.empty(4)
            K.apply_correction(lla0, V_N, Q_NB, dx, -1.0, lla, v, q)
            col.append(_nav_error(*_step(lla, v, q, AUX + dx[LAY.aux_state_index], dt, gravity), *truth))
        Phi[:, j] = (col[0] - col[1]) / (2 * eps[j])
    return Phi


def _f_fd(lla0, h=1e-2, gravity=0):
    """Continuous-time F from the one-step transitions over h, 2h, 3h: the
    one-sided four-point derivative ``(18 Phi(h) - 9 Phi(2h) + 2 Phi(3h) - 11 I) / 6h``
    cancels the h^2 and h^3 terms of the expansion (including those from F's
    change along the step), so what is left is O(h^3)."""
    eps = np.concatenate([np.full(b.size, EPS[b.name]) for b in LAY.blocks])
    P1, P2, P3 = (_phi_fd(lla0, m * h, eps, gravity) for m in (1, 2, 3))
    I9 = np.eye(LAY.size)[:9]
    return (18 * P1 - 9 * P2 + 2 * P3 - 11 * I9) / (6 * h), eps, h


def _f_model(lla0, gravity=0):
    F = np.zeros((LAY.size, LAY.size))
    K.fill_transition(F, LAY.kernel_index(), lla0, V_N, rot.dcm_from_quat(Q_NB), F_B, W_B,
                      K.sensor_corrections(LAY.kernel_index(), AUX), gravity)
    return F[:9]


def _f_dropped(lla0, gravity=0):
    """The terms ``_kernel`` drops on purpose, written out (its docstring):
    transport of the position error, the velocity error's own transport-rate
    term ``v x d w_en(vel)``, gravity's north height gradient.  The test holds
    ``F + these`` to the finite differences, so it checks both that F is right
    and that what it leaves out is exactly what it says, of order |v| / R."""
    lat, h = lla0[0], lla0[2]
    rn, re = earth.principal_radii(lat, h)
    tl = np.tan(lat)
    vn, ve, vd = V_N
    D = np.zeros((9, LAY.size))
    D[0, 0], D[0, 2] = -vd / rn, vn / rn
    D[1, 0], D[1, 1], D[1, 2] = ve * tl / rn, -(vd / re + vn * tl / rn), ve / re
    M = np.array([[0.0, 1.0 / re, 0.0], [-1.0 / rn, 0.0, 0.0], [0.0, -tl / re, 0.0]])  # d w_en / d v
    D[3:6, 3:6] = rot.skew(V_N) @ M
    gn = [earth.gravity_n(lat, h + s, gravity)[0] for s in (1.0, -1.0)]  # the model's own north gradient
    D[3, 2] = -(gn[0] - gn[1]) / 2.0
    return D


@pytest.mark.parametrize("gravity", list(earth.GRAVITY_MODELS))
@pytest.mark.parametrize("point", ["mid-latitude", "equator"])
def test_transition_matches_finite_differences_of_the_ned_step(point, gravity):
    """Every entry of the position, velocity and attitude rows of F against
    the compiled NED step's own Jacobian, with each gravity model (F's height
    gradient is the model's own).

    Tolerance: 1e-6 relative, plus an absolute floor made of (a) rounding:
    the finite difference resolves a row only to its quantity's spacing
    (latitude spacing times R for position, 1e-15 m/s, 1e-16 rad) over eps
    and h, amplified by the stencil's 18/6; (b) the terms the model drops on
    purpose, stated in ``_kernel``'s docstring: position error into gravity
    and Coriolis (below 1e-8 1/s^2), and into the Earth and transport rates
    (below 1e-10 1/(m s)).  Position rows are checked at the equator, where
    the latitude spacing is 2e-19 rad and does not swamp them; at 45 deg it
    would be 7e-10 m per difference.
    """
    lla0 = np.array([0.7, 0.1, 300.0]) if point == "mid-latitude" else np.array([2e-3, 1e-3, 0.5])
    code = earth.gravity_model_code(gravity)
    Ffd, eps, h = _f_fd(lla0, gravity=code)
    F = _f_model(lla0, code) + _f_dropped(lla0, code)
    R = 6.4e6
    spacing = np.r_[np.full(3, np.spacing(lla0[0]) * R + np.spacing(lla0[2])), np.full(3, 1e-15), np.full(3, 1e-16)]
    rounding = 10.0 * 3.0 / h * spacing[:, None] / eps[None, :]
    dropped = np.r_[np.zeros(3), np.full(3, 1e-8), np.full(3, 1e-10)][:, None] * (np.arange(LAY.size) < 3)[None, :]
    tol = 1e-6 * np.abs(F) + rounding + dropped + 1e-12
    rows = slice(0, 3) if point == "equator" else slice(3, 9)
    bad = np.argwhere(np.abs(Ffd - F)[rows] > tol[rows])
    names = LAY.state_names()
    msg = [f"F[{names[rows.start + i]}, {names[j]}] = {F[rows.start + i, j]:.6e}, finite differences "
           f"{Ffd[rows.start + i, j]:.6e}" for i, j in bad]
    assert not msg, "\n".join(msg)


def test_transition_catches_a_wrong_entry():
    """The check has teeth: a sign error in a transport-rate term (3e-6 1/s)
    or a missing 1/(1+s) factor (2e-3 relative) fails it."""
    lla0 = np.array([0.7, 0.1, 300.0])
    Ffd, eps, h = _f_fd(lla0)
    F = _f_model(lla0) + _f_dropped(lla0)
    tol = 1e-6 * np.abs(F) + 1e-8
    bad = F.copy()
    bad[3, 0 + 3] *= -1.0  # vel_n / vel_n: vD / R_N (a dropped term: the test knows its form too)
    assert np.abs(Ffd - bad)[3, 3] > tol[3, 3]
    bad = F.copy()
    ba = LAY.slice("ba")
    bad[3:6, ba] *= 1.0 + AUX[LAY.aux_slice("sa")]
    assert (np.abs(Ffd - bad)[3:6, ba] > tol[3:6, ba]).any()


def test_constant_entries_are_the_blocks_declarations():
    r, c, v = LAY.constant_entries()
    got = {(LAY.state_names()[i], LAY.state_names()[j]): x for i, j, x in zip(r, c, v)}
    assert got[("clock_bias", "clock_drift")] == 1.0
    for a in "xyz":
        assert got[(f"bg_{a}", f"bg_{a}")] == pytest.approx(-1 / 300.0)
        assert got[(f"ba_{a}", f"ba_{a}")] == pytest.approx(-1 / 300.0)
    assert ("sg_x", "sg_x") not in got  # random walk


@pytest.mark.parametrize("gm", [False, True])
@pytest.mark.parametrize("second_order", [True, False])
def test_sparse_covariance_step_equals_dense(rng, gm, second_order):
    lay = fullest_layout(gm)
    n = lay.size
    rows, cols = lay.transition_pattern()
    active = np.unique(rows)
    F = np.zeros((n, n))
    F[rows, cols] = rng.normal(0, 3.0, len(rows))
    M = rng.normal(size=(n, n))
    P = M @ M.T + n * np.eye(n)
    q = rng.uniform(0, 1, n)
    dt = 0.01
    Phi = np.eye(n) + F * dt
    ref = Phi @ P @ Phi.T + np.diag(q) * dt
    if not second_order:
        ref -= F @ P @ F.T * dt * dt
    got = P.copy()
    K.propagate_covariance(got, F, rows, cols, active, dt, q, np.zeros((n, n)), np.zeros((n, n)),
                           np.zeros((n, len(active))), second_order)
    assert np.allclose(got, ref, rtol=1e-12, atol=1e-12)
    assert np.array_equal(got, got.T)


def test_transition_pattern_covers_every_nonzero_of_F(rng):
    """fill_transition and the constants write only inside the pattern (else
    the sparse products would miss terms)."""
    for lay in (fullest_layout(True), StateLayout(ins_blocks())):
        n = lay.size
        F = np.zeros((n, n))
        r, c, v = lay.constant_entries()
        F[r, c] = v
        C = np.linalg.qr(rng.normal(size=(3, 3)))[0]
        aux = rng.normal(0, 1e-3, lay.aux_size)
        K.fill_transition(F, lay.kernel_index(), np.array([0.7, 0.1, 300.0]), np.array([10.0, -5.0, 0.3]), C,
                          np.array([0.5, -0.2, -9.8]), np.array([0.01, 0.02, -0.03]),
                          K.sensor_corrections(lay.kernel_index(), aux))
        rows, cols = lay.transition_pattern()
        mask = np.zeros((n, n), bool)
        mask[rows, cols] = True
        assert not np.any(F[~mask])


# --- the covariance step (FilterSettings.covariance_step_s) ---------------------------------------------------

_DRIVE = """name = "car200"
[start]
lat_deg = 40.0966
lon_deg = -105.1474
height_m = 1600.0
yaw_deg = 40.0
speed_m_s = 15.0
[imu]
rate_hz = 200.0
grade = "industrial-mems"
[gnss]
rate_hz = 1.0
white_h_m = 0.3
white_v_m = 0.5
[[segment]]
type = "cruise"
duration_s = 60.0
[[segment]]
type = "turn"
angle_deg = 90.0
radius_m = 60.0
[[segment]]
type = "accelerate"
speed_m_s = 22.0
duration_s = 15.0
[[segment]]
type = "turn"
angle_deg = -120.0
radius_m = 80.0
[[segment]]
type = "cruise"
duration_s = 60.0
"""


@pytest.fixture(scope="module")
def drive200(tmp_path_factory):
    from inskit.simulation.scenario import load_scenario, simulate

    p = tmp_path_factory.mktemp("car200") / "s.toml"
    p.write_text(_DRIVE)
    return simulate(load_scenario(p), seed=5)


def _run_drive(sim, step, outage=(110.0, 150.0), progress=None):
    from inskit.integration import FilterSettings, GnssPosition, InitialUncertainty, run_filter
    from inskit.types import GnssData

    g = sim.gnss
    t_rel = g.time - sim.imu.time[0]
    keep = (t_rel < outage[0]) | (t_rel > outage[1])
    gk = GnssData(g.time[keep], g.lla[keep], g.sigma_ned[keep])
    noise = SensorNoise(np.radians(0.15) / 60.0, 0.06 / 60.0, np.radians(5.0) / 3600.0, 50e-6 * 9.81, 300.0)
    st = FilterSettings.standard(noise, InitialUncertainty(), scale_factors=True, covariance_step_s=step,
                                 lever_arm_b=tuple(sim.scenario.gnss.lever_arm_b_m))
    return run_filter(sim.imu, sim.truth.state(0), [GnssPosition(gk)], st, progress=progress)


def test_a_coarser_covariance_step_changes_little_and_one_row_steps_are_the_every_row_filter(drive200):
    """At 200 Hz, stepping the covariance every 0.02 s (4 rows) with the
    rows' mean rate and specific force: the sigmas within 1 % of the
    every-row filter's where both are propagated to the same time (the
    fixes), the solution within 2 % of its
    free-inertial error at the end of a 40 s outage (the discretisation
    of the Riccati equation, O(dt), against errors O(1)); a step shorter
    than a row is the every-row filter, bit for bit; and where the caller
    splits its calls (a progress callback) changes nothing."""
    sim = drive200
    every = _run_drive(sim, 0.0)
    coarse = _run_drive(sim, 0.02)
    half_row = _run_drive(sim, 0.002)
    assert np.array_equal(half_row.sigma, every.sigma) and np.array_equal(half_row.nav.lla, every.nav.lla)
    rel = np.abs(coarse.sigma / every.sigma - 1.0)[len(sim.imu) // 20:]  # after the priors' first sharp fall
    fix_rows = np.searchsorted(sim.imu.time, sim.gnss.time) - len(sim.imu) // 20
    fix_rows = fix_rows[(fix_rows >= 0) & (fix_rows < len(rel))]
    assert rel[fix_rows].max() < 0.01  # where both are propagated to the same time: the discretisation only
    assert rel.max() < 0.04  # between steps the coarse sigmas are up to three rows old (a turn: 1 % a row)
    assert rel.max() > 1e-4  # it did step differently
    truth = sim.truth
    k = int(np.searchsorted(sim.imu.time - sim.imu.time[0], 150.0))
    err = [np.linalg.norm((r.nav.lla[k, :2] - truth.lla[k, :2]) * [6.37e6, 6.37e6 * np.cos(truth.lla[k, 0])])
           for r in (every, coarse)]
    assert err[0] > 1.0  # the outage did coast
    assert abs(err[1] - err[0]) < 0.02 * err[0]
    calls = []
    again = _run_drive(sim, 0.02, progress=calls.append)
    assert len(calls) > 5 and np.array_equal(again.nav.lla, coarse.nav.lla)
    assert np.array_equal(again.sigma, coarse.sigma)
