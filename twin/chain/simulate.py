"""Run a motion-system configuration on the full or the reduced platform, with the IMU.

Examples
--------
>>> from twin.chain.signals import rest
>>> sim = simulate("srs", rest(1.0), model="reduced", seed=1)
>>> sim.imu.accel.shape[1], round(float(sim.imu.accel[:, 2].mean()), 1)
(3, -9.8)

"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from twin.chain.config import MotionSystem, resolve
from twin.chain.extensions import SensorFilterStream
from twin.chain.imu import ImuRecord, ImuSpec, VirtualImu
from twin.chain.jets import JetSignal
from twin.chain.limits import LimitReport
from twin.chain.noise import MotionNoise, NoiseStream
from twin.chain.physics import FullPlatform
from twin.chain.reduced import ReducedPlatform
from twin.chain.response import PlatformResponse
from twin.chain.signals import check_physical
from twin.chain.stepping import CHUNK_S, Platform, overlapped
from twin.chain.stream import ChainStream, noise_streams
from twin.chain.trajectory import Trajectory
from twin.core.errors import ConfigError, SignalError
from twin.platform.platform_physics import PlatformPhysics

FloatArray = NDArray[np.float64]

MODELS = ("full", "reduced")


def make_platform(
    platform: str,
    model: str = "full",
    limit_mode: str = "limit",
    physics: PlatformPhysics | None = None,
    leg_forces: bool = True,
) -> Platform:
    """Return the full (MuJoCo) or reduced platform of ``platform``.

    ``leg_forces``: the full platform's actuator forces in its responses (False: None, for a
    caller that reads the motion only; :class:`twin.chain.physics.FullPlatform`).

    Raises
    ------
    ConfigError
        For ``physics`` (actuators, payload) with the reduced model, which has neither.

    """
    if model == "full":
        if physics is None:
            return FullPlatform(platform, limit_mode, leg_forces=leg_forces)
        return FullPlatform(platform, limit_mode, physics=physics.legs, payload=physics.payload,
                            leg_forces=leg_forces)  # fmt: skip
    if model == "reduced":
        if physics is not None:
            raise ConfigError(f"the configuration's physics ({physics.describe()}) needs the "
                              "full model: the reduced one (Eq 5.11) has no legs or cabin to "
                              "load; give --model full")  # fmt: skip
        return ReducedPlatform(platform, limit_mode=limit_mode)
    raise SignalError(f"unknown model {model!r}; expected one of {', '.join(MODELS)}")


def default_imu(platform: str) -> ImuSpec:
    """Return the ADIS16355 at the UGP with the platform's ``platform.toml`` rate and ranges."""
    from twin.platform.facts import load_facts

    f = load_facts(platform)
    return ImuSpec(rate_hz=f.imu_rate_hz, accel_range=f.imu_accel_range,
                   gyro_range=float(np.radians(f.imu_gyro_range_deg_s)))  # fmt: skip


@dataclass
class Simulation:
    """Everything a run produced.

    Attributes
    ----------
    config : MotionSystem
        The configuration.
    model : str
        ``"full"`` or ``"reduced"``.
    seed : int
        The run's seed (noise and IMU draw from it).
    commands : Trajectory
        The pose commands as given.
    response : PlatformResponse
        Cabin motion at the platform rate.
    imu : ImuRecord
        Virtual IMU samples.
    imu_spec : ImuSpec
        The IMU used.
    limits : LimitReport
        Actuator-limit counts.
    notes : list of str
        Things the user should know about this run.

    """

    config: MotionSystem
    model: str
    seed: int
    commands: Trajectory
    response: PlatformResponse
    imu: ImuRecord
    imu_spec: ImuSpec
    limits: LimitReport
    notes: list[str] = field(default_factory=list)


@dataclass
class Run:
    """A prepared run whose chunks can be streamed (see :func:`prepare`).

    Attributes
    ----------
    config, model, seed, commands, imu_spec, limits, notes
        As in :class:`Simulation`.
    platform : FullPlatform or ReducedPlatform
        The platform.
    noise : MotionNoise or None
        The heave-noise generator (seeded from ``seed``; see :meth:`noise_stream`).
    chunk_s : float
        Command seconds fed to the chain per step (memory stays bounded for any duration;
        results do not depend on it).

    """

    config: MotionSystem
    model: str
    seed: int
    commands: Trajectory
    imu_spec: ImuSpec
    limits: LimitReport
    notes: list[str]
    platform: Platform
    noise: MotionNoise | None
    chunk_s: float = CHUNK_S

    def noise_stream(self) -> NoiseStream | None:
        """Return a fresh stream of this run's heave noise (same seed, same samples)."""
        return noise_streams(self.config, [self.seed], self.imu_spec.rate_hz)[0]

    @property
    def platform_input(self) -> JetSignal:
        """The commands after the configuration's blocks, whole (the platform adds the noise)."""
        sig = JetSignal.from_trajectory(self.commands)
        for block in self.config.blocks(self.platform.own_lag_s):
            sig = block(sig)
        return sig

    def chunks(self) -> Iterator[tuple[PlatformResponse, ImuRecord]]:
        """Yield (response, IMU) chunk pairs; memory stays bounded for any duration."""
        return self._read(self._responses(), self.seed, self.imu_spec)

    def read_by_imus(self, readings: Sequence[tuple[int, ImuSpec]]) -> list[Simulation]:
        """Simulate the motion once and return it read by each (seed, IMU) pair.

        Each result has the bits of ``prepare(config, commands, model, seed, imu).collect()``
        (tested): without heave noise the motion does not depend on the seed or the IMU, only
        the IMU's noise and bias do, so a set of noise realisations, or an ideal IMU beside a
        real one, costs one platform simulation (the diagnosis' sensor-noise realisations).
        The motion is held whole meanwhile.

        Raises
        ------
        SignalError
            When the configuration has heave noise (each seed then moves the platform
            differently: simulate each), or ``readings`` is empty.

        """
        if self.noise is not None:
            raise SignalError(
                f"{self.config.name} has heave noise, so each seed moves the platform "
                "differently; simulate each seed (prepare(...).collect())"
            )
        if not readings:
            raise SignalError("give at least one (seed, IMU) pair to read the motion with")
        motion = list(self._responses())
        out = []
        for seed, spec in readings:
            pairs = list(self._read(motion, seed, spec))
            run = dataclasses.replace(self, seed=int(seed), imu_spec=spec)
            out.append(run.simulation([r for r, _ in pairs], [rec for _, rec in pairs]))
        return out

    def _responses(self) -> Iterator[PlatformResponse]:
        """Yield the platform's motion chunk by chunk (one run)."""
        cmd = self.commands
        chain = ChainStream(self.config, self.platform, cmd.rate_hz, cmd.t0, self.seed,
                            self.imu_spec.rate_hz, self.limits)  # fmt: skip
        step = max(1, round(self.chunk_s * cmd.rate_hz))
        # one chunk of look-ahead: the full model's physics of chunk k + 1 rolls in a thread
        # while chunk k's IMU is computed (the same results; twin_throughput bench)
        for response in overlapped(self._command_jets(step), chain.submit):
            chunk = response.run(0)
            if chunk.t.size:
                yield chunk

    def _read(
        self, motion: Iterable[PlatformResponse], seed: int, spec: ImuSpec
    ) -> Iterator[tuple[PlatformResponse, ImuRecord]]:
        """Yield each chunk of motion with the IMU's reading of it (its noise from ``seed``).

        The IMU reads the motion through its mount's rotation (``imu_alignment``), adds its
        bias and noise and saturates in its own axes; the ``sensor_filter`` s act after that,
        on what the rotated sensing elements read.
        """
        rng = np.random.default_rng(np.random.SeedSequence([seed, 1]))
        imu = VirtualImu(spec, rng, self.config.imu_rotation)
        filters = [SensorFilterStream(e, spec.rate_hz) for e in self.config.of("sensor_filter")]
        for chunk in motion:
            rec = imu.feed(chunk)
            chunk = dataclasses.replace(chunk, rotation=None)  # the IMU's only: not kept
            if filters:
                values = np.hstack([rec.accel, rec.gyro])
                for filt in filters:
                    values = filt(values)
                rec = ImuRecord(rec.t, values[:, :3], values[:, 3:], rec.saturated)
            yield chunk, rec

    def _command_jets(self, step: int) -> Iterator[FloatArray]:
        """Yield the commands' jets (cubic spline), ``step`` samples at a time, (1, n, 6, 3)."""
        cmd = self.commands
        for k in range(0, cmd.n, step):
            _, rate, acc = cmd.derivatives(cmd.t[k : k + step], 2)
            yield np.stack([cmd.values[k : k + step], rate, acc], axis=-1)[None]

    def collect(self) -> Simulation:
        """Run all chunks and return the joined :class:`Simulation`."""
        responses, records = [], []
        for resp, rec in self.chunks():
            responses.append(resp)
            records.append(rec)
        return self.simulation(responses, records)

    def simulation(self, responses: list[PlatformResponse], records: list[ImuRecord]) -> Simulation:
        """Join chunks produced by :meth:`chunks` into a :class:`Simulation`."""
        return Simulation(
            self.config, self.model, self.seed, self.commands,
            PlatformResponse.concatenate(responses), VirtualImu.concatenate(records),
            self.imu_spec, self.limits, self.notes,
        )  # fmt: skip


def prepare(
    config: MotionSystem | str,
    commands: Trajectory,
    model: str = "full",
    seed: int = 0,
    imu: ImuSpec | None = None,
    limit_mode: str = "limit",
    platform: Platform | None = None,
) -> Run:
    """Set up a run: apply the blocks to the commands and choose the noise.

    Parameters
    ----------
    config : MotionSystem or str
        Configuration or its name (:func:`twin.chain.config.motion_system`).
    commands : Trajectory
        Pose commands (offsets from neutral, thesis base frame), any rate.
    model : str
        ``"full"`` (MuJoCo) or ``"reduced"`` (Eq 5.11).
    seed : int
        Seed for the noise and the IMU; the same seed gives bit-identical results.
    imu : ImuSpec, optional
        The IMU; the ADIS16355 at the UGP by default.
    limit_mode : str
        ``"limit"`` or ``"strict"`` (see :mod:`twin.chain.limits`).
    platform : FullPlatform or ReducedPlatform, optional
        A platform object to reuse (e.g. with an edited model); made from ``config`` if not.

    """
    ms = resolve(config)
    if not isinstance(seed, int | np.integer) or seed < 0:
        raise SignalError(f"seed must be an integer >= 0; got {seed!r}")
    check_physical(commands)
    plat = (platform if platform is not None
            else make_platform(ms.platform, model, limit_mode, ms.physics))  # fmt: skip
    notes = []
    short = ms.delays_s < plat.own_lag_s
    if short.any():
        notes.append(
            f"delay {ms.delays_s.min() * 1e3:.1f} ms is shorter than the full model's own lag "
            f"({plat.own_lag_s.max() * 1e3:.1f} ms) in some DOFs; no delay added there"
        )
    spec = imu if imu is not None else default_imu(ms.platform)
    noise = ms.noise_block(spec.rate_hz)
    limits = LimitReport(plat.limits.mode, plat.rate_hz)
    return Run(ms, plat.kind, int(seed), commands, spec, limits, notes, plat, noise)


def simulate(
    config: MotionSystem | str,
    commands: Trajectory,
    model: str = "full",
    seed: int = 0,
    imu: ImuSpec | None = None,
    limit_mode: str = "limit",
    platform: Platform | None = None,
) -> Simulation:
    """Simulate a configuration end to end (arguments as :func:`prepare`).

    Returns
    -------
    Simulation

    """
    return prepare(config, commands, model, seed, imu, limit_mode, platform).collect()
