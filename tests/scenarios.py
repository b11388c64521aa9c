"""Scenario dicts the tests share (imported by name: pytest puts this folder on
``sys.path``).  One place for the short simulated car of Boulder that the
navigate, mounting, time-offset and vehicle-axes tests drive in their own ways."""

START = {"lat_deg": 40.0966, "lon_deg": -105.1474, "height_m": 1600.0}


def short_car(name, segments, lever_arm_b_m=(0.0, 0.0, -1.2)):
    """A 100 Hz industrial-MEMS car at :data:`START` with 1 Hz fixes (0.5 m
    horizontal, 1 m vertical white noise, no velocity) from an antenna at
    ``lever_arm_b_m`` (None: at the IMU), driving ``segments``."""
    gnss = {"rate_hz": 1.0, "white_h_m": 0.5, "white_v_m": 1.0, "velocity_sigma_m_s": 0.0}
    if lever_arm_b_m is not None:
        gnss["lever_arm_b_m"] = list(lever_arm_b_m)
    return {"name": name, "start": dict(START), "imu": {"rate_hz": 100.0, "grade": "industrial-mems"},
            "gnss": gnss, "segment": [dict(s) for s in segments]}


def write_drive(folder, scenario: dict, seed):
    """Simulate ``scenario`` (a dict such as :func:`short_car` makes) with
    ``seed`` and write its files (imu.csv, gnss.csv, truth.csv) into
    ``folder``, the simulator's warnings silenced; returns ``folder``."""
    import warnings

    from inskit.jobs.simulate import write_simulation
    from inskit.simulation.scenario import Scenario, simulate

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        write_simulation(simulate(Scenario.model_validate(scenario), seed=seed), folder, plot=False, overwrite=True)
    return folder
