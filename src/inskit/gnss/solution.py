"""Single-point solutions as files and as errors against a reference.

* :func:`write_pos` writes an RTKLIB solution file (``.pos``, latitude /
  longitude / height format, GPST time tags), the format RTKLIB's
  ``rnx2rtkp`` writes and :func:`inskit.io.rtklib.read_pos` reads; Q = 5
  (single) for every row.  Formatted column by column with ``np.char`` (no
  Python per value) and written whole or not at all
  (:func:`inskit.files.write_text`).
* :func:`errors_against` gives per-epoch east/north/up errors against a
  reference position (a surveyed station or a per-epoch reference track)
  and the usual summary figures.

References
----------
T. Takasu, RTKLIB ver. 2.4.2 Manual, App. B.2 "Solution file" (field
layout; the format is reproduced from the documentation, no code taken).
"""

from __future__ import annotations

from functools import reduce

import numpy as np

from .. import earth
from ..errors import InputError
from ..files import write_text
from .spp import EXCLUDED, SOLVED, SppSolution

#: Q flag RTKLIB uses for a single-point solution
Q_SINGLE = 5

_HEADER = ("%  GPST                  latitude(deg) longitude(deg)  height(m)   Q  ns   sdn(m)   sde(m)   sdu(m)"
           "  sdne(m)  sdeu(m)  sdun(m) age(s)  ratio")
_HEADER_VEL = ("    vn(m/s)    ve(m/s)    vu(m/s)      sdvn     sdve     sdvu    sdvne    sdveu    sdvun")
_GPS_EPOCH = np.datetime64("1980-01-06T00:00:00", "ms")


def gpst_strings(t_gps_s):
    """``YYYY/MM/DD HH:MM:SS.sss`` GPST strings of seconds since the GPS epoch
    (rounded to the millisecond), vectorised."""
    ms = np.round(np.asarray(t_gps_s, dtype=float) * 1000.0).astype(np.int64)
    iso = np.datetime_as_string(_GPS_EPOCH + ms.astype("timedelta64[ms]"), unit="ms")
    return np.char.replace(np.char.replace(iso, "-", "/"), "T", " ")


def _signed_sqrt(c):
    return np.sign(c) * np.sqrt(np.abs(c))


def _columns_to_lines(cols):
    """Join formatted columns ``[(fmt, array), ...]`` into row strings."""
    parts = [np.char.mod(fmt, a) if fmt else np.asarray(a, dtype=str) for fmt, a in cols]
    return reduce(lambda x, y: np.char.add(np.char.add(x, " "), y), parts)


def write_pos(path, sol: SppSolution, *, header_lines=(), statuses=(SOLVED, EXCLUDED)):
    """Write the solved epochs of ``sol`` as an RTKLIB ``.pos`` file.

    Parameters
    ----------
    path : str or Path
    sol : SppSolution
    header_lines : sequence of str
        Extra header lines (each written after ``%``), e.g. program, input
        files and options.
    statuses : sequence of int
        Epoch statuses written (default solved and solved with exclusions;
        unsolved and flagged epochs are left out, as RTKLIB leaves out
        solutions that fail its validation).

    Notes
    -----
    Columns: GPST date and time, latitude and longitude [deg], ellipsoidal
    height [m], Q (5), ns, sdn sde sdu [m], sdne sdeu sdun (signed square
    roots of the covariances, RTKLIB's convention) [m], age [s] (0), ratio
    (0); then, when every written epoch has a Doppler velocity, vn ve vu
    [m/s] (north-east-up) and sdvn sdve sdvu sdvne sdveu sdvun [m/s].

    Returns
    -------
    Path
    """
    keep = np.isin(sol.status, list(statuses))
    n = int(keep.sum())
    lla = sol.lla[keep]
    P = sol.cov_enu[keep]                           # E, N, U
    lon = -((-lla[:, 1] + np.pi) % (2.0 * np.pi) - np.pi)  # wrapped into (-pi, pi]
    cols = [
        ("", gpst_strings(sol.time[keep])),
        ("%14.9f", np.degrees(lla[:, 0])),
        ("%14.9f", np.degrees(lon)),
        ("%10.4f", lla[:, 2]),
        ("%3d", np.full(n, Q_SINGLE)),
        ("%3d", sol.n_sats[keep]),
        ("%8.4f", np.sqrt(P[:, 1, 1])),
        ("%8.4f", np.sqrt(P[:, 0, 0])),
        ("%8.4f", np.sqrt(P[:, 2, 2])),
        ("%8.4f", _signed_sqrt(P[:, 1, 0])),
        ("%8.4f", _signed_sqrt(P[:, 0, 2])),
        ("%8.4f", _signed_sqrt(P[:, 2, 1])),
        ("%6.2f", np.zeros(n)),
        ("%6.1f", np.zeros(n)),
    ]
    header = _HEADER
    v_enu = sol.v_enu[keep]
    Pv = sol.cov_v_enu[keep]
    with_vel = n > 0 and np.isfinite(v_enu).all() and np.isfinite(Pv).all()
    if with_vel:
        header += _HEADER_VEL
        cols += [("%10.5f", v_enu[:, 1]), ("%10.5f", v_enu[:, 0]), ("%10.5f", v_enu[:, 2]),
                 ("%9.5f", np.sqrt(Pv[:, 1, 1])), ("%8.5f", np.sqrt(Pv[:, 0, 0])), ("%8.5f", np.sqrt(Pv[:, 2, 2])),
                 ("%8.5f", _signed_sqrt(Pv[:, 1, 0])), ("%8.5f", _signed_sqrt(Pv[:, 0, 2])),
                 ("%8.5f", _signed_sqrt(Pv[:, 2, 1]))]
    lines = ["% program   : inskit spp (single-point positioning)"]
    lines += [f"% {h}" for h in header_lines]
    if n:
        lines.append(f"% obs start : {gpst_strings(sol.time[keep][:1])[0]} GPST")
        lines.append(f"% obs end   : {gpst_strings(sol.time[keep][-1:])[0]} GPST")
    lines.append("% pos mode  : Single")
    lines.append("%")
    lines.append(header)
    body = _columns_to_lines(cols).tolist() if n else []
    return write_text(path, "\n".join(lines + body) + "\n")


def errors_against(sol: SppSolution, reference_e, *, statuses=(SOLVED, EXCLUDED)):
    """East/north/up errors of the solutions against a reference position.

    Parameters
    ----------
    sol : SppSolution
    reference_e : (3,) or (n, 3) array_like
        Reference ECEF position [m]: one point (a static station) or one per
        epoch of ``sol`` (NaN rows are left out).
    statuses : sequence of int
        Epoch statuses scored (default solved and solved with exclusions).

    Returns
    -------
    enu : (n, 3) ndarray
        Error east, north, up [m] in the local frame of the reference;
        NaN at epochs not scored.
    summary : dict
        ``epochs_solved`` (epochs scored), ``epochs_total``,
        ``horizontal_rms_m``, ``rms_3d_m``, ``mean_enu_m``, ``std_enu_m``
        (lists of 3, east-north-up), ``max_horizontal_m``.
    """
    ref = np.asarray(reference_e, dtype=float)
    n = len(sol)
    if ref.shape == (3,):
        ref = np.broadcast_to(ref, (n, 3))
    if ref.shape != (n, 3):
        raise InputError(f"`reference_e` must have shape (3,) or ({n}, 3), got {np.shape(reference_e)}")
    ok = np.isin(sol.status, list(statuses)) & np.isfinite(ref).all(axis=1) & np.isfinite(sol.r_e).all(axis=1)
    enu = np.full((n, 3), np.nan)
    if ok.any():
        enu[ok] = earth.ecef_to_enu(sol.r_e[ok], earth.ecef_to_lla(ref[ok]))
    e = enu[ok]
    if len(e):
        h2 = e[:, 0] ** 2 + e[:, 1] ** 2
        summary = {
            "epochs_solved": int(ok.sum()), "epochs_total": n,
            "horizontal_rms_m": float(np.sqrt(h2.mean())),
            "rms_3d_m": float(np.sqrt((h2 + e[:, 2] ** 2).mean())),
            "mean_enu_m": e.mean(axis=0).tolist(), "std_enu_m": e.std(axis=0).tolist(),
            "max_horizontal_m": float(np.sqrt(h2.max())),
        }
    else:
        summary = {"epochs_solved": 0, "epochs_total": n, "horizontal_rms_m": float("nan"),
                   "rms_3d_m": float("nan"), "mean_enu_m": [float("nan")] * 3, "std_enu_m": [float("nan")] * 3,
                   "max_horizontal_m": float("nan")}
    return enu, summary


__all__ = ["Q_SINGLE", "errors_against", "gpst_strings", "write_pos"]
