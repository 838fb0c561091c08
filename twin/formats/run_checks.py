"""Plausibility of a recorded run: what a well-formed ``twin-run/1`` folder must also be.

:func:`twin.formats.runs.read_run` checks the format (files, headers, numbers, uniform time); here
is whether the numbers are a motion system's: every reader of runs (``twin diagnose``, ``twin
agard`` on a run folder, the notebooks) gets them through :func:`plausible_run`, and ``twin
import`` checks what it is about to write the same way. One function per check, each raising
:class:`~twin.core.errors.RunFormatError` with one line that says what is implausible and how to
fix it. The yardstick is the nominal twin's ideal IMU reading of the run's own commands
(:mod:`twin.formats.run_expected`):

- :func:`supported_rate`: the IMU's rate within :data:`IMU_RATE_HZ` (faster: resampled
  with a note; slower: refused);
- :func:`check_constant`: no channel constant where the commands move it (a dead or unlogged
  sensor, an all-zero file);
- :func:`check_gyro_offset`: gyros that read no steady rate (gravity on a gyro: accelerometer
  and gyro columns swapped);
- :func:`check_gravity`: the accelerometers read gravity as the commanded attitude does,
  (0, 0, -9.81) m/s^2 at rest (not 1.0: g; not +9.81: z up; not 0: gravity removed);
- :func:`check_gyro_scale`: gyros in rad/s (not deg/s: 57 times the commanded rate);
- :func:`check_timing`: the IMU follows its commands, with the right signs, within the lags a
  platform can have (not 0.5 s off their clock, not another run's IMU).

:func:`check_distinct` refuses the same run given twice (it would count twice).
"""

from __future__ import annotations

import dataclasses
import hashlib
from collections.abc import Sequence
from fractions import Fraction
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import signal

from twin.chain.config import MotionSystem
from twin.chain.imu import G, rotate_readings
from twin.core.errors import RunFormatError
from twin.core.frames import DOF_NAMES
from twin.formats.run_expected import BAND_HZ, Comparison, compare, ideal_imu
from twin.formats.runs import HEADERS, RecordedRun, read_run

FloatArray = NDArray[np.float64]
CHANNELS = HEADERS["imu.csv"][1:]
#: Where such data can be brought into the format (every message about a recording says it).
IMPORT_HINT = "twin import converts units, axes and clocks of measured logs"

#: IMU rates the App. C.2.3 post-processing is made for [Hz]. Below 100 Hz the IMU cannot
#: fill the 100 Hz analysis grid (its samples would be invented by interpolation). Above
#: 2048 Hz (2.5 x the ADIS16355's 819.2 Hz) the 201-tap FIR of App. C.2.3, whose length is
#: counted in samples, no longer stops the noise above the grid's 50 Hz Nyquist frequency
#: (89 dB down at 2048 Hz, 29 dB at 4096 Hz, 1 dB at 20 kHz): it aliases into the describing
#: functions (at 20 kHz, 12 dB and 80 deg wrong at 0.1 Hz in pitch).
IMU_RATE_HZ = (100.0, 2048.0)
#: A faster IMU is resampled to about this rate [Hz] (the ADIS16355's, the thesis' own).
RESAMPLED_RATE_HZ = 819.2
#: Largest numerator or denominator of the resampling ratio (scipy.signal.resample_poly):
#: 20 kHz -> 819.2 Hz is 128/3125 exactly.
MAX_RATIO_TERM = 10_000

#: Smallest motion of a channel the commands predict (rms about its mean, band-limited) for it
#: to count as driven: 0.01 m/s^2 and 0.001 rad/s, far below any IMU's noise, so a channel
#: that stays exactly constant while that much is commanded is no sensor reading.
MOTION_FLOOR = np.array([0.01] * 3 + [0.001] * 3)
#: Median step between consecutive samples above which a channel shows sensor noise, per
#: channel [m/s^2, rad/s]: 1/300 of the ADIS16355's (0.34 m/s^2 and 0.01 rad/s rms per
#: sample); a noise-free reading of a platform's motion moves far less from sample to sample.
NOISE_STEP = np.array([1e-3] * 3 + [1e-4] * 3)
#: A driven channel is compared when it moves at least this share of the most-moved channel
#: of its kind (specific force, rate): the others are cross-talk, lost in the sensor noise.
INFORMATIVE_SHARE = 0.05
#: The accelerometers' median over the record may differ from the nominal twin's (gravity in
#: the commanded attitude) by this much [m/s^2]: 15 % of g. A mount tilted by a few degrees or
#: a bias of tens of mg stays well inside; g (1.0), z up (+9.81), gravity removed (0), a
#: swapped axis (9.81 on x or y) or ft/s^2 (32.2) are far outside.
GRAVITY_TOLERANCE = 0.15 * G
#: A median rate above this on any gyro [rad/s] (29 deg/s) is no angular rate: the
#: ADIS16355's bias is 0.015 deg/s, and a platform returns, so its mean rate is about zero.
GYRO_OFFSET_MAX = 0.5
#: Gyros whose rms exceeds the nominal twin's (where the commands rotate) by more than this
#: factor are not in rad/s (deg/s reads 57 times): 10 is the top of the diagnosis' gain search.
GYRO_SCALE_MAX = 10.0
#: Rms the gyros may have on top of the commanded rate before their scale is judged [rad/s]:
#: 0.05 rad/s (3 deg/s) in the 15 Hz band is 25 times the ADIS16355's noise there.
GYRO_NOISE_ALLOWANCE = 0.05
#: The largest extra delay [s] a platform may show beyond its nominal one: the top of the
#: diagnosis' delay search (and of ``twin import``'s plausible lag). Less delay than nominal
#: is allowed down to none at all.
MAX_EXTRA_DELAY_S = 0.3
#: Slack on the allowed lags [s]: two samples of the 100 Hz grid and a platform's own lag.
LAG_TOLERANCE_S = 0.02
#: A peak outside the allowed lags is taken for a clock offset when its correlation beats
#: every allowed lag's by this much plus three standard errors of the difference of two
#: correlations r (sqrt(2 (1 - r^2) / n), n the independent samples in the band: 2 x 15 Hz x
#: the time compared): a periodic signal correlates as well one period on, within the noise.
OFFSET_MARGIN = 0.05
#: Least correlation of a peak that tells where the IMU is on the commands' clock.
MIN_CORRELATION = 0.3
#: An IMU that follows its commands correlates with the nominal twin's reading about as the
#: expected's rms over the recorded one's (a gain of 1, the rest noise); one that correlates at
#: less than this share of that, at every lag, does not follow them. Judged only where the
#: expected would explain at least :data:`MIN_EXPLAINED` of the recorded rms.
FOLLOW_SHARE = 0.25
MIN_EXPLAINED = 0.5
#: A channel whose correlation with the nominal twin's is below minus this at the lag that
#: fits best (and never above half of it) is logged with the wrong sign.
FLIPPED = 0.5


def supported_rate(run: RecordedRun) -> RecordedRun:
    """Return the run with its IMU at a rate the post-processing is made for.

    Above :data:`IMU_RATE_HZ` the IMU is resampled to about :data:`RESAMPLED_RATE_HZ`
    (:func:`scipy.signal.resample_poly`, anti-aliased) and the run's ``notes`` say so
    (``meta.json``'s ``imu.rate_hz`` becomes the new rate).

    Raises
    ------
    RunFormatError
        An IMU slower than the range.

    """
    rate = float(run.meta["imu"]["rate_hz"])
    lo, hi = IMU_RATE_HZ
    where = f"{run.path}/imu.csv"
    if rate < lo:
        raise RunFormatError(
            f"{where}: sampled at {rate:g} Hz, below the {lo:g} Hz of the analysis grid "
            f"(App. C.2.3); record the IMU at {lo:g}-{hi:g} Hz"
        )
    if rate <= hi:
        return run
    ratio = Fraction(RESAMPLED_RATE_HZ / rate).limit_denominator(MAX_RATIO_TERM)
    values = signal.resample_poly(run.imu, ratio.numerator, ratio.denominator, axis=0,
                                  padtype="line")  # fmt: skip
    new = rate * ratio
    t = run.imu_t[0] + np.arange(len(values)) / new
    keep = t <= run.imu_t[-1] + 1e-9
    note = (f"{where}: sampled at {rate:g} Hz, above the {hi:g} Hz the App. C.2.3 "
            f"post-processing is made for; resampled to {float(new):.6g} Hz "
            "(scipy.signal.resample_poly)")  # fmt: skip
    meta = {**run.meta, "imu": {**run.meta["imu"], "rate_hz": float(new)}}
    return dataclasses.replace(run, meta=meta, imu_t=t[keep], imu=values[keep],
                               notes=(*run.notes, note))  # fmt: skip


def _informative(cmp: Comparison) -> list[int]:
    """Channels the commands drive clearly (:data:`MOTION_FLOOR`, :data:`INFORMATIVE_SHARE`)."""
    sd = cmp.expected.std(axis=0)
    out = []
    for group in (slice(0, 3), slice(3, 6)):
        top = sd[group].max()
        out += [k for k in range(group.start, group.stop)
                if sd[k] > MOTION_FLOOR[k] and sd[k] >= INFORMATIVE_SHARE * top]  # fmt: skip
    return out


def _dofs_moving(run: RecordedRun) -> str:
    """Name the DOFs the commands move (for messages)."""
    span = np.ptp(run.commands.values, axis=0)
    return ", ".join(d for d, s in zip(DOF_NAMES, span, strict=True) if s > 0) or "no DOF"


def check_constant(run: RecordedRun, cmp: Comparison | None, where: str) -> None:
    """Refuse IMU channels that stay constant where they cannot.

    A twin's ideal IMU reads every motion and nothing else: its channels that nothing moves
    stay constant. A channel logged as one value is a dead or unlogged sensor (or a file of
    zeros) when the commands move it (:data:`MOTION_FLOOR`), or when another channel of the
    same sensor (accelerometers, gyros) that nothing moves shows noise (:data:`NOISE_STEP`):
    a real sensor's axes all do.
    """
    flat = np.ptp(run.imu, axis=0) == 0
    if not flat.any():
        return
    if cmp is None:
        return
    moved = cmp.expected.std(axis=0)
    driven = moved > MOTION_FLOOR
    # noise shows on the axes nothing moves (a tenth of the floor): steps a motion cannot make
    step = np.median(np.abs(np.diff(run.imu, axis=0)), axis=0)
    shows = (moved <= 0.1 * MOTION_FLOOR) & (step > NOISE_STEP)
    noisy = np.repeat([bool(shows[g].any()) for g in (slice(0, 3), slice(3, 6))], 3)
    dead = [c for c, f, d, n in zip(CHANNELS, flat, driven, noisy, strict=True) if f and (d or n)]
    if not dead:
        return
    value = run.imu[0, CHANNELS.index(dead[0])] + 0.0  # no "-0"
    what = "every channel is" if flat.all() else f"{', '.join(dead)} stay{'s' * (len(dead) == 1)}"
    why = (f"the commands move {_dofs_moving(run)}" if driven[flat].any()
           else "the sensor's other axes read noise")  # fmt: skip
    raise RunFormatError(
        f"{where}: {what} constant ({dead[0]} = {value:g} throughout) while {why}: a dead or "
        f"unlogged sensor, or a file of zeros; give the recorded IMU ({IMPORT_HINT})"
    )


def check_gyro_offset(run: RecordedRun, where: str) -> None:
    """Refuse gyros with a steady rate (:data:`GYRO_OFFSET_MAX`): gravity on a gyro, ...

    With gravity's magnitude on the gyros and not on the accelerometers, the two triples of
    columns are swapped.
    """
    gyro = np.median(run.imu[:, 3:], axis=0)
    if np.abs(gyro).max() <= GYRO_OFFSET_MAX:
        return
    accel = np.median(run.imu[:, :3], axis=0)
    shown = ", ".join(f"{c} {v:+.3g}" for c, v in zip(CHANNELS[3:], gyro, strict=True))
    if abs(np.linalg.norm(gyro) / G - 1) < 0.15 and np.linalg.norm(accel) < 0.5 * G:
        raise RunFormatError(
            f"{where}: the gyros read gravity ({shown}) and the accelerometers do not "
            "(ax, ay, az median " + ", ".join(f"{v:+.3g}" for v in accel) + "): the "
            "accelerometer and gyro columns are swapped; the columns are t,ax,ay,az,p,q,r"
        )
    raise RunFormatError(
        f"{where}: the gyros read a steady rate ({shown} rad/s median), which no platform "
        f"holds (it returns); not an angular rate in rad/s: check the columns and units "
        f"({IMPORT_HINT})"
    )


def check_gravity(
    run: RecordedRun, cmp: Comparison | None, where: str, rotation: ArrayLike | None = None
) -> None:
    """Refuse accelerometers that do not read gravity as the commanded attitude does.

    The median specific force over the record is compared with the nominal twin's (about
    (0, 0, -9.81) m/s^2, tilted as the commands tilt the cabin and as the configuration's
    ``imu_alignment``, ``rotation``, tilts the IMU); beyond :data:`GRAVITY_TOLERANCE` the
    message names the likely cause.
    """
    got = np.median(run.imu[:, :3], axis=0)
    if cmp is not None:
        want = np.median(cmp.expected[:, :3], axis=0)
    else:  # too short to filter: the commands' own attitude
        c = run.commands
        ideal = rotate_readings(ideal_imu(c, run.meta["imu"]["position_m"], c.t), rotation)
        want = np.median(ideal[:, :3], axis=0)
    if np.linalg.norm(got - want) <= GRAVITY_TOLERANCE:
        return
    size = float(np.linalg.norm(got))
    shown = "(" + ", ".join(f"{v:+.3g}" for v in got) + ") m/s^2"
    wanted = "(" + ", ".join(f"{v:+.3g}" for v in want) + ")"
    if np.linalg.norm(got - (0.0, 0.0, -G)) <= GRAVITY_TOLERANCE:
        why = ("the IMU reads a level cabin where the commands tilt it: angles in commands.csv "
               "in degrees? (the format's are in rad)")  # fmt: skip
    elif abs(size - 1.0) < 0.15:
        why = "gravity as 1: in g; multiply ax, ay, az by 9.81 for m/s^2"
    elif abs(size / G - 1) < 0.15 and got[2] > 0.8 * G:
        why = ("gravity up: the IMU logs z up; the twin's cabin axes are x forward, y right, "
               "z down (negate ay, az, q, r)")  # fmt: skip
    elif abs(size / G - 1) < 0.15:
        axis = "xyz"[int(np.argmax(np.abs(got)))]
        why = (f"gravity along {axis}: axes mapped wrong or a rotated mount; the twin's cabin "
               "axes are x forward, y right, z down")  # fmt: skip
    elif size < 0.15 * G:
        why = ("no gravity: the format holds specific force, which reads (0, 0, -9.81) at rest "
               "(gravity removed, or a file of zeros)")  # fmt: skip
    else:
        why = (f"gravity as {size:.3g} where it is {G:g} m/s^2: a unit error (ft/s^2 read "
               f"{G / 0.3048:.3g}, g 1.0)")  # fmt: skip
    raise RunFormatError(f"{where}: the accelerometers read {shown} (median) where the commands "
                         f"give {wanted}; {why} ({IMPORT_HINT})")  # fmt: skip


def check_gyro_scale(cmp: Comparison | None, where: str) -> None:
    """Refuse gyros that read far more than the commanded rate (:data:`GYRO_SCALE_MAX`)."""
    if cmp is None:
        return
    rates = [k for k in _informative(cmp) if k >= 3]
    if not rates:
        return
    got = np.nanstd(cmp.aligned[:, rates], axis=0)
    want = cmp.expected[:, rates].std(axis=0)
    ratio = got / (want + GYRO_NOISE_ALLOWANCE)
    j = int(np.argmax(ratio))
    if ratio[j] > GYRO_SCALE_MAX:
        raise RunFormatError(
            f"{where}: {CHANNELS[rates[j]]} moves {got[j] / want[j]:.3g} times as much "
            "as the commands turn the cabin (rms): not rad/s (deg/s reads 57 times); give the "
            f"gyros in rad/s ({IMPORT_HINT})"
        )


def allowed_lags(config: MotionSystem) -> tuple[float, float]:
    """Lags of the IMU behind the nominal twin a platform can have [s]: none to the most."""
    nominal = float(np.max(config.delays_s))
    return -nominal - LAG_TOLERANCE_S, MAX_EXTRA_DELAY_S + LAG_TOLERANCE_S


def check_timing(cmp: Comparison | None, config: MotionSystem, where: str) -> None:
    """Refuse an IMU that does not follow its commands within a platform's lags.

    The band-limited IMU is cross-correlated with the nominal twin's reading of the commands
    over :data:`twin.formats.run_expected.SEARCH_S` of lags, on the channels the commands drive.
    Refused: a channel anti-correlated (:data:`FLIPPED`) at every allowed lag (a sign error);
    a peak outside :func:`allowed_lags` clearly above every allowed lag's (a clock offset);
    no correlation at any lag where the commanded motion should dominate (another run's
    IMU). Where the IMU's noise would drown the commanded motion nothing is refused.
    """
    if cmp is None:
        return
    channels = _informative(cmp)
    if not channels:
        return
    corr = cmp.correlation(channels)
    lo, hi = allowed_lags(config)
    allowed = (corr.lags_s >= lo) & (corr.lags_s <= hi)
    total = corr.total()
    if not np.isfinite(total[allowed]).any():
        return
    each = corr.per_channel()[allowed]
    for j, c in enumerate(channels):
        if np.nanmin(each[:, j]) < -FLIPPED and np.nanmax(each[:, j]) < FLIPPED / 2:
            raise RunFormatError(
                f"{where}: {CHANNELS[c]} moves against the commands (correlation "
                f"{np.nanmin(each[:, j]):+.2f} with the nominal twin's): logged with the wrong "
                f"sign; the twin's cabin axes are x forward, y right, z down ({IMPORT_HINT})"
            )
    inside = float(np.nanmax(total[allowed]))
    outside_all = np.where(allowed, np.nan, total)
    if np.isfinite(outside_all).any():
        k = int(np.nanargmax(outside_all))
        outside = float(outside_all[k])
        n = 2 * BAND_HZ * float(corr.covered_s[k])
        margin = OFFSET_MARGIN + 3 * np.sqrt(2 * max(1 - outside**2, 0.0) / n)
        if outside >= MIN_CORRELATION and outside > inside + margin:
            lag = float(corr.lags_s[k])
            raise RunFormatError(
                f"{where}: the IMU follows the commands {abs(lag):.2f} s "
                f"{'late' if lag > 0 else 'early'} (correlation {outside:.2f}; {inside:.2f} at "
                f"most within the {1e3 * lo:+.0f} to {1e3 * hi:+.0f} ms a platform responds "
                "in, beyond the nominal twin's delay): the IMU's clock is off the commands'; "
                f"shift imu.csv's t by {-lag:+.2f} s, or use twin import (--clock-offset)"
            )
    zero = len(corr.lags_s) // 2  # the expected's rms over the recorded's, at lag zero
    share = float(np.sqrt(corr.expected_power[zero].sum() / corr.measured_power[zero].sum()))
    best = float(np.nanmax(total))
    if share >= MIN_EXPLAINED and best < FOLLOW_SHARE * min(share, 1.0):
        raise RunFormatError(
            f"{where}: the IMU does not follow the commands (correlation {best:.2f} at best "
            f"within +-{corr.lags_s[-1]:g} s, where the commanded motion alone would give about "
            f"{min(share, 1.0):.2f}): an imu.csv of another run, or the commands of another; "
            "give the files of one run"
        )


def check_plausible(run: RecordedRun, where: str | None = None) -> None:
    """Check that a run's data are a motion system's (every check of the module docstring).

    Parameters
    ----------
    run : RecordedRun
        The run (its IMU at a supported rate: :func:`supported_rate`).
    where : str, optional
        What the messages name (default the run's ``imu.csv``).

    Raises
    ------
    RunFormatError
        The first check that fails, in one line naming what is implausible and the fix.

    """
    where = where or f"{run.path}/imu.csv"
    config = MotionSystem.from_meta(run.meta["platform"], run.meta["platform_config"])
    cmp = compare(run, config)
    check_constant(run, cmp, where)
    check_gyro_offset(run, where)
    check_gravity(run, cmp, where, config.imu_rotation)
    check_gyro_scale(cmp, where)
    check_timing(cmp, config, where)


def read_plausible_run(folder: str | Path | RecordedRun) -> RecordedRun:
    """Read a ``twin-run/1`` folder (:func:`twin.formats.runs.read_run`) and check it is plausible.

    The reader every analysis uses: the format first, then the physics (:func:`plausible_run`).
    A run already read is checked as it is.
    """
    return plausible_run(read_run(folder))


def plausible_run(run: RecordedRun) -> RecordedRun:
    """Return a run read from a folder at a supported IMU rate, once it passes every check.

    The IMU may come back resampled (:func:`supported_rate`, with a note in ``notes``). A run
    that passed once (``run.plausible``) is returned as it is: an analysis handed runs its
    caller checked does not check them again.

    Raises
    ------
    RunFormatError
        An IMU too slow, or the first check of :func:`check_plausible` that fails.

    """
    if run.plausible:
        return run
    run = supported_rate(run)
    check_plausible(run)
    return dataclasses.replace(run, plausible=True)


def fingerprint(run: RecordedRun) -> str:
    """Return a digest of a run's commands and IMU (equal for identical content)."""
    h = hashlib.sha256()
    for a in (run.commands.values, run.imu_t, run.imu):
        h.update(np.ascontiguousarray(a).tobytes())
    return h.hexdigest()


def check_distinct(runs: Sequence[RecordedRun]) -> None:
    """Refuse a run given twice: the same folder, or another folder with the same data.

    A run counted twice halves its noise in the statistics: limits shrink, findings firm up,
    with nothing measured twice.
    """
    seen: dict[object, RecordedRun] = {}
    for run in runs:
        for key in (("path", run.path.resolve()), ("data", fingerprint(run))):
            if key in seen:
                first = seen[key]
                same = "the same folder" if key[0] == "path" else "the same commands and IMU"
                raise RunFormatError(
                    f"{run.path}: given twice ({same} as {first.path}); give each run once (a "
                    "run counted twice makes the diagnosis claim more than was measured)"
                )
            seen[key] = run
