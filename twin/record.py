"""Rerun recordings of a run: the only module that imports rerun.

One blueprint: a 3D view of base, legs and cabin moving (z up, MuJoCo's world), next to time
series of commanded vs actual pose, leg lengths and the IMU channels. Save headless to an
``.rrd`` file or stream live to a running viewer. Data are sent as whole columns per chunk
(:func:`rerun.send_columns`), so recording a long run costs no per-sample Python work.

Entity paths
------------
``world/base`` (static outline), ``world/legs`` and ``world/cabin`` (per 3D frame),
``pose/command/<dof>``, ``pose/actual/<dof>`` (m, deg), ``legs/l1`` ... ``legs/l6`` (m),
``imu/ax``, ``imu/ay``, ``imu/az`` (m/s^2), ``imu/p``, ``imu/q``, ``imu/r`` (deg/s).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import rerun as rr
import rerun.blueprint as rrb
from numpy.typing import NDArray

from twin.chain.imu import ImuRecord
from twin.chain.response import PlatformResponse
from twin.frames import DOF_NAMES, MJ_FROM_THESIS, rotation_matrix
from twin.platform.geometry import Geometry

FloatArray = NDArray[np.float64]
TIMELINE = "sim_time"
IMU_CHANNELS = ("ax", "ay", "az", "p", "q", "r")


def blueprint() -> rrb.Blueprint:
    """Return the one layout used for every run."""
    return rrb.Blueprint(
        rrb.Horizontal(
            rrb.Spatial3DView(origin="/world", name="platform"),
            rrb.Vertical(
                rrb.TimeSeriesView(origin="/pose", name="pose: command vs actual"),
                rrb.TimeSeriesView(origin="/legs", name="leg lengths"),
                rrb.TimeSeriesView(origin="/imu", name="IMU"),
            ),
            column_shares=[1, 1],
        ),
        collapse_panels=True,
    )


def _z_up(points: FloatArray) -> FloatArray:
    """Thesis base-frame points (z down) to MuJoCo world (z up)."""
    return points @ MJ_FROM_THESIS.T


def _every(t: FloatArray, rate_hz: float, start: float, dt: float) -> NDArray[np.intp]:
    """Return the indices of samples (``dt`` apart) nearest a ``rate_hz`` grid from ``start``."""
    phase = (t - start) * rate_hz
    return np.flatnonzero(np.abs(phase - np.round(phase)) < 0.5 * rate_hz * dt + 1e-9)


class Recorder:
    """Stream a run to Rerun, chunk by chunk.

    Parameters
    ----------
    geometry : Geometry
        The platform (for the 3D view).
    name : str
        Recording name shown in the viewer.
    rrd : str or Path, optional
        Save to this file (headless).
    connect : str, optional
        gRPC URL of a running viewer to stream to instead (``""`` for Rerun's default).
    series_rate_hz, frames_rate_hz : float
        Rates at which pose/leg series and 3D frames are logged (IMU: every sample).

    """

    def __init__(
        self,
        geometry: Geometry,
        name: str,
        rrd: str | Path | None = None,
        connect: str | None = None,
        series_rate_hz: float = 100.0,
        frames_rate_hz: float = 30.0,
    ) -> None:
        self.geo = geometry
        self.series_rate_hz, self.frames_rate_hz = series_rate_hz, frames_rate_hz
        self.rec = rr.RecordingStream(application_id="twin", recording_id=None)
        self.rec.send_recording_name(name)
        self._final: Path | None = None
        if rrd is not None:  # written under a temporary name, renamed by close()
            self._final = Path(rrd)
            self._final.parent.mkdir(parents=True, exist_ok=True)
            self._partial = self._final.with_name(f".{self._final.name}.partial")
            self.rec.save(str(self._partial), default_blueprint=blueprint())
        elif connect is not None:
            self.rec.connect_grpc(connect or None, default_blueprint=blueprint())
        else:
            raise ValueError("Recorder needs a file (rrd) or a viewer URL (connect)")
        self._t0: float | None = None
        self._dt = 1e-3  # sample interval of the responses, from the first chunk
        base = _z_up(np.vstack([geometry.base_gimbals, geometry.base_gimbals[:1]]))
        self.rec.log("world/base", rr.LineStrips3D([base], colors=[[120, 120, 120]]), static=True)

    def log(
        self, response: PlatformResponse, imu: ImuRecord | None = None, offset_s: float = 0.0
    ) -> None:
        """Log one chunk of a run, its times shifted by ``offset_s`` [s]."""
        if offset_s:
            response = dataclasses.replace(response, t=response.t + offset_s)
            if imu is not None:
                imu = dataclasses.replace(imu, t=imu.t + offset_s)
        t = response.t
        if self._t0 is None:
            self._t0 = float(t[0])
        if t.size > 1:
            self._dt = float(t[1] - t[0])
        self._series(response, _every(t, self.series_rate_hz, self._t0, self._dt))
        self._frames(response, _every(t, self.frames_rate_hz, self._t0, self._dt))
        if imu is not None and len(imu.t):
            values = np.hstack([imu.accel, np.degrees(imu.gyro)])
            times = rr.TimeColumn(TIMELINE, duration=imu.t)
            for k, ch in enumerate(IMU_CHANNELS):
                self.rec.send_columns(f"imu/{ch}", indexes=[times],
                                      columns=rr.Scalars.columns(scalars=values[:, k]))  # fmt: skip

    def _series(self, r: PlatformResponse, idx: NDArray[np.intp]) -> None:
        times = rr.TimeColumn(TIMELINE, duration=r.t[idx])
        scale = np.array([1, 1, 1, *(3 * [180 / np.pi])])
        for kind, values in (("command", r.command[idx]), ("actual", r.pose[idx])):
            for k, dof in enumerate(DOF_NAMES):
                column = rr.Scalars.columns(scalars=values[:, k] * scale[k])
                self.rec.send_columns(f"pose/{kind}/{dof}", indexes=[times], columns=column)
        for j in range(6):
            self.rec.send_columns(f"legs/l{j + 1}", indexes=[times],
                                  columns=rr.Scalars.columns(scalars=r.legs[idx, j]))  # fmt: skip

    def _frames(self, r: PlatformResponse, idx: NDArray[np.intp]) -> None:
        if idx.size == 0:
            return
        pose = r.pose[idx]
        T = rotation_matrix(pose[:, 3:])
        ugp = self.geo.neutral_ugp + pose[:, :3]
        top = ugp[:, None, :] + np.einsum("nij,kj->nki", T, self.geo.cabin_gimbals)
        top_w = _z_up(top)
        base_w = _z_up(self.geo.base_gimbals)
        legs = np.stack([np.broadcast_to(base_w, top_w.shape), top_w], axis=2)  # (n, 6, 2, 3)
        times = rr.TimeColumn(TIMELINE, duration=r.t[idx])
        strips = rr.LineStrips3D.columns(strips=legs.reshape(-1, 2, 3))
        self.rec.send_columns("world/legs", indexes=[times],
                              columns=strips.partition([6] * len(idx)))  # fmt: skip
        cabin = np.concatenate([top_w, top_w[:, :1]], axis=1)  # closed outline (n, 7, 3)
        self.rec.send_columns(
            "world/cabin", indexes=[times],
            columns=rr.LineStrips3D.columns(strips=cabin).partition([1] * len(idx)),
        )  # fmt: skip

    def close(self) -> None:
        """Flush and close the recording (the ``.rrd`` appears under its name only now)."""
        self.rec.flush()
        self.rec.disconnect()
        if self._final is not None:
            self._partial.replace(self._final)

    def abort(self) -> None:
        """Close and delete a partly written ``.rrd``."""
        self.rec.disconnect()
        if self._final is not None:
            self._partial.unlink(missing_ok=True)


def read_entities(path: str | Path) -> dict[str, int]:
    """Return {entity path: number of logged rows} of an ``.rrd`` file (for checks and tests)."""
    from rerun.chunk import RrdReader

    counts: dict[str, int] = {}
    for chunk in RrdReader(str(path)).stream():
        counts[chunk.entity_path] = counts.get(chunk.entity_path, 0) + chunk.num_rows
    return counts


def record_series(
    path: str | Path, name: str, t: FloatArray, series: dict[str, FloatArray]
) -> Path:
    """Save scalar time series (entity path -> samples at ``t``) to an ``.rrd`` file.

    Written to a partial name and renamed; used for pilot-in-the-loop runs (e, u, theta, the
    forcing functions and the felt motion), each its own time series under one timeline.
    """
    final = Path(path)
    final.parent.mkdir(parents=True, exist_ok=True)
    partial = final.with_name(f".{final.name}.partial")
    rec = rr.RecordingStream(application_id="twin", recording_id=None)
    rec.send_recording_name(name)
    rec.save(str(partial), default_blueprint=rrb.Blueprint(rrb.TimeSeriesView(origin="/")))
    times = rr.TimeColumn(TIMELINE, duration=np.asarray(t, dtype=float))
    try:
        for entity, values in series.items():
            rec.send_columns(
                entity,
                indexes=[times],
                columns=rr.Scalars.columns(scalars=np.asarray(values, float)),
            )
        rec.flush()
    except BaseException:
        rec.disconnect()
        partial.unlink(missing_ok=True)
        raise
    rec.disconnect()
    partial.replace(final)
    return final
