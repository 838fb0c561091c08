"""AGARD-AR-144 hysteresis: output against input position, low frequency (agard.hysteresis)."""

import json
import shutil

import numpy as np
import pytest

from twin.agard.hysteresis import (
    HysteresisSegment,
    analyse_hysteresis,
    fitting_amplitude,
    hysteresis_signal,
    run_hysteresis,
    simulate_positions,
)
from twin.agard.positions import PositionRecord
from twin.agard.session import Session
from twin.core.errors import DataError, SignalError
from twin.measurement.measure import Bench, configure
from twin.platform.actuators import LegPhysics
from twin.platform.geometry import load_geometry
from twin.platform.kinematics import inverse
from twin.platform.platform_physics import PlatformPhysics

#: Total delay of the mpi configuration [s] (platform.toml delay_s, §5.5.2).
MPI_DELAY_S = 0.035
F_HZ = 0.1


def heave_leg_ratio() -> float:
    """|d leg / d heave| of the MPI at neutral, by differencing the inverse kinematics."""
    geo, dz = load_geometry("mpi"), 1e-6
    d = (inverse(geo, [0, 0, dz, 0, 0, 0]) - inverse(geo, np.zeros(6))) / dz
    return float(np.abs(d).mean())


def bench(**legs) -> Bench:
    """Full mpi without filter and heave noise, ideal actuators but for ``legs``."""
    physics = PlatformPhysics(legs=LegPhysics.ideal().replace(**legs))
    return Bench(configure("mpi", break_hz=0, noise=False).replace(physics=physics), "full")


def test_play_gives_a_loop_of_its_width():
    """Play is a backlash of total width play_m on each leg (actuators.shape_reference); in
    heave all legs move alike, so the cabin's loop is play / |d leg / d heave| wide at zero
    input, at any amplitude beyond it."""
    play = 0.004
    r = run_hysteresis(Session(bench(play_m=play)), "heave", F_HZ, [0.05, 0.01])
    expected = play / heave_leg_ratio()  # 4.44 mm
    for lp in r.loops:
        assert lp.width == pytest.approx(expected, rel=0.02)  # tolerance 2 %
        assert lp.width_max == pytest.approx(expected, rel=0.05)
        assert lp.width_pct == pytest.approx(100 * expected / lp.amplitude, rel=0.02)
        # the raw loop adds the delay's 2 A sin(2 pi f tau)
        delay_width = 2 * lp.amplitude * np.sin(2 * np.pi * F_HZ * MPI_DELAY_S)
        assert lp.raw_width == pytest.approx(expected + delay_width, rel=0.02)


def test_without_play_or_friction_only_the_delay_opens_the_loop():
    r = run_hysteresis(Session(bench()), "heave", F_HZ, [0.05, 0.01])
    for lp in r.loops:
        delay_width = 2 * lp.amplitude * np.sin(2 * np.pi * F_HZ * MPI_DELAY_S)
        assert lp.lag_s == pytest.approx(MPI_DELAY_S)
        assert lp.raw_width == pytest.approx(delay_width, rel=0.05)
        assert lp.lag_width == pytest.approx(delay_width, rel=1e-9)
        assert abs(lp.width_pct) < 0.1  # beyond the delay: below 0.1 % of the amplitude
        assert abs(lp.width_max_pct) < 0.1


@pytest.mark.parametrize(
    ("field", "values"),
    [("coulomb_n", (50.0, 100.0, 200.0)), ("play_m", (0.001, 0.002, 0.004))],
)
def test_the_width_grows_with_one_legs_friction_or_play(field, values):
    widths = []
    for v in values:
        per_leg = [0.0] * 6
        per_leg[0] = v  # leg 1 only
        r = run_hysteresis(Session(bench(**{field: per_leg})), "heave", F_HZ, [0.05])
        widths.append(r.loops[0].width)
    assert 0 < widths[0] < widths[1] < widths[2]


def test_a_recorded_run_is_analysed_from_its_leg_lengths(tmp_path):
    s = Session(bench(play_m=0.004), out=tmp_path)
    simulated = run_hysteresis(s, "heave", F_HZ, [0.05])
    folder = next((tmp_path / "runs").iterdir())
    record = PositionRecord.from_run(folder)
    sig = hysteresis_signal("heave", F_HZ, 0.05)
    r = analyse_hysteresis([HysteresisSegment(record, *sig.window, F_HZ, 0.05)])
    assert r.dof == "heave"
    assert r.loops[0].width == pytest.approx(simulated.loops[0].width, rel=0.02)
    bare = tmp_path / "bare"
    shutil.copytree(folder, bare)
    (bare / "actuators.csv").unlink()
    (bare / "forces.csv").unlink(missing_ok=True)
    with pytest.raises(DataError, match="lacks a position record"):
        PositionRecord.from_run(bare)


def test_default_amplitudes_are_the_largest_within_the_limits_and_a_hundredth():
    assert fitting_amplitude("mpi", "heave", 0.05) == 0.2  # 0.5 m breaks the MPI's stroke
    s = Session(Bench(configure("srs", noise=False), "reduced"))
    r = run_hysteresis(s, "heave", 0.2)
    top = fitting_amplitude("srs", "heave", 0.2)
    assert [lp.amplitude for lp in r.loops] == pytest.approx([top, top / 100])


def test_an_amplitude_beyond_the_limits_is_skipped_with_the_reason():
    s = Session(Bench(configure("srs", noise=False), "reduced"))
    r = run_hysteresis(s, "heave", 0.2, [0.9, 0.01])
    assert [lp.amplitude for lp in r.loops] == [0.01]
    assert "would break the srs limits" in r.skipped[0.9]
    assert "skipped" in r.format_table()


def test_result_outputs(tmp_path):
    s = Session(Bench(configure("srs", noise=False), "reduced"))
    r = run_hysteresis(s, "pitch", 0.2, [0.02, 0.002])
    d = json.loads(json.dumps(r.to_dict()))
    assert d["test"] == "hysteresis" and d["unit"] == "rad" and len(d["loops"]) == 2
    assert {"width", "width_pct", "width_max", "raw_width", "lag_width", "lag_ms"} <= set(
        d["loops"][0]
    )
    fig = r.plot(path=str(tmp_path / "loop.png"))
    assert (tmp_path / "loop.png").stat().st_size > 0 and len(fig.axes) == 4


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda: hysteresis_signal("heave", 5.0, 0.01), "frequency"),
        (lambda: hysteresis_signal("heave", 0.05, -0.01), "amplitude"),
        (lambda: hysteresis_signal("bounce", 0.05, 0.01), "unknown DOF"),
        (lambda: hysteresis_signal("heave", 0.05, 0.01, periods=0), "periods"),
        (lambda: analyse_hysteresis([]), "at least one segment"),
    ],
)
def test_bad_input_is_refused_naming_what_is_wrong(call, message):
    with pytest.raises(SignalError, match=message):
        call()


def test_a_window_of_other_than_whole_periods_is_refused():
    s = Session(Bench(configure("srs", noise=False), "reduced"))
    sig = hysteresis_signal("heave", 0.2, 0.01)
    record, _ = simulate_positions(s, sig, "heave")
    start, end = sig.window
    with pytest.raises(SignalError, match="whole number"):
        analyse_hysteresis([HysteresisSegment(record, start, end - 1.3, 0.2, 0.01)])
    with pytest.raises(SignalError, match="not the stated"):
        analyse_hysteresis([HysteresisSegment(record, start, end, 0.2, 0.05)])
    assert analyse_hysteresis([HysteresisSegment(record, start, end, 0.2, 0.01)]).loops
