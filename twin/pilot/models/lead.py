"""Lead information from the vestibular sensors through a motion system (§7.4, Eq 7.1-7.4).

The pilot generates lead from motion when the sensor's response to the felt motion acts as an
integrator of acceleration over the task's band: the semicircular canals for pitch (Eq 7.1,
7.2), the integrated otoliths for pitch-heave (Eq 7.3, 7.4). A motion system's platform filter
and delay add phase lag. The criterion used here, stated once for both thresholds and both
sensors: the lead channel's phase never lags an integrator's (-90 deg) by more than 45 deg
(halfway to the next order of lag: beyond it the channel is closer to a double integrator than
to an integrator) anywhere in the forcing-function band 0.06-2.8 Hz. The thresholds are the
lowest break frequency (no delay) and the largest delay (no filter) that meet it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import brentq

from twin.chain.config import MotionSystem
from twin.core.checks import number
from twin.core.errors import SignalError

FloatArray = NDArray[np.float64]

#: Forcing-function band of the pitch task [Hz] (§7.4) and the criterion [deg].
BAND_HZ = (0.06, 2.80)
INTEGRATOR_DEG = -90.0
MARGIN_DEG = 45.0
SENSORS = ("canals", "otoliths")


def sensor_response(sensor: str, f_hz: ArrayLike) -> NDArray[np.complex128]:
    """H_SCC of Eq 7.1 or (1/s) H_OTO of Eq 7.3 at ``f_hz``."""
    s = 2j * np.pi * np.asarray(f_hz, dtype=float)
    if sensor == "canals":
        return (1 + 0.11 * s) / ((1 + 5.9 * s) * (1 + 0.005 * s))
    if sensor == "otoliths":
        return (1 + s) / ((1 + 0.5 * s) * (1 + 0.016 * s)) / s
    raise ValueError(f"sensor must be one of {SENSORS}; got {sensor!r}")


def lead_phase_deg(
    sensor: str, break_hz: float | None, delay_s: float, f_hz: ArrayLike
) -> FloatArray:
    """Phase of the lead channel (sensor x platform filter x delay) [deg], continuous."""
    f = np.asarray(f_hz, dtype=float)
    phase = np.degrees(np.angle(sensor_response(sensor, f)))  # within (-180, 0] in the band
    phase = phase - 360.0 * f * delay_s
    if break_hz is not None:
        phase = phase - 2 * np.degrees(np.arctan(f / break_hz))
    return phase


def _worst(sensor: str, break_hz: float | None, delay_s: float) -> float:
    f = np.geomspace(*BAND_HZ, 400)
    return float(lead_phase_deg(sensor, break_hz, delay_s, f).min())


@dataclass(frozen=True)
class LeadAnalysis:
    """Thresholds and a configuration's standing for one sensor.

    Attributes
    ----------
    sensor : str
        ``canals`` or ``otoliths``.
    break_hz_threshold : float
        Lowest platform-filter break frequency meeting the criterion (no delay) [Hz].
    delay_threshold_s : float
        Largest delay meeting the criterion (no filter) [s].
    config_worst_phase_deg : float
        The configuration's lowest lead phase in the band [deg].
    config_meets : bool
        Whether the configuration meets the criterion.

    """

    sensor: str
    break_hz_threshold: float
    delay_threshold_s: float
    config_worst_phase_deg: float
    config_meets: bool


def analyse_lead(
    config: MotionSystem, sensor: str = "canals", margin_deg: float = MARGIN_DEG
) -> LeadAnalysis:
    """Thresholds of the criterion for ``sensor`` and where ``config`` stands.

    Raises
    ------
    SignalError
        For a ``margin_deg`` outside [0, 90] deg (0: the thesis' literal -90 deg; 90: a lag of
        180 deg, where a loop closed on the sensor has no phase left).

    """
    number(margin_deg, "margin_deg (lag allowed behind an integrator)", lo=0, hi=90,
           error=SignalError)  # fmt: skip
    limit = INTEGRATOR_DEG - margin_deg
    if _worst(sensor, None, 0.0) < limit:
        fb = tau = float("nan")  # the sensor alone already fails
    else:
        fb = brentq(lambda b: _worst(sensor, b, 0.0) - limit, 0.05, 1000.0)
        tau = brentq(lambda d: _worst(sensor, None, d) - limit, 0.0, 1.0)
    worst = _worst(sensor, config.filter_break_hz, config.delay_s)
    return LeadAnalysis(sensor, float(fb), float(tau), worst, worst >= limit)
