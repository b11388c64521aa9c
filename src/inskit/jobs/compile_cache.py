"""Build the compile cache of every command at install time (``make install``).

inskit's per-epoch loops are compiled by numba with ``cache=True``: the
first run of a kernel compiles it (seconds) and writes the machine code
beside the source; every later run loads it.  ``make install`` used to run
only ``inskit navigate`` on the bundled drive, so the first ``inskit
simulate``, ``mechanize``, ``platform``, ``gyrofree``, ``align``, ``spp``
or tightly coupled run of a new user still compiled its kernels (issue 13:
no compile at run time).  :func:`warm` runs each command family once on
small inputs it makes itself (a two-minute car, a short static log, the
bundled RINEX sample), in child processes, two at a time (the kernels of
two commands compile in parallel on two cores), and discards the outputs.

``python -m inskit.jobs.compile_cache [--list]``: prints one line per command and
its time on stderr; exit status 1 when one failed (its stderr tail is
printed; the cache of the others is kept).
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

_ROOT = Path(__file__).resolve().parents[3]
_EX = _ROOT / "examples"
_DATA = _ROOT / "data"


def _short(toml: Path, seconds: float) -> str:
    """The scenario ``toml`` cut at ``seconds`` (``duration_limit_s``)."""
    text = toml.read_text()
    key = 'name = "'
    i = text.index(key)
    return text[:i] + f"duration_limit_s = {seconds}\n" + text[i:]


def steps(tmp: Path) -> list[list[tuple[str, list]]]:
    """The warm-up commands as groups (a group's commands run in order, one
    after the other: a later one reads what an earlier one wrote; the groups
    run in parallel)."""
    car = tmp / "car.toml"
    car.write_text(_short(_EX / "car.toml", 150.0))
    static = tmp / "static.toml"
    static.write_text(_short(_EX / "static.toml", 120.0))
    tcb = tmp / "tcb.toml"
    tcb.write_text(_short(_EX / "tc_blockage.toml", 60.0))
    sim, st, gf = tmp / "sim", tmp / "static", tmp / "gf"
    platform = ([(f"platform simulate --kind {k}", ["platform", "simulate", car, "--kind", k, "--out",
                                                  tmp / f"plat_{k}", "--no-plots", "--force", "--duration", "60"])
                 for k in ("semi-analytical", "analytical", "geometric")]
                + [("platform simulate --earth sphere", ["platform", "simulate", car, "--earth", "sphere", "--out",
                                                         tmp / "plat_sphere", "--no-plots", "--force",
                                                         "--duration", "60"])]
                + [(f"platform integrate --filter {f}", ["platform", "integrate", car, "--scheme", "closed",
                                                         "--filter", f, "--out", tmp / f"plati_{f}", "--no-plots",
                                                         "--force", "--duration", "60"])
                   for f in ("kalman", "first-order", "second-order")])
    groups = [
        [("navigate (the bundled drive: filter, smoother, plots, matplotlib's font cache)",
          ["navigate", _EX / "drive_0708.toml", "--out", tmp / "nav", "--force", "--smooth"]),
         ("navigate, tightly coupled (pseudoranges and Doppler from RINEX)",
          ["navigate", _EX / "walk_0827_tight.toml", "--out", tmp / "tight", "--force", "--no-plots"]),
         ("spp", ["spp", _DATA / "abpo" / "abpo0080.15o.gz", _DATA / "abpo" / "abpo0080.15n.gz",
                  "--reference", "header", "--out", tmp / "spp", "--force"]),
         ("simulate with raw GNSS", ["simulate", tcb, "--out", tmp / "tcb", "--no-plot", "--force"])]
        + platform,
        [("simulate", ["simulate", car, "--out", sim, "--no-plot", "--force", "--seed", "1"])]
        + [(f"mechanize --frame {f}", ["mechanize", sim / "imu.csv", "--init-from", sim / "truth.csv",
                                       "--frame", f, "--out", tmp / f"mech_{f}.csv", "--force"])
           for f in ("ned", "wander", "ecef", "inertial")]
        + [("evaluate", ["evaluate", tmp / "mech_ned.csv", sim / "truth.csv"]),
           ("schemes", ["schemes", car, "--outage", "60,90", "--json"]),
           ("simulate a static log", ["simulate", static, "--out", st, "--no-plot", "--force"])]
        + [(f"align --method {m}", ["align", st / "imu.csv", "--lat", "45", "--method", m])
           for m in ("accel", "gyro", "blend", "fine")]
        + [("allan", ["allan", st / "imu.csv"]),
           ("gyrofree simulate", ["gyrofree", "simulate", "source003", "--layout", "ten", "--out", gf,
                                  "--duration", "2"]),
           ("gyrofree navigate", ["gyrofree", "navigate", gf / "array.csv", "--layout", "ten", "--init-from",
                                  gf / "truth.csv", "--out", tmp / "gfn"]),
           ("gyrofree navigate --solver least-squares",
            ["gyrofree", "navigate", gf / "array.csv", "--layout", "ten", "--init-from", gf / "truth.csv",
             "--solver", "least-squares", "--out", tmp / "gfn_lsq"])],
    ]
    return groups


def _run(label, args):
    t0 = time.perf_counter()
    p = subprocess.run([sys.executable, "-m", "inskit.cli", *map(str, args)], capture_output=True, text=True)
    return label, args, p.returncode, time.perf_counter() - t0, p.stderr


def warm(log=None) -> list:
    """Run every warm-up command (:func:`steps`); returns ``(label,
    returncode, seconds, stderr)`` per command; ``log(line)`` is called as
    each ends."""
    out = []
    with tempfile.TemporaryDirectory(prefix="inskit-warm-") as d:
        groups = steps(Path(d))

        def group(cmds):
            res = []
            for label, args in cmds:
                r = _run(label, args)
                if log:
                    log(f"  {r[3]:5.1f} s  {label}" + ("" if r[2] == 0 else f"  FAILED ({r[2]})"))
                res.append(r)
            return res

        with ThreadPoolExecutor(max_workers=2) as pool:
            for res in pool.map(group, groups):
                out += res
    return out


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if "--list" in argv:
        with tempfile.TemporaryDirectory() as d:
            for g in steps(Path(d)):
                for label, args in g:
                    print(f"inskit {' '.join(map(str, args))}    # {label}")
        return 0
    t0 = time.perf_counter()
    res = warm(log=lambda s: print(s, file=sys.stderr, flush=True))
    bad = [r for r in res if r[2] != 0]
    for label, args, code, _, err in bad:
        print(f"warm-up failed: inskit {' '.join(map(str, args))} ({label}), exit {code}:\n{err[-1500:]}",
              file=sys.stderr)
    print(f"compile cache built: {len(res) - len(bad)} of {len(res)} commands in {time.perf_counter() - t0:.0f} s",
          file=sys.stderr)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
