"""Frequency responses in a recording: Bode data on a frequency axis, and the paper figure.

Rerun plots scalars against a timeline, so a frequency response is logged against its own
sequence timeline :data:`FREQUENCY_TIMELINE` (frequency in mHz): pick it in the time panel
and each view under ``.../gain`` and ``.../phase`` becomes gain [dB] and phase [deg] against
frequency, with hover values; measured points come with their 95 % bounds as two thin
series. The same response as the paper's Bode figure (log frequency, error bars, grids) is
logged as an image beside it, for a reviewer who wants to look rather than hover.
"""

from __future__ import annotations

import io
import threading
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import rerun as rr
import rerun.blueprint as rrb
from matplotlib.figure import Figure
from numpy.typing import NDArray

from twin.measurement.describing_function import phase_deg
from twin.viz.record.stream import send_series, series_style

FloatArray = NDArray[np.float64]
#: Sequence timeline of frequency responses (integer millihertz).
FREQUENCY_TIMELINE = "frequency_mHz"


@dataclass(frozen=True)
class Curve:
    """One frequency response to log.

    Attributes
    ----------
    name : str
        Entity name and legend (e.g. ``measured``, ``eq_5_11``).
    f_hz : ndarray
        Frequencies [Hz].
    gain_db, phase_deg : ndarray
        Gain [dB] and phase [deg] (already on the branch to show).
    colour : tuple of int
        RGB.
    bounds : tuple of ndarray, optional
        Half-widths of the 95 % interval: below and above the gain [dB], and either side of
        the phase [deg]. Curves with bounds are measured points (one per frequency; drawn as
        points with their bounds); curves without are model lines, thinned to one point per
        millihertz of the timeline.

    """

    name: str
    f_hz: FloatArray
    gain_db: FloatArray
    phase_deg: FloatArray
    colour: tuple[int, int, int]
    bounds: tuple[FloatArray, FloatArray, FloatArray] | None = None


def log_curves(rec: rr.RecordingStream, path: str, curves: list[Curve]) -> None:
    """Log ``curves`` under ``path/gain/<name>`` [dB] and ``path/phase/<name>`` [deg]."""
    for c in curves:
        f = np.asarray(c.f_hz, dtype=float)
        order = np.argsort(f, kind="stable")
        mhz = np.round(f[order] * 1e3).astype(np.int64)
        keep = np.concatenate([[True], np.diff(mhz) > 0])  # one value per millihertz
        if c.bounds is not None and not keep.all():
            raise ValueError(f"{path}/{c.name}: measured points share a frequency; log one "
                             "curve per run")  # fmt: skip
        times = rr.TimeColumn(FREQUENCY_TIMELINE, sequence=mhz[keep])
        sel = order[keep]
        points = c.bounds is not None
        for part, values, unit in (("gain", c.gain_db, "dB"), ("phase", c.phase_deg, "deg")):
            entity = f"{path}/{part}/{c.name}"
            series_style(rec, entity, f"{c.name} [{unit}]", c.colour, points=points)
            send_series(rec, entity, times, np.asarray(values, dtype=float)[sel])
        if c.bounds is not None:
            low, high, dphase = (np.asarray(b, dtype=float)[sel] for b in c.bounds)
            pale = tuple(int(0.5 * v + 127) for v in c.colour)
            edges = (("gain", "lo95", np.asarray(c.gain_db)[sel] - low, "dB"),
                     ("gain", "hi95", np.asarray(c.gain_db)[sel] + high, "dB"),
                     ("phase", "lo95", np.asarray(c.phase_deg)[sel] - dphase, "deg"),
                     ("phase", "hi95", np.asarray(c.phase_deg)[sel] + dphase, "deg"))  # fmt: skip
            for part, edge, values, unit in edges:
                entity = f"{path}/{part}/{c.name}_{edge}"
                series_style(rec, entity, f"{c.name} 95 % {edge[:2]} [{unit}]", pale, 0.75)
                send_series(rec, entity, times, values)


#: pyplot keeps global state: figures drawn for recordings in worker threads (the AGARD
#: demo's benches run in two) are drawn one at a time.
FIGURE_LOCK = threading.Lock()


def log_figure(rec: rr.RecordingStream, path: str, draw: Callable[[], Figure]) -> None:
    """Log the matplotlib figure ``draw()`` returns as a static PNG image at ``path``."""
    import matplotlib.pyplot as plt

    buf = io.BytesIO()
    with FIGURE_LOCK:
        fig = draw()
        fig.savefig(buf, format="png", dpi=100)
        plt.close(fig)
    rec.log(path, rr.EncodedImage(contents=buf.getvalue(), media_type="image/png"), static=True)


def response_views(path: str, title: str) -> rrb.Horizontal:
    """Return the views of one logged response: its figure, and gain and phase vs frequency."""
    return rrb.Horizontal(
        rrb.Spatial2DView(origin=f"{path}/figure", name=f"{title} (figure)"),
        rrb.Vertical(
            rrb.TimeSeriesView(
                origin=f"{path}/gain", name=f"{title}: gain [dB] (timeline {FREQUENCY_TIMELINE})"
            ),
            rrb.TimeSeriesView(
                origin=f"{path}/phase", name=f"{title}: phase [deg] (timeline {FREQUENCY_TIMELINE})"
            ),
        ),
        column_shares=[3, 2],
        name=title,
    )


def bode_curve(
    name: str, f_hz: FloatArray, h: NDArray[np.complex128], colour: tuple[int, int, int]
) -> Curve:
    """Return a model's :class:`Curve`: gain in dB, phase unwrapped from the lowest frequency."""
    f = np.asarray(f_hz, dtype=float)
    order = np.argsort(f, kind="stable")
    phase = np.empty(f.size)
    phase[order] = phase_deg(np.asarray(h)[order])
    return Curve(name, f, 20 * np.log10(np.abs(h)), phase, colour)
