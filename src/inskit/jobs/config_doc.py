"""Generate ``docs/config.md``: every key of the ``inskit navigate`` config
and of the ``inskit simulate`` scenario files, from their pydantic models.

    python -m inskit.jobs.config_doc > docs/config.md
    python -m inskit.jobs.config_doc --write            # the same, atomically
    python -m inskit.jobs.config_doc --check            # exit 1 if docs/config.md is stale

For each key: its TOML type, its unit (from the name's suffix, ``_deg``,
``_m_s``, ``_deg_sqrt_h`` ..., else from a ``[unit]`` in its description),
its default, the allowed values (a ``Literal``) or bounds (``gt/ge/lt/le``),
and its meaning (the field's ``description``).  Section texts are the models'
docstrings.  Scenario fields that carry no description in
:mod:`inskit.simulation.scenario` take theirs from :data:`SCENARIO_MEANINGS`.
"""

from __future__ import annotations

import argparse
import inspect
import re
import sys
import types
import typing
from pathlib import Path

from annotated_types import Ge, Gt, Le, Lt
from pydantic import BaseModel
from pydantic_core import PydanticUndefined

from ..errors import InputError
from ..files import write_text
from ..simulation.scenario import Scenario, segment_keys_text
from ..simulation.sensors import TRIAD_TERMS
from .config import INTERNAL_KEYS, NavigateConfig

#: the file this module generates, relative to the repository root
DOC_PATH = Path("docs") / "config.md"
REGENERATE = "python -m inskit.jobs.config_doc --write"

#: name suffix -> unit, longest first wins (the datasheet units of the files)
SUFFIX_UNITS = {
    "_deg_h_sqrt_h": "deg/h/sqrt(h)",
    "_ug_sqrt_h": "micro-g/sqrt(h)",
    "_m_sqrt_h": "m/sqrt(h)",
    "_deg_sqrt_h": "deg/sqrt(h)",
    "_m_s_sqrt_h": "m/s/sqrt(h)",
    "_ppm_sqrt_s": "ppm/sqrt(s)",
    "_s_sqrt_s": "s/sqrt(s)",
    "_deg_h": "deg/h",
    "_deg_s": "deg/s",
    "_m_s2": "m/s^2",
    "_m_s": "m/s",
    "_dbhz": "dB-Hz",
    "_ppm": "ppm",
    "_deg": "deg",
    "_hz": "Hz",
    "_ug": "micro-g",
    "_mg": "milli-g",
    "_us": "µs",
    "_m": "m",
    "_s": "s",
}

#: meanings of the scenario keys whose Field has no description (keys: "Model.field")
SCENARIO_MEANINGS = {
    "Scenario.name": "name of the scenario (progress and summaries)",
    "Scenario.description": "free text for the reader (not used by the programs)",
    "Scenario.duration_limit_s": "end the run here when the segments last longer (the segments are cut, not scaled)",
    "Scenario.start": "the start of the trajectory",
    "Scenario.imu": "the simulated IMU",
    "Scenario.gnss": "the simulated GNSS fixes",
    "Scenario.raw_gnss": "raw GNSS observations (written as RINEX 3); absent: none",
    "Scenario.vibration": "vibration on top of the whole trajectory",
    "Scenario.segment": "the manoeuvres, in order",
    "StartSpec.lat_deg": "initial latitude",
    "StartSpec.lon_deg": "initial longitude",
    "StartSpec.height_m": "initial ellipsoidal height",
    "StartSpec.yaw_deg": "initial heading (yaw of the body axes)",
    "StartSpec.speed_m_s": "initial speed along the heading",
    "StartSpec.transition_s": "length of the smooth (quintic) transitions that start and end turns and climbs",
    "ImuSpec.rate_hz": "IMU output rate",
    "ImuSpec.grade": "error preset of the IMU (ideal: no errors); imu.gyro and imu.accel override its terms",
    "ImuSpec.quadrature_nodes": "Gauss-Legendre nodes per IMU interval for the exact increments of the "
                                "trajectory (exact for motion polynomial up to degree 2 x nodes - 1)",
    "GnssSpec.rate_hz": "rate of the position (and velocity) fixes",
    "GnssSpec.white_h_m": "white position noise per horizontal axis",
    "GnssSpec.white_v_m": "white position noise, vertical",
    "GnssSpec.correlated_h_m": "first-order Gauss-Markov position error sigma per horizontal axis",
    "GnssSpec.correlated_v_m": "first-order Gauss-Markov position error sigma, vertical",
    "GnssSpec.correlation_time_s": "correlation time of the Gauss-Markov position errors",
    "GnssSpec.velocity_sigma_m_s": "white velocity noise per axis; 0 writes no velocity",
    "GnssSpec.lever_arm_b_m": "antenna position relative to the trajectory point in body axes (forward, right, "
                              "down); also the antenna of [raw_gnss]",
    "GnssSpec.latency_s": "a fix stamped t describes the antenna at t - latency (those of the first latency_s "
                          "seconds the start); shorter than the run",
    "GnssSpec.outages_s": "[start, end] windows with no fixes [s of scenario time]",
    "GnssSpec.outlier_probability": "probability that a fix is an outlier",
    "GnssSpec.outlier_sigma_m": "sigma of the error added to an outlier fix per axis",
    "VibrationSpec.target": "what vibrates: an attitude angle, or the down position",
    "VibrationSpec.frequency_hz": "sinusoidal: the frequency (required); random: the band centre (the band "
                                  "0.5-1.5 x it), or give band_hz instead",
    "VibrationSpec.kind": "sinusoidal (amplitude = peak) or random (band-limited, amplitude = RMS; needs a seed)",
    "VibrationSpec.band_hz": "random: the [low, high] frequency band (instead of frequency_hz)",
    "SegmentSpec.type": "the manoeuvre; each takes exactly its keys (and repeat): " + segment_keys_text(),
    "SegmentSpec.duration_s": "length of the segment",
    "SegmentSpec.speed_m_s": "accelerate, decelerate: the speed at the segment's end (above the current speed "
                             "for accelerate, below it for decelerate)",
    "SegmentSpec.angle_deg": "turn: heading change (negative: to the left); climb, descend: flight-path angle, "
                             "|angle_deg| < 90 (its sign is ignored: climb goes up, descend down)",
    "SegmentSpec.rate_deg_s": "turn: heading rate",
    "SegmentSpec.radius_m": "turn, figure-eight: turn radius (at the current speed)",
    "SegmentSpec.amplitude_deg": "pitch, roll: the angle reached and left again; coning: the half-angle",
    "SegmentSpec.frequency_hz": "coning: the coning frequency (below the IMU's Nyquist frequency, imu.rate_hz / 2)",
    "SegmentSpec.repeat": "how many times the segment is repeated",
}

#: cross-key rules of the scenario sections, whose models have no docstrings (keys: model name)
SECTION_RULES = {
    "ImuSpec": "Rules: imu.gyro and imu.accel overrides need a grade other than \"ideal\". They take these "
               "terms of the grade's datasheet (gyro unit / accelerometer unit; allowed values): " + "; ".join(
                   f"{k} ({r.gyro_unit}" + (f" / {r.accel_unit}" if r.accel_unit else ", gyros only")
                   + f"; {r.takes}): {r.meaning}" for k, r in TRIAD_TERMS.items()) + ".",
    "RawGnssSection": "Rules: give start_utc, or start_gps_week with start_sow_s, or neither (default: GPS week "
                      "2374, 243240 s of week, the day of the drive_0708 log); the scenario must end inside that "
                      "GPS week. cn0_horizon_dbhz is at most cn0_zenith_dbhz. Some satellite must be in view at "
                      "some epoch, and the receiver clock offset must stay within +-0.5 s over the run (clock_jumps "
                      "keeps it within a millisecond).",
    "BlockageSpec": "Rules: end_s after start_s; keep or sats, not both.",
    "GnssSpec": "Rules: every outages_s window [start, end] has 0 <= start < end.",
    "VibrationSpec": "Rules: a sinusoidal vibration takes frequency_hz, a random one frequency_hz or band_hz "
                     "(0 < low < high), not both. Its highest frequency (a random one's top of the band) must be "
                     "below the IMU's Nyquist frequency, imu.rate_hz / 2 (with imu.quadrature_nodes 1 or 2 lower "
                     "still: where their increments stay within 0.1 %). The amplitude of an attitude (roll, "
                     "pitch, yaw) is within +-360 deg.",
    "SegmentSpec": "Rules: each type takes exactly its keys, listed under type (a key its type would ignore is an "
                   "error): turns take rate_deg_s or radius_m, not both; accelerate must speed up and decelerate "
                   "slow down; climb and descend take |angle_deg| < 90; a coning frequency must be below the IMU's "
                   "Nyquist frequency, imu.rate_hz / 2 (with imu.quadrature_nodes 1 or 2 lower still).",
}

#: units of keys whose name carries none (keys: "Model.field")
UNIT_NOTES = {
    "VibrationSpec.amplitude": "deg or m",
}


# --- one key ------------------------------------------------------------------------
def _is_model(tp):
    return inspect.isclass(tp) and issubclass(tp, BaseModel)


def _strip_optional(tp):
    """``(inner type, optional?)`` of ``X | None``."""
    if typing.get_origin(tp) in (typing.Union, types.UnionType):
        args = [a for a in typing.get_args(tp) if a is not type(None)]
        if len(args) == 1:
            return args[0], True
    return tp, False


def submodel(tp):
    """``(model, is_array)`` when ``tp`` is a section (a model, an optional
    model, or a list of models: an array of tables), else ``(None, False)``."""
    tp, _ = _strip_optional(tp)
    if _is_model(tp):
        return tp, False
    if typing.get_origin(tp) is list and _is_model(typing.get_args(tp)[0]):
        return typing.get_args(tp)[0], True
    return None, False


def type_name(tp, optional=None) -> str:
    """The TOML type of an annotation, in words; ``optional`` (default: the
    annotation allows None) adds "(optional)"."""
    while typing.get_origin(tp) is typing.Annotated:  # a tagged type: its base
        tp = typing.get_args(tp)[0]
    tp, may_be_none = _strip_optional(tp)
    optional = may_be_none if optional is None else optional
    origin, args = typing.get_origin(tp), typing.get_args(tp)
    if origin in (typing.Union, types.UnionType):  # several kinds (a grade: a name or a table)
        names = list(dict.fromkeys(type_name(a, optional=False) for a in args if a is not type(None)))
        name = " or ".join(names)
    elif origin is typing.Literal:
        name = "string" if all(isinstance(a, str) for a in args) else "value"
    elif tp is bool:
        name = "boolean"
    elif tp is int:
        name = "integer"
    elif tp is float:
        name = "number"
    elif tp is str:
        name = "string"
    elif inspect.isclass(tp) and issubclass(tp, Path):
        name = "path"
    elif tp is dict or origin is dict:
        name = "table"
    elif origin is tuple:
        inner = {type_name(a) for a in args}
        name = f"{len(args)} {inner.pop()}s" if len(inner) == 1 else "[" + ", ".join(type_name(a) for a in args) + "]"
        name = f"array of {name}"
    elif origin is list:
        inner = type_name(args[0])
        if typing.get_origin(args[0]) is tuple:
            name = "array of [" + ", ".join(type_name(a) for a in typing.get_args(args[0])) + "]"
        else:
            name = f"array of {inner}s"
    elif _is_model(tp):
        name = "table"
    else:  # pragma: no cover - a new kind of annotation: say so rather than guess
        raise TypeError(f"config_doc: no TOML name for the annotation {tp!r}")
    return f"{name} (optional)" if optional else name


def unit_of(name: str, description: str | None) -> str:
    """The unit of a key: its name's suffix (longest match), else the last
    ``[...]`` of its description, else ``-`` (dimensionless or not a quantity)."""
    for suffix in sorted(SUFFIX_UNITS, key=len, reverse=True):
        if name.endswith(suffix):
            return SUFFIX_UNITS[suffix]
    found = re.findall(r"\[([^\[\]]+)\]", description or "")
    return found[-1] if found else "-"


def _toml(v) -> str:
    """A value as it is written in TOML."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (str, Path)):
        return f'"{v}"'
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml(x) for x in v) + "]"
    if isinstance(v, float):
        return repr(v)
    if isinstance(v, BaseModel):
        return "(see the table)"
    return str(v)


def default_of(field) -> str:
    if field.is_required():
        return "required"
    if field.default_factory is None and field.default is PydanticUndefined:  # pragma: no cover
        return "required"
    v = field.get_default(call_default_factory=True)
    if v is None:
        return "unset"
    if isinstance(v, BaseModel):
        return "defaults below"
    return f"`{_toml(v)}`"


def allowed_of(field, model=None, name=None) -> str:
    """Literal values and numeric bounds, e.g. ``"loose", "tight"`` or ``> 0, <= 1000``; with ``model`` and
    ``name`` also the range of an angle or longitude checked by its validator (:func:`validator_bounds`)."""
    tp, _ = _strip_optional(field.annotation)
    if typing.get_origin(tp) is list:
        tp = typing.get_args(tp)[0]
    parts = []
    if typing.get_origin(tp) is typing.Literal:
        parts.append(", ".join(f"`{_toml(a)}`" for a in typing.get_args(tp)))
    ops = {Gt: (">", "gt"), Ge: (">=", "ge"), Lt: ("<", "lt"), Le: ("<=", "le")}
    for m in field.metadata:
        for cls, (sym, attr) in ops.items():
            if isinstance(m, cls):
                parts.append(f"{sym} {_toml(getattr(m, attr))}")
    if model is not None:
        parts += validator_bounds(model, name)
    return ", ".join(parts) if parts else ""


def validator_bounds(model, name) -> list[str]:
    """The bounds a field validator of ``model`` puts on field ``name``
    (:func:`inskit.config_files.check_angles`: each within +-360;
    :func:`~inskit.config_files.check_longitude`: the longitude range;
    :func:`~inskit.config_files.check_height`: +-MAX_HEIGHT_M)."""
    from ..config_files import ANGLE_LIMIT_DEG, LONGITUDE_RANGE_DEG, check_angles, check_height, check_longitude
    from ..units import MAX_HEIGHT_M

    out = []
    for dec in model.__pydantic_decorators__.field_validators.values():
        if name not in dec.info.fields:
            continue
        if dec.func is check_angles:
            out += [f">= {_toml(-ANGLE_LIMIT_DEG)}", f"<= {_toml(ANGLE_LIMIT_DEG)}"]
        elif dec.func is check_longitude:
            out += [f">= {_toml(LONGITUDE_RANGE_DEG[0])}", f"<= {_toml(LONGITUDE_RANGE_DEG[1])}"]
        elif dec.func is check_height:
            out += [f">= {_toml(-MAX_HEIGHT_M)}", f"<= {_toml(MAX_HEIGHT_M)}"]
    return out


def meaning_of(model, name, field) -> str:
    text = field.description or SCENARIO_MEANINGS.get(f"{model.__name__}.{name}", "")
    return text


def rows(model) -> list[dict]:
    """One dict per key of ``model`` (its sections included as rows of type table)."""
    out = []
    for name, field in model.model_fields.items():
        if name in INTERNAL_KEYS and model is NavigateConfig:
            continue
        desc = meaning_of(model, name, field)
        sub, is_array = submodel(field.annotation)
        unit = UNIT_NOTES.get(f"{model.__name__}.{name}") or unit_of(name, desc)
        out.append({"key": name, "type": ("array of tables" if is_array else "table") if sub else
                    type_name(field.annotation, optional=default_of(field) == "unset"),
                    "unit": "-" if sub else unit, "default": default_of(field), "allowed": allowed_of(field, model, name),
                    "meaning": desc, "section": sub, "array": is_array})
    return out


# --- the document ------------------------------------------------------------------
def _cell(text) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def _doc(model) -> str:
    d = model.__dict__.get("__doc__")
    return inspect.cleandoc(d) if d else ""


def _sections(model, prefix, out):
    """Markdown of ``model``'s keys, then of each of its sections, depth first."""
    rs = rows(model)
    scalars = [r for r in rs if r["section"] is None]
    if scalars:
        out.append("| key | type | unit | default | allowed | meaning |")
        out.append("| --- | --- | --- | --- | --- | --- |")
        for r in scalars:
            out.append("| " + " | ".join(_cell(x) for x in (f"`{r['key']}`", r["type"], r["unit"], r["default"],
                                                             r["allowed"], r["meaning"])) + " |")
        out.append("")
    for r in rs:
        if r["section"] is None:
            continue
        name = f"{prefix}{r['key']}"
        out.append(f"### `[[{name}]]`" if r["array"] else f"### `[{name}]`")
        out.append("")
        doc = _doc(r["section"])  # the model's docstring, else the field's meaning
        text = " ".join(x for x in (doc or (r["meaning"] and r["meaning"][0].upper() + r["meaning"][1:] + "."),
                                    "Optional." if r["default"] == "unset" else "",
                                    "Repeat the table once per item." if r["array"] else "") if x)
        rule = SECTION_RULES.get(r["section"].__name__, "")
        for par in (text, rule):
            if par:
                out.append(par)
                out.append("")
        _sections(r["section"], f"{name}.", out)


def render() -> str:
    """The whole of ``docs/config.md``."""
    out = ["# Configuration reference", "",
           "<!-- Generated from the pydantic models by `" + REGENERATE + "`; do not edit by hand. -->", "",
           "Every key of the three TOML files inskit reads: the `inskit navigate` configuration "
           "(`src/inskit/jobs/config.py`), the `inskit simulate` scenario (`src/inskit/simulation/scenario.py`) "
           "and the `inskit study` file (`src/inskit/jobs/study.py`). "
           "Units follow datasheets at this edge (degrees, deg/h, deg/sqrt(h), micro-g, ppm) and are named by the "
           "key's suffix; inside, everything is SI. Relative paths are taken relative to the file that holds them. "
           "An unknown key, a value outside its bounds, or a key that would be ignored in its context is an "
           "error naming the key. *allowed* lists the accepted values or the bounds; *unset* means the key is "
           "optional and has no value unless given.", "",
           "## `inskit navigate` configuration", "",
           "Example: [examples/drive_0708.toml](../examples/drive_0708.toml) (loose coupling), "
           "[examples/walk_0827_tight.toml](../examples/walk_0827_tight.toml) (tight coupling). "
           "Command-line flags (`--imu`, `--gnss`, `--scheme`, `--outages`, `--out`, ...) override these keys.", "",
           "### Top level", ""]
    _sections(NavigateConfig, "", out)
    out += ["## Scenario files (`inskit simulate`)", "",
            "Example: [examples/car.toml](../examples/car.toml); with raw GNSS "
            "[examples/tc_blockage.toml](../examples/tc_blockage.toml).", "",
            _doc(Scenario) or "", "", "### Top level", ""]
    _sections(Scenario, "", out)
    from .study import AllanGrade, StudySpec

    out += ["## Study files (`inskit study`)", "",
            "Example: [examples/study_outage_grades.toml](../examples/study_outage_grades.toml) (a sweep of "
            "grades), [examples/study_mc_mems.toml](../examples/study_mc_mems.toml) (one Monte Carlo case), "
            "[examples/study_allan_grades.toml](../examples/study_allan_grades.toml) (a grade fitted to a static "
            "log).", "", _doc(StudySpec) or "", "", "### Top level", ""]
    _sections(StudySpec, "", out)
    out += ["### A grade fitted to a static log (`grades` entry `{allan = ...}`)", "", _doc(AllanGrade) or "", ""]
    _sections(AllanGrade, "grades[].", out)
    text = "\n".join(out)
    text = re.sub(r"\n{3,}", "\n\n", text)
    return text.rstrip("\n") + "\n"


def missing_meanings() -> list[str]:
    """Keys (``Model.field``) documented without a meaning: a new field needs
    a ``description=`` (or, for a scenario field, an entry here)."""
    from .study import AllanGrade, StudySpec

    seen, todo, missing = set(), [NavigateConfig, Scenario, StudySpec, AllanGrade], []
    while todo:
        m = todo.pop()
        if m in seen:
            continue
        seen.add(m)
        for r in rows(m):
            if not r["meaning"]:
                missing.append(f"{m.__name__}.{r['key']}")
            if r["section"] is not None:
                todo.append(r["section"])
    return sorted(missing)


def main(argv=None) -> int:
    """``python -m inskit.jobs.config_doc [--write [PATH] | --check [PATH]]``."""
    ap = argparse.ArgumentParser(prog="python -m inskit.jobs.config_doc", description=__doc__.splitlines()[0])
    g = ap.add_mutually_exclusive_group()
    g.add_argument("--write", nargs="?", const=str(DOC_PATH), metavar="PATH",
                   help=f"write the reference to PATH (default {DOC_PATH}, run from the repository root)")
    g.add_argument("--check", nargs="?", const=str(DOC_PATH), metavar="PATH",
                   help="exit 1 when PATH differs from a fresh generation")
    a = ap.parse_args(argv)
    text = render()
    if a.write:
        p = Path(a.write)
        if not p.parent.is_dir():
            raise InputError(f"{p.parent}: no such folder (run from the repository root, or give --write PATH)")
        write_text(p, text)
        print(f"wrote {p}", file=sys.stderr)
        return 0
    if a.check:
        p = Path(a.check)
        if not p.is_file() or p.read_text() != text:
            print(f"{p} is stale: regenerate it with `{REGENERATE}`", file=sys.stderr)
            return 1
        return 0
    sys.stdout.write(text)
    return 0


if __name__ == "__main__":  # pragma: no cover
    try:
        sys.exit(main())
    except InputError as exc:
        print(f"config_doc: error: {exc}", file=sys.stderr)
        sys.exit(2)
