"""The signal-to-noise test: operational limits against system limits (§3.3.2, Fig 3.6).

Single sines on a frequency x amplitude grid drive one DOF; at every point the total noise
ratio of :func:`twin.agard.noise_level.decompose` (all noise over the fundamental, as a ratio of
standard deviations) is measured. Contours of the noise ratio in the acceleration-amplitude
versus frequency plane are the operational limits; they are drawn against the system limits:
the largest sine amplitude the DOF can make at each frequency, limited by its excursion
(App. B.3 workspace), and by the actuators' velocity and acceleration through the platform
Jacobian at neutral (Eq A.11):

    a_max(f) = min(x_max w^2, v_max w, a_max),  w = 2 pi f.

Points beyond the system limits are not run.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cache
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from twin.agard.noise_level import NoiseLevelPoint, analyse_noise
from twin.agard.session import Session
from twin.core.frames import acceleration_unit, dof_index
from twin.core.plotting import AxesArg, finish, subplots
from twin.core.results import frame

if TYPE_CHECKING:
    import pandas as pd
    from matplotlib.figure import Figure

FloatArray = NDArray[np.float64]

#: Default grid: six frequencies as in §3.4.2, amplitudes as fractions of the system limit.
DEFAULT_FREQUENCIES_HZ = (0.05, 0.1, 0.2, 0.5, 1.0, 2.0)
DEFAULT_FRACTIONS = (0.005, 0.01, 0.03, 0.1, 0.3, 0.8)


@cache
def dof_limits(platform: str, dof: str) -> tuple[float, float, float]:
    """Excursion [m, rad], velocity and acceleration limits of one DOF moving alone.

    Excursion: the smaller side of the App. B.3 workspace. Velocity and acceleration: the
    actuator limits (Table 5.1) divided by the largest leg rate per unit DOF rate at neutral
    (the DOF's column of the Jacobian, Eq A.11).
    """
    from twin.platform.facts import load_facts
    from twin.platform.geometry import load_geometry
    from twin.platform.kinematics import jacobian, workspace

    geo, facts = load_geometry(platform), load_facts(platform)
    k = dof_index(dof)
    r = workspace(geo)[dof]
    column = np.abs(jacobian(geo, np.zeros(6))[:, k]).max()
    return (min(-r.min, r.max), facts.max_velocity / column, facts.max_acceleration / column)


def system_limit(platform: str, dof: str, f_hz: ArrayLike) -> FloatArray:
    """Largest sine acceleration amplitude of ``dof`` at ``f_hz`` [m/s^2 or rad/s^2]."""
    x, v, a = dof_limits(platform, dof)
    w = 2 * np.pi * np.asarray(f_hz, dtype=float)
    return np.minimum(np.minimum(x * w**2, v * w), a)


@dataclass(frozen=True)
class SnrResult:
    """Noise ratios on a frequency x amplitude grid of one DOF.

    Attributes
    ----------
    dof, platform : str
        Driven DOF and platform.
    points : list of NoiseLevelPoint
        The runs.
    skipped : list of (float, float, str)
        (frequency, amplitude, reason) of grid points not run.
    source : str
        What was measured.

    """

    dof: str
    platform: str
    points: list[NoiseLevelPoint]
    skipped: list[tuple[float, float, str]] = field(default_factory=list)
    source: str = ""

    def to_dict(self) -> dict[str, object]:
        """JSON-ready."""
        return {
            "test": "signal-to-noise",
            "dof": self.dof,
            "source": self.source,
            "points": [
                {
                    "frequency_hz": p.frequency_hz,
                    "amplitude": p.amplitude,
                    "noise_ratio": p.decomposition.ratios["total"],
                }
                for p in self.points
            ],
            "skipped": [
                {"frequency_hz": f, "amplitude": a, "reason": r} for f, a, r in self.skipped
            ],
        }

    def format_table(self) -> str:
        """Noise ratio per frequency (rows) and amplitude."""
        lines = [f"signal-to-noise, {self.dof} ({self.source}): total noise ratio"]
        for f in sorted({p.frequency_hz for p in self.points}):
            row = [p for p in self.points if p.frequency_hz == f]
            cells = "  ".join(
                f"{p.amplitude:.3g}: {p.decomposition.ratios['total']:.3f}" for p in row
            )
            lines.append(f"{f:6.2f} Hz  {cells}")
        if self.skipped:
            lines.append(f"{len(self.skipped)} grid point(s) beyond the system limits not run")
        return "\n".join(lines)

    def to_frame(self) -> pd.DataFrame:
        """One row per grid point: frequency, amplitude and total noise ratio."""
        return frame(self.to_dict()["points"])  # type: ignore[arg-type]

    def plot(
        self,
        ax: AxesArg = None,
        *,
        path: str | None = None,
        levels: Sequence[float] = (0.05, 0.1, 0.2, 0.5, 1),
    ) -> Figure:
        """Contours of the noise ratio against the system limits (as Fig 3.6).

        Parameters
        ----------
        ax : Axes, optional
            One Axes to draw on (its figure gets the colour bar); a new figure by default.
        path : str, optional
            Save the figure here.
        levels : sequence of float
            Noise ratios of the contours.

        Returns
        -------
        matplotlib.figure.Figure

        """
        fig, ax = subplots(ax, figsize=(6, 4.2))
        f = np.array([p.frequency_hz for p in self.points])
        a = np.array([p.amplitude for p in self.points])
        r = np.array([p.decomposition.ratios["total"] for p in self.points])
        if len(self.points) >= 3 and np.unique(f).size > 1 and np.unique(a).size > 1:
            cs = ax.tricontour(np.log10(f), np.log10(a), r, levels=list(levels), cmap="viridis")
            ax.clabel(cs, fontsize=7, fmt="%g")
        sc = ax.scatter(np.log10(f), np.log10(a), c=np.log10(r), s=12, cmap="viridis")
        fig.colorbar(sc, ax=ax, label="log10 noise ratio")
        fl = np.geomspace(min(f.min(initial=0.05), 0.02), max(f.max(initial=2), 5), 200)
        ax.plot(
            np.log10(fl),
            np.log10(system_limit(self.platform, self.dof, fl)),
            "k-",
            lw=1.2,
            label="system limit",
        )
        unit = acceleration_unit(self.dof)
        ax.set_xlabel("log10 frequency [Hz]")
        ax.set_ylabel(f"log10 amplitude [{unit}]")
        ax.set_title(f"signal-to-noise, {self.dof}: {self.source}", fontsize=9)
        ax.legend(fontsize=7, loc="lower right")
        return finish(fig, path)


def run_snr(
    session: Session,
    dof: str,
    frequencies_hz: Sequence[float] = DEFAULT_FREQUENCIES_HZ,
    fractions: Sequence[float] = DEFAULT_FRACTIONS,
    window_s: float = 10.0,
) -> SnrResult:
    """Run the grid: at each frequency, sines of ``fractions`` of the system limit.

    The session's progress counts the grid's runs.
    """
    platform = session.bench.config.platform
    points, skipped = [], []
    session.expect(len(frequencies_hz) * len(fractions), f"signal-to-noise {dof}")
    for f in frequencies_hz:
        limit = float(system_limit(platform, dof, f))
        for frac in fractions:
            amp = frac * limit
            m = session.measure_sine(dof, f, amp, window_s, f"snr-{dof}-{f:g}Hz-{amp:.3g}")
            if isinstance(m, str):
                skipped.append((float(f), float(amp), m))
            else:
                points.append(analyse_noise(m, dof))
    return SnrResult(dof, platform, points, skipped, session.bench.name)
