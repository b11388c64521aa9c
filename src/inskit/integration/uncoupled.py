"""The uncoupled scheme: no filter, every GNSS fix resets the INS.

SYSTEM.md §2 table 2-2 (source 000): the simplest integration, where the
satellite solution overwrites the inertial position (and velocity, when the
receiver gives one) at each fix and the INS only bridges between fixes and
through outages.  Sensor errors are never estimated, so the INS drifts from
the last reset as if free.
"""

from __future__ import annotations

import numpy as np

from .. import earth
from ..errors import InputError
from ..rotations import dcm_from_quat
from ..strapdown import NedIntegrator
from ..types import GnssData, ImuData, NavSolution, NavState
from .measurements import ned_difference


def run_uncoupled(imu: ImuData, initial: NavState, gnss: GnssData, *, use=None, lever_arm_b=(0.0, 0.0, 0.0),
                  use_velocity=None, coning=True, gravity="normal") -> NavSolution:
    """Free-inertial NED mechanization reset to every used GNSS fix.

    At a fix time ``t`` (between IMU samples ``k`` and ``k+1``) the INS state
    at ``k`` is moved so that its antenna, extrapolated to ``t`` with the IMU
    velocity, sits on the fix; the velocity is overwritten with the fix's
    (minus the lever-arm velocity) when ``use_velocity``.

    Parameters
    ----------
    imu, initial : ImuData, NavState
    gnss : GnssData
    use : (n,) bool array, optional
        Fixes to use.
    lever_arm_b : (3,) array_like
        IMU-to-antenna lever arm, body axes [m].
    use_velocity : bool, optional
        Reset the velocity too (default: when the GNSS data carry one).
    coning : bool
    gravity : {"normal", "normal-simple", "j2"}
        Gravity model of the mechanization (:func:`inskit.earth.gravity_n`).

    Returns
    -------
    NavSolution
    """
    use = np.ones(len(gnss), bool) if use is None else np.asarray(use, bool)
    if use_velocity is None:
        use_velocity = gnss.has_velocity
    if use_velocity and not gnss.has_velocity:
        raise InputError("use_velocity is set but the GNSS data carry no velocity")
    lever = np.asarray(lever_arm_b, dtype=float)
    t = imu.time
    rows = np.nonzero(use)[0]
    k = np.searchsorted(t, gnss.time[rows], side="right") - 1
    ok = (k >= 1) & (gnss.time[rows] <= t[-1])
    rows, k = rows[ok], k[ok]
    ins = NedIntegrator(initial, coning=coning, gravity=gravity)
    parts = [NavSolution._trusted(t[:1], initial.lla[None], initial.v_n[None], initial.q_nb[None])]
    k_done = 1
    for r, kk in zip(rows.tolist(), k.tolist()):
        if kk + 1 > k_done:
            parts.append(ins.run(imu.slice(k_done, kk + 1)))
            k_done = kk + 1
        st = ins.state
        C_nb = dcm_from_quat(st.q_nb)
        w_b = imu.dtheta_b[kk] / (t[kk] - t[kk - 1])
        d = ned_difference(st.lla, gnss.lla[r]) + C_nb @ lever + st.v_n * (gnss.time[r] - t[kk])
        rn, re = earth.principal_radii(st.lla[0], st.lla[2])
        lla = st.lla - np.array([d[0] / rn, d[1] / (re * np.cos(st.lla[0])), -d[2]])
        v = gnss.v_n[r] - C_nb @ np.cross(w_b, lever) if use_velocity else None
        ins.reset(lla, v)
        last = parts[-1]
        if len(last) and last.time[-1] == t[kk]:  # the reset state is the row's output
            last.lla[-1] = lla
            if v is not None:
                last.v_n[-1] = v
    if k_done < len(t):
        parts.append(ins.run(imu.slice(k_done, len(t))))
    return NavSolution.concat(parts)
