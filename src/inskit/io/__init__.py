"""Reading and writing navigation data files.

Formats (all CSV with one header line; units are carried in column names):

* IMU: :func:`read_imu` / :func:`write_imu`
* GNSS fixes: :func:`read_gnss` / :func:`write_gnss`
* navigation solutions and truth: :func:`read_solution` / :func:`write_solution`

:func:`read_imu` and :func:`read_gnss` also read the other formats inskit
knows (the rtklibexplorer IMU log, RTKLIB ``.pos``), recognised by their
header (:mod:`.formats`); ``format=`` names one.

See ``docs/formats.md`` for the column lists.  Every reader validates what it
reads and raises :class:`~inskit.errors.InputError` with the file, the line or
column, and what was expected.
"""

from .csv_formats import (  # noqa: I001
    read_height,
    read_speed,
    read_speed_course,
    read_solution,
    write_gnss,
    write_imu,
    write_solution,
)
from .formats import read_gnss, read_imu

__all__ = ["read_gnss", "read_height", "read_imu", "read_solution", "read_speed", "read_speed_course", "write_gnss", "write_imu", "write_solution"]
