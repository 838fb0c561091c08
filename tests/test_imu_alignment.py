"""imu_alignment: the IMU mounted with its axes rotated on the cabin (cross-axis leakage).

Every expected value is written out here by hand: the rotation matrices below are spelt
element by element (not :func:`twin.core.frames.rotation_matrix`), gravity is the thesis' 9.81
m/s^2, and the leakage factors are the sines and cosines of the mount's angles. Convention:
R = Rz(yaw) Ry(pitch) Rx(roll) takes the IMU's axes to the cabin's, the IMU reads R^T v of a
cabin-axes vector v, so an IMU pitched nose-up by d on a cabin at rest reads ax = +g sin d.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

import twin.formats.run_checks as checks
from twin.chain.config import MotionSystem, load_config, motion_system
from twin.chain.extensions import Extension
from twin.chain.imu import ImuSpec
from twin.chain.signals import rest
from twin.chain.simulate import Simulation, default_imu, simulate
from twin.chain.trajectory import Trajectory
from twin.cli.main import main
from twin.core.errors import ConfigError, RunFormatError, SignalError
from twin.formats.run_checks import read_plausible_run
from twin.formats.runs import read_run

G = 9.81
IDEAL = default_imu("srs").ideal()


def _rx(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _ry(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def _rz(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _mount(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """R of the convention above, by hand."""
    return _rz(yaw) @ _ry(pitch) @ _rx(roll)


def _alignment(roll: float = 0.0, pitch: float = 0.0, yaw: float = 0.0) -> Extension:
    return Extension("imu_alignment", {"roll_rad": roll, "pitch_rad": pitch, "yaw_rad": yaw})


def _with(config: str | MotionSystem, *extensions: Extension) -> MotionSystem:
    ms = motion_system(config) if isinstance(config, str) else config
    return ms.replace(extensions=(*ms.extensions, *extensions))


def _pitching(duration_s: float = 3.0, amplitude: float = 0.05, f_hz: float = 1.0) -> Trajectory:
    """Pure pitch from rest: theta = A (1 - cos 2 pi f t) [rad], the other DOFs still."""
    t = np.arange(round(duration_s * 100) + 1) / 100.0
    values = np.zeros((t.size, 6))
    values[:, 4] = amplitude * (1.0 - np.cos(2 * np.pi * f_hz * t))
    return Trajectory(100.0, values)


def _readings(sim: Simulation) -> np.ndarray:
    return np.hstack([sim.imu.accel, sim.imu.gyro])


def _bits(sim: Simulation) -> list[bytes]:
    return [sim.imu.t.tobytes(), sim.imu.accel.tobytes(), sim.imu.gyro.tobytes(),
            sim.response.pose.tobytes(), bytes([sim.imu.saturated % 256])]  # fmt: skip


# --- (1) gravity at rest ------------------------------------------------------------------------


@pytest.mark.parametrize("delta", [0.01, -0.15])
def test_a_pitched_imu_at_rest_reads_g_sin_delta_in_x(delta):
    """Nose-up by delta: R^T (0, 0, -g) = (g sin delta, 0, -g cos delta) (Ry(delta)^T's third
    column times -g)."""
    sim = simulate(_with("srs", _alignment(pitch=delta)), rest(1.0), "reduced", 1, IDEAL)
    ax, ay, az = sim.imu.accel.T
    assert ax == pytest.approx(np.full(ax.size, G * np.sin(delta)), rel=1e-6)
    assert az == pytest.approx(np.full(az.size, -G * np.cos(delta)), rel=1e-6)
    assert np.all(np.abs(ay) < 1e-12)
    assert np.all(np.abs(sim.imu.gyro) < 1e-12)  # at rest no rate leaks anywhere


def test_all_three_angles_at_rest_read_gravity_through_rz_ry_rx():
    """R = Rz Ry Rx: R^T (0, 0, -g) = -g R[2, :] = g (sin p, -sin r cos p, -cos r cos p), yaw
    not entering (another order, e.g. Rx Ry Rz, would let it)."""
    roll, pitch, yaw = 0.12, -0.07, 0.19
    sim = simulate(_with("srs", _alignment(roll, pitch, yaw)), rest(1.0), "reduced", 1, IDEAL)
    want = G * np.array([np.sin(pitch), -np.sin(roll) * np.cos(pitch),
                         -np.cos(roll) * np.cos(pitch)])  # fmt: skip
    assert np.allclose(sim.imu.accel, want, rtol=0, atol=1e-12)
    assert np.allclose(_mount(roll, pitch, yaw).T @ [0.0, 0.0, -G], want, rtol=0, atol=1e-12)


# --- (2) a pitch rate leaks into p ----------------------------------------------------------------


def test_a_yawed_imu_reads_a_pitch_rate_in_p():
    """Pure pitch (roll = yaw = 0): the cabin's rate is (0, q, 0) in cabin axes (Eq A.4 with
    psi = 0 gives omega_b = (0, theta_dot, 0), and T = Ry(theta) leaves the y axis alone). An
    IMU yawed by psi, R = Rz(psi), reads Rz(psi)^T (0, q, 0) = Rz(-psi) (0, q, 0) =
    (q sin psi, q cos psi, 0): p / q_true = sin psi, q / q_true = cos psi, so the p channel
    reads tan psi times the q channel."""
    psi = 0.05
    commands = _pitching()
    ref = simulate("srs", commands, "reduced", 1, IDEAL)
    sim = simulate(_with("srs", _alignment(yaw=psi)), commands, "reduced", 1, IDEAL)
    q_true = ref.imu.gyro[:, 1]
    assert np.ptp(q_true) > 0.2  # the signal does pitch (0.05 rad at 1 Hz: 0.31 rad/s)
    assert np.max(np.abs(ref.imu.gyro[:, [0, 2]])) < 1e-12 * np.max(np.abs(q_true))

    def ratio(x: np.ndarray, y: np.ndarray) -> float:  # least-squares amplitude ratio x / y
        return float(x @ y / (y @ y))

    p, q, r = sim.imu.gyro.T
    assert ratio(p, q_true) == pytest.approx(np.sin(psi), rel=1e-9)
    assert ratio(q, q_true) == pytest.approx(np.cos(psi), rel=1e-9)
    assert ratio(p, q) == pytest.approx(np.tan(psi), rel=1e-9)
    assert np.allclose(p, np.sin(psi) * q_true, rtol=0, atol=1e-12)
    assert np.max(np.abs(r)) < 1e-12


# --- (3) zero rotation --------------------------------------------------------------------------


def test_a_zero_rotation_leaves_every_bit():
    """The MPI (filter, delay, heave noise) with the data-sheet IMU's noise and bias, a pitch
    motion: zero angles give the bits of no extension, and the same IMU noise draws."""
    commands = _pitching(2.0)
    imu = default_imu("mpi")
    plain = simulate("mpi", commands, "reduced", 4, imu)
    zero = simulate(_with("mpi", _alignment()), commands, "reduced", 4, imu)
    assert _bits(zero) == _bits(plain)
    assert zero.imu.saturated == plain.imu.saturated


def test_the_noise_draws_do_not_depend_on_the_rotation():
    """The rotated elements read R^T truth, then the same seeded bias and noise: with and
    without the mount, the difference of the readings is R^T truth - truth exactly (the ideal
    IMU's readings give truth)."""
    commands, R = _pitching(2.0), _mount(0.03, -0.02, 0.04)
    noisy, aligned = default_imu("srs"), _with("srs", _alignment(0.03, -0.02, 0.04))
    truth = _readings(simulate("srs", commands, "reduced", 2, IDEAL))
    diff = (_readings(simulate(aligned, commands, "reduced", 2, noisy))
            - _readings(simulate("srs", commands, "reduced", 2, noisy)))  # fmt: skip
    leak = np.hstack([truth[:, :3] @ R - truth[:, :3], truth[:, 3:] @ R - truth[:, 3:]])
    assert np.allclose(diff, leak, rtol=0, atol=1e-12)


# --- (4) the twin-config/1 round trip -------------------------------------------------------------


def test_a_saved_configuration_reads_back_the_alignment(tmp_path):
    align = _alignment(0.003, -0.0021, 0.0175)
    cfg = _with("srs", Extension("gain", {"gain": 1.1}, ("pitch",)), align)
    path = cfg.save(tmp_path / "tilted.json")
    saved = json.loads(path.read_text())["platform_config"]["extensions"][1]
    pars = {"roll_rad": 0.003, "pitch_rad": -0.0021, "yaw_rad": 0.0175}
    assert saved == {"effect": "imu_alignment", "parameters": pars, "dofs": []}
    for loaded in (load_config(path), motion_system(str(path))):
        assert loaded.extensions == cfg.extensions
        assert loaded.to_meta() == cfg.to_meta()
        assert np.allclose(loaded.imu_rotation, _mount(0.003, -0.0021, 0.0175), rtol=0, atol=1e-15)


def test_an_alignment_is_described_in_degrees():
    ext = _alignment(np.radians(0.5), np.radians(-0.2), np.radians(1.0))
    assert ext.describe() == "imu_alignment: IMU rotated by roll 0.50°, pitch -0.20°, yaw 1.00°"


def test_two_alignments_compose_in_order():
    """The second is a rotation relative to the axes the first left: R = R1 R2."""
    a, b = _alignment(0.1, 0.0, 0.0), _alignment(0.0, 0.0, 0.15)
    got = _with("srs", a, b).imu_rotation
    assert np.allclose(got, _rx(0.1) @ _rz(0.15), rtol=0, atol=1e-15)
    assert not np.allclose(got, _rz(0.15) @ _rx(0.1), rtol=0, atol=1e-3)


# --- (5) malformed values -----------------------------------------------------------------------


@pytest.mark.parametrize(
    ("parameters", "match"),
    [
        ({"roll_rad": float("nan"), "pitch_rad": 0.0, "yaw_rad": 0.0},
         r"imu_alignment parameter roll_rad must be a number in \[-0.2, 0.2\]; got nan"),
        ({"roll_rad": 0.0, "pitch_rad": 0.5, "yaw_rad": 0.0},
         r"imu_alignment parameter pitch_rad must be a number in \[-0.2, 0.2\]; got 0.5"),
        ({"roll_rad": 0.0, "pitch_rad": 0.0, "yaw_rad": -0.2001},
         r"yaw_rad must be a number in \[-0.2, 0.2\]; got -0.2001"),
        ({"rol_rad": 0.0, "pitch_rad": 0.0, "yaw_rad": 0.0},
         r"unknown parameter 'rol_rad' \(did you mean 'roll_rad'\?\); allowed: roll_rad, "
         r"pitch_rad, yaw_rad"),
        ({"roll_rad": 0.0, "pitch_rad": 0.0},
         "takes parameters roll_rad, pitch_rad, yaw_rad; got pitch_rad, roll_rad"),
        ({"roll_rad": "0.1", "pitch_rad": 0.0, "yaw_rad": 0.0}, "roll_rad must be a number"),
    ],
)  # fmt: skip
def test_a_malformed_alignment_is_refused(parameters, match):
    with pytest.raises(ConfigError, match=match):
        Extension("imu_alignment", parameters)


def test_a_malformed_alignment_in_a_file_is_named_with_the_file(tmp_path):
    path = _with("srs", _alignment(0.1)).save(tmp_path / "cfg.json")
    data = json.loads(path.read_text())
    data["platform_config"]["extensions"][0]["parameters"]["roll_rad"] = 0.5
    path.write_text(json.dumps(data))
    want = (
        rf"{path.name}: platform_config extensions\[0\]: imu_alignment parameter roll_rad "
        r"must be a number in \[-0.2, 0.2\]"
    )
    with pytest.raises(ConfigError, match=want):
        load_config(path)


def test_an_alignment_has_no_response_of_one_dof():
    """Its leakage crosses channels: the per-DOF response refuses it, and a configuration's
    Eq 5.11 response leaves it out."""
    ext = _alignment(0.1, 0.0, 0.0)
    with pytest.raises(SignalError, match="imu_alignment has no response of one DOF"):
        ext.response([1.0])
    f = np.array([0.1, 1.0, 10.0])
    ms = motion_system("mpi")
    assert np.array_equal(_with(ms, ext).response_at_hz(f), ms.response_at_hz(f))


# --- (6) both models, and the order with a sensor filter ------------------------------------------


@pytest.mark.parametrize("model", ["reduced", "full"])
def test_both_models_read_the_motion_through_the_mount(model):
    """On either platform the aligned IMU reads R^T of what the well-mounted one reads, the
    motion itself unchanged."""
    commands, angles = _pitching(2.0), (0.04, -0.03, 0.06)
    plain = simulate("srs", commands, model, 3, IDEAL)
    sim = simulate(_with("srs", _alignment(*angles)), commands, model, 3, IDEAL)
    assert sim.response.pose.tobytes() == plain.response.pose.tobytes()
    R, v = _mount(*angles), _readings(plain)
    want = np.hstack([(R.T @ v[:, :3].T).T, (R.T @ v[:, 3:].T).T])
    assert np.allclose(_readings(sim), want, rtol=0, atol=1e-12)
    assert np.max(np.abs(sim.imu.gyro[:, 0])) > 0.01  # the pitch rate leaks into p


def test_the_sensor_filter_filters_what_the_rotated_element_reads():
    """The mount comes first, the filter after it: with a yaw psi and a filter on p, p reads
    sin psi times the *filtered* pitch rate (a filter before the mount would leave it
    unfiltered); the filter is linear, so the filtered rate is q of the same filter on q."""
    psi, commands = 0.08, _pitching(2.0, f_hz=3.0)
    lowpass = {"cutoff_hz": 2.0}
    ref = simulate(_with("srs", Extension("sensor_filter", {**lowpass, "channels": ("q",)})),
                   commands, "reduced", 1, IDEAL)  # fmt: skip
    cfg = _with("srs", _alignment(yaw=psi),
                Extension("sensor_filter", {**lowpass, "channels": ("p",)}))  # fmt: skip
    p = simulate(cfg, commands, "reduced", 1, IDEAL).imu.gyro[:, 0]
    unfiltered = simulate("srs", commands, "reduced", 1, IDEAL).imu.gyro[:, 1]
    assert np.allclose(p, np.sin(psi) * ref.imu.gyro[:, 1], rtol=0, atol=1e-12)
    assert np.max(np.abs(p - np.sin(psi) * unfiltered)) > 0.01 * np.sin(psi)


def test_saturation_acts_in_the_imus_own_axes():
    """An accelerometer range of 9.7 m/s^2 clips the well-mounted z axis at rest (9.81) but not
    one pitched by 0.2 rad (9.81 cos 0.2 = 9.61; x reads 9.81 sin 0.2 = 1.95)."""
    imu = ImuSpec(rate_hz=IDEAL.rate_hz, accel_range=9.7, accel_noise_sd=0.0, gyro_noise_sd=0.0,
                  accel_bias_sd=0.0, gyro_bias_sd=0.0)  # fmt: skip
    plain = simulate("srs", rest(1.0), "reduced", 1, imu)
    sim = simulate(_with("srs", _alignment(pitch=0.2)), rest(1.0), "reduced", 1, imu)
    assert plain.imu.saturated == plain.imu.t.size
    assert sim.imu.saturated == 0
    assert sim.imu.accel[:, 2] == pytest.approx(np.full(sim.imu.t.size, -G * np.cos(0.2)))


# --- a recorded run of a tilted IMU is plausible --------------------------------------------------


def test_a_run_with_a_tilted_imu_passes_the_plausibility_checks(tmp_path):
    """A twin run of an IMU pitched by 0.2 rad reads gravity 1.95 m/s^2 in x, beyond the
    gravity check's tolerance: the check expects what its configuration's mount reads."""
    cfg = _with("srs", _alignment(pitch=0.2)).save(tmp_path / "tilted.json")
    out = tmp_path / "run"
    assert main(["simulate", str(cfg), "--model", "reduced", "--signal", "multisine1-pitch",
                 "--seed", "1", "--out", str(out), "--quiet"]) == 0  # fmt: skip
    read_plausible_run(out)
    run = read_run(out)  # the short-run fallback (no comparison) takes the mount too
    rotation = load_config(cfg).imu_rotation
    checks.check_gravity(run, None, "imu.csv", rotation)
    with pytest.raises(RunFormatError, match="rotated mount"):
        checks.check_gravity(run, None, "imu.csv")
