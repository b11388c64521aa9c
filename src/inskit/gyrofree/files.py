"""File formats of the gyro-free INS (documented in ``docs/formats.md``).

* Layout CSV (:func:`read_layout`, :func:`write_layout`): one accelerometer
  per row, ``name, x_m, y_m, z_m, axis_x, axis_y, axis_z`` (position from the
  reference point and unit sensing axis, body axes forward-right-down).
  Lines starting with ``#`` and blank lines are ignored.
* Array CSV (:func:`read_array`, :func:`write_array`): the raw outputs,
  ``time_s`` then one column per accelerometer, ``<name>_m_s2`` (or
  ``<name>_g``).
* Inertial solution CSV (:func:`write_inertial`, :func:`read_inertial`):
  ``time_s, x_m, y_m, z_m, vx_m_s, vy_m_s, vz_m_s, q0, q1, q2, q3`` (inertial
  frame, quaternion body to inertial, scalar first), plus optional columns.
* Rate estimates (:func:`write_rates`): the IMU CSV of :mod:`inskit.io`
  (``gyro_*_rad_s``, ``accel_*_m_s2``), so ``inskit mechanize`` reads them.

Every reader validates what it reads and raises
:class:`~inskit.errors.InputError` naming the file, the line (the header is
line 1, as an editor shows it) and the field.
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pandas as pd

from ..errors import InputError
from ..files import write_csv, write_text
from ..io.csv_formats import at_row, check_time_column, numeric_columns, read_table, require_columns, check_writable
from ..units import G0
from .layout import ArrayLayout
from .model import ArrayData
from .motion import InertialSolution
from .solvers import ArraySolution

LAYOUT_COLUMNS = ("name", "x_m", "y_m", "z_m", "axis_x", "axis_y", "axis_z")
ARRAY_UNITS = {"m_s2": 1.0, "g": G0}
INERTIAL_COLUMNS = ("time_s", "x_m", "y_m", "z_m", "vx_m_s", "vy_m_s", "vz_m_s", "q0", "q1", "q2", "q3")
#: Largest plausible lever arm [m]: larger values usually mean millimetres.
MAX_LEVER_ARM_M = 100.0


def read_layout(path) -> ArrayLayout:
    """Read and validate a layout file (see module docstring).

    Raises
    ------
    InputError
        Naming the file, line and field: a missing column, an empty or
        non-numeric field, a repeated name, a sensing axis that is not a unit
        vector (norm off 1 by more than 1e-3), an implausible position.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: no such layout file")
    try:
        text = path.read_text()
    except UnicodeDecodeError:
        raise InputError(f"{path}: not a text file") from None
    rows = [(i + 1, r) for i, r in enumerate(csv.reader(text.splitlines()))
            if r and "".join(r).strip() and not r[0].lstrip().startswith("#")]
    if not rows:
        raise InputError(f"{path}: the layout file is empty; expected a header {','.join(LAYOUT_COLUMNS)}")
    hline, header = rows[0]
    header = [h.strip() for h in header]
    missing = [c for c in LAYOUT_COLUMNS if c not in header]
    if missing:
        raise InputError(f"{path}: line {hline}: missing column(s) {', '.join(missing)}; expected "
                         f"{','.join(LAYOUT_COLUMNS)}, found {','.join(header)}")
    unknown = [c for c in header if c not in LAYOUT_COLUMNS]
    if unknown:
        raise InputError(f"{path}: line {hline}: unknown column(s) {', '.join(unknown)}; expected "
                         f"{','.join(LAYOUT_COLUMNS)}")
    col = {c: header.index(c) for c in LAYOUT_COLUMNS}
    names, pos, ax, seen = [], [], [], {}
    for line, r in rows[1:]:
        if len(r) != len(header):
            raise InputError(f"{path}: line {line}: {len(r)} fields, expected {len(header)} ({','.join(header)})")
        name = r[col["name"]].strip()
        if not name:
            raise InputError(f"{path}: line {line}: field 'name' is empty")
        try:
            ArrayLayout((name,), [[0, 0, 0]], [[1, 0, 0]])
        except InputError as exc:
            raise InputError(f"{path}: line {line}: field 'name': {exc}") from None
        if name in seen:
            raise InputError(f"{path}: line {line}: accelerometer name {name!r} repeats line {seen[name]}")
        seen[name] = line
        vals = []
        for c in LAYOUT_COLUMNS[1:]:
            raw = r[col[c]].strip()
            try:
                v = float(raw)
            except ValueError:
                v = np.nan
            if not np.isfinite(v):
                what = "is empty" if raw == "" else f"has {raw!r}"
                raise InputError(f"{path}: line {line}: field '{c}' {what}; expected a finite number")
            vals.append(v)
        p, e = np.array(vals[:3]), np.array(vals[3:])
        if np.linalg.norm(p) > MAX_LEVER_ARM_M:
            raise InputError(f"{path}: line {line}: fields x_m, y_m, z_m put {name} {np.linalg.norm(p):.4g} m from "
                             f"the reference point (more than {MAX_LEVER_ARM_M:g} m: metres are expected)")
        ne = np.linalg.norm(e)
        if abs(ne - 1.0) > 1e-3:
            raise InputError(f"{path}: line {line}: fields axis_x, axis_y, axis_z of {name} have norm {ne:.6g}; "
                             "the sensing axis must be a unit vector (norm within 1e-3 of 1)")
        names.append(name)
        pos.append(p)
        ax.append(e / ne)
    if not names:
        raise InputError(f"{path}: the layout file has a header but no accelerometers")
    return ArrayLayout(tuple(names), np.array(pos), np.array(ax), path.name, None)


def write_layout(path, layout: ArrayLayout, *, overwrite=False):
    """Write a layout file that :func:`read_layout` reads back exactly."""
    path = check_writable(path, overwrite)
    lines = [f"# accelerometer layout '{layout.label}'" + (f", d = {layout.d:g} m" if layout.d else ""),
             ",".join(LAYOUT_COLUMNS)]
    for n, p, e in zip(layout.names, layout.positions_b, layout.axes_b):
        lines.append(",".join([n] + [f"{x:.17g}" for x in (*p, *e)]))
    return write_text(path, "\n".join(lines) + "\n")


def read_array(path, layout: ArrayLayout | None = None) -> ArrayData:
    """Read raw array outputs.

    Parameters
    ----------
    path : str or Path
    layout : ArrayLayout, optional
        When given, the file must hold exactly one column per accelerometer
        of the layout (any order; returned in the layout's order).

    Returns
    -------
    ArrayData
    """
    path, df = read_table(path)
    require_columns(path, df, ["time_s"])
    t = numeric_columns(path, df, ["time_s"])[:, 0]
    check_time_column(path, t)
    cols = {}
    for c in df.columns:
        if c == "time_s":
            continue
        for u in ARRAY_UNITS:
            if c.endswith("_" + u) and len(c) > len(u) + 1:
                name = c[: -len(u) - 1]
                if name in cols:
                    raise InputError(f"{path}: accelerometer {name} has two columns ({cols[name][0]} and {c})")
                cols[name] = (c, u)
                break
        else:
            raise InputError(f"{path}: column '{c}' is not an accelerometer output: expected <name>_m_s2 or "
                             "<name>_g")
    if not cols:
        raise InputError(f"{path}: no accelerometer columns (<name>_m_s2 or <name>_g) after time_s")
    if layout is not None:
        missing = [n for n in layout.names if n not in cols]
        extra = [n for n in cols if n not in layout.names]
        if missing or extra:
            parts = []
            if missing:
                parts.append(f"no column for {', '.join(missing)}")
            if extra:
                parts.append(f"columns for {', '.join(extra)} which are not in the layout")
            raise InputError(f"{path}: does not match layout '{layout.label}': {'; '.join(parts)} (the layout has "
                             f"{', '.join(layout.names)})")
        names = list(layout.names)
    else:
        names = list(cols)
    y = np.column_stack([numeric_columns(path, df, [cols[n][0]])[:, 0] * ARRAY_UNITS[cols[n][1]] for n in names])
    return ArrayData(t, y, tuple(names))


def write_array(path, data: ArrayData, *, overwrite=False):
    """Write raw outputs (``time_s``, ``<name>_m_s2``), full precision."""
    path = check_writable(path, overwrite)
    cols = {"time_s": data.time}
    for j, n in enumerate(data.names):
        cols[f"{n}_m_s2"] = data.outputs[:, j]
    return write_csv(path, cols, "%.17g")


def write_inertial(path, sol: InertialSolution, *, extra=None, overwrite=False):
    """Write an inertial-frame solution or truth (``extra``: name -> (n,) columns)."""
    path = check_writable(path, overwrite)
    cols = {"time_s": sol.time}
    for j, c in enumerate(INERTIAL_COLUMNS[1:4]):
        cols[c] = sol.r_i[:, j]
    for j, c in enumerate(INERTIAL_COLUMNS[4:7]):
        cols[c] = sol.v_i[:, j]
    for j, c in enumerate(INERTIAL_COLUMNS[7:]):
        cols[c] = sol.q_ib[:, j]
    for k, v in (extra or {}).items():
        cols[k] = np.asarray(v)
    df = pd.DataFrame(cols)
    if df.isna().any().any():
        raise InputError(f"{path}: refusing to write a NaN (column '{df.columns[df.isna().any()][0]}')")
    return write_csv(path, df, "%.15g")


def read_inertial(path):
    """Read an inertial solution; returns ``(InertialSolution, extra)``."""
    path, df = read_table(path)
    require_columns(path, df, list(INERTIAL_COLUMNS))
    a = numeric_columns(path, df, list(INERTIAL_COLUMNS))
    check_time_column(path, a[:, 0])
    nq = np.linalg.norm(a[:, 7:], axis=1)
    bad = np.abs(nq - 1) > 1e-6
    if bad.any():
        i = int(np.argmax(bad))
        raise InputError(f"{path}: {at_row(path, i)}: q0..q3 have norm {nq[i]:.9g}; expected a unit quaternion")
    extra = {c: numeric_columns(path, df, [c])[:, 0] for c in df.columns if c not in INERTIAL_COLUMNS}
    return InertialSolution(a[:, 0], a[:, 1:4], a[:, 4:7], a[:, 7:] / nq[:, None]), extra


def write_rates(path, sol: ArraySolution, *, overwrite=False):
    """Write the estimated rate and specific force in the IMU CSV format
    (``gyro_{x,y,z}_rad_s``, ``accel_{x,y,z}_m_s2``).  Spinning bodies exceed
    the IMU reader's unit-plausibility limits: read them back with
    ``check_units=False`` (``--no-unit-check``)."""
    if not sol.signed:
        raise InputError("the solution holds rate magnitudes only; they are not IMU rates")
    path = check_writable(path, overwrite)
    cols = {"time_s": sol.time}
    for j, a in enumerate("xyz"):
        cols[f"gyro_{a}_rad_s"] = sol.omega_ib_b[:, j]
    for j, a in enumerate("xyz"):
        cols[f"accel_{a}_m_s2"] = sol.f_b[:, j]
    df = pd.DataFrame(cols)
    if df.isna().any().any():
        raise InputError(f"{path}: refusing to write a NaN (column '{df.columns[df.isna().any()][0]}')")
    return write_csv(path, df, "%.17g")


__all__ = ["LAYOUT_COLUMNS", "read_array", "read_inertial", "read_layout", "write_array", "write_inertial",
           "write_layout", "write_rates"]
