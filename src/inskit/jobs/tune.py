"""Filter settings chosen from the data by cross-validation (``inskit tune``).

A setting that makes the outages of a benchmark look good must not be chosen
by looking at them: the withheld fixes are the test.  This job chooses among
candidate settings with **validation outages of its own**, placed in the
stretches where the benchmark's protocol keeps GNSS on:

1. the protocol's own windows stay withheld (their fixes are never read);
2. in every stretch between them, after ``reaid_s`` of aiding (the filter
   settles after the protocol's outage), ``hold_s`` more seconds of fixes
   are withheld, provided ``reaid_s`` of aiding remain before the next
   protocol window or the end of the fixes;
3. each candidate is run with both sets of windows withheld and scored by the
   horizontal RMS of its error at the end of the validation outages, against
   the validation fixes withheld there (fixes the final run will use); a
   candidate that calibrates (``[imu] time_offset_search`` or ``[gnss]
   sigma_scale_search = "calibrate"``) calibrates in each run, on the fixes
   that run uses;
4. the candidate with the smallest score wins among those whose run is
   healthy and *consistent*: in one more run with only the protocol's
   windows withheld (the run the config will make), the mean NIS per degree
   of freedom of each GNSS measurement (fixes, velocity, pseudoranges) within
   :data:`NIS_BAND`, the band of the drive's consistency test (a setting
   that scores well by declaring the fixes far noisier than their
   innovations show is not chosen); its keys are printed as a TOML snippet
   to put into the config.

With ``shifts`` > 1 each candidate runs once per placement of the validation
outages, shifted together by up to ``reaid_s - SHIFT_MIN_REAID_S`` either
way (each keeping at least that much aiding on both sides), and is scored
over all of them: eleven validation outages of 15 s decide little (on
drive_0708 the three placements of ``--shifts 3`` rank two noise models
2.70 / 2.09 m over 33 outages where the default placement alone gave
1.45 / 1.46 m, the other way round).

The score uses the same forward filter, outage length scale and data as the
final run, and no withheld fix of the protocol.  (K-fold style validation of
a filter's tuning on held-out aiding: e.g. the cross-validated tuning of
Kalman-filter noise in the adaptive-estimation literature; here without any
model of the score, by plain runs.)
"""

from __future__ import annotations

import itertools
import math
import os
from concurrent.futures import ProcessPoolExecutor

import numpy as np

from ..errors import ConfigError

#: with shifts, every shifted validation outage keeps at least this much aiding on each side [s]
SHIFT_MIN_REAID_S = 5.0
#: a consistent candidate's GNSS innovations: mean NIS per degree of freedom within this band (1 expected;
#: a third to three times it, as the health verdict's bounds and tests/test_jobs_navigate.py)
NIS_BAND = (1.0 / 3.0, 3.0)
#: the measurements whose NIS decides consistency (the constraints' noise stands for model errors and is
#: conservative by design: their low NIS is a warning of the health verdict, not a reason)
GNSS_MEASUREMENTS = ("gnss_pos", "gnss_vel", "gnss_speed_course", "pseudorange", "pseudorange_rate")
#: keys a candidate grid may vary: "section.key"
_SECTIONS = ("imu", "gnss", "noise", "init", "constraints", "filter", "odometer", "earth", "height")


def parse_grid(specs) -> dict:
    """``["noise.bias_tau_s=300,3000", "constraints.nhc_sigma_m_s=0.1,0.3"]``
    as ``{"noise.bias_tau_s": [300.0, 3000.0], ...}`` (numbers, true/false,
    text, or a vector in brackets: ``constraints.nhc_lever_arm_b_m=[0,0,0],[0.06,0,0.81]``)."""
    grid = {}
    for spec in specs:
        if "=" not in spec:
            raise ConfigError(f"--grid {spec!r}: expected SECTION.KEY=V1,V2,...")
        key, vals = spec.split("=", 1)
        key = key.strip()
        if key.count(".") != 1 or key.split(".")[0] not in _SECTIONS:
            raise ConfigError(f"--grid {spec!r}: the key must be SECTION.KEY with a section of the navigate config "
                              f"({', '.join(_SECTIONS)})")
        if key in grid:
            raise ConfigError(f"--grid {spec!r}: the key {key} is given twice; give its values in one --grid")
        items = [v.strip() for v in _split_top(vals) if v.strip()]
        if not items:
            raise ConfigError(f"--grid {spec!r}: no values")
        vals = [_value(v) for v in items]
        seen = {}
        for text, v in zip(items, vals):
            if _same_key(v) in seen:
                raise ConfigError(f"--grid {spec!r}: the value {text} repeats {seen[_same_key(v)]}")
            seen[_same_key(v)] = text
        grid[key] = vals
    if not grid:
        raise ConfigError("give at least one --grid SECTION.KEY=V1,V2,...")
    return grid


def _same_key(v):
    """What makes two grid values the same candidate: equal numbers (1 and
    1.0), equal text, but a boolean never a number (Python's ``True == 1``:
    ``constraints.mounting=true,1`` named the wrong type a repeat)."""
    if isinstance(v, tuple):
        return tuple(_same_key(x) for x in v)
    return (isinstance(v, bool), v)


def _split_top(text):
    """``text`` split at the commas outside brackets."""
    out, depth, cur = [], 0, ""
    for ch in text:
        depth += (ch == "[") - (ch == "]")
        if ch == "," and depth == 0:
            out.append(cur)
            cur = ""
        else:
            cur += ch
    return out + [cur]


def _value(text):
    if text.startswith("[") and text.endswith("]"):  # a vector: a tuple of numbers (hashable, like the others)
        return tuple(_value(v.strip()) for v in text[1:-1].split(",") if v.strip())
    low = text.lower()
    if low in ("true", "false"):
        return low == "true"
    try:
        v = float(text)
    except ValueError:
        return text
    return int(v) if v.is_integer() and "." not in text and "e" not in low else v


def candidates(grid: dict) -> list[dict]:
    """Every combination of the grid's values, in a fixed order."""
    keys = list(grid)
    return [dict(zip(keys, combo)) for combo in itertools.product(*(grid[k] for k in keys))]


def overrides_of(params: dict) -> dict:
    """``{"a.b": v}`` as the nested override dict of the config loader; a
    switch turned off also resets the keys that only count with it on
    (:func:`inskit.jobs.config.switched_off_overrides`)."""
    from .config import switched_off_overrides

    return _nested({**params, **switched_off_overrides(params)})


def _nested(params: dict) -> dict:
    """``{"a.b": v}`` as ``{"a": {"b": v}}``."""
    out = {}
    for k, v in params.items():
        sect, key = k.split(".")
        out.setdefault(sect, {})[key] = v
    return out


def validation_windows(protocol_rel, t_first_rel, t_last_rel, hold_s=10.0, reaid_s=10.0, start_after_s=60.0):
    """Validation outages in the stretches the protocol leaves aided.

    Parameters
    ----------
    protocol_rel : list of (start, end)
        The protocol's windows [s after the first fix].
    t_first_rel, t_last_rel : float
        First and last fix [s after the first fix].
    hold_s, reaid_s : float
        Length of a validation outage, and the aiding kept before and after it.
    start_after_s : float
        No validation outage before this (start-up and first convergence).

    Returns
    -------
    list of (start, end), [s after the first fix]
    """
    edges = sorted((float(a), float(b)) for a, b in protocol_rel)
    stretches = []
    t = t_first_rel
    for a, b in edges:
        if a > t:
            stretches.append((t, a))
        t = max(t, b)
    if t_last_rel > t:
        stretches.append((t, t_last_rel))
    out = []
    for a, b in stretches:
        s = max(a + reaid_s, start_after_s)
        while s + hold_s + reaid_s <= b + 1e-9:
            out.append((s, s + hold_s))
            s += hold_s + 2.0 * reaid_s
    return out


def _run_one(args):
    config_path, params, sets = args
    from . import config as C
    from .navigate import calibrated_config, navigate, summary
    from ..errors import InskitError

    errs, health, reasons, nis = [], "healthy", [], {}
    for windows_rel, val_rel in sets:  # one run per placement of the validation outages
        over = overrides_of(params)
        over["outages"] = ({"protocol": "windows", "windows_s": [list(w) for w in windows_rel], "keep_satellites": 0}
                           if windows_rel else {"protocol": "none"})  # the consistency run of a config without any
        cfg = C.load_config(config_path, over)
        try:  # its searches ([imu] time_offset_search, [gnss] sigma_scale_search) on this run's fixes, as navigate's
            cfg, _ = calibrated_config(cfg)
            s = summary(navigate(cfg))
        except (InskitError, np.linalg.LinAlgError, FloatingPointError) as exc:  # diverged or refused: scored as
            return {"params": params, "cv_rms_m": math.inf, "error": str(exc).splitlines()[0][:300]}
        val = [o for o in s["outage_table"] if any(abs(o["start_s"] - v[0]) < 1e-6 for v in val_rel)]
        errs += [o["horizontal_m"] for o in val]
        if s["health"]["verdict"] != "healthy":
            health = s["health"]["verdict"]
        reasons += [r for r in s["health"].get("reasons", []) if r not in reasons]
        if val_rel:
            continue
        # the run the config will make (only the protocol's windows withheld): its GNSS NIS says whether
        # the candidate's noise is consistent (the validation runs withhold a quarter more fixes)
        for name, m in s["health"].get("measurements", {}).items():
            if name in GNSS_MEASUREMENTS and m.get("mean_nis") is not None and m.get("dof"):
                nis[name] = float(m["mean_nis"] / m["dof"])
    errs = np.array(errs, float)
    return {"params": params, "cv_rms_m": float(np.sqrt(np.mean(errs ** 2))) if len(errs) else math.inf,
            "cv_max_m": float(errs.max()) if len(errs) else math.inf, "cv_outages": int(len(errs)),
            "health": health, "health_reasons": reasons, "gnss_mean_nis_per_dof": nis,
            # no GNSS innovations (the uncoupled scheme): consistency unknown, not granted
            "consistent": bool(nis) and all(NIS_BAND[0] <= v <= NIS_BAND[1] for v in nis.values())}


def shifted_windows(val, protocol_rel, t_first_rel, t_last_rel, reaid_s, shifts, min_reaid_s=SHIFT_MIN_REAID_S):
    """The validation outages ``val`` moved together to ``shifts`` placements.

    Placement ``k`` moves every outage by ``d_k``, evenly spaced over
    ``+-(reaid_s - min_reaid_s)`` (one placement: ``val`` itself); an outage
    that would come within ``min_reaid_s`` of a protocol window, of the
    first fix or of the last is left out of that placement.

    Returns
    -------
    list of (shift_s, windows)
    """
    m = min(min_reaid_s, reaid_s)  # a validation outage placed with less aiding keeps what it was placed with
    spread = max(0.0, reaid_s - m)
    if shifts <= 1 or spread <= 1e-6:  # no room to move: one placement (three copies of it decided nothing more)
        return [(0.0, list(val))]
    out = []
    for k in range(shifts):
        d = -spread + 2.0 * spread * k / (shifts - 1)
        keep = []
        for a, b in val:
            a2, b2 = a + d, b + d
            clear = a2 - m >= t_first_rel - 1e-9 and b2 + m <= t_last_rel + 1e-9
            clear = clear and all(b2 + m <= pa + 1e-9 or a2 - m >= pb - 1e-9 for pa, pb in protocol_rel)
            if clear:
                keep.append((a2, b2))
        out.append((d, keep))
    return out


def distinct_placements(placed, t_rel):
    """The placements of :func:`shifted_windows` that withhold different fixes.

    Two placements shifted by less than the fixes' interval can withhold the
    same fixes: the same runs, whose outages would be scored twice over.
    The first of each set of fixes is kept.

    Parameters
    ----------
    placed : list of (shift_s, windows)
    t_rel : (n,) array
        The fixes' times [s after the first fix].

    Returns
    -------
    list of (shift_s, windows)
    """
    from .outages import withheld_mask

    seen, out = set(), []
    for d, w in placed:
        key = tuple(np.flatnonzero(withheld_mask(t_rel, w)).tolist())
        if key not in seen:
            seen.add(key)
            out.append((d, w))
    return out


def check_separated(windows, validation, t_rel, reaid_s):
    """Refuse a set of withheld windows (the protocol's and the validation
    outages of one run) in which a validation outage and its neighbour have
    no used fix between them: they are one outage, and the end of the first
    is not the end of an outage (``--reaid`` shorter than the fixes'
    interval; 0 put every validation outage flush against the next).

    Raises
    ------
    ConfigError
        Naming the two windows [s after the first fix] and ``--reaid``.
    """
    from .outages import withheld_mask

    w = sorted((float(a), float(b)) for a, b in windows)
    val = {(float(a), float(b)) for a, b in validation}
    used = t_rel[~withheld_mask(t_rel, w)]
    for (a0, b0), (a1, b1) in zip(w, w[1:]):
        if ((a0, b0) in val or (a1, b1) in val) and not np.any((used > b0) & (used < a1)):
            dt = float(np.median(np.diff(t_rel))) if len(t_rel) > 1 else float("nan")
            raise ConfigError(f"--reaid {reaid_s:g}: the outages {a0:g}-{b0:g} s and {a1:g}-{b1:g} s (after the first "
                              f"fix) have no GNSS fix between them (fixes every {dt:g} s): they are one outage, not "
                              "two; give a longer --reaid")


def default_spacing(protocol_rel):
    """Validation outages like the protocol's: ``hold_s`` the median length of
    its windows (10 s without any), ``reaid_s`` 10 s, or less (not under 2 s)
    so that one validation outage fits the median aided stretch between two
    protocol windows."""
    if not protocol_rel:
        return 10.0, 10.0
    w = sorted(protocol_rel)
    hold = float(np.median([b - a for a, b in w]))
    gaps = [w[i + 1][0] - w[i][1] for i in range(len(w) - 1)]
    if not gaps:
        return hold, 10.0
    return hold, float(min(10.0, max(2.0, (np.median(gaps) - hold) / 2.0 - 1e-6)))


def tune(config_path, grid: dict, *, hold_s=None, reaid_s=None, start_after_s=60.0, workers=None,
         progress=None, shifts=1) -> dict:
    """Cross-validate the candidates of ``grid`` on ``config_path``'s data.

    ``hold_s`` and ``reaid_s`` default to :func:`default_spacing` (validation
    outages as long as the protocol's); ``shifts`` placements of them
    (:func:`shifted_windows`) are each run and scored together.

    Returns a dict: ``windows_protocol_s`` and ``windows_validation_s`` (s
    after the first fix), ``candidates`` (each with ``params``,
    ``cv_rms_m``, ``cv_max_m``, ``cv_outages``, ``health``; ranked best
    first, healthy runs before unhealthy ones), ``best`` (the params) and
    ``best_toml`` (a snippet).  A candidate the config refuses, or a grid in
    which no candidate runs healthy, is a :class:`ConfigError`.
    """
    from . import config as C
    from .navigate import load_inputs, outage_windows

    cfg = C.load_config(config_path)
    if cfg.gnss.coupling == "tight":
        raise ConfigError(f"{config_path}: tune works on loose coupling (the validation outages withhold fixes)")
    _, gnss = load_inputs(cfg)[:2]
    t0 = float(gnss.time[0])
    protocol = [(a - t0, b - t0) for a, b in outage_windows(cfg, gnss)]
    d_hold, d_reaid = default_spacing(protocol)
    hold_s = d_hold if hold_s is None else float(hold_s)
    reaid_s = d_reaid if reaid_s is None else float(reaid_s)
    span = float(gnss.time[-1]) - t0
    val = validation_windows(protocol, 0.0, span, hold_s, reaid_s, start_after_s)
    if not val:
        raise ConfigError(f"{config_path}: no room for a validation outage of {hold_s:g} s with {reaid_s:g} s of "
                          f"aiding on each side between the protocol's outages, after the first {start_after_s:g} s "
                          f"of the {span:g} s of fixes; shorten --hold, --reaid or --start-after")
    cands = candidates(grid)
    for p in cands:  # a candidate the config refuses: said now, naming --grid, not halfway through the search
        try:
            c = C.load_config(config_path, overrides_of(p))
        except ConfigError as exc:
            raise ConfigError(f"--grid candidate {p}: {exc}") from None
        if c.noise.from_static and ({"noise.gyro_arw_deg_sqrt_h", "noise.accel_vrw_m_s_sqrt_h"} & set(p)):
            raise ConfigError(f"--grid candidate {p}: with noise.from_static = true the white noise is raised to "
                              "what the static start measures, so a grid of gyro_arw_deg_sqrt_h or "
                              "accel_vrw_m_s_sqrt_h would not run the values it names; add "
                              "--grid noise.from_static=false")
    if int(shifts) < 1:
        raise ConfigError(f"shifts must be at least 1, got {shifts!r}")
    t_rel = np.asarray(gnss.time, float) - t0
    placed = shifted_windows(val, protocol, 0.0, float(gnss.time[-1]) - t0, reaid_s, int(shifts))
    shifted = len(placed)
    placed = distinct_placements(placed, t_rel)  # the same fixes withheld: the same runs, scored once
    if not any(w for _, w in placed):
        raise ConfigError(f"{config_path}: no placement of the validation outages keeps "
                          f"{min(SHIFT_MIN_REAID_S, reaid_s):g} s of aiding on both sides; shorten --hold or "
                          "--reaid, or use fewer --shifts")
    sets = [(sorted(protocol + w), w) for _, w in placed if w] + [(list(protocol), [])]
    for windows, w in sets:
        check_separated(windows, w, t_rel, reaid_s)
    warnings = []
    if int(shifts) > 1 and shifted == 1:
        warnings.append(f"--shifts {int(shifts)}: one placement only (re-aiding {reaid_s:g} s leaves no room to move the "
                     f"validation outages while keeping {SHIFT_MIN_REAID_S:g} s of aiding)")
    elif len(placed) < shifted:
        warnings.append(f"--shifts {int(shifts)}: {len(placed)} placements withhold different fixes (the fixes come "
                        f"every {float(np.median(np.diff(t_rel))):g} s); the {shifted - len(placed)} that repeat one "
                        "of them were not run")
    jobs = [(str(config_path), p, sets) for p in cands]
    workers = workers or min(len(jobs), os.cpu_count() or 1)
    results = []
    if workers == 1:
        for j in jobs:
            results.append(_run_one(j))
            if progress:
                progress(1)
    else:
        with ProcessPoolExecutor(workers) as ex:
            for r in ex.map(_run_one, jobs):
                results.append(r)
                if progress:
                    progress(1)
    # healthy and consistent candidates first: a setting whose own run is unhealthy, or whose GNSS
    # innovations say its noise is far off, is not recommended on its score
    ranked = sorted(results, key=lambda r: (r.get("health") != "healthy", not r.get("consistent", False),
                                            r["cv_rms_m"], cands.index(r["params"])))
    best = ranked[0]["params"]
    if not math.isfinite(ranked[0]["cv_rms_m"]):
        raise ConfigError(f"{config_path}: every candidate failed; first error: {ranked[0].get('error')}")
    if ranked[0].get("health") != "healthy":
        raise ConfigError(f"{config_path}: no candidate gave a healthy run (the best score, "
                          f"{ranked[0]['cv_rms_m']:.3f} m, came with {ranked[0].get('health_reasons')}); "
                          "widen the grid or mend the config first")
    if not ranked[0].get("consistent", False):
        nis = ", ".join(f"{k} {v:.2f}" for k, v in (ranked[0].get("gnss_mean_nis_per_dof") or {}).items())
        warnings.append(f"no healthy candidate had its GNSS innovations in band (mean NIS per degree of freedom "
                        f"within {NIS_BAND[0]:.3g}..{NIS_BAND[1]:.3g}); the best one's: {nis or 'none (no GNSS update)'}:"
                        " its noise is off or unjudged, widen the grid or mend the noise before taking it")
    for r in ranked:  # JSON has no infinity: a failed candidate has no score
        for k in ("cv_rms_m", "cv_max_m"):
            if k in r and not math.isfinite(r[k]):
                r[k] = None
    return {"config": str(config_path), "hold_s": hold_s, "reaid_s": reaid_s,
            "windows_protocol_s": protocol, "windows_validation_s": val, "shifts": int(shifts),
            "windows_validation_shifted_s": [{"shift_s": d, "windows_s": w} for d, w in placed],
            "candidates": ranked,
            "best": best, "best_toml": toml_snippet(best), "warnings": warnings,
            "placements": len(placed)}


def toml_snippet(params: dict) -> str:
    """The chosen keys as TOML sections (a switch turned off: with the keys
    of the config that serve it, which go, named in a comment)."""
    from .config import switched_off_overrides

    lines = []
    drop = sorted(switched_off_overrides(params))
    if drop:
        lines.append(f"# and remove from the config those it sets of (they serve what is switched off): "
                     f"{', '.join(drop)}")
    for sect, keys in _nested(params).items():
        lines.append(f"[{sect}]")
        for k, v in keys.items():
            lines.append(f"{k} = {_toml_value(v)}")
    return "\n".join(lines) + "\n"


def _toml_value(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(v)
    if isinstance(v, (tuple, list)):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    return '"' + str(v).replace('"', '\\"') + '"'


def table_text(res: dict) -> str:
    """The ranking as text."""
    keys = list(res["candidates"][0]["params"])
    head = "  ".join(f"{k:>24}" for k in keys) + f"  {'cv RMS [m]':>11}  {'cv max [m]':>10}  {'GNSS NIS/dof':>12}  health"
    rows = [head]
    for r in res["candidates"]:
        vals = "  ".join(f"{_toml_value(v) if isinstance(v, tuple) else str(v):>24}"
                         for v in (r["params"][k] for k in keys))
        rms, mx = r.get("cv_rms_m"), r.get("cv_max_m")
        nis = r.get("gnss_mean_nis_per_dof") or {}
        nis_txt = "/".join(f"{v:.2f}" for v in nis.values()) or "-"
        verdict = r.get("health", "failed: " + r.get("error", ""))
        if "health" in r and not r.get("consistent", False):
            verdict += ", inconsistent" if nis else ", no GNSS NIS"
        rows.append(f"{vals}  {'-' if rms is None else f'{rms:.3f}':>11}  {'-' if mx is None else f'{mx:.3f}':>10}  "
                    f"{nis_txt:>12}  {verdict}")
    n = len(res["windows_validation_s"])
    rows.append(f"{n} validation outages of {res['hold_s']:g} s (after {res['reaid_s']:g} s of aiding) between the "
                f"{len(res['windows_protocol_s'])} outages of the protocol, whose fixes were never used")
    placed = res.get("windows_validation_shifted_s") or []
    if len(placed) > 1:
        by = ", ".join(f"{p['shift_s']:+g}" for p in placed)
        scored = sum(len(p["windows_s"]) for p in placed)
        rows.append(f"  run at {len(placed)} placements (shifted by {by} s): {scored} outages scored per candidate")
    rows.append("best:\n" + res["best_toml"])
    rows += [f"warning: {w}" for w in res.get("warnings", [])]
    return "\n".join(rows)
