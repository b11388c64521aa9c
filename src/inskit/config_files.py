"""Reading TOML files and turning pydantic validation errors into one line.

Shared by the ``navigate`` configuration and the simulation scenarios.
"""

from __future__ import annotations

import math
import tomllib
import typing
from pathlib import Path

from pydantic import ValidationError

from .errors import ConfigError, InputError


def read_toml(path, kind="config"):
    """The parsed TOML of ``path``; a missing file or bad syntax is a ConfigError."""
    path = Path(path)
    if path.is_dir():  # inskit.navigate("examples"): a folder, not a missing file
        tomls = sorted(p.name for p in path.glob("*.toml"))[:5]
        raise ConfigError(f"{path}: is a folder; expected a {kind} file (a .toml file"
                          + (f", e.g. {', '.join(tomls)} in it)" if tomls else ")"))
    if not path.is_file():
        raise ConfigError(f"{path}: no such {kind} file")
    raw = path.read_bytes()
    try:
        text = raw.decode("utf-8-sig")  # TOML is UTF-8; a byte-order mark (Windows editors) is dropped
    except UnicodeDecodeError as exc:
        line = raw[: exc.start].count(b"\n") + 1
        raise ConfigError(f"{path}: line {line}: byte 0x{raw[exc.start]:02x} is not UTF-8; a {kind} file is UTF-8 "
                          "text (save it as UTF-8)") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{path}: not valid TOML ({exc})") from None
    _refuse_non_finite(data, path, "")
    other = toml_kind(data)
    if other is not None and kind in _KINDS and other != kind:  # another command's file: say so, not 'field required'
        what, command = _KINDS[other]
        raise ConfigError(f"{path}: this is {what}, which `{command}` takes, not {_KINDS[kind][0]} "
                          "(docs/config.md describes each)")
    return data


#: the TOML files inskit reads: what each is, and the command that takes it
_KINDS = {"config": ("a navigate configuration", "inskit navigate"),
          "scenario": ("a scenario file", "inskit simulate"),
          "study": ("a study file", "inskit study")}


def toml_kind(data) -> str | None:
    """Which of inskit's TOML files ``data`` (parsed) is, by the keys only
    that kind has: ``"study"`` (top-level ``scenario`` and ``kind`` or
    ``runs``), ``"scenario"`` (``[[segment]]`` tables, or a ``[start]``
    table), ``"config"`` (an ``[imu]`` table naming a ``file``, or a
    ``[gnss]`` table naming ``file`` or ``obs``); None when it is none of
    them or looks like more than one."""
    if not isinstance(data, dict):
        return None
    imu, gnss = data.get("imu"), data.get("gnss")
    found = {k for k, hit in (
        ("study", isinstance(data.get("scenario"), str) and ("kind" in data or "runs" in data)),
        ("scenario", isinstance(data.get("segment"), list) or isinstance(data.get("start"), dict)),
        ("config", (isinstance(imu, dict) and "file" in imu)
         or (isinstance(gnss, dict) and ("file" in gnss or "obs" in gnss))),
    ) if hit}
    return found.pop() if len(found) == 1 else None


def _refuse_non_finite(node, path, where):
    """TOML allows nan and inf; no setting of ours means either."""
    if isinstance(node, dict):
        for k, v in node.items():
            _refuse_non_finite(v, path, f"{where}.{k}" if where else str(k))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            _refuse_non_finite(v, path, f"{where}[{i}]")
    elif isinstance(node, float) and not math.isfinite(node):
        raise ConfigError(f"{path}: field '{where}': {node} is not a finite number")


#: the largest magnitude a float setting may have: none of ours means more, and a square of more overflows
#: (gyro_arw_deg_sqrt_h = 1e300 was 'internal error: OverflowError', exit 3)
MAX_SETTING = 1e12


def check_magnitude(v):
    """A pydantic after-validator for every field (``field_validator("*")``):
    a float (or one inside a tuple or list) beyond :data:`MAX_SETTING` is
    refused, naming the value."""
    items = v if isinstance(v, (tuple, list)) else (v,)
    for x in items:
        if isinstance(x, float) and abs(x) > MAX_SETTING:
            raise ValueError(f"{x:g} is beyond +-{MAX_SETTING:g}: no setting means a value that large (a unit or "
                             "an exponent slipped?)")
    return v

def height_problem(v) -> str | None:
    """What is wrong with a height a user gave [m], in words (None:
    nothing): beyond +-:data:`inskit.units.MAX_HEIGHT_M` of the ellipsoid,
    the limit of the height log's readings too.  Not a finite number: None
    (the caller's own checks say so)."""
    from .units import MAX_HEIGHT_M

    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or abs(v) <= MAX_HEIGHT_M:
        return None
    return (f"{v:g} m is beyond +-{MAX_HEIGHT_M / 1000:g} km of the ellipsoid: a pressure or another unit? "
            "expected a height in metres")


def check_height(v):
    """A pydantic after-validator of a height field [m] (None passes):
    :func:`height_problem`'s message."""
    problem = height_problem(v)
    if problem:
        raise ValueError(problem)
    return v


#: an angle setting [deg] beyond a full turn either way is refused: no orientation needs more, and 370 for 37.0
#: (or a value in another unit) would be taken without a word, the angle modulo 360
ANGLE_LIMIT_DEG = 360.0
#: the longitudes a setting may hold [deg], as the readers of positions take them (east positive; 180..360 the
#: western half counted eastward)
LONGITUDE_RANGE_DEG = (-180.0, 360.0)

#: the elevation masks a user sets [deg] (``inskit spp --mask``, ``[gnss] mask_deg``, ``[raw_gnss] mask_deg``):
#: from the horizon to below the zenith, [0, 90).  Below the horizon the Saastamoinen delay is undefined
#: (:func:`inskit.gnss.atmosphere.saastamoinen_delay` gives NaN), a signal would cross the Earth, and the code
#: weight 1 / sin^2(el) has no bound at 0.
MASK_RANGE_DEG = (0, 90)


def mask_problem(mask_deg) -> str | None:
    """What is wrong with an elevation mask a user set [deg], in words
    (None: nothing): the one check and message of ``inskit spp --mask``, the
    navigate config's ``[gnss] mask_deg`` and the scenario's ``[raw_gnss]
    mask_deg`` (:data:`MASK_RANGE_DEG`).  Not a number: None (the caller's
    type check says so)."""
    lo, hi = MASK_RANGE_DEG
    if isinstance(mask_deg, bool) or not isinstance(mask_deg, (int, float)):
        return None
    if math.isfinite(mask_deg) and lo <= mask_deg < hi:
        return None
    return (f"{mask_deg:g} is outside [{lo:g}, {hi:g}) degrees: an elevation mask is an elevation from the horizon "
            f"({lo:g}: every satellite above it) up to below the zenith (below the horizon no troposphere model "
            "holds and a signal would cross the Earth)")


def check_mask(v):
    """A pydantic before-validator of an elevation-mask field: :func:`mask_problem`'s message (the field's
    ``ge``/``lt`` bounds, the same range, then never speak; they document it)."""
    problem = mask_problem(v)
    if problem:
        raise ValueError(problem)
    return v


def _angle_names(v):
    """The components of an angle setting for a message: roll, pitch, yaw of a triple; none of a scalar."""
    if isinstance(v, (tuple, list)):
        return ("roll ", "pitch ", "yaw ") if len(v) == 3 else tuple(f"item {k + 1} " for k in range(len(v)))
    return ("",)


def check_angles(v):
    """A pydantic after-validator of an angle field [deg] (a scalar or a
    roll, pitch, yaw triple; None passes): each value within
    +-:data:`ANGLE_LIMIT_DEG`, else refused naming the component and the
    value (the field is named by the caller's location)."""
    if v is None:
        return v
    for name, x in zip(_angle_names(v), v if isinstance(v, (tuple, list)) else (v,)):
        if isinstance(x, (int, float)) and abs(x) <= MAX_SETTING and not abs(x) <= ANGLE_LIMIT_DEG:
            raise ValueError(f"{name}{x:g} is outside [-{ANGLE_LIMIT_DEG:g}, {ANGLE_LIMIT_DEG:g}] degrees: no "
                             "angle needs more than a full turn either way (a typo, or another unit?)")
    return v


#: the largest lever-arm component a setting may hold [m]: no vehicle carries its sensors a kilometre apart;
#: beyond it is a typo or another unit (``--lever-arm 1e12,0,0`` ended in 'innovation covariance is not positive
#: definite: the filter diverged', naming no setting)
LEVER_ARM_LIMIT_M = 1000.0


def check_lever_arm(v):
    """A pydantic after-validator of a lever-arm field [m] (a forward,
    right, down triple): each component within
    +-:data:`LEVER_ARM_LIMIT_M`, else refused naming the component and the
    value (the field is named by the caller's location)."""
    for name, x in zip(("x (forward) ", "y (right) ", "z (down) "), v):
        if isinstance(x, (int, float)) and abs(x) <= MAX_SETTING and not abs(x) <= LEVER_ARM_LIMIT_M:
            raise ValueError(f"{name}{x:g} m is beyond +-{LEVER_ARM_LIMIT_M:g} m: no vehicle carries its sensors "
                             "that far apart (a typo, or millimetres?); expected metres in body axes")
    return v


def check_option_angles(option, rpy):
    """Angles [deg] given with a command-line ``option`` (roll, pitch, yaw)
    held to :func:`check_angles`' range, else an InputError naming the
    option; returns ``rpy``."""
    try:
        check_angles(tuple(float(v) for v in rpy))
    except ValueError as exc:
        raise InputError(f"{option}: {exc}") from None
    return rpy


def check_option_height(option, h, what=""):
    """A height [m] given with a command-line ``option`` held to
    :func:`height_problem`'s range, else an InputError naming the option
    (``what`` names the value inside it); returns ``h``."""
    problem = height_problem(float(h))
    if problem:
        raise InputError(f"{option}: {what}{problem}")
    return h


def check_option_init(option, x):
    """A ``lat_deg,lon_deg,height_m,vn,ve,vd,roll_deg,pitch_deg,yaw_deg``
    state given with ``option`` (``inskit mechanize --init``, ``inskit
    gyrofree navigate --init``): its height and angles held to the config
    keys' ranges, the option named (a latitude beyond +-90 deg was said
    by the state's own check in radians' words); returns ``x``."""
    if not -90.0 <= x[0] <= 90.0:
        raise InputError(f"{option}: latitude must be within [-90, 90] deg, got {x[0]:g}")
    lo, hi = LONGITUDE_RANGE_DEG
    if not lo <= x[1] <= hi:
        raise InputError(f"{option}: longitude must be within [{lo:g}, {hi:g}] deg, got {x[1]:g}")
    check_option_height(option, x[2], "height_m ")
    check_option_angles(option, x[6:9])
    return x


def check_longitude(v):
    """A pydantic after-validator of a longitude field [deg] (None passes):
    within :data:`LONGITUDE_RANGE_DEG`, as the position readers take it."""
    lo, hi = LONGITUDE_RANGE_DEG
    if v is not None and abs(v) <= MAX_SETTING and not lo <= v <= hi:
        raise ValueError(f"{v:g} is outside [{lo:g}, {hi:g}] degrees (a longitude, east positive; a typo?)")
    return v


def _leaf_kinds(tp):
    """The scalar kinds an annotation admits: a set of 'bool', 'number',
    'text' and 'other' (any type that is none of these, e.g. a model)."""
    import typing
    from pathlib import PurePath

    if tp is bool:
        return {"bool"}
    if tp in (int, float):
        return {"number"}
    if tp is str or (isinstance(tp, type) and issubclass(tp, PurePath)):
        return {"text"}
    if tp is type(None):
        return set()
    origin = typing.get_origin(tp)
    if origin is typing.Literal:
        return {"bool" if isinstance(a, bool) else "number" if isinstance(a, (int, float)) else "text"
                for a in typing.get_args(tp)}
    args = [a for a in typing.get_args(tp) if a is not Ellipsis]
    if origin is not None and args:
        out = set()
        for a in args:
            out |= _leaf_kinds(a)
        return out
    return {"other"}


def _literal_choices(tp):
    """The text values of the Literal inside an annotation (``Literal[...]``, ``Literal[...] | None``), else ()."""
    if typing.get_origin(tp) is typing.Literal:
        return tuple(a for a in typing.get_args(tp) if isinstance(a, str))
    for a in typing.get_args(tp):
        c = _literal_choices(a)
        if c:
            return c
    return ()


def _check_dict_values(v):
    """A free-form table of numeric overrides (the scenario's ``[imu.gyro]`` and ``[imu.accel]``): every
    value a number or a list of numbers, within :data:`MAX_SETTING`."""
    if not isinstance(v, dict):
        return v
    for k, x in v.items():
        items = x if isinstance(x, (list, tuple)) else [x]
        for y in items:
            kind = _kind(y)
            if kind != "number":
                raise ValueError(f"{k} = {_shown(y)}: expected a number (or a list of numbers)")
            if abs(y) > MAX_SETTING:
                raise ValueError(f"{k} = {y:g} is beyond +-{MAX_SETTING:g}: no setting means a value that large")
    return v


def _shown(v):
    """A TOML value as its file shows it: text in quotes, true/false, numbers as they are."""
    if isinstance(v, str):
        return f'"{v}"'
    if isinstance(v, bool):
        return "true" if v else "false"
    return repr(v)


def _kind(v):
    if isinstance(v, bool):
        return "bool"
    if isinstance(v, (int, float)):
        return "number"
    if isinstance(v, str):
        return "text"
    return None


_SAY = {"bool": "true or false", "number": "a number", "text": "text"}
_IS = {"bool": "a boolean", "number": "a number", "text": "text"}


def check_scalar_type(cls, v, info):
    """A pydantic before-validator for every field (``field_validator("*",
    mode="before")``): a TOML value of the wrong kind is refused instead of
    coerced, e.g. ``rate_hz = "10"`` (text in quotes), ``rate_hz = true`` or
    ``zupt = 1`` (pydantic would take them as 10.0, 1.0 and True), also inside
    a list.  Kinds the annotation admits pass on to the field's own checks."""
    field = cls.model_fields.get(info.field_name)
    if field is None:
        return v
    if field.annotation is dict or typing.get_origin(field.annotation) is dict:
        return _check_dict_values(v)
    kinds = _leaf_kinds(field.annotation)
    choices = _literal_choices(field.annotation)
    if "other" in kinds or not kinds:
        return v

    def walk(x):
        if isinstance(x, (list, tuple)):
            for y in x:
                walk(y)
            return
        k = _kind(x)
        if k is not None and k not in kinds:
            want = " or ".join(_SAY[w] for w in sorted(kinds))
            if choices and kinds == {"text"}:
                want = "one of " + ", ".join(f'"{c}"' for c in choices)
            hint = " (without quotes)" if k == "text" else ""
            raise ValueError(f"{_shown(x)} is {_IS[k]}; this setting takes {want}{hint}")

    walk(v)
    return v


def validation_message(source, exc: ValidationError, model=None):
    """``source: field 'a.b': what is wrong (and N more)``; an unknown key of
    ``model`` (the validated class) is followed by the nearest known one."""
    errors = exc.errors()
    e = errors[0]
    where = ".".join(str(x) for x in e["loc"]) or "(top level)"
    more = f" (and {len(errors) - 1} more)" if len(errors) > 1 else ""
    hint = ""
    if e["type"] == "extra_forbidden" and model is not None and e["loc"]:
        keys = _known_keys(model, e["loc"][:-1])
        if keys:
            import difflib

            near = difflib.get_close_matches(str(e["loc"][-1]), keys, n=1, cutoff=0.6)
            hint = f"; did you mean '{near[0]}'?" if near else f"; the keys here are {', '.join(keys)}"
    msg = e["msg"].removeprefix("Value error, ")
    return f"{source}: field '{where}': {msg}{hint}{more}"


def _known_keys(model, loc):
    """The field names of the model that ``loc`` (a path of keys and list
    indices) leads to from ``model``; None where the path is not one model
    (a union of several)."""
    cur = model
    for part in loc:
        if isinstance(part, int):  # a list item: the list's model is taken already
            continue
        field = cur.model_fields.get(part)
        if field is None:
            return None
        cur = _model_of(field.annotation)
        if cur is None:
            return None
    return list(cur.model_fields)


def _model_of(tp):
    """The one pydantic model inside an annotation (``X``, ``X | None``,
    ``list[X]``), else None."""
    import typing

    from pydantic import BaseModel

    if isinstance(tp, type) and issubclass(tp, BaseModel):
        return tp
    found = {m for m in (_model_of(a) for a in typing.get_args(tp)) if m is not None}
    return found.pop() if len(found) == 1 else None
