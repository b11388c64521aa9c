"""Every published experiment and every measured README claim, in one report
(``inskit reproduce all``).

Each experiment runs through the same job function its own command calls
(``inskit reproduce alignment-ga``, ``demo --checks``, ``spp``, ``navigate``,
``schemes``, ``bench`` ...) and is reduced to *quantities*: a published (or
claimed) figure, ours, the tolerance stated here and a verdict.

Kinds of quantity and their verdicts
------------------------------------
``published``
    A figure of a source document (or a closed form).  The tolerance is what
    the source's printed precision allows (half a unit of its last digit) or,
    for a closed form, the size of the terms it neglects.  Verdict ``pass``
    when ``|ours - published| <= tolerance``; ``differs`` when it is outside
    and the difference is a *known, explained* one (listed in this module, with
    the reason in the note: the source's inputs are unstated, or its printed
    figure cannot be reproduced by any reading found); ``fail`` otherwise.
``claim``
    A figure measured by this project and quoted in README.md (or a commit).
    Runs are deterministic (seeds fixed), so the tolerance is
    ``max(1 % of the claim, half a unit of its last printed digit)``;
    ``pass`` or ``fail``.
``bound``
    ``pass`` when ``ours <= published`` (closure to rounding, agreement of two
    optimisers); else ``fail``.
``info``
    Machine-dependent (timings) or without a published number: reported,
    never judged; its verdict is ``info``.

An experiment fails when any of its quantities fails (or it raised); the
command's exit status is 1 when any experiment fails.  ``differs`` does not
fail an experiment: it is the honest record of a published figure we do not
reproduce, and the regression test (``tests/test_jobs_reproduce_all.py``)
still holds our figure to its tolerance.

References
----------
The sources' own references are in the individual jobs
(:mod:`.reproduce_alignment`, :mod:`.reproduce_gyrofree`, :mod:`.platform`,
:mod:`.reproduce_tight`, :mod:`.demo`, :mod:`.spp`).  Coning drift of the
uncompensated (single-sample) attitude update: Savage, *Strapdown
Analytics* (2000), sec. 7.1.1.1 (classical coning, algorithm error
``Omega (1 - cos a) (1 - sin(Omega h) / (Omega h))``).
"""

from __future__ import annotations

import base64
import html
import json
import math
import sys
import time
import traceback
from pathlib import Path

import numpy as np

from ..errors import ConfigError
from ..files import plain_json, relocated, staged_tree, write_json, write_text

ROOT = Path(__file__).resolve().parents[3]
DOC_PATH = ROOT / "docs" / "REPRODUCE.md"

PUBLISHED, CLAIM, BOUND, INFO = "published", "claim", "bound", "info"


# --- quantities -----------------------------------------------------------------------
def _num(x):
    if x is None:
        return None
    if isinstance(x, (bool, np.bool_)):
        return float(bool(x))
    return float(x)


def published(quantity, ours, value, tol, *, unit="", note="", known_difference=False, shown=None):
    """A figure of a source (or closed form) against ours, ``tol`` absolute."""
    return {"quantity": quantity, "kind": PUBLISHED, "reference": _num(value), "reference_text": shown,
            "ours": _num(ours), "tolerance": float(tol), "tolerance_text": None, "unit": unit, "note": note,
            "known_difference": bool(known_difference)}


def claim(quantity, ours, value, resolution, *, unit="", note="", rel=0.01):
    """A README (or commit) claim: tolerance ``max(rel |value|, resolution / 2)``."""
    tol = max(rel * abs(value), resolution / 2.0)
    return {"quantity": quantity, "kind": CLAIM, "reference": float(value), "reference_text": None,
            "ours": _num(ours), "tolerance": tol,
            "tolerance_text": f"{rel:.0%} or half of {resolution:g}", "unit": unit, "note": note,
            "known_difference": False}


def bound(quantity, ours, limit, *, unit="", note="", shown=None):
    """Pass when ``ours <= limit``."""
    return {"quantity": quantity, "kind": BOUND, "reference": float(limit), "reference_text": shown,
            "ours": _num(ours), "tolerance": float(limit), "tolerance_text": "upper bound", "unit": unit,
            "note": note, "known_difference": False}


def info(quantity, ours, *, unit="", note="", shown=None):
    """Reported, not judged (machine-dependent or nothing to compare with)."""
    return {"quantity": quantity, "kind": INFO, "reference": None, "reference_text": shown, "ours": _num(ours),
            "tolerance": None, "tolerance_text": None, "unit": unit, "note": note, "known_difference": False}


def verdict(q) -> str:
    """``pass``, ``fail``, ``differs`` or ``info`` for one quantity (module docstring)."""
    if q["kind"] == INFO:
        return "info"
    ours = q["ours"]
    if ours is None or not math.isfinite(ours):
        return "fail"
    if q["kind"] == BOUND:
        return "pass" if ours <= q["reference"] else "fail"
    if abs(ours - q["reference"]) <= q["tolerance"] * (1 + 1e-12):
        return "pass"
    return "differs" if q["known_difference"] else "fail"


# --- the experiments ------------------------------------------------------------------
def _exp_alignment(out, log):
    from .reproduce_alignment import run

    r = run(out, log=log)
    m6 = [x["m"] for x in r["fig6"] if np.isfinite(x["m"])]
    m7 = [x["m"] for x in r["fig7"] if np.isfinite(x["m"])]
    tilt7 = max(max(abs(x["alpha"]), abs(x["beta"])) for x in r["fig7"])
    ga = max([c["J_relative_difference"] for c in r["ga_checks"]]
             + [abs(x["ga_J_arcmin"] - x["J_arcmin"]) / x["J_arcmin"] for x in r["fig6"] + r["fig7"]
                if np.isfinite(x["ga_J_arcmin"]) and x["J_arcmin"] > 0])
    hl, ot = r["headline"], r["one_vs_two_step"]
    q = [
        published("fig. 6: smallest optimal m, accelerometer error 0..0.1 mg", min(m6), 1.0, 1e-3,
                  note="the GA codes m on 16 bits (1.5e-5); 1e-3 is the resolution of reading a plotted curve"),
        published("fig. 7: largest optimal m, gyro error 0..1 % Earth rate", max(m7), 0.0, 1e-3),
        published("fig. 7: largest tilt error over the gyro sweep", tilt7, 0.0, 1e-6, unit="arcmin",
                  note="roll and pitch independent of the gyro error (exact for m = 0)"),
        published("headline: eq. 29, B = 0.01 m/s^2, D = 0.04 deg/h", hl["eq29_literal_arcmin"], 16.3, 0.05,
                  unit="arcmin", known_difference=True,
                  note=f"eq. 29 taken literally; the expectation form gives {hl['eq29_expectation_arcmin']:.2f}, the "
                       f"gyro basis {hl['same_signs']['gyro_basis_arcmin']:.2f}: no reading found gives 16.3"),
        published("headline: GA-blended one-step alignment, all three angles", hl["same_signs"]["ga_arcmin"], 4.0,
                  0.5, unit="arcmin", known_difference=True, shown="about 4",
                  note="'about 4' read as 4 +- 0.5; with the azimuth weight k3 = 0 (tilt only) the GA gives "
                       f"{hl['same_signs']['tilt_only_ga_arcmin']:.2f} (same signs) and "
                       f"{hl['opposite_signs']['tilt_only_ga_arcmin']:.2f} (opposite): 'about 4' matches a "
                       "tilt-only criterion"),
        published("headline, tilt-only criterion (k3 = 0), same signs", hl["same_signs"]["tilt_only_ga_arcmin"],
                  4.0, 0.5, unit="arcmin", shown="about 4", known_difference=True,
                  note="the readings closest to the source: 4.96 and 3.49 bracket 'about 4'"),
        published("headline, tilt-only criterion (k3 = 0), opposite signs", hl["opposite_signs"]["tilt_only_ga_arcmin"],
                  4.0, 0.5, unit="arcmin", shown="about 4", known_difference=True,
                  note="as above"),
        bound("GA optimum against the scalar minimiser: largest relative difference in J", ga, 0.01,
              shown="agree (no number)", note="the job requires agreement within 1 %"),
        published("one step as good as two: J(one step) / J(analytic + fine Kalman), 600 s static",
                  ot["one_step_unblended_arcmin"] / ot["two_step_arcmin"], 1.0, 0.1,
                  shown="as good as (1)", note="'as good as' read as within 10 %; constant biases are "
                                                "unobservable at rest"),
    ]
    return q, {"one_vs_two_step": ot}


def _exp_gyrofree(out, log):
    from .gyrofree import reproduce_gyrofree as job
    from .reproduce_gyrofree import PUBLISHED_ANALYTIC, PUBLISHED_SIMULATED

    r = job(out, log=log)
    tc = r["truth_check"]
    ents = {e["item"]: e for e in r["entries"]}
    analytic = [float(x) for x in ents["analytic position error, bias 1 um/s^2 and misalignment <= 0.1 deg, X, Y, "
                                       "Z [m]"]["ours"].strip("[]").split(",")]
    simulated = [float(x) for x in ents["simulated position error after 10 s (fig. 14), X, Y, Z [m]"]["ours"]
                 .strip("[]").split(",")]
    q = []
    for j, ax in enumerate("XYZ"):
        q.append(claim(f"error-free truth r(10 s), {ax}", tc["r_10s_m"][j], [350.07, 815.02, 1006.63][j], 0.01,
                       unit="m", note="closed-form scenario truth (README)"))
    q.append(bound("error-free array (closed form + eq. 43-44): max position error over 10 s",
                   tc["closed_form"]["position_error_max_m"], 1e-9, unit="m", shown="0 (README: 7e-11)",
                   note="closure to rounding at 1 kHz"))
    for j, ax in enumerate("XYZ"):
        q.append(published(f"analytic position error at 10 s, {ax} (our reading of the inputs)", analytic[j],
                           PUBLISHED_ANALYTIC[j], 0.005, unit="m", known_difference=True,
                           note="the source states neither the angles, their signs, d nor the unit; the note of "
                                "`inskit reproduce gyrofree --out DIR` lists the closest readings"))
    for j, ax in enumerate("XYZ"):
        q.append(published(f"simulated position error at 10 s (fig. 14), {ax}", simulated[j], PUBLISHED_SIMULATED[j],
                           0.05, unit="m", known_difference=True,
                           note="same reading as the analytic row; our simulation agrees with our analytic value"))
    for row in r["growth_60s"]:
        q.append(info(f"60 s growth, {row['unit']}: RMS at 60 s", row["rms_60s_m"], unit="m",
                      note=r["growth_grades"]))
    return q, {}


def _exp_filters(out, log):
    from .platform import ESTIMATOR_NAMES, TABLE1
    from .platform import reproduce_integration_filters as job

    r = job(out, log=log)
    rows = {x["filter"]: x for x in r["table"]}
    # published entries of table 1 that we do not reproduce (ours smaller in every case, as measured when this list
    # was written): the source gives one run with partly unstated drifts and SNS noise; see docs/platform.md
    known = {("kalman", "alpha_x"), ("kalman", "alpha_y"), ("kalman", "dV_xi"), ("kalman", "dV_eta"),
             ("kalman", "d_phi"), ("kalman", "d_lambda"),
             ("first-order", "alpha_y"), ("first-order", "dV_xi"), ("second-order", "alpha_y"),
             ("second-order", "dV_xi"), ("first-order", "dV_eta"), ("second-order", "dV_eta")}
    units = {"alpha_x": "arcmin", "alpha_y": "arcmin", "d_phi": "arcmin", "d_lambda": "arcmin", "dV_xi": "m/s",
             "dV_eta": "m/s"}
    q = []
    for name in ("kalman", "first-order", "second-order"):
        for col, unit in units.items():
            pub = TABLE1[name][col]
            digits = len(f"{pub}".split(".")[1]) if "." in f"{pub}" else 0
            q.append(published(f"table 1, {ESTIMATOR_NAMES[name]}: steady-state {col} (max over the last 2 h)",
                               rows[name][col], pub, 0.5 * 10.0 ** -digits, unit=unit,
                               known_difference=(name, col) in known,
                               note="printed to one or two digits: half a unit of the last"
                                    + ("; ours smaller (source inputs partly unstated)" if (name, col) in known
                                       else "")))
    k, f1, f2 = rows["kalman"], rows["first-order"], rows["second-order"]
    q.append(claim("Kalman: largest steady-state velocity error", max(k["dV_xi"], k["dV_eta"]), 0.01, 0.01,
                   unit="m/s"))
    q.append(claim("Kalman: largest steady-state tilt", max(k["alpha_x"], k["alpha_y"]), 0.04, 0.01, unit="arcmin"))
    q.append(claim("simple filters: smaller of their largest velocity errors",
                   min(max(f["dV_xi"], f["dV_eta"]) for f in (f1, f2)), 0.03, 0.01, unit="m/s"))
    q.append(claim("simple filters: smaller of their largest tilts",
                   min(max(f["alpha_x"], f["alpha_y"]) for f in (f1, f2)), 0.10, 0.01, unit="arcmin"))
    better_v = k["dV_xi"] <= min(f1["dV_xi"], f2["dV_xi"]) and k["dV_eta"] <= min(f1["dV_eta"], f2["dV_eta"])
    better_t = (k["alpha_x"] <= min(f1["alpha_x"], f2["alpha_x"])
                and k["alpha_y"] <= min(f1["alpha_y"], f2["alpha_y"]))
    q.append(published("Kalman best on absolute velocity (1 = yes)", better_v, 1.0, 0.0, shown="yes"))
    q.append(published("Kalman best on horizontal tilt (1 = yes)", better_t, 1.0, 0.0, shown="yes"))
    c = r["compute"]
    q.append(info("compute time, Kalman / 1st order (whole closed-loop run)", c["kalman_over_first_order"],
                  unit="ratio", shown="2.33 (source); README 4.5-4.9",
                  note="machine- and load-dependent timing: not judged"))
    for o in r["outage"]:
        q.append(info(f"30 min outage, {ESTIMATOR_NAMES[o['filter']]} {o['scheme']} loop: horizontal error growth",
                      o["growth_m"], unit="m", shown="closed loop keeps its compensation"))
    return q, {}


def _exp_tight(kind):
    def run(out, log):
        from .reproduce_tight import run as job

        r, _ = job(out, (kind,), seed=1, log=log)
        q = []
        if kind == "walk":
            rows = {x["solution"]: x for x in r["walk"]["table"]}
            sp, ti = rows["single-point"], rows["tight (pseudorange + Doppler)"]
            q += [claim("single-point: horizontal RMS against RTK", sp["horizontal_rms_m"], 8.50, 0.01, unit="m"),
                  claim("single-point: horizontal jitter", sp["horizontal_jitter_m"], 0.35, 0.01, unit="m"),
                  claim("tight: horizontal RMS against RTK", ti["horizontal_rms_m"], 9.06, 0.01, unit="m"),
                  claim("tight: horizontal jitter", ti["horizontal_jitter_m"], 0.047, 0.001, unit="m")]
        else:
            rows = r["blockage"]["table"]
            claims = {"tight": (1.57, 1.07, 8.30), "loose": (77.5, 8.3, 15.5)}
            for sol, vals in claims.items():
                mine = [x for x in rows if x["solution"] == sol]
                for x, v in zip(mine, vals):
                    res = 0.01 if sol == "tight" else 0.1
                    q.append(claim(f"{sol}: worst horizontal error, blockage keeping {x['satellites']} satellites",
                                   x["max_horizontal_m"], v, res, unit="m"))
                    if sol == "tight":
                        q.append(published(f"tight within 3 sigma of its own covariance ({x['satellites']} "
                                           "satellites; 1 = yes)", x["within_bound"], 1.0, 0.0, shown="yes",
                                           note="source 000: tight coupling works with fewer than four "
                                                "satellites"))
        return q, {}

    return run


def _exp_demo(out, log):
    from .demo import closed_form_checks

    c = closed_form_checks(log=log)
    s, sc, co = c["stationary"], c["schuler"], c["coning_attitude_drift"]
    a, w, T = np.radians(1.0), 2 * np.pi * 1.0, 600.0  # the check's cone: 1 deg half-angle at 1 Hz, 10 min
    h = 0.01
    single = w * (1 - np.cos(a)) * (1 - np.sin(w * h) / (w * h)) * T
    q = [
        published("stationary 1 h, ideal sensors: horizontal max", s["horizontal_max_m"], 0.0, 1e-6, unit="m",
                  note="exactly zero in closed form; 1 um allows rounding"),
        published("stationary 1 h: attitude max", s["attitude_max_arcsec"], 0.0, 1e-3, unit="arcsec"),
        published("Schuler period, 100 ug north bias", sc["period_s"], sc["closed_form_period_s"],
                  0.005 * sc["closed_form_period_s"], unit="s",
                  note="2 pi sqrt(R_N / g); 0.5 %: the closed form neglects the Earth-rate (Foucault) coupling"),
        published("Schuler first peak", sc["first_peak_m"], sc["closed_form_peak_m"], 0.03 * sc["closed_form_peak_m"],
                  unit="m", note="2 b / w_s^2; 3 % for the same reason"),
        published("coning 10 min, single-sample 100 Hz: attitude drift", co["single_sample_100hz_rad"], single,
                  0.02 * single, unit="rad",
                  note="Omega (1 - cos a)(1 - sin(Omega h)/(Omega h)) T (Savage 2000, 7.1.1.1); 2 % covers the "
                       "small-angle terms"),
        published("coning: two-sample drift at 100 Hz / at 200 Hz", co["two_sample_100hz_rad"] / co["two_sample_200hz_rad"],
                  16.0, 0.8, unit="ratio", note="fourth-order residual of the two-sample algorithm: 2^4 = 16, 5 %"),
        bound("coning: two-sample / single-sample drift at 100 Hz", co["two_sample_100hz_rad"] / co["single_sample_100hz_rad"],
              0.1, unit="ratio", note="the correction removes > 90 % of the drift"),
    ]
    return q, {"checks": c}


def _exp_spp(out, log):
    from .spp import run_spp

    r = run_spp(str(ROOT / "data" / "abpo" / "abpo0080.15o.gz"), str(ROOT / "data" / "abpo" / "abpo0080.15n.gz"),
                reference="header", out=str(out), overwrite=True, log=log)
    m, s = r["mean_neu_m"], r["std_neu_m"]
    rt_note = ("RTKLIB 2.4.3b34 on the same files and models (data/abpo/README.md); a different implementation "
               "(satellite selection, outlier handling): printed precision as tolerance")
    q = [claim("epochs solved", r["epochs_solved"], 2727, 1, rel=0.0),
         claim("horizontal RMS", r["horizontal_rms_m"], 3.20, 0.01, unit="m"),
         claim("3-D RMS", r["rms_3d_m"], 6.25, 0.01, unit="m"),
         published("RTKLIB: horizontal RMS", r["horizontal_rms_m"], 3.4, 0.05, unit="m", known_difference=True,
                   note=rt_note),
         published("RTKLIB: 3-D RMS", r["rms_3d_m"], 6.3, 0.05, unit="m", known_difference=True,
                   note=rt_note)]
    for j, (ax, pm, ps) in enumerate(zip("NEU", (-2.55, -0.01, 3.07), (2.03, 0.96, 4.34))):
        q.append(published(f"RTKLIB: mean {ax}", m[j], pm, 0.005, unit="m", known_difference=True, note=rt_note))
        q.append(published(f"RTKLIB: std {ax}", s[j], ps, 0.005, unit="m", known_difference=True, note=rt_note))
    return q, {}


def _exp_drive(out, log):
    from . import config as C
    from . import navigate as N

    cfg = C.load_config(ROOT / "examples" / "drive_0708.toml")
    res = N.navigate(cfg, smooth=True, log=log)
    s = N.summary(res)
    N.write_outputs(res, Path(out), s)
    f = s["forward"]
    q = [claim("forward: outage-end horizontal RMS (11 outages of 15 s)", f["outage_end_horizontal_rms_m"], 1.98,
               0.01, unit="m"),
         claim("forward: outage-end horizontal max", f["outage_end_horizontal_max_m"], 5.5, 0.1, unit="m"),
         claim("forward: GNSS-on horizontal RMS (fit to the fixes used)", f["gnss_on_horizontal_rms_m"] * 100, 0.45, 0.01,
               unit="cm"),
         claim("RTS smoother: outage-end horizontal RMS", s["outage_end_horizontal_rms_m"], 0.018, 0.001, unit="m"),
         claim("RTS smoother: worst point inside the outages, RMS", s["outage_worst_horizontal_rms_m"], 0.123, 0.01,
               unit="m"),
         published("health verdict healthy (1 = yes)", s["health"]["verdict"] == "healthy", 1.0, 0.0, shown="yes",
                   note="the run's own health checks")]
    return q, {}


def _exp_walk_startup(out, log):
    from . import config as C
    from . import navigate as N

    cfg = C.load_config(ROOT / "examples" / "walk_0827.toml")
    res = N.navigate(cfg, log=log)
    s = N.summary(res)
    N.write_outputs(res, Path(out), s)
    c = s["measurements"]["gnss_pos"]
    q = [bound("rejected fixes (fraction, issue 14: below 5 %)", c["rejected"] / max(c["used"] + c["rejected"], 1),
               0.05),
         claim("rejected fixes", c["rejected"], 0, 1),
         claim("outage-end horizontal RMS (three 10 s outages)", s["outage_end_horizontal_rms_m"], 2.87, 0.01,
               unit="m"),
         published("health verdict healthy (1 = yes)", s["health"]["verdict"] == "healthy", 1.0, 0.0, shown="yes",
                   note="the run's own health checks"),
         info("start-up: the choice it made (in the note)", 1.0, note=s["startup"].get("reason", ""))]
    return q, {}


def _exp_schemes(out, log):
    from ..simulation.scenario import load_scenario
    from .montecarlo import compare_schemes

    log("schemes: examples/car.toml, outage 1200..1260 s, seed 1")
    rows = {x["scheme"]: x for x in compare_schemes(load_scenario(ROOT / "examples" / "car.toml"), (1200.0, 1260.0), 1)}
    write_json(Path(out) / "schemes.json", rows)
    q = [claim("closed loop: horizontal error at the outage end", rows["closed"]["outage_end_horizontal_m"], 3.6, 0.1,
               unit="m"),
         claim("open loop: horizontal error at the outage end", rows["open"]["outage_end_horizontal_m"], 556, 1,
               unit="m"),
         claim("uncoupled: horizontal error at the outage end", rows["uncoupled"]["outage_end_horizontal_m"] / 1000,
               9.9, 0.1, unit="km")]
    return q, {}


def _exp_odometer(out, log):
    from .odometer_study import odometer_study

    r = odometer_study()
    write_json(Path(out) / "odometer_study.json", r)
    s = r["summary"]
    return [claim("60 s outages, outage-end horizontal RMS without the odometer",
                  s["without"]["outage_end_horizontal_rms_m"], 4.04, 0.01, unit="m",
                  note="claim of commit c347ecc (odometer study)"),
            claim("same, with the odometer", s["with"]["outage_end_horizontal_rms_m"], 0.99, 0.01, unit="m")], {}


def _exp_bench(out, log):
    from .bench import run_benchmarks

    r = run_benchmarks(quick=False, progress=lambda name: log(f"bench: {name} done"))
    write_json(Path(out) / "bench.json", r)
    q = [info(k, v, unit="1/s", note="machine-dependent: reported, not compared")
         for k, v in r.items() if k.endswith("_per_s") and isinstance(v, (int, float))]
    return q, {"bench": r}


#: name -> (source, function, cheap (a few seconds: in the default test suite))
EXPERIMENTS = {
    "demo-checks": ("closed forms: stationary, Schuler (Groves 2013 sec. 5.7), coning (Savage 2000 7.1.1.1); "
                    "`inskit demo --checks`", _exp_demo, True),
    "spp-abpo": ("README claim and RTKLIB's published figures (data/abpo/README.md); `inskit spp`", _exp_spp, True),
    "tight-blockage": ("README claim (source 000: tight coupling below four satellites); "
                       "`inskit reproduce tight-coupling --out DIR --experiment blockage`", _exp_tight("blockage"),
                       True),
    "tight-walk": ("README claim; `inskit reproduce tight-coupling --out DIR --experiment walk`", _exp_tight("walk"),
                   False),
    "drive-0708": ("README claim; `inskit navigate examples/drive_0708.toml --smooth`", _exp_drive, False),
    "walk-startup": ("README claim (issue 14: the job's own start-up on a walk); "
                     "`inskit navigate examples/walk_0827.toml`", _exp_walk_startup, False),
    "schemes-car": ("README claim; `inskit schemes examples/car.toml --outage 1200,1260 --seed 1`", _exp_schemes,
                    False),
    "alignment-ga": ("source 002, figures 6-9 and headline case; `inskit reproduce alignment-ga --out DIR`",
                     _exp_alignment, False),
    "gyrofree": ("source 003, figures 11-14; `inskit reproduce gyrofree --out DIR`", _exp_gyrofree, False),
    "integration-filters": ("source 004, table 1; `inskit reproduce integration-filters --out DIR`", _exp_filters,
                            False),
    "odometer-study": ("README claim; `inskit.jobs.odometer_study.odometer_study()`", _exp_odometer, False),
    "bench": ("README throughput (machine-dependent); `inskit bench --json`", _exp_bench, False),
}
CHEAP = tuple(k for k, v in EXPERIMENTS.items() if v[2])


def parse_only(text):
    """``"a,b"`` -> ``["a", "b"]``, checked against :data:`EXPERIMENTS`."""
    names = [x.strip() for x in str(text).split(",") if x.strip()]
    bad = [x for x in names if x not in EXPERIMENTS]
    if bad or not names:
        raise ConfigError(f"--only: unknown experiment(s) {', '.join(bad) or '(none given)'}; expected a "
                          f"comma-separated subset of {', '.join(EXPERIMENTS)}")
    return names


#: the report files of :func:`run_all`, beside one folder per experiment; ``reproduce.json`` marks the folder as
#: one that ``inskit reproduce all`` wrote (rerun into it freely)
OUTPUT_FILES = ("REPORT.md", "report.html", "reproduce.json")


def check_outputs_all(out, names, force=False):
    """Refuse, before any experiment runs, to write into a folder that is
    not an earlier ``reproduce all``'s (no ``reproduce.json``) but holds
    files of the report's names or a folder of an experiment's (the user's
    REPORT.md was replaced without a word), unless ``force``; and, ``force``
    or not, a report name that is a folder (:func:`inskit.files.check_outputs`)."""
    from ..errors import InputError
    from ..files import check_outputs

    out = Path(out)
    check_outputs([out / n for n in OUTPUT_FILES], (), overwrite=True)
    if force or (out / "reproduce.json").is_file():
        return
    theirs = [p.name for p in [out / n for n in OUTPUT_FILES] + [out / n for n in names] if p.exists()]
    if theirs:
        raise InputError(f"{out}: holds {', '.join(theirs)} but no reproduce.json: not the folder of an earlier "
                         "`inskit reproduce all`; refusing to overwrite them (use --force or another --out)")


def run_all(out_dir, *, only=None, log=None, force=False) -> dict:
    """Run the experiments (all, or those named in ``only``), write
    ``REPORT.md``, ``report.html`` and ``reproduce.json`` into ``out_dir``.

    Parameters
    ----------
    out_dir : str or Path
        Output folder; each experiment writes its figures into ``out_dir/<name>/``.
    only : iterable of str or str, optional
        Experiment names (keys of :data:`EXPERIMENTS`), or ``"a,b"``.
    log : callable, optional
        Progress, one line per experiment (and the jobs' own lines).
    force : bool, optional
        Write into a folder that is not an earlier ``reproduce all``'s
        although it holds files of the report's names
        (:func:`check_outputs_all`), replacing them.

    Returns
    -------
    dict
        ``experiments`` (each: ``name``, ``source``, ``quantities`` with
        ``verdict``, ``verdict``, ``seconds``, ``figures``, ``error``),
        ``failed`` (names), ``seconds``, ``files``.
    """
    from ..files import check_folder_writable

    log = log or (lambda s: None)
    names = list(EXPERIMENTS) if only is None else (parse_only(only) if isinstance(only, str) else parse_only(
        ",".join(only)))
    out = Path(out_dir)
    check_outputs_all(out, names, force)
    check_folder_writable(out)
    t_all = time.perf_counter()
    # every experiment's folder and the report land together once the run is through, or nothing does: an
    # interrupted run left the folders of the experiments it had run (their figures, a simulated drive) and
    # no reproduce.json, a folder its own rerun then took for another command's
    with staged_tree(out) as tmp:
        res = _run_experiments(names, tmp, out, log)
    return res


def _run_experiments(names, tmp, out, log):
    """The experiments of :func:`run_all` into ``tmp`` (a staging folder of
    ``out``) and the report files; the paths in the result name ``out``."""
    t_all = time.perf_counter()
    exps = []
    quiet = (lambda s: None)
    for i, name in enumerate(names, 1):
        source, fn, _ = EXPERIMENTS[name]
        d = tmp / name
        d.mkdir(parents=True, exist_ok=True)
        t0 = time.perf_counter()
        err, quantities, extra = None, [], {}
        try:
            quantities, extra = fn(d, quiet)
        except Exception as exc:  # noqa: BLE001 - one experiment's failure is reported, the others still run
            err = f"{type(exc).__name__}: {exc}"
            extra = {"traceback": traceback.format_exc()}
        for q in quantities:
            q["verdict"] = verdict(q)
        v = "fail" if err or any(q["verdict"] == "fail" for q in quantities) else "pass"
        secs = time.perf_counter() - t0
        figs = sorted(str(p.relative_to(tmp)) for p in d.rglob("*.png"))
        counts = {k: sum(q["verdict"] == k for q in quantities) for k in ("pass", "differs", "fail", "info")}
        exps.append({"name": name, "source": source, "verdict": v, "seconds": secs, "quantities": quantities,
                     "figures": figs, "error": err, "counts": counts,
                     "extra": relocated(json.loads(json.dumps(plain_json(extra), allow_nan=False, default=str)),
                                        tmp, out)})
        log(f"reproduce all [{i}/{len(names)}] {name}: {v.upper()} in {secs:.1f} s ({counts['pass']} pass, "
            f"{counts['differs']} differ, {counts['fail']} fail, {counts['info']} info)" + (f": {err}" if err else ""))
    res = {"experiments": exps, "failed": [e["name"] for e in exps if e["verdict"] == "fail"],
           "seconds": time.perf_counter() - t_all, "python": sys.version.split()[0]}
    res["files"] = [str(out / n) for n in OUTPUT_FILES]
    write_text(tmp / "REPORT.md", report_markdown(res))
    write_text(tmp / "report.html", report_html(res, tmp))
    write_json(tmp / "reproduce.json", res)
    return res


# --- reports ---------------------------------------------------------------------------
def fmt(x):
    """A number as the report prints it (6 significant digits: far below every tolerance)."""
    if x is None:
        return "-"
    return f"{x:.6g}"


def _ref_text(q):
    if q["reference_text"]:
        return q["reference_text"] if q["reference"] is None else f"{q['reference_text']} ({fmt(q['reference'])})"
    return fmt(q["reference"])


def _tol_text(q):
    if q["tolerance"] is None:
        return "-"
    if q["kind"] == BOUND:
        return f"<= {fmt(q['tolerance'])}"
    return f"±{fmt(q['tolerance'])}"


HEADER = "| quantity | unit | published / claimed | ours | tolerance | verdict | note |"


def _cell(s):
    return str(s).replace("|", "/").replace("\n", " ")


def report_markdown(res, *, title="inskit reproduce all", figure_links=True) -> str:
    """The report as Markdown: a summary table, then one table per experiment."""
    lines = [f"# {title}", "",
             "Every published experiment of the sources and every measured README claim, rerun by "
             "`inskit reproduce all --out DIR` (kinds of verdict: `src/inskit/jobs/reproduce_all.py`). "
             "`pass`: within the stated tolerance; `differs`: a published figure we do not reproduce, explained in "
             "the note; `fail`: outside the tolerance; `info`: reported only (machine-dependent or nothing to "
             "compare).", "",
             f"Total time {res['seconds']:.0f} s; failed: {', '.join(res['failed']) or 'none'}.", "",
             "| experiment | source | verdict | pass | differs | fail | info | seconds |",
             "| --- | --- | --- | --- | --- | --- | --- | --- |"]
    for e in res["experiments"]:
        c = e["counts"]
        lines.append(f"| {e['name']} | {_cell(e['source'])} | {e['verdict']} | {c['pass']} | {c['differs']} | "
                     f"{c['fail']} | {c['info']} | {e['seconds']:.1f} |")
    for e in res["experiments"]:
        lines += ["", f"## {e['name']}", "", f"Source: {e['source']}. Verdict: **{e['verdict']}** in "
                                            f"{e['seconds']:.1f} s.", ""]
        if e["error"]:
            lines += [f"Error: `{_cell(e['error'])}`", ""]
        lines += [HEADER, "| --- | --- | --- | --- | --- | --- | --- |"]
        for q in e["quantities"]:
            lines.append(f"| {_cell(q['quantity'])} | {q['unit']} | {_cell(_ref_text(q))} | {fmt(q['ours'])} | "
                         f"{_tol_text(q)} | {q['verdict']} | {_cell(q['note'])} |")
        if e["figures"]:
            lines.append("")
            if figure_links:
                lines.append("Figures: " + ", ".join(f"[{Path(f).name}]({f})" for f in e["figures"]))
            else:
                lines.append("Figures (in the output folder): " + ", ".join(f"`{f}`" for f in e["figures"]))
    return "\n".join(lines) + "\n"


def report_html(res, out_dir) -> str:
    """The same report as one self-contained HTML page (figures inlined as base64 PNG)."""
    esc = html.escape
    color = {"pass": "#1a7f37", "fail": "#cf222e", "differs": "#9a6700", "info": "#57606a"}
    p = ["<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'><title>inskit reproduce all</title><style>",
         "body{font-family:sans-serif;max-width:1200px;margin:1em auto;padding:0 1em}"
         "table{border-collapse:collapse;margin:.5em 0;font-size:13px}td,th{border:1px solid #ccc;padding:3px 6px;"
         "vertical-align:top}th{background:#f3f3f3}img{max-width:100%;border:1px solid #ddd;margin:4px 0}"
         ".v{font-weight:bold}@media print{img{max-width:80%}}",
         "</style></head><body><h1>inskit reproduce all</h1>",
         f"<p>Total time {res['seconds']:.0f} s; failed: {esc(', '.join(res['failed']) or 'none')}.</p>",
         "<table><tr><th>experiment</th><th>source</th><th>verdict</th><th>pass</th><th>differs</th><th>fail</th>"
         "<th>info</th><th>seconds</th></tr>"]
    for e in res["experiments"]:
        c = e["counts"]
        p.append(f"<tr><td><a href='#{esc(e['name'])}'>{esc(e['name'])}</a></td><td>{esc(e['source'])}</td>"
                 f"<td class='v' style='color:{color[e['verdict']]}'>{e['verdict']}</td><td>{c['pass']}</td>"
                 f"<td>{c['differs']}</td><td>{c['fail']}</td><td>{c['info']}</td><td>{e['seconds']:.1f}</td></tr>")
    p.append("</table>")
    for e in res["experiments"]:
        p.append(f"<h2 id='{esc(e['name'])}'>{esc(e['name'])}</h2><p>Source: {esc(e['source'])}. Verdict: "
                 f"<span class='v' style='color:{color[e['verdict']]}'>{e['verdict']}</span> in "
                 f"{e['seconds']:.1f} s.</p>")
        if e["error"]:
            p.append(f"<p style='color:#cf222e'>Error: {esc(e['error'])}</p>")
        p.append("<table><tr><th>quantity</th><th>unit</th><th>published / claimed</th><th>ours</th>"
                 "<th>tolerance</th><th>verdict</th><th>note</th></tr>")
        for q in e["quantities"]:
            p.append(f"<tr><td>{esc(q['quantity'])}</td><td>{esc(q['unit'])}</td><td>{esc(_ref_text(q))}</td>"
                     f"<td>{fmt(q['ours'])}</td><td>{esc(_tol_text(q))}</td>"
                     f"<td class='v' style='color:{color[q['verdict']]}'>{q['verdict']}</td>"
                     f"<td>{esc(q['note'])}</td></tr>")
        p.append("</table>")
        for f in e["figures"]:
            data = base64.b64encode((Path(out_dir) / f).read_bytes()).decode("ascii")
            p.append(f"<figure><img alt='{esc(f)}' src='data:image/png;base64,{data}'>"
                     f"<figcaption>{esc(f)}</figcaption></figure>")
    p.append("</body></html>")
    return "\n".join(p) + "\n"


# --- docs/REPRODUCE.md -------------------------------------------------------------------
def write_docs(res, path=DOC_PATH):
    """docs/REPRODUCE.md from a run (figures named, not linked: they live in the run's folder)."""
    text = report_markdown(res, title="Reproduction report (generated)", figure_links=False)
    head, _, rest = text.partition("\n\n")
    text = (head + "\n\nGenerated by `python -m inskit.jobs.reproduce_all --write-docs`; do not edit. "
            "`tests/test_jobs_reproduce_all.py` reruns the experiments and fails when a figure here no longer "
            "matches within its tolerance. Timings are those of the generating machine.\n\n" + rest)
    return write_text(path, text)


def parse_report(text) -> dict:
    """The tables of a report (REPORT.md or docs/REPRODUCE.md): ``{experiment:
    [{quantity, unit, reference, ours, tolerance, verdict}, ...]}`` with ``ours``
    a float (or None) and ``tolerance`` the text of its column."""
    out, name, in_table = {}, None, False
    for line in text.splitlines():
        if line.startswith("## "):
            name, in_table = line[3:].strip(), False
            out[name] = []
        elif name and line.startswith(HEADER):
            in_table = True
        elif name and in_table and line.startswith("| ---"):
            continue
        elif name and in_table and line.startswith("|"):
            cells = [c.strip() for c in line.strip().strip("|").split("|")]
            if len(cells) != 7:
                raise ValueError(f"row of {name} has {len(cells)} cells, expected 7: {line}")
            out[name].append({"quantity": cells[0], "unit": cells[1], "reference": cells[2],
                              "ours": None if cells[3] == "-" else float(cells[3]), "tolerance": cells[4],
                              "verdict": cells[5]})
        elif in_table and not line.startswith("|"):
            in_table = False
    return out


def main(argv=None):
    """``python -m inskit.jobs.reproduce_all [--write-docs] [--out DIR] [--only a,b]``."""
    import argparse

    ap = argparse.ArgumentParser(prog="python -m inskit.jobs.reproduce_all")
    ap.add_argument("--out", default=str(ROOT / "out" / "reproduce"))
    ap.add_argument("--only")
    ap.add_argument("--write-docs", action="store_true", help="write docs/REPRODUCE.md from this run")
    a = ap.parse_args(argv)
    res = run_all(a.out, only=a.only, log=lambda s: print(s, file=sys.stderr, flush=True))
    if a.write_docs:
        print(f"wrote {write_docs(res)}", file=sys.stderr)
    return 1 if res["failed"] else 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
