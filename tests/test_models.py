"""The two MJCF models: load, step warning-free, loops stay closed, XML is current."""

import mujoco
import numpy as np
import pytest

from twin.core.errors import ModelFileError
from twin.core.frames import rotation_matrix
from twin.platform.build import read_build_parameters, render
from twin.platform.facts import PLATFORMS, load_model, model_dir, model_path
from twin.platform.geometry import load_geometry

PLATFORM_NAMES = list(PLATFORMS)
LOOP_RESIDUAL_LIMIT = 1e-4  # m, largest allowed gap in a closed leg loop


def equality_residual(data: mujoco.MjData) -> float:
    eq = data.efc_type == mujoco.mjtConstraint.mjCNSTR_EQUALITY
    return float(np.abs(data.efc_pos[eq]).max())


@pytest.mark.parametrize("platform", PLATFORM_NAMES)
def test_committed_xml_is_what_the_builder_writes(platform):
    folder = model_dir(platform)
    for filename, text in render(read_build_parameters(folder / "build.toml")).items():
        assert (folder / filename).read_text() == text, (
            f"{folder / filename} is stale: run `make models`"
        )


@pytest.mark.parametrize("platform", PLATFORM_NAMES)
def test_scene_steps_10_s_at_home_without_warning_and_loops_closed(platform):
    model = mujoco.MjModel.from_xml_path(str(model_path(platform, scene=True)))
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
    worst = 0.0
    for _ in range(round(10.0 / model.opt.timestep)):
        mujoco.mj_step(model, data)
        worst = max(worst, equality_residual(data))
    assert all(w.number == 0 for w in data.warning), [w.number for w in data.warning]
    assert worst < LOOP_RESIDUAL_LIMIT
    # still at neutral: the static-force feedback (K_s) leaves only a sub-millimetre sag
    geo = load_geometry(platform)
    ugp = data.sensor("ugp_position").data
    assert np.allclose(ugp, geo.neutral_ugp, atol=5e-4)


@pytest.mark.parametrize("platform", PLATFORM_NAMES)
def test_scene_loads_and_steps_in_dm_control(platform):
    from dm_control import mjcf

    root = mjcf.from_path(str(model_path(platform, scene=True)))
    assert len(root.find_all("actuator")) == 12
    physics = mjcf.Physics.from_mjcf_model(root)
    physics.reset(keyframe_id=0)
    physics.step(nstep=100)
    assert np.isfinite(physics.data.qpos).all()


@pytest.mark.parametrize("platform", PLATFORM_NAMES)
def test_no_sensor_the_twin_knows_to_be_wrong_under_implicitfast(platform):
    """MuJoCo's accelerometer and frame accelerations miss the implicit damping correction
    (~2.4x in heave with K_d on the legs): the models do not carry them."""
    model = load_model(platform)
    kinds = {mujoco.mjtSensor(int(t)) for t in model.sensor_type}
    wrong = {mujoco.mjtSensor.mjSENS_ACCELEROMETER, mujoco.mjtSensor.mjSENS_FRAMELINACC,
             mujoco.mjtSensor.mjSENS_FRAMEANGACC}  # fmt: skip
    assert model.opt.integrator == mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    assert not kinds & wrong


@pytest.mark.parametrize("platform", PLATFORM_NAMES)
def test_loops_stay_closed_and_legs_track_under_a_fast_heave_pitch_drive(platform):
    """3.35 Hz (Table 5.2's highest signal-1 frequency) heave + pitch, PD fed with the
    reference leg velocity (Eq 5.9): loop residual < 1e-4 m and legs track within 2 mm."""
    model = load_model(platform)
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, 0)
    geo = load_geometry(platform)
    w = 2 * np.pi * 3.35
    heave, pitch = 1.0 / w**2, np.radians(57.3) / w**2  # 1 m/s^2 and 57.3 deg/s^2

    def lengths(t):
        pose = np.array([0, 0, heave * np.sin(w * t), 0, pitch * np.sin(w * t), 0])
        c = geo.neutral_ugp + pose[:3]
        return np.linalg.norm(c + geo.cabin_gimbals @ rotation_matrix(pose[3:]).T
                              - geo.base_gimbals, axis=1)  # fmt: skip

    worst, track = 0.0, 0.0
    for _ in range(2000):
        t = data.time
        data.ctrl[:6] = lengths(t)
        data.ctrl[6:] = (lengths(t + 1e-6) - lengths(t - 1e-6)) / 2e-6
        mujoco.mj_step(model, data)
        worst = max(worst, equality_residual(data))
        legs = np.array([data.sensor(f"leg{j}_length").data[0] for j in range(1, 7)])
        track = max(track, np.abs(legs - lengths(data.time)).max())
    assert worst < LOOP_RESIDUAL_LIMIT
    assert track < 2e-3


def test_mpi_model_carries_table_5_4_parameters():
    # Table 5.4: m_c, cg, inertia, K_p, K_d, K_s
    model = load_model("mpi")
    cabin = model.body("cabin").id
    assert model.body_mass[cabin] == pytest.approx(250.0)
    assert np.allclose(model.body_ipos[cabin], [0.025, -0.015, 0.05])
    assert np.allclose(model.body_inertia[cabin], [825.0, 825.0, 425.0])
    assert model.body_gravcomp[cabin] == pytest.approx(0.9973)
    for j in range(1, 7):
        assert model.actuator_gainprm[model.actuator(f"leg{j}_position").id][0] == 21000.0
        assert model.actuator_gainprm[model.actuator(f"leg{j}_velocity").id][0] == 73500.0
    assert model.opt.timestep == 0.001  # physics at 1 kHz


def test_malformed_build_file_is_rejected_with_its_name(tmp_path):
    bad = tmp_path / "build.toml"
    bad.write_text((model_dir("mpi") / "build.toml").read_text().replace("stroke = 0.45", ""))
    with pytest.raises(ModelFileError, match=r"missing key 'stroke'"):
        read_build_parameters(bad)
    bad.write_text("[model\nname=")
    with pytest.raises(ModelFileError, match="not valid TOML"):
        read_build_parameters(bad)
