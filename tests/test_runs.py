"""Recorded-run format twin-run/1, the simulate CLI and Rerun recordings."""

import json
import shutil
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
from group_signals import AS_IN_A_TERMINAL

from twin.chain.trajectory import uniform_rate
from twin.cli.main import main
from twin.core.errors import RunFormatError, SignalError
from twin.core.ownership import MANIFEST
from twin.formats.runs import read_run
from twin.viz.record import read_entities


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
    assert [p.name for p in run_dir[0].parent.glob(".*")] == [MANIFEST]  # no leftovers


def test_rrd_holds_entities_and_samples(run_dir):
    """A simulate recording: the MPI drawn from its MJCF (base plate and cabin frame as
    cylinders, cockpit box, moved by Transform3D; the commanded pose as a ghost), IMU axes as
    arrows, per-DOF series in separate translation / rotation groups with names, the IMU
    decimated to 100 Hz by default."""
    from twin.viz.record import read_archetypes

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
    with pytest.raises(RunFormatError) as e:
        read_run(d)
    assert str(e.value) == f"{d}/imu.csv: sampled at 819.2 Hz but meta.json says 1000 Hz"


def test_a_time_glitch_is_named_at_its_row_in_the_file(run_dir, tmp_path):
    """Rows 501 on 3 ms late: the message names row 501 (not a row where the mean step,
    pulled by the glitch, first leaves the grid) and the file by its path."""
    d = _copy(run_dir, tmp_path)
    path = d / "commands.csv"
    rows = np.loadtxt(path, delimiter=",", skiprows=1)
    rows[500:, 0] += 0.003
    np.savetxt(path, rows, delimiter=",", fmt="%.10g", header="t,x,y,z,roll,pitch,yaw",
               comments="")  # fmt: skip
    with pytest.raises(RunFormatError) as e:
        read_run(d)
    assert str(e.value).startswith(f"{path}: time steps must be uniform: row 501 is at 5.003 s, ")
    assert "0.013 s after row 500 (4.99 s)" in str(e.value)
    assert "the typical step is 0.01 s" in str(e.value)


def test_a_drifting_clock_is_named_where_it_leaves_the_grid():
    """Steps growing from 10 ms by 0.01 us each (each within 1 % of the typical step), so
    the times bow off the uniform grid: first by more than 1 % of a step at row 22."""
    t = np.concatenate([[0.0], np.cumsum(0.01 + 1e-8 * np.arange(1000))])
    with pytest.raises(SignalError, match=r"^x.csv: time steps must be uniform \(mean 0.010005 "
                       r"s\); row 22 is at 0.210002 s, -0.000103 s off the grid, more than 1 % "
                       "of a step: the clock drifts$"):  # fmt: skip
        uniform_rate(t, "x.csv")


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


def _interrupted_run(out) -> subprocess.Popen:
    """Start a long full-model run and Ctrl-C it once its chunks are being written."""
    proc = subprocess.Popen(  # SIGINT as a terminal gives it, whatever the suite inherited
        [sys.executable, "-c", AS_IN_A_TERMINAL, "simulate", "mpi", "--signal", "rest-600", "--out",
         str(out), "--quiet"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    deadline = time.monotonic() + 60
    while not any(p.stat().st_size for p in out.parent.glob(".run.*/actuators.csv")):
        assert proc.poll() is None and time.monotonic() < deadline, proc.communicate()
        time.sleep(0.02)
    time.sleep(0.3)  # a few chunks on: the physics of the next rolls in its thread
    proc.send_signal(signal.SIGINT)
    return proc


def test_ctrl_c_during_a_full_model_run_exits_130(tmp_path):
    """Ctrl-C while the full model's physics rolls in its thread: 'interrupted', exit 130,
    nothing left; before, MuJoCo went on in C while Python exited (exit 139, Segmentation
    fault). Two runs at once, interrupted at different moments of their chunks."""
    procs = [_interrupted_run(tmp_path / f"{k}" / "run") for k in range(2)]
    for k, proc in enumerate(procs):
        out, err = proc.communicate(timeout=60)
        assert (proc.returncode, out, err) == (130, "", "twin: interrupted\n")
        assert not any((tmp_path / f"{k}").iterdir())


def test_simulate_says_where_the_recording_went(tmp_path, capsys):
    out, rrd = tmp_path / "run", tmp_path / "rest.rrd"
    assert main(["simulate", "srs", "--signal", "rest-1", "--model", "reduced", "--out",
                 str(out), "--rrd", str(rrd)]) == 0  # fmt: skip
    printed = capsys.readouterr().out
    assert f"wrote {out} (" in printed
    assert f"wrote {rrd} (a Rerun recording; view it with python -m rerun {rrd})" in printed
    assert rrd.is_file()
