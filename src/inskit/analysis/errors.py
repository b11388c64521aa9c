"""Navigation error against a reference: errors, statistics, plots.

Position errors are NED metres (solution minus truth, resolved at the truth
position), velocity errors m/s, attitude errors the wrapped differences of
roll, pitch and yaw, reported in arcmin at the edge.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..files import save_figure
from .. import earth
from .. import rotations as rot
from ..errors import InputError
from ..types import NavSolution
from ..units import ARCMIN


@dataclass(frozen=True)
class NavError:
    """Solution minus truth at common times.

    Attributes
    ----------
    time : (n,) ndarray
    pos_ned : (n, 3) ndarray
        [m].
    vel_ned : (n, 3) ndarray
        [m/s].
    att_rpy : (n, 3) ndarray
        Roll, pitch, yaw differences [rad], wrapped to (-pi, pi].
    """

    time: np.ndarray
    pos_ned: np.ndarray
    vel_ned: np.ndarray
    att_rpy: np.ndarray

    @property
    def horizontal(self):
        return np.hypot(self.pos_ned[:, 0], self.pos_ned[:, 1])


def nav_error(sol: NavSolution, truth: NavSolution) -> NavError:
    """Errors of ``sol`` against ``truth``, evaluated at the solution times that
    lie inside the truth's span (truth interpolated linearly)."""
    inside = (sol.time >= truth.time[0]) & (sol.time <= truth.time[-1])
    if not inside.any():
        raise InputError(
            f"the solution ({sol.time[0]:.3f}..{sol.time[-1]:.3f} s) and the truth "
            f"({truth.time[0]:.3f}..{truth.time[-1]:.3f} s) do not overlap in time: mismatched time bases?"
        )
    s = sol if inside.all() else NavSolution(sol.time[inside], sol.lla[inside], sol.v_n[inside], sol.q_nb[inside])
    tr = truth.interpolate(s.time)
    r_s = earth.lla_to_ecef(s.lla)
    r_t = earth.lla_to_ecef(tr.lla)
    C_ne = np.swapaxes(earth.dcm_en(tr.lla[:, 0], tr.lla[:, 1]), -1, -2)
    dpos = np.einsum("nij,nj->ni", C_ne, r_s - r_t)
    datt = rot.wrap_angle(s.euler - tr.euler)
    return NavError(s.time, dpos, s.v_n - tr.v_n, datt)


def _stats(x):
    x = np.asarray(x, dtype=float)
    return {"rms": float(np.sqrt(np.mean(x**2))), "max": float(np.max(np.abs(x))), "final": float(x[-1])}


def summarize(err: NavError) -> dict:
    """RMS, maximum absolute and final values of every error component.

    Keys: ``north_m``, ``east_m``, ``down_m``, ``horizontal_m``, ``3d_m``,
    ``vn_m_s``, ``ve_m_s``, ``vd_m_s``, ``roll_arcmin``, ``pitch_arcmin``,
    ``yaw_arcmin``; each maps to ``{"rms", "max", "final"}``.
    """
    p, v, a = err.pos_ned, err.vel_ned, err.att_rpy / ARCMIN
    out = {
        "north_m": _stats(p[:, 0]),
        "east_m": _stats(p[:, 1]),
        "down_m": _stats(p[:, 2]),
        "horizontal_m": _stats(err.horizontal),
        "3d_m": _stats(np.linalg.norm(p, axis=1)),
        "vn_m_s": _stats(v[:, 0]),
        "ve_m_s": _stats(v[:, 1]),
        "vd_m_s": _stats(v[:, 2]),
        "roll_arcmin": _stats(a[:, 0]),
        "pitch_arcmin": _stats(a[:, 1]),
        "yaw_arcmin": _stats(a[:, 2]),
    }
    out["epochs"] = int(len(err.time))
    out["duration_s"] = float(err.time[-1] - err.time[0])
    return out


def plot_errors(err: NavError, path, *, title="Navigation error", sigma=None):
    """Plot position, velocity and attitude errors against time to a PNG.

    Parameters
    ----------
    err : NavError
    path : str or Path
    sigma : dict, optional
        ``{"pos": (n, 3), "vel": (n, 3), "att": (n, 3)}`` 1-sigma arrays
        [m, m/s, rad]; drawn as +-3 sigma envelopes.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = err.time - err.time[0]
    fig, axes = plt.subplots(3, 1, figsize=(9, 9), sharex=True)
    groups = [
        (err.pos_ned, "position error [m]", ("north", "east", "down"), 1.0, "pos"),
        (err.vel_ned, "velocity error [m/s]", ("north", "east", "down"), 1.0, "vel"),
        (err.att_rpy / ARCMIN, "attitude error [arcmin]", ("roll", "pitch", "yaw"), 1.0 / ARCMIN, "att"),
    ]
    for ax, (data, label, names, scale, key) in zip(axes, groups):
        for j, name in enumerate(names):
            (line,) = ax.plot(t, data[:, j], lw=0.8, label=name)
            if sigma is not None and key in sigma:
                s = 3.0 * np.asarray(sigma[key])[:, j] * scale
                ax.plot(t, s, lw=0.6, ls="--", color=line.get_color())
                ax.plot(t, -s, lw=0.6, ls="--", color=line.get_color())
        ax.set_ylabel(label)
        ax.grid(True, alpha=0.3)
        ax.legend(loc="upper left", fontsize=8)
    axes[-1].set_xlabel("time since start [s]")
    axes[0].set_title(title)
    fig.tight_layout()
    save_figure(fig, path, dpi=110)
    return path
