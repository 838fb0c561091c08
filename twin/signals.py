"""Command signals: the fade of Eq 3.1, the multi-sines of Eq 5.2 / Table 5.2, built-ins.

Signals are pose-offset trajectories (:class:`twin.trajectory.Trajectory`) in the thesis base
frame, sampled at the command rate. Multi-sine amplitudes are given in acceleration (Table 5.2)
and integrated analytically to position, as the thesis does.

Examples
--------
>>> sig = describing_signal(2, "pitch")
>>> sig.commands.rate_hz, sig.window, sig.frequencies_hz[-1]
(100.0, (7.0, 27.0), 7.1)

"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from twin.errors import SignalError
from twin.frames import DOF_NAMES
from twin.thesis import TABLE_5_2
from twin.trajectory import Trajectory

FloatArray = NDArray[np.float64]

#: Length of the describing-function measurement window [s]: every Table 5.2 frequency is a
#: multiple of 0.05 Hz, so 20 s holds an integer number of periods of each.
WINDOW_S = 20.0


def fade(t: ArrayLike, f_fade: float, fade_out_at: float | None = None) -> FloatArray:
    """Fade-in (and optional fade-out) window of Eq 3.1.

    Parameters
    ----------
    t : array_like
        Times [s] from the start of the signal.
    f_fade : float
        Fade frequency f_f [Hz] (Eq 3.2: half the driving frequency); the fade lasts
        1 / (2 f_f) s.
    fade_out_at : float, optional
        Time at which the fade-out ends (the mirror image of the fade-in).

    Returns
    -------
    ndarray
        Window values in [0, 1].

    """
    tt = np.asarray(t, dtype=float)
    length = 0.5 / f_fade
    w = np.where(tt < length, 0.5 - 0.5 * np.cos(2 * np.pi * f_fade * np.clip(tt, 0, None)), 1.0)
    w = np.where(tt < 0, 0.0, w)
    if fade_out_at is not None:
        w = w * fade(fade_out_at - tt, f_fade)
    return w


@dataclass(frozen=True)
class MultiSine:
    """A sum of sines specified in acceleration (Eq 5.2).

    Attributes
    ----------
    frequencies_hz : ndarray
        Frequencies [Hz].
    amplitudes : ndarray
        Acceleration amplitudes [m/s^2 or rad/s^2].

    """

    frequencies_hz: FloatArray
    amplitudes: FloatArray

    def acceleration(self, t: ArrayLike) -> FloatArray:
        """Return u(t) of Eq 5.2 [m/s^2 or rad/s^2]."""
        w = 2 * np.pi * self.frequencies_hz
        return np.sin(np.multiply.outer(np.asarray(t, float), w)) @ self.amplitudes

    def position(self, t: ArrayLike) -> FloatArray:
        """Return the double integral of u(t) with zero mean [m or rad]."""
        w = 2 * np.pi * self.frequencies_hz
        return -np.sin(np.multiply.outer(np.asarray(t, float), w)) @ (self.amplitudes / w**2)

    def position_amplitudes(self) -> FloatArray:
        """Return the position amplitude of each sine [m or rad]."""
        return self.amplitudes / (2 * np.pi * self.frequencies_hz) ** 2


#: Signal 3 is the twin's own (not in the thesis): it extends the Table 5.2 frequencies to
#: 10 Hz, the upper end of the MPI model's frequency range of interest (§5.5.1), with the
#: largest Table 5.2 amplitudes.
EXTENSION_SIGNAL = {
    "frequency_hz": (4.50, 8.50, 10.00),
    "translation_m_s2": (0.200, 0.200, 0.200),
    "rotation_deg_s2": (57.296, 57.296, 57.296),
}
SIGNALS = {**TABLE_5_2, 3: EXTENSION_SIGNAL}


def table_5_2(signal: int, dof: str) -> MultiSine:
    """Return multi-sine ``signal`` for a DOF in SI units: 1 and 2 of Table 5.2, or 3."""
    if signal not in SIGNALS:
        raise SignalError(
            f"multi-sine signals are 1 and 2 (Table 5.2) and 3 (to 10 Hz); got {signal!r}"
        )
    if dof not in DOF_NAMES:
        raise SignalError(f"unknown DOF {dof!r}; expected one of {', '.join(DOF_NAMES)}")
    row = SIGNALS[signal]
    rotational = DOF_NAMES.index(dof) >= 3
    amps = np.radians(row["rotation_deg_s2"]) if rotational else np.array(row["translation_m_s2"])
    return MultiSine(np.array(row["frequency_hz"]), np.asarray(amps, dtype=float))


@dataclass(frozen=True)
class DescribingSignal:
    """Commands for one describing-function measurement and where to analyse them.

    Attributes
    ----------
    commands : Trajectory
        Pose-offset commands (only ``dof`` moves).
    dof : str
        Driven degree of freedom.
    frequencies_hz : ndarray
        The excited frequencies.
    window : tuple of float
        Start and end [s] of the periodic part to analyse (``WINDOW_S`` long).

    """

    commands: Trajectory
    dof: str
    frequencies_hz: FloatArray
    window: tuple[float, float]


def describing_signal(
    signal: int, dof: str, rate_hz: float = 100.0, settle_s: float = 2.0, scale: float = 1.0
) -> DescribingSignal:
    """Build a Table 5.2 multi-sine run for one DOF: fade-in, settle, 20 s window, fade-out.

    The fade (Eq 3.1) uses the lowest frequency of the signal (f_f = f_min / 2, Eq 3.2) and
    multiplies the whole position signal, so position, velocity and acceleration start and
    end at zero. The window starts ``settle_s`` after the fade-in so that filters have settled.

    Parameters
    ----------
    signal : int
        1 or 2 (Table 5.2), or 3 (:data:`EXTENSION_SIGNAL`).
    dof : str
        One of :data:`twin.frames.DOF_NAMES`.
    rate_hz : float
        Command rate [Hz].
    settle_s : float
        Time between the end of the fade-in and the start of the window [s].
    scale : float
        Factor on all amplitudes (1 = Table 5.2).

    """
    ms = table_5_2(signal, dof)
    ms = MultiSine(ms.frequencies_hz, ms.amplitudes * scale)
    f_fade = ms.frequencies_hz.min() / 2
    fade_len = 0.5 / f_fade
    start = fade_len + settle_s
    end = start + WINDOW_S
    total = end + fade_len
    n = round(total * rate_hz) + 1
    t = np.arange(n) / rate_hz
    values = np.zeros((n, 6))
    values[:, DOF_NAMES.index(dof)] = ms.position(t) * fade(t, f_fade, fade_out_at=total)
    return DescribingSignal(Trajectory(rate_hz, values), dof, ms.frequencies_hz, (start, end))


def rest(duration_s: float, rate_hz: float = 100.0) -> Trajectory:
    """Return neutral-pose commands for ``duration_s`` seconds."""
    if not np.isfinite(duration_s) or duration_s <= 0:
        raise SignalError(f"rest duration must be a positive number of seconds; got {duration_s}")
    return Trajectory(rate_hz, np.zeros((round(duration_s * rate_hz) + 1, 6)))


_BUILTIN = re.compile(r"^(?:multisine(?P<sig>[123])-(?P<dof>[a-z]+)|rest-(?P<dur>[0-9.]+))$")

#: Help text listing the built-in signal names.
BUILTIN_HELP = (
    "multisine1-DOF or multisine2-DOF (Table 5.2), multisine3-DOF (4.5-10 Hz), DOF one of "
    + ", ".join(DOF_NAMES)
    + ", or rest-SECONDS"
)


def builtin_signal(name: str, rate_hz: float = 100.0) -> Trajectory:
    """Return a built-in command signal by name.

    Parameters
    ----------
    name : str
        ``multisine1-<dof>``, ``multisine2-<dof>`` (Table 5.2 describing-function signals with
        fades), ``multisine3-<dof>`` (4.5, 8.5, 10 Hz) or ``rest-<seconds>``.
    rate_hz : float
        Command rate [Hz].

    Raises
    ------
    SignalError
        For an unknown name.

    """
    m = _BUILTIN.match(name)
    if m is None or (m["dof"] is not None and m["dof"] not in DOF_NAMES):
        raise SignalError(f"unknown signal {name!r}; built-in signals are {BUILTIN_HELP}")
    if m["dur"] is not None:
        return rest(float(m["dur"]), rate_hz)
    return describing_signal(int(m["sig"]), m["dof"], rate_hz).commands
