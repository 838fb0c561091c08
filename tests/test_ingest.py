"""``twin import``: measured logs as labs write them -> ``twin-run/1``.

The logs are written here by a small "lab logger" (independent of the importer): a simulated
run with a hidden extra delay and an IMU mounted off the UGP, written with other column names
and units, jittery or irregular stamps, an IMU on its own clock and logging z up. The import
must recover what the logger did (clock offset, mount, units) and say what it cannot tell.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from twin.chain.config import motion_system
from twin.chain.imu import G, ImuSpec
from twin.chain.simulate import default_imu
from twin.cli.main import main
from twin.core.errors import DataError, UsageError
from twin.diagnose.data import load_case
from twin.diagnose.hidden import record_runs
from twin.formats.runs import read_run
from twin.ingest import import_run
from twin.ingest.columns import split_unit, target_of
from twin.ingest.timebase import regularise

EXTRA_DELAY_S = 0.030
MOUNT = (0.12, -0.05, -0.30)
EPOCH = 1234.5  # IMU clock minus command clock [s]


@pytest.fixture(scope="module")
def truth_run(tmp_path_factory) -> Path:
    """A pitch multi-sine on the MPI with 30 ms more delay, IMU at MOUNT (simulated once)."""
    nominal = motion_system("mpi")
    truth = nominal.override(None, 1e3 * (nominal.delay_s + EXTRA_DELAY_S), None, None)
    spec = default_imu("mpi")
    imu = ImuSpec(MOUNT, spec.rate_hz, spec.accel_range, spec.gyro_range)
    out = tmp_path_factory.mktemp("truth")
    return record_runs(truth, nominal, "pitch", out, 3, signals=(1,), with_signal_meta=False,
                       imu=imu)[0]  # fmt: skip


def _write(path: Path, header: list[str], rows: np.ndarray, fmt: str = "%.6f") -> Path:
    np.savetxt(path, rows, delimiter=",", header=",".join(header), comments="", fmt=fmt)
    return path


def lab_logs(run: Path, folder: Path, epoch: float = EPOCH, copy: bool = False,
             z_up: bool = True, seed: int = 1) -> tuple[Path, Path]:  # fmt: skip
    """Write a run as a lab's two loggers would (see module docstring)."""
    rec = read_run(run)
    rng = np.random.default_rng(seed)
    c = rec.commands
    stamps_ms = 1e3 * c.t + rng.normal(0.0, 0.8, c.n)  # software stamps, 0.8 ms jitter
    cmd = _write(folder / "cmd.csv", ["Time [ms]", "heave_mm", "pitch_deg", "roll_deg", "status"],
                 np.column_stack([stamps_ms, 1e3 * c.values[:, 2], np.degrees(c.values[:, 4]),
                                  np.degrees(c.values[:, 3]), np.ones(c.n)]))  # fmt: skip
    # the IMU logger: 250 Hz with irregular sample times, g and deg/s, z up, its own clock
    t = rec.imu_t
    n = int((t[-1] - t[0]) * 250)
    ts = t[0] + np.arange(n) / 250 + rng.uniform(-1.5e-3, 1.5e-3, n)
    v = np.column_stack([np.interp(ts, t, rec.imu[:, j]) for j in range(6)])
    if z_up:
        v[:, [1, 2, 4, 5]] *= -1
    cols = [ts + epoch, *(v[:, :3] / G).T, *np.degrees(v[:, 3:]).T, np.full(n, 25.0)]
    header = ["timestamp", "AccX (g)", "AccY (g)", "AccZ (g)", "GyroX (deg/s)",
              "GyroY (deg/s)", "GyroZ (deg/s)", "temp"]  # fmt: skip
    if copy:  # the IMU logger also records the command it sees (on its clock)
        cols.append(np.degrees(c.at(np.clip(ts, c.t[0], c.t[-1]))[:, 4]))
        header.append("pitch_cmd [deg]")
    imu = _write(folder / "imu.csv", header, np.column_stack(cols))
    return cmd, imu


def test_headers_give_names_and_units() -> None:
    assert split_unit("Time [ms]") == ("Time", "ms")
    assert split_unit("AccZ (g)") == ("AccZ", "g")
    assert split_unit("heave_mm") == ("heave", "mm")
    assert split_unit("gyro_y_deg/s") == ("gyro_y", "deg/s")
    assert split_unit("temp") == ("temp", None)
    assert target_of("AccZ") == ("az", False)
    assert target_of("Gyro-Y") == ("q", False)
    assert target_of("cmd_heave") == ("z", True)
    assert target_of("pitch_setpoint") == ("pitch", True)
    assert target_of("temperature") == (None, False)


def test_jittery_stamps_and_irregular_sampling() -> None:
    rng = np.random.default_rng(0)
    k = np.arange(5000)
    x = np.sin(2 * np.pi * 0.7 * k / 200.0)[:, None]
    jit = regularise(5.0 + k / 200.0 + rng.normal(0, 1e-3, k.size), x, "jit", smooth=True)
    assert jit.how == "jittery stamps" and jit.rate_hz == 200.0
    assert abs(jit.t0 - 5.0) < 1e-4 and np.array_equal(jit.values, x)  # samples kept
    # an irregular logger: samples off the grid by up to 40 % of a step, 5 % dropped
    irregular = (k + rng.uniform(-0.4, 0.4, k.size))[rng.uniform(size=k.size) > 0.05] / 200.0
    reg = regularise(irregular, np.sin(2 * np.pi * 0.7 * irregular)[:, None], "irr", True)
    assert reg.how == "interpolated"
    assert np.max(np.abs(reg.values[:, 0] - np.sin(2 * np.pi * 0.7 * reg.t))) < 1e-4


def test_other_clock_other_units_z_up_off_ugp(truth_run: Path, tmp_path: Path) -> None:
    cmd, imu = lab_logs(truth_run, tmp_path)
    rep = import_run([cmd, imu], tmp_path / "run", platform="mpi")
    # the clocks differ by far more than any delay: the offset is estimated against the nominal
    # twin, so it holds the epoch plus the hidden extra delay, and says delay is then hidden
    assert rep.clock.how == "estimated" and rep.clock.delay_identifiable is False
    assert abs(rep.clock.offset_s - (EPOCH + EXTRA_DELAY_S)) < 0.003
    # mount: x and z show in a pitch run (lever of q-dot), y does not
    x, y, z = rep.mount["position_m"]
    assert abs(x - MOUNT[0]) < 0.03 and abs(z - MOUNT[2]) < 0.03 and y == 0.0
    assert "y not identifiable" in rep.mount["how"]
    assert any("z up" in n for n in rep.notes)
    run = read_run(tmp_path / "run")
    assert run.meta["import"]["clock"]["delay_identifiable"] is False
    assert run.meta["imu"]["position_m"] == rep.mount["position_m"]
    truth = read_run(truth_run)
    np.testing.assert_allclose(run.commands.values, truth.commands.values, atol=2e-5)
    # the imported IMU is the truth's on its clock (the offset's error is the residual)
    t = run.imu_t + EPOCH - rep.clock.offset_s
    q_truth = np.interp(t, truth.imu_t, truth.imu[:, 4])
    assert np.corrcoef(run.imu[:, 4], q_truth)[0, 1] > 0.9
    case = load_case([tmp_path / "run"], realisations=2)
    assert "delay" in case.unidentifiable


def test_given_offset_leaves_the_delay_to_the_diagnosis(truth_run: Path, tmp_path: Path) -> None:
    from twin.diagnose.diagnosis import diagnose

    cmd, imu = lab_logs(truth_run, tmp_path)
    rep = import_run([cmd, imu], tmp_path / "run", platform="mpi", clock_offset_s=EPOCH)
    assert rep.clock.how == "given" and rep.clock.delay_identifiable
    assert abs(rep.clock.apparent_extra_delay_s - EXTRA_DELAY_S) < 0.004
    d = diagnose([tmp_path / "run"])
    assert [f.extension.effect for f in d.findings][:1] == ["delay"]
    assert abs(d.findings[0].extension.value("extra_delay_s") - EXTRA_DELAY_S) < 0.005


def test_command_copy_on_the_imu_clock_tells_offset_from_delay(
    truth_run: Path, tmp_path: Path
) -> None:
    cmd, imu = lab_logs(truth_run, tmp_path, copy=True)
    rep = import_run([cmd, imu], tmp_path / "run", platform="mpi")
    assert rep.clock.how == "measured" and rep.clock.delay_identifiable
    assert abs(rep.clock.offset_s - EPOCH) < 0.002
    assert abs(rep.clock.apparent_extra_delay_s - EXTRA_DELAY_S) < 0.004


@pytest.mark.parametrize(("epoch", "how", "identifiable"),
                         [(0.0, "shared", True), (-0.2, "estimated", False)])  # fmt: skip
def test_overlapping_clocks(truth_run, tmp_path, epoch, how, identifiable) -> None:
    """Times that overlap: one clock unless the IMU would respond before its commands."""
    cmd, imu = lab_logs(truth_run, tmp_path, epoch=epoch, z_up=False)
    rep = import_run([cmd, imu], tmp_path / "run", platform="mpi")
    assert (rep.clock.how, rep.clock.delay_identifiable) == (how, identifiable)
    if how == "shared":  # the extra lag is reported, and why it cannot be told apart
        assert abs(rep.clock.apparent_extra_delay_s - EXTRA_DELAY_S) < 0.004
        assert "cannot tell" in rep.clock.statement
    else:
        assert abs(rep.clock.offset_s - (epoch + EXTRA_DELAY_S)) < 0.003
        assert "before its commands" in rep.clock.statement


def test_one_file_is_one_clock(truth_run: Path, tmp_path: Path) -> None:
    rec = read_run(truth_run)
    t = rec.imu_t
    pose = rec.commands.at(t)
    path = _write(tmp_path / "log.csv", ["t", "z", "pitch", "ax", "ay", "az", "p", "q", "r"],
                  np.column_stack([t, pose[:, 2], pose[:, 4], rec.imu]))  # fmt: skip
    rep = import_run([path], tmp_path / "run", config="mpi")
    assert rep.clock.how == "shared" and rep.clock.offset_s == 0.0
    assert abs(rep.clock.apparent_extra_delay_s - EXTRA_DELAY_S) < 0.004


def _table(tmp_path: Path, header: str, rows: list[str], name: str = "x.csv") -> Path:
    p = tmp_path / name
    p.write_text(header + "\n" + "\n".join(rows) + "\n")
    return p


@pytest.mark.parametrize(
    ("header", "rows", "mapping", "message"),
    [
        ("z,az", ["0,-9.81"] * 40, [], "no time column"),
        ("t,z", [f"{k / 100},0" for k in range(40)], [], "no file has IMU columns"),
        ("t,z,az", [f"{k / 100},0,-9.81" for k in range(40)], ["az=az:furlong"],
         "unknown acceleration unit 'furlong'"),
        ("t,z,ax,az", [f"{k / 100},0,-9.81,0" for k in range(40)], [], "gravity reads"),
        ("t,z,az", [f"{k / 100},0,-9.81" for k in range(20)] + ["0.1,0,-9.81"] * 20, [],
         "the time goes back"),
        ("t,z,az", [f"{k / 100},0,-9.81" for k in range(20)]
         + [f"{1 + k / 100},0,-9.81" for k in range(20)], [], "a gap of"),
        ("t,z,az", [f"{k / 100},0,-9.81" for k in range(39)] + ["0.39,0,abc"], [],
         "'abc' is not a number"),
        ("t,z,az", [f"{k / 100},0,-9.81" for k in range(40)], ["q=gyro_q"], "no column 'gyro_q'"),
        ("t,z,az", [f"{k / 100},0,-9.81" for k in range(40)], ["w=az"], "unknown target 'w'"),
        ("t,z,az", [f"{k / 100},0,-3.0" for k in range(40)], [], "that is 1 g in none of"),
    ],
)  # fmt: skip
def test_what_cannot_be_used_is_named(tmp_path, header, rows, mapping, message) -> None:
    path = _table(tmp_path, header, rows)
    with pytest.raises((DataError, UsageError), match=message):
        import_run([path], tmp_path / "run", platform="mpi", mapping=mapping)
    assert not (tmp_path / "run").exists()


def test_cli_one_line_and_nothing_written(tmp_path: Path, capsys) -> None:
    path = _table(tmp_path, "t,z,ax,az", [f"{k / 100},0,-9.81,0" for k in range(40)])
    assert main(["import", str(path), "--platform", "mpi", "--out", str(tmp_path / "r")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("twin: error:") and "gravity" in err[0]
    assert not (tmp_path / "r").exists()
    assert main(["import", str(path), "--out", str(tmp_path / "r")]) == 2
    assert "platform" in capsys.readouterr().err


def test_cli_json(truth_run: Path, tmp_path: Path, capsys) -> None:
    cmd, imu = lab_logs(truth_run, tmp_path, copy=True)
    out = tmp_path / "run"
    args = ["import", str(cmd), str(imu), "--platform", "mpi", "--out", str(out), "--json",
            "--imu-position", *map(str, MOUNT), "--quiet"]  # fmt: skip
    assert main(args) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["clock"]["how"] == "measured" and doc["mount"]["how"] == "given"
    assert read_run(out).meta["imu"]["position_m"] == list(MOUNT)
    assert main(args) == 2  # exists: not overwritten without --overwrite


@pytest.fixture(scope="module")
def weak_run(tmp_path_factory) -> Path:
    """Heave lines at 10-15 Hz behind the MPI's 1 Hz filter: about 1 % of the command remains."""
    from twin.chain.signals import MultiSine, periodic_signal
    from twin.diagnose.hidden import play

    mpi = motion_system("mpi")
    ms = MultiSine(np.array([10.0, 12.0, 15.0]), np.array([0.5, 0.5, 0.5]))  # within limits
    sig = periodic_signal(ms, "heave", 100.0, None, 20.0, "lines above the filter")
    return play(mpi, mpi, sig, tmp_path_factory.mktemp("weak") / "run", seed=2)


@pytest.mark.parametrize(("epoch", "shared"), [(0.0, True), (EPOCH, False)])
def test_a_response_too_weak_to_align(weak_run, tmp_path, epoch, shared) -> None:
    """Too weak to align with the nominal twin: one clock where the times overlap, else refused."""
    cmd, imu = lab_logs(weak_run, tmp_path, epoch=epoch, z_up=False)
    if shared:
        rep = import_run([cmd, imu], tmp_path / "run", platform="mpi")
        assert (rep.clock.how, rep.clock.offset_s) == ("shared", 0.0)
        assert "too weak against the noise to check it" in rep.clock.statement
    else:  # nothing says the clocks are one: refused, nothing written
        with pytest.raises(DataError, match="do not correlate"):
            import_run([cmd, imu], tmp_path / "run", platform="mpi")
        assert not (tmp_path / "run").exists()
