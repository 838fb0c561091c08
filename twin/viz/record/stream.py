"""One Rerun recording's life: saved to an ``.rrd`` under a partial name, or streamed live.

A recording saved to a file is written as ``.NAME.partial`` beside it and renamed by
:meth:`Recording.close`; :meth:`Recording.abort` (or leaving a ``with`` block by an exception)
deletes it, so a failed run never leaves a half-written ``.rrd`` behind.
"""

from __future__ import annotations

from pathlib import Path

import rerun as rr
import rerun.blueprint as rrb

from twin.core.errors import UsageError
from twin.core.lifecycle import CloseOrAbort, check_output_file
from twin.core.ownership import check_replace, record

#: The kind of output a recording is (in the manifest of its folder).
RECORDING = "recording"
#: The time axis of every run.
TIMELINE = "sim_time"


def check_recording_path(rrd: str | Path) -> Path:
    """Return ``rrd`` as a path a recording can be written to (:func:`check_output_file`).

    Raises
    ------
    UsageError
        ``rrd`` is an existing folder, one of its parents is a file, its folder cannot be
        written, or it is a file that is not an earlier recording of the twin (without
        ``--overwrite``) or an input (:func:`twin.core.ownership.check_replace`).

    """
    final = check_output_file(rrd)
    check_replace(final, RECORDING)
    return final


class Recording(CloseOrAbort):
    """A Rerun recording stream with its sink (see the module docstring).

    Parameters
    ----------
    name : str
        Recording name shown in the viewer.
    layout : rerun.blueprint.Blueprint
        Its default layout.
    rrd : str or Path, optional
        Save to this file (headless).
    connect : str, optional
        gRPC URL of a running viewer to stream to instead (``""`` for Rerun's default).

    """

    def __init__(
        self,
        name: str,
        layout: rrb.Blueprint,
        rrd: str | Path | None = None,
        connect: str | None = None,
    ) -> None:
        self.rec = rr.RecordingStream(application_id="twin", recording_id=None)
        self.rec.send_recording_name(name)
        self.final: Path | None = None
        if rrd is not None:
            self.final = check_recording_path(rrd)
            self.final.parent.mkdir(parents=True, exist_ok=True)
            self._partial = self.final.with_name(f".{self.final.name}.partial")
            try:
                self.rec.save(str(self._partial), default_blueprint=layout)
            except RuntimeError as e:  # Rerun's own error for a file it cannot create
                raise UsageError(f"{self.final}: cannot write the recording ({e})") from None
        elif connect is not None:
            self.rec.connect_grpc(connect or None, default_blueprint=layout)
        else:
            raise ValueError("a recording needs a file (rrd) or a viewer URL (connect)")

    def close(self) -> None:
        """Flush and close (the ``.rrd`` appears under its name only now)."""
        self.rec.flush()
        self.rec.disconnect()
        if self.final is not None:
            try:
                self._partial.replace(self.final)
            except BaseException:
                self._partial.unlink(missing_ok=True)
                raise
            record(self.final, RECORDING)

    def abort(self) -> None:
        """Close and delete a partly written ``.rrd``."""
        self.rec.disconnect()
        if self.final is not None:
            self._partial.unlink(missing_ok=True)


def series_style(
    rec: rr.RecordingStream, path: str, name: str, colour, width: float = 1.5, points: bool = False
) -> None:
    """Log the static style of one scalar series: its name (with unit), colour and width."""
    if points:
        style = rr.SeriesPoints(colors=[colour], names=[name], marker_sizes=[3.0])
    else:
        style = rr.SeriesLines(colors=[colour], names=[name], widths=[width])
    rec.log(path, style, static=True)


def send_series(rec: rr.RecordingStream, path: str, times: rr.TimeColumn, values) -> None:
    """Send one scalar series as a whole column against ``times``."""
    rec.send_columns(path, indexes=[times], columns=rr.Scalars.columns(scalars=values))
