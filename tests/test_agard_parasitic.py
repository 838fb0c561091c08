"""The AGARD-AR-144 parasitic-motion test (twin.agard.parasitic).

Expected values are written out here: the tilt of a pitching cabin is g theta (theta =
-A / omega^2 for an acceleration sine of amplitude A), and an IMU yawed by psi reads
Rz(psi)^T of the cabin's vectors, (a cos psi, -a sin psi, 0) for a surge a and (q sin psi,
q cos psi, 0) for a pitch rate q (tests/test_imu_alignment.py spells these out by hand).
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from twin.agard.parasitic import (
    ABOVE_NOISE_DB,
    Segment,
    analyse_parasitic,
    analyse_segments,
    run_parasitic,
)
from twin.agard.session import Session
from twin.chain.extensions import Extension
from twin.chain.signals import single_sine
from twin.chain.simulate import default_imu
from twin.core.errors import SignalError
from twin.core.frames import DOF_NAMES
from twin.diagnose.physical_vocabulary import PhysicalCause, configured
from twin.measurement.measure import Bench, configure

G = 9.81
F_HZ, AMPLITUDE = 0.5, 0.3  # the module's default sine


@pytest.fixture(scope="module")
def reduced_nominal():
    """All six DOFs on the reduced SRS with its ADIS16355 (noise on)."""
    return run_parasitic(Session(Bench(configure("srs"), "reduced")))


def test_reduced_model_has_no_parasitic_motion_above_noise(reduced_nominal):
    """Eq 5.11 drives each DOF on its own, so with the tilt removed every off-diagonal cell is
    IMU noise: no coupling 10 dB above its floor, rms within 20 % of the noise rms."""
    r = reduced_nominal
    assert r.dofs == DOF_NAMES
    for d in DOF_NAMES:
        for m in DOF_NAMES:
            c = r.cells[d][m]
            if m == d:
                assert c.coupling_mean == pytest.approx(1.0, abs=0.05)  # DF gain at 0.5 Hz
                assert c.rms_over_noise > 2.0  # 0.21 rms of the sine over <= 0.095 of noise
                continue
            assert not c.above_noise, (d, m, c)
            assert c.rms_over_noise == pytest.approx(1.0, abs=0.2), (d, m, c)
            assert c.peak < 6 * c.noise_rms


def test_tilt_of_the_driven_pitch_and_roll_is_g_over_omega_squared(reduced_nominal):
    """A sine A sin(w t) in pitch is theta = -A / w^2 sin(w t): surge reads g theta, a coupling
    g / w^2 times the pitch's DF gain (0.994 at 0.5 Hz); roll reads -g phi in sway. That is
    what was removed; what is left is at noise level."""
    r = reduced_nominal
    textbook = G / (2 * np.pi * F_HZ) ** 2
    for d, m in (("pitch", "surge"), ("roll", "sway")):
        c = r.cells[d][m]
        assert c.tilt == pytest.approx(textbook * r.cells[d][d].coupling_mean, rel=0.01)
        assert c.coupling_mean < 0.05 * c.tilt
    assert r.cells["surge"]["sway"].tilt == 0.0


def test_tilt_kept_shows_as_coupling(reduced_nominal):
    """Without removal the pitch's tilt is the surge coupling itself (g / w^2 = 0.994)."""
    with Session(Bench(configure("srs"), "reduced")) as s:
        r = run_parasitic(s, dofs=("pitch",), remove_tilt=False)
    assert r.cells["pitch"]["surge"].coupling_mean == pytest.approx(
        G / (2 * np.pi * F_HZ) ** 2, rel=0.02
    )
    assert r.cells["pitch"]["surge"].above_noise


@pytest.mark.slow
def test_full_model_nominal_coupling_is_small():
    """The full MuJoCo SRS: the thesis found its parasitic motion negligible (§5.5). Stated
    bound: every off-diagonal coupling is at noise level (the ADIS16355's floor at 0.3 m/s^2
    reaches 2 % in the translations), or below 2 % between translations, between rotations and
    from a translation into a rotation (rad/s^2 per m/s^2), and below 10 % from a rotation into
    a translation (m/s^2 per rad/s^2); and it never exceeds 10 %."""
    r = run_parasitic(Session(Bench(configure("srs"), "full")))
    for i, d in enumerate(DOF_NAMES):
        for j, m in enumerate(DOF_NAMES):
            if i == j:
                continue
            c = r.cells[d][m]
            bound = 0.10 if (i >= 3 and j < 3) else 0.02
            assert c.coupling_mean < bound or not c.above_noise, (d, m, c)
            assert c.coupling_mean < 0.10, (d, m, c)
    assert r.cells["heave"]["heave"].coupling_mean == pytest.approx(1.0, abs=0.05)


@pytest.mark.parametrize("friction", [(300.0, 1000.0, 3000.0)])
def test_leg_friction_couples_heave_into_rotations_growing_with_its_size(friction):
    """Coulomb friction on leg 1 alone breaks the platform's symmetry: heave then rolls, pitches
    and yaws it. The summed coupling power into roll, pitch and yaw grows with the friction
    at every step, and at 3000 N stands above noise in each of the three (none does without)."""
    base = configure("srs")

    def couplings(cfg):
        with Session(Bench(cfg, "full")) as s:
            r = run_parasitic(s, dofs=("heave",))
        return r.cells["heave"]

    nominal = couplings(base)
    rot = ("roll", "pitch", "yaw")
    assert not any(nominal[m].above_noise for m in rot)
    sizes = []
    for n in friction:
        cells = couplings(configured(base, PhysicalCause("leg", {"leg": 1, "coulomb_n": n})))
        sizes.append(np.sqrt(sum(cells[m].coupling_mean ** 2 for m in rot)))
    total0 = np.sqrt(sum(nominal[m].coupling_mean ** 2 for m in rot))
    assert total0 < sizes[0] < sizes[1] < sizes[2]
    assert all(cells[m].above_noise for m in rot)
    assert sizes[2] > 4 * total0


def test_a_yawed_imu_gives_cross_coupling_sin_psi():
    """An IMU yawed by psi reads -a sin psi in sway while surging and q sin psi in roll while
    pitching: coupling sin psi times the driven DOF's gain, and cos psi on the diagonal (ideal
    IMU: no noise, so the tolerance is the model's, 0.5 %)."""
    psi = 0.05
    cfg = configure("srs")
    cfg = cfg.replace(extensions=(*cfg.extensions, Extension(
        "imu_alignment", {"roll_rad": 0.0, "pitch_rad": 0.0, "yaw_rad": psi})))  # fmt: skip
    reference = run_parasitic(Session(Bench(configure("srs"), "reduced",
                                            imu=default_imu("srs").ideal())),
                              dofs=("surge", "pitch"))  # fmt: skip
    r = run_parasitic(Session(Bench(cfg, "reduced", imu=default_imu("srs").ideal())),
                      dofs=("surge", "pitch"))  # fmt: skip
    for d, m in (("surge", "sway"), ("pitch", "roll")):
        gain = reference.cells[d][d].coupling_mean
        assert r.cells[d][m].coupling_mean == pytest.approx(np.sin(psi) * gain, rel=0.005)
        assert r.cells[d][d].coupling_mean == pytest.approx(np.cos(psi) * gain, rel=0.005)
        assert reference.cells[d][m].coupling_mean < 1e-3 * np.sin(psi)


def test_a_yawed_imu_with_noise_stands_above_it():
    """With the ADIS16355's noise a 0.1 rad mount gives sin psi = 10.0 % within three noise
    floors, and above noise (0.05 rad, 5 %, stands only about 9 dB above a 2 % floor)."""
    psi = 0.1
    cfg = configure("srs")
    cfg = cfg.replace(extensions=(*cfg.extensions, Extension(
        "imu_alignment", {"roll_rad": 0.0, "pitch_rad": 0.0, "yaw_rad": psi})))  # fmt: skip
    r = run_parasitic(Session(Bench(cfg, "reduced")), dofs=("surge",))
    c = r.cells["surge"]["sway"]
    assert c.above_noise
    assert c.coupling_mean == pytest.approx(np.sin(psi), abs=3 * c.coupling_noise)


def _long_run():
    """One run: 5 s at rest, then two single sines of surge one after the other (a schedule)."""
    from twin.chain.trajectory import Trajectory

    bench = Bench(configure("srs"), "reduced")
    a = single_sine("surge", 0.5, AMPLITUDE, window_s=10.0)
    b = single_sine("surge", 1.0, AMPLITUDE, window_s=10.0)
    values = np.vstack([np.zeros((500, 6)), a.commands.values, b.commands.values[1:]])
    shift_a, shift_b = 5.0, 5.0 + a.commands.duration
    m = bench.measure(bench.prepare(Trajectory(100.0, values)).collect())
    wa = (a.window[0] + shift_a, a.window[1] + shift_a)
    wb = (b.window[0] + shift_b, b.window[1] + shift_b)
    return m, wa, wb


def test_segments_of_one_long_run_with_a_rest_record():
    """Two surge sines inside one run, analysed as two segments of one driven DOF, with the
    run's first seconds at rest as the noise reference: both segments' lines are reported, the
    surge gain is about 1 at both, the undriven rms equals the rest rms within 20 % and no
    coupling stands above noise."""
    m, wa, wb = _long_run()
    r = analyse_segments(
        {"surge": [Segment(m, wa, (0.5,)), Segment(m, wb, (1.0,))]}, rest=[(m, (0.5, 4.5))]
    )
    assert r.noise_basis == "rest record"
    assert r.frequencies_hz["surge"].tolist() == [0.5, 1.0]
    assert r.cells["surge"]["surge"].coupling_mean == pytest.approx(1.0, abs=0.05)
    for d in DOF_NAMES[1:]:
        c = r.cells["surge"][d]
        assert c.rms_over_noise == pytest.approx(1.0, abs=0.2), (d, c)
        assert not c.above_noise, (d, c)
    json.dumps(r.to_dict())
    assert "rest record" in r.format_table()


def test_run_folder_style_analysis_and_outputs(tmp_path):
    """analyse_parasitic on a session's run (design from its meta), to_dict JSON, a figure."""
    with Session(Bench(configure("srs"), "reduced"), out=tmp_path) as s:
        sig = single_sine("roll", 0.5, AMPLITUDE, window_s=20.0)
        m = s.measure(sig, "roll")
    r = analyse_parasitic(m)
    assert r.dofs == ("roll",)
    d = json.loads(json.dumps(r.to_dict()))
    assert d["cells"]["roll"]["sway"]["tilt"] > 0.9
    assert d["above_noise_db"] == ABOVE_NOISE_DB
    table = r.format_table()
    assert "roll" in table and "~" in table
    fig = r.plot(path=str(tmp_path / "parasitic.png"))
    assert (tmp_path / "parasitic.png").stat().st_size > 1000
    assert fig.axes


# --- bad input -----------------------------------------------------------------------------------


def _one_run():
    bench = Bench(configure("srs"), "reduced")
    sig = single_sine("surge", 0.5, AMPLITUDE, window_s=10.0)
    return bench.measure(bench.prepare(sig.commands).collect()), sig


def test_unknown_dof_is_refused():
    with pytest.raises(SignalError, match=r"unknown DOF 'swing'.*surge, sway, heave"):
        run_parasitic(Session(Bench(configure("srs"), "reduced")), dofs=("swing",))
    m, sig = _one_run()
    with pytest.raises(SignalError, match="unknown DOF 'x'"):
        analyse_segments({"x": [Segment(m, sig.window, (0.5,))]})
    with pytest.raises(SignalError, match="driven once"):
        run_parasitic(Session(Bench(configure("srs"), "reduced")), dofs=("surge", "surge"))


def test_window_outside_the_run_is_refused():
    m, _ = _one_run()
    end = float(m.t[-1])
    with pytest.raises(SignalError, match=r"outside the run .*within the measurement"):
        analyse_segments({"surge": [Segment(m, (end - 4.0, end + 6.0), (0.5,))]})
    with pytest.raises(SignalError, match="start < end"):
        analyse_segments({"surge": [Segment(m, (10.0, 5.0), (0.5,))]})


def test_window_without_whole_periods_or_unexcited_lines_is_refused():
    m, sig = _one_run()
    w = sig.window
    with pytest.raises(SignalError, match="whole number of periods"):
        analyse_segments({"surge": [Segment(m, (w[0], w[1] - 0.3), (0.5,))]})
    with pytest.raises(SignalError, match="do not excite"):
        analyse_segments({"surge": [Segment(m, w, (0.5, 1.5))]})
    with pytest.raises(SignalError, match="do not excite"):
        analyse_segments({"sway": [Segment(m, w, (0.5,))]})
    with pytest.raises(SignalError, match="Nyquist"):
        analyse_segments({"surge": [Segment(m, w, (60.0,))]})
    with pytest.raises(SignalError, match="no segment"):
        analyse_segments({"surge": []})


def test_other_bad_arguments_are_refused():
    s = Session(Bench(configure("srs"), "reduced"))
    with pytest.raises(SignalError, match=r"unknown parasitic signal 'chirp'.*sine, multisine1"):
        run_parasitic(s, dofs=("surge",), signal="chirp")
    with pytest.raises(SignalError, match="amplitude must be one positive number"):
        run_parasitic(s, dofs=("surge", "sway"), amplitude=(0.3, -1.0))
    with pytest.raises(SignalError, match="no bins free"):
        run_parasitic(s, dofs=("surge",), signal="multisine1")
