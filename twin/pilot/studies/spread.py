"""How the simulated subjects differ where the thesis does not say: the spreads that are settings.

The thesis reports its nine subjects' measures, not how the subjects differ in what the
model needs (how well each perceives motion, how long each one's visual delay is). These
spreads set how alike the subjects' responses to the motion system are, and so the effect
sizes a population shows; they are chosen by profiles against Tables 6.4-6.7
(``python bench/pilot_adaptive.py --spread-profile``, docs "Subjects who differ in
perceiving motion" and "Subjects who differ in visual delay"). :class:`Spread` holds them,
checked once, so every function that draws subjects takes one value.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

from twin.core.errors import SignalError

#: Spread between subjects of how well they perceive motion: the log-normal sd (median 1) of
#: the felt rate's observation-noise ratio relative to the subject's own ratio.
MOTION_NOISE_SD = 0.5
#: Largest motion spread accepted (a factor e^3 = 20 between subjects one sd apart).
MAX_MOTION_SPREAD = 3.0
#: Spread between subjects of their visual delay: the normal sd in s around 0.30 s (the
#: delays of §6.3).
VISUAL_DELAY_SD = 0.01
#: Largest visual-delay spread accepted, in s (draws are kept above 0.09 s).
MAX_VISUAL_DELAY_SD = 0.1


def _checked(value: float, largest: float, name: str, kind: str) -> float:
    """Return ``value`` as a float in [0, ``largest``] (-0 is 0), or raise naming ``name``."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise SignalError(f"{name} must be {kind} in [0, {largest:g}]; got {value!r}")
    x = float(value)
    if math.isnan(x) or not 0 <= x <= largest:
        raise SignalError(f"{name} must be {kind} in [0, {largest:g}]; got {value}")
    return abs(x)


@dataclass(frozen=True)
class Spread:
    """The subjects' spreads that are settings, checked on construction.

    Attributes
    ----------
    motion : float
        Log-normal sd of the subjects' motion perception (:data:`MOTION_NOISE_SD`; 0: every
        subject perceives motion as well as vision), in [0, :data:`MAX_MOTION_SPREAD`].
    visual_delay : float
        Sd of the subjects' visual delay in s (:data:`VISUAL_DELAY_SD`; 0: all at the mean),
        in [0, :data:`MAX_VISUAL_DELAY_SD`].

    Raises
    ------
    SignalError
        A spread that is NaN or out of its range (the message names which and the range).

    """

    motion: float = MOTION_NOISE_SD
    visual_delay: float = VISUAL_DELAY_SD

    def __post_init__(self) -> None:
        object.__setattr__(
            self,
            "motion",
            _checked(
                self.motion, MAX_MOTION_SPREAD, "the motion perception's spread", "a log-normal sd"
            ),
        )
        object.__setattr__(
            self,
            "visual_delay",
            _checked(
                self.visual_delay, MAX_VISUAL_DELAY_SD, "the visual delay's spread", "an sd in s"
            ),
        )

    def to_dict(self) -> dict[str, float]:
        """JSON-ready: ``{"motion_spread": ..., "visual_delay_sd": ...}``."""
        return {"motion_spread": self.motion, "visual_delay_sd": self.visual_delay}

    def describe(self) -> str:
        """One phrase for table headers: the motion and visual-delay spreads."""
        return (f"motion perception spread {self.motion:g}, visual delay sd "
                f"{self.visual_delay * 1e3:g} ms")  # fmt: skip


#: The default subjects' spreads.
DEFAULT_SPREAD = Spread()


def checked(spread: object) -> Spread:
    """Return ``spread`` if it is a :class:`Spread`, or raise a TypeError saying what to pass.

    Raises
    ------
    TypeError
        Anything but a :class:`Spread` (e.g. the float of a motion spread alone).

    """
    if not isinstance(spread, Spread):
        raise TypeError(f"spread must be a twin.pilot.studies.spread.Spread (e.g. "
                        f"Spread(motion=0.5, visual_delay=0.01)); got {type(spread).__name__} "
                        f"{spread!r}")  # fmt: skip
    return spread
