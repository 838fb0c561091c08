"""Command signals of the AGARD-AR-144 tests (§3.2.3) and the describing functions (§5.3.1).

Signals are pose-offset trajectories (:class:`twin.chain.trajectory.Trajectory`) in the thesis base
frame, sampled at the command rate. Every periodic signal has the phases of §3.2.3: fade-in
(Eq 3.1, fade frequency half the lowest frequency present, Eq 3.2), pre-measurement (Eq 3.3
periods of the lowest frequency), the measurement window (an integer number of periods of
every frequency present) and fade-out. Amplitudes are given in acceleration and integrated
analytically to position, as the thesis does: single sines (Eq 3.4), multi-sines (Eq 3.5;
Table 5.2's two signals), and the square-wave acceleration steps of the dynamic threshold test
(Fig 3.2b). :func:`check_signal` says which platform limit a signal would break before it is
run.

Examples
--------
>>> sig = describing_signal(2, "pitch")
>>> sig.commands.rate_hz, sig.window, float(sig.frequencies_hz[-1])
(100.0, (7.0, 27.0), 7.1)

"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from twin.chain.trajectory import Trajectory
from twin.core.checks import check_duration, number
from twin.core.errors import SignalError, SignalLimitError
from twin.core.frames import DOF_NAMES, acceleration_unit, dof_index
from twin.core.thesis import TABLE_5_2

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
    rotational = dof_index(dof) >= 3
    amps = np.radians(row["rotation_deg_s2"]) if rotational else np.array(row["translation_m_s2"])
    return MultiSine(np.array(row["frequency_hz"]), np.asarray(amps, dtype=float))


@dataclass(frozen=True)
class DescribingSignal:
    """A periodic test signal in one DOF and where to analyse it.

    Attributes
    ----------
    commands : Trajectory
        Pose-offset commands (only ``dof`` moves).
    dof : str
        Driven degree of freedom.
    frequencies_hz : ndarray
        The excited frequencies.
    window : tuple of float
        Start and end [s] of the measurement window (an integer number of periods of every
        excited frequency).
    amplitudes : ndarray or None
        Acceleration amplitude of each frequency [m/s^2 or rad/s^2].
    label : str
        Short description for reports.

    """

    commands: Trajectory
    dof: str
    frequencies_hz: FloatArray
    window: tuple[float, float]
    amplitudes: FloatArray | None = None
    label: str = ""


def premeasurement_periods(f_hz: float) -> int:
    """Return the pre-measurement periods N_p of Eq 3.3 for the (lowest) frequency ``f_hz``."""
    return 2 if f_hz < 0.5 else 5 if f_hz < 2.0 else 10


def base_frequency(frequencies_hz: ArrayLike, resolution_hz: float = 1e-4) -> float:
    """Greatest common divisor of the frequencies (to ``resolution_hz``) [Hz].

    A window of ``k / base_frequency`` seconds holds an integer number of periods of every
    frequency (§3.2.3.3: the frequencies are multiples of the base frequency 1 / t_m).
    """
    ticks = np.round(np.asarray(frequencies_hz, dtype=float) / resolution_hz).astype(np.int64)
    if np.any(ticks <= 0):
        raise SignalError(f"frequencies must be >= {resolution_hz} Hz; got {frequencies_hz}")
    return float(np.gcd.reduce(ticks)) * resolution_hz


def periodic_signal(
    ms: MultiSine,
    dof: str,
    rate_hz: float = 100.0,
    settle_s: float | None = None,
    window_s: float = WINDOW_S,
    label: str = "",
) -> DescribingSignal:
    """Build a periodic run in one DOF: fade-in, pre-measurement, window, fade-out (§3.2.3).

    The fade (Eq 3.1) uses the lowest frequency (f_f = f_min / 2, Eq 3.2) and multiplies the
    whole position signal, so position, velocity and acceleration start and end at zero.

    Parameters
    ----------
    ms : MultiSine
        Frequencies and acceleration amplitudes (one frequency: a single sine, Eq 3.4).
    dof : str
        One of :data:`twin.core.frames.DOF_NAMES`.
    rate_hz : float
        Command rate [Hz].
    settle_s : float, optional
        Pre-measurement time [s]; Eq 3.3 (N_p periods of the lowest frequency) by default.
    window_s : float
        Shortest measurement window [s]; rounded up to whole periods of the base frequency.
    label : str
        Description for reports.

    """
    if dof not in DOF_NAMES:
        raise SignalError(f"unknown DOF {dof!r}; expected one of {', '.join(DOF_NAMES)}")
    f = np.asarray(ms.frequencies_hz, dtype=float)
    amps = np.asarray(ms.amplitudes, dtype=float)
    if f.size == 0 or f.shape != amps.shape or not np.all(np.isfinite(f) & np.isfinite(amps)):
        raise SignalError("a periodic signal needs finite frequencies and amplitudes, one each")
    if np.any(f <= 0) or np.any(f >= rate_hz / 2):
        raise SignalError(
            f"frequencies must lie between 0 and the Nyquist frequency {rate_hz / 2:g} Hz; "
            f"got {f.tolist()}"
        )
    f_min = float(f.min())
    period = 1.0 / base_frequency(f)
    window = period * max(1, int(np.ceil(window_s / period - 1e-9)))
    fade_len = 1.0 / f_min  # 1 / (2 f_f) with f_f = f_min / 2
    settle = premeasurement_periods(f_min) / f_min if settle_s is None else float(settle_s)
    start = fade_len + settle
    end = start + window
    total = end + fade_len
    n = round(total * rate_hz) + 1
    t = np.arange(n) / rate_hz
    values = np.zeros((n, 6))
    values[:, dof_index(dof)] = ms.position(t) * fade(t, f_min / 2, fade_out_at=total)
    return DescribingSignal(Trajectory(rate_hz, values), dof, f, (start, end), amps, label)


def describing_signal(
    signal: int,
    dof: str,
    rate_hz: float = 100.0,
    settle_s: float | None = 2.0,
    scale: float = 1.0,
) -> DescribingSignal:
    """Build a Table 5.2 multi-sine run for one DOF (see :func:`periodic_signal`).

    Parameters
    ----------
    signal : int
        1 or 2 (Table 5.2), or 3 (:data:`EXTENSION_SIGNAL`).
    dof : str
        One of :data:`twin.core.frames.DOF_NAMES`.
    rate_hz : float
        Command rate [Hz].
    settle_s : float or None
        Time between the end of the fade-in and the start of the 20 s window [s]; None for
        the pre-measurement of Eq 3.3 (2 periods of the lowest frequency). The default 2 s
        lets the filters settle and keeps the runs short.
    scale : float
        Factor on all amplitudes (1 = Table 5.2).

    """
    ms = table_5_2(signal, dof)
    ms = MultiSine(ms.frequencies_hz, ms.amplitudes * scale)
    return periodic_signal(ms, dof, rate_hz, settle_s, WINDOW_S, f"Table 5.2 signal {signal}")


def single_sine(
    dof: str,
    frequency_hz: float,
    amplitude: float,
    rate_hz: float = 100.0,
    window_s: float = 10.0,
    settle_s: float | None = None,
) -> DescribingSignal:
    """Build a single sine (Eq 3.4) in acceleration, with the phases of §3.2.3.

    Parameters
    ----------
    dof : str
        Driven DOF.
    frequency_hz : float
        Frequency [Hz].
    amplitude : float
        Acceleration amplitude [m/s^2 or rad/s^2].
    rate_hz : float
        Command rate [Hz].
    window_s : float
        Shortest measurement window [s] (whole periods).
    settle_s : float, optional
        Pre-measurement time; Eq 3.3 by default.

    """
    if dof not in DOF_NAMES:
        raise SignalError(f"unknown DOF {dof!r}; expected one of {', '.join(DOF_NAMES)}")
    unit = acceleration_unit(dof)
    ms = MultiSine(np.array([float(frequency_hz)]), np.array([float(amplitude)]))
    label = f"sine {frequency_hz:g} Hz, {amplitude:g} {unit}"
    return periodic_signal(ms, dof, rate_hz, settle_s, window_s, label)


#: Acceleration levels of the dynamic threshold signal, in units of the step amplitude: every
#: level lasts one step length; velocity and position return to zero at the end (Fig 3.2b).
STEP_PATTERN = (1, -1, -1, 1, -1, 1, 1, -1)
#: Largest step amplitude [m/s^2 or rad/s^2]: ten times the SRS heave acceleration limit.
MAX_STEP = 100.0


@dataclass(frozen=True)
class StepSignal:
    """The square-wave acceleration steps of the dynamic threshold test (§3.2.3.5, Fig 3.2b).

    Attributes
    ----------
    commands : Trajectory
        Pose-offset commands (the double integral of the acceleration levels).
    dof : str
        Driven DOF.
    amplitude : float
        Step amplitude [m/s^2 or rad/s^2].
    step_s : float
        Length of each level [s].
    start_s : float
        Time of the first step [s].
    levels : tuple of int
        Acceleration levels in units of ``amplitude`` (:data:`STEP_PATTERN`).

    """

    commands: Trajectory
    dof: str
    amplitude: float
    step_s: float
    start_s: float
    levels: tuple[int, ...] = STEP_PATTERN

    def acceleration(self, t: ArrayLike) -> FloatArray:
        """Return the commanded acceleration profile at ``t`` [m/s^2 or rad/s^2]."""
        k = np.floor((np.asarray(t, dtype=float) - self.start_s) / self.step_s).astype(int)
        inside = (k >= 0) & (k < len(self.levels))
        lv = np.asarray(self.levels, dtype=float)
        return np.where(inside, lv[np.clip(k, 0, len(lv) - 1)], 0.0) * self.amplitude

    @property
    def step_times(self) -> FloatArray:
        """Times at which the acceleration level changes [s]."""
        lv = np.concatenate([[0], self.levels, [0]])
        change = np.flatnonzero(np.diff(lv) != 0)
        return self.start_s + change * self.step_s


def square_steps(
    dof: str,
    amplitude: float,
    step_s: float,
    rate_hz: float = 100.0,
    rest_s: float = 2.0,
    repeats: int = 1,
) -> StepSignal:
    """Build the dynamic threshold signal: steps of ``amplitude`` lasting ``step_s``.

    The levels of :data:`STEP_PATTERN` are integrated twice analytically (position is
    piecewise quadratic), with ``rest_s`` at rest before and after.

    Parameters
    ----------
    dof : str
        Driven DOF.
    amplitude : float
        Step amplitude [m/s^2 or rad/s^2] (§3.3.4: 0.1 m/s^2 for 1 s; §4.2: 0.1875 m/s^2 for
        0.5 s).
    step_s : float
        Length of each level [s].
    rate_hz : float
        Command rate [Hz].
    rest_s : float
        Rest before the first and after the last step [s].
    repeats : int
        How many times the pattern is run (each ends at rest, so they can follow each other);
        more repeats average more noise out of the fit.

    """
    if not isinstance(repeats, int) or repeats < 1:
        raise SignalError(f"repeats must be an integer >= 1; got {repeats!r}")
    if dof not in DOF_NAMES:
        raise SignalError(f"unknown DOF {dof!r}; expected one of {', '.join(DOF_NAMES)}")
    number(amplitude, "step amplitude [m/s^2 or rad/s^2]", lo=0, lo_open=True, hi=MAX_STEP,
           error=SignalError)  # fmt: skip
    number(step_s, "step length [s]", lo=0, lo_open=True, error=SignalError)
    if step_s * rate_hz < 2 or rest_s < 0:
        raise SignalError(f"steps must last at least 2 command samples; got {step_s} s")
    levels = STEP_PATTERN * repeats
    total = check_duration(2 * rest_s + len(levels) * step_s, "step signal", SignalError)
    t = np.arange(round(total * rate_hz) + 1) / rate_hz
    x = np.zeros_like(t)
    v = p = 0.0
    for k, level in enumerate(levels):  # exact double integral, level by level
        t0 = rest_s + k * step_s
        tau = np.clip(t - t0, 0.0, step_s)
        a = level * amplitude
        seg = (t >= t0) & (t < t0 + step_s)
        x[seg] = p + v * tau[seg] + 0.5 * a * tau[seg] ** 2
        p, v = p + v * step_s + 0.5 * a * step_s**2, v + a * step_s
    values = np.zeros((t.size, 6))
    values[:, dof_index(dof)] = x
    return StepSignal(Trajectory(rate_hz, values), dof, float(amplitude), float(step_s), rest_s,
                      levels)  # fmt: skip


#: Largest pose offset a command may ask for: 10 m and 180 deg from neutral. Beyond them a
#: command is not a motion-platform pose (a unit or file error); within them the platform's
#: own limits (stroke, velocity, acceleration) apply as the limit mode says.
MAX_COMMAND = (10.0, 10.0, 10.0, np.pi, np.pi, np.pi)


def check_physical(commands: Trajectory, what: str = "the commands") -> None:
    """Raise :class:`SignalLimitError` for a pose command beyond :data:`MAX_COMMAND`.

    Examples
    --------
    >>> bad = Trajectory(100.0, np.array([[0, 0, 0, 0, 0, 0], [0, 0, 1e300, 0, 0, 0.0]]))
    >>> check_physical(bad, "commands.csv")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    twin.core.errors.SignalLimitError: commands.csv: heave is 1e+300 m at row 2 (t = 0.01 s); ...

    """
    over = np.abs(commands.values) > np.asarray(MAX_COMMAND)
    if over.any():
        row, col = np.argwhere(over)[0]
        unit = "m" if col < 3 else "rad"
        raise SignalLimitError(
            f"{what}: {DOF_NAMES[col]} is {commands.values[row, col]:g} {unit} at row {row + 1} "
            f"(t = {commands.t0 + row / commands.rate_hz:g} s); a pose command must lie within "
            "10 m and 180 deg of neutral"
        )


def check_signal(commands: Trajectory, platform: str, what: str = "the signal") -> None:
    """Raise :class:`SignalLimitError` if ``commands`` would break a platform limit.

    Leg lengths, velocities and accelerations are evaluated by the exact inverse kinematics
    from the commands' spline at four times the command rate and compared with the stroke
    and the actuator limits of ``platform.toml`` (Table 5.1).

    Parameters
    ----------
    commands : Trajectory
        Pose-offset commands.
    platform : str
        ``"mpi"`` or ``"srs"``.
    what : str
        Name of the signal for the message.

    """
    from twin.platform.facts import load_facts
    from twin.platform.geometry import load_geometry
    from twin.platform.kinematics import actuator_trajectory

    geo, facts = load_geometry(platform), load_facts(platform)
    t = commands.t0 + np.arange(4 * (commands.n - 1) + 1) / (4 * commands.rate_hz)
    pose, rate, acc = commands.derivatives(t)
    legs = actuator_trajectory(geo, t, pose, rate, acc)
    broken = legs.limit_violations(geo, facts.max_velocity, facts.max_acceleration)
    if broken:
        raise SignalLimitError(f"{what} would break the {platform} limits: " + "; ".join(broken))


#: What a rest signal's duration may be (messages).
REST_DURATION = "the duration must be a positive number of seconds (rest-SECONDS, e.g. rest-60)"


def rest(duration_s: float, rate_hz: float = 100.0, name: str | None = None) -> Trajectory:
    """Return neutral-pose commands for ``duration_s`` seconds (refused if a run cannot fit).

    Parameters
    ----------
    duration_s : float
        Duration [s]: finite, > 0, at least one command sample, and a run of it must fit in
        memory (:func:`twin.core.checks.check_duration`).
    rate_hz : float
        Command rate [Hz].
    name : str, optional
        The signal's name in messages (default ``rest-<duration>``).

    Raises
    ------
    SignalError
        Naming the signal, for a duration that is not allowed.

    """
    name = name or f"rest-{duration_s:g}"
    if not np.isfinite(duration_s) or duration_s <= 0:
        raise SignalError(f"{name}: {REST_DURATION}; got {duration_s}")
    check_duration(duration_s, name, SignalError)
    if round(duration_s * rate_hz) < 1:
        raise SignalError(f"{name}: shorter than one command sample "
                          f"({1 / rate_hz:g} s at {rate_hz:g} Hz)")  # fmt: skip
    return Trajectory(rate_hz, np.zeros((round(duration_s * rate_hz) + 1, 6)))


_BUILTIN = re.compile(r"^(?:multisine(?P<sig>[123])-(?P<dof>[a-z]+)|rest-(?P<dur>.*))$", re.S)

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
        For an unknown name, or a rest duration that is no number or not allowed (see
        :func:`rest`).

    Examples
    --------
    >>> builtin_signal("rest-2").duration
    2.0
    >>> builtin_signal("rest-a")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    twin.core.errors.SignalError: rest-a: the duration must be a positive number of seconds ...

    """
    m = _BUILTIN.match(name)
    if m is None or (m["dof"] is not None and m["dof"] not in DOF_NAMES):
        raise SignalError(f"unknown signal {name!r}; built-in signals are {BUILTIN_HELP}")
    if m["dur"] is not None:
        try:
            duration = float(m["dur"])
        except ValueError:
            raise SignalError(f"{name}: {REST_DURATION}; got {m['dur']!r}") from None
        return rest(duration, rate_hz, name)
    return describing_signal(int(m["sig"]), m["dof"], rate_hz).commands
