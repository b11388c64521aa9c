"""Data containers shared across the package: IMU samples, navigation states.

They are valid when constructed or refuse to be: shapes, finiteness and time
order are checked once here, so the compiled kernels can trust their input.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from . import rotations as rot
from .errors import InputError
from .units import DEG


def plain_number(x, digits=None) -> str:
    """A number as a message shows it: ``inf``, ``nan``, ``0.1``, never
    ``np.float64(0.1)`` (the ``repr`` of a numpy scalar since numpy 2).

    ``digits=None`` gives the shortest text that reads back as the same
    float (``repr(float(x))``), for a value the user must find in a file;
    an integer gives ``:.{digits}g``.  Arrays give ``[a, b, ...]``; what is
    not a number comes back as its ``repr``.
    """
    if np.ndim(x) > 0:
        return "[" + ", ".join(plain_number(v, digits) for v in np.asarray(x).ravel()) + "]"
    try:
        v = float(x)
    except (TypeError, ValueError):
        return repr(x)
    return repr(v) if digits is None else f"{v:.{digits}g}"


def as_float_array(name, x) -> np.ndarray:
    """``x`` as a C-contiguous float64 array, or an :class:`InputError`
    naming ``name`` when it holds no plain real numbers.

    Lists, tuples, pandas Series and DataFrames, integer and float32 arrays
    and strided views are taken (converted, never modified).  Refused:
    ``None``, text, complex numbers (numpy would drop the imaginary part with
    a warning), ragged nesting, and datetimes (numpy would give nanoseconds
    since 1970); a timedelta becomes seconds.
    """
    if x is None:
        raise InputError(f"`{name}` is None; expected an array of numbers")
    try:
        a = np.asarray(x)
    except (TypeError, ValueError) as exc:  # ragged nesting: [[1, 2, 3], [4, 5]]
        raise InputError(f"`{name}` is not an array of numbers: a {type(x).__name__} whose rows differ in "
                         "length") from None
    kind = a.dtype.kind
    if kind == "m":  # a timedelta (pandas' time since the start) is seconds
        return np.ascontiguousarray(a / np.timedelta64(1, "s"), dtype=float)
    if kind == "M":
        raise InputError(f"`{name}` holds datetimes ({a.dtype}); expected seconds as numbers, e.g. "
                         f"(t - t0) / np.timedelta64(1, 's')")
    if kind == "c":
        raise InputError(f"`{name}` holds complex numbers; expected real numbers")
    if kind in "fiub":
        return np.ascontiguousarray(a, dtype=float)
    try:  # object or text: numbers held as objects convert, text does not
        return np.ascontiguousarray(a, dtype=float)
    except (TypeError, ValueError):
        flat = a.ravel()
        bad = next((v for v in flat if not isinstance(v, (int, float, np.integer, np.floating))), None)
        if isinstance(bad, (str, bytes)):  # numpy's str_ and bytes_ are these too
            shown = f"the text {str(bad)!r}"
        else:
            shown = f"{bad!r} ({type(bad).__name__})"
        raise InputError(f"`{name}` holds {shown}; expected numbers") from None


def _as_array(name, x, shape_tail, n=None):
    a = as_float_array(name, x)
    if a.ndim != 1 + len(shape_tail) or a.shape[1:] != tuple(shape_tail):
        want = "(n" + "".join(f", {s}" for s in shape_tail) + ")"
        raise InputError(f"`{name}` must have shape {want}, got {a.shape}")
    if n is not None and a.shape[0] != n:
        raise InputError(f"`{name}` has {a.shape[0]} rows but `time` has {n}")
    flat = a.reshape(a.shape[0], int(np.prod(shape_tail)))  # not -1: no rows is valid (an empty selection)
    bad = ~np.isfinite(flat).all(axis=1)
    if bad.any():
        k = int(np.argmax(bad))
        v = flat[k][~np.isfinite(flat[k])][0]
        raise InputError(f"`{name}` has a NaN or infinite value ({plain_number(v)}) at row {k}")
    return a


def check_lla(name, lla):
    """Refuse a latitude beyond +-90 deg or a longitude beyond a full turn in
    the ``(n, 3)`` or ``(3,)`` array ``lla`` [rad, rad, m]: both are what
    degrees given where radians are expected look like (45 deg read as
    45 rad is 2578 deg)."""
    a = np.atleast_2d(lla)
    for j, what, limit, shown in ((0, "latitude", np.pi / 2, "+-90 deg"), (1, "longitude", 2 * np.pi,
                                                                           "+-360 deg (a full turn)")):
        bad = np.abs(a[:, j]) > limit
        if bad.any():
            k = int(np.argmax(bad))
            row = f" at row {k}" if np.ndim(lla) == 2 else ""
            raise InputError(f"`{name}` holds a {what} of {plain_number(a[k, j])} rad{row} ({a[k, j] / DEG:.6g} deg), "
                             f"beyond {shown}: degrees where radians are expected? (np.radians)")


def check_euler(name, rpy, n=None):
    """Roll, pitch, yaw [rad] as float64, ``(3,)`` (``n=None``) or ``(n, 3)``,
    refused when not finite or when they look like degrees where radians
    are expected: one set of angles (an initial state, a mounting) with an
    angle beyond a full turn (``[0, 0, 90]``); a series with a pitch beyond
    +-90 deg, where every ZYX pitch lies (its roll and yaw may be unwrapped
    over several turns)."""
    a = as_float_array(name, rpy)
    if n is None:
        if a.size != 3 or a.ndim > 2 or (a.ndim == 2 and a.shape[0] != 1):
            raise InputError(f"`{name}` must be roll, pitch, yaw: shape (3,), got {a.shape}")
        a = a.reshape(3)
    else:
        a = _as_array(name, a, (3,), n)
    flat = np.atleast_2d(a)
    if not np.isfinite(flat).all():
        raise InputError(f"`{name}` has a NaN or infinite value ({plain_number(flat[~np.isfinite(flat)][0])})")
    if a.ndim == 1:
        bad, beyond = np.abs(flat) > 2 * np.pi, "a full turn"
    else:
        bad, beyond = np.zeros_like(flat, dtype=bool), "+-90 deg, where every ZYX pitch lies"
        bad[:, 1] = np.abs(flat[:, 1]) > np.pi / 2 + 1e-9
    if bad.any():
        k, j = np.argwhere(bad)[0]
        row = f" at row {k}" if a.ndim == 2 else ""
        raise InputError(f"`{name}`: {('roll', 'pitch', 'yaw')[j]} {plain_number(flat[k, j])} rad{row} "
                         f"({flat[k, j] / DEG:.6g} deg) is beyond {beyond}: degrees where radians are expected? "
                         "(np.radians)")
    return a


def check_quaternions(name, q):
    """``q`` (``(n, 4)`` or ``(4,)``) normalised; refused when a norm is off 1
    by more than 1e-6 (not an attitude quaternion: a zero row, Euler
    angles, another layout)."""
    nq = np.linalg.norm(q, axis=-1)
    bad = np.abs(nq - 1.0) > 1e-6
    if np.any(bad):
        k = int(np.argmax(np.atleast_1d(bad)))
        row = f" at row {k}" if np.ndim(q) == 2 else ""
        raise InputError(f"`{name}` must hold unit quaternions (scalar first), its norm is "
                         f"{plain_number(np.atleast_1d(nq)[k])}{row}")
    return q / (nq[..., None] if np.ndim(q) == 2 else nq)


def _as_vector(name, x, size):
    """One vector of ``size`` numbers (a (1, size) row too), float64."""
    a = as_float_array(name, x)
    if a.size != size or a.ndim > 2 or (a.ndim == 2 and a.shape[0] != 1):
        raise InputError(f"`{name}` must have shape ({size},), got {a.shape}")
    return a.reshape(size)


def check_time_precision(name, t):
    """Refuse a time array ``t`` held in floats narrower than float64
    (float32, float16), naming ``name``: such a time has lost its precision
    before it arrives (a float32 holds 24 bits, so a time of 1e4 s steps by
    0.98 ms and a 100 Hz log at that time reads as alternating 9.8 and
    10.7 ms steps), which no conversion gives back.  Integers, float64 and
    wider pass (they are converted to float64 as :func:`as_float_array`
    converts them); so do lists and tuples of Python numbers."""
    dtype = getattr(t, "dtype", None)
    if dtype is None and isinstance(t, (list, tuple)):  # a list of numpy float32 scalars is float32 too
        try:
            dtype = np.asarray(t).dtype
        except (TypeError, ValueError):  # ragged: check_time says so
            return
    if dtype is None:
        return
    dtype = np.dtype(dtype)
    if dtype.kind == "f" and dtype.itemsize < 8:
        a = np.asarray(t)
        top = float(np.nanmax(np.abs(a[np.isfinite(a)]))) if np.isfinite(a).any() else 0.0
        step = float(np.spacing(dtype.type(top))) if top > 0 else float(np.finfo(dtype).tiny)
        raise InputError(f"`{name}` holds {dtype} values; time must be float64 seconds: a {dtype} time of "
                         f"{top:.6g} s is only resolved to {step:.3g} s, so its steps are wrong before they "
                         "arrive (convert the source data, not this array: np.asarray(t, dtype=np.float64) "
                         "cannot give back the lost digits)")


def check_time(name, t):
    """Validate a strictly increasing, finite time vector; return it as float64."""
    t = as_float_array(name, t)
    if t.ndim != 1:
        raise InputError(f"`{name}` must have shape (n,), got {t.shape}")
    if not np.isfinite(t).all():
        k = int(np.argmax(~np.isfinite(t)))
        raise InputError(f"`{name}` has a NaN or infinite value ({plain_number(t[k])}) at row {k}")
    d = np.diff(t)
    if (d <= 0).any():
        k = int(np.argmax(d <= 0)) + 1
        what = "repeats" if d[k - 1] == 0 else "goes back from"
        raise InputError(
            f"`{name}` must strictly increase: row {k} ({plain_number(t[k])}) {what} row {k - 1} "
            f"({plain_number(t[k - 1])})"
        )
    return t


@dataclass(frozen=True)
class ImuData:
    """Strapdown IMU output as angle and velocity increments.

    Row ``k`` holds the increments over ``(time[k-1], time[k]]``; row 0 holds
    those over the interval that ends at ``time[0]`` (ignored when ``time[0]``
    is the initial epoch of a run).  Irregular steps are allowed.  In an
    increment file row 0 is the initial epoch and holds zeros; a file that
    starts with a real increment is read with ``first_row="increment"``
    (``docs/formats.md``, :func:`inskit.io.csv_formats.first_row_rule`).

    Attributes
    ----------
    time : (n,) ndarray
        Sample times [s], strictly increasing; float64 (integers are
        converted, float32 is refused: :func:`check_time_precision`).
    dtheta_b : (n, 3) ndarray
        Angle increments of the body rate ``omega_ib_b`` [rad].
    dv_b : (n, 3) ndarray
        Velocity increments of the specific force ``f_b`` [m/s].
    """

    time: np.ndarray
    dtheta_b: np.ndarray
    dv_b: np.ndarray

    def __post_init__(self):
        check_time_precision("time", self.time)
        t = check_time("time", self.time)
        object.__setattr__(self, "time", t)
        object.__setattr__(self, "dtheta_b", _as_array("dtheta_b", self.dtheta_b, (3,), len(t)))
        object.__setattr__(self, "dv_b", _as_array("dv_b", self.dv_b, (3,), len(t)))

    def __len__(self):
        return len(self.time)

    @classmethod
    def from_rates(cls, time, gyro_b, accel_b, *, sampled="instant"):
        """Build increments from sampled rates.

        Parameters
        ----------
        time : (n,) array_like
            Sample times [s].
        gyro_b : (n, 3) array_like
            Angular rate ``omega_ib_b`` [rad/s].
        accel_b : (n, 3) array_like
            Specific force ``f_b`` [m/s^2].
        sampled : {"instant", "average"}
            ``"instant"``: rates are point samples at ``time`` and are
            integrated with the trapezoid rule (second order);
            ``"average"``: each sample is the mean over the preceding interval
            (what most MEMS output after their anti-alias filter).
        """
        check_time_precision("time", time)
        t = check_time("time", time)
        w = _as_array("gyro_b", gyro_b, (3,), len(t))
        f = _as_array("accel_b", accel_b, (3,), len(t))
        if sampled not in ("instant", "average"):
            raise InputError(f"`sampled` must be 'instant' or 'average', got {sampled!r}")
        if len(t) == 0:  # no samples: no increments
            return cls(t, w, f)
        dt = np.empty_like(t)
        dt[1:] = np.diff(t)
        dt[0] = dt[1] if len(t) > 1 else 0.0
        if sampled == "instant":
            wm = np.vstack([w[:1], 0.5 * (w[1:] + w[:-1])])
            fm = np.vstack([f[:1], 0.5 * (f[1:] + f[:-1])])
        else:  # "average"
            wm, fm = w, f
        return cls(t, wm * dt[:, None], fm * dt[:, None])

    def rates(self):
        """Mean rates over each interval: ``(gyro_b, accel_b)`` [rad/s, m/s^2]."""
        dt = np.empty_like(self.time)
        dt[1:] = np.diff(self.time)
        if len(dt):  # no samples: no rates
            dt[0] = dt[1] if len(dt) > 1 else 1.0
        return self.dtheta_b / dt[:, None], self.dv_b / dt[:, None]

    def slice(self, start, stop=None):
        """Rows ``start:stop`` as a new ImuData."""
        s = slice(start, stop)
        return ImuData(self.time[s], self.dtheta_b[s], self.dv_b[s])

    def to_dataframe(self, *, rates=False):
        """The samples as a pandas DataFrame, columns named as the IMU file
        format names them (``docs/formats.md``).

        Parameters
        ----------
        rates : bool
            False: ``time_s, dtheta_{x,y,z}_rad, dv_{x,y,z}_m_s`` (the
            increments as held); True: ``time_s, gyro_{x,y,z}_rad_s,
            accel_{x,y,z}_m_s2``, the mean rates over each interval
            (:meth:`rates`).
        """
        import pandas as pd

        if rates:
            a, b = self.rates()
            names = ("gyro_{}_rad_s", "accel_{}_m_s2")
        else:
            a, b = self.dtheta_b, self.dv_b
            names = ("dtheta_{}_rad", "dv_{}_m_s")
        cols = {"time_s": self.time}
        for name, x in zip(names, (a, b)):
            for j, axis in enumerate("xyz"):
                cols[name.format(axis)] = x[:, j]
        return pd.DataFrame(cols)


@dataclass(frozen=True)
class NavState:
    """Navigation state at one epoch, in NED terms.

    Attributes
    ----------
    time : float
        [s].
    lla : (3,) ndarray
        Latitude, longitude [rad], ellipsoidal height [m].
    v_n : (3,) ndarray
        Earth-relative velocity resolved in NED [m/s].
    q_nb : (4,) ndarray
        Attitude quaternion, body to NED, scalar first.
    """

    time: float
    lla: np.ndarray
    v_n: np.ndarray
    q_nb: np.ndarray

    def __post_init__(self):
        lla, v, q = (_as_vector(name, x, size) for name, x, size in
                     (("lla", self.lla, 3), ("v_n", self.v_n, 3), ("q_nb", self.q_nb, 4)))
        check_time_precision("time", self.time)
        time = as_float_array("time", self.time)
        if time.ndim != 0 and time.shape != (1,):
            raise InputError(f"`time` must be one number [s], got shape {time.shape}")
        time = float(time.reshape(()))
        if not np.isfinite(time):
            raise InputError(f"`time` of the state is {plain_number(time)}; expected a finite number [s]")
        for name, x in (("lla", lla), ("v_n", v), ("q_nb", q)):
            if not np.isfinite(x).all():
                raise InputError(f"`{name}` of the state has a NaN or infinite value ({plain_number(x)})")
        check_lla("lla", lla)
        q = check_quaternions("q_nb", q)
        object.__setattr__(self, "time", time)
        object.__setattr__(self, "lla", lla)
        object.__setattr__(self, "v_n", v)
        object.__setattr__(self, "q_nb", q)

    @classmethod
    def from_euler(cls, time, lla, v_n, rpy):
        """State from roll, pitch, yaw [rad] (ZYX) instead of a quaternion."""
        return cls(time, lla, v_n, rot.quat_from_euler(check_euler("rpy", rpy)))

    @property
    def C_nb(self):
        return rot.dcm_from_quat(self.q_nb)

    @property
    def euler(self):
        """``[roll, pitch, yaw]`` [rad]."""
        return rot.euler_from_quat(self.q_nb)


def _query_times(t):
    """Times asked of a solution: float64 ``(m,)`` (one number: ``(1,)``), finite."""
    t = as_float_array("t", t)
    if t.ndim != 1:
        raise InputError(f"`t` must be one time or shape (m,), got {t.shape}")
    if not np.isfinite(t).all():
        k = int(np.argmax(~np.isfinite(t)))
        raise InputError(f"`t` has a NaN or infinite value ({plain_number(t[k])}) at row {k}")
    return t


#: the navigation columns of a solution, in order, as :meth:`NavSolution.columns`, ``to_dataframe`` and the
#: solution files name them (:mod:`inskit.io` reads and writes these names); no ``extra`` column may take one
NAVIGATION_COLUMNS = ("time_s", "lat_deg", "lon_deg", "height_m", "vn_m_s", "ve_m_s", "vd_m_s",
                      "roll_deg", "pitch_deg", "yaw_deg")


def _column_names(name, a) -> list:
    """The column names extra ``a`` named ``name`` takes in a table: its own
    name (one value per row), ``name_0 .. name_{k-1}`` (``(n, k)``)."""
    return [name] if a.ndim == 1 else [f"{name}_{j}" for j in range(a.shape[1])]


def _extra_columns(extra, n) -> dict:
    """``extra`` as a new dict of arrays of ``n`` rows each (None: no column).

    A name that is a navigation column's (:data:`NAVIGATION_COLUMNS`), or
    that another extra column's table names would take (``b`` of shape
    ``(n, 2)`` is written as ``b_0, b_1``, so no ``b_1`` beside it), is
    refused: in a table or a file one of them would overwrite the other.
    """
    if extra is None:
        return {}
    if not isinstance(extra, dict):
        raise InputError(f"`extra` must be a dict of column name -> array of {n} rows, got {type(extra).__name__}")
    out = {}
    for k, v in extra.items():
        if not isinstance(k, str):
            raise InputError(f"`extra` column names must be text (units in the name: 'sigma_n_m'), got {k!r}")
        a = np.asarray(v)
        if a.ndim == 0:
            raise InputError(f"extra column `{k}` is one value ({v!r}); expected an array of {n} rows")
        if len(a) != n:
            raise InputError(f"extra column `{k}` has {len(a)} rows, expected {n}")
        out[k] = a
    owner = dict.fromkeys(NAVIGATION_COLUMNS, None)  # table name -> the extra column that takes it (None: navigation)
    for k, a in out.items():
        for c in _column_names(k, a):
            if c in owner:
                if owner[c] is None:
                    raise InputError(f"extra column `{k}` has the name of a navigation column "
                                     f"({', '.join(NAVIGATION_COLUMNS)}), which tables and solution files hold "
                                     "already: one would overwrite the other; give it another name (units in the "
                                     "name: 'truth_height_m')")
                raise InputError(f"extra columns `{owner[c]}` and `{k}` would both be the column {c!r} of a table "
                                 f"or a file (an (n, k) extra `b` is written as b_0 .. b_k-1): one would overwrite "
                                 "the other; rename one of them")
            owner[c] = k
    return out


@dataclass(frozen=True)
class NavSolution:
    """A navigation solution (or a truth trajectory) over time, in NED terms.

    Attributes
    ----------
    time : (n,) ndarray
        [s], strictly increasing; float64 (:func:`check_time_precision`).
    lla : (n, 3) ndarray
        Latitude, longitude [rad], height [m].
    v_n : (n, 3) ndarray
        NED velocity [m/s].
    q_nb : (n, 4) ndarray
        Attitude quaternions, body to NED.
    extra : dict of str -> ndarray
        Further per-epoch columns (sigmas, wander angle, biases ...), each with
        ``n`` rows; names carry their unit (``sigma_n_m``, ``alpha_rad``).
        A name of :data:`NAVIGATION_COLUMNS`, or one another extra column's
        table names take (``b_1`` beside a ``b`` of shape ``(n, 2)``), is
        refused: in a table or a file one would overwrite the other.
    """

    time: np.ndarray
    lla: np.ndarray
    v_n: np.ndarray
    q_nb: np.ndarray
    extra: dict = field(default_factory=dict)

    def __post_init__(self):
        check_time_precision("time", self.time)
        t = check_time("time", self.time)
        lla = _as_array("lla", self.lla, (3,), len(t))
        check_lla("lla", lla)
        object.__setattr__(self, "time", t)
        object.__setattr__(self, "lla", lla)
        object.__setattr__(self, "v_n", _as_array("v_n", self.v_n, (3,), len(t)))
        object.__setattr__(self, "q_nb", check_quaternions("q_nb", _as_array("q_nb", self.q_nb, (4,), len(t))))
        object.__setattr__(self, "extra", _extra_columns(self.extra, len(t)))

    def __len__(self):
        return len(self.time)

    @classmethod
    def _trusted(cls, time, lla, v_n, q_nb, extra=None):
        """Build without validation, for arrays a compiled kernel just produced
        from validated input (checking 10^6 rows again would cost more than the
        integration).  Not for user data."""
        obj = object.__new__(cls)
        for k, v in (("time", time), ("lla", lla), ("v_n", v_n), ("q_nb", q_nb), ("extra", extra or {})):
            object.__setattr__(obj, k, v)
        return obj

    @classmethod
    def from_euler(cls, time, lla, v_n, rpy, extra=None):
        """Solution from ``(n, 3)`` roll, pitch, yaw [rad] (ZYX) instead of quaternions."""
        return cls(time, lla, v_n, rot.quat_from_euler(check_euler("rpy", rpy, len(np.atleast_1d(time)))),
                   extra or {})

    @property
    def euler(self):
        """``(n, 3)`` roll, pitch, yaw [rad]."""
        return rot.euler_from_quat(self.q_nb)

    @property
    def C_nb(self):
        return rot.dcm_from_quat(self.q_nb)

    def state(self, k):
        """The NavState at row ``k``."""
        return NavState(self.time[k], self.lla[k], self.v_n[k], self.q_nb[k])

    def columns(self, rows=None) -> dict:
        """The solution as named columns, units in the names, as the solution
        files hold them (``docs/formats.md``): ``time_s, lat_deg, lon_deg,
        height_m, vn_m_s, ve_m_s, vd_m_s, roll_deg, pitch_deg, yaw_deg``
        (longitude wrapped into (-180, 180], ZYX Euler angles), then every
        ``extra`` column under its own name (an (n, k) one as ``name_0`` ..
        ``name_{k-1}``).

        Parameters
        ----------
        rows : (m,) int array, optional
            Only these rows.

        Returns
        -------
        dict of str -> (n,) or (m,) ndarray
        """
        sl = slice(None) if rows is None else np.asarray(rows)
        rpy = rot.euler_from_quat(self.q_nb[sl]) / DEG
        lla, v = self.lla[sl], self.v_n[sl]
        nav = (self.time[sl], lla[:, 0] / DEG, -((-lla[:, 1] + np.pi) % (2.0 * np.pi) - np.pi) / DEG, lla[:, 2],
               v[:, 0], v[:, 1], v[:, 2], rpy[:, 0], rpy[:, 1], rpy[:, 2])
        cols = dict(zip(NAVIGATION_COLUMNS, nav))
        for k, a in self.extra.items():
            a = np.asarray(a)[sl]
            names = _column_names(k, a)
            clash = [c for c in names if c in cols]
            if clash:  # a solution built by _trusted (no checks) with such a name: refused, not written over
                raise InputError(f"extra column `{k}` would overwrite the column {clash[0]!r} of the solution "
                                 f"({', '.join(NAVIGATION_COLUMNS)} and the other extra columns); rename it")
            if a.ndim == 1:
                cols[k] = a
            else:
                for j, c in enumerate(names):
                    cols[c] = a[:, j]
        return cols

    def to_dataframe(self):
        """The solution as a pandas DataFrame with the columns of
        :meth:`columns` (the names of the solution CSV and Parquet files).

        ``df.set_index("time_s")`` gives a time index; ``extra`` columns
        (sigmas, estimates) follow the navigation ones.
        """
        import pandas as pd

        return pd.DataFrame(self.columns())

    def slice(self, start, stop=None):
        s = slice(start, stop)
        return NavSolution(self.time[s], self.lla[s], self.v_n[s], self.q_nb[s],
                           {k: v[s] for k, v in self.extra.items()})

    @staticmethod
    def concat(parts):
        """Join solutions that follow each other in time.

        Every part must hold the same ``extra`` columns; they keep the first
        part's order.  Parts of no rows are skipped; a list of only such parts
        gives the first of them.
        """
        given = list(parts)
        if not given:
            raise InputError("NavSolution.concat: no solution to join (an empty list)")
        parts = [p for p in given if len(p)]
        if not parts:
            return given[0]
        if len(parts) == 1:
            return parts[0]
        keys = list(parts[0].extra)  # a list, not a set: the columns keep their order from run to run
        for i, p in enumerate(parts[1:], 1):
            if set(p.extra) != set(keys):
                diff = sorted(set(keys) ^ set(p.extra))
                raise InputError(f"NavSolution.concat: the solutions hold different extra columns: "
                                 f"{', '.join(diff)} in one of solution 0 and solution {i} only")
        return NavSolution(
            np.concatenate([p.time for p in parts]),
            np.concatenate([p.lla for p in parts]),
            np.concatenate([p.v_n for p in parts]),
            np.concatenate([p.q_nb for p in parts]),
            {k: np.concatenate([p.extra[k] for p in parts]) for k in keys},
        )

    def sample(self, t):
        """``(lla, v_n, q_nb)`` at any times ``t`` inside the span, in any order
        (linear in position and velocity, normalised linear quaternion blend;
        the longitude along the shorter way round, so that two rows either
        side of the antimeridian, +179.99 and -179.99 deg, give a point
        between them and not one on the far side of the Earth).

        Parameters
        ----------
        t : float or (m,) array_like
            [s]; one time gives arrays of one row.

        Returns
        -------
        lla : (m, 3) ndarray
        v_n : (m, 3) ndarray
        q_nb : (m, 4) ndarray
        """
        t = _query_times(t)
        if len(t) and (t.min() < self.time[0] or t.max() > self.time[-1]):
            raise InputError(
                f"requested times {t.min():.3f}..{t.max():.3f} s fall outside the solution span "
                f"{self.time[0]:.3f}..{self.time[-1]:.3f} s"
            )
        i, j, w = self._bracket(t)
        q = rot.quat_blend(self.q_nb[i], self.q_nb[j], w)
        lla = self.lla[i] * (1 - w[:, None]) + self.lla[j] * w[:, None]
        dlon = self.lla[j, 1] - self.lla[i, 1]
        across = np.abs(dlon) > np.pi  # the rows straddle the antimeridian (or a +-pi wrap)
        if across.any():
            d = dlon[across] - np.copysign(2.0 * np.pi, dlon[across])
            lla[across, 1] = rot.wrap_angle(self.lla[i[across], 1] + d * w[across])
        w = w[:, None]
        return lla, self.v_n[i] * (1 - w) + self.v_n[j] * w, q

    def _bracket(self, t):
        """The rows ``i`` and ``j`` on either side of each of the times ``t``
        (inside the span) and the weight ``w`` of row ``j``.  A solution of
        one row (a file holding only the initial state) is its own value at
        its one time: ``i = j = 0``, ``w = 0`` (the span check leaves no
        other time), not the NaN of a zero-length interval."""
        if len(self.time) == 1:
            z = np.zeros(len(t), dtype=int)
            return z, z, np.zeros(len(t))
        i = np.clip(np.searchsorted(self.time, t, side="right") - 1, 0, len(self.time) - 2)
        return i, i + 1, (t - self.time[i]) / (self.time[i + 1] - self.time[i])

    def interpolate(self, t):
        """Solution at strictly increasing times ``t`` (float or ``(m,)``)
        inside the span (see :meth:`sample`)."""
        t = check_time("t", _query_times(t))
        lla, v, q = self.sample(t)
        i, j, w = self._bracket(t)
        extra = {k: (x[i] * (1 - w) + x[j] * w) if x.ndim == 1 else (x[i] * (1 - w)[:, None] + x[j] * w[:, None])
                 for k, x in self.extra.items()}
        return NavSolution(t, lla, v, q, extra)


def fix_sigmas(sigma_ned, sigma_floor_m=0.0, sigma_scale_ned=(1.0, 1.0, 1.0)):
    """Fixes' north, east, down position sigmas [m] as a filter takes them:
    the file's (``(n, 3)`` or ``(3,)``), no smaller than ``sigma_floor_m``,
    times the per-axis ``sigma_scale_ned`` (``[gnss] sigma_floor_m``,
    ``sigma_scale_ned``).  The one rule for the position updates
    (:class:`inskit.integration.GnssPosition`) and for a start-up whose
    position is a fix's (:func:`inskit.alignment.coarse.fix_sigma_m`)."""
    return np.maximum(sigma_ned, sigma_floor_m) * np.asarray(sigma_scale_ned, dtype=float)


@dataclass(frozen=True)
class GnssData:
    """GNSS position (and optionally velocity) fixes with their sigmas.

    Attributes
    ----------
    time : (n,) ndarray
        [s], on the same time base as the IMU, strictly increasing; float64
        (:func:`check_time_precision`).
    lla : (n, 3) ndarray
        Antenna latitude, longitude [rad], height [m].
    sigma_ned : (n, 3) ndarray
        1-sigma position errors north, east, down [m], all > 0.
    v_n : (n, 3) ndarray or None
        NED velocity [m/s].
    sigma_v_ned : (n, 3) ndarray or None
        1-sigma velocity errors [m/s], all > 0.
    """

    time: np.ndarray
    lla: np.ndarray
    sigma_ned: np.ndarray
    v_n: np.ndarray | None = None
    sigma_v_ned: np.ndarray | None = None

    def __post_init__(self):
        check_time_precision("time", self.time)
        t = check_time("time", self.time)
        lla = _as_array("lla", self.lla, (3,), len(t))
        check_lla("lla", lla)
        object.__setattr__(self, "time", t)
        object.__setattr__(self, "lla", lla)
        s = _as_array("sigma_ned", self.sigma_ned, (3,), len(t))
        if (s <= 0).any():
            raise InputError(f"`sigma_ned` must be > 0, row {int(np.argmax((s <= 0).any(axis=1)))} has {s[(s <= 0).any(axis=1)][0]}")
        object.__setattr__(self, "sigma_ned", s)
        if (self.v_n is None) != (self.sigma_v_ned is None):
            raise InputError("GNSS velocity and its sigmas must be given together")
        if self.v_n is not None:
            object.__setattr__(self, "v_n", _as_array("v_n", self.v_n, (3,), len(t)))
            sv = _as_array("sigma_v_ned", self.sigma_v_ned, (3,), len(t))
            if (sv <= 0).any():
                raise InputError("`sigma_v_ned` must be > 0")
            object.__setattr__(self, "sigma_v_ned", sv)

    def __len__(self):
        return len(self.time)

    @property
    def has_velocity(self):
        return self.v_n is not None

    def to_dataframe(self):
        """The fixes as a pandas DataFrame, columns named as the GNSS file
        format names them: ``time_s, lat_deg, lon_deg, height_m, sigma_n_m,
        sigma_e_m, sigma_d_m`` and, with velocity, ``vn_m_s, ve_m_s, vd_m_s,
        sigma_vn_m_s, sigma_ve_m_s, sigma_vd_m_s`` (longitude wrapped into
        (-180, 180])."""
        import pandas as pd

        cols = {"time_s": self.time, "lat_deg": self.lla[:, 0] / DEG,
                "lon_deg": -((-self.lla[:, 1] + np.pi) % (2.0 * np.pi) - np.pi) / DEG,
                "height_m": self.lla[:, 2]}
        for j, a in enumerate("ned"):
            cols[f"sigma_{a}_m"] = self.sigma_ned[:, j]
        if self.has_velocity:
            for j, a in enumerate("ned"):
                cols[f"v{a}_m_s"] = self.v_n[:, j]
            for j, a in enumerate("ned"):
                cols[f"sigma_v{a}_m_s"] = self.sigma_v_ned[:, j]
        return pd.DataFrame(cols)

    def select(self, mask):
        """Fixes where ``mask`` is true.

        Parameters
        ----------
        mask : (n,) bool array_like
            One flag per fix (not row numbers: ``g.select(np.isin(np.arange(len(g)), rows))``).
        """
        m = np.asarray(mask)
        if m.dtype.kind != "b":
            raise InputError(f"`mask` must hold booleans, one per fix, got {m.dtype} values (row numbers? "
                             "a mask is one True or False per fix)")
        if m.shape != (len(self),):
            raise InputError(f"`mask` must have shape ({len(self)},), one flag per fix, got {m.shape}")
        return GnssData(self.time[m], self.lla[m], self.sigma_ned[m],
                        None if self.v_n is None else self.v_n[m],
                        None if self.sigma_v_ned is None else self.sigma_v_ned[m])
