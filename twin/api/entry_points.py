"""The twin's entry points, one call each: what :mod:`twin` exports.

Every function here takes its configuration the same way (:func:`twin.chain.config.resolve`):
a name (``"mpi"``, ``"srs"``, ``"condition-8"``, ...), the path of a ``twin-config/1`` file
(``str`` or :class:`pathlib.Path`), or a :class:`~twin.chain.config.MotionSystem`. The
obvious arguments come first; every other one is keyword-only. Models default to the
reduced one (Eq 5.11, fast); ``model="full"`` runs the MuJoCo platform.

Examples
--------
>>> import twin
>>> r = twin.describing_function("mpi", "pitch", signals=(2,))
>>> round(r.delay_s * 1e3)  # the fitted delay [ms]; configured: 35 ms
36
>>> r.to_frame().columns[:3].tolist()
['frequency_hz', 'gain', 'gain_db']

"""

from __future__ import annotations

import importlib
import inspect
import os
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from twin.core.errors import UsageError

if TYPE_CHECKING:
    from twin.agard.compare import Comparison
    from twin.agard.df import DfResult
    from twin.agard.session import Session
    from twin.chain.config import MotionSystem
    from twin.chain.imu import ImuSpec
    from twin.chain.simulate import Simulation
    from twin.chain.trajectory import Trajectory
    from twin.core.progress import ProgressFn
    from twin.core.results import Result
    from twin.diagnose.diagnosis import Diagnosis
    from twin.formats.runs import RecordedRun
    from twin.pilot.models.pitch import PitchPilot, PitchRuns
    from twin.platform.kinematics import DofRange

# The modules behind each entry point are imported by the entry point, so that ``import twin``
# loads neither NumPy nor SciPy: the ``twin`` command sets one BLAS thread before NumPy loads
# (twin.core.threads), and it imports this package first.

#: A configuration as every entry point takes it.
Config = "MotionSystem | str | os.PathLike[str]"

#: The AGARD-AR-144 tests of :func:`agard_test`, by the name ``twin agard`` gives them: the
#: ``run_*`` function (module and name) that runs each.
AGARD_TESTS: dict[str, str] = {
    "df": "twin.agard.df:run_df",
    "noise": "twin.agard.noise_level:run_noise",
    "snr": "twin.agard.snr:run_snr",
    "threshold": "twin.agard.threshold:run_threshold",
    "omct": "twin.agard.omct:run_omct",
    "linearity": "twin.agard.linearity:run_linearity",
    "hysteresis": "twin.agard.hysteresis:run_hysteresis",
    "bump": "twin.agard.bump:run_bump",
    "limits": "twin.agard.limits:run_limits",
    "parasitic": "twin.agard.parasitic:run_parasitic",
}

#: The six DOFs (as :data:`twin.core.frames.DOF_NAMES`).
DOFS = ("surge", "sway", "heave", "roll", "pitch", "yaw")


def config_names() -> list[str]:
    """Return every configuration name the entry points accept (besides files and objects).

    Examples
    --------
    >>> config_names()[:3]
    ['mpi', 'mpi-2008', 'srs']

    """
    from twin.chain.config import config_names as names

    return names()


def resolve(config: Config) -> MotionSystem:
    """Return the configuration ``config`` names (:func:`twin.chain.config.resolve`)."""
    from twin.chain.config import resolve as resolved

    return resolved(config)


def configure(
    config: Config,
    *,
    break_hz: float | None = None,
    delay_ms: float | None = None,
    noise: bool | None = None,
    resonance: bool | None = None,
) -> MotionSystem:
    """Return a configuration, with the overrides of ``twin agard`` if given.

    As :func:`twin.measurement.measure.configure`: ``config`` a name, a ``twin-config/1``
    file or a configuration; ``break_hz`` [Hz] (0: no filter), ``delay_ms`` (total delay),
    ``noise`` (Eq 5.10) and ``resonance`` (Eq 5.12/5.13) override it.
    """
    from twin.measurement.measure import configure as configured

    return configured(config, break_hz=break_hz, delay_ms=delay_ms, noise=noise,
                      resonance=resonance)  # fmt: skip


def simulate(
    config: Config,
    signal: Trajectory | str,
    *,
    model: str = "reduced",
    seed: int = 0,
    imu: ImuSpec | None = None,
    limit_mode: str = "limit",
) -> Simulation:
    """Simulate a configuration driven by ``signal`` (:func:`twin.chain.simulate.simulate`).

    Parameters
    ----------
    config : str, path or MotionSystem
        The configuration.
    signal : Trajectory or str
        Pose commands, or a built-in signal's name (``multisine2-heave``, ``rest-5``, ...:
        :func:`twin.chain.signals.builtin_signal`).
    model : str
        ``"reduced"`` (Eq 5.11) or ``"full"`` (MuJoCo).
    seed : int
        Seed of the noise and the IMU; the same seed gives bit-identical results.
    imu : ImuSpec, optional
        The IMU; the platform's ADIS16355 at the UGP by default.
    limit_mode : str
        ``"limit"`` or ``"strict"`` (:mod:`twin.chain.limits`).

    Returns
    -------
    Simulation
        The cabin motion (``response``), the IMU (``imu``) and the limits met (``limits``).

    """
    from twin.chain.signals import builtin_signal
    from twin.chain.simulate import simulate as simulated
    from twin.chain.trajectory import Trajectory

    commands = builtin_signal(signal) if isinstance(signal, str) else signal
    if not isinstance(commands, Trajectory):
        raise UsageError(
            f"signal: expected a Trajectory or a built-in signal's name; got "
            f"{type(signal).__name__}"
        )
    return simulated(resolve(config), commands, model, seed, imu, limit_mode)


def session(
    config: Config,
    *,
    model: str = "reduced",
    seed: int = 0,
    imu: ImuSpec | None = None,
    out: str | Path | None = None,
    rrd: str | None = None,
    progress: ProgressFn | None = None,
) -> Session:
    """Return a :class:`~twin.agard.session.Session`: a bench to run several tests on.

    Use it as a context manager (``with twin.session("mpi") as s: ...``) with the ``run_*``
    functions of :mod:`twin.agard`'s modules; runs are numbered (and seeded) in order.
    ``out`` keeps each run as a ``twin-run/1`` folder, ``rrd`` a Rerun recording.
    """
    from twin.agard.session import Session
    from twin.measurement.measure import Bench
    from twin.viz.record import bench_recorder

    bench = Bench(resolve(config), model, seed, imu)
    recorder = bench_recorder(bench, rrd) if rrd is not None else None
    return Session(bench, out, recorder, progress)


def describing_function(
    config: Config,
    dof: str,
    *,
    model: str = "reduced",
    seed: int = 0,
    signals: Sequence[int] = (1, 2),
    imu: ImuSpec | None = None,
    out: str | Path | None = None,
    rrd: str | None = None,
) -> DfResult:
    """Measure a describing function as AGARD-AR-144 does (``twin agard df``).

    Runs the Table 5.2 multi-sines ``signals`` in ``dof`` and analyses the IMU as the thesis'
    App. C does; the runs have seeds ``seed``, ``seed + 1``, ...

    Parameters
    ----------
    config : str, path or MotionSystem
        The configuration.
    dof : str
        The driven DOF (``surge`` ... ``yaw``).
    model : str
        ``"reduced"`` (Eq 5.11) or ``"full"`` (MuJoCo).
    seed : int
        Seed of the first run.
    signals : sequence of int
        Table 5.2 signals (1, 2) or the extension signal 3.
    imu : ImuSpec, optional
        The IMU; the platform's by default.
    out : str or Path, optional
        Folder for the runs (``OUT/runs/NN-name``, ``twin-run/1``).
    rrd : str, optional
        Rerun recording of the runs.

    Returns
    -------
    DfResult

    """
    from twin.agard.df import run_df

    with session(config, model=model, seed=seed, imu=imu, out=out, rrd=rrd) as s:
        return run_df(s, dof, signals)


def agard_test(
    config: Config,
    test: str,
    dof: str | Sequence[str],
    *,
    model: str = "reduced",
    seed: int = 0,
    imu: ImuSpec | None = None,
    out: str | Path | None = None,
    rrd: str | None = None,
    **options: Any,
) -> Result:
    """Run one AGARD-AR-144 test on a configuration (``twin agard TEST``).

    Parameters
    ----------
    config : str, path or MotionSystem
        The configuration.
    test : str
        One of :data:`AGARD_TESTS`: ``df``, ``noise``, ``snr``, ``threshold``, ``omct``,
        ``linearity``, ``hysteresis``, ``bump``, ``limits``, ``parasitic``.
    dof : str or sequence of str
        The driven DOF (``parasitic``: one or several).
    model, seed, imu, out, rrd
        As :func:`describing_function`.
    **options
        The test's own settings, by the names of its ``run_*`` function (e.g. ``amplitude``
        and ``repeats`` for :func:`twin.agard.threshold.run_threshold`).

    Returns
    -------
    Result
        The test's result (:class:`twin.core.results.Result`).

    Raises
    ------
    UsageError
        For an unknown test or an option the test does not take (naming the allowed ones).

    """
    if test not in AGARD_TESTS:
        raise UsageError(f"unknown AGARD test {test!r}; expected one of {', '.join(AGARD_TESTS)}")
    module, name = AGARD_TESTS[test].split(":")
    run = getattr(importlib.import_module(module), name)
    allowed = list(inspect.signature(run).parameters)[2:]
    unknown = sorted(set(options) - set(allowed))
    if unknown:
        raise UsageError(
            f"the {test} test takes no {', '.join(unknown)}; its options: {', '.join(allowed)}"
        )
    if test == "parasitic":
        dof = (dof,) if isinstance(dof, str) else tuple(dof)
    elif not isinstance(dof, str):
        raise UsageError(f"dof: the {test} test drives one DOF ({', '.join(DOFS)})")
    with session(config, model=model, seed=seed, imu=imu, out=out, rrd=rrd) as s:
        return run(s, dof, **options)


def compare(
    config: Config,
    *,
    dofs: Sequence[str] = DOFS,
    signals: Sequence[int] = (1, 2, 3),
    progress: ProgressFn | None = None,
) -> Comparison:
    """Compare the full and the reduced model of a configuration (``twin compare``).

    See :func:`twin.agard.compare.compare`; the full model runs, so this takes a while.
    """
    from twin.agard.compare import compare as compared

    return compared(resolve(config), dofs, signals, progress)


def diagnose_runs(
    runs: Sequence[str | Path | RecordedRun],
    *,
    config: Config | None = None,
    model: str = "reduced",
    validate: Sequence[str | Path | RecordedRun] = (),
    seed: int = 0,
    dofs: Sequence[str] | None = None,
    physics: bool = False,
    max_hz: float = 15.0,
    realisations: int = 4,
    imu_noise: float | None = None,
    progress: ProgressFn | None = None,
) -> Diagnosis:
    """Diagnose recorded runs against the nominal twin (``twin diagnose``).

    Named apart from the subpackage :mod:`twin.diagnose` (a function of that name would
    shadow it as an attribute of :mod:`twin`).

    Parameters
    ----------
    runs : sequence of path or RecordedRun
        ``twin-run/1`` folders of one platform (or runs already read).
    config : str, path or MotionSystem, optional
        The nominal configuration; the one the runs' ``meta.json`` names by default.
    model, validate, seed, dofs, physics, max_hz, realisations, imu_noise, progress
        As :func:`twin.diagnose.diagnosis.diagnose`.

    Returns
    -------
    Diagnosis

    """
    from twin.diagnose.diagnosis import diagnose as diagnosed
    from twin.formats.runs import RecordedRun

    if isinstance(runs, str | os.PathLike | RecordedRun):
        raise UsageError("runs: expected a sequence of runs (a list of run folders); got one")
    nominal = None if config is None else resolve(config)
    return diagnosed(list(runs), nominal, model, validate, max_hz, seed, dofs, realisations,
                     progress, imu_noise, physics)  # fmt: skip


def load_run(path: str | Path) -> RecordedRun:
    """Read a ``twin-run/1`` run folder (:func:`twin.formats.runs.read_run`)."""
    from twin.formats.runs import read_run

    return read_run(path)


def workspace(platform: Config) -> dict[str, DofRange]:
    """Return a platform's workspace per DOF, each alone (App. B.3; ``twin workspace``).

    ``platform`` is a platform (``mpi``, ``srs``) or any configuration: its platform's.
    """
    from twin.platform.geometry import load_geometry
    from twin.platform.kinematics import workspace as ranges

    return ranges(load_geometry(resolve(platform).platform))


def fly(
    config: Config,
    *,
    pilot: PitchPilot | None = None,
    runs: int = 1,
    seed: int = 0,
    remnant_scale: float = 0.0,
    model: str = "reduced",
    progress: ProgressFn | None = None,
) -> PitchRuns:
    """Fly the thesis' pitch task through a motion configuration (``twin pilot run``).

    Parameters
    ----------
    config : str, path or MotionSystem
        The motion configuration (``condition-1`` ... ``condition-8``, ``srs``, ...).
    pilot : PitchPilot, optional
        The pilot; the thesis' nominal one by default.
    runs : int
        Runs, each with fresh remnant and noise.
    seed : int
        Seed of remnant and motion noise.
    remnant_scale : float
        Gain on the unit remnant (0: none).
    model : str
        ``"reduced"`` or ``"full"``.
    progress : callable, optional
        Called with the flown time.

    Returns
    -------
    PitchRuns
        Error, stick, aircraft and felt pitch of every run
        (:func:`twin.pilot.models.pitch.simulate_pitch`).

    """
    from twin.pilot.models.pitch import PitchPilot, simulate_pitch

    return simulate_pitch(pilot if pilot is not None else PitchPilot(), resolve(config), runs,
                          seed, remnant_scale, model=model, progress=progress)  # fmt: skip
