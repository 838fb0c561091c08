"""The bad inputs of issue 17, one by one: each is one line naming what is wrong, exit 2.

(:mod:`tests.test_fuzz_inputs` tries thousands of damaged files and odd numbers; this module
names the cases a user met, with the message each must give.)
"""

from __future__ import annotations

import errno
import inspect
import json
import os
import shutil
from pathlib import Path

import numpy as np
import pytest
from cli_contract import fails_in_one_line as _one_line

from twin.cli.main import EXIT_BROKEN_PIPE, EXIT_BUG, error_line, main
from twin.core.errors import DataError
from twin.core.ownership import MANIFEST

REST = ["simulate", "srs", "--model", "reduced", "--signal", "rest-1", "--quiet"]


@pytest.fixture(scope="module")
def run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A valid 1-s run folder."""
    out = tmp_path_factory.mktemp("r") / "run"
    assert main([*REST, "--out", str(out)]) == 0
    return out


def test_output_paths_are_refused_before_any_work(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "file.txt").write_text("mine")
    (tmp_path / "folder").mkdir()
    cases = [
        ([*REST, "--out", "file.txt/sub"], "file.txt is a file, not a folder"),
        ([*REST, "--out", "/proc/sys/twin-run"], "cannot write in /proc/sys"),
        ([*REST, "--out", "o1", "--rrd", "folder"], "argument --rrd: folder: is a folder"),
        ([*REST, "--out", "o2", "--rrd", "/proc/sys/x.rrd"], "read-only file system"),
        (["pilot", "run", "srs", "--out", "folder", "--quiet"], "--out: folder: is a folder"),
        (["compare", "srs", "--plot", "bode.xyz"], "unknown file type '.xyz'"),
        (["diagnose", "x", "--save-config", "folder"], "--save-config: folder: is a folder"),
        (["agard", "df", "srs", "--dof", "pitch", "--out", "file.txt"], "file.txt: is a file"),
    ]
    for argv, message in cases:
        _one_line(capsys, argv, message)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file.txt", "folder"]
    assert (tmp_path / "file.txt").read_text() == "mine" and not any(
        (tmp_path / "folder").iterdir()
    )


def test_missing_folders_of_an_output_file_are_made(tmp_path, run):
    rrd = tmp_path / "new" / "deeper" / "run.rrd"
    assert main([*REST, "--out", str(tmp_path / "o"), "--rrd", str(rrd)]) == 0
    assert rrd.is_file() and [p.name for p in rrd.parent.glob(".*")] == [MANIFEST]


def _full_disk_on(monkeypatch: pytest.MonkeyPatch, name: str) -> None:
    """Make writing a run folder's ``name`` fail as on a full disk: its rows, then its close.

    (A real full disk refuses the buffered rows again when the file is closed.)
    """
    import twin.formats.runs

    write_rows = twin.formats.runs._write_rows
    full = OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    def write_or_fail(fh, t, values, block=8192):
        if Path(fh.name).name != name:
            return write_rows(fh, t, values, block)
        close, failed = fh.close, []

        def close_once():
            close()
            if not failed:  # once: the garbage collector may close it again
                failed.append(True)
                raise full

        fh.close = close_once
        fh.write("0.01,0.5")  # part of a row, left in the buffer
        raise full

    monkeypatch.setattr(twin.formats.runs, "_write_rows", write_or_fail)


def test_a_full_disk_leaves_nothing_and_names_the_file(tmp_path, capsys, monkeypatch):
    """simulate, import and agard report on a full disk: the file named, no staging folder."""
    run = tmp_path / "in"
    assert main([*REST[:-3], "--signal", "rest-6", "--quiet", "--out", str(run)]) == 0
    _full_disk_on(monkeypatch, "imu.csv")
    out = tmp_path / "out"
    imported = ["import", str(run / "commands.csv"), str(run / "imu.csv"), "--platform", "srs",
                "--clock-offset", "0", "--imu-position", "0", "0", "0", "--quiet"]  # fmt: skip
    report = ["agard", "report", "srs", "--model", "reduced", "--dof", "heave", "--quiet"]
    for argv, file in [
        (REST, f"{out}/imu.csv"),
        (imported, f"{out}/imu.csv"),
        (report, f"{out}/runs/00-multisine1-heave/imu.csv"),
    ]:
        message = f"twin: error: {file}: cannot be written (No space left on device)\n"
        _one_line(capsys, [*argv, "--out", str(out)], message)
        assert sorted(p.name for p in tmp_path.iterdir()) == ["in"], argv


def _edited_run(run: Path, where: Path, edit) -> Path:
    copy = where / "run"
    shutil.copytree(run, copy)
    meta = json.loads((copy / "meta.json").read_text())
    edit(meta)
    (copy / "meta.json").write_text(json.dumps(meta))
    return copy


@pytest.mark.parametrize(
    ("keys", "value", "message"),
    [
        (
            ("imu", "position_m"),
            ["a", 0, 0],
            "imu.position_m [x, y, z][0] must be a number; got 'a'",
        ),
        (("imu", "position_m"), [0, 0], "imu.position_m [x, y, z] must be 3 numbers"),
        (("platform_config", "noise_highpass_hz"), "x", "noise_highpass_hz must be a number"),
        (("platform_config", "noise_highpass_hz"), [1], "noise_highpass_hz must be a number"),
        (("platform_config", "noise"), "yes", "noise must be true or false; got 'yes'"),
        (("platform_config", "delay_s"), 1e300, "delay_s must be a number in [0, 10]"),
        (("command_rate_hz",), True, "command_rate_hz must be a number"),
        (("platform",), ["srs"], "platform must be one of mpi, srs; got ['srs']"),
    ],
)
def test_wrong_types_in_meta_json_are_named(run, tmp_path, capsys, keys, value, message):
    def edit(meta: dict) -> None:
        node = meta
        for k in keys[:-1]:
            node = node[k]
        node[keys[-1]] = value

    bad = _edited_run(run, tmp_path, edit)
    _one_line(capsys, ["agard", "noise", str(bad), "--quiet"], f"{bad}/meta.json: ", message)


@pytest.mark.parametrize(
    ("value", "message"),
    [("abc", "noise_highpass_hz must be a number"), ([1], "noise_highpass_hz must be a number"),
     (1e-300, "noise_highpass_hz must be a number in [0.01, 1000]")],
)  # fmt: skip
def test_wrong_types_in_a_config_file_are_named(tmp_path, capsys, value, message):
    from twin.chain.config import motion_system

    cfg = motion_system("mpi").save(tmp_path / "c.json")
    doc = json.loads(cfg.read_text())
    doc["platform_config"]["noise_highpass_hz"] = value
    cfg.write_text(json.dumps(doc))
    out = tmp_path / "o"
    _one_line(capsys, ["simulate", str(cfg), *REST[2:], "--out", str(out)], message)
    assert not out.exists()


def test_wrong_types_in_omct_bounds_are_named(tmp_path, capsys, run):
    from twin.agard.omct import EXAMPLE_BOUNDS

    text = Path(EXAMPLE_BOUNDS).read_text()
    for old, new, message in [
        ("frequency_rad_s = [", 'frequency_rad_s = ["a", ', "frequency_rad_s[0] must be a number"),
        ("frequency_rad_s = [", "frequency_rad_s = [[1], ", "frequency_rad_s[0] must be a number"),
    ]:
        bad = tmp_path / "b.toml"
        bad.write_text(text.replace(old, new, 1))
        _one_line(capsys, ["agard", "omct", str(run), "--bounds", str(bad), "--quiet"], message)
    bad.write_bytes(b"\xff\xfe\x00 binary")
    _one_line(capsys, ["agard", "omct", str(run), "--bounds", str(bad)], "not UTF-8 text")


def test_binary_files_are_refused_and_a_byte_order_mark_is_read(tmp_path, capsys, run):
    commands = tmp_path / "cmd" / "commands.csv"
    commands.parent.mkdir()
    commands.write_bytes(b"t,x,y,z,roll,pitch,yaw\n\xff\xfe\x00\x01")
    argv = ["simulate", "srs", "--model", "reduced", "--signal", str(commands), "--quiet"]
    _one_line(capsys, [*argv, "--out", str(tmp_path / "o1")], "not UTF-8 text (byte 0xff")
    commands.write_bytes(b"\xef\xbb\xbf" + (run / "commands.csv").read_bytes())
    assert main([*argv, "--out", str(tmp_path / "o2")]) == 0
    pilot = tmp_path / "p.csv"
    pilot.write_bytes(b"t,ft,fd,e,u,theta\n\x80\x81")
    _one_line(capsys, ["pilot", "identify", str(pilot)], "not UTF-8 text")


def test_odd_numbers_on_the_command_line(capsys, tmp_path):
    cases = [
        (["pilot", "run", "condition-1", "--seed", "-1"], "seed must be an integer >= 0"),
        (["pilot", "lead", "srs", "--margin-deg", "nan"], "--margin-deg: must be a number in"),
        (["pilot", "lead", "srs", "--margin-deg", "1e9"], "in [0, 90]"),
        (["simulate", "srs", "--signal", "rest-1", "--delay-ms", "1e300"], "[0, 10000]"),
        (["simulate", "srs", "--signal", "rest-1", "--break-hz", "1e-300"], "0 (no filter) or in"),
        (
            ["pilot", "run", "srs", "--runs", "100000000"],
            "--runs: must be an integer in [1, 1,000]",
        ),
        (["pilot", "montecarlo", "--fit-runs", "-1"], "--fit-runs: must be an integer in [0, 500]"),
        (["agard", "threshold", "srs", "--dof", "pitch", "--amplitude", "1e300"], "(0, 100]"),
    ]
    for argv, message in cases:
        _one_line(capsys, argv, message)


def test_options_are_named_as_typed_not_by_the_librarys_names(capsys, run):
    """The command line names the option (--max-hz), the library its parameter (max_hz)."""
    from twin.core.errors import SignalError
    from twin.diagnose.diagnosis import diagnose

    cases = [
        (["pilot", "adapt", "mpi", "--weight", "-1"], "argument --weight: must be a number in "
         "(0, 1000]; got -1"),
        (["pilot", "lead", "srs", "--margin-deg", "100"], "argument --margin-deg: must be a "
         "number in [0, 90]; got 100"),
        (["diagnose", str(run), "--max-hz", "100"], "argument --max-hz: must be a number in "
         "(0.5, 45]; got 100"),
        (["diagnose", str(run), "--each", "--max-hz", "100"], "argument --max-hz: must be a "
         "number in (0.5, 45]"),
        (["diagnose", str(run), "--imu-noise", "0"], "argument --imu-noise: must be a number in "
         "[0.001, 1000]; got 0"),
    ]  # fmt: skip
    for argv, message in cases:
        _one_line(capsys, argv, f"twin: error: {message}")
    with pytest.raises(SignalError, match=r"^max_hz must be in \(0.5, 45\] Hz"):
        diagnose([run], max_hz=100)


def test_a_signal_says_what_is_allowed(capsys, tmp_path, run):
    """A rest duration that is no number or too long, a commands file missing or misnamed."""
    from twin.cli.simulate import signal_help

    sim = ["simulate", "srs", "--model", "reduced", "--quiet", "--out", str(tmp_path / "o"),
           "--signal"]  # fmt: skip
    positive = "the duration must be a positive number of seconds (rest-SECONDS, e.g. rest-60)"
    for name in ("rest-nan", "rest--5", "rest-abc", "rest-inf", "rest-"):
        _one_line(capsys, [*sim, name], f"twin: error: {name}: {positive}; got ")
    _one_line(capsys, [*sim, "rest-1e9"], "twin: error: rest-1e9: a run of 1e+09 s needs about ",
              " s fit here); simulate it in shorter pieces")  # fmt: skip
    missing = tmp_path / "my" / "commands.csv"
    allowed = f"no such file or folder; --signal takes {signal_help()}\n"
    _one_line(capsys, [*sim, str(missing)], f"twin: error: {missing}: {allowed}")
    lab = tmp_path / "cmd.csv"  # any name; the header says the format
    lab.write_text("time_ms,heave_mm\n0,0\n10,1\n", encoding="utf-8")
    _one_line(capsys, [*sim, str(lab)], f"twin: error: {lab}: ", "; a lab's log in other "
              "columns or units: twin import reads it")  # fmt: skip
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cmd.csv"]


def test_a_run_longer_than_memory_is_refused_with_its_size(tmp_path, capsys):
    out = tmp_path / "o"
    argv = [
        "simulate",
        "srs",
        "--model",
        "reduced",
        "--signal",
        "rest-100000000",
        "--out",
        str(out),
    ]
    err = _one_line(capsys, argv, "rest-100000000: a run of 1e+08 s needs about ", "TiB of memory")
    assert "are available" in err and not out.exists()


def test_non_physical_commands_are_refused_before_running(tmp_path, capsys, run):
    commands = tmp_path / "cmd" / "commands.csv"
    commands.parent.mkdir()
    rows = (run / "commands.csv").read_text().splitlines()
    rows[5] = "0.04,0,0,1e300,0,0,0"
    commands.write_text("\n".join(rows) + "\n")
    out = tmp_path / "o"
    argv = ["simulate", "srs", "--model", "reduced", "--signal", str(commands), "--out", str(out)]
    _one_line(capsys, argv, "heave is 1e+300 m at row 5", "within 10 m and 180 deg")
    assert not out.exists()


def test_identify_says_a_run_without_excitation_has_none(tmp_path, capsys):
    from twin.pilot.models.records import write_pilot_csv

    t = np.arange(9000) / 100.0
    zero = np.zeros_like(t)
    f = write_pilot_csv(
        tmp_path / "zero.csv", dict(t=t, ft=zero, fd=zero, e=zero, u=zero, theta=zero)
    )
    _one_line(capsys, ["pilot", "identify", str(f)], "no excitation: ft, fd, e, u, theta constant")


def test_error_line_maps_every_kind_of_failure(monkeypatch):
    line, code = error_line(PermissionError(13, "Permission denied", "/x/y.csv"))
    assert (line, code) == ("twin: error: /x/y.csv: Permission denied", 2)
    line, code = error_line(DataError("a.csv: bad"))
    assert (line, code) == ("twin: error: a.csv: bad", 2)
    assert error_line(MemoryError())[1] == 2 and "not enough memory" in error_line(MemoryError())[0]
    assert error_line(KeyboardInterrupt()) == ("twin: interrupted", 130)
    line, code = error_line(ZeroDivisionError("division by zero"))
    assert code == EXIT_BUG and line.startswith("twin: internal error: ZeroDivisionError")
    assert "TWIN_DEBUG=1" in line


def test_twin_debug_shows_the_traceback_of_a_bug(monkeypatch):
    import twin.platform.kinematics as kinematics

    def broken(geometry):
        raise ZeroDivisionError("a bug")

    monkeypatch.setattr(kinematics, "workspace", broken)  # a bug under the command
    assert main(["workspace", "srs"]) == EXIT_BUG
    monkeypatch.setenv("TWIN_DEBUG", "1")
    with pytest.raises(ZeroDivisionError):
        main(["workspace", "srs"])


def test_a_reader_that_goes_away_ends_the_command_quietly(monkeypatch, capsys):
    """``twin ... | head``: stdout's reader closed early; no error line, exit 141 as a shell
    reports SIGPIPE (before, 'twin: error: Broken pipe')."""

    class Closed:
        def write(self, text: str) -> int:
            raise BrokenPipeError(32, "Broken pipe")

        def flush(self) -> None:
            raise BrokenPipeError(32, "Broken pipe")

    monkeypatch.setattr("sys.stdout", Closed())
    assert main(["pilot", "lead", "srs"]) == EXIT_BROKEN_PIPE == 141
    assert capsys.readouterr().err == ""


def test_the_command_line_bounds_are_the_library_bounds():
    """The parser keeps its own copies (it must not import the heavy modules)."""
    from twin.cli import pilot as cli_pilot
    from twin.pilot.models import pitch
    from twin.pilot.studies import montecarlo

    assert cli_pilot.MAX_RUNS == pitch.MAX_RUNS
    assert cli_pilot.MAX_MC_RUNS == montecarlo.MAX_RUNS
    batch = inspect.signature(montecarlo.monte_carlo).parameters["batch"].default
    assert cli_pilot.MC_BATCH == batch


def test_outputs_never_replace_a_users_folder(tmp_path, capsys, monkeypatch, run):
    monkeypatch.chdir(tmp_path)
    mine = tmp_path / "mydocs"
    mine.mkdir()
    (mine / "thesis.txt").write_text("mine")
    sim = ["simulate", "srs", "--model", "reduced", "--signal", "rest-1", "--quiet"]
    for argv in (
        [*sim, "--out", "mydocs", "--overwrite"],
        [*sim, "--out", ".", "--overwrite"],
        ["agard", "noise", str(run), "--out", "mydocs"],
        ["agard", "noise", str(run), "--out", "."],
        ["agard", "noise", str(run), "--out", str(run)],
    ):
        _one_line(capsys, argv, "give a new folder")
    assert (mine / "thesis.txt").read_text() == "mine" and (run / "meta.json").is_file()
    (tmp_path / "link").symlink_to(mine)
    _one_line(capsys, [*sim, "--out", "link", "--overwrite"], "is a symbolic link")
    _one_line(
        capsys, [*sim, "--out", "r", "--rrd", "r/x.rrd"], "must not lie inside the output folder"
    )
    assert sorted(p.name for p in tmp_path.iterdir()) == ["link", "mydocs"]
