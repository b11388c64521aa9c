"""Unit conversion constants: multiply a value in the named unit to get SI.

``DEG`` is one degree in radians, so ``30 * DEG`` is 30 degrees in radians and
``x / DEG`` turns radians into degrees.  ``DEG_PER_HOUR`` is one deg/h in rad/s.
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
