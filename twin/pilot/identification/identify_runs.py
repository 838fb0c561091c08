"""Identify the pilot from recorded ``twin-pilot/1`` runs (§6.3.4), as ``twin pilot identify``.

One or several runs of one condition (repetitions: the same forcing functions, as ``twin
pilot run --runs N --out`` writes them) are read and checked; their last 81.92 s are averaged
at the forcing functions' lines, as the thesis averaged its five; and three estimates are
made of them:

- the Fourier-coefficient (FC) estimates of the pilot's responses H_pe and H_ptheta at the
  lines (:func:`twin.pilot.identification.fc.fc_estimate`);
- the ARX estimates at the same lines, orders chosen by
  :func:`twin.pilot.identification.arx.select_orders`;
- the maximum-likelihood fit of the pilot model (Eq 6.5-6.7) in the closed loop through the
  motion system the runs were flown with
  (:func:`twin.pilot.identification.mle.fit_pitch_pilot`), which is
  the one given, checked against the runs' ``theta_felt``, or the built-in one ``theta_felt``
  follows (:func:`twin.pilot.identification.felt_motion.match_motion`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from twin.core.errors import SignalError, UsageError
from twin.core.plotting import AxesArg, finish, subplots
from twin.core.results import frame

if TYPE_CHECKING:
    import pandas as pd
    from matplotlib.figure import Figure

    from twin.chain.config import MotionSystem
    from twin.core.progress import ProgressFn
    from twin.pilot.identification.arx import ArxModel
    from twin.pilot.identification.fc import FcEstimate
    from twin.pilot.identification.felt_motion import MotionMatch
    from twin.pilot.identification.mle import PilotFit
    from twin.pilot.models.pitch import PitchPilot

#: A run read for identification: its name, its columns, the last 81.92 s and its rate [Hz].
_Window = tuple[str, dict, dict, float]


@dataclass(frozen=True)
class PilotIdentification:
    """The pilot identified from recorded runs (:func:`identify`).

    Attributes
    ----------
    runs : tuple of str
        The runs, as given.
    rate_hz : float
        Their sample rate.
    continuous_loop : bool
        The fit modelled a loop that did not hold u over each sample.
    fc : FcEstimate
        FC estimates of the repetitions' mean at the forcing functions' lines.
    arx : ArxModel
        The ARX model of the repetitions' mean
        (at :data:`twin.pilot.identification.arx.ARX_RATE_HZ`).
    arx_h_pe, arx_h_ptheta : ndarray of complex
        The ARX model's responses at the FC estimate's lines.
    mle : PilotFit
        The maximum-likelihood fit of Eq 6.5-6.7 in the closed loop.
    motion : MotionMatch
        The motion system the fit modelled and where it came from.

    """

    runs: tuple[str, ...]
    rate_hz: float
    continuous_loop: bool
    fc: FcEstimate
    arx: ArxModel
    arx_h_pe: np.ndarray
    arx_h_ptheta: np.ndarray
    mle: PilotFit
    motion: MotionMatch

    @property
    def label(self) -> str:
        """The runs as a message names them: the first, and how many more."""
        first = self.runs[0]
        return first if len(self.runs) == 1 else f"{first} and {len(self.runs) - 1} more"

    def to_dict(self) -> dict[str, Any]:
        """Return the identification as strict JSON (``twin pilot identify --json``)."""
        fc = self.fc
        return {
            "runs": list(self.runs),
            "omega_rad_s": fc.omega_rad_s.tolist(),
            "fc": {
                "h_pe_gain": np.abs(fc.h_pe[0]).tolist(),
                "h_pe_phase_deg": np.degrees(np.angle(fc.h_pe[0])).tolist(),
                "h_ptheta_gain": np.abs(fc.h_px[0]).tolist(),
                "h_ptheta_phase_deg": np.degrees(np.angle(fc.h_px[0])).tolist(),
            },
            "arx": {
                "orders": self.arx.orders.__dict__,
                "h_pe_gain": np.abs(self.arx_h_pe).tolist(),
                "h_ptheta_gain": np.abs(self.arx_h_ptheta).tolist(),
            },
            "mle": self.mle.to_dict(),
            "motion": self.motion.to_dict(),
        }

    def to_frame(self) -> pd.DataFrame:
        """Return the FC and ARX estimates, one row per forcing-function line."""
        fc = self.fc
        return frame({
            "omega_rad_s": fc.omega_rad_s,
            "fc_h_pe_gain": np.abs(fc.h_pe[0]),
            "fc_h_pe_phase_deg": np.degrees(np.angle(fc.h_pe[0])),
            "fc_h_ptheta_gain": np.abs(fc.h_px[0]),
            "fc_h_ptheta_phase_deg": np.degrees(np.angle(fc.h_px[0])),
            "arx_h_pe_gain": np.abs(self.arx_h_pe),
            "arx_h_ptheta_gain": np.abs(self.arx_h_ptheta),
        })  # fmt: skip

    def plot(self, ax: AxesArg = None, *, path: str | None = None) -> Figure:
        """Plot the pilot's visual (H_pe) and motion (H_ptheta) gains: FC points, ARX line.

        Parameters
        ----------
        ax : sequence of two Axes, optional
            Where to draw: H_pe's gain, then H_ptheta's; a new figure by default.
        path : str, optional
            Save the figure here.

        Returns
        -------
        matplotlib.figure.Figure

        """
        fc = self.fc
        fig, axes = subplots(ax, 1, 2, figsize=(9, 3.5), panels="H_pe's and H_ptheta's gain")
        pairs = ((fc.h_pe[0], self.arx_h_pe, "H_pe"), (fc.h_px[0], self.arx_h_ptheta, "H_ptheta"))
        for a, (h_fc, h_arx, name) in zip(axes, pairs, strict=True):
            a.semilogx(fc.omega_rad_s, 20 * np.log10(np.abs(h_fc)), "o", label="FC")
            a.semilogx(fc.omega_rad_s, 20 * np.log10(np.abs(h_arx)), "-", label="ARX")
            a.set_xlabel("frequency [rad/s]")
            a.set_ylabel("gain [dB]")
            a.set_title(f"{name} from {self.label}", fontsize=9)
            a.grid(True, which="both", alpha=0.3)
            a.legend(fontsize=8)
        return finish(fig, path)

    def format_text(self) -> str:
        """Return the identification as ``twin pilot identify`` prints it.

        The MLE's fit and each parameter with its spread (and, where it applies, why it is
        not identifiable), the minima the data do or do not rule out, parameters at the end
        of their range, and the ARX structure.
        """
        from twin.pilot.identification.mle import LOWER, PARAMETERS, UPPER, fit_text

        mle, cfg = self.mle, self.motion.config
        p = mle.pilot
        loop = "continuous" if self.continuous_loop else f"held over each {1e3 / self.rate_hz:g} ms"
        reps = "" if len(self.runs) == 1 else f", {len(self.runs)} repetitions averaged"
        lines = [
            f"{self.label}: MLE fit (Eq 6.5-6.7, closed loop through {cfg.name}'s pitch "
            f"response, u {loop}{reps}), VAF {mle.vaf_percent:.1f} %",
            "  " + self.motion.format(),
            "  " + fit_text(mle.evidence["fit"]),
        ]
        own_sd = mle.crlb_at_estimate or mle.crlb
        for name, sd in mle.crlb.items():
            value = getattr(p, name)
            span = ""
            if mle.intervals is not None:
                span = "  2-sd interval " + interval_text(name, *mle.intervals[name])
            if name in mle.on_range_bound:
                sd_text = "at the end of its range: no sd"
            elif not np.isfinite(sd):  # JSON: null
                sd_text = "no finite sd: the data do not pin it down here"
            elif own_sd[name] == sd:
                sd_text = f"CRLB sd {sd:.4f}"
            else:
                sd_text = (f"sd {sd:.4f}: the CRLB here, {own_sd[name]:.4f}, widened for the "
                           "fits below")  # fmt: skip
            flag = ""
            if name in mle.unidentifiable:
                why = ("at the end of its range" if name in mle.on_range_bound else
                       "sd above a third of its value" if not sd < abs(value) / 3 else
                       "its likelihood-ratio interval reaches far beyond 2 sd")  # fmt: skip
                flag = f"  not identifiable ({why})"
            lines.append(f"  {name:9s} {value:8.4f}  ({sd_text}){span}{flag}")

        def moved(other: PitchPilot, skip: str = "") -> str:
            far = [f"{n} {getattr(other, n):.4f}" for n in own_sd
                   if n != skip and abs(getattr(other, n) - getattr(p, n)) > own_sd[n]]  # fmt: skip
            return ", ".join(far) or "every parameter within one CRLB of the estimate"

        def end_of(name: str, at: float) -> str:
            side = "lower" if at == LOWER[PARAMETERS.index(name)] else "upper"
            return f"the {side} end of its range, {at:g}"

        why = mle.evidence.get("competing_minima", [])
        for other, ev in zip(mle.competing, why, strict=True):
            lines.append(f"  another minimum the data do not rule out (chi-square "
                         f"+{ev['delta_chi2']:.2f} over the best, Vuong's z {ev['vuong_z']:.2f}; "
                         f"it competes within 3.84 or below z 1.96): {moved(other)}")  # fmt: skip
        ruled = mle.evidence.get("ruled_out_minima", [])
        if ruled:
            rises = ", ".join(f"+{ev['delta_chi2']:.1f}" for ev in ruled[:4])
            lines.append(f"  {len(ruled)} other minim{'um' if len(ruled) == 1 else 'a'} the data "
                         f"rule out (chi-square {rises}{', ...' if len(ruled) > 4 else ''}): a "
                         "bound is widened for the selection where its estimate is near the "
                         "limit at which one would compete again "
                         "(twin.pilot.identification.selection)")  # fmt: skip
        for name, other in mle.on_range_bound.items():
            at, k = getattr(other, name), PARAMETERS.index(name)
            end, way = (LOWER[k], "up") if at > getattr(p, name) else (UPPER[k], "down")
            lines.append(f"  {name} estimated at {end_of(name, end)}: the data allow it {way} to "
                         f"{at:.4f} (chi-square +3.84, the rest refitted); the fit there: "
                         f"{moved(other, name)}")  # fmt: skip
        for name, other in mle.range_end.items():
            rise = mle.evidence["range_end"][name]
            lines.append(f"  {name} may be at {end_of(name, getattr(other, name))}: held there, "
                         f"the rest refitted, the chi-square rises by {rise:.2f} (< 3.84); the "
                         f"fit there: {moved(other, name)}")  # fmt: skip
        if mle.competing or mle.on_range_bound or mle.range_end:
            lines.append("  (the fits above list the parameters more than one CRLB from the "
                         "estimate)")  # fmt: skip
        lines.append(f"  ARX structure {self.arx.orders}; FC and ARX responses at "
                     f"{self.fc.omega_rad_s.size} lines in --json")  # fmt: skip
        return "\n".join(lines)


def interval_text(name: str, low: float, high: float) -> str:
    """Return ``[low, high]``, saying so where an end is the fit's range, not the data's bound.

    Examples
    --------
    >>> interval_text("k_v", 1.2, 1.8)
    '[1.2000, 1.8000]'

    """
    from twin.pilot.identification.mle import LOWER, PARAMETERS, UPPER

    k = PARAMETERS.index(name)
    open_ends = [side for side, hit in (("below", low <= LOWER[k] and LOWER[k] > 0),
                                        ("above", high >= UPPER[k])) if hit]  # fmt: skip
    return f"[{low:.4f}, {high:.4f}]" + (f" (open {' and '.join(open_ends)})" if open_ends else "")


def read_window(path: str | Path) -> _Window:
    """Read a ``twin-pilot/1`` run; return its name, columns, last 81.92 s and rate [Hz].

    Raises
    ------
    SignalError
        Naming the file: shorter than the window, or without excitation in it.

    """
    from twin.pilot.models.forcing import MEASUREMENT_S
    from twin.pilot.models.records import read_pilot_csv

    name = str(path)
    d = read_pilot_csv(path)
    rate = float(d["rate_hz"])
    n = round(MEASUREMENT_S * rate)
    if d["t"].size < n:
        raise SignalError(
            f"{name}: needs at least {MEASUREMENT_S} s of data ({n} samples at {rate:g} Hz); "
            f"has {d['t'].size} samples"
        )
    w = {k: v[-n:] for k, v in d.items() if k != "rate_hz"}
    felt = "theta_felt" if "theta_felt" in w else "theta"
    flat = [k for k in ("ft", "fd", "e", "u", felt) if np.ptp(w[k]) == 0]
    if flat:
        raise SignalError(
            f"{name}: the run carries no excitation: {', '.join(flat)} constant over the "
            f"last {MEASUREMENT_S} s (a tracking run has the Table 6.2 forcing functions in ft "
            "and fd, the pilot's e and u, and the motion the pilot felt)"
        )
    return name, d, w, rate


def _check_repetitions(runs: Sequence[_Window]) -> None:
    """Refuse runs that are not repetitions of the first: columns, grid, forcing, the same u."""
    name, d, w, rate = runs[0]
    for other, od, ow, orate in runs[1:]:
        if set(od) != set(d):
            cols = [",".join(k for k in x if k != "rate_hz") for x in (od, d)]
            raise SignalError(f"{other}: columns {cols[0]}; {name} has {cols[1]}: repetitions "
                              "must have the same columns")  # fmt: skip
        if not np.isclose(orate, rate, rtol=1e-9) or ow["t"].size != w["t"].size:
            raise SignalError(f"{other}: {orate:g} Hz, {ow['t'].size} samples in the window; "
                              f"{name} has {rate:g} Hz, {w['t'].size}: repetitions must share "
                              "the time grid")  # fmt: skip
        differ = [k for k in ("ft", "fd") if not np.allclose(ow[k], w[k], rtol=1e-6, atol=1e-9)]
        if differ:
            verb = "differ" if differ[1:] else "differs"
            raise SignalError(f"{other}: {' and '.join(differ)} {verb} from {name}'s: "
                              "repetitions must share the forcing functions (the thesis' five "
                              "runs per condition did)")  # fmt: skip
        if np.array_equal(ow["u"], w["u"]):
            raise SignalError(f"{other}: u is {name}'s, sample for sample: the same run twice "
                              "is not a repetition")  # fmt: skip


def identify(
    runs: Sequence[str | Path],
    config: str | MotionSystem | None = None,
    *,
    continuous_loop: bool = False,
    intervals: bool = False,
    progress: ProgressFn | None = None,
) -> PilotIdentification:
    """Identify the pilot from ``twin-pilot/1`` runs: FC, ARX and the MLE (§6.3.4).

    Parameters
    ----------
    runs : sequence of str or Path
        One run, or repetitions of one condition (the same time grid and forcing functions,
        as ``twin pilot run --runs N --out`` writes them): their last 81.92 s are averaged at
        the forcing functions' lines, as the thesis averaged its five.
    config : str or MotionSystem, optional
        The motion system the runs were flown with (a name, a ``twin-config/1`` file or a
        configuration): the fit models the loop through it; checked against the runs'
        ``theta_felt``. None: the built-in one ``theta_felt`` follows (refused if none is
        within 5 %), or ``condition-1`` for runs without ``theta_felt``.
    continuous_loop : bool
        The recorded loop did not hold u over each sample (default: it did, as the twin's and
        a digital simulator's do; the MLE models that zero-order hold).
    intervals : bool
        Also each parameter's likelihood-ratio interval (2 sd) from the profile likelihood
        (typically 5-35 s more).
    progress : callable, optional
        Told what the fit is doing (:class:`twin.core.progress.Progress`).

    Returns
    -------
    PilotIdentification
        The FC, ARX and MLE estimates and the motion system fitted through.

    Raises
    ------
    UsageError
        No runs, or a run given twice.
    SignalError
        A run that cannot be read, is shorter than 81.92 s or carries no excitation; runs that
        are not repetitions of one condition; a ``theta_felt`` no configuration explains; an
        analysis that refuses the data. The message names the run.

    Examples
    --------
    >>> from twin.pilot.identification.identify_runs import identify
    >>> result = identify(["out/pilot-1.csv", "out/pilot-2.csv"],
    ...                   "condition-8")  # doctest: +SKIP
    >>> result.mle.pilot.k_v  # doctest: +SKIP
    1.52
    >>> sorted(result.to_dict())  # doctest: +SKIP
    ['arx', 'fc', 'mle', 'motion', 'omega_rad_s', 'runs']

    """
    from twin.chain.config import motion_system
    from twin.pilot.identification.arx import ARX_RATE_HZ, decimate, select_orders
    from twin.pilot.identification.fc import fc_estimate
    from twin.pilot.identification.felt_motion import felt_mismatch, match_motion
    from twin.pilot.identification.mle import fit_pitch_pilot
    from twin.pilot.models.forcing import pitch_task

    if not runs:
        raise UsageError("no runs: give at least one twin-pilot/1 file")
    given = motion_system(config) if isinstance(config, str) else config
    seen: dict[Path, str] = {}
    for path in map(str, runs):
        resolved = Path(path).resolve()
        if resolved in seen:
            again = "given twice" if seen[resolved] == path else f"{seen[resolved]} again"
            raise UsageError(f"{path} is {again}: give each repetition once")
        seen[resolved] = path
    windows = [read_window(path) for path in runs]
    _check_repetitions(windows)
    name, d, w, rate = windows[0]
    label = name if len(windows) == 1 else f"{name} and {len(windows) - 1} more"
    try:
        motion = match_motion(d, given)
    except SignalError as e:
        raise SignalError(f"{name}: {e}") from None
    cfg = motion.config
    if motion.mismatch is not None:  # every repetition felt the motion system the first did
        for other, od, _, _ in windows[1:]:
            off = felt_mismatch(od["theta"], od["theta_felt"], rate, cfg)
            if off > max(2 * motion.mismatch, motion.mismatch + 0.01):
                raise SignalError(
                    f"{other}: theta_felt differs from {cfg.name}'s response to theta by "
                    f"{off:.1%} rms, {name}'s by {motion.mismatch:.1%}: repetitions must be "
                    "flown through one motion system"
                )
    felt_key = "theta_felt" if "theta_felt" in w else "theta"
    # the repetitions' mean: FC and ARX of the averaged run (linear: the lines' average)
    mean = {k: np.mean([r[2][k] for r in windows], axis=0) for k in ("e", "u", felt_key)}
    u_runs = np.array([r[2]["u"] for r in windows]) if len(windows) > 1 else w["u"]
    fd, ft = pitch_task()
    try:  # the analyses' refusals name the runs they refuse
        fc = fc_estimate(mean["e"][None], mean["u"][None], mean[felt_key][None], fd, ft,
                         w["fd"], w["ft"])  # fmt: skip
        arx = select_orders(*(decimate(mean[k], rate, ARX_RATE_HZ) for k in ("u", "e", felt_key)),
                            rate_hz=ARX_RATE_HZ)  # fmt: skip
        h_pe, h_px = arx.responses(fc.omega_rad_s)
        mle = fit_pitch_pilot(w["ft"], w["fd"], u_runs, cfg, rate, hold=not continuous_loop,
                              progress=progress, intervals=intervals)  # fmt: skip
    except SignalError as e:
        raise SignalError(f"{label}: {e}") from None
    return PilotIdentification(
        runs=tuple(r[0] for r in windows),
        rate_hz=rate,
        continuous_loop=continuous_loop,
        fc=fc,
        arx=arx,
        arx_h_pe=h_pe,
        arx_h_ptheta=h_px,
        mle=mle,
        motion=motion,
    )
