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
from twin.chain.simulate import default_imu, prepare
from twin.diagnose.candidates import DYNAMIC, Model, fit_set, numeric_names
from twin.diagnose.data import Case, Channel, clean_config, measurement_channels, nominal_imu
from twin.diagnose.detect import expected_delta_bic, expected_noise_delta_bic, fisher_std
from twin.diagnose.evidence import Lines, lines, nominal_line_sd
from twin.diagnose.residuals import segment
from twin.diagnose.select import BIC_MARGIN
from twin.errors import SignalError
from twin.frames import DOF_NAMES
from twin.measurement.measure import from_imu
from twin.run_folder import execute, run_meta, signal_meta
from twin.signals import describing_signal

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

    """

    seed: int
    config: MotionSystem
    dof: str
    extensions: tuple[Extension, ...] = ()
    imu_noise: float = 1.0
    redraws: int = 0

    @property
    def extension(self) -> Extension | None:
        """The first hidden effect (None: a clean run)."""
        return self.extensions[0] if self.extensions else None

    @property
    def truth(self) -> MotionSystem:
        """The configuration the runs are simulated with (nominal + effects)."""
        return self.config.replace(extensions=(*self.config.extensions, *self.extensions))

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


def _imu_noise(rng: np.random.Generator, imu_noise: tuple[float, float] | float) -> float:
    if isinstance(imu_noise, int | float):
        return float(imu_noise)
    lo, hi = imu_noise
    return float(np.exp(rng.uniform(np.log(lo), np.log(hi))))


def clean(
    seed: int,
    imu_noise: tuple[float, float] | float = 1.0,
    dofs: Sequence[str] = ("heave", "pitch"),
) -> Hidden:
    """Draw a platform, a DOF and an IMU from ``seed`` with no effect (the nominal model holds).

    ``imu_noise``: a range to draw the IMU's noise factor from, or the factor.
    """
    rng = np.random.default_rng(seed)
    platform, dof = str(rng.choice(PLATFORMS)), str(rng.choice(list(dofs)))
    return Hidden(seed, motion_system(platform), dof, (), _imu_noise(rng, imu_noise))


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
        if _detectable(config, dof, exts, noise, seed, imu_known):
            return Hidden(seed, config, dof, exts, noise, attempt)
    what = " + ".join(kinds) if kinds else "effect"
    raise SignalError(f"seed {seed}: no detectable {what} in {max_redraws} draws")


_CHANNELS: dict[tuple[str, str, int], list[Channel]] = {}


def _detectable(
    config: MotionSystem,
    dof: str,
    exts: tuple[Extension, ...],
    imu_noise: float,
    seed: int,
    imu_known: bool = False,
) -> bool:
    """Return whether a draw passes the drawing rule of the module docstring."""
    imu = nominal_imu({}, config.platform)
    key = (config.name, dof, seed)
    if key not in _CHANNELS:  # the nominal runs depend on platform, DOF and seed only
        if any(k[2] != seed for k in _CHANNELS):
            _CHANNELS.clear()
        _CHANNELS[key] = [_channel(config, dof, number, imu, seed) for number in (1, 2)]
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
            evidence_ = expected_noise_delta_bic(e.value("scale"), segs, imu_known)
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


def _channel(config: MotionSystem, dof: str, number: int, imu: ImuSpec, seed: int) -> Channel:
    """Return the nominal prediction and noise of one Table 5.2 run (no file written)."""
    sig = describing_signal(number, dof, settle_s=None)
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
        with_signal_meta, hidden.imu,
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

    """
    out = Path(out)
    folders = []
    for number in signals:
        sig = describing_signal(number, dof, settle_s=None)
        run = prepare(truth, sig.commands, model, 7919 * seed + number, imu)
        meta = run_meta(
            run, f"hidden-effect run, seed {seed}", nominal, sig if with_signal_meta else None
        )
        folder = out / f"seed{seed}-{dof}-multisine{number}"
        execute(run, meta, folder, overwrite=True)
        folders.append(folder)
    return folders
