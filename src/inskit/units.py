"""Unit conversion constants: multiply a value in the named unit to get SI.

``DEG`` is one degree in radians, so ``30 * DEG`` is 30 degrees in radians and
``x / DEG`` turns radians into degrees.  ``DEG_PER_HOUR`` is one deg/h in rad/s.

Also the sampling limits shared by the scenario files, the simulations and
the command line (:data:`MAX_RATE_HZ`, :data:`MAX_SAMPLES`): constants of the
lowest layer, so the command line's option types take them without importing
the simulation.
"""

import math

DEG = math.pi / 180.0
ARCMIN = DEG / 60.0
ARCSEC = DEG / 3600.0
HOUR = 3600.0
DEG_PER_S = DEG
DEG_PER_HOUR = DEG / HOUR
DEG_PER_SQRT_HOUR = DEG / math.sqrt(HOUR)
G0 = 9.80665  # standard gravity [m/s^2], used only to convert "g" units
MILLI_G = 1e-3 * G0
MICRO_G = 1e-6 * G0
MICRO_G_PER_SQRT_HZ = MICRO_G
PPM = 1e-6

#: The highest sampling rate [Hz] inskit simulates or writes: a scenario's ``[imu] rate_hz``, the
#: navigate config's ``[output] rate_hz`` and every rate option of the command line (``--rate``,
#: ``--truth-rate``, ``--output-rate``; ``--dt`` of ``inskit platform`` as its inverse, the shortest step).
MAX_RATE_HZ = 10_000  # an int: 10000, not 10000.0, in the messages and docs/config.md
#: The most samples one simulated series (IMU, truth, accelerometer array, platform epochs) may hold:
#: 1000 s at :data:`MAX_RATE_HZ`, 27.8 h at 100 Hz; about 10 GB of arrays in the simulations.  Beyond it a
#: rate times a duration is refused before any array is made.
MAX_SAMPLES = 10_000_000
#: The heights [m] a user gives (an initial state's, a held or aiding height, a height log's readings, a
#: scenario's start) lie within this many metres of the ellipsoid: the deepest trench and the highest aircraft
#: with room to spare.  Beyond it the number is a wrong unit or column (101325, a pressure in Pa; millimetres),
#: or, below -6.4e6 m, a point past the Earth's centre; taken in silence it sent a run off the Earth.
MAX_HEIGHT_M = 100_000.0
#: The velocity components [m/s] a solution or truth file may hold: below 100 km of height nothing moves at
#: the Earth's escape speed (11.2 km/s); beyond it the number is another unit or column (mm/s, a position),
#: and squared into the error statistics it made them infinite.
MAX_SPEED_M_S = 12_000.0
