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

The Python face (``docs/api.md``): :func:`navigate`, :func:`simulate`,
:func:`mechanize`, the readers :func:`read_imu` (every IMU format inskit
knows, recognised by its header: the inskit CSV and the rtklibexplorer log
of the bundled drives), :func:`read_gnss` (inskit CSV, RTKLIB ``.pos``),
:func:`read_solution` and :func:`read_truth`, and the data types
:class:`ImuData`, :class:`GnssData`, :class:`NavState`,
:class:`NavSolution` (``.to_dataframe()``).  They load on first use, so
``import inskit`` pulls in neither numba nor scipy, pandas or matplotlib.

Modules mirror the domain: :mod:`earth`, :mod:`rotations`, :mod:`strapdown`,
:mod:`io`, :mod:`analysis`, :mod:`simulation`, :mod:`alignment`,
:mod:`filters`, :mod:`integration`, :mod:`gnss`, :mod:`gyrofree`,
:mod:`platform`, :mod:`jobs` (what the commands run), :mod:`cli`.
"""

from importlib import import_module as _import_module

from .errors import ConfigError, InputError, InskitError


def _refresh_compile_cache():
    """numba's cache rebuilt when a compiled source changed (:mod:`._numba_cache`)."""
    try:
        from . import _numba_cache

        _numba_cache.refresh()
    except Exception:  # noqa: BLE001 (a check of the cache must never stop the package from loading)
        pass


_refresh_compile_cache()


def _install_blas_finder():
    """numba's BLAS check without ``scipy.linalg``'s import (:mod:`._numba_blas`)."""
    try:
        from . import _numba_blas

        _numba_blas.install()
    except Exception:  # noqa: BLE001 (a speed-up only: numba then does as it always did)
        pass


_install_blas_finder()


def _install_light_cache_loads():
    """numba's cache loads without its registries' refresh (:mod:`._numba_load`)."""
    try:
        from . import _numba_blas, _numba_load

        _numba_load.install(preload_blas=_numba_blas.preload)
    except Exception:  # noqa: BLE001 (a speed-up only: numba then does as it always did)
        pass


_install_light_cache_loads()

#: public name -> (module, attribute), loaded on first access (PEP 562)
_LAZY = {
    "navigate": ("inskit.api", "navigate"),
    "NavigationRun": ("inskit.api", "NavigationRun"),
    "simulate": ("inskit.api", "simulate"),
    "mechanize": ("inskit.api", "mechanize"),
    "read_imu": ("inskit.io.formats", "read_imu"),
    "read_gnss": ("inskit.io.formats", "read_gnss"),
    "read_solution": ("inskit.io.csv_formats", "read_solution"),
    "read_truth": ("inskit.io.csv_formats", "read_solution"),  # truth files are solution files
    "write_solution": ("inskit.io.csv_formats", "write_solution"),
    "ImuData": ("inskit.types", "ImuData"),
    "GnssData": ("inskit.types", "GnssData"),
    "NavState": ("inskit.types", "NavState"),
    "NavSolution": ("inskit.types", "NavSolution"),
}

#: subpackages and modules reachable as attributes without their own import (``inskit.io.read_imu``)
_SUBMODULES = ("alignment", "analysis", "api", "earth", "errors", "filters", "gnss", "gyrofree", "integration", "io",
               "jobs", "platform", "rotations", "simulation", "strapdown", "types", "units")

__all__ = ["ConfigError", "GnssData", "ImuData", "InputError", "InskitError", "NavSolution", "NavState",
           "NavigationRun", "__version__", "mechanize", "navigate", "read_gnss", "read_imu", "read_solution",
           "read_truth", "simulate", "write_solution"]


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("inskit")
    except PackageNotFoundError:  # running from a source tree without install
        return "0.0.0"


def __getattr__(name):
    if name in _LAZY:
        module, attr = _LAZY[name]
        value = getattr(_import_module(module), attr)
    elif name in _SUBMODULES:
        value = _import_module(f"inskit.{name}")
    elif name == "__version__":
        value = _version()  # importlib.metadata costs 35 ms: only when asked
    else:
        raise AttributeError(f"module 'inskit' has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(__all__) | set(_SUBMODULES) | {k for k in globals() if not k.startswith("_")})
