"""Runs with hidden effects: the seeded generator the diagnosis is tested (and shown) on.

:func:`draw` picks, from a seed only, a platform (MPI or SRS with their nominal configurations
and noise), a DOF (any of the six), one or two effects with random parameters and an IMU whose
noise is drawn between 0.3 and 3 times the data sheet's (log-uniform: a real unit is rarely
the nominal one); :func:`record` simulates both Table 5.2 multi-sines through the nominal
configuration *plus* the effects, with that IMU, and writes ``twin-run/1`` folders whose
``meta.json`` names only the nominal configuration, as a real platform's recording would.

Drawing rule (parameters only where the runs could reveal them): a draw is kept when, on the
nominal twin's prediction of the two runs and the drawn IMU's noise, (1) every effect's
expected BIC improvement on top of the others (:func:`twin.diagnose.detect.expected_delta_bic`)
is at least ``DETECTABLE_FACTOR`` times the naming threshold and (2) the Cramér-Rao standard
deviation of every parameter, fitted jointly, is at most a third of the test's tolerance (delay
5 ms, others 20 %), so that a fit within tolerance is likely, and (3) for two effects, no other
single or pair of linear effects explains their noise-free lines within the naming margin (they
can be told apart at all); otherwise it is drawn again (the count is returned). Motion noise
(``noise``) exists only where the configuration has it (the MPI's heave), so it is drawn only
there, 1.3-10 times larger or smaller; with the IMU's noise level unknown it is told from the
IMU's only by its shape below 1 Hz, so the rule admits it large or behind a quiet IMU.

With ``nuisance=True`` (opt-in: without it every draw is as before, bit for bit) what is
nominal varies too, as on a real platform (a generator that varies only the hidden effect
flatters the diagnosis); the diagnosis is still told the nominal configuration only. Drawn per
draw from a stream of its own (seeded by the draw's seed, so the platform, DOF, effects and
IMU of an attempt are those the draw without nuisances gives), see :class:`Nuisance` and
:data:`NUISANCE_RANGES`:

- the motion-noise level (Eq 5.10), where the configuration has one (the MPI's heave),
  0.5-2 times (log-uniform): §5.4.4 fits Eq 5.10 to the *mean* of the measured spectra and
  §3.4.1 shows the noise ratio changing with the input amplitude; the thesis gives no spread,
  so this factor of 2 either way is an assumption;
- the platform filter's break frequency (Eq 5.1), where the configuration has a filter,
  +-10 % (uniform): the thesis gives no tolerance; it validates the filter by Bode plots only
  ("very similar to the analytic response", §5.5.2, Fig 5.7; "follows the analytical model
  well", §5.6.2.1, Fig 5.9), and +-10 % at f_b is 0.8 dB and 5.5 deg, about what such a
  plot, read by eye, shows;
- the signal's amplitudes, 0.5-1.2 times Table 5.2's (as :mod:`twin.diagnose.hidden_physics`);
- the run length: the measurement window holds one or two base periods (20 or 40 s; Table
  5.2's lines are multiples of 0.05 Hz, so 20 s is the shortest window the design allows).

The drawing rule is then judged on the runs as they are recorded (amplitudes and window) and,
for motion noise, on its level times the nuisance factor; the break frequency's variation is
not part of it (the diagnosis is not told it).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from itertools import combinations
from pathlib import Path

import numpy as np

from twin.chain.config import MotionSystem, motion_system
from twin.chain.extensions import DOF_CHANNEL, EFFECTS, Extension
from twin.chain.imu import ImuSpec
from twin.chain.signals import (
    WINDOW_S,
    DescribingSignal,
    describing_signal,
    periodic_signal,
    table_5_2,
)
from twin.chain.simulate import default_imu, prepare
from twin.core.errors import SignalError
from twin.core.frames import DOF_NAMES
from twin.diagnose.candidates import DYNAMIC, Model, fit_set, numeric_names
from twin.diagnose.data import Case, Channel, measurement_channels, nominal_imu
from twin.diagnose.detect import expected_delta_bic, expected_noise_delta_bic, fisher_std
from twin.diagnose.evidence import Lines, lines, nominal_line_sd
from twin.diagnose.residuals import segment
from twin.diagnose.select import BIC_MARGIN
from twin.formats.run_folder import execute, run_meta, signal_meta
from twin.measurement.measure import clean_config, from_imu

#: The effects the generator hides: the chain's vocabulary as the diagnosis fits it to the
#: lines (``platform_lag``, the platform-side reading of a ``sensor_filter``, is drawn by the
#: tests of the sensor-or-platform judgement instead, tests/test_diagnose_sensor_side.py;
#: ``imu_alignment`` is not fitted to one DOF's lines).
DRAWN = tuple(e for e in EFFECTS if e not in ("platform_lag", "imu_alignment"))

#: Expected evidence of a drawn effect, in multiples of the naming threshold.
DETECTABLE_FACTOR = 3.0
#: Tolerances of the hidden-effect tests: absolute for delay [s], relative otherwise.
TOLERANCE = {"extra_delay_s": 0.005}
RELATIVE_TOLERANCE = 0.2
PLATFORMS = ("mpi", "srs")
DOFS = DOF_NAMES
#: Range of the drawn IMU noise, in multiples of the data sheet's (log-uniform).
IMU_NOISE = (0.3, 3.0)
#: Key of the nuisances' random stream (``SeedSequence([seed, NUISANCE_STREAM])``).
NUISANCE_STREAM = 7


@dataclass(frozen=True)
class NuisanceRanges:
    """Ranges the nominal's nuisance parts are drawn from (see the module docstring).

    Attributes
    ----------
    motion_noise : (float, float)
        Factor on the configuration's motion noise (log-uniform).
    filter_break : float
        Relative spread of the platform filter's break frequency (uniform, +-).
    amplitude : (float, float)
        Factor on the signals' amplitudes (uniform).
    periods : tuple of int
        Measurement windows, in base periods of 20 s (one drawn, equally likely).

    """

    motion_noise: tuple[float, float] = (0.5, 2.0)
    filter_break: float = 0.10
    amplitude: tuple[float, float] = (0.5, 1.2)
    periods: tuple[int, ...] = (1, 2)


#: The ranges :func:`draw` and :func:`clean` use with ``nuisance=True``.
NUISANCE_RANGES = NuisanceRanges()


@dataclass(frozen=True)
class Nuisance:
    """How a draw's truth differs from the nominal besides its hidden effects.

    Attributes
    ----------
    motion_noise : float
        Factor on the motion noise (1: the configuration has none, or the nominal level).
    filter_break : float
        Factor on the platform filter's break frequency (1: no filter, or the nominal).
    amplitude : float
        Factor on the Table 5.2 amplitudes.
    periods : int
        Measurement window in base periods of :data:`twin.chain.signals.WINDOW_S`.

    """

    motion_noise: float = 1.0
    filter_break: float = 1.0
    amplitude: float = 1.0
    periods: int = 1

    @property
    def window_s(self) -> float:
        """The measurement window [s]."""
        return WINDOW_S * self.periods

    def describe(self) -> str:
        """One line: the nuisances."""
        return (
            f"motion noise x{self.motion_noise:.2f}, break x{self.filter_break:.3f}, "
            f"amplitude x{self.amplitude:.2f}, window {self.window_s:g} s"
        )


def draw_nuisance(
    seed: int, attempt: int, config: MotionSystem, ranges: NuisanceRanges = NUISANCE_RANGES
) -> Nuisance:
    """Draw the nuisances of one attempt of a draw (a stream of their own; see the module).

    Parameters
    ----------
    seed : int
        The draw's seed.
    attempt : int
        The attempt (0 for the first; each redraw draws the nuisances anew).
    config : MotionSystem
        The nominal configuration: motion noise and break frequency vary only where it has them.
    ranges : NuisanceRanges
        The ranges.

    Returns
    -------
    Nuisance

    """
    rng = np.random.default_rng(np.random.SeedSequence([seed, NUISANCE_STREAM, attempt]))
    lo, hi = ranges.motion_noise
    noise = float(np.exp(rng.uniform(np.log(lo), np.log(hi))))
    brk = float(rng.uniform(1 - ranges.filter_break, 1 + ranges.filter_break))
    amplitude = float(rng.uniform(*ranges.amplitude))
    periods = int(rng.choice(ranges.periods))
    return Nuisance(
        noise if config.noise else 1.0,
        brk if config.filter_break_hz is not None else 1.0,
        amplitude,
        periods,
    )


@dataclass(frozen=True)
class Hidden:
    """A drawn case.

    Attributes
    ----------
    seed : int
        The seed it was drawn from.
    config : MotionSystem
        Nominal configuration (what ``meta.json`` says).
    dof : str
        Driven DOF.
    extensions : tuple of Extension
        The hidden effects (empty: a clean run).
    imu_noise : float
        The recording IMU's noise over the data sheet's.
    redraws : int
        Draws rejected by the detectability rule.
    nuisance : Nuisance or None
        How the nominal's nuisance parts differ in the truth (None: they do not).

    """

    seed: int
    config: MotionSystem
    dof: str
    extensions: tuple[Extension, ...] = ()
    imu_noise: float = 1.0
    redraws: int = 0
    nuisance: Nuisance | None = None

    @property
    def extension(self) -> Extension | None:
        """The first hidden effect (None: a clean run)."""
        return self.extensions[0] if self.extensions else None

    @property
    def truth(self) -> MotionSystem:
        """The configuration the runs are simulated with (nominal + nuisances + effects)."""
        return _truth(self.config, self.extensions, self.nuisance)

    @property
    def effects(self) -> tuple[str, ...]:
        """The hidden effects' names."""
        return tuple(e.effect for e in self.extensions)

    def signal(self, number: int) -> DescribingSignal:
        """Return Table 5.2 run ``number`` as recorded (the nuisances' amplitude and window)."""
        return hidden_signal(number, self.dof, self.nuisance)

    def describe(self) -> str:
        """One line: the draw."""
        what = " + ".join(e.describe() for e in self.extensions) or "clean"
        text = f"seed {self.seed}: {self.config.name} {self.dof}, {what}; IMU noise "
        text += f"x{self.imu_noise:.2f}"
        return text + (f"; {self.nuisance.describe()}" if self.nuisance is not None else "")

    @property
    def imu(self) -> ImuSpec:
        """The recording IMU (the platform's ADIS16355 with the drawn noise)."""
        return default_imu(self.config.platform).with_noise(self.imu_noise)


def _parameters(effect: str, rng: np.random.Generator, config: MotionSystem, dof: str) -> dict:
    u = rng.uniform
    sign = rng.choice([-1.0, 1.0])
    if effect == "delay":
        return {
            "extra_delay_s": float(u(0.01, 0.08) if sign > 0 else -u(0.005, 0.9 * config.delay_s))
        }
    if effect == "gain":
        return {"gain": float(np.exp(sign * u(np.log(1.08), np.log(1.5))))}
    if effect == "platform_filter":
        if config.filter_break_hz is None:
            return {"break_hz": float(np.exp(u(np.log(1.0), np.log(8.0))))}
        f = config.filter_break_hz * np.exp(sign * u(np.log(1.25), np.log(2.5)))
        return {"break_hz": float(f)}
    if effect == "resonance":
        return {
            "frequency_hz": float(np.exp(u(np.log(2.0), np.log(9.0)))),
            "damping": float(u(0.1, 0.6)),
        }
    if effect == "lead":
        return {"time_constant_s": float(u(0.008, 0.05))}
    if effect == "sensor_filter":
        return {
            "cutoff_hz": float(np.exp(u(np.log(1.5), np.log(10.0)))),
            "channels": (DOF_CHANNEL[dof],),
        }
    if effect == "backlash":
        play = u(0.001, 0.006) if dof in ("surge", "sway", "heave") else np.radians(u(0.05, 0.4))
        return {"play": float(play)}
    if effect == "noise":  # up to a tenfold (a worn bearing, a loose joint): when the IMU's
        # own noise level is unknown, motion noise is told from it by its shape below 1 Hz only
        return {"scale": float(np.exp(sign * u(np.log(1.3), np.log(10.0))))}
    raise SignalError(f"unknown effect {effect!r}")


def _truth(
    config: MotionSystem, exts: tuple[Extension, ...], nuisance: Nuisance | None
) -> MotionSystem:
    """Return the nominal with the nuisances and the hidden effects."""
    base = (*config.extensions,)
    if nuisance is None:
        return config.replace(extensions=(*base, *exts))
    changes: dict[str, object] = {}
    if config.filter_break_hz is not None and nuisance.filter_break != 1.0:
        changes["filter_break_hz"] = config.filter_break_hz * nuisance.filter_break
    if config.noise and nuisance.motion_noise != 1.0:
        base = (*base, Extension("noise", {"scale": nuisance.motion_noise}, ("heave",)))
    return config.replace(extensions=(*base, *exts), **changes)


def hidden_signal(number: int, dof: str, nuisance: Nuisance | None = None) -> DescribingSignal:
    """Return Table 5.2 signal ``number`` for ``dof`` with a draw's amplitude and window.

    Without nuisances it is :func:`twin.chain.signals.describing_signal` with the pre-measurement of
    Eq 3.3, as the generator has always recorded.
    """
    if nuisance is None:
        return describing_signal(number, dof, settle_s=None)
    if nuisance.periods == 1:
        return describing_signal(number, dof, settle_s=None, scale=nuisance.amplitude)
    ms = table_5_2(number, dof)
    ms = type(ms)(ms.frequencies_hz, ms.amplitudes * nuisance.amplitude)
    return periodic_signal(ms, dof, 100.0, None, nuisance.window_s, f"Table 5.2 signal {number}")


def _imu_noise(rng: np.random.Generator, imu_noise: tuple[float, float] | float) -> float:
    if isinstance(imu_noise, int | float):
        return float(imu_noise)
    lo, hi = imu_noise
    return float(np.exp(rng.uniform(np.log(lo), np.log(hi))))


def clean(
    seed: int,
    imu_noise: tuple[float, float] | float = 1.0,
    dofs: Sequence[str] = ("heave", "pitch"),
    nuisance: bool = False,
    nuisance_ranges: NuisanceRanges = NUISANCE_RANGES,
) -> Hidden:
    """Draw a platform, a DOF and an IMU from ``seed`` with no effect (the nominal model holds).

    Parameters
    ----------
    seed : int
        Everything follows from it.
    imu_noise : (float, float) or float
        A range to draw the IMU's noise factor from, or the factor.
    dofs : sequence of str
        DOFs to draw from.
    nuisance : bool
        Draw the nominal's nuisance parts too (see the module docstring); off: as before.
    nuisance_ranges : NuisanceRanges
        Their ranges.

    Returns
    -------
    Hidden

    """
    rng = np.random.default_rng(seed)
    platform, dof = str(rng.choice(PLATFORMS)), str(rng.choice(list(dofs)))
    config = motion_system(platform)
    noise = _imu_noise(rng, imu_noise)
    if not nuisance:
        return Hidden(seed, config, dof, (), noise)
    return Hidden(seed, config, dof, (), noise, 0, draw_nuisance(seed, 0, config, nuisance_ranges))


def _motion_noise(config: MotionSystem, dof: str) -> bool:
    return bool(config.noise) and dof == "heave"


def draw(
    seed: int,
    effect: str | Sequence[str] | None = None,
    dofs: Sequence[str] = DOFS,
    imu_noise: tuple[float, float] | float = IMU_NOISE,
    count: int = 1,
    max_redraws: int = 60,
    imu_known: bool = False,
    nuisance: bool = False,
    nuisance_ranges: NuisanceRanges = NUISANCE_RANGES,
) -> Hidden:
    """Draw detectable hidden effects from ``seed``.

    Parameters
    ----------
    seed : int
        Everything follows from it.
    effect : str or sequence of str, optional
        The effect type(s); ``count`` random distinct ones by default.
    dofs : sequence of str
        DOFs to draw from.
    imu_noise : (float, float) or float
        Range of the IMU's noise factor (log-uniform), or the factor.
    count : int
        Number of effects when ``effect`` is not given.
    max_redraws : int
        Draws tried before giving up.
    imu_known : bool
        Judge the detectability of motion noise as a diagnosis told the IMU's noise would
        (else the IMU's noise level is a fitted nuisance, and only the shapes tell them apart).
    nuisance : bool
        Draw the nominal's nuisance parts too (see the module docstring); off (the default),
        every draw is as it always was.
    nuisance_ranges : NuisanceRanges
        Their ranges.

    Returns
    -------
    Hidden

    Raises
    ------
    SignalError
        When no draw in ``max_redraws`` passes the drawing rule.

    """
    rng = np.random.default_rng(seed)
    kinds = (effect,) if isinstance(effect, str) else (tuple(effect) if effect else None)
    for attempt in range(max_redraws + 1):
        platform = str(rng.choice(PLATFORMS))
        dof = str(rng.choice(list(dofs)))
        if kinds and "noise" in kinds:  # motion noise exists in the MPI's heave only
            platform, dof = "mpi", "heave"
        config = motion_system(platform)
        pool = [e for e in DRAWN if e != "noise" or _motion_noise(config, dof)]
        chosen = kinds or tuple(str(k) for k in rng.choice(pool, size=count, replace=False))
        exts = tuple(Extension(k, _parameters(k, rng, config, dof), (dof,)) for k in chosen)
        noise = _imu_noise(rng, imu_noise)
        if "noise" in chosen and not _motion_noise(config, dof):
            continue
        nui = draw_nuisance(seed, attempt, config, nuisance_ranges) if nuisance else None
        if _detectable(config, dof, exts, noise, seed, imu_known, nui):
            return Hidden(seed, config, dof, exts, noise, attempt, nui)
    what = " + ".join(kinds) if kinds else "effect"
    raise SignalError(f"seed {seed}: no detectable {what} in {max_redraws} draws")


_CHANNELS: dict[tuple[object, ...], list[Channel]] = {}


def _detectable(
    config: MotionSystem,
    dof: str,
    exts: tuple[Extension, ...],
    imu_noise: float,
    seed: int,
    imu_known: bool = False,
    nuisance: Nuisance | None = None,
) -> bool:
    """Return whether a draw passes the drawing rule of the module docstring."""
    imu = nominal_imu({}, config.platform)
    runs = None if nuisance is None else (nuisance.amplitude, nuisance.periods)
    key = (config.name, dof, seed) if runs is None else (config.name, dof, seed, runs)
    if key not in _CHANNELS:  # the nominal runs depend on platform, DOF, seed (and the runs)
        if any(k[2] != seed for k in _CHANNELS):
            _CHANNELS.clear()
        _CHANNELS[key] = [_channel(config, dof, number, imu, seed, nuisance) for number in (1, 2)]
    channels = _CHANNELS[key]
    case = Case(config, "reduced", imu, channels, seed)
    base = Model(case, dof)
    power = (1.0, imu_noise**2)
    evidence = [lines(c, sd=nominal_line_sd(c, power)) for c in channels]
    dynamic = [e for e in exts if e.effect != "noise"]
    for e in exts:
        others = [x for x in dynamic if x is not e]
        if e.effect == "noise":
            segs = [segment(c).scaled(power) for c in channels]
            scale = e.value("scale") * (nuisance.motion_noise if nuisance else 1.0)
            evidence_ = expected_noise_delta_bic(scale, segs, imu_known)
            if evidence_ < DETECTABLE_FACTOR * BIC_MARGIN:
                return False
            continue
        ctx = base
        for x in others:
            ctx = ctx.with_(x)
        if expected_delta_bic(ctx, [e], evidence) < DETECTABLE_FACTOR * BIC_MARGIN:
            return False
    if dynamic:
        for name, sd in fisher_std(base, dynamic, evidence).items():
            effect, par = name.split(".")
            ext = next(x for x in dynamic if x.effect == effect)
            tol = TOLERANCE.get(par, RELATIVE_TOLERANCE * abs(ext.value(par)))
            if not sd <= tol / 3:
                return False
    if len(dynamic) > 1:
        return _distinguishable(base, dynamic, evidence)
    return True


def _distinguishable(base: Model, exts: list[Extension], evidence: list[Lines]) -> bool:
    """Whether no other set of as many linear effects explains the noise-free truth.

    The true lines (noise-free) are fitted with every other single and pair of linear effects;
    if one comes within the naming margin in BIC (2 chi2 + extra parameters x ln n), no method
    can tell them apart from these runs, and the draw is not admitted.
    """
    true = base
    for e in exts:
        true = true.with_(e)
    clean = [replace(x, measured=true.line_prediction(x)) for x in evidence]
    n = 2 * sum(x.size for x in clean)
    p_true = sum(len(numeric_names(e.effect)) for e in exts)
    names = {e.effect for e in exts}
    linear = [e for e in DYNAMIC if e != "backlash"]
    for k in range(1, len(exts) + 1):
        for alt in combinations(linear, k):
            if set(alt) == names:
                continue
            fit = fit_set(alt, base, clean)
            if 2 * fit.chi2 + (fit.parameters - p_true) * np.log(n) < BIC_MARGIN:
                return False
    return True


def _channel(
    config: MotionSystem,
    dof: str,
    number: int,
    imu: ImuSpec,
    seed: int,
    nuisance: Nuisance | None = None,
) -> Channel:
    """Return the nominal prediction and noise of one Table 5.2 run (no file written)."""
    sig = hidden_signal(number, dof, nuisance)
    sim = prepare(clean_config(config), sig.commands, "reduced", seed, imu.ideal()).collect()
    meta = {"signal": signal_meta(sig)}
    m = from_imu(sig.commands, sim.imu, f"nominal-{number}", config, meta)
    return measurement_channels(m, config, "reduced", imu, seed, 0, [dof], realisations=4)[0]


def record(
    hidden: Hidden,
    out: str | Path,
    model: str = "reduced",
    signals: tuple[int, ...] = (1, 2),
    with_signal_meta: bool = True,
) -> list[Path]:
    """Simulate the runs of a hidden case and write them (meta names the nominal only)."""
    return record_runs(
        hidden.truth, hidden.config, hidden.dof, out, hidden.seed, model, signals,
        with_signal_meta, hidden.imu, hidden.nuisance,
    )  # fmt: skip


def record_runs(
    truth: MotionSystem,
    nominal: MotionSystem,
    dof: str,
    out: str | Path,
    seed: int = 0,
    model: str = "reduced",
    signals: tuple[int, ...] = (1, 2),
    with_signal_meta: bool = True,
    imu: ImuSpec | None = None,
    nuisance: Nuisance | None = None,
) -> list[Path]:
    """Simulate Table 5.2 multi-sines through ``truth``; write run folders that name ``nominal``.

    Parameters
    ----------
    truth, nominal : MotionSystem
        What the runs are simulated with, and what their ``meta.json`` says.
    dof : str
        Driven DOF.
    out : path
        Parent folder; runs are ``seed<seed>-<dof>-multisine<n>``.
    seed : int
        Seed (noise and IMU of run n use ``7919 seed + n``).
    model : str
        Platform model of the truth.
    signals : tuple of int
        Table 5.2 signals to run.
    with_signal_meta : bool
        Write the signal design into ``meta.json`` (without it the diagnosis infers it).
    imu : ImuSpec, optional
        The recording IMU (the platform's nominal one by default).
    nuisance : Nuisance, optional
        The runs' amplitude factor and window (its motion noise and break frequency are
        ``truth``'s business); None: Table 5.2 as it is, 20 s.

    Returns
    -------
    list of Path
        The run folders.

    """
    out = Path(out)
    return [
        play(
            truth, nominal, hidden_signal(number, dof, nuisance),
            out / f"seed{seed}-{dof}-multisine{number}", 7919 * seed + number, model,
            with_signal_meta, imu, f"hidden-effect run, seed {seed}",
        )
        for number in signals
    ]  # fmt: skip


def play(
    truth: MotionSystem,
    nominal: MotionSystem,
    signal: DescribingSignal,
    folder: str | Path,
    seed: int,
    model: str = "reduced",
    with_signal_meta: bool = True,
    imu: ImuSpec | None = None,
    notes: str = "hidden-effect run",
) -> Path:
    """Play one signal through ``truth`` and write its run folder naming ``nominal``.

    What a lab does with a designed run (:func:`twin.diagnose.design.design_run`): the
    platform, whose truth the diagnosis does not know, runs the commands.

    Parameters
    ----------
    truth, nominal : MotionSystem
        What the run is simulated with, and what its ``meta.json`` says.
    signal : DescribingSignal
        The commands and their design.
    folder : str or Path
        Run folder to write (replaced if the twin wrote it).
    seed : int
        Seed of the run's noise and IMU.
    model : str
        Platform model of the truth.
    with_signal_meta : bool
        Write the signal design into ``meta.json``.
    imu : ImuSpec, optional
        The recording IMU (the platform's nominal one by default).
    notes : str
        ``meta.json``'s notes.

    Returns
    -------
    Path
        The run folder.

    """
    run = prepare(truth, signal.commands, model, seed, imu)
    meta = run_meta(run, notes, nominal, signal if with_signal_meta else None)
    execute(run, meta, Path(folder), overwrite=True)
    return Path(folder)


#: What :func:`judged` returns.
VERDICTS = ("right", "ambiguous", "wrong", "none")


def judged(hidden: Hidden, diagnosis: object) -> str:
    """Judge a diagnosis of a drawn case against its truth.

    Motion noise (``noise``) findings are left out unless motion noise is among the hidden
    effects (with nuisances on, the nominal's own motion-noise level varies: naming it is not a
    wrong cause). The first finding left is the one a user acts on.

    Parameters
    ----------
    hidden : Hidden
        The draw.
    diagnosis : Diagnosis
        Its diagnosis (anything with ``findings``: a list of objects with ``extension``,
        ``ambiguous`` and ``evidence`` as :class:`twin.diagnose.select.Finding` has).

    Returns
    -------
    str
        One of :data:`VERDICTS`. With hidden effects: ``right`` (the first finding is not
        ambiguous, names a true effect, and every true effect is named), ``ambiguous`` (the
        first finding is ambiguous and every true effect is among the named set or its
        ``alternatives``), ``wrong`` (the first finding is not a true effect and not ambiguous,
        or ambiguous without the truth among its explanations), ``none`` (no finding; also a
        pair of which one effect is named first and the other is not named anywhere: nothing
        false is presented). A clean draw: ``right`` when no dynamic cause is named, else
        ``wrong``. Where the nuisances moved the platform filter's break, a finding of a
        platform filter at the true break (within :data:`RELATIVE_TOLERANCE`) names a real
        difference from the nominal: it counts as a true effect.

    """
    truth = set(hidden.effects)
    findings = [
        f for f in getattr(diagnosis, "findings", diagnosis)  # a list of findings will do too
        if "noise" in truth or f.extension.effect != "noise"
    ]  # fmt: skip
    if any(_names_moved_filter(hidden, f.extension) for f in findings):
        truth.add("platform_filter")
    if not truth:
        return "wrong" if findings else "right"
    if not findings:
        return "none"
    top = findings[0]
    named = {f.extension.effect for f in findings} | set(top.evidence.get("set") or ())
    if top.ambiguous:
        covered = set(named)
        for alt in top.evidence.get("alternatives") or []:
            covered |= set(alt.get("effects") or ())
        if truth <= covered:
            return "ambiguous"
        return "none" if top.extension.effect in truth else "wrong"
    if top.extension.effect not in truth:
        return "wrong"
    return "right" if truth <= named else "none"


def values_within_tolerance(hidden: Hidden, diagnosis: object) -> bool:
    """Whether every hidden effect is named with its values within the tests' tolerances.

    Parameters
    ----------
    hidden : Hidden
        The draw.
    diagnosis : Diagnosis
        Its diagnosis (or a list of findings).

    Returns
    -------
    bool
        Each numeric parameter of each hidden effect (motion noise aside: its scale is judged
        on its own) against the finding of that effect in the draw's DOF: within
        :data:`TOLERANCE` (absolute) or :data:`RELATIVE_TOLERANCE` of the true value. False
        where an effect is not named there.

    """
    findings = list(getattr(diagnosis, "findings", diagnosis))
    for true in hidden.extensions:
        if true.effect == "noise":
            continue
        named = next((f.extension for f in findings if f.extension.effect == true.effect
                      and hidden.dof in f.extension.dofs), None)  # fmt: skip
        if named is None:
            return False
        for par in numeric_names(true.effect):
            tol = TOLERANCE.get(par, RELATIVE_TOLERANCE * abs(true.value(par)))
            if abs(named.value(par) - true.value(par)) > tol:
                return False
    return True


def _names_moved_filter(hidden: Hidden, ext: Extension) -> bool:
    """Whether ``ext`` is a platform filter at the break the draw's nuisances moved it to."""
    moved = hidden.nuisance is not None and hidden.nuisance.filter_break != 1.0
    if not moved or ext.effect != "platform_filter" or hidden.config.filter_break_hz is None:
        return False
    true_hz = hidden.config.filter_break_hz * hidden.nuisance.filter_break  # type: ignore[union-attr]
    return abs(float(ext.value("break_hz")) / true_hz - 1) <= RELATIVE_TOLERANCE


def truth_delta_bic(hidden: Hidden, diagnosis: object) -> tuple[float | None, float]:
    """Return the BIC improvement of the true set of effects and of the named set.

    Read from the selection table of the driven DOF (every single effect and pair the diagnosis
    fitted, against the nominal model); the named set is the first finding's ``set`` (0 when
    nothing is named). The true set's is None where the table has no row for it (motion noise,
    or more effects than were fitted together).

    Parameters
    ----------
    hidden : Hidden
        The draw.
    diagnosis : Diagnosis
        Its diagnosis.

    Returns
    -------
    (float or None, float)
        BIC improvement of the true set and of the named set.

    """
    report = diagnosis.dofs.get(hidden.dof)  # type: ignore[attr-defined]
    table = report.selection.table if report is not None else []
    rows = {tuple(sorted(r["effects"])): float(r["delta_bic"]) for r in table}
    true = rows.get(tuple(sorted(e for e in hidden.effects)))
    chain = [f for f in diagnosis.findings if f.extension.effect != "noise"]  # type: ignore[attr-defined]
    named = 0.0
    if chain:
        key = tuple(sorted(chain[0].evidence.get("set") or (chain[0].extension.effect,)))
        named = rows.get(key, float(chain[0].evidence.get("delta_bic", 0.0)))
    return true, named
