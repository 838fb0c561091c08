"""Plausibility of recorded runs: garbage in a well-formed ``twin-run/1`` folder is refused.

Each broken run is a valid simulated run (the SRS on the reduced model: quick) transformed
as a lab's logger could have written it: the IMU in g, logging z up, gyro and accelerometer
columns swapped, gyros in deg/s, one axis negated, 0.5 s off the commands' clock, another
run's IMU, all zeros or one dead axis, a 20 kHz or a 50 Hz IMU; and the same run given
twice. Before these checks every one of them was read without a word (and diagnosed: causes
at the search bounds, "VAF -inf", limits that shrink). Now the reader refuses each with one
line saying what is implausible and how to fix it, and every command inherits that; the
twin's own runs (any DOF, both platforms and models, noisy or ideal IMU) still pass.
"""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import numpy as np
import pytest
from scipy import signal

import twin.formats.run_checks as checks
from twin.chain.config import motion_system
from twin.chain.extensions import Extension
from twin.chain.imu import G
from twin.chain.signals import MultiSine, periodic_signal, rest
from twin.chain.simulate import default_imu, prepare
from twin.cli.main import main
from twin.core.errors import DataError, RunFormatError
from twin.core.frames import DOF_NAMES
from twin.diagnose.diagnosis import diagnose
from twin.formats.run_checks import read_plausible_run
from twin.formats.run_folder import execute, run_meta
from twin.formats.runs import read_run
from twin.ingest import import_run
from twin.measurement.describing_function import fourier_coefficients
from twin.measurement.measure import from_run

IMU_HEADER = "t,ax,ay,az,p,q,r"


def _simulate(out: Path, signal_name: str, seed: int) -> Path:
    assert main(["simulate", "srs", "--model", "reduced", "--signal", signal_name, "--seed",
                 str(seed), "--out", str(out), "--quiet"]) == 0  # fmt: skip
    return out


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """Two valid pitch runs of the SRS (Table 5.2 multi-sines 1 and 2, reduced model)."""
    root = tmp_path_factory.mktemp("valid")
    return (_simulate(root / "pitch1", "multisine1-pitch", 1),
            _simulate(root / "pitch2", "multisine2-pitch", 2))  # fmt: skip


def _imu(run: Path) -> np.ndarray:
    return np.loadtxt(run / "imu.csv", delimiter=",", skiprows=1)


def _with_imu(src: Path, dst: Path, rows: np.ndarray, rate_hz: float | None = None) -> Path:
    """A copy of run ``src`` whose imu.csv holds ``rows`` (t and six channels)."""
    shutil.copytree(src, dst)
    np.savetxt(dst / "imu.csv", rows, delimiter=",", fmt="%.10g", header=IMU_HEADER, comments="")
    if rate_hz is not None:
        meta = json.loads((dst / "meta.json").read_text())
        meta["imu"]["rate_hz"] = rate_hz
        (dst / "meta.json").write_text(json.dumps(meta))
    return dst


def _scaled(k: np.ndarray):
    return lambda t, v: (t, v * k)


#: name -> (what is done to the IMU's times and values, what the refusal must say)
BROKEN = {
    "imu in g": (_scaled(np.array([1 / G] * 3 + [1.0] * 3)), "gravity as 1: in g"),
    "imu logs z up": (_scaled(np.array([1, -1, -1, 1, -1, -1.0])), "the IMU logs z up"),
    "gyro and accelerometer swapped": (lambda t, v: (t, v[:, [3, 4, 5, 0, 1, 2]]),
                                       "accelerometer and gyro columns are swapped"),
    "gyros in deg/s": (_scaled(np.array([1.0] * 3 + [np.degrees(1.0)] * 3)), "not rad/s"),
    "q negated": (_scaled(np.array([1, 1, 1, 1, -1, 1.0])), "q moves against the commands"),
    "imu 0.5 s late": (lambda t, v: (t + 0.5, v), "follows the commands 0.50 s late"),
    "imu 0.5 s early": (lambda t, v: (t - 0.5, v), "follows the commands 0.50 s early"),
    "all-zero imu": (lambda t, v: (t, 0 * v), "every channel is constant"),
    "p dead": (lambda t, v: (t, v * [1, 1, 1, 0, 1, 1]),
               "p stays constant (p = 0 throughout) while the sensor's other axes read noise"),
}  # fmt: skip


def _one_error_line(capsys: pytest.CaptureFixture[str]) -> str:
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
    assert len(err) == 1 and err[0].startswith("twin: error: "), err
    return err[0]


@pytest.mark.parametrize("case", list(BROKEN))
def test_an_implausible_run_is_refused_in_one_line(runs, tmp_path, capsys, case) -> None:
    """Read without a word before; now refused by the reader, named, and by the CLI in one
    line with exit 2 (``twin diagnose`` here: no diagnosis starts)."""
    damage, message = BROKEN[case]
    imu = _imu(runs[0])
    t, v = damage(imu[:, 0], imu[:, 1:])
    bad = _with_imu(runs[0], tmp_path / "bad", np.column_stack([t, v]))
    with pytest.raises(RunFormatError, match=re.escape(message)) as e:
        read_plausible_run(bad)
    assert str(e.value).startswith(f"{bad}/imu.csv: ")
    out = tmp_path / "report"
    code = main(["diagnose", str(bad), "--out", str(out), "--no-figures", "--quiet"])
    assert code == 2 and not out.exists()
    assert message in _one_error_line(capsys)


def test_another_runs_imu_is_refused(runs, tmp_path) -> None:
    """Multi-sine 1's commands with multi-sine 2's IMU (same DOF, same length): the IMU
    follows no lag of the commands."""
    other = _imu(runs[1])
    n = min(len(other), len(_imu(runs[0])))
    bad = _with_imu(runs[0], tmp_path / "bad", other[:n])
    with pytest.raises(RunFormatError, match="the IMU does not follow the commands"):
        read_plausible_run(bad)


def _line(run, window: tuple[float, float], f: list[float]) -> np.ndarray:
    """Describing function (measured / commanded pitch acceleration) at ``f`` [Hz]."""
    m = from_run(run)
    x = fourier_coefficients(m.t, m.measured[:, 4], f, window)
    return x / fourier_coefficients(m.t, m.commanded[:, 4], f, window)


def test_a_20_khz_imu_is_resampled_with_a_note(tmp_path) -> None:
    """A 15 s pitch run (0.2 and 1.4 Hz) with its IMU upsampled to 20 kHz: read as it is, the
    App. C.2.3 FIR (201 taps) let the noise alias and the describing function came out 1.3 dB
    and 22 deg wrong at 0.2 Hz; the reader now resamples it to 819.2 Hz, says so, and the
    describing function is the original's (within 0.01 dB, 0.1 deg)."""
    sig = periodic_signal(MultiSine(np.array([0.2, 1.4]), np.array([0.2, 0.5])), "pitch",
                          settle_s=0.0, window_s=5.0)  # fmt: skip
    (tmp_path / "cmd").mkdir()
    c = sig.commands
    np.savetxt(tmp_path / "cmd" / "commands.csv", np.column_stack([c.t, c.values]), delimiter=",",
               fmt="%.10g", header="t,x,y,z,roll,pitch,yaw", comments="")  # fmt: skip
    run = _simulate(tmp_path / "run", str(tmp_path / "cmd" / "commands.csv"), 3)
    imu = _imu(run)
    up = signal.resample_poly(imu[:, 1:], 3125, 128, axis=0, padtype="line")  # 819.2 -> 20 kHz
    t = imu[0, 0] + np.arange(len(up)) / 20_000.0
    keep = t <= imu[-1, 0]
    fast = _with_imu(run, tmp_path / "fast", np.column_stack([t[keep], up[keep]]), 20_000.0)
    rec = read_plausible_run(fast)
    assert rec.meta["imu"]["rate_hz"] == pytest.approx(819.2)
    assert len(rec.notes) == 1 and "sampled at 20000 Hz" in rec.notes[0]
    assert "resampled to 819.2 Hz" in rec.notes[0]
    ratio = _line(rec, sig.window, [0.2, 1.4]) / _line(
        read_plausible_run(run), sig.window, [0.2, 1.4]
    )
    assert np.all(np.abs(20 * np.log10(np.abs(ratio))) < 0.01)
    assert np.all(np.abs(np.degrees(np.angle(ratio))) < 0.1)


def test_an_imu_slower_than_the_analysis_grid_is_refused(runs, tmp_path) -> None:
    """Every 16th sample: 51.2 Hz, below the 100 Hz grid the analyses put the IMU on."""
    bad = _with_imu(runs[0], tmp_path / "bad", _imu(runs[0])[::16], 819.2 / 16)
    with pytest.raises(RunFormatError, match=r"sampled at 51.2 Hz, below the 100 Hz"):
        read_plausible_run(bad)


def test_imu_axes_that_gravity_contradicts_are_refused(runs, tmp_path, capsys) -> None:
    """A lab log whose IMU reads gravity z down, imported with ``--imu-axes flu``: obeyed
    (and every axis turned) before; now refused, naming the axes gravity implies."""
    rec = read_plausible_run(runs[0])
    first = rec.imu_t < 15.0  # the first 15 s: a quick import
    pitch = np.degrees(rec.commands.at(rec.imu_t[first])[:, 4])
    log = tmp_path / "log.csv"
    np.savetxt(log, np.column_stack([rec.imu_t[first], pitch, rec.imu[first]]), delimiter=",",
               fmt="%.8g", header="time_s,pitch_deg,ax,ay,az,p,q,r", comments="")  # fmt: skip
    with pytest.raises(DataError, match=r"--imu-axes flu, but gravity reads az -9.8\d m/s\^2 at "
                       r"rest, which is z down \(frd\)"):  # fmt: skip
        import_run([log], tmp_path / "flu", platform="srs", imu_axes="flu")
    out = tmp_path / "out"
    code = main(["import", str(log), "--platform", "srs", "--imu-axes", "flu", "--out", str(out),
                 "--quiet"])  # fmt: skip
    assert code == 2 and not out.exists()
    assert "--imu-axes frd" in _one_error_line(capsys)
    import_run([log], tmp_path / "frd", platform="srs", imu_axes="frd")  # what gravity says
    assert read_plausible_run(tmp_path / "frd").imu[:, 2].mean() == pytest.approx(-G, abs=0.05)


def _twin_run(out: Path, platform: str, dof: str, model: str, ideal: bool, seed: int) -> Path:
    """A short run of the twin (fade, 4 s window, fade) driving one DOF."""
    acc = 0.3 if dof in ("surge", "sway", "heave") else 0.2
    sig = periodic_signal(MultiSine(np.array([0.5, 1.25, 3.0]), np.full(3, acc)), dof,
                          settle_s=0.0, window_s=4.0)  # fmt: skip
    imu = default_imu(platform)
    run = prepare(platform, sig.commands, model, seed, imu.ideal() if ideal else imu)
    execute(run, run_meta(run, f"{dof} check run", signal=sig), out)
    return out


@pytest.mark.parametrize("dof", DOF_NAMES)
def test_the_twins_own_runs_pass(tmp_path, dof) -> None:
    """No false alarm: every DOF on both platforms (reduced model), with the data sheet's
    noise and with an ideal IMU (no noise, yet nothing constant where it moves)."""
    for k, (platform, ideal) in enumerate([("mpi", False), ("srs", True)]):
        rec = read_plausible_run(_twin_run(tmp_path / f"{k}", platform, dof, "reduced", ideal, k))
        assert rec.notes == ()


def test_the_full_models_runs_and_rest_pass(tmp_path) -> None:
    """The full (MuJoCo) model's heave noise and dynamics, and a rest run of an ideal IMU
    (every channel constant: nothing commanded moves, gravity reads -9.81)."""
    assert (
        read_plausible_run(_twin_run(tmp_path / "full", "mpi", "pitch", "full", False, 7)).notes
        == ()
    )
    run = prepare("srs", rest(3.0), "reduced", 0, default_imu("srs").ideal())
    execute(run, run_meta(run, "rest"), tmp_path / "rest")
    rec = read_plausible_run(tmp_path / "rest")
    assert np.ptp(rec.imu, axis=0).max() == 0.0 and rec.notes == ()


def test_the_same_run_twice_is_refused(runs, tmp_path, capsys) -> None:
    """The same folder twice, a copy of it, or a run also given for validation: refused
    before any work (it would count twice, and the detection limits would shrink)."""
    copy = tmp_path / "copy"
    shutil.copytree(runs[0], copy)
    with pytest.raises(RunFormatError, match=r"given twice \(the same folder as"):
        diagnose([runs[0], runs[0]])
    with pytest.raises(RunFormatError, match=r"given twice \(the same commands and IMU as"):
        diagnose([runs[0], copy])
    with pytest.raises(RunFormatError, match="given twice"):
        diagnose([runs[0], runs[1]], validate=[copy])
    out = tmp_path / "report"
    code = main(["diagnose", str(runs[0]), str(copy), "--out", str(out), "--no-figures", "--quiet"])
    assert code == 2 and not out.exists()
    assert "given twice" in _one_error_line(capsys)


def test_a_fit_at_its_search_bound_is_no_finding(tmp_path, monkeypatch, capsys) -> None:
    """Pitch responding at 5 % of the commands (a gain below the search's 0.1): the gain
    fitted at 0.1 was named a finding; now it is reported "at the bound" in the terminal,
    the summary and the JSON, and nothing is named. (The search is restricted to gain to
    keep the test quick.)"""
    from twin.diagnose import diagnosis
    from twin.diagnose.hidden import record_runs

    monkeypatch.setattr(diagnosis, "DYNAMIC", ("gain",))
    srs = motion_system("srs")
    truth = srs.replace(extensions=(Extension("gain", {"gain": 0.05}, ("pitch",)),))
    run = record_runs(truth, srs, "pitch", tmp_path, 5, signals=(1,))[0]
    out = tmp_path / "report"
    assert main(["diagnose", str(run), "--out", str(out), "--no-figures", "--quiet"]) == 0
    terminal = capsys.readouterr().out
    assert "at the bound: gain in pitch: gain 0.1 at the lower bound of its search (0.1 to 10)" in (
        terminal
    )
    assert "not a finding" in terminal and "no finding within the search bounds" in terminal
    doc = json.loads((out / "diagnosis.json").read_text())
    assert doc["findings"] == [] and doc["extended_config"]["extensions"] == []
    [entry] = doc["at_bound"]
    assert (entry["effect"], entry["parameter"], entry["bound"]) == ("gain", "gain", "lower")
    assert entry["value"] == pytest.approx(0.1) and entry["search"] == [0.1, 10.0]
    assert doc["nominal"]["dofs"]["pitch"]["at_bound"][0]["effect"] == "gain"
    summary = (out / "summary.md").read_text()
    assert "## At the bound (not findings)" in summary
    assert "- gain in pitch: gain 0.1 at the lower bound" in summary


def test_a_run_is_checked_once(runs, monkeypatch) -> None:
    """The analyses hand each other runs already checked: they are not checked again."""
    calls = []
    original = checks.check_plausible
    monkeypatch.setattr(checks, "check_plausible", lambda r: calls.append(r) or original(r))
    raw = read_run(runs[0])
    assert not raw.plausible
    once = read_plausible_run(raw)
    assert once.plausible and len(calls) == 1
    assert read_plausible_run(once) is once and len(calls) == 1
