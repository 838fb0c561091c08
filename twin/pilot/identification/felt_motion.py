"""Which motion system a recorded pilot run was flown through, read from its felt attitude.

The closed-loop fit (:mod:`twin.pilot.identification.mle`) models the loop through the motion
system's pitch response, so it needs the right one: fitted through the SRS baseline, a run flown
behind the MPI platform's 1 Hz filter is explained by a different pilot. A ``twin-pilot/1`` run that
carries ``theta_felt`` (the attitude the motion system gave the pilot) shows which response
it had: ``theta_felt`` is the simulated attitude ``theta`` through it. Each candidate's
response is applied to ``theta`` (the whole record, zero-padded so nothing wraps round) and
compared with ``theta_felt`` over the measurement window, less the record's first seconds
(:func:`settle_s`: the felt response to the attitude before the record began).

The mismatch is the rms of the difference over the rms of ``theta_felt``. On the twin's own
runs (remnant 15 %) the right configuration leaves under 0.01 % (reduced platform), 0.3 % with
the platform noise on, 0.7 % with the full MuJoCo platform; 10 ms more or less delay leaves
1.6-2.4 %; the 1 Hz filter added or missed, 37-60 %; a 2 Hz filter for the 1 Hz, 23 %. A
constant offset of the felt attitude is left out. The platform noise of Table 6.3 is in heave
and the fit does not model it, so conditions that differ only in noise have the same pitch
response and are named together.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from twin.chain.config import MotionSystem, config_names, motion_system
from twin.core.errors import SignalError
from twin.pilot.models.forcing import MEASUREMENT_S
from twin.pilot.models.pitch import PITCH, motion_response

FloatArray = NDArray[np.float64]
#: Configuration assumed when a run has neither ``--config`` nor ``theta_felt``.
DEFAULT_CONFIG = "condition-1"
#: Largest mismatch with which a configuration is taken as the run's own when none is given.
MATCH_MAX = 0.05
#: A given configuration is questioned when its mismatch is above :data:`QUESTION_FROM` and a
#: built-in one's is below it by :data:`BETTER_BY` or more (10 ms of delay off is 1.6-2.4 %),
#: and whenever its mismatch is above :data:`MATCH_MAX`.
QUESTION_FROM = 0.01
BETTER_BY = 3.0
#: Start of a record left out of the comparison [s], at least: the felt response to the
#: attitude before the record began (the 1 Hz filter's and the delays' memory is under a
#: second); a slower platform filter leaves out :data:`SETTLE_PERIODS` of its break period.
SETTLE_S = 2.0
SETTLE_PERIODS = 2.0
#: Responses closer than this (relative, at every frequency) count as the same.
SAME_RESPONSE = 1e-9


def settle_s(config: MotionSystem) -> float:
    """Return how much of a record's start is left out when checking ``config`` [s]."""
    fb = config.breaks_hz[PITCH]
    return SETTLE_S if fb is None else max(SETTLE_S, SETTLE_PERIODS / fb)


def felt_mismatch(theta: FloatArray, theta_felt: FloatArray, rate_hz: float,
                  config: MotionSystem) -> float:  # fmt: skip
    """Return how far ``theta_felt`` is from ``config``'s response to ``theta``.

    Parameters
    ----------
    theta, theta_felt : ndarray
        Simulated and felt pitch attitude [rad], the whole record (the comparison uses its
        last 81.92 s, less the record's first :func:`settle_s`).
    rate_hz : float
        Sample rate [Hz].
    config : MotionSystem
        The candidate.

    Returns
    -------
    float
        Rms of the difference over the rms of ``theta_felt``, both about their means (a
        constant offset of the felt attitude, e.g. a sensor's, does not count).

    Raises
    ------
    SignalError
        A record too short to leave anything after the settling, or a constant
        ``theta_felt``.

    """
    start = max(theta.size - round(MEASUREMENT_S * rate_hz), round(settle_s(config) * rate_hz))
    if start >= theta.size - 1:
        raise SignalError(f"a run of {theta.size} samples is too short to check its felt motion "
                          f"through {config.name}")  # fmt: skip
    padded = 2 * theta.size
    w = 2 * np.pi * np.fft.rfftfreq(padded, 1.0 / rate_hz)
    predicted = np.fft.irfft(np.fft.rfft(theta, padded) * motion_response(config, w), padded)
    felt = theta_felt[start:] - np.mean(theta_felt[start:])
    scale = float(np.sqrt(np.mean(felt**2)))
    if scale == 0.0:
        raise SignalError("theta_felt is constant over the measurement window: no felt motion")
    diff = felt - predicted[start : theta.size]
    return float(np.sqrt(np.mean((diff - np.mean(diff)) ** 2)) / scale)


@dataclass(frozen=True)
class MotionMatch:
    """The motion system a run is fitted through, and how its felt attitude agrees.

    Attributes
    ----------
    config : MotionSystem
        The configuration the fit uses.
    source : str
        ``"given"`` (``--config``), ``"theta_felt"`` (the best-matching configuration) or
        ``"default"`` (neither: :data:`DEFAULT_CONFIG`).
    mismatch : float or None
        Its mismatch with ``theta_felt`` (:func:`felt_mismatch`; None without it).
    candidates : dict of str to float
        Every built-in configuration's mismatch, best first (empty without ``theta_felt``).
    same_response : tuple of str
        Built-in configurations with the same pitch response as ``config``.

    """

    config: MotionSystem
    source: str
    mismatch: float | None
    candidates: dict[str, float]
    same_response: tuple[str, ...]

    @property
    def better(self) -> str | None:
        """A built-in configuration ``theta_felt`` follows much better than ``config``, if any."""
        if self.mismatch is None or self.mismatch <= QUESTION_FROM:
            return None
        name, best = next(iter(self.candidates.items()))
        return name if best * BETTER_BY <= self.mismatch else None

    @property
    def warning(self) -> str | None:
        """Why ``config`` may not be the run's own, if it may not (None: no reason to doubt)."""
        if self.better is not None:
            return (f"theta_felt differs from {self.better}'s response by only "
                    f"{100 * self.candidates[self.better]:.1f} %: was the run flown through it? "
                    "(the fit models the loop through the given one)")  # fmt: skip
        if self.mismatch is not None and self.mismatch > MATCH_MAX:
            return (f"theta_felt differs from the given configuration's response by "
                    f"{100 * self.mismatch:.1f} %, more than the {100 * MATCH_MAX:.0f} % "
                    "within which a configuration is taken as a run's own: is it this "
                    "run's? (the fit models the loop through it)")  # fmt: skip
        return None

    @property
    def label(self) -> str:
        """The configuration's name, marked when a file's shares a built-in one's name."""
        name = self.config.name
        if name in config_names() and name not in self.same_response:
            return f"{name} (from a file: not the built-in {name})"
        return name

    def to_dict(self) -> dict[str, object]:
        """JSON-ready (``warning`` null when there is no reason to doubt the configuration)."""
        return {
            "config": self.config.name,
            "source": self.source,
            "mismatch": self.mismatch,
            "same_response": list(self.same_response),
            "candidates": self.candidates,
            "warning": self.warning,
        }

    def format(self) -> str:
        """One or two lines for the identify report."""
        alike = [n for n in self.same_response if n != self.config.name]
        name = self.label + (f" (or {', '.join(alike)}: the same pitch response)"
                             if alike else "")  # fmt: skip
        if self.mismatch is None:
            if self.source == "default":
                return (f"motion system: {name}, assumed: the run has no theta_felt and no "
                        "--config was given")  # fmt: skip
            return f"motion system: {name}, given; the run has no theta_felt to check it"
        off = f"theta_felt differs from its response to theta by {100 * self.mismatch:.1f} % rms"
        if self.source == "given":
            line = f"motion system: {name}, given; {off}"
        else:
            line = f"motion system: {name}, the built-in one theta_felt follows best: {off}"
            others = [(n, m) for n, m in self.candidates.items() if n not in self.same_response]
            if others:
                line += f"; the next, {others[0][0]}, {100 * others[0][1]:.1f} %"
        if self.warning is not None:
            line += f"\n  WARNING: {self.warning}"
        return line


def _same(a: MotionSystem, b: MotionSystem, w: FloatArray) -> bool:
    ha, hb = motion_response(a, w), motion_response(b, w)
    return bool(np.all(np.abs(ha - hb) <= SAME_RESPONSE * np.abs(hb)))


def match_motion(run: Mapping[str, FloatArray], config: MotionSystem | None = None,
                 rate_hz: float | None = None) -> MotionMatch:  # fmt: skip
    """Check ``config`` against the run's ``theta_felt``, or choose it from ``theta_felt``.

    Parameters
    ----------
    run : mapping
        A read ``twin-pilot/1`` run (:func:`twin.pilot.models.records.read_pilot_csv`): ``theta``,
        maybe ``theta_felt``, and ``rate_hz``.
    config : MotionSystem, optional
        The configuration the user gave; None to choose among the built-in ones.
    rate_hz : float, optional
        Sample rate (the run's ``rate_hz`` by default).

    Returns
    -------
    MotionMatch
        The configuration to fit through, where it came from, and every built-in one's
        mismatch.

    Raises
    ------
    SignalError
        No configuration given and ``theta_felt`` follows none of the built-in ones within
        :data:`MATCH_MAX` (the fit would model the wrong loop: give ``--config``).

    """
    rate = float(run["rate_hz"]) if rate_hz is None else rate_hz
    builtin = {name: motion_system(name) for name in config_names()}
    w = 2 * np.pi * np.geomspace(0.01, 0.5 * rate, 200)

    def alike(cfg: MotionSystem) -> tuple[str, ...]:
        return tuple(n for n, c in builtin.items() if _same(c, cfg, w))

    if "theta_felt" not in run:
        cfg = config if config is not None else builtin[DEFAULT_CONFIG]
        return MotionMatch(cfg, "given" if config is not None else "default", None, {}, alike(cfg))
    theta, felt = np.asarray(run["theta"]), np.asarray(run["theta_felt"])
    found = {n: felt_mismatch(theta, felt, rate, c) for n, c in builtin.items()}
    candidates = dict(sorted(found.items(), key=lambda kv: (kv[1], kv[0])))
    if config is not None:
        known = config.name in builtin and _same(builtin[config.name], config, w)
        own = found[config.name] if known else felt_mismatch(theta, felt, rate, config)
        return MotionMatch(config, "given", own, candidates, alike(config))
    name, best = next(iter(candidates.items()))
    if best > MATCH_MAX:
        raise SignalError(
            f"theta_felt follows none of the built-in motion systems within "
            f"{100 * MATCH_MAX:.0f} % (best {name}, {100 * best:.1f} %); give the run's own "
            "configuration (--config NAME or twin-config/1 file; --break-hz, --delay-ms to "
            "change it)"
        )
    return MotionMatch(builtin[name], "theta_felt", best, candidates, alike(builtin[name]))
