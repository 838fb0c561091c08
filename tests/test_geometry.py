"""Geometry is read from the compiled MJCF and equals the thesis' tables."""

import mujoco
import numpy as np
import pytest

from twin.core.errors import ModelFileError, UnknownPlatformError
from twin.platform.facts import load_facts
from twin.platform.geometry import geometry_from_model, load_geometry

# Table B.2 (MPI) and Table B.4 (SRS), typed from the thesis: base x, y, cabin x, y per leg.
TABLE_B2 = [
    (-0.327, -0.730, 0.226, -0.556), (0.796, -0.082, 0.369, -0.473),
    (0.796, 0.082, 0.369, 0.473), (-0.327, 0.730, 0.226, 0.556),
    (-0.469, 0.648, -0.594, 0.082), (-0.469, -0.648, -0.594, -0.082),
]  # fmt: skip
TABLE_B4 = [
    (1.071, 1.255, 1.597, 0.100), (0.551, 1.555, -0.712, 1.433),
    (-1.623, 0.300, -0.885, 1.333), (-1.623, -0.300, -0.885, -1.333),
    (0.551, -1.555, -0.712, -1.433), (1.071, -1.255, 1.597, -0.100),
]  # fmt: skip


@pytest.mark.parametrize(("platform", "table"), [("mpi", TABLE_B2), ("srs", TABLE_B4)])
def test_gimbals_read_from_mjcf_equal_the_thesis_tables(platform, table):
    geo = load_geometry(platform)
    t = np.array(table)
    assert np.array_equal(geo.base_gimbals[:, :2], t[:, :2])
    assert np.array_equal(geo.cabin_gimbals[:, :2], t[:, 2:])


def test_mpi_base_is_1_209_m_below_ugp_and_stroke_is_0_45_m():
    geo = load_geometry("mpi")  # §5.4.2 and Table 5.1
    assert geo.neutral_height == pytest.approx(1.209, abs=1e-9)
    assert np.allclose(geo.stroke, 0.45, atol=2e-5)  # XML keeps 6 significant digits
    # stroke centred on the neutral length (§A.1.2: actuators extended halfway)
    assert np.allclose((geo.leg_min + geo.leg_max) / 2, geo.neutral_lengths, atol=5e-6)


def test_srs_stroke_is_1_15_m():
    assert np.allclose(load_geometry("srs").stroke, 1.15, atol=2e-5)  # Table 5.1


def test_platform_facts_hold_table_5_1_limits():
    mpi, srs = load_facts("mpi"), load_facts("srs")
    assert (mpi.max_velocity, mpi.max_acceleration) == (0.3, 2.0)
    assert (srs.max_velocity, srs.max_acceleration) == (1.0, 13.0)
    assert mpi.filter_break_hz == 1.0 and srs.filter_break_hz == 0.0


def test_unknown_platform_names_the_known_ones():
    with pytest.raises(
        UnknownPlatformError, match=r"unknown platform 'simona' \(known platforms: mpi, srs\)"
    ):
        load_geometry("simona")


def test_model_without_the_twin_sites_is_rejected():
    model = mujoco.MjModel.from_xml_string(
        '<mujoco><worldbody><body name="base" quat="0 1 0 0"/><body name="cabin" quat="0 1 0 0">'
        '<freejoint/><geom size="0.1"/></body></worldbody></mujoco>'
    )
    with pytest.raises(ModelFileError, match="no site 'base_gimbal_1'"):
        geometry_from_model(model)
