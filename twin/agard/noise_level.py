"""The half-Hertz noise-level test (§3.3.1, Fig 3.3, Fig 3.5).

A single sine (0.5 Hz by default) drives one DOF; over a window of whole periods the spectrum of
the measured acceleration in the driven DOF is partitioned (Fig 3.3) into

A. the fundamental (the driving frequency),
B. the 2nd and 3rd harmonics (low-frequency non-linearity),
C. the 4th and higher harmonics (high-frequency non-linearity),
D. everything else but DC: the stochastic residue,

each expressed as a standard deviation (square root of its power) and normalised by the
fundamental's. Roughness is C and D together. The undriven DOFs give the parasitic
acceleration, as a standard deviation and a peak value.

Examples
--------
>>> import numpy as np
>>> t = np.arange(0, 20, 0.01)
>>> y = np.sin(2 * np.pi * 0.5 * t) + 0.1 * np.sin(2 * np.pi * 1.0 * t)
>>> d = decompose(t, y, 0.5, (0.0, 20.0))
>>> round(d.ratios["low_frequency_nonlinearity"], 3)
0.1

"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from twin.agard.session import Session
from twin.core.errors import SignalError
from twin.core.frames import DOF_NAMES, acceleration_unit
from twin.core.plotting import AxesArg, finish, subplots
from twin.core.results import frame
from twin.measurement.measure import Measurement, driven_dof
from twin.measurement.periodic import periodic_design

if TYPE_CHECKING:
    import pandas as pd
    from matplotlib.figure import Figure

FloatArray = NDArray[np.float64]

#: Component names, in the order of Fig 3.3.
COMPONENTS = (
    "fundamental",
    "low_frequency_nonlinearity",
    "high_frequency_nonlinearity",
    "stochastic",
)

#: Default input amplitudes of the half-Hertz test: six per DOF as in §3.4.1 (the thesis'
#: values are only drawn in Fig 3.4), geometric from 0.02 to 0.5 m/s^2 or rad/s^2; all stay
#: inside the MPI's limits at 0.5 Hz.
DEFAULT_AMPLITUDES = (0.02, 0.04, 0.08, 0.15, 0.3, 0.5)


@dataclass(frozen=True)
class Decomposition:
    """The Fig 3.3 partition of one signal.

    Attributes
    ----------
    sigma : dict of str to float
        Standard deviation of each component of :data:`COMPONENTS` [signal units].
    ratios : dict of str to float
        Non-fundamental components, roughness and the total noise, each divided by the
        fundamental's standard deviation.

    """

    sigma: dict[str, float]
    ratios: dict[str, float]


def decompose(
    t: FloatArray, y: FloatArray, frequency_hz: float, window: tuple[float, float]
) -> Decomposition:
    """Partition the spectrum of ``y`` over ``window`` around the driving frequency (Fig 3.3).

    Parameters
    ----------
    t, y : ndarray, shape (n,)
        Uniformly sampled signal.
    frequency_hz : float
        Driving frequency; the window must hold a whole number of its periods.
    window : tuple of float
        Start (inclusive) and end (exclusive) [s].

    """
    sel = (t >= window[0] - 1e-9) & (t < window[1] - 1e-9)
    x = y[sel]
    n = x.size
    periods = frequency_hz * (window[1] - window[0])
    if n < 8 or abs(periods - round(periods)) > 1e-6 or round(periods) < 1:
        raise SignalError(
            f"the window {window} must hold a whole number of periods of {frequency_hz} Hz"
        )
    power = 2 * np.abs(np.fft.rfft(x)) ** 2 / n**2  # variance per bin (one-sided)
    if n % 2 == 0:
        power[-1] /= 2
    power[0] = 0.0  # the mean is not noise
    k0 = round(periods)
    harmonic = np.zeros(power.size, dtype=int)
    harmonic[k0::k0] = np.arange(1, harmonic[k0::k0].size + 1)
    parts = {
        "fundamental": power[harmonic == 1].sum(),
        "low_frequency_nonlinearity": power[(harmonic == 2) | (harmonic == 3)].sum(),
        "high_frequency_nonlinearity": power[harmonic >= 4].sum(),
        "stochastic": power[harmonic == 0].sum(),
    }
    sigma = {k: float(np.sqrt(v)) for k, v in parts.items()}
    a = sigma["fundamental"]
    if a <= 0:
        raise SignalError(f"no response at the driving frequency {frequency_hz} Hz")
    rough = np.hypot(sigma["high_frequency_nonlinearity"], sigma["stochastic"])
    total = np.sqrt(sum(parts[k] for k in COMPONENTS[1:]))
    ratios = {k: sigma[k] / a for k in COMPONENTS[1:]}
    ratios.update(roughness=float(rough / a), total=float(total / a))
    return Decomposition(sigma, ratios)


@dataclass(frozen=True)
class NoiseLevelPoint:
    """The noise levels of one run.

    Attributes
    ----------
    dof : str
        Driven DOF.
    frequency_hz, amplitude : float
        Driving frequency [Hz] and commanded acceleration amplitude.
    decomposition : Decomposition
        Driven-DOF partition.
    parasitic : dict of str to (float, float)
        Undriven DOF -> (standard deviation, peak) of its acceleration over the window.
    source : str
        What was measured.

    """

    dof: str
    frequency_hz: float
    amplitude: float
    decomposition: Decomposition
    parasitic: dict[str, tuple[float, float]]
    source: str

    def to_dict(self) -> dict[str, object]:
        """JSON-ready."""
        return {
            "dof": self.dof,
            "frequency_hz": self.frequency_hz,
            "amplitude": self.amplitude,
            "sigma": self.decomposition.sigma,
            "ratios": self.decomposition.ratios,
            "parasitic": {d: {"sigma": s, "peak": p} for d, (s, p) in self.parasitic.items()},
            "source": self.source,
        }


def analyse_noise(m: Measurement, dof: str | None = None) -> NoiseLevelPoint:
    """Return the noise levels of one single-sine measurement."""
    k = driven_dof(m, dof)
    sig = m.meta.get("signal", {})
    if "frequencies_hz" in sig and "window_s" in sig:
        freqs, window = sig["frequencies_hz"], tuple(sig["window_s"])
    else:
        f_arr, window = periodic_design(m, k)
        freqs = list(f_arr)
    if len(freqs) != 1:
        raise SignalError(
            f"{m.source}: the noise-level test needs a single sine; the run has "
            f"{len(freqs)} frequencies ({', '.join(f'{f:g}' for f in freqs)} Hz)"
        )
    f0 = float(freqs[0])
    d = decompose(m.t, m.measured[:, k], f0, window)
    sel = (m.t >= window[0] - 1e-9) & (m.t < window[1] - 1e-9)
    u = m.commanded[sel, k]
    amplitude = float(np.sqrt(2) * np.std(u))
    parasitic = {}
    for j in range(6):
        if j != k:
            x = m.measured[sel, j] - m.measured[sel, j].mean()
            parasitic[DOF_NAMES[j]] = (float(x.std()), float(np.abs(x).max()))
    return NoiseLevelPoint(DOF_NAMES[k], f0, amplitude, d, parasitic, m.source)


@dataclass(frozen=True)
class NoiseLevelResult:
    """The half-Hertz noise-level test of one DOF over several amplitudes (Fig 3.5).

    Attributes
    ----------
    points : list of NoiseLevelPoint
        One per amplitude, ascending.
    skipped : dict of float to str
        Amplitudes not run, with the platform limit they would break.

    """

    points: list[NoiseLevelPoint]
    skipped: dict[float, str] = field(default_factory=dict)

    def to_dict(self) -> dict[str, object]:
        """JSON-ready."""
        return {
            "test": "half-Hertz noise level",
            "points": [p.to_dict() for p in self.points],
            "skipped": {str(a): why for a, why in self.skipped.items()},
        }

    def format_table(self) -> str:
        """Plain-text table: noise ratios per amplitude."""
        if not self.points:
            return "no amplitude could be run: " + "; ".join(self.skipped.values())
        p0 = self.points[0]
        unit = acceleration_unit(p0.dof)
        lines = [
            f"half-Hertz noise level, {p0.dof} at {p0.frequency_hz:g} Hz ({p0.source})",
            f"{'A [' + unit + ']':>14} {'2nd-3rd':>8} {'4th+':>8} {'stoch.':>8} {'rough.':>8} "
            f"{'total':>8} {'parasitic max sigma':>20}",
        ]
        for p in self.points:
            r = p.decomposition.ratios
            worst = max(p.parasitic, key=lambda d: p.parasitic[d][0])
            lines.append(
                f"{p.amplitude:14.3f} {r['low_frequency_nonlinearity']:8.4f} "
                f"{r['high_frequency_nonlinearity']:8.4f} {r['stochastic']:8.4f} "
                f"{r['roughness']:8.4f} {r['total']:8.4f} "
                f"{p.parasitic[worst][0]:12.4f} ({worst})"
            )
        for a, why in self.skipped.items():
            lines.append(f"{a:14.3f} skipped: {why}")
        return "\n".join(lines)

    def to_frame(self) -> pd.DataFrame:
        """One row per amplitude (:meth:`NoiseLevelPoint.to_dict`, nested values as ``a.b``)."""
        return frame(p.to_dict() for p in self.points)

    def plot(self, ax: AxesArg = None, *, path: str | None = None) -> Figure:
        """Bar chart of the noise ratios per amplitude (as Fig 3.5).

        Parameters
        ----------
        ax : Axes, optional
            Where to draw: the bar chart; a new figure by default.
        path : str, optional
            Save the figure here.

        Returns
        -------
        matplotlib.figure.Figure

        """
        fig, ax = subplots(ax, figsize=(7, 3.8))
        names = (
            "low_frequency_nonlinearity",
            "high_frequency_nonlinearity",
            "stochastic",
            "roughness",
            "total",
        )
        labels = ("2nd-3rd harmonics", "4th+ harmonics", "stochastic", "roughness", "total")
        x = np.arange(len(self.points))
        width = 0.8 / len(names)
        for i, (name, label) in enumerate(zip(names, labels, strict=True)):
            ax.bar(
                x + (i - 2) * width,
                [p.decomposition.ratios[name] for p in self.points],
                width,
                label=label,
            )
        ax.set_xticks(x, [f"{p.amplitude:.3g}" for p in self.points])
        ax.set_yscale("log")
        if self.points:
            p0 = self.points[0]
            unit = acceleration_unit(p0.dof)
            ax.set_xlabel(f"input amplitude [{unit}]")
            ax.set_title(
                f"noise levels at {p0.frequency_hz:g} Hz, {p0.dof}: {p0.source}", fontsize=9
            )
        ax.set_ylabel("noise ratio [-]")
        ax.legend(fontsize=7, ncol=3)
        return finish(fig, path)


def run_noise(
    session: Session,
    dof: str,
    amplitudes: Sequence[float] = DEFAULT_AMPLITUDES,
    frequency_hz: float = 0.5,
    window_s: float = 20.0,
) -> NoiseLevelResult:
    """Run single sines of several amplitudes in ``dof`` and analyse each (§3.4.1).

    Amplitudes whose signal would break a platform limit are skipped and reported.
    """
    points, skipped = [], {}
    session.expect(len(amplitudes), f"noise level {dof}")
    for a in sorted(amplitudes):
        m = session.measure_sine(
            dof, frequency_hz, a, window_s, f"sine-{dof}-{frequency_hz:g}Hz-{a:g}"
        )
        if isinstance(m, str):
            skipped[float(a)] = m
        else:
            points.append(analyse_noise(m, dof))
    return NoiseLevelResult(points, skipped)
