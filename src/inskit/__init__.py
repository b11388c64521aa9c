"""inskit: inertial navigation and INS/GNSS integration.

Frame grammar (used in every name in the package)
--------------------------------------------------
Frames: ``i`` inertial (ECI, coincident with ``e`` at the start of a run),
``e`` Earth-centred Earth-fixed (WGS84), ``n`` local level North-East-Down,
``w`` wander-azimuth (``n`` turned about its down axis by the wander angle),
``b`` body (forward-right-down), ``p`` platform.

* ``C_nb`` is the direction-cosine matrix that maps a vector resolved in ``b``
  into ``n``: ``f_n = C_nb @ f_b`` (inner letters cancel by eye).
* ``omega_ie_n`` is the angular rate of ``e`` relative to ``i`` resolved in
  ``n``; ``v_n`` is the Earth-relative velocity resolved in ``n``.
* Quaternions are scalar first, Hamilton product, ``q_nb`` rotating ``b`` into
  ``n`` exactly as ``C_nb`` does.
* Euler angles are ``roll, pitch, yaw`` of the ZYX rotation:
  ``C_nb = Rz(yaw) @ Ry(pitch) @ Rx(roll)``.
* SI units and radians everywhere inside the package; degrees, deg/h, micro-g
  and friends appear only at the edges (file readers, CLI options, plots),
  converted through the constants in :mod:`inskit.units`.

Modules mirror the domain: :mod:`earth`, :mod:`rotations`, :mod:`strapdown`,
:mod:`io`, :mod:`analysis`, :mod:`cli` (and later simulation, alignment,
filters, gnss, gyro-free, platform).
"""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("inskit")
except PackageNotFoundError:  # running from a source tree without install
    __version__ = "0.0.0"

from .errors import InputError, InskitError  # noqa: E402

__all__ = ["InputError", "InskitError", "__version__"]
