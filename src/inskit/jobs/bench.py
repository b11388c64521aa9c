"""Throughput benchmarks (``inskit bench``): numbers, not timed tests.

Each figure is the **median** of several repeats after a warm-up call (so
compile time is excluded), with the spread (slowest, fastest) beside it under
``<key>_spread``; numba runs on one core (no parallel kernels).  The filter
jobs run the settings ``inskit navigate`` runs by default (Gauss-Markov
biases with a 300 s correlation time, NHC at 10 Hz), not a lighter variant.
"""

from __future__ import annotations

import platform
import time

import numpy as np

from .. import __version__
from ..simulation import StationaryTrajectory, ideal_imu, truth_solution
from ..strapdown import mechanize
from ..types import ImuData


def _median_rate(fn, n, repeats):
    """Median rate over ``repeats`` timed calls after a warm-up, and the
    spread (min, max) of the rates."""
    fn()
    rates = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        rates.append(n / (time.perf_counter() - t0))
    return float(np.median(rates)), [float(min(rates)), float(max(rates))]


def _static_imu(duration_s, rate_hz, rng):
    """A 100 Hz static log with white noise, built without the slow quadrature."""
    t = np.arange(0.0, duration_s, 1.0 / rate_hz)
    traj = StationaryTrajectory((np.radians(45.0), 0.0, 100.0))
    one = ideal_imu(traj, t[:2], nodes=1)
    dt = 1.0 / rate_hz
    dth = np.tile(one.dtheta_b[1], (len(t), 1)) + rng.normal(0, 1e-6, (len(t), 3))
    dv = np.tile(one.dv_b[1], (len(t), 1)) + rng.normal(0, 1e-4 * dt, (len(t), 3))
    return ImuData(t, dth, dv), truth_solution(traj, t[:1]).state(0)


def run_benchmarks(quick=False, progress=None, cli=True):
    """Run the benchmarks; return a flat dict of figures.

    Keys: ``ned_epochs_per_s`` (NED mechanization over a 1 h, 100 Hz run,
    whole-array call including result construction), ``wander_epochs_per_s``,
    ``ecef_epochs_per_s``, ``inertial_epochs_per_s``, ``lc_epochs_per_s``
    (the whole closed-loop 21-state filter as navigate runs it by default:
    IMU-rate covariance propagation with Gauss-Markov biases, 1 Hz GNSS
    position updates, NHC at 10 Hz, through the public ``run_filter``, on a
    static log), ``lc_drive_epochs_per_s`` and ``lc_drive_4hz_epochs_per_s``
    (the same filter on the dynamic 200 Hz car drive of the whole-command
    figure, with its 1 Hz fixes and with 4 Hz fixes: :func:`_drive_filter_jobs`;
    with ``cli`` only, as they need ``examples/car.toml``),
    ``tc_epochs_per_s`` (the same with a receiver clock and pseudorange plus
    Doppler updates from 8 satellites at 1 Hz), ``spp_epochs_per_s``
    (single-point positioning of the bundled ABPO day),
    ``gyrofree_epochs_per_s`` (ten-accelerometer closed-form solve plus the
    source's inertial navigation, compiled); with ``cli`` the end-to-end
    command figures of :mod:`.bench_cli` (``navigate_cli_epochs_per_s``,
    ``navigate_peak_rss_mb``, ``simulate_cli_epochs_per_s``,
    ``mechanize_cli_epochs_per_s``, ...).
    """
    rng = np.random.default_rng(0)
    duration = 600.0 if quick else 3600.0
    imu, init = _static_imu(duration, 100.0, rng)
    n = len(imu) - 1
    repeats = 2 if quick else 5
    out = {"inskit_version": __version__, "python": platform.python_version(),
           "machine": platform.machine(), "bench_imu_epochs": n, "bench_imu_rate_hz": 100.0}
    def put(key, fn):
        med, spread = _median_rate(fn, n, repeats)
        out[key] = round(med)
        out[f"{key}_spread"] = [round(v) for v in spread]

    for frame in ("ned", "wander", "ecef", "inertial"):
        put(f"{frame}_epochs_per_s", lambda f=frame: mechanize(imu, init, frame=f))
        if progress:
            progress(frame)
    sim = _simulate_rate(quick)
    out["simulate_epochs_per_s"], out["simulate_scenario"] = sim[0], sim[1]
    if len(sim) > 2:
        out["simulate_epochs_per_s_spread"] = sim[2]
    if progress:
        progress("simulate")
    put("lc_epochs_per_s", _lc_job(imu, init))
    out["lc_states"] = 21
    out["lc_gnss_rate_hz"] = 1.0
    if progress:
        progress("lc")
    if cli:  # the filter alone on the dynamic drive of the whole-command figure (needs examples/car.toml)
        jobs = _drive_filter_jobs(quick)
        if jobs:
            n_d = jobs.pop("epochs")
            for key, fn in jobs.items():
                med, spread = _median_rate(fn, n_d, 2 if quick else 3)
                out[key], out[f"{key}_spread"] = round(med), [round(v) for v in spread]
            out["lc_drive_epochs"] = n_d
            if progress:
                progress("lc on the drive")
    put("tc_epochs_per_s", _tc_job(imu, init))
    out["tc_satellites"] = 8
    out["tc_rate_hz"] = 1.0
    if progress:
        progress("tc")
    out.update(_spp_rate(repeats))
    if progress:
        progress("spp")
    from .bench_gyrofree import gyrofree_rate

    out["gyrofree_epochs_per_s"], out["gyrofree_epochs_per_s_spread"] = gyrofree_rate(quick)
    if progress:
        progress("gyrofree")
    if cli:
        from .bench_cli import cli_benchmarks

        out.update(cli_benchmarks(quick, repeats=2 if quick else 3, progress=progress))
    return out


def _spp_rate(repeats):
    """Single-point positioning of the bundled IGS ABPO day (2727 epochs):
    both range-table passes and both solves, as ``inskit spp`` runs them."""
    from pathlib import Path

    from .spp import spp_throughput

    d = Path(__file__).resolve().parents[3] / "data" / "abpo"
    obs, nav = d / "abpo0080.15o.gz", d / "abpo0080.15n.gz"
    if not (obs.is_file() and nav.is_file()):
        return {"spp_epochs_per_s": None, "spp_note": "data/abpo not found (run from a source checkout)"}
    r = spp_throughput(obs, nav, repeats=repeats, systems=("G",))
    return {"spp_epochs_per_s": round(r["epochs_per_s"]),
            "spp_epochs_per_s_spread": [round(r["epochs_per_s_min"]), round(r["epochs_per_s_max"])],
            "spp_epochs": r["epochs"]}


def _simulate_rate(quick):
    """IMU epochs per second of the car scenario (ideal IMU by quadrature plus
    the full industrial-MEMS error model; GNSS and files excluded)."""
    from pathlib import Path

    from ..simulation.imu import ideal_imu
    from ..simulation.scenario import build_trajectory, imu_errors, load_scenario
    from ..simulation.sensors import apply_imu_errors

    path = Path(__file__).resolve().parents[3] / "examples" / "car.toml"
    if not path.is_file():
        return None, "examples/car.toml not found (run from a source checkout)"
    sc = load_scenario(path)
    tr = build_trajectory(sc, np.random.default_rng(0))
    t = np.arange(0.0, min(tr.duration, 300.0 if quick else tr.duration), 1.0 / sc.imu.rate_hz)
    err = imu_errors(sc)
    tr.kinematics(t[:10])  # position integration happens once per trajectory

    def job():
        apply_imu_errors(ideal_imu(tr, t, nodes=sc.imu.quadrature_nodes), err, np.random.default_rng(1))

    med, spread = _median_rate(job, len(t), 3)
    return round(med), "car", [round(v) for v in spread]


def _tc_table(times, r_rx, n_sat=8, seed=0):
    """Corrected ranges of ``n_sat`` satellites 20,000 km away at ``times``,
    seen from a receiver at rest at ``r_rx`` with a drifting clock."""
    from types import SimpleNamespace

    rng = np.random.default_rng(seed)
    up = r_rx / np.linalg.norm(r_rx)
    dirs = []
    while len(dirs) < n_sat:
        d = rng.normal(size=3)
        d /= np.linalg.norm(d)
        if d @ up > 0.3:
            dirs.append(d)
    dirs = np.array(dirs)
    vel = np.cross(dirs, up) * 3.9e3
    m = len(times)
    t = np.repeat(times, n_sat)
    tt = (t - times[0])[:, None]
    ps = np.tile(r_rx + 2.0e7 * dirs, (m, 1)) + np.tile(vel, (m, 1)) * tt
    vs = np.tile(vel, (m, 1))
    d = r_rx - ps
    rng_m = np.linalg.norm(d, axis=1)
    clock_b, clock_d = 3.0e4 + 20.0 * (t - times[0]), np.full(len(t), 20.0)
    return SimpleNamespace(time=t, epoch=np.repeat(np.arange(m), n_sat), sat=np.tile([f"G{k:02d}" for k in
                           range(1, n_sat + 1)], m), sat_pos_e=ps, sat_vel_e=vs, travel_s=rng_m / 299792458.0 * 0,
                           pseudorange_m=rng_m + clock_b, sigma_pr_m=np.full(len(t), 3.0),
                           range_rate_m_s=np.einsum("ij,ij->i", d / rng_m[:, None], -vs) + clock_d,
                           sigma_rr_m_s=np.full(len(t), 0.1), elevation_rad=np.full(len(t), 0.8))


def _tc_job(imu, init):
    """The tightly coupled filter as navigate runs it: 21 INS states plus the
    receiver clock, IMU-rate propagation, pseudorange and pseudorange-rate
    updates from 8 satellites every second, gated per satellite."""
    from .. import earth
    from ..integration import FilterSettings, run_filter
    from ..integration.blocks import ReceiverClock
    from ..integration.tight import Pseudorange, PseudorangeRate

    table = _tc_table(imu.time[::100], earth.lla_to_ecef(init.lla))
    settings = FilterSettings.standard(_navigate_noise(), scale_factors=True,
                                       extra_blocks=[ReceiverClock(estimate0=(3.0e4, 20.0))])
    meas = [Pseudorange(table), PseudorangeRate(table)]
    return lambda: run_filter(imu, init, meas, settings)


def _navigate_noise():
    """The sensor noise ``inskit navigate`` builds from its default ``[noise]``
    section (Gauss-Markov biases, 300 s)."""
    from .config import NoiseSection
    from .navigate import sensor_noise

    return sensor_noise(NoiseSection())


def _drive_filter_jobs(quick):
    """The filter alone (``run_filter``, no reading or writing) on the 200 Hz
    car drive of ``navigate_cli_epochs_per_s`` (1 h; 10 min in quick mode),
    started from the truth's first row, 21 states, ZUPT where the fixes
    stand still and NHC at 10 Hz:

    * ``lc_drive_epochs_per_s``: its 1 Hz fixes (antenna 1.2 m above the
      IMU), the settings of the whole-command figure;
    * ``lc_drive_4hz_epochs_per_s``: 4 Hz fixes (the truth with 2 cm of
      noise), the update rates of drive_0708's config (ZUPT/NHC at 10 Hz,
      4 Hz GNSS).

    Returns ``{key: job, "epochs": n}``, or {} without ``examples/car.toml``."""
    from ..alignment.coarse import static_intervals
    from ..integration import FilterSettings, GnssPosition, NonHolonomic, ZeroVelocity, run_filter
    from ..io.csv_formats import lean_columns, read_gnss, read_imu
    from ..types import GnssData, NavState
    from .bench_cli import _EXAMPLES, bench_drive

    if not (_EXAMPLES / "car.toml").is_file():
        return {}
    d = bench_drive(600.0 if quick else 3600.0, 200.0)
    imu, g1 = read_imu(d / "imu.csv"), read_gnss(d / "gnss.csv")
    names = ["time_s", "lat_deg", "lon_deg", "height_m", "vn_m_s", "ve_m_s", "vd_m_s", "roll_deg", "pitch_deg",
             "yaw_deg"]
    tr = lean_columns(d / "truth.csv", [names])[0]
    init = NavState.from_euler(float(tr[0, 0]), np.radians(tr[0, 1:3]).tolist() + [float(tr[0, 3])], tr[0, 4:7],
                               np.radians(tr[0, 7:10]))
    k4 = np.searchsorted(tr[:, 0], np.arange(tr[0, 0], tr[-1, 0], 0.25))
    rng = np.random.default_rng(4)
    lla4 = np.column_stack([np.radians(tr[k4, 1]), np.radians(tr[k4, 2]), tr[k4, 3]])
    lla4[:, 2] += rng.normal(0.0, 0.02, len(k4))
    g4 = GnssData(tr[k4, 0], lla4, np.full((len(k4), 3), 0.02))
    settings = FilterSettings.standard(_navigate_noise(), scale_factors=True)
    still = ZeroVelocity(static_intervals(g1), 10.0, 0.02)
    nhc = NonHolonomic([(imu.time[0], imu.time[-1])], 10.0, 0.1)
    m1 = [GnssPosition(g1, lever_arm_b=np.array([0.0, 0.0, -1.2])), still, nhc]
    m4 = [GnssPosition(g4), still, nhc]
    return {"lc_drive_epochs_per_s": lambda: run_filter(imu, init, m1, settings),
            "lc_drive_4hz_epochs_per_s": lambda: run_filter(imu, init, m4, settings),
            "epochs": len(imu) - 1}


def _lc_job(imu, init):
    """The whole closed-loop filter as navigate runs it by default: NED
    mechanization and 21-state covariance propagation at IMU rate with
    Gauss-Markov biases, a GNSS position update every second, NHC at 10 Hz."""
    from ..integration import FilterSettings, GnssPosition, NonHolonomic, run_filter
    from ..types import GnssData

    tg = imu.time[::100]
    gnss = GnssData(tg, np.tile(init.lla, (len(tg), 1)), np.full((len(tg), 3), 0.5))
    settings = FilterSettings.standard(_navigate_noise(), scale_factors=True)
    meas = [GnssPosition(gnss), NonHolonomic([(imu.time[0], imu.time[-1])], 10.0, 0.1)]
    return lambda: run_filter(imu, init, meas, settings)
