"""The evidence of a physical diagnosis: every channel a run has, at the driven DOF's lines.

A fault in one leg, a heavier cabin or a rotated IMU shows beyond the driven DOF's own
channel: as parasitic motion in the five undriven DOFs (§3.3.1) and, where a run logs them,
in the legs' lengths (``actuators.csv``) and forces (``forces.csv``). For every run and every
driven DOF this module holds, at that DOF's excited lines and over its measurement window
(and over each half, for the held-out check), the measured complex amplitudes of each
channel of each *source*:

==========  ==================================================================  =========
source      channels                                                            unit
==========  ==================================================================  =========
``imu``     the six DOF accelerations of the post-processed IMU (App. C.2.3)    SI
``legs``    the six leg lengths (``actuators.csv``)                             m
``forces``  the six leg forces (``forces.csv``)                                 N
==========  ==================================================================  =========

with each amplitude's standard deviation from the measured residual (measured - nominal) at
the non-excited bins beside the line, as :mod:`twin.diagnose.evidence` does for the driven
channel (AGARD-AR-144's noise estimate). A source that a simulation logs without noise (leg
lengths, forces) gets a floor on that deviation, a logger's resolution (:data:`FLOOR`,
an assumption): without one a noise-free log would weigh any model error as infinitely sure.

A prediction (a simulated run of a candidate physics) is turned into the same amplitudes and
standardised residuals, so every candidate is scored on the same evidence.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from twin.chain.config import MotionSystem
from twin.chain.imu import ImuRecord, ImuSpec
from twin.chain.simulate import prepare
from twin.chain.trajectory import interp_columns
from twin.core.frames import DOF_NAMES
from twin.diagnose.data import driven_dofs
from twin.diagnose.evidence import in_window, line_design, neighbour_sd
from twin.formats.runs import RecordedRun
from twin.measurement.measure import Measurement, clean_config, from_imu
from twin.measurement.periodic import periodic_design

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]
#: The sources of evidence, in order.
SOURCES = ("imu", "legs", "forces")
#: Smallest standard deviation of a line amplitude per source: a 1 um leg-length and a 1 N
#: force resolution (assumptions, of a logger of ordinary resolution); the IMU's, far below
#: any IMU's noise, only keeps a noise-free recording finite.
FLOOR = {"imu": 1e-6, "legs": 1e-6, "forces": 1.0}


@dataclass(frozen=True, eq=False)
class Simulated:
    """What one simulation of a run gives, on the run's analysis grid.

    Attributes
    ----------
    series : dict of str to ndarray, shape (n, 6)
        Per source (:data:`SOURCES`): the IMU's six DOF accelerations, the leg lengths and
        the leg forces.
    imu : ImuRecord
        The (ideal) IMU's samples (an IMU rotation is applied to them without simulating).

    """

    series: dict[str, FloatArray]
    imu: ImuRecord


def simulate_run(config: MotionSystem, m: Measurement, imu: ImuSpec, seed: int) -> Simulated:
    """Simulate a measurement's commands through ``config`` on the full model (ideal IMU).

    Parameters
    ----------
    config : MotionSystem
        The configuration (its noise is left out: the prediction is noise-free).
    m : Measurement
        The measured run (its commands and analysis grid).
    imu : ImuSpec
        The nominal IMU (mount and rate); read without noise.
    seed : int
        Seed (nothing random remains; kept for the chain's bookkeeping).

    """
    sim = prepare(clean_config(config), m.commands, "full", seed, imu.ideal()).collect()
    return Simulated(_series(sim.imu, sim.commands, config, m, sim.response), sim.imu)


def reread(sim: Simulated, record: ImuRecord, config: MotionSystem, m: Measurement) -> Simulated:
    """Return ``sim`` with its IMU source read from another record of the same motion."""
    series = dict(sim.series)
    series["imu"] = _imu_series(record, config, m)
    return Simulated(series, record)


def _imu_series(record: ImuRecord, config: MotionSystem, m: Measurement) -> FloatArray:
    """Post-process IMU samples onto the measurement's grid (six DOF accelerations)."""
    p = from_imu(m.commands, record, config.name, config, {})
    same = p.t.shape == m.t.shape and np.allclose(p.t, m.t, atol=1e-9)
    return p.measured if same else interp_columns(m.t, p.t, p.measured)


def _series(record, commands, config, m, response) -> dict[str, FloatArray]:
    """Return the sources of one simulation on the measurement's grid."""
    out = {"imu": _imu_series(record, config, m),
           "legs": interp_columns(m.t, response.t, response.legs)}  # fmt: skip
    if response.leg_force is not None:
        out["forces"] = interp_columns(m.t, response.t, response.leg_force)
    return out


def measured_sources(rec: RecordedRun, m: Measurement) -> dict[str, FloatArray]:
    """Return a recorded run's sources on its analysis grid (the logs it has)."""
    out = {"imu": m.measured}
    for source, table in (("legs", rec.actuators), ("forces", rec.forces)):
        if table is not None and len(table) > 1:
            inside = (m.t >= table[0, 0] - 1e-9) & (m.t <= table[-1, 0] + 1e-9)
            if inside.mean() > 0.9:  # a log that covers the test
                out[source] = interp_columns(m.t, table[:, 0], table[:, 1:])
    return out


@dataclass(frozen=True, eq=False)
class Block:
    """The lines of one driven DOF of one run, over one window, in every channel.

    Attributes
    ----------
    run : int
        Index of the run in the case.
    driven : str
        The driven DOF whose lines these are.
    window : tuple of float
        The window [s].
    f : ndarray
        The lines [Hz].
    channels : list of tuple of (str, int)
        (source, channel index) of each column.
    measured : ndarray of complex, shape (lines, channels)
        Measured amplitudes.
    sd : ndarray, shape (lines, channels)
        Their standard deviations.

    """

    run: int
    driven: str
    window: tuple[float, float]
    f: FloatArray
    channels: list[tuple[str, int]]
    measured: ComplexArray
    sd: FloatArray
    _projector: FloatArray
    _sel: NDArray[np.bool_]

    def amplitudes(self, series: dict[str, FloatArray]) -> ComplexArray:
        """Return a simulation's amplitudes in this block's channels."""
        x = np.column_stack([series[s][self._sel, c] for s, c in self.channels])
        coef = self._projector @ x
        m = self.f.size
        return coef[:m] + 1j * coef[m : 2 * m]

    def residuals(self, series: dict[str, FloatArray]) -> FloatArray:
        """Standardised real residuals of a simulation (real and imaginary parts)."""
        r = (self.measured - self.amplitudes(series)) / self.sd
        return np.concatenate([r.real.ravel(), r.imag.ravel()])

    def source_of(self) -> NDArray[np.str_]:
        """Return, per residual of :meth:`residuals`, its channel's source label.

        ``imu`` channels are labelled ``driven`` (the driven DOF's own) or ``undriven``.
        """
        labels = [("driven" if DOF_NAMES[c] == self.driven else "undriven") if s == "imu"
                  else s for s, c in self.channels]  # fmt: skip
        one = np.tile(np.array(labels), (self.f.size, 1)).ravel()
        return np.concatenate([one, one])


def _projector(t: FloatArray, f: FloatArray, window: tuple[float, float]):
    """Return the least-squares projector onto the lines over a window, and its samples.

    The fit of :func:`twin.diagnose.evidence.line_amplitudes`, prepared once for many signals.
    """
    sel = in_window(t, window)
    return np.linalg.pinv(line_design(t[sel], f)), sel


def blocks(
    run: int,
    rec: RecordedRun,
    m: Measurement,
    nominal: Simulated,
    max_hz: float,
    dofs: Sequence[str] | None = None,
) -> dict[str, list[Block]]:
    """Return the evidence of one run: per window kind (``full``, ``half1``, ``half2``).

    Parameters
    ----------
    run : int
        The run's index.
    rec, m : RecordedRun, Measurement
        The run as read and as post-processed.
    nominal : Simulated
        The nominal model's simulation of it (for the residual the noise is measured on).
    max_hz : float
        Top of the band.
    dofs : sequence of str, optional
        The driven DOFs to use (all driven ones by default).

    """
    measured = measured_sources(rec, m)
    channels = [(s, c) for s in SOURCES if s in measured and s in nominal.series
                for c in range(6)]  # fmt: skip
    y = np.column_stack([measured[s][:, c] for s, c in channels])
    p = np.column_stack([nominal.series[s][:, c] for s, c in channels])
    floor = np.array([FLOOR[s] for s, _ in channels])
    out: dict[str, list[Block]] = {"full": [], "half1": [], "half2": []}
    for k in driven_dofs(m, dofs):
        f, window = periodic_design(m, k)
        f = np.asarray(f, dtype=float)
        keep = f <= max_hz
        f, window = f[keep], tuple(float(w) for w in window)
        sd_full = neighbour_sd(m.t, y - p, f, window)
        ok = np.isfinite(sd_full).all(axis=1)  # a line with no noise-only bin beside it
        f, sd_full = f[ok], np.sqrt(sd_full[ok] ** 2 + floor**2)
        if f.size == 0:
            continue
        mid = window[0] + 0.5 * (window[1] - window[0])
        for name, w in (("full", window), ("half1", (window[0], mid)), ("half2", (mid, window[1]))):
            proj, sel = _projector(m.t, f, w)
            part = np.sqrt((window[1] - window[0]) / (w[1] - w[0]))
            coef = proj @ y[sel]
            amp = coef[: f.size] + 1j * coef[f.size : 2 * f.size]
            out[name].append(Block(run, DOF_NAMES[k], w, f, channels, amp, sd_full * part,
                                   proj, sel))  # fmt: skip
    return out
