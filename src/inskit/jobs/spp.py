"""``inskit spp``: single-point positioning of a RINEX observation file, its
output files and its scores against a reference position.

Output folder (``out``), each file written whole or not at all, and
``summary.json`` last with the list of files (the mark of a complete run):

* ``spp.pos``: RTKLIB solution format, Q = 5 (:func:`inskit.gnss.solution.write_pos`);
* ``spp_solution.csv``: the package's GNSS fix format
  (:func:`inskit.io.csv_formats.write_gnss`; time = GPS seconds of week),
  ready for ``inskit navigate``;
* ``spp_epochs.csv``: every epoch with its status, satellites, DOPs,
  sigmas, residual test, clocks, excluded satellites and (with a reference)
  its east/north/up error.
"""

from __future__ import annotations

import time
import warnings
from pathlib import Path

import numpy as np

from ..errors import ConfigError, InputError
from ..files import check_folder_writable, write_csv, write_json

IONO = ("klobuchar", "iono-free", "none")
TROPO = ("saastamoinen", "none")
SYSTEMS = ("G", "E")
FILES = ("spp.pos", "spp_solution.csv", "spp_epochs.csv", "summary.json")


def _log_default(msg):
    pass


def parse_systems(systems):
    """``"G,E"`` or a sequence of letters -> a checked tuple."""
    if isinstance(systems, str):
        systems = [s for s in systems.replace(" ", "").split(",") if s]
    systems = tuple(str(s).upper() for s in systems)
    bad = [s for s in systems if s not in SYSTEMS]
    if not systems or bad or len(set(systems)) != len(systems):
        raise ConfigError(f"--systems: expected a comma-separated subset of {','.join(SYSTEMS)}, got "
                          f"{','.join(systems) or 'nothing'}")
    return systems


def parse_reference(reference, obs=None):
    """``None``, ``"header"``, ``"X,Y,Z"`` or three numbers -> ECEF (3,) or None."""
    if reference is None:
        return None
    if isinstance(reference, str) and reference.strip().lower() == "header":
        if obs is None:
            return "header"
        r = getattr(obs, "approx_position_e", None)
        if r is None or not np.isfinite(r).all() or not np.linalg.norm(r) > 6.0e6:
            raise InputError(f"{obs.path}: --reference header, but the header has no usable APPROX POSITION XYZ "
                             f"(got {None if r is None else np.asarray(r).tolist()}); give --reference X,Y,Z")
        return np.asarray(r, dtype=float).reshape(3)
    if isinstance(reference, str):
        parts = [p for p in reference.replace(" ", "").split(",") if p]
        try:
            r = np.array([float(p) for p in parts])
        except ValueError:
            raise InputError(f"--reference: expected X,Y,Z (ECEF metres) or 'header', got {reference!r}") from None
    else:
        r = np.asarray(reference, dtype=float).reshape(-1)
    if r.shape != (3,) or not np.isfinite(r).all():
        raise InputError(f"--reference: expected three finite ECEF coordinates X,Y,Z [m] or 'header', got "
                         f"{reference!r}")
    if not 6.2e6 < np.linalg.norm(r) < 6.6e6:
        raise InputError(f"--reference {r.tolist()}: |r| = {np.linalg.norm(r) / 1e3:.1f} km is not on the Earth's "
                         "surface; ECEF metres expected")
    return r


def _check_options(mask_deg, iono, tropo):
    if iono not in IONO:
        raise ConfigError(f"--iono must be one of {', '.join(IONO)}, got {iono!r}")
    if tropo not in TROPO:
        raise ConfigError(f"--tropo must be one of {', '.join(TROPO)}, got {tropo!r}")
    from ..config_files import mask_problem

    problem = mask_problem(mask_deg)
    if problem:
        raise ConfigError(f"--mask: {problem}")


def _refuse(out, overwrite, inputs=()):
    from ..files import check_outputs

    files = [out / f for f in FILES]
    check_outputs(files, inputs, overwrite)
    return files


def _read(obs_path, nav_path, systems):
    from ..gnss.rinex import read_nav, read_obs

    for p, what in ((obs_path, "observation"), (nav_path, "navigation")):
        if not Path(p).is_file():
            raise InputError(f"{p}: no such {what} file")
    obs = read_obs(obs_path, systems=systems)
    nav = read_nav(nav_path, systems=systems)
    return obs, nav


def _median(x):
    x = np.asarray(x, dtype=float)
    x = x[np.isfinite(x)]
    return float(np.median(x)) if len(x) else float("nan")


#: Unhealthy above this fraction of epochs unsolved, or flagged by the residual test or HDOP: an
#: open-sky receiver with broadcast orbits covering its day solves nearly every epoch, so a tenth
#: lost names a cause (orbits, obstruction, a wrong file) the figures would otherwise hide.
UNHEALTHY_EPOCH_FRACTION = 0.10
#: A median code residual above this [m] says the models or the data are wrong (about 1 m is usual).
RESIDUAL_WARN_M = 10.0
#: A median HDOP above this says the geometry, not the receiver, sets the errors.
HDOP_WARN = 5.0
#: A receiver whose median Doppler speed [m/s] exceeds the first, or (without Doppler) whose fixes lie
#: further than the second [m] (95th percentile) from their median, moves: errors against one
#: ``--reference`` point then measure its travel, not the fixes' accuracy (a static receiver's single-point
#: fixes scatter over metres and their Doppler speeds over centimetres per second).
MOVING_SPEED_M_S, MOVING_SPREAD_M = 0.5, 100.0


def receiver_motion(sol, enu):
    """``{"median_speed_m_s", "spread_m"}`` of the solved epochs (None
    where none has the figure): the median horizontal Doppler speed and
    the 95th percentile of the horizontal distance of the fixes, ``enu``
    against the reference, from their median."""
    ok = np.isfinite(enu).all(axis=1)
    v = np.asarray(sol.v_enu)[ok][:, :2]
    v = v[np.isfinite(v).all(axis=1)]
    h = enu[ok][:, :2]
    spread = float(np.percentile(np.hypot(*(h - np.median(h, axis=0)).T), 95)) if len(h) else None
    return {"median_speed_m_s": float(np.median(np.hypot(v[:, 0], v[:, 1]))) if len(v) else None,
            "spread_m": spread}


def motion_warning(m) -> str | None:
    """The warning of a receiver that moves (:func:`receiver_motion`) scored against one reference point."""
    if not m:
        return None
    speed, spread = m.get("median_speed_m_s"), m.get("spread_m")
    if not ((speed is not None and speed > MOVING_SPEED_M_S)
            or (speed is None and spread is not None and spread > MOVING_SPREAD_M)):
        return None
    said = ([f"median Doppler speed {speed:.3g} m/s"] if speed is not None else []) + (
        [f"95 % of the fixes within {spread:.4g} m of their median"] if spread is not None else [])
    return (f"the receiver moves ({', '.join(said)}): the errors against the one --reference point measure its "
            "travel, not the fixes' accuracy; score a moving receiver against its own track")


def spp_health(s: dict) -> dict:
    """Verdict of a single-point run from its summary ``s``: ``verdict``
    ("healthy" or "unhealthy"), ``reasons`` (each a sentence) and
    ``warnings``.  Unhealthy when more than
    :data:`UNHEALTHY_EPOCH_FRACTION` of the epochs are unsolved or flagged;
    warned of any unsolved, flagged or excluded epoch, of solved epochs
    without a redundant range (unchecked: ``epochs_without_redundancy``), observed satellites
    without a usable ephemeris, a median residual
    above :data:`RESIDUAL_WARN_M` and a median HDOP above :data:`HDOP_WARN`."""
    n = max(int(s["epochs_total"]), 1)
    reasons, warns = [], []
    for key, what in (("epochs_unsolved", "unsolved"), ("epochs_flagged", "flagged (residual test or HDOP)")):
        k = int(s[key])
        if not k:
            continue
        line = f"{k} of {n} epochs ({100.0 * k / n:.1f} %) {what}"
        (reasons if k / n > UNHEALTHY_EPOCH_FRACTION else warns).append(line)
    if s.get("epochs_excluded_sats"):
        warns.append(f"{s['epochs_excluded_sats']} epochs solved only after excluding a satellite (residual test)")
    k, m = int(s.get("epochs_without_redundancy") or 0), int(s.get("epochs_solved") or 0)
    if k:  # as many satellites as unknowns: the fix fits them exactly, whatever their errors
        warns.append(f"{k} of {m} solved epochs ({100.0 * k / max(m, 1):.1f} %) had no redundant range (as many "
                     "satellites as unknowns): the residual test and the satellite exclusion could not run there, "
                     "so their fixes are unchecked (their residuals are zero by construction)")
    res = s.get("rms_residual_median_m")
    if res is not None and res > RESIDUAL_WARN_M:
        warns.append(f"median RMS code residual {res:.1f} m (about 1 m is usual): models or data are off")
    lost = s.get("satellites_without_ephemeris") or {}
    if lost:
        names = sorted(lost)
        shown = ", ".join(names[:8]) + (f" and {len(names) - 8} more" if len(names) > 8 else "")
        warns.append(f"{len(names)} observed satellite{'s' if len(names) != 1 else ''} without a usable ephemeris "
                     f"in the navigation file ({shown}): {sum(lost.values())} ranges unused")
    hd = s.get("hdop_median")
    if hd is not None and hd > HDOP_WARN:
        warns.append(f"median HDOP {hd:.1f}: the geometry, not the ranges, sets the errors")
    moving = motion_warning(s.get("reference_motion"))
    if moving:
        warns.append(moving)
    return {"verdict": "unhealthy" if reasons else "healthy", "reasons": reasons, "warnings": warns}


def run_spp(obs_path, nav_path, *, reference=None, mask_deg=10.0, iono="klobuchar", tropo="saastamoinen",
            systems=("G", "E"), out=None, overwrite=False, raim=True, log=None):
    """Single-point positioning of ``obs_path`` with the broadcast orbits of
    ``nav_path``.

    Parameters
    ----------
    obs_path, nav_path : str or Path
        RINEX 2/3 observation and navigation files (gzip or Hatanaka allowed).
    reference : None, "header", "X,Y,Z" or (3,) array_like
        Reference ECEF position [m] to score against ("header": the
        observation header's APPROX POSITION XYZ).
    mask_deg : float
        Elevation mask [deg].
    iono : {"klobuchar", "iono-free", "none"}
    tropo : {"saastamoinen", "none"}
    systems : str or sequence of str
        GNSS systems ("G", "E").
    out : str or Path, optional
        Output folder for spp.pos, spp_solution.csv, spp_epochs.csv and
        summary.json.
    overwrite : bool
        Replace the files of an earlier run in ``out``.
    raim : bool
        Fault detection and exclusion by the residual test.
    log : callable, optional
        Progress and warnings, one line per call (stderr in the CLI).

    Returns
    -------
    dict
        JSON-ready summary: ``epochs_total``, ``epochs_solved`` (statuses 1
        and 2), ``epochs_flagged``, ``epochs_unsolved``,
        ``epochs_excluded_sats``, ``horizontal_rms_m``, ``rms_3d_m``,
        ``mean_enu_m``, ``std_enu_m``, ``max_horizontal_m`` (against the
        reference; None without one), ``hdop_median``, ``n_sats_median``,
        ``seconds`` (read + solve wall time), ``read_s``, ``solve_s``,
        ``notes``, ``health`` (:func:`spp_health`), ``files`` ...
    """
    from ..gnss.solution import errors_against, write_pos
    from ..gnss.spp import EXCLUDED, FLAGGED, STATUS_NAMES, UNSOLVED, spp

    log = log or _log_default
    systems = parse_systems(systems)
    mask_deg = float(mask_deg)
    _check_options(mask_deg, iono, tropo)
    if not (reference is None or isinstance(reference, str)):
        reference = parse_reference(reference)
    files = []
    if out is not None:
        out = Path(out)
        files = _refuse(out, overwrite, [obs_path, nav_path])
        check_folder_writable(out)
    t0 = time.perf_counter()
    with warnings.catch_warnings(record=True) as read_warnings:
        warnings.simplefilter("always")
        obs, nav = _read(obs_path, nav_path, systems)
    t1 = time.perf_counter()
    ref = parse_reference(reference, obs) if isinstance(reference, str) else reference
    log(f"spp: {len(obs.time)} epochs, {len(obs.sats)} satellites in {Path(obs_path).name}; "
        f"{len(nav.sats)} navigation records in {Path(nav_path).name}")
    for w in read_warnings:
        log(f"spp: {w.message}")
    timing = {}
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        sol = spp(obs, nav, mask_deg=mask_deg, iono=iono, tropo=tropo, raim=raim, systems=systems, timing=timing,
                  settings={"mask": "--mask", "iono": "--iono klobuchar"})
    t2 = time.perf_counter()
    notes = [str(w.message) for w in read_warnings] + list(sol.notes)
    from ..gnss.spp import clock_jump_note, receiver_clock_jumps

    jump_note = clock_jump_note(sol, *receiver_clock_jumps(sol), path=Path(obs_path).name)
    if jump_note:
        notes.append(jump_note + ": each epoch's clock takes it")
    notes += [str(w.message) for w in caught if str(w.message) not in notes]
    for n_ in notes[len(read_warnings):]:
        log(f"spp: {n_}")
    solved = sol.solved
    s = {
        "obs": str(obs_path), "nav": str(nav_path), "systems": list(systems), "mask_deg": mask_deg, "iono": iono,
        "tropo": tropo, "raim": bool(raim),
        "epochs_total": len(sol), "epochs_solved": int(solved.sum()),
        "epochs_flagged": int((sol.status == FLAGGED).sum()), "epochs_unsolved": int((sol.status == UNSOLVED).sum()),
        "epochs_excluded_sats": int((sol.status == EXCLUDED).sum()),
        # solved with no redundant range: no residual test or exclusion possible (RAIM had nothing to check)
        "epochs_without_redundancy": int((solved & (np.asarray(sol.redundancy) <= 0)).sum()),
        "epochs_with_velocity": int((solved & np.isfinite(sol.v_e).all(axis=1)).sum()),
        "status_names": {str(k): v for k, v in STATUS_NAMES.items()},
        "hdop_median": _median(sol.hdop[solved]), "n_sats_median": _median(sol.n_sats[solved]),
        "rms_residual_median_m": _median(sol.rms_residual_m[solved]),
        "ranges_dropped": timing.get("dropped", {}),
        "satellites_without_ephemeris": timing.get("no_ephemeris", {}),
        "seconds": t2 - t0, "read_s": t1 - t0, "solve_s": t2 - t1,
        "reference_e": None if ref is None else ref.tolist(),
        "notes": notes,
    }
    enu = None
    if ref is not None:
        enu, e = errors_against(sol, ref)
        s.update({k: e[k] for k in ("horizontal_rms_m", "rms_3d_m", "mean_enu_m", "std_enu_m",
                                    "max_horizontal_m")})
        s["mean_neu_m"] = [e["mean_enu_m"][1], e["mean_enu_m"][0], e["mean_enu_m"][2]]
        s["std_neu_m"] = [e["std_enu_m"][1], e["std_enu_m"][0], e["std_enu_m"][2]]
        s["reference_motion"] = receiver_motion(sol, enu)
    else:
        s.update({k: None for k in ("horizontal_rms_m", "rms_3d_m", "mean_enu_m", "std_enu_m", "max_horizontal_m",
                                    "mean_neu_m", "std_neu_m", "reference_motion")})
    s["health"] = spp_health(s)
    if out is not None:
        s["files"] = [str(f) for f in _write(out, files, sol, enu, obs_path, nav_path, s, write_pos, log)]
    else:
        s["files"] = []
    return s


def _write(out, files, sol, enu, obs_path, nav_path, s, write_pos, log):
    from ..io.csv_formats import write_gnss

    pos, fixes, epochs, summary = files
    write_pos(pos, sol, header_lines=(f"inp file  : {obs_path}", f"inp file  : {nav_path}",
                                      f"elev mask : {s['mask_deg']:g} deg", f"ionos opt : {s['iono']}",
                                      f"tropo opt : {s['tropo']}", f"navi sys  : {','.join(s['systems'])}"))
    written = [pos]
    if sol.solved.any():
        has_v = np.isfinite(sol.v_e[sol.solved]).all(axis=1)
        with_v = bool(has_v.all())
        if has_v.any() and not with_v:
            s["notes"].append(f"velocity left out of {fixes.name}: {int((~has_v).sum())} of {len(has_v)} fixes "
                              "have no Doppler velocity")
            log(f"spp: {s['notes'][-1]}")
        write_gnss(fixes, sol.to_gnss_data(with_velocity=with_v), overwrite=True)
        written.append(fixes)
    else:
        fixes.unlink(missing_ok=True)  # no stale fixes from an earlier run beside this run's files
    cols = {"time_gps_s": sol.time, "week": sol.week, "sow_s": sol.sow, "status": sol.status,
            "refusal": sol.refusal, "n_sats": sol.n_sats, "redundancy": sol.redundancy,
            "gdop": sol.gdop, "pdop": sol.pdop, "hdop": sol.hdop, "vdop": sol.vdop,
            "sigma_e_m": sol.sigma_enu[:, 0], "sigma_n_m": sol.sigma_enu[:, 1], "sigma_u_m": sol.sigma_enu[:, 2],
            "rms_residual_m": sol.rms_residual_m, "chi2": sol.chi2, "chi2_limit": sol.chi2_limit}
    if enu is not None:
        cols.update({"err_e_m": enu[:, 0], "err_n_m": enu[:, 1], "err_u_m": enu[:, 2]})
    cols.update({"x_m": sol.r_e[:, 0], "y_m": sol.r_e[:, 1], "z_m": sol.r_e[:, 2]})
    for k, sy in enumerate(sol.systems):
        cols[f"clock_{sy}_m"] = sol.clock_m[:, k]
    v = sol.v_enu
    cols.update({"ve_m_s": v[:, 0], "vn_m_s": v[:, 1], "vu_m_s": v[:, 2], "clock_drift_m_s": sol.clock_drift_m_s,
                 "excluded": list(sol.excluded)})
    write_csv(epochs, cols, "%.10g")
    written += [epochs, summary]
    s["files"] = [str(f) for f in written]
    write_json(summary, s, indent=2)  # strict JSON: a NaN figure is null
    return written


def spp_throughput(obs_path, nav_path, repeats=5, *, systems=("G", "E")):
    """Epochs per second of the SPP solve path (both range-table passes and
    both solves; files read once, one warm-up call excluded), for
    ``inskit bench``.

    Returns
    -------
    dict
        ``epochs``, ``repeats``, ``epochs_per_s`` (median), ``epochs_per_s_min``,
        ``epochs_per_s_max``, ``spread`` ((max - min) / median).
    """
    from ..gnss.spp import spp

    systems = parse_systems(systems)
    obs, nav = _read(obs_path, nav_path, systems)
    n = len(obs.time)
    rates = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        spp(obs, nav, systems=systems)
        for _ in range(max(1, int(repeats))):
            t0 = time.perf_counter()
            spp(obs, nav, systems=systems)
            rates.append(n / (time.perf_counter() - t0))
    med = float(np.median(rates))
    return {"epochs": n, "repeats": len(rates), "epochs_per_s": med, "epochs_per_s_min": float(min(rates)),
            "epochs_per_s_max": float(max(rates)), "spread": float((max(rates) - min(rates)) / med)}


__all__ = ["IONO", "SYSTEMS", "TROPO", "parse_reference", "parse_systems", "run_spp", "spp_throughput"]
