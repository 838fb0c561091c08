"""Recorded-run format twin-run/1, the simulate CLI and Rerun recordings."""

import json
import shutil

import numpy as np
import pytest

from twin.cli.main import main
from twin.errors import RunFormatError
from twin.record import read_entities
from twin.runs import read_run


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    base = tmp_path_factory.mktemp("runs")
    out, rrd = base / "run", base / "run.rrd"
    code = main(["simulate", "mpi", "--signal", "multisine2-pitch", "--seed", "4",
                 "--out", str(out), "--rrd", str(rrd), "--quiet"])  # fmt: skip
    assert code == 0
    return out, rrd


def test_simulated_run_reads_back(run_dir):
    run = read_run(run_dir[0])
    assert run.meta["format"] == "twin-run/1"
    assert run.meta["platform"] == "mpi"
    assert run.meta["platform_config"]["delay_s"] == 0.035
    assert run.commands.rate_hz == pytest.approx(100.0)
    assert run.imu.shape[1] == 6
    assert np.mean(run.imu[:200, 2]) == pytest.approx(-9.81, abs=0.05)
    assert run.actuators is not None and run.actuators.shape[0] == run.commands.n
    assert not list(run_dir[0].parent.glob(".*"))  # no temporary leftovers


def test_rrd_holds_entities_and_samples(run_dir):
    """A simulate recording: the MPI drawn from its MJCF (base plate and cabin frame as
    cylinders, cockpit box, moved by Transform3D; the commanded pose as a ghost), IMU axes as
    arrows, per-DOF series in separate translation / rotation groups with names, the IMU
    decimated to 100 Hz by default."""
    from twin.record import read_archetypes

    counts = read_entities(run_dir[1])
    kinds = read_archetypes(run_dir[1])
    run = read_run(run_dir[0])
    # block means of round(819.2 / 100) = 8 samples (102.4 Hz), the last partial block, and
    # the static style row
    assert counts["/imu/accel/z"] == -(-len(run.imu_t) // 8) + 1
    assert counts["/translation/heave/command"] >= run.commands.n  # + the static style row
    assert counts["/rotation/pitch/actual"] == counts["/rotation/pitch/command"]
    assert counts["/legs/l1"] == run.commands.n + 1
    assert counts["/world/base/legs"] > 25 * run.commands.duration
    assert counts["/world/cabin"] == counts["/world/command"] == counts["/world/base/legs"]
    assert kinds["/world/base"] == {"Transform3D"} and kinds["/world/cabin"] == {"Transform3D"}
    assert kinds["/world/cabin/cockpit"] == {"Boxes3D"}
    assert kinds["/world/cabin/upper_frame"] == kinds["/world/base/base_plate"] == {"Cylinders3D"}
    assert kinds["/world/command/cockpit"] == {"Boxes3D"}
    assert kinds["/world/cabin/imu"] == {"Arrows3D"}
    assert kinds["/world/base/legs"] == {"LineStrips3D"}
    assert kinds["/rotation/pitch/actual"] == {"Scalars", "SeriesLines"}
    assert not any(p.startswith("/pose") for p in counts)  # m and deg no longer mixed
    assert kinds["/legs/shortest"] == kinds["/legs/longest"] == {"Scalars", "SeriesLines"}


def _copy(run_dir, tmp_path):
    dst = tmp_path / "bad"
    shutil.copytree(run_dir[0], dst)
    return dst


def _edit_csv(path, row, col, value):
    lines = path.read_text().splitlines()
    cells = lines[row].split(",")
    cells[col] = value
    lines[row] = ",".join(cells)
    path.write_text("\n".join(lines) + "\n")


@pytest.mark.parametrize(
    ("damage", "message"),
    [
        (lambda d: (d / "imu.csv").unlink(), "missing imu.csv"),
        (lambda d: _edit_csv(d / "commands.csv", 0, 3, "heave"), "commands.csv: header"),
        (
            lambda d: _edit_csv(d / "commands.csv", 5, 0, "0.001"),
            "commands.csv: time must increase",
        ),
        (lambda d: _edit_csv(d / "imu.csv", 7, 2, "nan"), r"imu.csv: row 7 \(line 8\): ay"),
        (lambda d: _edit_csv(d / "actuators.csv", 3, 1, "abc"), "actuators.csv: not a table"),
    ],
)
def test_malformed_runs_are_rejected(run_dir, tmp_path, damage, message):
    d = _copy(run_dir, tmp_path)
    damage(d)
    with pytest.raises(RunFormatError, match=message):
        read_run(d)


def test_rate_mismatch_with_meta_is_rejected(run_dir, tmp_path):
    d = _copy(run_dir, tmp_path)
    meta = json.loads((d / "meta.json").read_text())
    meta["imu"]["rate_hz"] = 1000.0
    (d / "meta.json").write_text(json.dumps(meta))
    with pytest.raises(
        RunFormatError, match=r"imu\.csv: sampled at 819\.2 Hz but meta\.json says 1000"
    ):
        read_run(d)


def test_commands_file_drives_a_run_at_its_own_rate(run_dir, tmp_path, capsys):
    src = run_dir[0] / "commands.csv"
    lines = src.read_text().splitlines()
    sub = tmp_path / "cmd"
    sub.mkdir()
    (sub / "commands.csv").write_text("\n".join([lines[0], *lines[1::2]]) + "\n")  # 50 Hz
    out = tmp_path / "r50"
    assert main(["simulate", "srs", "--signal", str(sub / "commands.csv"), "--model",
                 "reduced", "--out", str(out), "--quiet"]) == 0  # fmt: skip
    run = read_run(out)
    assert run.meta["command_rate_hz"] == pytest.approx(50.0)


def test_cli_errors_are_one_line(tmp_path, capsys):
    assert (
        main(["simulate", "condition-9", "--signal", "rest-1", "--out", str(tmp_path / "x")]) == 2
    )
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "unknown configuration 'condition-9'" in err[0]
    assert not (tmp_path / "x").exists()
    assert main(["simulate", "mpi", "--signal", "rest-1", "--strict", "--out",
                 str(tmp_path / "y"), "--quiet"]) == 0  # fmt: skip
    assert main(["simulate", "mpi", "--signal", "rest-1", "--out", str(tmp_path / "y")]) == 2
    assert "already exists" in capsys.readouterr().err


def test_strict_rejection_leaves_nothing_written(tmp_path, capsys):
    t = np.arange(0, 4.0, 0.01)
    z = -0.15 * np.sin(2 * np.pi * 2.0 * t) * np.clip(t - 1, 0, 1)
    rows = np.column_stack([t, 0 * t, 0 * t, z, 0 * t, 0 * t, 0 * t])
    cmd = tmp_path / "commands.csv"
    np.savetxt(cmd, rows, delimiter=",", header="t,x,y,z,roll,pitch,yaw", comments="")
    out, rrd = tmp_path / "strict", tmp_path / "strict.rrd"
    code = main(["simulate", "mpi-2008", "--signal", str(cmd), "--strict", "--out", str(out),
                 "--rrd", str(rrd), "--quiet"])  # fmt: skip
    assert code == 2
    assert "actuator limit" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["commands.csv"]


def test_raw_imu_records_every_sample(tmp_path):
    """``--raw-imu``: every 819.2 Hz IMU sample in the recording, not ~100 Hz block means."""
    out, rrd = tmp_path / "run", tmp_path / "run.rrd"
    assert main(["simulate", "srs", "--signal", "rest-2", "--model", "reduced", "--out",
                 str(out), "--rrd", str(rrd), "--raw-imu", "--quiet"]) == 0  # fmt: skip
    assert read_entities(rrd)["/imu/gyro/q"] == len(read_run(out).imu_t) + 1  # + style row
