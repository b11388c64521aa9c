"""The Python face of inskit: what ``import inskit`` offers at the top.

Each function forwards to the job or reader the command line uses, so a
script and ``inskit navigate`` give the same numbers::

    import inskit

    imu = inskit.read_imu("data/drive_0708/imu_1934_gpst.csv.gz")   # format from the header
    run = inskit.navigate("examples/drive_0708.toml")                # nothing written to disk
    df = run.solution.to_dataframe()                                 # time_s, lat_deg, ... yaw_deg, sigmas
    run.health["verdict"]                                            # "healthy" or "unhealthy"

``docs/api.md`` walks through it.  The heavy libraries (numba, scipy,
pandas, matplotlib) are imported by the functions that need them, so
``import inskit`` stays cheap.
"""

from __future__ import annotations

import numbers
from dataclasses import dataclass, field
from pathlib import Path

from .errors import InputError, is_number
from .types import NavSolution


@dataclass
class NavigationRun:
    """What :func:`navigate` returns.

    Attributes
    ----------
    solution : NavSolution
        The smoothed solution when the run was smoothed, else the forward
        one, with its sigmas and estimates as ``extra`` columns (the columns
        of ``solution_forward.parquet``).
    forward : NavSolution
        The forward filter's solution.
    smoothed : NavSolution or None
        The RTS-smoothed solution (``smooth=True``).
    summary : dict
        Every figure of the run: the ``summary.json`` of ``inskit navigate``
        and the keys of ``inskit navigate --json`` (outage scores, update
        counts, start-up, final estimates, ``health``).
    files : list of Path
        The files written (empty unless ``out_dir`` was given).
    details : inskit.jobs.navigate.NavigateResult
        Everything else: the inputs as read, the filter output with its
        innovations, the settings, the outage windows.
    """

    solution: NavSolution
    forward: NavSolution
    smoothed: NavSolution | None
    summary: dict
    files: list = field(default_factory=list)
    details: object = None

    @property
    def health(self) -> dict:
        """The verdict on the run (``summary["health"]``): ``verdict``
        (``"healthy"`` / ``"unhealthy"``), ``reasons``, ``warnings``, and per
        measurement statistics (:func:`inskit.jobs.navigate.health`)."""
        return self.summary["health"]

    @property
    def config(self):
        """The validated configuration of the run (a ``NavigateConfig``)."""
        return self.details.config

    def to_dataframe(self):
        """``solution.to_dataframe()``: one row per IMU epoch, units in the
        column names."""
        return self.solution.to_dataframe()

    def __repr__(self):
        s = self.summary
        return (f"NavigationRun({s.get('name')!r}: {s.get('solution')} {s.get('scheme')} solution, "
                f"{len(self.solution)} epochs over {s.get('duration_s', 0.0):.1f} s, "
                f"health {self.health.get('verdict')!r}, {len(self.files)} files written)")


def _check_flag(name, value):
    """A keyword that is True or False (``smooth="no"`` is a non-empty string, so truthy)."""
    if not isinstance(value, bool) and not (hasattr(value, "dtype") and getattr(value, "dtype").kind == "b"):
        raise InputError(f"{name} must be True or False, got {value!r}")
    return bool(value)


def _check_path(name, value, also=""):
    """A file or folder argument: a str or a path-like object."""
    import os

    if not isinstance(value, (str, os.PathLike)):
        raise InputError(f"{name} must be a file path (str or Path){also}, got {type(value).__name__} {value!r}")
    return Path(value)


def _check_seed(seed):
    """A seed of :func:`simulate`: an int >= 0, None (fresh entropy) or a
    ``numpy.random.Generator`` (drawn from: :func:`inskit.simulation.scenario.simulate`)."""
    import numpy as np

    if seed is None or isinstance(seed, np.random.Generator):
        return seed
    if isinstance(seed, bool) or not isinstance(seed, numbers.Integral):
        raise InputError(f"seed must be an integer >= 0 or a numpy.random.Generator, got {type(seed).__name__} "
                         f"{seed!r}")
    if seed < 0:
        raise InputError(f"seed must be an integer >= 0 or a numpy.random.Generator, got {seed}")
    return int(seed)


def _config(config, overrides):
    from .jobs import config as C

    if isinstance(config, C.NavigateConfig):
        if not overrides:
            return config
        data = config.model_dump(exclude=set(C.INTERNAL_KEYS), exclude_unset=True)
        return C.config_from_dict(data, base_dir=config.base_dir, source=f"config {config.name!r}",
                                  overrides=overrides)
    if isinstance(config, dict):
        return C.config_from_dict(config, base_dir=Path.cwd(), source="config dict", overrides=overrides)
    if isinstance(config, (str, Path)):
        return C.load_config(config, overrides)
    raise InputError(f"navigate: expected a config file path, a dict or a NavigateConfig, got "
                     f"{type(config).__name__}")


def navigate(config, *, smooth=False, truth=None, out_dir=None, overwrite=False, progress=None, log=None,
             **overrides) -> NavigationRun:
    """INS/GNSS integration as ``inskit navigate`` runs it, from Python.

    Parameters
    ----------
    config : str, Path, dict or NavigateConfig
        A TOML config file (``docs/config.md``; relative paths in it are
        taken relative to the file), the same as a nested dict (relative
        paths then start in the working directory), or a validated config.
    smooth : bool
        Add the RTS smoother; ``solution`` and the top-level summary keys
        then describe the smoothed solution.
    truth : str, Path or NavSolution, optional
        A truth trajectory (instead of the config's ``[truth] file``): its
        errors are added to the summary (``truth_errors``) and the outages
        are scored against it too (``..._vs_truth_...`` keys), as with
        ``inskit navigate --truth``.
    out_dir : str, Path or True, optional
        Where to write what ``inskit navigate`` writes (solution Parquet and
        CSV, ``innovations.csv``, ``config_used.json``, plots unless
        ``[output] plots = false``, ``summary.json`` last); True: the
        config's ``[output] dir`` (``out/<name>`` without one).  Default
        None: nothing is written.
    overwrite : bool
        Write into an ``out_dir`` that already holds files (files of the
        same names are replaced, and the files an earlier run listed in its
        summary removed once the new set is in place, as ``--force`` does;
        other files stay).
    progress : callable, optional
        Called with the number of IMU epochs done, now and then.
    log : callable, optional
        Called with each warning line (IMU gaps, rate changes, yaw bank).
    **overrides
        Config sections to change, each a dict of keys, merged on top of the
        file: ``filter={"scheme": "open"}``, ``outages={"protocol": "none"}``,
        ``imu={"time_offset_s": -0.2}``.

    Returns
    -------
    NavigationRun

    Raises
    ------
    ConfigError, InputError
        A bad config (naming the key) or input file (naming file and line);
        an ``out_dir`` that is not empty without ``overwrite`` (the message
        says what it holds: an earlier run's results, or other files).
    """
    from . import io
    from .files import check_folder_writable
    from .jobs import navigate as N

    smooth, overwrite = _check_flag("smooth", smooth), _check_flag("overwrite", overwrite)
    if truth is not None and not isinstance(truth, NavSolution):
        truth = _check_path("truth", truth, " or a NavSolution")
    for name, f in (("progress", progress), ("log", log)):
        if f is not None and not callable(f):
            raise InputError(f"{name} must be a function (or None), got {type(f).__name__} {f!r}")
    if out_dir is not None and out_dir is not True and out_dir is not False:
        out_dir = _check_path("out_dir", out_dir, ", True or None")
    cfg = _config(config, overrides)
    target = None
    if out_dir is not None and out_dir is not False:
        if out_dir is True:
            target = cfg.resolve(cfg.output.dir) if cfg.output.dir else Path("out") / cfg.name
        else:
            target = out_dir
        occupied = None if overwrite else N.occupied_folder_message(target, "overwrite=True", "another out_dir")
        if occupied:
            raise InputError(occupied)
        given = [config if isinstance(config, (str, Path)) else None,
                 truth if not isinstance(truth, NavSolution) else None]  # the files given apart from the config's
        N.refuse_overwriting_inputs(cfg, target, given, overwrite, "overwrite=True", "another out_dir")
        check_folder_writable(target)  # before the computation, not after it; a file there: 'is a file; ...'
    if truth is not None and not isinstance(truth, NavSolution):
        truth = io.read_solution(truth)
    cfg, extra = N.calibrated_config(cfg, log=log)  # [imu] time_offset_search = "calibrate"
    res = N.run(cfg, smooth=smooth, progress=progress, log=log, truth=truth)
    s = N.summary(res)  # truth_errors and the outages scored against the truth, as with --truth
    s.update(extra)
    N.check_time_offset(res.config, s, log=log)  # unhealthy GNSS updates: is it the IMU's time tags?
    files = []
    if target is not None:
        files = N.write_outputs(res, target, s, replace_previous=overwrite)
    forward = res.forward.solution
    smoothed = res.smoothed.solution if res.smoothed is not None else None
    return NavigationRun(smoothed if smoothed is not None else forward, forward, smoothed, s, list(files), res)


def simulate(scenario, seed=0, *, truth_rate_hz=None, out_dir=None, overwrite=False, plot=False):
    """Simulate a scenario as ``inskit simulate`` does.

    Parameters
    ----------
    scenario : str, Path or Scenario
        A scenario TOML file (``docs/config.md``, "Scenario files") or a
        validated :class:`inskit.simulation.scenario.Scenario`.
    seed : int >= 0, None or numpy.random.Generator
        Seed of every random draw (same seed, same numbers; None: fresh
        entropy, another run every call).  A Generator is drawn from and
        advances (a second call with it gives another run); raw GNSS draws
        from a child it spawns.  A fresh ``numpy.random.default_rng(s)``
        gives the numbers of ``seed=s``, the files of ``inskit simulate
        --seed s``.
    truth_rate_hz : float, optional
        Rate of the truth (default: the IMU rate).
    out_dir : str or Path, optional
        Write ``imu.csv``, ``gnss.csv``, ``truth.csv`` (and the RINEX files
        of a ``[raw_gnss]`` scenario) there; default: nothing written.
    overwrite : bool
        Replace those files when they exist.
    plot : bool
        With ``out_dir``: also ``scenario.png``.

    Returns
    -------
    inskit.simulation.scenario.Simulation
        ``.truth`` (NavSolution), ``.imu`` and ``.imu_ideal`` (ImuData),
        ``.gnss`` (GnssData), ``.draws`` (the random errors drawn).
    """
    from .simulation.scenario import Scenario, load_scenario
    from .simulation.scenario import simulate as run

    seed = _check_seed(seed)
    overwrite, plot = _check_flag("overwrite", overwrite), _check_flag("plot", plot)
    if out_dir is not None:
        out_dir = _check_path("out_dir", out_dir, " or None")
    else:  # both were ignored without a word: nothing is written without out_dir
        for name, on in (("plot", plot), ("overwrite", overwrite)):
            if on:
                raise InputError(f"{name}=True would be ignored: without out_dir nothing is written (give "
                                 "out_dir=FOLDER for the files)")
    if truth_rate_hz is not None and not is_number(truth_rate_hz):
        raise InputError(f"truth_rate_hz must be a number [Hz] (or None), got {type(truth_rate_hz).__name__} "
                         f"{truth_rate_hz!r}")
    if not isinstance(scenario, Scenario):
        scenario = load_scenario(_check_path("scenario", scenario, " or a Scenario"))
    sim = run(scenario, seed, truth_rate_hz=truth_rate_hz)
    if out_dir is not None:
        from .jobs.simulate import write_simulation

        write_simulation(sim, out_dir, overwrite=overwrite, plot=plot)
    return sim


def mechanize(imu, initial, *, frame="ned", **options) -> NavSolution:
    """Free-inertial navigation (:func:`inskit.strapdown.mechanize`): IMU
    increments from an initial :class:`~inskit.types.NavState`, in the
    ``frame`` of ``"ned"``, ``"wander"``, ``"ecef"``, ``"inertial"``."""
    from .strapdown import mechanize as run

    return run(imu, initial, frame=frame, **options)
