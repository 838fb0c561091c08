"""Rerun recordings of platform runs (``twin simulate``, ``twin agard``).

The platform in 3D as its MJCF draws it (:mod:`twin.platform.visual`): the base and the cabin
as bodies (boxes and cylinders from their visual geoms) placed by ``Transform3D``s, the legs
as lines between the gimbals, the IMU's axes as arrows on the cabin, the commanded pose as a
translucent ghost of the cabin; beside it the pose as time series with names, colours and
units (translations in m and rotations in deg in separate views), the leg lengths and the IMU
(decimated to ``imu_rate_hz`` by block means for display; ``imu_rate_hz=None`` logs every
sample). Save headless to an ``.rrd`` file or stream live to a running viewer. Data are sent as
whole columns per chunk (:func:`rerun.send_columns`), so recording a long run costs no
per-sample Python work.

Entity paths
------------
``world/base`` (static transform: MuJoCo's z-up world from the thesis' z-down base frame),
``world/base/<geom>`` (static shapes), ``world/base/legs`` (per 3D frame, thesis base frame);
``world/cabin`` (``Transform3D`` per frame) with ``world/cabin/<geom>`` and ``world/cabin/imu``
(static, cabin frame); ``world/command`` (``Transform3D`` per frame) with its translucent
shapes; ``translation/<dof>/command|actual`` [m], ``rotation/<dof>/command|actual`` [deg],
``legs/l1`` ... ``legs/l6`` [m] with the stroke's ends ``legs/shortest`` and ``legs/longest``,
``leg_forces/f1`` ... ``leg_forces/f6`` [N] (full model), ``imu/accel/x|y|z`` [m/s^2],
``imu/gyro/p|q|r`` [deg/s]; an AGARD session adds each
describing function under ``df/<dof>`` (:meth:`Recorder.log_describing_function`).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import rerun as rr
import rerun.blueprint as rrb
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from twin.chain.imu import ImuRecord
from twin.chain.response import PlatformResponse
from twin.core.frames import DOF_NAMES, MJ_FROM_THESIS, dof_index, rotation_matrix
from twin.measurement.describing_function import dense_frequencies
from twin.measurement.measure import Bench
from twin.platform.facts import PLATFORMS
from twin.platform.geometry import Geometry, load_geometry
from twin.platform.kinematics import leg_vectors
from twin.platform.visual import Shape, imu_site, platform_shapes
from twin.viz.record.spectra import Curve, bode_curve, log_curves, log_figure, response_views
from twin.viz.record.stream import TIMELINE, Recording

FloatArray = NDArray[np.float64]
IMU_ACCEL, IMU_GYRO = ("x", "y", "z"), ("p", "q", "r")
#: Per-DOF colours (surge, sway, heave, roll, pitch, yaw); the command is drawn lighter.
DOF_COLOURS = ((31, 119, 180), (255, 127, 14), (44, 160, 44),
               (214, 39, 40), (148, 103, 189), (140, 86, 75))  # fmt: skip
AXIS_COLOURS = ((220, 40, 40), (40, 180, 40), (40, 80, 220))
#: Opacity of the commanded pose's ghost.
GHOST_ALPHA = 0.25


def blueprint(kind: str = "simulate", df_dofs: tuple[str, ...] = ()) -> rrb.Blueprint:
    """Return the layout of a platform run's recording (``simulate`` or ``agard``).

    The platform and its series in one tab; with ``df_dofs``, one more tab per describing
    function logged (figure, gain and phase against frequency).
    """
    series = [
        rrb.TimeSeriesView(origin="/translation", name="translation [m]: command vs actual"),
        rrb.TimeSeriesView(origin="/rotation", name="rotation [deg]: command vs actual"),
        rrb.TimeSeriesView(origin="/legs", name="leg lengths [m]"),
        rrb.TimeSeriesView(origin="/leg_forces", name="leg forces [N] (full model)"),
        rrb.TimeSeriesView(origin="/imu/accel", name="IMU specific force [m/s^2]"),
        rrb.TimeSeriesView(origin="/imu/gyro", name="IMU angular rate [deg/s]"),
    ]
    platform = rrb.Horizontal(
        rrb.Spatial3DView(origin="/world", name=f"platform ({kind})"),
        rrb.Vertical(*series),
        column_shares=[1, 1],
        name=f"platform ({kind})",
    )
    if not df_dofs:
        return rrb.Blueprint(platform, collapse_panels=True)
    tabs = [response_views(f"/df/{dof}", f"describing function, {dof}") for dof in df_dofs]
    return rrb.Blueprint(rrb.Tabs(platform, *tabs), collapse_panels=True)


def _every(t: FloatArray, rate_hz: float, start: float, dt: float) -> NDArray[np.intp]:
    """Return the indices of samples (``dt`` apart) nearest a ``rate_hz`` grid from ``start``."""
    phase = (t - start) * rate_hz
    return np.flatnonzero(np.abs(phase - np.round(phase)) < 0.5 * rate_hz * dt + 1e-9)


def _rgba(colour: tuple[float, ...], alpha: float | None = None) -> list[int]:
    rgba = [round(255 * c) for c in colour]
    if alpha is not None:
        rgba[3] = round(255 * alpha)
    return rgba


def _shape_archetype(shape: Shape, alpha: float | None = None):
    """Return the rerun archetype drawing one MJCF geom in its body frame."""
    style = {"quaternions": [shape.quat_xyzw], "colors": [_rgba(shape.rgba, alpha)],
             "fill_mode": "solid"}  # fmt: skip
    if shape.kind == "box":
        return rr.Boxes3D(half_sizes=[shape.size], centers=[shape.pos], **style)
    radius, half = shape.size
    if shape.kind == "cylinder":
        return rr.Cylinders3D(lengths=[2 * half], radii=[radius], centers=[shape.pos], **style)
    # a capsule starts at its translation and runs along its z: move the start to one end
    start = np.asarray(shape.pos) - Rotation.from_quat(shape.quat_xyzw).apply([0, 0, half])
    return rr.Capsules3D(lengths=[2 * half], radii=[radius], translations=[start], **style)


class Recorder:
    """Stream a run to Rerun, chunk by chunk.

    Parameters
    ----------
    geometry : Geometry
        The platform (its name, ``mpi`` or ``srs``, selects the MJCF drawn; another
        geometry is drawn as gimbal outlines).
    name : str
        Recording name shown in the viewer.
    rrd : str or Path, optional
        Save to this file (headless).
    connect : str, optional
        gRPC URL of a running viewer to stream to instead (``""`` for Rerun's default).
    series_rate_hz, frames_rate_hz : float
        Rates at which pose/leg series and 3D frames are logged.
    imu_rate_hz : float or None
        IMU display rate: block means of round(IMU rate / ``imu_rate_hz``) raw samples (8 at
        819.2 Hz: 102.4 Hz shown); None logs every raw sample.
    kind : str
        Recording kind shown in the layout (``simulate``, ``agard``).
    imu_position_m : tuple of float, optional
        The IMU's mount in the cabin frame [m] (its axes are drawn there); the model's ``imu``
        site otherwise.

    """

    def __init__(
        self,
        geometry: Geometry,
        name: str,
        rrd: str | Path | None = None,
        connect: str | None = None,
        series_rate_hz: float = 100.0,
        frames_rate_hz: float = 30.0,
        imu_rate_hz: float | None = 100.0,
        kind: str = "simulate",
        imu_position_m: tuple[float, float, float] | None = None,
    ) -> None:
        if imu_rate_hz is not None and not imu_rate_hz > 0:
            raise ValueError(f"imu_rate_hz must be > 0 or None (raw); got {imu_rate_hz}")
        self.geo = geometry
        self.series_rate_hz, self.frames_rate_hz = series_rate_hz, frames_rate_hz
        self.imu_rate_hz = imu_rate_hz
        self.kind = kind
        self.recording = Recording(name, blueprint(kind), rrd, connect)
        self.rec = self.recording.rec
        self.df_dofs: list[str] = []
        self._t0: float | None = None
        self._dt = 1e-3  # sample interval of the responses, from the first chunk
        self._imu_held: tuple[FloatArray, FloatArray] | None = None  # samples of a part block
        self._static_scene(imu_position_m)

    def _static_scene(self, imu_position_m: tuple[float, float, float] | None) -> None:
        log = self.rec.log
        log("world/base", rr.Transform3D(mat3x3=MJ_FROM_THESIS), static=True)
        shapes = platform_shapes(self.geo.name) if self.geo.name in PLATFORMS else ()
        for shape in shapes:
            log(f"world/{shape.body}/{shape.name}", _shape_archetype(shape), static=True)
            if shape.body == "cabin":
                log(f"world/command/{shape.name}", _shape_archetype(shape, GHOST_ALPHA),
                    static=True)  # fmt: skip
        if not shapes:  # a geometry without an MJCF: gimbal outlines
            base = np.vstack([self.geo.base_gimbals, self.geo.base_gimbals[:1]])
            cabin = np.vstack([self.geo.cabin_gimbals, self.geo.cabin_gimbals[:1]])
            log("world/base/outline", rr.LineStrips3D([base], colors=[[120, 120, 120]]),
                static=True)  # fmt: skip
            log("world/cabin/outline", rr.LineStrips3D([cabin], colors=[[90, 90, 200]]),
                static=True)  # fmt: skip
        if imu_position_m is not None:
            imu = np.asarray(imu_position_m, dtype=float)
        else:
            imu = imu_site(self.geo.name) if shapes else np.zeros(3)
        length = 0.2 * self.geo.neutral_height
        log("world/cabin/imu", rr.Arrows3D(origins=[imu] * 3, vectors=length * np.eye(3),
                                           colors=AXIS_COLOURS, labels=["x", "y", "z"]),
            static=True)  # fmt: skip
        for k, dof in enumerate(DOF_NAMES):
            group, unit = ("translation", "m") if k < 3 else ("rotation", "deg")
            colour = np.array(DOF_COLOURS[k])
            for what, c in (("actual", colour), ("command", 0.45 * colour + 0.55 * 255)):
                log(f"{group}/{dof}/{what}", rr.SeriesLines(
                    colors=[c.astype(int)], names=[f"{dof} {what} [{unit}]"],
                    widths=[2.0 if what == "actual" else 1.0]), static=True)  # fmt: skip
        for j in range(6):
            style = rr.SeriesLines(colors=[DOF_COLOURS[j]], names=[f"leg {j + 1} [m]"])
            log(f"legs/l{j + 1}", style, static=True)
            log(f"leg_forces/f{j + 1}", rr.SeriesLines(colors=[DOF_COLOURS[j]],
                                                       names=[f"leg {j + 1} force [N]"]),
                static=True)  # fmt: skip
        for end in ("shortest", "longest"):
            log(f"legs/{end}", rr.SeriesLines(colors=[[0, 0, 0]], names=[f"{end} leg [m]"],
                                              widths=[0.75]), static=True)  # fmt: skip
        for group, channels, unit in (("accel", IMU_ACCEL, "m/s^2"), ("gyro", IMU_GYRO, "deg/s")):
            for ch, c in zip(channels, AXIS_COLOURS, strict=True):
                log(f"imu/{group}/{ch}", rr.SeriesLines(colors=[c], names=[f"{ch} [{unit}]"]),
                    static=True)  # fmt: skip

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
            self._imu(imu)

    def _imu(self, imu: ImuRecord) -> None:
        t = np.asarray(imu.t, dtype=float)
        values = np.hstack([imu.accel, np.degrees(imu.gyro)])
        if self.imu_rate_hz is not None:
            held = self._imu_held
            if held is not None and held[0].size:
                if t[0] - held[0][-1] > 1.5 / imu.rate_hz:  # a new run: no block spans the gap
                    self._send_imu(held[0].mean(keepdims=True), held[1].mean(axis=0)[None])
                else:
                    t = np.concatenate([held[0], t])
                    values = np.vstack([held[1], values])
            block = max(1, round(imu.rate_hz / self.imu_rate_hz))
            whole = t.size // block * block
            self._imu_held = (t[whole:], values[whole:])
            t = t[:whole].reshape(-1, block).mean(axis=1)
            values = values[:whole].reshape(-1, block, 6).mean(axis=1)
            if not t.size:
                return
        self._send_imu(t, values)

    def _send_imu(self, t: FloatArray, values: FloatArray) -> None:
        times = rr.TimeColumn(TIMELINE, duration=t)
        for k, path in enumerate([*(f"imu/accel/{c}" for c in IMU_ACCEL),
                                  *(f"imu/gyro/{c}" for c in IMU_GYRO)]):  # fmt: skip
            self.rec.send_columns(path, indexes=[times],
                                  columns=rr.Scalars.columns(scalars=values[:, k]))  # fmt: skip

    def _series(self, r: PlatformResponse, idx: NDArray[np.intp]) -> None:
        times = rr.TimeColumn(TIMELINE, duration=r.t[idx])
        scale = np.array([1, 1, 1, *(3 * [180 / np.pi])])
        for kind, values in (("command", r.command[idx]), ("actual", r.pose[idx])):
            for k, dof in enumerate(DOF_NAMES):
                group = "translation" if k < 3 else "rotation"
                column = rr.Scalars.columns(scalars=values[:, k] * scale[k])
                self.rec.send_columns(f"{group}/{dof}/{kind}", indexes=[times], columns=column)
        for j in range(6):
            self.rec.send_columns(f"legs/l{j + 1}", indexes=[times],
                                  columns=rr.Scalars.columns(scalars=r.legs[idx, j]))  # fmt: skip
            if r.leg_force is not None:
                force = rr.Scalars.columns(scalars=r.leg_force[idx, j])
                self.rec.send_columns(f"leg_forces/f{j + 1}", indexes=[times], columns=force)
        if idx.size:  # the stroke's ends, at the chunk's first and last logged sample
            ends = rr.TimeColumn(TIMELINE, duration=r.t[idx[[0, -1]]])
            for end, value in (("shortest", self.geo.leg_min.max()),
                               ("longest", self.geo.leg_max.min())):  # fmt: skip
                column = rr.Scalars.columns(scalars=[value, value])
                self.rec.send_columns(f"legs/{end}", indexes=[ends], columns=column)

    def _frames(self, r: PlatformResponse, idx: NDArray[np.intp]) -> None:
        if idx.size == 0:
            return
        times = rr.TimeColumn(TIMELINE, duration=r.t[idx])
        for path, pose in (("world/cabin", r.pose[idx]), ("world/command", r.command[idx])):
            rot = MJ_FROM_THESIS @ rotation_matrix(pose[:, 3:])
            where = (self.geo.neutral_ugp + pose[:, :3]) @ MJ_FROM_THESIS.T
            self.rec.send_columns(path, indexes=[times], columns=rr.Transform3D.columns(
                translation=where, quaternion=Rotation.from_matrix(rot).as_quat()))  # fmt: skip
        top = self.geo.base_gimbals + leg_vectors(self.geo, r.pose[idx])  # Eq A.5
        base = np.broadcast_to(self.geo.base_gimbals, top.shape)
        legs = np.stack([base, top], axis=2)  # (n, 6, 2, 3), thesis base frame
        strips = rr.LineStrips3D.columns(strips=legs.reshape(-1, 2, 3))
        self.rec.send_columns("world/base/legs", indexes=[times],
                              columns=strips.partition([6] * len(idx)))  # fmt: skip

    def log_describing_function(self, result, config=None) -> None:
        """Log a describing function (a :class:`twin.agard.df.DfResult`) under ``df/<dof>``.

        The measured points with their 95 % bounds, the configuration's reduced model (Eq 5.11
        and any extension; ``config``, the result's own analytic model otherwise) as a line,
        and the paper figure of both (:func:`twin.agard.df.DfResult.plot`).
        """
        dof, f = result.dof, result.frequencies_hz
        low, high, dphase = result.bounds_95()
        curves = [Curve("measured", f, 20 * np.log10(result.gain), result.phase_deg,
                        DOF_COLOURS[dof_index(dof)], (low, high, dphase))]  # fmt: skip
        if config is not None:
            fa = dense_frequencies(f)
            h = config.transfer_function(dof).response_at_hz(fa)  # python-control
            name = "eq_5_11" if not config.extensions else "model_with_extensions"
            curves.append(bode_curve(name, fa, h, (60, 60, 60)))
        else:
            curves.append(bode_curve("eq_5_11", f, result.analytic(), (60, 60, 60)))
        log_curves(self.rec, f"df/{dof}", curves)
        log_figure(self.rec, f"df/{dof}/figure", lambda: result.plot(config=config))
        if dof not in self.df_dofs:
            self.df_dofs.append(dof)

    def close(self) -> None:
        """Flush and close the recording (the ``.rrd`` appears under its name only now)."""
        held = self._imu_held
        if held is not None and held[0].size:  # the last, partial block
            self._send_imu(held[0].mean(keepdims=True), held[1].mean(axis=0)[None])
        if self.df_dofs:  # the layout with a tab per describing function
            self.rec.send_blueprint(blueprint(self.kind, tuple(self.df_dofs)))
        self.recording.close()

    def abort(self) -> None:
        """Close and delete a partly written ``.rrd``."""
        self.recording.abort()


def bench_recorder(bench: Bench, rrd: str | Path) -> Recorder:
    """Return the recording of an AGARD session on ``bench``, saved to ``rrd``.

    The bench's platform in 3D with its IMU's mount, every run one after the other and the
    describing functions found (:class:`twin.agard.session.Session` takes it).
    """
    imu = bench.imu.position_m if bench.imu is not None else None
    return Recorder(
        load_geometry(bench.config.platform), bench.name, rrd=rrd, kind="agard", imu_position_m=imu
    )
