"""Measurements: run a test signal on a twin (or read a recorded run) and get accelerations.

Every AGARD-AR-144 test compares a commanded acceleration with the acceleration an IMU
measured (§3.3: "acceleration is chosen as the metric"). A :class:`Measurement` holds both on
the post-processing grid (App. C.2.3: FIR 201 taps / 15 Hz, Savitzky-Golay differentiator,
100 Hz):

* commanded: the second derivative of the pose commands (the cubic spline the twin follows):
  UGP acceleration in base axes [m/s^2] and Euler-angle accelerations [rad/s^2];
* measured: the IMU's specific force with the static 1 g removed (f + (0, 0, 9.81) in cabin
  axes: a cabin at rest reads zero; tilt still shows, as g sin(theta) in surge when pitching,
  because specific force is what a pilot feels, §3.3) and the angular acceleration
  differentiated from the gyros [rad/s^2].

A :class:`Bench` is what is measured: a motion-system configuration on the full or reduced
platform, with a seed and an IMU. The same analyses run on a recorded ``twin-run/1`` folder
(:func:`from_run`), so a real platform's measurement goes through the same code.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from twin.chain.config import MotionSystem, motion_system, resolve
from twin.chain.imu import ImuRecord, ImuSpec, postprocess
from twin.chain.signals import check_signal
from twin.chain.simulate import MODELS, Run, Simulation, make_platform, prepare
from twin.chain.trajectory import Trajectory, interp_columns
from twin.core.errors import RunFormatError, SignalError, UnknownPlatformError
from twin.core.frames import DOF_NAMES, dof_index
from twin.formats.run_checks import read_plausible_run
from twin.formats.runs import RecordedRun

FloatArray = NDArray[np.float64]
G = 9.81
#: Rate of the post-processed signals (App. C.2.3) [Hz].
ANALYSIS_RATE_HZ = 100.0
#: Least time [s] the IMU record and the commands must cover together to be measured.
MIN_OVERLAP_S = 1.0
#: Where one file goes on beyond the other, the share of its activity in the time both cover
#: above which the test went on there (a file cut short).
GOES_ON = 0.3
#: A command's first or last speed or acceleration above this share of its largest: moving.
MOVING_REL = 0.01


@dataclass(frozen=True, eq=False)
class Measurement:
    """Commanded and measured accelerations of one run, on the post-processing grid.

    Attributes
    ----------
    t : ndarray, shape (n,)
        Time [s].
    commanded, measured : ndarray, shape (n, 6)
        Accelerations per DOF (surge, sway, heave [m/s^2], roll, pitch, yaw [rad/s^2]).
    commands : Trajectory
        The pose commands of the run.
    source : str
        What was measured (configuration, model and seed, or the run folder).
    config : MotionSystem
        The configuration (for the analytic model; from ``meta.json`` for recorded runs).
    meta : dict
        Signal design and other facts (``signal`` as written by :mod:`twin.agard.runs`).

    """

    t: FloatArray
    commanded: FloatArray
    measured: FloatArray
    commands: Trajectory
    source: str
    config: MotionSystem
    meta: dict = field(default_factory=dict)


def from_imu(
    commands: Trajectory, imu: ImuRecord, source: str, config: MotionSystem, meta: dict
) -> Measurement:
    """Post-process IMU samples (App. C.2.3) and pair them with the commanded accelerations.

    Only the time both cover is kept: a recorder that logs the IMU before the commands start
    or after they end (a platform at rest) is common, and the commands say nothing there.

    Raises
    ------
    SignalError
        The two cover less than :data:`MIN_OVERLAP_S` together.

    """
    p = postprocess(imu, ANALYSIS_RATE_HZ)
    start, end = commands.t0, commands.t0 + commands.duration
    keep = (p.t >= start - 1e-9) & (p.t <= end + 1e-9)
    if p.t[keep].size < 2 or p.t[keep][-1] - p.t[keep][0] < MIN_OVERLAP_S:
        raise SignalError(
            f"{source}: the IMU record ({p.t[0]:.2f}-{p.t[-1]:.2f} s) and the commands "
            f"({start:.2f}-{end:.2f} s) overlap for less than {MIN_OVERLAP_S:g} s; both must "
            "cover the test, on one clock"
        )
    t = p.t[keep]
    acc = commands.at(t, 2)
    measured = np.hstack([p.accel[keep] + np.array([0.0, 0.0, G]),
                          p.angular_acceleration[keep]])  # fmt: skip
    return Measurement(t, acc, measured, commands, source, config, meta)


def clean_config(config: MotionSystem) -> MotionSystem:
    """Return the configuration without noise (for noise-free predictions)."""
    return config.replace(
        name=config.name,
        noise=False,
        extensions=tuple(e for e in config.extensions if e.effect != "noise"),
    )


def simulate_measurement(
    config: MotionSystem, commands: Trajectory, t: FloatArray, model: str, seed: int, imu: ImuSpec
) -> FloatArray:
    """Run commands through a configuration; the post-processed accelerations at ``t``.

    Returns
    -------
    ndarray, shape (len(t), 6)
        As :attr:`twin.measurement.measure.Measurement.measured`, interpolated onto ``t`` when the
        simulated IMU's grid differs (a recorded IMU may start elsewhere on the clock).

    """
    return simulate_measurements(config, commands, t, model, [(seed, imu)])[0]


def simulate_measurements(
    config: MotionSystem,
    commands: Trajectory,
    t: FloatArray,
    model: str,
    readings: Sequence[tuple[int, ImuSpec]],
) -> list[FloatArray]:
    """:func:`simulate_measurement` for each (seed, IMU) pair, the platform simulated once.

    Without heave noise the motion is the same for every pair (only the IMU's noise differs:
    :meth:`twin.chain.simulate.Run.read_by_imus`, the same bits); with it each pair is its
    own simulation. The full platform leaves the actuators' forces out (read by no
    measurement).
    """

    def run_of(seed: int, imu: ImuSpec) -> Run:
        plat = make_platform(config.platform, model, physics=config.physics, leg_forces=False)
        return prepare(config, commands, model, seed, imu, platform=plat)

    run = run_of(*readings[0])
    if run.noise is None:
        sims = run.read_by_imus(readings)
    else:
        sims = [run.collect()] + [run_of(s, i).collect() for s, i in readings[1:]]
    out = []
    for sim in sims:
        m = from_imu(sim.commands, sim.imu, f"{config.name} ({model})", config, {})
        same = m.t.shape == t.shape and np.allclose(m.t, t, atol=1e-9)
        out.append(m.measured if same else interp_columns(t, m.t, m.measured))
    return out


def run_config(run: RecordedRun | str | Path) -> MotionSystem:
    """Return the configuration a recorded run's ``meta.json`` names."""
    rec = run if isinstance(run, RecordedRun) else read_plausible_run(run)
    return MotionSystem.from_meta(
        rec.meta["platform"], rec.meta["platform_config"], f"from {rec.path}/meta.json"
    )


def from_run(run: RecordedRun | str | Path) -> Measurement:
    """Return the :class:`Measurement` of a recorded ``twin-run/1`` folder (validated)."""
    rec = run if isinstance(run, RecordedRun) else read_plausible_run(run)
    config = run_config(rec)
    _check_not_cut(rec)
    imu = ImuRecord(rec.imu_t, rec.imu[:, :3], rec.imu[:, 3:])
    m = from_imu(rec.commands, imu, str(rec.path), config, dict(rec.meta))
    window = m.meta.get("signal", {}).get("window_s")
    if window is not None and not (m.t[0] - 1e-6 <= window[0] and window[1] <= m.t[-1] + 1e-6):
        raise RunFormatError(
            f"{rec.path}/meta.json: signal.window_s [{window[0]:g}, {window[1]:g}] s is not "
            f"covered by both the commands ({rec.commands.t0:g}-"
            f"{rec.commands.t0 + rec.commands.duration:g} s) and imu.csv ({rec.imu_t[0]:g}-"
            f"{rec.imu_t[-1]:g} s); a file cut short, or a window from another run"
        )
    return m


def _check_not_cut(rec: RecordedRun) -> None:
    """Refuse a commands file or an IMU record that stops while the test goes on.

    An IMU logged beyond the commands is common (the platform at rest before and after the
    test), and only the time both cover is measured. But where one file goes on more than
    :data:`MIN_OVERLAP_S` beyond the other, what it holds there tells whether the test went
    on: commands still moving there (their speed's rms at least :data:`GOES_ON` of that in the
    time both cover, in a DOF that moves), or commands that stop moving (speed or
    acceleration at their first or last sample above :data:`MOVING_REL` of their largest, in
    a DOF that moves) while the IMU moves there about as much as during the test (no logged
    channel's rms, mean removed, down to :data:`GOES_ON` of its own in the time both cover)
    mean a file cut short, whose measurement would pair the IMU with the wrong commands.
    """
    c = rec.commands
    first, last = c.t0, c.t0 + c.duration
    both = (max(first, rec.imu_t[0]), min(last, rec.imu_t[-1]))
    speed = np.diff(c.values, axis=0) * c.rate_hz
    ts = c.t[:-1]

    def rms(x: FloatArray, lo: float, hi: float, t: FloatArray) -> FloatArray:
        y = x[(t >= lo) & (t <= hi)]
        return np.sqrt(np.mean((y - y.mean(axis=0)) ** 2, axis=0)) if len(y) > 1 else 0 * x[0]

    during_cmd = rms(speed, *both, ts)
    moves = during_cmd > 0.01 * during_cmd.max()  # DOFs the test drives (not numerical dust)
    during_imu = rms(rec.imu, *both, rec.imu_t)
    live = during_imu > 0  # a channel logged as a constant tells nothing
    # the commands' speed and acceleration at their first and last sample, over their largest
    acc = np.diff(c.values, 2, axis=0) if c.n > 2 else np.zeros((1, c.values.shape[1]))
    rel = [np.abs(d[[0, -1]]) / np.where(np.abs(d).max(axis=0) > 0, np.abs(d).max(axis=0), 1)
           for d in (speed, acc)]  # fmt: skip
    at_edge = np.where(moves, np.maximum(*rel), 0.0).max(axis=1)  # (first, last)
    span = (f"the commands cover {first:g}-{last:g} s and the IMU {rec.imu_t[0]:g}-"
            f"{rec.imu_t[-1]:g} s")  # fmt: skip
    for lo, hi, row, what in ((rec.imu_t[0], first, 0, "commands.csv starts late"),
                              (last, rec.imu_t[-1], 1, "commands.csv ends early")):  # fmt: skip
        if hi - lo > MIN_OVERLAP_S and at_edge[row] > MOVING_REL and live.any():
            beyond = rms(rec.imu, lo, hi, rec.imu_t)
            if np.all(beyond[live] > GOES_ON * during_imu[live]):
                raise RunFormatError(
                    f"{rec.path}/{what}: {span}, and the IMU moves as much outside the "
                    "commands as within them; give the whole commands, or cut imu.csv to "
                    "the time they cover"
                )
    for lo, hi, what in ((first, rec.imu_t[0], "imu.csv starts late"),
                         (rec.imu_t[-1], last, "imu.csv ends early")):  # fmt: skip
        if hi - lo > MIN_OVERLAP_S and moves.any():
            beyond = rms(speed, lo, hi, ts)
            if np.any(beyond[moves] >= GOES_ON * during_cmd[moves]):
                raise RunFormatError(
                    f"{rec.path}/{what}: {span}, and the commands move outside the IMU "
                    "record; give the whole record, or cut commands.csv to the time it covers"
                )


@dataclass(frozen=True)
class Bench:
    """A simulated platform set up for tests: configuration, model, seed and IMU.

    Attributes
    ----------
    config : MotionSystem
        The motion system.
    model : str
        ``"full"`` (MuJoCo) or ``"reduced"`` (Eq 5.11).
    seed : int
        Seed of the first run; run ``k`` of a test uses ``seed + k``.
    imu : ImuSpec or None
        The IMU; the platform's ADIS16355 at the UGP by default.

    """

    config: MotionSystem
    model: str = "full"
    seed: int = 0
    imu: ImuSpec | None = None

    def __post_init__(self) -> None:
        """Check the model and seed."""
        if self.model not in MODELS:
            raise SignalError(f"unknown model {self.model!r}; expected one of {MODELS}")
        if not isinstance(self.seed, int) or self.seed < 0:
            raise SignalError(f"seed must be an integer >= 0; got {self.seed!r}")

    @property
    def name(self) -> str:
        """Short description, e.g. ``mpi (full, seed 0)``."""
        return f"{self.config.name} ({self.model}, seed {self.seed})"

    def prepare(
        self, commands: Trajectory, k: int = 0, label: str = "signal", check_limits: bool = True
    ) -> Run:
        """Check ``commands`` against the platform limits and set up run ``k``.

        ``check_limits=False`` lets commands beyond the limits through to the actuator
        limiter (the system-limits test, :mod:`twin.agard.limits`, drives into them).
        """
        if check_limits:
            check_signal(commands, self.config.platform, label)
        return prepare(self.config, commands, self.model, self.seed + k, self.imu)

    def measure(self, sim: Simulation, meta: dict | None = None) -> Measurement:
        """Turn a simulation of this bench into a :class:`Measurement`."""
        source = f"{self.config.name} ({self.model}) run seed {sim.seed}"
        return from_imu(sim.commands, sim.imu, source, self.config, dict(meta or {}))


def configure(
    config: MotionSystem | str | os.PathLike[str],
    *,
    break_hz: float | None = None,
    delay_ms: float | None = None,
    noise: bool | None = None,
    resonance: bool | None = None,
) -> MotionSystem:
    """Return a configuration, with the overrides of ``twin agard`` if given.

    Parameters
    ----------
    config : str, path or MotionSystem
        A name (``mpi``, ``srs``, ``condition-N``, ...: :func:`twin.chain.config.config_names`),
        a ``twin-config/1`` file or a configuration (:func:`twin.chain.config.resolve`).
    break_hz : float, optional
        Platform-filter break frequency [Hz]; 0 removes the filter.
    delay_ms : float, optional
        Total motion-system delay [ms] (command to measured response, as §5.6.2.2 measures
        it: on the SRS, 25 ms is the SRS alone and 60 ms adds the MPI's 35 ms).
    noise : bool, optional
        Heave noise of Eq 5.10 on or off.
    resonance : bool, optional
        SRS resonance terms of Eq 5.12/5.13 on or off.

    Examples
    --------
    >>> configure("mpi", break_hz=5).filter_break_hz
    5.0

    """
    return resolve(config).override(break_hz, delay_ms, noise, resonance)


def is_run_folder(target: str | Path) -> bool:
    """Whether a command-line target names a run folder (rather than a configuration)."""
    return Path(target).is_dir() and (Path(target) / "meta.json").exists()


def check_target(target: str) -> None:
    """Raise a clear error for a target that is neither a configuration nor a run folder."""
    if is_run_folder(target):
        return
    if Path(target).is_dir():
        raise UnknownPlatformError(f"{target}: a folder without meta.json is not a twin-run/1 run")
    if "/" in target and not target.endswith(".json") and not Path(target).exists():
        raise UnknownPlatformError(
            f"{target}: no such twin-run/1 folder (a command's target is a configuration name, "
            "a twin-config/1 .json file or a twin-run/1 folder)"
        )
    motion_system(target)  # a name or a twin-config/1 file


def driven_dof(m: Measurement, dof: str | None = None) -> int:
    """Index of the driven DOF: ``dof`` if given, else the one the commands move most."""
    if dof is not None:
        return dof_index(dof)
    signal = m.meta.get("signal", {})
    if signal.get("dof") in DOF_NAMES:
        return dof_index(signal["dof"])
    excursion = np.ptp(m.commands.values, axis=0)
    if not excursion.any():
        raise SignalError(f"{m.source}: the commands do not move; no driven DOF")
    return int(np.argmax(excursion))
