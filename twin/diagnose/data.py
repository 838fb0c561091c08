"""What a diagnosis compares: a recorded run, the nominal twin's prediction and its noise.

For every run and every driven DOF a :class:`Channel` holds, on the App. C.2.3 grid (100 Hz):
the measured acceleration of the DOF (the IMU channel that measures it, post-processed), the
nominal twin's noise-free prediction of it (the run's own commands through the nominal
configuration, ideal IMU), and realisations of each nominal noise *source* apart: the motion
noise of the configuration (Eq 5.10; the same run with the configuration's noise and an ideal
IMU, minus the noise-free one) and the IMU's own noise (noise-free configuration, the nominal
IMU). Kept apart, the diagnosis can scale each to what the measurement shows: a real IMU is
rarely the data sheet's, and its noise is a nuisance, not a cause
(:mod:`twin.diagnose.nuisance`). The realisations give each source's spectrum over any segment
of the run, with no model of the post-processing needed.
"""

from __future__ import annotations

import functools
import json
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from twin.chain.config import MotionSystem, resolve
from twin.chain.imu import ImuSpec
from twin.chain.simulate import MODELS, default_imu
from twin.chain.trajectory import Trajectory
from twin.core.errors import RunFormatError, SignalError
from twin.core.frames import DOF_NAMES, dof_index
from twin.core.progress import ProgressFn
from twin.core.threads import concurrently
from twin.formats.run_checks import check_distinct, read_plausible_run
from twin.formats.runs import RecordedRun
from twin.measurement.measure import (
    Measurement,
    clean_config,
    from_run,
    simulate_measurement,
    simulate_measurements,
)
from twin.measurement.periodic import periodic_design

FloatArray = NDArray[np.float64]
#: Noise realisations simulated per run and noise source for the nominal noise spectra.
NOISE_REALISATIONS = 4
#: Factor on the realisations where the configuration has motion noise: the estimates of the
#: two sources' spectral shapes are what tell them apart (with 4, a motion noise the runs
#: should show at 3x the naming threshold was named in 18 of 20 draws; with 8, see the tests).
MOTION_NOISE_FACTOR = 2
#: The nominal noise sources, in the order of :attr:`Channel.sources`.
NOISE_SOURCES = ("motion", "imu")
#: A DOF is analysed when its commanded acceleration has at least this fraction of the RMS of
#: the most-driven DOF (in its own units).
DRIVEN_FRACTION = 0.05


@dataclass(frozen=True, eq=False)
class Channel:
    """One DOF of one run: measured, nominal prediction, nominal noise.

    Attributes
    ----------
    run : str
        Run folder.
    dof : str
        DOF name.
    t : ndarray, shape (n,)
        Time [s] (100 Hz).
    measured, nominal : ndarray, shape (n,)
        Measured acceleration and the nominal twin's noise-free prediction [m/s^2 or rad/s^2].
    sources : ndarray, shape (2, k, n)
        Realisations of the nominal noise on the same grid, per source of
        :data:`NOISE_SOURCES` (motion noise all zero where the configuration has none).
    lines_hz : ndarray
        Excited frequencies.
    window : tuple of float
        Measurement window [s] (whole periods of the signal).
    commands : Trajectory
        The run's command trajectory (for re-simulation).
    filter_scale : float
        The run's platform-filter setting over the case's nominal one (1: the nominal's;
        :meth:`Case.config_of`).

    """

    run: str
    dof: str
    t: FloatArray
    measured: FloatArray
    nominal: FloatArray
    sources: FloatArray
    lines_hz: FloatArray
    window: tuple[float, float]
    commands: Trajectory = field(repr=False)
    filter_scale: float = 1.0

    @property
    def noise(self) -> FloatArray:
        """Realisations of the nominal total noise (the sources added), shape (k, n)."""
        return self.sources.sum(axis=0)

    @property
    def has_motion_noise(self) -> bool:
        """Whether the nominal configuration has motion noise in this DOF."""
        return bool(np.any(self.sources[0]))

    @property
    def index(self) -> int:
        """DOF index."""
        return dof_index(self.dof)

    @property
    def rate_hz(self) -> float:
        """Sample rate [Hz]."""
        return 1.0 / float(self.t[1] - self.t[0])

    def halves(self) -> tuple[tuple[float, float], tuple[float, float]]:
        """Return the two halves of the measurement window."""
        a, b = self.window
        mid = a + 0.5 * (b - a)
        return (a, mid), (mid, b)


@dataclass(frozen=True, eq=False)
class Case:
    """Runs to diagnose against one nominal configuration.

    Each run may have been recorded at its own setting of the platform filter (the thesis'
    Ch. 4 measured the MPI at 1, 5 and 10 Hz): its channels say how many times the nominal's
    (:attr:`Channel.filter_scale`), and :meth:`config_of` gives any configuration at a
    channel's setting. Every explanation is stated at the nominal's setting.

    Attributes
    ----------
    config : MotionSystem
        Nominal configuration.
    model : str
        ``"reduced"`` or ``"full"``.
    imu : ImuSpec
        The nominal IMU (mount and rate from the run's ``meta.json``).
    channels : list of Channel
        Every driven DOF of every run.
    seed : int
        Seed of the noise realisations.
    unidentifiable : dict
        Effects these runs cannot show, with the reason (e.g. ``delay`` when ``twin import``
        had to estimate the clock offset from the response).
    runs : tuple of (RecordedRun, Measurement)
        The runs as read and as post-processed (every channel and log: the physical
        diagnosis uses them all).

    """

    config: MotionSystem
    model: str
    imu: ImuSpec
    channels: list[Channel]
    seed: int
    unidentifiable: dict[str, str] = field(default_factory=dict)
    runs: tuple[tuple[RecordedRun, Measurement], ...] = ()

    @property
    def clean(self) -> MotionSystem:
        """The nominal configuration without noise (for noise-free predictions)."""
        return clean_config(self.config)

    @property
    def dofs(self) -> list[str]:
        """Analysed DOFs, in DOF order."""
        return [d for d in DOF_NAMES if any(c.dof == d for c in self.channels)]

    def of(self, dof: str) -> list[Channel]:
        """Channels of one DOF."""
        return [c for c in self.channels if c.dof == dof]

    def config_of(self, ch: Channel, config: MotionSystem | None = None) -> MotionSystem:
        """Return ``config`` (the noise-free nominal by default) at the setting of ``ch``'s run."""
        return (self.clean if config is None else config).filter_scaled(ch.filter_scale)

    @property
    def filter_scales(self) -> tuple[float, ...]:
        """Each run's platform-filter setting over the nominal's, in the order of :attr:`runs`."""
        scale = {c.run: c.filter_scale for c in self.channels}
        return tuple(scale.get(m.source, 1.0) for _, m in self.runs)

    @property
    def settings_hz(self) -> dict[str, float]:
        """Runs recorded at another filter setting than the nominal's: run -> break [Hz]."""
        fb = self.config.filter_break_hz
        return {c.run: fb * c.filter_scale for c in self.channels
                if fb is not None and c.filter_scale != 1.0}  # fmt: skip


def nominal_imu(meta: dict, platform: str) -> ImuSpec:
    """Return the platform's ADIS16355 at the mount and rate of a run's ``meta.json``."""
    spec = default_imu(platform)
    imu = meta.get("imu", {})
    return ImuSpec(
        position_m=tuple(float(v) for v in imu.get("position_m", spec.position_m)),
        rate_hz=float(imu.get("rate_hz", spec.rate_hz)),
        accel_range=spec.accel_range,
        gyro_range=spec.gyro_range,
    )


def driven_dofs(m: Measurement, dofs: Sequence[str] | None = None) -> list[int]:
    """Return the indices of the DOFs a run drives (or of ``dofs``, checked)."""
    if dofs:
        bad = [d for d in dofs if d not in DOF_NAMES]
        if bad:
            raise SignalError(f"unknown DOF {bad[0]!r}; expected one of {', '.join(DOF_NAMES)}")
        return [dof_index(d) for d in dofs]
    rms = np.sqrt(np.mean(m.commanded**2, axis=0))
    if not rms.any():
        raise SignalError(f"{m.source}: the commands do not move; nothing to diagnose")
    sig = m.meta.get("signal", {})
    if sig.get("dof") in DOF_NAMES:
        return [dof_index(sig["dof"])]
    # translations and rotations in their own units: compare within each group
    out = []
    for group in (slice(0, 3), slice(3, 6)):
        top = rms[group].max()
        out += [
            k + group.start
            for k, v in enumerate(rms[group])
            if top > 0 and v >= DRIVEN_FRACTION * top
        ]
    return sorted(out)


def measurement_channels(
    m: Measurement,
    nominal: MotionSystem,
    model: str,
    imu: ImuSpec,
    seed: int = 0,
    offset: int = 0,
    dofs: Sequence[str] | None = None,
    realisations: int = NOISE_REALISATIONS,
    filter_scale: float = 1.0,
) -> list[Channel]:
    """Return the channels of one measurement: nominal prediction and noise per driven DOF.

    Realisation ``i`` of each source is simulated with seed ``seed + offset + i + 1``;
    ``nominal`` is taken at the run's filter setting (``filter_scale`` times its own).
    """
    nominal = nominal.filter_scaled(filter_scale)
    clean = clean_config(nominal)
    driven = driven_dofs(m, dofs)
    if nominal.noise and dof_index("heave") in driven:  # the motion noise (heave only) is told
        realisations *= MOTION_NOISE_FACTOR  # from the IMU's by the two spectra's shapes
    seeds = [seed + offset + i + 1 for i in range(realisations)]
    # the prediction (ideal IMU) and the IMU's realisations share one noise-free motion; with
    # motion noise each seed moves the platform differently: the simulations run side by side
    readings = [(seed, imu.ideal()), *((s, imu) for s in seeds)]
    jobs = [functools.partial(simulate_measurements, clean, m.commands, m.t, model, readings)]
    if nominal.noise:
        jobs += [functools.partial(simulate_measurement, nominal, m.commands, m.t, model, s,
                                   imu.ideal()) for s in seeds]  # fmt: skip
    (pred, *read), *noisy = concurrently(jobs)
    motion = [r - pred for r in noisy] if nominal.noise else [np.zeros_like(pred) for _ in seeds]
    sensor = [r - pred for r in read]
    out = []
    for k in driven:
        lines, window = periodic_design(m, k)
        sources = np.array([[r[:, k] for r in motion], [r[:, k] for r in sensor]])
        out.append(Channel(m.source, DOF_NAMES[k], m.t, m.measured[:, k], pred[:, k], sources,
                           lines, tuple(window), m.commands, filter_scale))  # fmt: skip
    return out


def _setting(config: MotionSystem) -> str:
    """Return a configuration's filter setting in words."""
    fb = config.filter_break_hz
    return "no filter" if fb is None else f"filter at {fb:g} Hz"


def _as_nominal(config: MotionSystem) -> str:
    """Return what a configuration says of the platform (name, description, filter setting aside).

    The filter's break is a setting a run may change (:meth:`Case.config_of`): runs that
    differ only in it name one nominal (whether there is a filter at all is not a setting).
    """
    meta = {k: v for k, v in config.to_meta().items() if k not in ("name", "description")}
    meta["filter_break_hz"] = config.filter_break_hz is not None
    return json.dumps(meta, sort_keys=True, default=str)


def load_case(
    runs: Sequence[str | Path | RecordedRun],
    config: str | MotionSystem | None = None,
    model: str = "reduced",
    seed: int = 0,
    dofs: Sequence[str] | None = None,
    realisations: int = NOISE_REALISATIONS,
    progress: ProgressFn | None = None,
    filter_scales: Sequence[float] | None = None,
    own_filter: bool = False,
) -> Case:
    """Read runs, simulate the nominal twin on their commands and its noise.

    Parameters
    ----------
    runs : sequence of path
        ``twin-run/1`` folders of the same platform.
    config : str or MotionSystem, optional
        Nominal configuration, for every run at its setting of the platform filter; by
        default the runs' ``meta.json`` (``platform`` and ``platform_config``), which must
        then name the same one but for the filter's setting: each run is then compared at its
        own, and the nominal is the one at the lowest setting among them.
    model : str
        ``"reduced"`` (default) or ``"full"``.
    seed : int
        Seed of the simulated noise realisations.
    dofs : sequence of str, optional
        DOFs to analyse; the driven ones by default.
    realisations : int
        Noise realisations per run.
    progress : callable, optional
        Called with a message per run.
    filter_scales : sequence of float, optional
        Each run's platform-filter setting over the nominal's (as a diagnosis wrote them:
        ``nominal.filter_scales``); by default 1 with ``config``, the runs' own without.
    own_filter : bool
        With ``config``: compare each run at its own filter setting over ``config``'s (the
        runs must then name ``config`` but for the setting: validation runs of a diagnosis
        without ``config``).

    Raises
    ------
    RunFormatError
        A run folder is malformed (also for a malformed ``platform_config``), or a run is
        given twice (:func:`twin.formats.run_checks.check_distinct`).
    SignalError
        Unknown model, platforms that differ, runs naming different nominal configurations
        without ``config`` (or with ``own_filter``), runs at different filter settings with
        ``config`` (without ``own_filter`` or ``filter_scales``), ``filter_scales`` that are
        not one positive number per run, nothing driven.

    """
    if model not in MODELS:
        raise SignalError(f"unknown model {model!r}; expected one of {', '.join(MODELS)}")
    if not runs:
        raise SignalError("give at least one run folder to diagnose")
    if realisations < 2:
        raise SignalError(f"need at least 2 noise realisations; got {realisations}")
    recs = [read_plausible_run(path) for path in runs]
    check_distinct(recs)
    measurements = []
    for rec in recs:
        try:
            measurements.append(from_run(rec))
        except SignalError as e:
            raise RunFormatError(f"{rec.path}/meta.json: {e}") from e
    platforms = {m.config.platform for m in measurements}
    if len(platforms) > 1:
        raise SignalError(f"the runs are of different platforms ({', '.join(sorted(platforms))})")
    settings = [m.config.filter_break_hz for m in measurements]
    if config is None:  # the nominal: the runs' own, at the lowest filter setting among them
        nominal = min(measurements, key=lambda m: m.config.filter_break_hz or 0.0).config
        own_filter = True
    else:
        nominal = resolve(config)
        if nominal.platform not in platforms:
            raise SignalError(
                f"configuration {nominal.name!r} is of the {nominal.platform} platform; the runs "
                f"are of the {platforms.pop()}"
            )
    if own_filter:
        other = next((m for m in measurements if _as_nominal(m.config) != _as_nominal(nominal)),
                     None)  # fmt: skip
        if other is not None:
            raise SignalError(
                f"the runs name different nominal configurations ({other.source}: "
                f"{other.config.name!r}; the nominal: {nominal.name!r}); the nominal is the "
                "model every run is compared with: give it (--config NAME or FILE)"
            )
    elif filter_scales is None and len(set(settings)) > 1:
        raise SignalError(
            "the runs were recorded at different platform-filter settings ("
            + ", ".join(f"{m.source}: {_setting(m.config)}" for m in measurements)
            + "); a configuration given (--config or an override) compares every run at its "
            f"setting ({_setting(nominal)}): leave it out to compare each run at its own"
        )
    scales = [1.0] * len(measurements)
    if own_filter and nominal.filter_break_hz is not None:  # each run at its own setting
        scales = [s / nominal.filter_break_hz for s in settings]  # type: ignore[operator]
    if filter_scales is not None:
        try:
            given = [float(k) for k in filter_scales]
        except (TypeError, ValueError):
            given = []
        if len(given) != len(measurements) or not all(np.isfinite(k) and k > 0 for k in given):
            raise SignalError(
                f"filter_scales: one positive number per run ({len(measurements)}); got "
                f"{list(filter_scales)!r}"
            )
        scales = given
    imu = nominal_imu(measurements[0].meta, nominal.platform)
    unidentifiable = {}
    for m in measurements:
        clock = m.meta.get("import", {}).get("clock", {})
        if clock.get("delay_identifiable") is False:
            unidentifiable["delay"] = (
                f"not identifiable: twin import estimated the clock offset of {m.source} by "
                "aligning its response with the nominal twin, which absorbs any extra delay"
            )
    channels = []
    for r, m in enumerate(measurements):
        if progress:
            progress(f"nominal twin on {m.source} ({model})")
        channels += measurement_channels(m, nominal, model, imu, seed, 1000 * r, dofs, realisations,
                                         scales[r])  # fmt: skip
    pairs = tuple(zip(recs, measurements, strict=True))
    return Case(nominal, model, imu, channels, seed, unidentifiable, pairs)
