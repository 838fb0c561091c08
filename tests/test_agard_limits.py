"""The AGARD-AR-144 system-limits test (twin.agard.limits): measured, not computed."""

import json

import numpy as np
import pytest

from twin.agard.limits import (
    analyse_limits,
    dof_limits,
    limits_signal,
    recorded_counts,
    run_limits,
)
from twin.agard.positions import PositionRecord
from twin.agard.session import Session
from twin.core.errors import SignalError
from twin.formats.run_checks import read_plausible_run
from twin.measurement.measure import Bench, Measurement, configure, from_run
from twin.platform.facts import load_facts
from twin.platform.geometry import load_geometry
from twin.platform.kinematics import jacobian, workspace

HEAVE = 2


def test_signal_goes_out_and_back_both_ways():
    sig = limits_signal("heave", 0.2, 0.1, 0.3, 2.0, 20.0, level=0.5, hold_s=1.0)
    c = sig.commands
    # 0.2 m at 0.3 m/s, 2 m/s^2, 20 m/s^3: jerk 0.1 s, constant acceleration 0.05 s, 0.075 m
    # to reach 0.3 m/s and back, so a cruise of 0.125 / 0.3 s: 0.91667 s a move; 0.1 m: 0.58333
    total = 1.0 + 2 * 0.916667 + 2 * 0.583333 + 3 * 1.0 + 1.0
    assert c.duration == pytest.approx(total, abs=0.011)
    x = c.values[:, HEAVE]
    assert x.max() == pytest.approx(0.2, abs=1e-9) and x.min() == pytest.approx(-0.1, abs=1e-9)
    assert abs(x[-1]) < 1e-12 and abs(x[0]) == 0
    fine = np.arange(0, c.duration, 1e-3)
    assert np.abs(c.at(fine, 1)[:, HEAVE]).max() == pytest.approx(0.3, rel=2e-3)
    assert np.abs(c.at(fine, 2)[:, HEAVE]).max() == pytest.approx(2.0, rel=0.03)
    assert not np.any(np.delete(c.values, HEAVE, axis=1))
    assert sig.meta() == {"kind": "limits", "dof": "heave", "level": 0.5, "distance_pos": 0.2,
                          "distance_neg": 0.1, "vmax": 0.3, "amax": 2.0, "jmax": 20.0}  # fmt: skip


def _synthetic(sig, pose):
    """A measurement of ``sig`` on the SRS (no filter, 25 ms) whose pose is given."""
    c = sig.commands
    t = c.t
    commanded = c.at(t, 2)
    measured = np.zeros_like(commanded)
    measured[:, HEAVE] = np.interp(t - 0.025, t, commanded[:, HEAVE], left=0.0)
    return Measurement(t, commanded, measured, c, "synthetic", configure("srs"),
                       {"signal": sig.meta()})  # fmt: skip


def _late(sig):
    t = sig.commands.t
    return np.interp(t - 0.025, t, sig.commands.values[:, HEAVE], left=0.0)


def test_shortfall_names_the_stroke_of_a_recorded_run():
    # SRS heave: the design's stroke-limited excursion is +0.678 m; a stroke end at +0.56 m
    # (83 % of it) stops a move to 0.6 m
    sig = limits_signal("heave", 0.6, 0.2, 0.3, 2.0, 20.0)
    pose = np.clip(_late(sig), -1.0, 0.56)
    r = analyse_limits(_synthetic(sig, pose), pose, "heave")
    assert r.counts is None
    assert r.stopped_by == ("stroke",)
    assert r.reached.excursion_max == pytest.approx(0.56, abs=1e-9)
    assert r.reached.excursion_min == pytest.approx(-0.2, abs=1e-4)
    assert r.shortfall()["stroke"] == pytest.approx(1 - 0.56 / 0.6, abs=1e-3)
    assert r.reached.velocity == pytest.approx(0.3, rel=0.02)
    assert r.level == 1.0  # from the run's meta.json signal


def test_a_shortfall_far_below_the_design_limits_names_no_limit():
    """A stroke end at 0.15 m, far inside the SRS's 0.68 m, is the motion's own, not a limit
    (the platform's dynamics cut short a brief acceleration plateau the same way)."""
    sig = limits_signal("heave", 0.2, 0.2, 0.3, 2.0, 20.0)
    pose = np.clip(_late(sig), -1.0, 0.15)
    r = analyse_limits(_synthetic(sig, pose), pose, "heave")
    assert r.shortfall()["stroke"] == pytest.approx(0.25, abs=1e-3)
    assert r.stopped_by == ()


def test_shortfall_names_the_velocity_of_a_recorded_run():
    # SRS heave: 1.13 m/s by design at neutral; commanded 1.2 m/s, the platform reaches 1 m/s
    sig = limits_signal("heave", 0.5, 0.5, 1.2, 10.0, 100.0)
    target = _late(sig)
    pose = np.zeros_like(target)
    step = 1.0 / 100  # the platform moves at 1 m/s at most
    for i in range(1, target.size):
        pose[i] = pose[i - 1] + np.clip(target[i] - pose[i - 1], -step, step)
    r = analyse_limits(_synthetic(sig, pose), pose, "heave")
    assert r.stopped_by == ("velocity",)
    assert r.reached.velocity == pytest.approx(1.0, rel=0.02)
    assert r.reached.excursion_max == pytest.approx(0.5, abs=1e-6)  # caught up in the hold
    # counts given (a simulated run) decide instead of the shortfall
    counted = analyse_limits(_synthetic(sig, pose), pose, "heave", {"acceleration": 7})
    assert counted.stopped_by == ("acceleration",)
    assert counted.counts == {"stroke": 0, "velocity": 0, "acceleration": 7, "force": 0}


def test_full_model_reaches_the_workspace_and_the_stroke_stops_it(tmp_path):
    """MPI, full model, the default levels in heave; the last level run again as a folder."""
    ws = workspace(load_geometry("mpi"))["heave"]
    session = Session(Bench(configure("mpi"), "full", seed=0), out=tmp_path)
    r = run_limits(session, "heave")
    assert [lv.level for lv in r.levels] == [0.25, 0.5, 0.75, 1.0, 1.2]
    for lv in r.levels[:3]:  # inside every limit: reached what the platform was sent
        assert lv.stopped_by == ()
        assert lv.reached.excursion_max == pytest.approx(lv.expected.excursion_max, rel=0.01)
        assert lv.reached.velocity == pytest.approx(lv.expected.velocity, rel=0.03)
    top = r.levels[-1]
    print("heave level 1.2: reached", top.reached, "counts", top.counts, "workspace",
          ws.min, ws.max)  # fmt: skip
    assert top.commanded.excursion_max == pytest.approx(1.2 * ws.max, rel=1e-6)
    assert "stroke" in top.stopped_by and top.counts["stroke"] > 0
    # the stroke-limited excursion of `twin workspace`, within 1 mm
    assert top.reached.excursion_max == pytest.approx(ws.max, abs=1e-3)
    assert top.reached.excursion_min == pytest.approx(ws.min, abs=1e-3)
    assert all(v < 2e-3 for v in top.coupled.values())  # heave: all legs end together
    d = json.loads(json.dumps(r.to_dict()))
    assert d["test"] == "system limits" and len(d["levels"]) == 5
    assert d["max_reached"]["excursion_max"] == pytest.approx(top.reached.excursion_max)
    table = r.format_table()
    assert "stroke" in table and table.count("\n") == 8
    png = tmp_path / "limits.png"
    r.plot(path=str(png))
    assert png.stat().st_size > 10_000
    # the recorded run of the last level: pose from the leg lengths, limits from the shortfall
    folder = tmp_path / "runs" / "04-limits-heave-1.2"
    rec = read_plausible_run(folder)
    m = from_run(folder)
    assert recorded_counts(rec) == top.counts
    recorded = analyse_limits(m, PositionRecord.from_run(rec).on(m.t), "heave")
    assert recorded.counts is None and "stroke" in recorded.stopped_by
    assert recorded.reached.excursion_max == pytest.approx(top.reached.excursion_max, abs=5e-4)
    assert recorded.reached.excursion_min == pytest.approx(top.reached.excursion_min, abs=5e-4)


def test_a_speed_beyond_the_leg_velocity_limit_is_stopped_by_it():
    """MPI heave without its platform filter (which would slow the moves itself)."""
    geo, facts = load_geometry("mpi"), load_facts("mpi")
    # the leg-velocity limit through the Jacobian, along the heave excursion of the moves
    poses = np.zeros((81, 6))
    poses[:, HEAVE] = np.linspace(-0.2, 0.21, 81)
    legs = np.abs(jacobian(geo, poses)[:, :, HEAVE]).max(axis=1)
    low, high = facts.max_velocity / legs.max(), facts.max_velocity / legs.min()
    session = Session(Bench(configure("mpi", break_hz=0), "full", seed=0))
    r = run_limits(session, "heave", levels=(1.0,), vmax=0.5, amax=2.0, size=0.8)
    lv = r.levels[0]
    print("heave at 0.5 m/s: reached", lv.reached.velocity, "counts", lv.counts, "limit",
          low, high)  # fmt: skip
    assert lv.stopped_by == ("velocity",)
    assert lv.counts["velocity"] > 0 and lv.counts["stroke"] == 0
    assert lv.counts["acceleration"] == 0  # 2 m/s^2 in heave: 1.8 m/s^2 a leg, under 2
    assert 0.98 * low < lv.reached.velocity < 1.02 * high
    assert lv.reached.velocity < 0.75 * lv.commanded.velocity
    # below the limit the same moves are not stopped
    r = run_limits(session, "heave", levels=(1.0,), vmax=0.25, amax=2.0, size=0.8)
    assert r.levels[0].stopped_by == ()
    assert r.levels[0].reached.velocity == pytest.approx(0.25, rel=0.03)


def test_pitch_goes_beyond_the_first_stroke_end_in_coupled_motion():
    """One leg ends its stroke first; the others go on and the cabin leaves pure pitch."""
    ws = workspace(load_geometry("mpi"))["pitch"]
    r = run_limits(Session(Bench(configure("mpi"), "full", seed=0)), "pitch", levels=(1.2,))
    lv = r.levels[0]
    print("pitch level 1.2: reached", lv.reached.excursion_min, lv.reached.excursion_max,
          "workspace", ws.min, ws.max, "coupled", lv.coupled)  # fmt: skip
    assert "stroke" in lv.stopped_by
    assert lv.reached.excursion_max > ws.max - 1e-3 and lv.reached.excursion_min < ws.min + 1e-3
    assert lv.reached.excursion_max < 1.2 * ws.max
    assert max(lv.coupled.values()) > 5e-3


def test_dof_limits_follow_the_geometry_and_the_facts():
    lim = dof_limits("mpi", "heave")
    ws = workspace(load_geometry("mpi"))["heave"]
    j = np.abs(jacobian(load_geometry("mpi"), np.zeros(6))[:, HEAVE]).max()
    assert (lim.excursion_min, lim.excursion_max) == (ws.min, ws.max)
    assert lim.velocity == pytest.approx(0.3 / j) and lim.acceleration == pytest.approx(2.0 / j)
    assert lim.velocity_range[0] <= lim.velocity <= lim.velocity_range[1]


def test_bad_input_names_what_is_allowed():
    session = Session(Bench(configure("mpi"), "reduced"))
    with pytest.raises(SignalError, match="unknown DOF 'bounce'"):
        run_limits(session, "bounce")
    with pytest.raises(SignalError, match="at least one limits level"):
        run_limits(session, "heave", levels=())
    with pytest.raises(SignalError, match=r"limits level\[1\]"):
        run_limits(session, "heave", levels=(0.5, 4.0))
    with pytest.raises(SignalError, match="limits vmax"):
        run_limits(session, "heave", vmax=-1.0)
    with pytest.raises(SignalError, match="limits size"):
        run_limits(session, "heave", size=0.0)
    with pytest.raises(SignalError, match="limits distance -"):
        limits_signal("heave", 0.1, -0.1, 0.3, 2.0, 20.0)
    assert session.count == 0  # nothing was run
    sig = limits_signal("heave", 0.1, 0.1, 0.3, 2.0, 20.0)
    m = _synthetic(sig, _late(sig))
    with pytest.raises(SignalError, match="the pose must be"):
        analyse_limits(m, np.zeros(5), "heave")
    with pytest.raises(SignalError, match="limit counts are of"):
        analyse_limits(m, _late(sig), "heave", {"torque": 1})
    with pytest.raises(SignalError, match="window end"):
        analyse_limits(m, _late(sig), "heave", window=(3.0, 2.0))
    with pytest.raises(SignalError, match="do not move"):
        analyse_limits(m, _late(sig), "heave", window=(0.0, 0.9))
