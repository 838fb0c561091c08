"""Recorded runs without a test design in their meta.json, written here by hand (not by the
twin's writer): the excited lines and window are inferred from the commands, and files that do
not belong together are refused."""

import json
from pathlib import Path

import numpy as np
import pytest

from twin.agard.df import analyse_df
from twin.chain.config import motion_system
from twin.chain.signals import describing_signal
from twin.core.errors import RunFormatError, SignalError
from twin.measurement.measure import Bench, from_run
from twin.measurement.periodic import periodic_design

G = 9.80665
LINES = (0.25, 0.65, 1.35, 2.3, 3.35)  # equal position amplitudes: 0.25 Hz is weak in acceleration


def pitch(t, freqs=LINES, duration=60.0, fade=2.0, amp_deg=3.0):
    """Equal-amplitude pitch sines with smoothstep fades (not the twin's Eq 3.1 fades)."""
    t = np.asarray(t, dtype=float)
    s = sum(np.sin(2 * np.pi * f * t + i) for i, f in enumerate(freqs)) / len(freqs)
    w = np.clip(t / fade, 0, 1) * np.clip((duration - t) / fade, 0, 1)
    return np.radians(amp_deg) * s * w * w * (3 - 2 * w)


def write_run(
    folder: Path,
    command=pitch,
    cmd_rate=50.0,
    imu_rate=400.0,
    delay=0.060,
    cmd_span=(0.0, 60.0),
    imu_span=(0.0, 60.0),
    signal=None,
    seed=0,
) -> Path:
    """A twin-run/1 folder of an SRS pitch test with a pure delay, IMU noise of 0.01 m/s^2."""
    rng = np.random.default_rng(seed)
    folder.mkdir(parents=True)
    tc = np.arange(*cmd_span, 1 / cmd_rate)
    cmd = np.zeros((tc.size, 7))
    cmd[:, 0], cmd[:, 5] = tc, command(tc)
    np.savetxt(folder / "commands.csv", cmd, delimiter=",", header="t,x,y,z,roll,pitch,yaw",
               comments="", fmt="%.9g")  # fmt: skip
    ti = np.arange(*imu_span, 1 / imu_rate)
    th = command(ti - delay)
    h = 1e-4
    q = (command(ti - delay + h) - command(ti - delay - h)) / (2 * h)
    imu = np.zeros((ti.size, 7))
    imu[:, 0] = ti
    imu[:, 1] = G * np.sin(th) + 0.01 * rng.standard_normal(ti.size)
    imu[:, 3] = -G * np.cos(th) + 0.01 * rng.standard_normal(ti.size)
    imu[:, 5] = q + 0.001 * rng.standard_normal(ti.size)
    np.savetxt(folder / "imu.csv", imu, delimiter=",", header="t,ax,ay,az,p,q,r", comments="",
               fmt="%.9g")  # fmt: skip
    meta = {"format": "twin-run/1", "platform": "srs", "command_rate_hz": cmd_rate,
            "platform_config": {"filter_break_hz": None, "delay_s": 0.025, "noise": False},
            "imu": {"position_m": [0, 0, 0], "rate_hz": imu_rate}}  # fmt: skip
    if signal is not None:
        meta["signal"] = signal
    (folder / "meta.json").write_text(json.dumps(meta))
    return folder


@pytest.mark.parametrize("cmd_rate,imu_rate", [(50.0, 400.0), (100.0, 819.2)])
def test_every_line_of_a_hand_made_run_is_found_and_no_image(tmp_path, cmd_rate, imu_rate):
    """The lines are the commands' own: the weak-in-acceleration 0.25 Hz line is kept, and the
    image of the 50 Hz command rate (50 - 3.35 Hz in the spline's acceleration) is no line;
    the delay the data hold (60 ms) is measured."""
    r = analyse_df(from_run(write_run(tmp_path / "run", cmd_rate=cmd_rate, imu_rate=imu_rate)))
    assert np.allclose(r.frequencies_hz, LINES, atol=1e-3)
    assert r.delay_s == pytest.approx(0.060, abs=1e-3)


def test_the_inferred_design_of_table_5_2_signal_1_has_its_0_1_hz_line():
    """Table 5.2's multi-sine 1 (0.1-3.35 Hz) on the twin, without its design in the meta:
    all five lines, over a window of whole 20 s periods clear of the 10 s fades."""
    d = describing_signal(1, "pitch")
    bench = Bench(motion_system("srs"), "reduced")
    m = bench.measure(bench.prepare(d.commands).collect(), {})
    f, (start, end) = periodic_design(m, 4)
    assert np.allclose(f, d.frequencies_hz, rtol=1e-4)
    assert end - start == pytest.approx(20.0, rel=1e-4)
    assert start >= m.t[0] + 10.0 - 0.02 and end <= m.t[-1] - 10.0 + 0.02


def test_a_signal_that_is_no_multisine_is_refused(tmp_path):
    """A chirp has no lines that explain it: refused, saying to give the design."""

    def chirp(t):
        t = np.asarray(t, dtype=float)
        w = np.clip(np.minimum(t, 60.0 - t) / 2, 0, 1)
        return np.radians(2.0) * w * np.sin(2 * np.pi * (0.1 * t + 0.02 * t**2))

    with pytest.raises(SignalError, match=r"explain only \d+ % .*\(signal\.frequencies_hz"):
        analyse_df(from_run(write_run(tmp_path / "run", command=chirp)))


def test_commands_cut_short_are_refused(tmp_path):
    """Commands that end mid-motion while the IMU goes on (the same test, a file cut)."""
    folder = write_run(tmp_path / "run", cmd_span=(0.0, 30.0))
    with pytest.raises(
        RunFormatError,
        match=r"commands\.csv ends early: the commands cover 0-29\.98 s .* IMU moves as much",
    ):
        from_run(folder)


def test_an_imu_record_cut_short_is_refused(tmp_path):
    folder = write_run(tmp_path / "run", imu_span=(0.0, 30.0))
    with pytest.raises(
        RunFormatError, match=r"imu\.csv ends early: .* the commands move outside the IMU record"
    ):
        from_run(folder)


def test_an_imu_logged_beyond_commands_at_rest_is_measured_where_both_are(tmp_path):
    """The recorder logs the IMU 5 s before and after the commands, the platform at rest: the
    measurement keeps the commands' span and finds the lines and the delay."""
    folder = write_run(tmp_path / "run", cmd_span=(5.0, 65.0), imu_span=(0.0, 70.0),
                       command=lambda t: pitch(np.asarray(t) - 5.0))  # fmt: skip
    m = from_run(folder)
    assert m.t[0] >= 5.0 - 1e-9 and m.t[-1] <= 65.0
    r = analyse_df(m)
    assert np.allclose(r.frequencies_hz, LINES, atol=1e-3)
    assert r.delay_s == pytest.approx(0.060, abs=1e-3)


def test_a_design_window_beyond_the_files_is_refused(tmp_path):
    folder = write_run(tmp_path / "run", signal={"frequencies_hz": [0.25], "window_s": [40, 80]})
    with pytest.raises(RunFormatError, match=r"window_s \[40, 80\] s is not covered"):
        from_run(folder)
