"""GNSS constants: the values the signal-in-space interface documents fix.

The WGS84 ellipsoid and the navigation value of the Earth's rotation rate
live in :mod:`inskit.earth`; the values here are the ones the broadcast
orbit and clock algorithms require *exactly as the interface documents
state them* (they differ from the geodetic values in the last digits, and
using the wrong one moves a satellite by metres).

References
----------
IS-GPS-200N (2022), Table 20-IV and 20.3.3.3.3.1 (GM, Earth rate, F).
Galileo OS SIS ICD, Issue 2.0 (2021), Table 59 and 5.1.4/5.1.9 (GM, Earth rate).
RINEX 3.04 (IGS/RTCM 2018), Table A2 / section 5.1 (band numbers in
observation codes).
"""

from __future__ import annotations

import math

C = 299_792_458.0                    #: speed of light in vacuum [m/s] (IS-GPS-200 20.3.4.3)

GM_GPS = 3.986005e14                 #: WGS84 GM as used by GPS [m^3/s^2] (IS-GPS-200 Table 20-IV)
GM_GAL = 3.986004418e14              #: Earth's GM as used by Galileo [m^3/s^2] (OS SIS ICD Table 59)
OMEGA_E_GPS = 7.2921151467e-5        #: Earth rotation rate, GPS [rad/s] (IS-GPS-200 Table 20-IV)
OMEGA_E_GAL = 7.2921151467e-5        #: Earth rotation rate, Galileo [rad/s] (OS SIS ICD Table 59)

#: Relativistic clock constant F = -2 sqrt(GM) / c^2 [s/sqrt(m)]
#: (IS-GPS-200 20.3.3.3.3.1 gives -4.442807633e-10 for GPS).
F_REL_GPS = -2.0 * math.sqrt(GM_GPS) / C**2
F_REL_GAL = -2.0 * math.sqrt(GM_GAL) / C**2

SECONDS_PER_WEEK = 604_800.0
SECONDS_PER_DAY = 86_400.0
#: BeiDou Time = GPS Time - 14 s (BDS-SIS-ICD-B1I 3.0, 5.1.1 / RINEX 3.04 section 3.3).
BDT_MINUS_GPST_S = -14.0
#: Galileo System Time week number = GPS week number - 1024 (OS SIS ICD 5.1.2);
#: RINEX 3 writes the Galileo week continuous with the GPS week.
GAL_WEEK_OFFSET = 1024

# Carrier frequencies [Hz] (IS-GPS-200 3.3.1.1, IS-GPS-705, Galileo OS SIS ICD Table 2).
FREQ_L1 = 1575.42e6
FREQ_L2 = 1227.60e6
FREQ_L5 = 1176.45e6
FREQ_E1 = FREQ_L1
FREQ_E5A = FREQ_L5
FREQ_E5B = 1207.14e6
FREQ_E5 = 1191.795e6
FREQ_E6 = 1278.75e6

#: Band digit of a RINEX 3 observation code ('C1C' -> '1') to carrier frequency, per system.
BAND_FREQ = {
    "G": {"1": FREQ_L1, "2": FREQ_L2, "5": FREQ_L5},
    "E": {"1": FREQ_E1, "5": FREQ_E5A, "7": FREQ_E5B, "8": FREQ_E5, "6": FREQ_E6},
    "S": {"1": FREQ_L1, "5": FREQ_L5},
    "J": {"1": FREQ_L1, "2": FREQ_L2, "5": FREQ_L5, "6": FREQ_E6},
}


def frequency(system: str, code: str) -> float:
    """Carrier frequency [Hz] of a RINEX 3 observation code for a system.

    Parameters
    ----------
    system : str
        System letter, ``'G'``, ``'E'``, ``'S'`` or ``'J'``.
    code : str
        RINEX 3 observation code such as ``'C1C'``, ``'D1C'``, ``'L2L'``.

    Raises
    ------
    ConfigError
        When the band is not defined for that system (GLONASS FDMA bands
        depend on the channel number and are not supported).
    """
    from ..errors import ConfigError

    try:
        return BAND_FREQ[system][code[1]]
    except (KeyError, IndexError):
        raise ConfigError(
            f"observation code {code!r} has no known carrier frequency for system {system!r} "
            f"(known: {', '.join(f'{s}: ' + ''.join(sorted(b)) for s, b in BAND_FREQ.items())})"
        ) from None
