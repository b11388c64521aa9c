"""End-to-end figures of ``inskit bench``: the user's commands, timed whole.

What a user times is the command: start-up and imports, reading, the
filter, writing.  Each figure here runs the command line itself in a child
process (``python -m inskit.cli ...``) on a simulated drive written to a
cache folder once, and reports the median of the repeats with the spread
(slowest, fastest) and the child's own peak resident memory
(read from the child's ``/proc/self/status`` at its exit).

* ``navigate_cli_epochs_per_s``: ``inskit navigate`` on 1 h of a car at
  200 Hz (IMU CSV read, 21-state closed-loop filter with Gauss-Markov
  biases, ZUPT and NHC at 10 Hz, 1 Hz GNSS, the full-rate Parquet solution
  written, no plots), IMU epochs per second of wall time;
  ``navigate_peak_rss_mb``.
* ``simulate_cli_epochs_per_s``: ``inskit simulate`` of the same hour of
  car (``car.toml``, segments repeated, ``duration_limit_s``) at 100 Hz writing Parquet (``--format parquet --no-plot``).
* ``simulate_cli_floor_s`` (:func:`simulate_floor`): the interpreter, the
  libraries that command cannot do without and the writing of its own three
  Parquet tables, with no simulation: the time no implementation goes below
  here, beside ``simulate_cli_wall_s``.
* ``mechanize_cli_epochs_per_s``: ``inskit mechanize`` of that 100 Hz IMU
  file from the truth's first state, writing the solution CSV.

Quick mode (the tests) uses 120 s instead of an hour.  ``inskit bench
--long`` (:func:`long_benchmarks`) times navigate alone on 1, 4 and 8 hours
(forward and smoothed, wall time and peak memory per length).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from .. import __version__

_EXAMPLES = Path(__file__).resolve().parents[3] / "examples"

NAV_CONFIG = """# written by inskit bench: the end-to-end navigate figure
name = "bench_drive"
[imu]
file = "imu.csv"
format = "inskit"
[gnss]
file = "gnss.csv"
format = "inskit"
lever_arm_b_m = [0.0, 0.0, -1.2]
[constraints]
zupt = true
nhc = true
rate_hz = 10.0
[filter]
scheme = "closed"
scale_factors = true
[outages]
protocol = "none"
[output]
format = "parquet"
plots = false
"""


def cache_dir() -> Path:
    """Folder of the generated bench drives (``$INSKIT_BENCH_CACHE``, else
    ``$XDG_CACHE_HOME/inskit/bench``, else ``~/.cache/inskit/bench``)."""
    d = os.environ.get("INSKIT_BENCH_CACHE")
    if d:
        return Path(d)
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "inskit" / "bench"


def bench_drive(duration_s: float, rate_hz: float, root: Path | None = None) -> Path:
    """The car scenario (``examples/car.toml``, its segments repeated) cut at
    ``duration_s`` and sampled at ``rate_hz``, written once as CSV (imu,
    gnss, truth) with the navigate config beside it; returns the folder."""
    from ..simulation.scenario import load_scenario, simulate
    from .simulate import write_simulation

    import hashlib

    root = cache_dir() if root is None else Path(root)
    # keyed on what makes the files (the scenario, the navigate config, the simulator's and writers' code), so a
    # change of any of them makes new files rather than reusing stale ones
    src = Path(__file__).resolve().parents[1]
    h = hashlib.sha256((_EXAMPLES / "car.toml").read_bytes() + NAV_CONFIG.encode())
    for f in sorted((src / "simulation").glob("*.py")) + [src / "io" / "csv_formats.py", src / "files.py"]:
        h.update(f.read_bytes())
    d = root / f"car_{duration_s:g}s_{rate_hz:g}hz_v{__version__}_{h.hexdigest()[:12]}"
    if (d / "done").is_file():
        return d
    sc = load_scenario(_EXAMPLES / "car.toml")
    reps = int(np.ceil(duration_s / 1800.0)) + 1
    sc = sc.model_copy(update={"duration_limit_s": float(duration_s), "segment": list(sc.segment) * reps,
                               "imu": sc.imu.model_copy(update={"rate_hz": float(rate_hz)})})
    sim = simulate(sc, seed=1)
    write_simulation(sim, d, overwrite=True, plot=False)
    (d / "navigate.toml").write_text(NAV_CONFIG)
    (d / "done").write_text("ok\n")
    return d


#: the child's own high-water mark at exit: VmHWM of /proc/self/status belongs to the
#: process image after exec (getrusage's maxrss may still hold the parent's, copied by fork)
_WRAP = """
import atexit, resource, sys
def _hwm():
    try:
        kb = [l for l in open("/proc/self/status") if l.startswith("VmHWM:")][0].split()[1]
    except (OSError, IndexError):
        kb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    sys.stderr.write("\\n__inskit_peak_rss_kib__ %s\\n" % kb)
atexit.register(_hwm)
from inskit.cli import main
sys.argv = ["inskit"] + sys.argv[1:]
main()
"""


def _run_timed(args, cwd=None):
    """Run ``inskit ARGS`` in a child process; return (wall s, the child's
    own peak RSS in MiB, stdout)."""
    t0 = time.perf_counter()
    p = subprocess.run([sys.executable, "-c", _WRAP, *map(str, args)], cwd=cwd, capture_output=True)
    wall = time.perf_counter() - t0
    err = p.stderr.decode(errors="replace")
    if p.returncode != 0:
        raise RuntimeError(f"inskit {' '.join(map(str, args))} failed ({p.returncode}): {err[-500:]}")
    kib = [ln.split()[1] for ln in err.splitlines() if ln.startswith("__inskit_peak_rss_kib__")]
    return wall, float(kib[-1]) / 1024.0 if kib else float("nan"), p.stdout.decode()


def _scenario_text(duration_s):
    """``examples/car.toml`` with its segments repeated and cut at ``duration_s``."""
    text = (_EXAMPLES / "car.toml").read_text()
    seg = text[text.index("[[segment]]"):]
    reps = int(np.ceil(duration_s / 1800.0))
    return text.replace('name = "car"', f'name = "car"\nduration_limit_s = {duration_s}', 1) + ("\n" + seg) * reps


def _measure(name, args, n, repeats, out):
    """Time ``inskit ARGS`` ``repeats`` times after a warm-up run (compile and
    page caches); put ``<name>_cli_epochs_per_s`` (median, with its spread),
    ``<name>_cli_wall_s`` and ``<name>_peak_rss_mb`` into ``out``; return the
    last run's stdout."""
    _run_timed(args)
    runs = [_run_timed(args) for _ in range(repeats)]
    walls = [r[0] for r in runs]
    rates = [n / w for w in walls]
    key = f"{name}_cli_epochs_per_s"
    out[key] = round(float(np.median(rates)))
    out[f"{key}_spread"] = [round(min(rates)), round(max(rates))]
    out[f"{name}_cli_wall_s"] = round(float(np.median(walls)), 3)
    out[f"{name}_peak_rss_mb"] = round(max(r[1] for r in runs), 1)
    return runs[-1][2]


#: the floor of ``inskit simulate --format parquet``: a child that starts the interpreter, imports the libraries
#: the command cannot do without (numpy, pyarrow's Parquet writer, pydantic for the scenario, click, tomllib; not
#: numba, not inskit) and writes the command's own three tables with the writer's own settings
_FLOOR = """
import sys, time
t_start = float(sys.argv[1])
import json, tomllib
import numpy, click, pydantic
import pyarrow as pa, pyarrow.parquet as pq
t_import = time.time() - t_start
src, dst = sys.argv[2], sys.argv[3]
tables = [(name, pq.read_table(src + "/" + name)) for name in ("imu.parquet", "gnss.parquet", "truth.parquet")]
tables = [(n, pa.table({c: t.column(c).to_numpy() for c in t.column_names}, schema=t.schema)) for n, t in tables]
t0 = time.perf_counter()
for name, t in tables:
    pq.write_table(t, dst + "/" + name, compression="zstd", use_dictionary=False, use_byte_stream_split=True,
                   write_page_checksum=True)
print(json.dumps({"import_s": t_import, "write_s": time.perf_counter() - t0}))
"""


def simulate_floor(sim_dir: Path, n: int, repeats: int) -> dict:
    """What no implementation of ``inskit simulate --format parquet`` can go
    below on this machine (``_FLOOR``): the interpreter's start with the
    imports of the libraries it cannot do without, plus writing the
    command's own three Parquet tables (``sim_dir``: its last run) with the
    writer's settings; the simulation itself counts zero.  Medians of
    ``repeats`` runs after one warm-up: ``simulate_cli_floor_import_s``,
    ``simulate_cli_floor_write_s``, their sum ``simulate_cli_floor_s`` and
    the rate it would allow, ``simulate_cli_floor_epochs_per_s``."""
    import shutil

    dst = Path(tempfile.mkdtemp(prefix="inskit-floor-"))
    try:
        runs = []
        for _ in range(repeats + 1):
            p = subprocess.run([sys.executable, "-c", _FLOOR, repr(time.time()), str(sim_dir), str(dst)],
                               capture_output=True, check=True)
            runs.append(json.loads(p.stdout))
    finally:
        shutil.rmtree(dst, ignore_errors=True)
    imp = float(np.median([r["import_s"] for r in runs[1:]]))
    wr = float(np.median([r["write_s"] for r in runs[1:]]))
    return {"simulate_cli_floor_import_s": round(imp, 3), "simulate_cli_floor_write_s": round(wr, 3),
            "simulate_cli_floor_s": round(imp + wr, 3), "simulate_cli_floor_epochs_per_s": round(n / (imp + wr))}


def cli_benchmarks(quick=False, repeats=3, progress=None, root=None) -> dict:
    """The end-to-end figures (see the module docstring) as a flat dict."""
    if not (_EXAMPLES / "car.toml").is_file():
        return {"cli_note": "examples/car.toml not found (run from a source checkout)"}
    duration = 120.0 if quick else 3600.0
    out = {"cli_duration_s": duration}
    d200 = bench_drive(duration, 200.0, root)
    d100 = bench_drive(duration, 100.0, root)
    if progress:
        progress("bench drives")
    n200 = int(round(duration * 200.0))
    n100 = int(round(duration * 100.0))
    with tempfile.TemporaryDirectory(prefix="inskit-bench-") as tmp:
        nav = ["navigate", d200 / "navigate.toml", "--out", Path(tmp) / "nav", "--force", "--no-plots", "--json"]
        s = json.loads(_measure("navigate", nav, n200, repeats, out))
        out["navigate_cli_imu_rate_hz"] = 200.0
        out["navigate_cli_fixes_used"] = s["measurements"]["gnss_pos"]["used"]
        if progress:
            progress("navigate")
        cut = Path(tmp) / "car_1h.toml"
        cut.write_text(_scenario_text(duration))
        sim = ["simulate", cut, "--out", Path(tmp) / "sim", "--force", "--no-plot", "--format", "parquet", "--seed", "1"]
        _measure("simulate", sim, n100, repeats, out)
        out.update(simulate_floor(Path(tmp) / "sim", n100, repeats))
        if progress:
            progress("simulate")
        mech = ["mechanize", d100 / "imu.csv", "--init-from", d100 / "truth.csv", "--out", Path(tmp) / "mech.csv",
                "--force", "--json"]
        _measure("mechanize", mech, n100, repeats, out)
        if progress:
            progress("mechanize")
    return out


def long_benchmarks(hours=(1, 4, 8), progress=None, root=None) -> dict:
    """``inskit bench --long``: ``inskit navigate`` (forward, then with
    ``--smooth``) on 1, 4 and 8 hours of the 200 Hz car with 1 Hz GNSS, ZUPT
    and NHC at 10 Hz, one run each after a warm-up run on the hour: wall
    time, the child's peak RSS and the wall time per hour (a run linear in
    the log's length keeps it flat).  The drives are simulated once into the
    cache (8 h: 0.8 GB of IMU CSV and 1.6 GB of truth); the runs write 1.4 GB
    of Parquet into a temporary folder.  ``navigate_long_forward_rss_mb_per_hour``
    and ``navigate_long_smoothed_rss_mb_per_hour``: the peak RSS [MiB] each hour
    of log adds, between the shortest and the longest (0 for a run whose
    memory is bounded; the IMU log is held whole, 40 MB per hour at 200 Hz)."""
    if not (_EXAMPLES / "car.toml").is_file():
        return {"long_note": "examples/car.toml not found (run from a source checkout)"}
    rows = []
    with tempfile.TemporaryDirectory(prefix="inskit-bench-long-") as tmp:
        for i, h in enumerate(hours):
            d = bench_drive(3600.0 * h, 200.0, root)
            base = ["navigate", d / "navigate.toml", "--out", Path(tmp) / "nav", "--force", "--no-plots", "--json"]
            if i == 0:
                _run_timed(base)  # warm-up: compile and page caches
            wf, rf, out = _run_timed(base)
            ws, rs, _ = _run_timed(base + ["--smooth"])
            rows.append({"hours": h, "epochs": int(json.loads(out)["epochs"]),
                         "forward_wall_s": round(wf, 2), "forward_peak_rss_mb": round(rf, 1),
                         "smoothed_wall_s": round(ws, 2), "smoothed_peak_rss_mb": round(rs, 1),
                         "forward_s_per_hour": round(wf / h, 2), "smoothed_s_per_hour": round(ws / h, 2)})
            if progress:
                progress(f"navigate {h} h")
    out = {"navigate_long": rows}
    if len(rows) >= 2:  # memory a longer log adds: flat (0) when the run's memory is bounded
        a, b = rows[0], rows[-1]
        span = b["hours"] - a["hours"]
        out["navigate_long_forward_rss_mb_per_hour"] = round(
            (b["forward_peak_rss_mb"] - a["forward_peak_rss_mb"]) / span, 1)
        out["navigate_long_smoothed_rss_mb_per_hour"] = round(
            (b["smoothed_peak_rss_mb"] - a["smoothed_peak_rss_mb"]) / span, 1)
    return out
