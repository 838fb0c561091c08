"""The platform's pose during a run: simulated, or from the leg lengths a run logged.

Tests that measure position (hysteresis, system limits) read the output pose here: a
simulation's response, or a recorded run's ``actuators.csv`` through the forward kinematics
(Appendix A): the IMU's accelerations cannot be integrated twice over minutes without
drifting.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from twin.chain.config import MotionSystem
from twin.chain.simulate import Simulation
from twin.core.errors import DataError
from twin.formats.run_checks import read_plausible_run
from twin.formats.runs import RecordedRun
from twin.measurement.measure import run_config
from twin.platform.geometry import load_geometry
from twin.platform.kinematics import forward

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class PositionRecord:
    """Commanded and measured poses of one run, on one time grid.

    Attributes
    ----------
    t : ndarray, shape (n,)
        Time [s], uniform.
    commanded, output : ndarray, shape (n, 6)
        Pose offsets from neutral (m, rad): the commands, and the platform's pose.
    config : MotionSystem
        The configuration (for its lag).
    source : str
        What was measured.

    """

    t: FloatArray
    commanded: FloatArray
    output: FloatArray
    config: MotionSystem
    source: str

    @classmethod
    def from_simulation(cls, sim: Simulation) -> PositionRecord:
        """Return the simulated pose of the response against the commands at its samples."""
        r = sim.response
        source = f"{sim.config.name} ({sim.model}) run seed {sim.seed}"
        return cls(r.t, sim.commands.at(r.t), r.pose, sim.config, source)

    @classmethod
    def from_run(cls, run: RecordedRun | str | Path) -> PositionRecord:
        """Return the pose from a recorded run's leg lengths (``actuators.csv``) by kinematics.

        Lengths a hair beyond the stroke (a servo at its end) are clipped to it first.

        Raises
        ------
        DataError
            For a run without ``actuators.csv``: it has no position record.

        """
        rec = run if isinstance(run, RecordedRun) else read_plausible_run(run)
        if rec.actuators is None:
            raise DataError(
                f"{rec.path}: the run lacks a position record (no actuators.csv with the leg "
                "lengths); the output position cannot come from the IMU's accelerations "
                "(integrated twice over minutes they drift)"
            )
        config = run_config(rec)
        t = rec.actuators[:, 0]
        commanded = rec.commands.at(t)
        geo = load_geometry(config.platform)
        lengths = np.clip(rec.actuators[:, 1:7], geo.leg_min, geo.leg_max)
        fk = forward(geo, lengths, initial=commanded)
        return cls(t, commanded, fk.pose, config, str(rec.path))

    def on(self, t: FloatArray) -> FloatArray:
        """Return the output pose (n, 6) at times ``t`` (linear between samples)."""
        return np.column_stack([np.interp(t, self.t, self.output[:, c]) for c in range(6)])
