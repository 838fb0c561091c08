"""`twin agard ...`: JSON outputs, run folders as targets, report folders, errors."""

import json

import numpy as np
import pytest

from twin.agard.omct import BoundsFileError, read_bounds
from twin.cli.main import main


def _json(capsys, argv):
    assert main(argv) == 0
    return json.loads(capsys.readouterr().out)


def test_df_json_has_the_documented_keys(capsys):
    out = _json(capsys, ["agard", "df", "mpi", "--dof", "pitch", "--model", "reduced",
                         "--json", "--quiet"])  # fmt: skip
    assert {"frequencies_hz", "gain", "phase_deg", "delay_ms"} <= out.keys()
    assert len(out["frequencies_hz"]) == 11  # Table 5.2: 5 + 6 lines
    assert out["delay_ms"] == pytest.approx(35.0, abs=3.0)


def test_threshold_json_has_the_documented_keys(capsys):
    out = _json(capsys, ["agard", "threshold", "mpi", "--dof", "heave", "--model", "reduced",
                         "--break-hz", "10", "--amplitude", "0.1875", "--step-s", "0.5",
                         "--json", "--quiet"])  # fmt: skip
    assert {"delay_ms", "tau_ms", "t63_ms"} <= out.keys()
    assert out["t63_ms"] == pytest.approx(out["delay_ms"] + out["tau_ms"])


def test_a_recorded_run_is_analysed_by_the_same_command(capsys, tmp_path):
    assert main(["agard", "noise", "srs", "--dof", "heave", "--model", "reduced", "--out",
                 str(tmp_path), "--quiet"]) == 0  # fmt: skip
    capsys.readouterr()
    assert (tmp_path / "result.json").exists() and (tmp_path / "noise.png").exists()
    runs = sorted((tmp_path / "runs").iterdir())
    assert len(runs) == 6  # the six default amplitudes
    simulated = json.loads((tmp_path / "result.json").read_text())["points"][2]
    out = _json(capsys, ["agard", "noise", str(runs[2]), "--json"])
    again = out["points"][0]
    assert again["ratios"]["total"] == pytest.approx(simulated["ratios"]["total"], rel=1e-4)


def test_omct_json_checks_the_points_against_the_bounds_file(capsys):
    out = _json(capsys, ["agard", "omct", "srs", "--dof", "pitch", "--model", "reduced",
                         "--no-noise", "--ideal-imu", "--json", "--quiet"])  # fmt: skip
    assert len(out["frequencies_rad_s"]) == 12 and len(out["inside"]) == 12
    assert out["frequencies_rad_s"][0] == pytest.approx(0.1)
    assert out["frequencies_rad_s"][-1] == pytest.approx(10**1.2)
    assert "ILLUSTRATIVE" in out["bounds"]["title"]


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["agard", "df", "nosuch", "--dof", "heave"], "unknown configuration 'nosuch'"),
        (["agard", "df", "mpi"], "give --dof"),
        (
            ["agard", "df", "mpi", "--dof", "heave", "--break-hz", "-1"],
            "--break-hz: must be a number in [0, 1000]; got -1",
        ),
        (
            ["agard", "omct", "srs", "--dof", "heave", "--bounds", "/no/such.toml"],
            "no such OMCT bounds file",
        ),
        (["agard", "report", "srs", "--model", "reduced", "--seed", "-3"], "seed must be"),
    ],
)
def test_bad_input_is_one_line_and_exit_2(capsys, argv, message, tmp_path):
    assert main([*argv, "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1
    assert not (tmp_path / "o").exists()  # nothing written


def test_a_malformed_run_folder_is_rejected_naming_the_file(capsys, tmp_path):
    run = tmp_path / "run"
    run.mkdir()
    (run / "meta.json").write_text("{not json")
    assert main(["agard", "df", str(run)]) == 2
    assert "meta.json" in capsys.readouterr().err


def test_bounds_files_are_checked(tmp_path):
    good = read_bounds()
    assert "default" in good.tables
    b = good.at("heave", np.array([0.1, 15.85]))
    assert np.all(b["gain_min"] < b["gain_max"])
    bad = tmp_path / "b.toml"
    bad.write_text('format = "twin-omct-bounds/1"\n[pitch]\nfrequency_rad_s = [1.0, 2.0]\n'
                   "gain_min = [1.0, 1.0]\ngain_max = [0.5, 2.0]\n"
                   "phase_min_deg = [0.0, 0.0]\nphase_max_deg = [1.0, 1.0]\n")  # fmt: skip
    with pytest.raises(BoundsFileError, match="minimum lies above"):
        read_bounds(bad)
    bad.write_text('format = "other"\n')
    with pytest.raises(BoundsFileError, match="format must be"):
        read_bounds(bad)
    bad.write_text('format = "twin-omct-bounds/1"\n[wobble]\n')
    with pytest.raises(BoundsFileError, match="unknown table"):
        read_bounds(bad)


@pytest.mark.slow
def test_report_writes_a_complete_folder(capsys, tmp_path):
    out = tmp_path / "rep"
    assert main(["agard", "report", "srs", "--model", "reduced", "--dof", "heave", "--out",
                 str(out), "--quiet"]) == 0  # fmt: skip
    names = {p.name for p in out.iterdir()}
    tests = {"df", "noise", "threshold", "omct", "snr", "linearity", "hysteresis", "parasitic",
             "bump", "limits"}  # fmt: skip
    assert {"report.json", "summary.md", "runs"} | {f"{t}-heave.png" for t in tests} <= names
    report = json.loads((out / "report.json").read_text())
    assert set(report["dofs"]["heave"]) == tests
    assert "## heave" in (out / "summary.md").read_text()
    assert not (tmp_path / "rep.partial").exists()


def test_rrd_records_every_run_of_a_test(capsys, tmp_path):
    """An agard recording: every run on the platform, and the describing function against
    frequency (measured points with 95 % bounds, the configuration's Eq 5.11 as a line) with
    its figure."""
    from twin.viz.record import read_archetypes, read_entities, read_timelines

    rrd = tmp_path / "df.rrd"
    assert main(["agard", "df", "srs", "--dof", "heave", "--model", "reduced", "--rrd",
                 str(rrd), "--quiet"]) == 0  # fmt: skip
    counts = read_entities(rrd)
    out = capsys.readouterr().out
    assert "fitted delay" in out
    # both multi-sine runs, one after the other: 60 s + 40 s of IMU shown as block means of
    # round(819.2 / 100) = 8 samples
    assert counts["/imu/gyro/q"] == pytest.approx(819.2 * 100 / 8, rel=0.01)
    assert counts["/legs/l1"] > 0 and counts["/world/cabin"] > 0
    kinds, timelines = read_archetypes(rrd), read_timelines(rrd)
    assert kinds["/df/heave/figure"] == {"EncodedImage"}
    for part in ("gain", "phase"):
        assert kinds[f"/df/heave/{part}/measured"] == {"Scalars", "SeriesPoints"}
        assert kinds[f"/df/heave/{part}/eq_5_11"] == {"Scalars", "SeriesLines"}
        assert timelines[f"/df/heave/{part}/measured_hi95"] == {"frequency_mHz"}
    assert timelines["/legs/l1"] == {"sim_time"}
    assert counts["/df/heave/gain/measured"] > 10  # the Table 5.2 lines (+ the style row)
