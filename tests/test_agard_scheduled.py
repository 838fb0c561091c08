"""`twin agard report` on schedules and recorded runs: the tests a run holds, and not.

A lab's schedule runs in one run; the report finds each test's moves, analyses them and names
the tests the run lacks. A run made for one test reports that test and names the rest.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from twin.chain.config import motion_system
from twin.cli.main import main

SCHEDULE = """
schedule = "twin-schedule/1"
name = "heave set"

[[move]]
kind = "still"
duration_s = 1.0

[[move]]
kind = "sines"
dof = "heave"
frequencies_hz = [0.5]
amplitudes = [0.1]
fade_s = 2.0
duration_s = 14.0

[[move]]
kind = "sines"
dof = "heave"
frequencies_hz = [0.5]
amplitudes = [0.01]
fade_s = 2.0
duration_s = 14.0

[[move]]
kind = "sines"
dof = "heave"
frequencies_hz = [0.025]
amplitudes = [0.1]
fade_s = 5.0
duration_s = 50.0
"""


@pytest.fixture(scope="module")
def scheduled_run(tmp_path_factory):
    """A reduced-model MPI run of the schedule above, made by ``twin simulate``."""
    root = tmp_path_factory.mktemp("scheduled")
    path = root / "heave.toml"
    path.write_text(SCHEDULE, encoding="utf-8")
    run = root / "run"
    assert (
        main(
            [
                "simulate",
                "mpi",
                "--model",
                "reduced",
                "--signal",
                str(path),
                "--out",
                str(run),
                "--quiet",
            ]
        )
        == 0
    )
    return path, run


def test_simulate_writes_the_schedule_into_meta(scheduled_run):
    _, run = scheduled_run
    meta = json.loads((run / "meta.json").read_text())
    moves = meta["schedule"]["moves"]
    assert [m["kind"] for m in moves] == ["still", "sines", "sines", "sines"]
    assert [m["test"] for m in moves] == ["noise", "df", "df", "hysteresis"]


def test_report_of_a_scheduled_run_holds_its_tests_and_names_the_rest(
    scheduled_run, tmp_path, capsys
):
    _, run = scheduled_run
    out = tmp_path / "rep"
    assert main(["agard", "report", str(run), "--out", str(out), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert set(doc["tests"]) >= {"df", "linearity", "parasitic", "hysteresis"}
    assert {"threshold", "omct"} <= set(doc["missing"])
    # the describing function at the schedule's 0.5 Hz against the configuration's Eq 5.11
    # model (1 Hz filter, 35 ms delay) within 1 dB and 5 deg
    df = doc["tests"]["df"]["heave"]
    h = motion_system("mpi").response_at_hz([0.5])[0, 2]
    assert df["frequencies_hz"] == pytest.approx([0.5])
    assert 20 * np.log10(df["gain"][0] / abs(h)) == pytest.approx(0.0, abs=1.0)
    assert df["phase_deg"][0] == pytest.approx(np.degrees(np.angle(h)), abs=5.0)
    assert (out / "summary.md").exists() and (out / "df-heave.png").exists()
    assert (out / "hysteresis-heave.png").exists()
    # nominal, linear: the 10x smaller amplitude's gain within its interval of the larger's
    points = doc["tests"]["linearity"]["heave"]["points"]
    assert [p["amplitude"] for p in points] == pytest.approx([0.1 * np.pi**2, 0.01 * np.pi**2])
    assert all(p["linear"] for p in points)


def test_single_test_on_a_scheduled_run_reports_only_that_test(scheduled_run, tmp_path, capsys):
    _, run = scheduled_run
    assert main(["agard", "linearity", str(run), "--out", str(tmp_path / "lin"), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert list(doc["tests"]) == ["linearity"]


def test_report_of_a_one_test_run_names_the_tests_it_lacks(tmp_path, capsys):
    assert (
        main(
            [
                "agard",
                "df",
                "mpi",
                "--dof",
                "pitch",
                "--model",
                "reduced",
                "--out",
                str(tmp_path / "df"),
                "--quiet",
            ]
        )
        == 0
    )
    run = sorted((tmp_path / "df" / "runs").iterdir())[0]
    capsys.readouterr()
    assert main(["agard", "report", str(run), "--out", str(tmp_path / "rep"), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert set(doc["tests"]) == {"df"}
    # a multisine's window has no bin free of its lines for the parasitic motion's noise
    assert "no bins free of the lines" in doc["missing"]["parasitic"]
    assert {"linearity", "hysteresis", "threshold", "omct"} <= set(doc["missing"])


def test_linearity_of_a_run_without_schedule_is_refused(tmp_path, capsys):
    assert (
        main(
            [
                "simulate",
                "mpi",
                "--model",
                "reduced",
                "--signal",
                "multisine1-heave",
                "--out",
                str(tmp_path / "run"),
                "--quiet",
            ]
        )
        == 0
    )
    assert main(["agard", "linearity", str(tmp_path / "run")]) == 2
    err = capsys.readouterr().err
    assert "takes several sines; give the schedule" in err and err.count("\n") == 1


def test_a_malformed_schedule_stops_the_command_in_one_line(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text(
        'schedule = "twin-schedule/1"\n[[move]]\nkind = "sines"\ndof = "heave"\n'
        "frequencies_hz = [0.5]\namplitudes = [0.1]\nduration_s = 5\n"
    )
    assert main(["simulate", "mpi", "--signal", str(bad), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "move 1: a sines move needs fade_s" in err and err.count("\n") == 1
    assert not (tmp_path / "o").exists()
    assert (
        main(["agard", "report", "mpi", "--schedule", str(bad), "--out", str(tmp_path / "r")]) == 2
    )
    assert not (tmp_path / "r").exists()


def test_the_report_never_writes_into_its_run(scheduled_run, capsys):
    _, run = scheduled_run
    before = sorted(p.name for p in run.iterdir())
    assert main(["agard", "report", str(run), "--out", str(run)]) == 2
    assert "an input of this command" in capsys.readouterr().err
    assert sorted(p.name for p in run.iterdir()) == before


BUMP_AND_LIMITS = """
schedule = "twin-schedule/1"
name = "sway bumps and a limits move"

[[move]]
kind = "still"
duration_s = 1.0

[[move]]
kind = "constant_acceleration"
dof = "sway"
acceleration = 0.1
v_start = 0.0
v_end = 0.1

[[move]]
kind = "constant_speed"
dof = "sway"
speed = 0.1
duration_s = 1.0

[[move]]
kind = "constant_acceleration"
dof = "sway"
acceleration = -0.1
v_start = 0.1
v_end = -0.1

[[move]]
kind = "constant_speed"
dof = "sway"
speed = -0.1
duration_s = 1.0

[[move]]
kind = "constant_acceleration"
dof = "sway"
acceleration = 0.1
v_start = -0.1
v_end = 0.0

[[move]]
kind = "still"
duration_s = 1.0

[[move]]
kind = "point_to_point"
dof = "heave"
distance = 0.1
vmax = 0.2
amax = 1.0
jmax = 20.0

[[move]]
kind = "still"
duration_s = 2.0
"""


def test_report_of_bumps_and_limits_in_a_schedule(tmp_path, capsys):
    path = tmp_path / "bl.toml"
    path.write_text(BUMP_AND_LIMITS, encoding="utf-8")
    assert (
        main(
            [
                "agard",
                "report",
                "mpi",
                "--model",
                "reduced",
                "--schedule",
                str(path),
                "--out",
                str(tmp_path / "rep"),
                "--json",
                "--quiet",
            ]
        )
        == 0
    )
    doc = json.loads(capsys.readouterr().out)
    assert set(doc["tests"]) == {"bump", "limits"}
    (rev,) = doc["tests"]["bump"]["sway"]["reversals"]  # the one move through zero speed
    assert rev["speed"] == pytest.approx(0.1, rel=0.01)
    assert rev["acceleration"] == pytest.approx(-0.1, rel=0.01)
    (level,) = doc["tests"]["limits"]["heave"]["levels"]
    # a 0.1 m move well inside the MPI's limits: reached as commanded, nothing stopped it
    assert level["reached"]["excursion_max"] == pytest.approx(0.1, abs=2e-3)
    assert level["stopped_by"] == []
    assert {"df", "linearity", "parasitic", "hysteresis"} <= set(doc["missing"])
