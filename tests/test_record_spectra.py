"""Frequency responses in recordings: the frequency timeline, bounds, refused duplicates."""

import numpy as np
import pytest

from twin.viz.record import read_entities, read_timelines
from twin.viz.record.spectra import Curve, bode_curve, log_curves
from twin.viz.record.stream import Recording


def test_measured_points_with_bounds_and_a_model_line(tmp_path):
    f = np.array([0.5, 0.1, 2.0])  # any order
    h = 1 / (1 + 1j * f)
    measured = Curve("measured", f, 20 * np.log10(np.abs(h)), np.degrees(np.angle(h)),
                     (0, 0, 200), (np.full(3, 0.5), np.full(3, 0.6), np.full(3, 4.0)))  # fmt: skip
    dense = np.geomspace(0.01, 10.0, 400)  # below 0.1 Hz, several points per millihertz
    with Recording("t", _layout(), rrd=tmp_path / "r.rrd") as rec:
        log_curves(rec.rec, "df/x", [measured, bode_curve("model", dense, 1 / (1 + 1j * dense),
                                                          (0, 0, 0))])  # fmt: skip
    counts, timelines = read_entities(tmp_path / "r.rrd"), read_timelines(tmp_path / "r.rrd")
    assert counts["/df/x/gain/measured"] == 3 + 1  # + the style row
    assert counts["/df/x/phase/measured_hi95"] == 3 + 1
    thinned = len(np.unique(np.round(dense * 1e3)))
    assert thinned < 400 and counts["/df/x/gain/model"] == thinned + 1
    assert timelines["/df/x/gain/measured_lo95"] == {"frequency_mHz"}


def test_measured_points_sharing_a_frequency_are_refused(tmp_path):
    f = np.array([0.5, 0.5])
    bad = Curve("measured", f, np.zeros(2), np.zeros(2), (0, 0, 0),
                (np.ones(2), np.ones(2), np.ones(2)))  # fmt: skip
    with pytest.raises(ValueError, match="one curve per run"):
        with Recording("t", _layout(), rrd=tmp_path / "r.rrd") as rec:
            log_curves(rec.rec, "df/x", [bad])
    assert not list(tmp_path.iterdir())  # aborted: nothing half-written


def _layout():
    import rerun.blueprint as rrb

    return rrb.Blueprint(rrb.TimeSeriesView(origin="/"))


@pytest.mark.parametrize("command", ["pilot", "simulate"])
def test_a_recording_path_that_cannot_be_a_file_is_one_line_and_nothing_is_written(
    command, tmp_path, capsys
):
    from twin.cli.main import main

    folder, afile = tmp_path / "folder", tmp_path / "afile"
    folder.mkdir()
    afile.write_text("x")
    out = tmp_path / "out"
    for rrd, message in ((folder, "is a folder"), (afile / "x.rrd", "is a file, not a folder")):
        if command == "pilot":
            argv = ["pilot", "run", "condition-1", "--out", f"{out}.csv", "--rrd", str(rrd)]
        else:
            argv = ["simulate", "srs", "--signal", "rest-2", "--model", "reduced", "--out",
                    str(out), "--rrd", str(rrd), "--quiet"]  # fmt: skip
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert message in err and err.count("\n") == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["afile", "folder"]  # nothing else
    assert not list(folder.iterdir())
