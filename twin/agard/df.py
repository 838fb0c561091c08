"""The describing-function test (§3.3.3, §5.3.1): primary and cross describing functions.

The driven DOF is excited with multi-sines (Table 5.2's two signals by default); at every
excited frequency the describing function is the ratio of the Fourier coefficients of the
measured and the commanded acceleration over the measurement window (Eq 3.6). Cross
describing functions relate the same input to the accelerations measured in the undriven
DOFs. A pure delay is fitted to the phase on top of the configuration's known dynamics
(platform filter, resonance), and a Bode plot shows the analytic model (Eq 5.11) overlaid.

Examples
--------
>>> from twin.agard.session import Session
>>> from twin.measurement.measure import Bench, configure
>>> res = run_df(Session(Bench(configure("mpi"), "reduced")), "pitch", signals=(1,))
>>> round(res.delay_s * 1e3)
35

"""

from __future__ import annotations

import re
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from twin.agard.session import Session
from twin.chain.signals import describing_signal
from twin.core.errors import SignalError
from twin.core.frames import DOF_NAMES, dof_index
from twin.core.plotting import AxesArg, finish, subplots
from twin.core.results import frame, frd
from twin.formats.run_folder import signal_meta
from twin.measurement.describing_function import (
    ResponseMixin,
    dense_frequencies,
    describing_function,
    fit_delay,
    fourier_coefficients,
    neighbour_noise,
    phase_deg,
)
from twin.measurement.measure import Bench, Measurement, driven_dof
from twin.measurement.periodic import periodic_design

if TYPE_CHECKING:
    import control
    import pandas as pd
    from matplotlib.figure import Figure

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]
#: Points below this signal-to-noise ratio are drawn hollow [dB].
LOW_SNR_DB = 6.0


@dataclass(frozen=True, eq=False)
class DfResult(ResponseMixin):
    """Describing functions of one driven DOF.

    Attributes
    ----------
    dof : str
        Driven DOF.
    frequencies_hz : ndarray, shape (m,)
        Excited frequencies, ascending.
    response : ndarray of complex, shape (m,)
        Primary describing function (measured / commanded acceleration).
    cross : dict of str to ndarray of complex
        Cross describing functions: acceleration of each undriven DOF / commanded input.
    model : ndarray of complex, shape (m,)
        The configuration's known dynamics without delay (filter, resonance).
    configured_delay_s : float
        The configuration's total delay [s].
    delay_s : float
        Delay fitted to the phase of ``response / model``, each frequency weighted by its
        signal-to-noise power [s].
    source : str
        What was measured.
    noise : ndarray, shape (m,)
        Standard deviation of ``response`` at each frequency, from the neighbouring
        non-excited bins (:func:`twin.measurement.describing_function.neighbour_noise`).
    delay_equal_weights_s : float
        The delay fitted with every frequency weighted equally (the thesis' fit) [s].

    """

    dof: str
    frequencies_hz: FloatArray
    response: ComplexArray
    cross: dict[str, ComplexArray]
    model: ComplexArray
    configured_delay_s: float
    delay_s: float
    source: str
    noise: FloatArray
    delay_equal_weights_s: float

    @property
    def snr_db(self) -> FloatArray:
        """Signal-to-noise ratio at each frequency, ``20 log10(|H| / noise)`` [dB]."""
        with np.errstate(divide="ignore"):
            return 20 * np.log10(self.gain / self.noise)

    def analytic(self) -> ComplexArray:
        """Return the analytic model (known dynamics times the configured delay) at the lines."""
        return self.model * np.exp(-2j * np.pi * self.frequencies_hz * self.configured_delay_s)

    def analytic_phase_deg(self) -> FloatArray:
        """Phase of :meth:`analytic` at the lines [deg], unwrapped as the continuous curve is.

        The known dynamics change by less than 180 deg between lines, so they are unwrapped
        line to line; the delay's -360 f tau is added exactly (unwrapping the product line to
        line would jump a turn wherever the delay alone turns more than 180 deg between lines).
        """
        f = self.frequencies_hz
        return phase_deg(self.model) - 360.0 * f * self.configured_delay_s

    @property
    def phase_deg(self) -> FloatArray:
        """Measured phase [deg] on the branch nearest the analytic curve's at each line.

        Unwrapping the measured lines alone takes a wrong turn where they are sparse or noisy
        (heave behind the 1 Hz filter: 3.35 Hz at -205 deg, 7.1 Hz at +10 deg); this puts each
        within 180 deg of the model, as a reader compares them. A phase error beyond 180 deg
        (a delay far longer than configured, at high frequency) cannot show here: the fitted
        delay (``delay_s``) is where it shows.
        """
        ref = self.analytic_phase_deg()
        return ref + np.degrees(np.angle(self.response * np.exp(-1j * np.radians(ref))))

    def bounds_95(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        """95 % half-widths from the line noise: gain below and above [dB], phase [deg].

        ``noise`` is the complex response's total standard deviation (RMS of the neighbouring
        bins), so its component along the response - the gain's - and across it - the gain
        times the phase's - each have sd ``noise / sqrt(2)``: 1.96 of those on the gain, and the
        angle they subtend on the phase (90 deg where they reach the gain). The lower gain
        bound is cut at 20 dB below the point (a line whose noise reaches its gain has none).
        """
        g, half = self.gain, 1.96 * self.noise / np.sqrt(2)
        low = 20 * np.log10(g / np.maximum(g - half, 0.1 * g))
        high = 20 * np.log10((g + half) / g)
        phase = np.degrees(np.arcsin(np.clip(half / g, 0.0, 1.0)))
        return low, high, phase

    def to_dict(self) -> dict[str, object]:
        """JSON-ready result (``frequencies_hz``, ``gain``, ``phase_deg``, ``delay_ms``, ...)."""
        a = self.analytic()
        return {
            "test": "describing function",
            "dof": self.dof,
            "source": self.source,
            "frequencies_hz": self.frequencies_hz.tolist(),
            "gain": self.gain.tolist(),
            "gain_db": (20 * np.log10(self.gain)).tolist(),
            "phase_deg": self.phase_deg.tolist(),
            "delay_ms": self.delay_s * 1e3,
            "delay_equal_weights_ms": self.delay_equal_weights_s * 1e3,
            "configured_delay_ms": self.configured_delay_s * 1e3,
            "gain_sd": self.noise.tolist(),
            "snr_db": self.snr_db.tolist(),
            "analytic": {
                "gain": np.abs(a).tolist(),
                "phase_deg": self.analytic_phase_deg().tolist(),
            },
            "cross": {
                dof: {
                    "gain": np.abs(h).tolist(),
                    "phase_deg": phase_deg(h).tolist(),
                }
                for dof, h in self.cross.items()
            },
        }

    def format_table(self) -> str:
        """Plain-text table: frequency, measured gain and phase, Eq 5.11's, signal-to-noise."""
        a = self.analytic()
        lines = [
            f"describing function, {self.dof} ({self.source})",
            f"{'':7} {'measured':>16} {'Eq 5.11':>18}",
            f"{'f [Hz]':>7} {'gain dB':>8} {'deg':>7} {'gain dB':>10} {'deg':>7} {'SNR dB':>7}",
        ]
        phase_a = self.analytic_phase_deg()
        for f, g, p, ga, pa, snr in zip(
            self.frequencies_hz,
            self.gain,
            self.phase_deg,
            np.abs(a),
            phase_a,
            self.snr_db,
            strict=True,
        ):
            lines.append(
                f"{f:7.2f} {20 * np.log10(g):8.2f} {p:7.1f} {20 * np.log10(ga):10.2f}"
                f" {pa:7.1f} {snr:7.1f}"
            )
        lines.append(
            f"fitted delay {self.delay_s * 1e3:.1f} ms, weighted by signal-to-noise "
            f"({self.delay_equal_weights_s * 1e3:.1f} ms with equal weights; "
            f"configured {self.configured_delay_s * 1e3:.1f} ms)"
        )
        return "\n".join(lines)

    def to_frame(self) -> pd.DataFrame:
        """One row per excited line: frequency, measured and Eq 5.11 gain and phase, SNR."""
        a = self.analytic()
        return frame({
            "frequency_hz": self.frequencies_hz, "gain": self.gain,
            "gain_db": 20 * np.log10(self.gain), "phase_deg": self.phase_deg,
            "gain_sd": self.noise, "snr_db": self.snr_db, "analytic_gain": np.abs(a),
            "analytic_phase_deg": self.analytic_phase_deg(),
        })  # fmt: skip

    def to_frd(self) -> control.FrequencyResponseData:
        """Return the measured describing function at its lines, as python-control data (rad/s)."""
        return frd(self.response, self.frequencies_hz, self.dof)

    def plot(
        self, ax: AxesArg = None, *, path: str | None = None, config=None, cross: bool = True
    ) -> Figure:
        """Bode plot: measured points with 95 % error bars, the analytic model, the fitted delay.

        Parameters
        ----------
        ax : sequence of two Axes, optional
            Where to draw: gain and phase; a new figure by default.
        path : str, optional
            Save the figure here.
        config : MotionSystem, optional
            For a smooth analytic curve (otherwise the analytic model at the points).
        cross : bool
            Also show the largest cross describing function.

        """
        fig, (ax_g, ax_p) = subplots(ax, 2, 1, figsize=(6.5, 6), sharex=True)
        model = "Eq 5.11 of the configuration" if config is not None else "Eq 5.11"
        draw_bode(ax_g, ax_p, self, "C0", f"measured {self.dof}", config, model)
        if config is not None:
            fa = dense_frequencies(self.frequencies_hz)
            h0 = config.without_delay().response_at_hz(fa)[:, dof_index(self.dof)]
            hf = h0 * np.exp(-2j * np.pi * fa * self.delay_s)
            label = f"fitted delay {self.delay_s * 1e3:.1f} ms"
            ax_p.semilogx(fa, phase_deg(hf), "C1--", lw=0.8, label=label)
            ax_p.legend(fontsize=8)
        if cross and self.cross:
            worst = max(self.cross, key=lambda d: np.abs(self.cross[d]).max())
            f = self.frequencies_hz
            ax_g.semilogx(
                f, 20 * np.log10(np.abs(self.cross[worst]) + 1e-12), "x", label=f"cross: {worst}"
            )
        ax_g.legend(fontsize=8)
        ax_g.set_title(f"describing function, {self.dof}: {self.source}", fontsize=9)
        return finish(fig, path)


def draw_bode(
    ax_g, ax_p, r: DfResult, colour: str, label: str, config=None, model_label: str | None = None
) -> None:
    """Draw one describing function on gain and phase axes, as a paper's Bode plot.

    Measured points with 95 % error bars from the line noise (hollow below ``LOW_SNR_DB``),
    the phase on the model's branch, the analytic model as a line (smooth through
    ``config``'s Eq 5.11 when given, through its python-control transfer function; in the
    legend as ``model_label``), log frequency, grids, units.
    """
    f, k = r.frequencies_hz, dof_index(r.dof)
    if config is not None:
        fa = dense_frequencies(f)
        ha = config.transfer_function(k).response_at_hz(fa)  # python-control
        ax_g.semilogx(fa, 20 * np.log10(np.abs(ha)), "-", color=colour, lw=0.8, alpha=0.8,
                      label=model_label)  # fmt: skip
        ax_p.semilogx(fa, phase_deg(ha), "-", color=colour, lw=0.8, alpha=0.8)
    else:
        ax_g.semilogx(f, 20 * np.log10(np.abs(r.analytic())), "-", color=colour, lw=0.8,
                      label=model_label)  # fmt: skip
        ax_p.semilogx(f, r.analytic_phase_deg(), "-", color=colour, lw=0.8)
    low, high, dphase = r.bounds_95()
    gain_db, phase = 20 * np.log10(r.gain), r.phase_deg
    good = r.snr_db >= LOW_SNR_DB
    for sel, face, what in ((good, colour, ""), (~good, "none", f", SNR < {LOW_SNR_DB:g} dB")):
        if sel.any():
            ax_g.errorbar(f[sel], gain_db[sel], yerr=[low[sel], high[sel]], fmt="o", mfc=face,
                          mec=colour, ecolor=colour, capsize=2, ms=5,
                          label=f"{label} (95 %){what}")  # fmt: skip
            ax_p.errorbar(f[sel], phase[sel], yerr=dphase[sel], fmt="o", mfc=face, mec=colour,
                          ecolor=colour, capsize=2, ms=5)  # fmt: skip
    ax_g.set_xscale("log")
    ax_g.set_ylabel("gain [dB]")
    ax_p.set_ylabel("phase [deg]")
    ax_p.set_xlabel("frequency [Hz]")
    for ax in (ax_g, ax_p):
        ax.grid(True, which="major", alpha=0.5)
        ax.grid(True, which="minor", alpha=0.2)


def analyse_df(m: Measurement, dof: str | None = None) -> DfResult:
    """Return the describing functions of one measurement (design from its signal)."""
    k = driven_dof(m, dof)
    return analyse_windows(m, k, [periodic_design(m, k)])


def analyse_windows(
    m: Measurement, k: int, designs: Sequence[tuple[FloatArray, tuple[float, float]]]
) -> DfResult:
    """Return the describing functions of DOF ``k`` from windows of one measurement.

    Parameters
    ----------
    m : Measurement
        The run (e.g. a whole test schedule).
    k : int
        Driven DOF.
    designs : sequence of (frequencies [Hz], (start, end) [s])
        Each window holds whole periods of its frequencies (a schedule's sine moves, or a
        run's one design); frequencies met in several windows are all kept.

    """
    u = m.commanded[:, k]
    parts = []
    for f, window in designs:
        f = np.asarray(f, dtype=float)
        U = fourier_coefficients(m.t, u, f, window)
        h = describing_function(m.t, u, m.measured[:, k], f, window)
        noise = neighbour_noise(m.t, m.measured[:, k], f, window) / np.abs(U)
        cross = [describing_function(m.t, u, m.measured[:, j], f, window) for j in range(6)]
        parts.append((f, h, noise, cross))
    f = np.concatenate([p[0] for p in parts])
    order = np.argsort(f, kind="stable")
    h, noise = (np.concatenate([p[i] for p in parts])[order] for i in (1, 2))
    cross = {
        DOF_NAMES[j]: np.concatenate([p[3][j] for p in parts])[order] for j in range(6) if j != k
    }
    f = f[order]
    model = m.config.without_delay().response_at_hz(f)[:, k]
    return _result(DOF_NAMES[k], f, h, cross, model, m.config.delays_s[k], m.source, noise)


def _result(dof, f, h, cross, model, delay, source, noise) -> DfResult:
    snr = np.abs(h) ** 2 / np.where(noise > 0, noise, np.nan) ** 2
    weights = np.where(np.isfinite(snr), snr, 1.0) if np.any(noise > 0) else None
    return DfResult(
        dof,
        f,
        h,
        cross,
        model,
        delay,
        fit_delay(f, h, model, weights),
        source,
        noise,
        fit_delay(f, h, model),
    )


def joined_sources(sources: Sequence[str]) -> str:
    """Return the sources of joined results in one phrase.

    Runs of one simulated bench (``"mpi (full) run seed 0"``, ``... seed 1``) read
    ``"mpi (full): runs with seeds 0, 1"``; other sources (run folders) are listed.
    """
    seeds: dict[str, list[int]] = {}
    others = []
    for source in dict.fromkeys(sources):
        run = re.fullmatch(r"(.*) run seed (\d+)", source)
        if run:
            seeds.setdefault(run[1], []).append(int(run[2]))
        else:
            others.append(source)
    joined = [f"{bench}: run{'s with seeds' if len(s) > 1 else ' with seed'} "
              f"{', '.join(map(str, sorted(s)))}" for bench, s in seeds.items()]  # fmt: skip
    return "; ".join(joined + sorted(others))


def combine(results: Sequence[DfResult]) -> DfResult:
    """Join the describing functions of several runs of the same DOF (e.g. signals 1 and 2)."""
    if len({r.dof for r in results}) != 1:
        raise SignalError("only describing functions of the same DOF can be combined")
    f = np.concatenate([r.frequencies_hz for r in results])
    order = np.argsort(f)

    def join(name: str) -> NDArray:
        return np.concatenate([getattr(r, name) for r in results])[order]

    cross = {d: np.concatenate([r.cross[d] for r in results])[order] for d in results[0].cross}
    return _result(
        results[0].dof,
        f[order],
        join("response"),
        cross,
        join("model"),
        results[0].configured_delay_s,
        joined_sources([r.source for r in results]),
        join("noise"),
    )


def run_df(session: Session, dof: str, signals: Sequence[int] = (1, 2)) -> DfResult:
    """Run the Table 5.2 multi-sines in ``dof`` on a session's bench and analyse them."""
    results = []
    session.expect(len(signals), f"describing function {dof}")
    for number in signals:
        sig = describing_signal(number, dof, settle_s=None)
        m = session.measure(sig, f"multisine{number}-{dof}")
        results.append(analyse_df(m, dof))
    result = combine(results)
    if session.recorder is not None:
        session.recorder.log_describing_function(result, session.bench.config)
    return result


def sweep(
    bench: Bench, dofs: Sequence[str], signals: Sequence[int] = (1, 2), workers: int = 2
) -> dict[str, DfResult]:
    """Run the describing-function sweep of several DOFs, runs in parallel threads (no sinks).

    Runs are numbered as a :class:`Session` numbers them (DOF by DOF, signal by signal), so
    the seeds and the results equal those of :func:`run_df` on a fresh session.
    """
    jobs = [(dof, number) for dof in dofs for number in signals]

    def one(k: int) -> Measurement:
        dof, number = jobs[k]
        sig = describing_signal(number, dof, settle_s=None)
        sim = bench.prepare(sig.commands, k, f"multisine{number}-{dof}").collect()
        return bench.measure(sim, {"signal": signal_meta(sig)})

    with ThreadPoolExecutor(max(1, workers)) as pool:  # MuJoCo and NumPy release the GIL
        measurements = list(pool.map(one, range(len(jobs))))
    out = {}
    for dof in dofs:
        parts = [
            analyse_df(m, dof) for (d, _), m in zip(jobs, measurements, strict=True) if d == dof
        ]
        out[dof] = combine(parts)
    return out
