"""Full versus reduced platform: describing functions, Table 5.5 fits, differences (§5.5).

Two questions a motion-system engineer asks first:

1. *What are the platform's own dynamics?* :func:`platform_dynamics` drives the full MuJoCo
   model alone (no filter, no delay, no noise; §5.5.1) with the multi-sines of Table 5.2 in
   each DOF, and fits a first-order lag plus delay per DOF (Table 5.5).
2. *How far is the reduced model from the full one?* :func:`compare` drives both through the
   same configuration blocks with the same commands (noise off: the describing function is
   of the deterministic part) and reports gain and phase differences per DOF and frequency,
   the phase difference as an equivalent delay, and the time-domain RMS difference.

Examples
--------
Not run as a doctest (it takes some seconds; ``tests/test_compare.py`` runs it)::

    cmp = compare("mpi", dofs=("heave",), signals=(1,))
    print(cmp.format_table())

"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from twin.chain.config import MotionSystem, resolve
from twin.chain.physics import FullPlatform
from twin.chain.reduced import ReducedPlatform
from twin.chain.signals import describing_signal
from twin.chain.simulate import Platform, make_platform, simulate
from twin.core.errors import SignalError, UsageError
from twin.core.frames import DOF_NAMES, dof_index
from twin.core.plotting import AxesArg, finish, subplots
from twin.core.progress import ProgressFn
from twin.core.results import frame, frd, pick
from twin.core.thesis import TABLE_5_5
from twin.measurement.describing_function import (
    LagDelayFit,
    describing_function,
    fit_lag_delay,
    phase_deg,
)

if TYPE_CHECKING:
    import control
    import pandas as pd
    from matplotlib.figure import Figure

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]


def _check_dofs(dofs: Sequence[str]) -> tuple[str, ...]:
    bad = [d for d in dofs if d not in DOF_NAMES]
    if bad or not dofs:
        raise SignalError(f"unknown DOF(s) {bad}; choose from {', '.join(DOF_NAMES)}")
    return tuple(dofs)


@dataclass(frozen=True, eq=False)
class DofResponse:
    """Describing functions of one DOF: from the commands to the cabin pose.

    Attributes
    ----------
    dof : str
        Degree of freedom.
    frequencies_hz : ndarray
        Excited frequencies (sorted).
    full, reduced : ndarray of complex or None
        Describing function of each model (None if not run).
    rms_difference : float
        RMS of (full - reduced) pose in this DOF over the analysis windows, relative to the
        RMS of the command (NaN if only one model ran).

    """

    dof: str
    frequencies_hz: FloatArray
    full: ComplexArray | None
    reduced: ComplexArray | None
    rms_difference: float = float("nan")

    @property
    def gain_difference_db(self) -> FloatArray:
        """``20 log10 |H_full / H_reduced|`` [dB]."""
        return 20 * np.log10(np.abs(self.full / self.reduced))

    @property
    def phase_difference_deg(self) -> FloatArray:
        """Phase of H_full / H_reduced [deg] (negative: the full model lags)."""
        return np.angle(self.full / self.reduced, deg=True)

    @property
    def equivalent_delay_s(self) -> FloatArray:
        """The phase difference as a delay, -phase / (360 f) [s] (positive: full lags)."""
        return -self.phase_difference_deg / (360.0 * self.frequencies_hz)


def _drive(
    config: MotionSystem, platform: Platform, dof: str, signals: Sequence[int]
) -> tuple[FloatArray, ComplexArray, list[tuple[FloatArray, FloatArray, FloatArray]]]:
    """Run the multi-sines in one DOF; return frequencies, DF, and (t, cmd, pose) windows."""
    k = dof_index(dof)
    freqs, dfs, windows = [], [], []
    for number in signals:
        sig = describing_signal(number, dof)
        sim = simulate(config, sig.commands, platform.kind, platform=platform)
        r = sim.response
        command = sig.commands.at(r.t)[:, k]
        freqs.append(sig.frequencies_hz)
        dfs.append(describing_function(r.t, command, r.pose[:, k], sig.frequencies_hz,
                                       sig.window))  # fmt: skip
        sel = (r.t >= sig.window[0]) & (r.t < sig.window[1])
        windows.append((r.t[sel], command[sel], r.pose[sel, k]))
    f = np.concatenate(freqs)
    order = np.argsort(f)
    return f[order], np.concatenate(dfs)[order], windows


@dataclass(frozen=True, eq=False)
class PlatformDynamics:
    """Per-DOF lag-plus-delay fits of the full model alone (Table 5.5).

    Attributes
    ----------
    platform : str
        ``"mpi"`` or ``"srs"``.
    responses : dict of str to DofResponse
        Describing functions (``full`` only).
    fits : dict of str to LagDelayFit
        Fitted t_m and tau per DOF.

    """

    platform: str
    responses: dict[str, DofResponse]
    fits: dict[str, LagDelayFit]

    def table(self) -> list[dict[str, float | str | None]]:
        """Rows: DOF, fitted t_m, f_m, tau, and (MPI) Table 5.5 with the relative error."""
        rows = []
        for dof, fit in self.fits.items():
            ref = TABLE_5_5.get(dof) if self.platform == "mpi" else None
            rows.append({
                "dof": dof, "t_m_s": fit.t_m, "f_m_hz": fit.f_m, "tau_s": fit.tau,
                "thesis_t_m_s": ref[0] if ref else None,
                "thesis_f_m_hz": ref[1] if ref else None,
                "t_m_error": fit.t_m / ref[0] - 1 if ref else None,
            })  # fmt: skip
        return rows

    def to_dict(self) -> dict[str, object]:
        """JSON-ready result: the platform and the rows of :meth:`table`."""
        return {"platform": self.platform, "fits": self.table()}

    def to_frame(self) -> pd.DataFrame:
        """One row per DOF: the rows of :meth:`table`."""
        return frame(self.table())

    def to_frd(self, dof: str | None = None) -> control.FrequencyResponseData:
        """Return the full model's describing function of ``dof`` (the only one by default)."""
        r = self.responses[pick(dof, self.responses, "the platform dynamics")]
        return frd(r.full, r.frequencies_hz, r.dof)

    def plot(self, ax: AxesArg = None, *, path: str | None = None) -> Figure:
        """Bode plot per DOF: the full model's describing function and its lag-plus-delay fit.

        Parameters
        ----------
        ax : sequence of 2 x n Axes, optional
            Where to draw: gain (first row) and phase (second row), one column per DOF,
            in row order; a new figure by default.
        path : str, optional
            Save the figure here.

        Returns
        -------
        matplotlib.figure.Figure

        """
        n = len(self.fits)
        fig, axes = subplots(ax, 2, n, figsize=(3.2 * n, 5.5), squeeze=False, sharex=True)
        for j, (dof, fit) in enumerate(self.fits.items()):
            r = self.responses[dof]
            f = r.frequencies_hz
            fa = np.geomspace(f.min(), f.max(), 200)
            s = 2j * np.pi * fa
            hf = np.exp(-s * fit.tau) / (fit.t_m * s + 1)
            axes[0, j].semilogx(f, 20 * np.log10(np.abs(r.full)), "o", label="full model")
            axes[1, j].semilogx(f, phase_deg(r.full), "o")
            label = f"lag {fit.t_m * 1e3:.1f} ms + delay {fit.tau * 1e3:.1f} ms"
            axes[0, j].semilogx(fa, 20 * np.log10(np.abs(hf)), "k-", lw=0.8, label=label)
            axes[1, j].semilogx(fa, phase_deg(hf), "k-", lw=0.8)
            axes[0, j].set_title(dof)
            axes[0, j].legend(fontsize=7)
            axes[1, j].set_xlabel("frequency [Hz]")
        axes[0, 0].set_ylabel("gain [dB]")
        axes[1, 0].set_ylabel("phase [deg]")
        fig.suptitle(f"{self.platform}: full model alone (Table 5.5)")
        return finish(fig, path)

    def format_table(self) -> str:
        """Plain-text Table 5.5 comparison."""
        out = [f"{self.platform}: full model alone, first-order lag + delay per DOF (Table 5.5)",
               f"{'dof':6} {'t_m [s]':>9} {'f_m [Hz]':>9} {'tau [ms]':>9} "
               f"{'thesis t_m':>11} {'thesis f_m':>11} {'t_m err':>8}"]  # fmt: skip
        for r in self.table():
            ref = (f"{r['thesis_t_m_s']:>11.5f} {r['thesis_f_m_hz']:>11.2f} "
                   f"{r['t_m_error'] * 100:>+7.1f}%") if r["thesis_t_m_s"] else ""  # fmt: skip
            out.append(f"{r['dof']:6} {r['t_m_s']:>9.5f} {r['f_m_hz']:>9.2f} "
                       f"{r['tau_s'] * 1e3:>9.2f} {ref}")  # fmt: skip
        return "\n".join(out)


def platform_dynamics(
    platform: str = "mpi",
    dofs: Sequence[str] = DOF_NAMES,
    signals: Sequence[int] = (1, 2),
    progress: ProgressFn | None = None,
    timestep_s: float | None = None,
) -> PlatformDynamics:
    """Fit lag plus delay to the full model's describing functions per DOF (§5.5.1).

    Parameters
    ----------
    platform : str
        ``"mpi"`` or ``"srs"``.
    dofs : sequence of str
        DOFs to drive, one at a time.
    signals : sequence of int
        Multi-sine signals (1, 2: Table 5.2; 3: to 10 Hz).
    progress : callable, optional
        Called with a message before each DOF.
    timestep_s : float, optional
        Integration step of the full model (its 1 ms by default; for convergence studies).

    """
    alone = MotionSystem(
        "platform-alone", platform, None, 0.0, False,
        description="the full model without filter, delay or noise (§5.5.1)",
    )  # fmt: skip
    plat = FullPlatform(platform, timestep_s=timestep_s)
    responses, fits = {}, {}
    checked = _check_dofs(dofs)
    for dof in checked:
        f, h, _ = _drive(alone, plat, dof, signals)
        responses[dof] = DofResponse(dof, f, h, None)
        if progress:
            progress(f"{platform} full model alone [DOFs]", len(responses), len(checked))
        fits[dof] = fit_lag_delay(f, h)
    return PlatformDynamics(platform, responses, fits)


@dataclass(frozen=True, eq=False)
class Comparison:
    """Full versus reduced model of one configuration.

    Attributes
    ----------
    config : MotionSystem
        The configuration (noise off).
    dofs : dict of str to DofResponse
        Per-DOF describing functions of both models.
    analytic : dict of str to ndarray
        The reduced model's analytic response (Eq 5.11) at each DOF's frequencies.
    notes : list of str
        Anything worth knowing about the runs.

    """

    config: MotionSystem
    dofs: dict[str, DofResponse]
    analytic: dict[str, ComplexArray]
    notes: list[str] = field(default_factory=list)

    def worst(self, max_hz: float = np.inf) -> dict[str, tuple[float, float]]:
        """Largest absolute gain difference [dB] and phase difference [deg] per DOF up to max_hz."""
        out = {}
        for dof, r in self.dofs.items():
            sel = r.frequencies_hz <= max_hz + 1e-9
            out[dof] = (float(np.abs(r.gain_difference_db[sel]).max()),
                        float(np.abs(r.phase_difference_deg[sel]).max()))  # fmt: skip
        return out

    def to_dict(self) -> dict[str, object]:
        """JSON-ready result."""
        return {
            "config": self.config.to_meta(),
            "platform": self.config.platform,
            "dofs": {
                dof: {
                    "frequency_hz": r.frequencies_hz.tolist(),
                    "full_gain_db": (20 * np.log10(np.abs(r.full))).tolist(),
                    "full_phase_deg": np.angle(r.full, deg=True).tolist(),
                    "reduced_gain_db": (20 * np.log10(np.abs(r.reduced))).tolist(),
                    "reduced_phase_deg": np.angle(r.reduced, deg=True).tolist(),
                    "gain_difference_db": r.gain_difference_db.tolist(),
                    "phase_difference_deg": r.phase_difference_deg.tolist(),
                    "equivalent_delay_ms": (r.equivalent_delay_s * 1e3).tolist(),
                    "rms_difference": r.rms_difference,
                }
                for dof, r in self.dofs.items()
            },
            "notes": self.notes,
        }

    def format_table(self) -> str:
        """Plain-text table: per DOF and frequency, full minus reduced."""
        out = [f"full vs reduced, configuration {self.config.name} (platform "
               f"{self.config.platform}; noise off for the describing functions)",
               f"{'dof':6} {'f [Hz]':>7} {'full dB':>8} {'full deg':>9} {'red. dB':>8} "
               f"{'red. deg':>9} {'diff dB':>8} {'diff deg':>9} {'eq. delay ms':>13}"]  # fmt: skip
        for dof, r in self.dofs.items():
            for i, f in enumerate(r.frequencies_hz):
                out.append(
                    f"{dof:6} {f:>7.2f} {20 * np.log10(abs(r.full[i])):>8.2f} "
                    f"{np.angle(r.full[i], deg=True):>9.1f} "
                    f"{20 * np.log10(abs(r.reduced[i])):>8.2f} "
                    f"{np.angle(r.reduced[i], deg=True):>9.1f} {r.gain_difference_db[i]:>+8.2f} "
                    f"{r.phase_difference_deg[i]:>+9.2f} {r.equivalent_delay_s[i] * 1e3:>+13.2f}"
                )
            out.append(f"{dof:6} time domain: RMS(full - reduced) = "
                       f"{r.rms_difference * 100:.2f} % of RMS(command)")  # fmt: skip
        out.extend(f"note: {n}" for n in self.notes)
        return "\n".join(out)

    def to_frame(self) -> pd.DataFrame:
        """One row per DOF and line: the columns of :meth:`to_dict`'s ``dofs``."""
        rows = []
        for dof, part in self.to_dict()["dofs"].items():  # type: ignore[union-attr]
            n = len(part["frequency_hz"])
            rows += [{"dof": dof, **{k: v[i] for k, v in part.items() if isinstance(v, list)},
                      "rms_difference": part["rms_difference"]} for i in range(n)]  # fmt: skip
        return frame(rows)

    def to_frd(self, dof: str | None = None, model: str = "full") -> control.FrequencyResponseData:
        """Return the ``model``'s (``full``/``reduced``) describing function of ``dof``.

        ``dof`` may be left out where the comparison holds one DOF.
        """
        if model not in ("full", "reduced"):
            raise UsageError(f"model {model!r}: expected 'full' or 'reduced'")
        r = self.dofs[pick(dof, self.dofs, "the comparison")]
        return frd(getattr(r, model), r.frequencies_hz, f"{r.dof} ({model})")

    def plot(self, ax: AxesArg = None, *, path: str | None = None) -> Figure:
        """Bode plot per DOF: full, reduced and analytic Eq 5.11; saved to ``path`` if given.

        Parameters
        ----------
        ax : sequence of 2 x n Axes, optional
            Where to draw: gain (first row) and phase (second row), one column per DOF,
            in row order; a new figure by default.
        path : str, optional
            Save the figure here.

        Returns
        -------
        matplotlib.figure.Figure

        """
        n = len(self.dofs)
        fig, axes = subplots(ax, 2, n, figsize=(3.2 * n, 5.5), squeeze=False, sharex=True)
        for j, (dof, r) in enumerate(self.dofs.items()):
            f = r.frequencies_hz
            fa = np.geomspace(f.min(), max(f.max(), 10.0), 200)
            ha = self.config.response_at_hz(fa)[:, dof_index(dof)]
            axes[0, j].semilogx(fa, 20 * np.log10(np.abs(ha)), "k-", lw=0.8, label="Eq 5.11")
            axes[1, j].semilogx(fa, phase_deg(ha), "k-", lw=0.8)
            for h, style, label in ((r.full, "o", "full"), (r.reduced, "x", "reduced")):
                axes[0, j].semilogx(f, 20 * np.log10(np.abs(h)), style, label=label)
                axes[1, j].semilogx(f, phase_deg(h), style)
            axes[0, j].set_title(dof)
            axes[1, j].set_xlabel("frequency [Hz]")
        axes[0, 0].set_ylabel("gain [dB]")
        axes[1, 0].set_ylabel("phase [deg]")
        axes[0, 0].legend(fontsize=8)
        fig.suptitle(f"{self.config.name}: full vs reduced describing functions")
        return finish(fig, path)


def compare(
    config: MotionSystem | str,
    dofs: Sequence[str] = DOF_NAMES,
    signals: Sequence[int] = (1, 2, 3),
    progress: ProgressFn | None = None,
) -> Comparison:
    """Drive full and reduced model of a configuration with the same multi-sines.

    Parameters
    ----------
    config : MotionSystem or str
        Configuration (its noise is switched off for the describing functions).
    dofs : sequence of str
        DOFs to drive, one at a time.
    signals : sequence of int
        Multi-sines: 1, 2 (Table 5.2) and 3 (4.5-10 Hz).
    progress : callable, optional
        Called with a message before each run.

    """
    ms = resolve(config)
    ms_quiet = ms.replace(name=ms.name, noise=False)
    full = make_platform(ms.platform, "full")
    reduced = ReducedPlatform(ms.platform, rate_hz=full.rate_hz)  # same grid, sample by sample
    out, analytic = {}, {}
    checked = _check_dofs(dofs)
    for dof in checked:
        f, h_full, w_full = _drive(ms_quiet, full, dof, signals)
        _, h_red, w_red = _drive(ms_quiet, reduced, dof, signals)
        diff = np.concatenate([a[2] - b[2] for a, b in zip(w_full, w_red, strict=True)])
        cmd = np.concatenate([a[1] for a in w_full])
        rms = float(np.sqrt(np.mean(diff**2)) / np.sqrt(np.mean(cmd**2)))
        out[dof] = DofResponse(dof, f, h_full, h_red, rms)
        analytic[dof] = ms_quiet.response_at_hz(f)[:, dof_index(dof)]
        if progress:
            progress(f"{ms.name}: full and reduced [DOFs]", len(out), len(checked))
    notes = [] if not ms.noise else ["the configuration's noise was off for these runs"]
    return Comparison(ms_quiet, out, analytic, notes)
