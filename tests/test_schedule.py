"""Test schedules: the SRS MovementSeries JSON, the twin's TOML, the commands they make.

The schedules here are written by the tests (small, own); expected poses and durations are
textbook formulas computed in the tests, not by the code under test.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from twin.chain.profiles import point_to_point
from twin.core.errors import ScheduleError
from twin.formats.schedule import Schedule, read_schedule


def _pose(xyz=(0.0, 0.0, 0.0), ang=(0.0, 0.0, 0.0)) -> dict:
    return {
        "type": "Pose",
        "uvw": [0.0] * 3,
        "pqr": [0.0] * 3,
        "xyz": list(xyz),
        "phithetapsi": list(ang),
    }


def _profile_motion(t, axis, profile, dt, frm=None, move=None) -> dict:
    return {
        "time": t,
        "move": {
            "type": "ProfileMotion",
            "from": frm or _pose(),
            "move": move or _pose((0.0, 0.0, 1.0)),
            "axis": axis,
            "profile": profile,
            "dt": dt,
        },
    }


def _series(*moves) -> dict:
    return {"type": "MovementSeries", "moves": list(moves)}


def _write(tmp_path, doc, name="s.json"):
    p = tmp_path / name
    p.write_text(json.dumps(doc) if name.endswith(".json") else doc, encoding="utf-8")
    return p


# A faded sine in pitch (axis scale 0.7 rad per unit), then a heave bump series: constant
# acceleration through a reversal, constant speed, and a jerk-limited return to neutral.
W, GAIN = 2 * math.pi * 0.5, 0.1
SINE = {
    "type": "FadedSineProfile",
    "Tfade": 2.0,
    "Ttotal": 10.0,
    "omg": [W],
    "gain": [GAIN],
    "phi0": [0.0],
}


def _bump_series() -> dict:
    # 1) 0 -> 0.1 m/s at 0.1 m/s^2 (10 ms ramps): ends at 0.0505 m; 2) 0.1 -> -0.1 m/s at
    # -0.1 m/s^2; 3) -0.1 m/s for 1 s; 4) -0.1 -> 0 at 0.1 m/s^2; 5) back to 0 by a Profile.
    still = {"time": 0.0, "move": {"type": "Still", "xyz": [0, 0, 0], "phithetapsi": [0, 0, 0]}}
    acc = "ConstantAccelProfile"
    m1 = _profile_motion(
        1.0,
        [0, 0, 1, 0, 0, 0],
        {"type": acc, "a0": 0, "a1": 0, "ai": 0.1, "v0": 0.0, "v1": 0.1, "Ttotal": 1.01},
        1.01,
    )
    m2 = _profile_motion(
        2.01,
        [0, 0, 1, 0, 0, 0],
        {"type": acc, "a0": 0, "a1": 0, "ai": -0.1, "v0": 0.1, "v1": -0.1, "Ttotal": 2.01},
        2.01,
        frm=_pose((0, 0, 0.0505)),
    )
    m3 = _profile_motion(
        4.02,
        [0, 0, 1, 0, 0, 0],
        {"type": "ConstantSpeedProfile", "v0": -0.1, "Ttotal": 1.0},
        1.0,
        frm=_pose((0, 0, 0.0505)),
    )
    m4 = _profile_motion(
        5.02,
        [0, 0, 1, 0, 0, 0],
        {"type": acc, "a0": 0, "a1": 0, "ai": 0.1, "v0": -0.1, "v1": 0.0, "Ttotal": 1.01},
        1.01,
        frm=_pose((0, 0, -0.0495)),
    )
    # 4) ends at -0.0495 - 0.0505 = -0.1 m; a 0.1 m Profile move back up
    p = point_to_point(0.1, 0.4, 4.0, 100.0).duration
    m5 = {
        "time": 6.03,
        "move": {
            "type": "Movement",
            "from": _pose((0, 0, -0.1)),
            "move": _pose((0, 0, 0.1)),
            "axis": [0, 0, 1, 0, 0, 0],
            "dt": p,
            "profile": {"type": "Profile", "dist": 0.1, "vmx": 0.4, "amx": 4.0, "jmx": 100.0},
        },
    }
    return _series(still, m1, m2, m3, m4, m5)


def test_faded_sine_move_follows_the_formula(tmp_path):
    doc = _series(
        {"time": 0.0, "move": {"type": "Still", "xyz": [0, 0, 0], "phithetapsi": [0, 0, 0]}},
        _profile_motion(1.0, [0, 0, 0, 0, 0.7, 0], SINE, 10.0),
    )
    s = read_schedule(_write(tmp_path, doc))
    c = s.commands(100.0)
    t = np.arange(c.n) / 100.0
    inside = (t >= 3.0) & (t <= 9.0)  # between the 2 s fades of the move starting at 1 s
    # pitch = axis scale 0.7 x gain sin(omega (t - 1)), unfaded in the middle
    want = 0.7 * GAIN * np.sin(W * (t[inside] - 1.0))
    np.testing.assert_allclose(c.values[inside, 4], want, atol=1e-12)
    assert np.abs(c.values[:, [0, 1, 2, 3, 5]]).max() == 0.0
    assert abs(c.values[t <= 1.0, 4]).max() == 0.0 and abs(c.values[-1, 4]) < 1e-12
    (move,) = s.tests()["df"]
    assert move.dof == "pitch" and move.amplitudes[0] == pytest.approx(0.07)


def test_bump_series_positions_and_reversal(tmp_path):
    s = read_schedule(_write(tmp_path, _bump_series()))
    c = s.commands(1000.0)
    t = np.arange(c.n) / 1000.0
    z = c.values[:, 2]
    # a constant acceleration from 0 to 0.1 m/s in 1 s covers v^2 / (2 a) = 0.05 m (+ 0.1 m/s
    # x 5 ms of the second ramp): 0.0505 m at 2.01 s
    assert z[np.argmin(abs(t - 2.01))] == pytest.approx(0.0505, abs=1e-9)
    # the reversal at -0.1 m/s^2 from 0.1 m/s rises v^2 / (2 a) = 0.05 m further, plus
    # 0.1 m/s x 5 ms of its first ramp
    assert z.max() == pytest.approx(0.0505 + 0.0005 + 0.05, abs=2e-6)
    assert z[np.argmin(abs(t - 5.02))] == pytest.approx(-0.0495, abs=1e-9)
    assert z.min() == pytest.approx(-0.1, abs=2e-6) and abs(z[-1]) < 1e-9
    tests = s.tests()
    assert [m.number for m in tests["bump"]] == [3]  # only the move through v = 0
    assert [m.number for m in tests["limits"]] == [6]


def test_point_to_point_duration_is_the_textbook_one():
    # trapezoidal velocity with jerk-limited corners reaching vmax: T = d/v + v/a + a/j
    for d, v, a, j in ((0.5, 0.4, 4.0, 100.0), (1.0, 0.1, 2.0, 100.0), (0.9, 0.7, 3.9, 97.0)):
        assert point_to_point(d, v, a, j).duration == pytest.approx(d / v + v / a + a / j)
    # too short to reach vmax or amax: accelerate at jerk j for tj, brake likewise: d = 2 j tj^3
    tj = (0.001 / (2 * 100.0)) ** (1 / 3)
    assert point_to_point(0.001, 0.4, 4.0, 100.0).duration == pytest.approx(4 * tj, rel=1e-6)


def test_toml_schedule_matches_the_json_one(tmp_path):
    text = """
schedule = "twin-schedule/1"
[[move]]
kind = "still"
duration_s = 1.0
[[move]]
kind = "sines"
axis = [0, 0, 0, 0, 0.7, 0]
frequencies_hz = [0.5]
amplitudes = [0.1]
fade_s = 2.0
duration_s = 10.0
"""
    toml = read_schedule(_write(tmp_path, text, "s.toml")).commands()
    doc = _series(
        {"time": 0.0, "move": {"type": "Still", "xyz": [0, 0, 0], "phithetapsi": [0, 0, 0]}},
        _profile_motion(1.0, [0, 0, 0, 0, 0.7, 0], SINE, 10.0),
    )
    js = read_schedule(_write(tmp_path, doc)).commands()
    np.testing.assert_allclose(toml.values, js.values, atol=1e-12)


def test_toml_moves_follow_each_other(tmp_path):
    text = """
schedule = "twin-schedule/1"
name = "bump"
[[move]]
kind = "constant_acceleration"
dof = "sway"
acceleration = 0.2
v_start = 0.0
v_end = 0.1
[[move]]
kind = "constant_acceleration"
dof = "sway"
acceleration = -0.2
v_start = 0.1
v_end = 0.0
[[move]]
kind = "point_to_point"
dof = "sway"
distance = -0.05
vmax = 0.5
amax = 2.0
jmax = 50.0
"""
    s = read_schedule(_write(tmp_path, text, "b.toml"))
    assert s.name == "bump"
    c = s.commands(1000.0)
    # up to 0.1 m/s and back at 0.2 m/s^2: 2 x v^2 / (2 a) = 0.05 m (10 ms ramps add 0.1 x
    # 10 ms), then 0.05 m back down
    assert c.values[:, 1].max() == pytest.approx(0.05 + 0.1 * 0.01, abs=1e-6)
    assert abs(c.values[-1, 1] - 0.001) < 1e-6


BAD_JSON = [
    ({"type": "Sequence", "moves": []}, "not a MovementSeries"),
    (_series({"time": 0, "move": {"type": "Spin"}}), "move 1 (t = 0 s): unknown move type 'Spin'"),
    (
        _series(_profile_motion(0, [0, 0, 1, 0, 0, 0], {**SINE, "Ttotal": 9.0}, 10.0)),
        "Ttotal 9 s and dt 10 s differ",
    ),
    (
        _series(
            _profile_motion(0, [0, 0, 1, 0, 0, 0], SINE, 10.0),
            _profile_motion(5, [0, 0, 1, 0, 0, 0], SINE, 10.0),
        ),
        "move 2",
    ),
    (
        _series(
            _profile_motion(0, [0, 0, 1, 0, 0, 0], SINE, 10.0),
            _profile_motion(10, [0, 0, 1, 0, 0, 0], SINE, 10.0, frm=_pose((0, 0, 0.3))),
        ),
        "a jump of 0.3",
    ),
    (_series(_profile_motion(0, [0, 0, 0, 0, 0, 0], SINE, 10.0)), "axis is all zero"),
    (
        _series(_profile_motion(0, [0, 0, 1, 0, 0, 0], {**SINE, "omg": [1.0, 2.0]}, 10.0)),
        "one entry per sine",
    ),
    (
        _series(
            _profile_motion(
                0,
                [0, 0, 1, 0, 0, 0],
                {
                    "type": "ConstantAccelProfile",
                    "a0": 0,
                    "a1": 0,
                    "ai": 0.1,
                    "v0": 0,
                    "v1": 0.5,
                    "Ttotal": 1.0,
                },
                1.0,
            )
        ),
        "cannot take speed",
    ),
    (
        _series(_profile_motion(0, [0, 0, 1, 0, 0, 0], {**SINE, "omg": [float("nan")]}, 10.0)),
        "omg[0] must be a number",
    ),
]


@pytest.mark.parametrize(("doc", "message"), BAD_JSON)
def test_malformed_movement_series_is_refused_naming_the_move(tmp_path, doc, message):
    with pytest.raises(ScheduleError, match=None) as e:
        read_schedule(_write(tmp_path, doc))
    assert message in str(e.value)
    assert "\n" not in str(e.value)


BAD_TOML = [
    ('schedule = "twin-schedule/2"\n', "must say schedule"),
    ('schedule = "twin-schedule/1"\n', "no moves"),
    ('schedule = "twin-schedule/1"\n[[move]]\nkind = "wobble"\n', "move 1: unknown kind"),
    (
        'schedule = "twin-schedule/1"\n[[move]]\nkind = "sines"\ndof = "heave"\n'
        "frequencies_hz = [1.0]\namplitudes = [0.1, 0.2]\nfade_s = 1\nduration_s = 5\n",
        "amplitudes must be 1 numbers",
    ),
    (
        'schedule = "twin-schedule/1"\n[[move]]\nkind = "constant_speed"\ndof = "bob"\n'
        "speed = 1\nduration_s = 1\n",
        "unknown dof 'bob'",
    ),
    (
        'schedule = "twin-schedule/1"\n[[move]]\nkind = "constant_speed"\ndof = "heave"\n'
        "speed = 1\nduration_s = 1\nspin = 2\n",
        "unknown key 'spin'",
    ),
    (
        'schedule = "twin-schedule/1"\n[[move]]\nkind = "constant_speed"\ndof = "heave"\n'
        "speed = 1\nduration_s = 1\n",
        "heave speed 1, but the platform rests in the start",
    ),
    (
        'schedule = "twin-schedule/1"\n[[move]]\nkind = "constant_acceleration"\n'
        'dof = "heave"\nacceleration = 1\nv_start = 0\nv_end = 0.5\n[[move]]\n'
        'kind = "still"\nduration_s = 1\n',
        "speed jumps from 0.5 to 0",
    ),
    (
        'schedule = "twin-schedule/1"\n[[move]]\nkind = "still"\nduration_s = 1\n[[move]]\n'
        'kind = "constant_speed"\ndof = "heave"\nspeed = 0.2\nduration_s = 1\nstart_s = 2\n',
        "rests in the pause before it",
    ),
    (
        'schedule = "twin-schedule/1"\n[[move]]\nkind = "still"\nduration_s = 1\n[[move]]\n'
        'kind = "sines"\ndof = "heave"\nfrequencies_hz = [1.0]\namplitudes = [0.01]\n'
        "phases_deg = [90.0]\nfade_s = 0\nduration_s = 2\n",
        "a jump of 0.01",
    ),
    ("schedule = [", "not valid TOML"),
]


@pytest.mark.parametrize(("text", "message"), BAD_TOML)
def test_malformed_toml_schedule_is_refused(tmp_path, text, message):
    with pytest.raises(ScheduleError) as e:
        read_schedule(_write(tmp_path, text, "s.toml"))
    assert message in str(e.value)


def test_schedule_round_trips_through_json(tmp_path):
    s = read_schedule(_write(tmp_path, _bump_series()))
    back = Schedule.from_json(json.loads(json.dumps(s.to_json())))
    np.testing.assert_array_equal(back.commands().values, s.commands().values)
    with pytest.raises(ScheduleError, match="not a schedule as the twin writes it"):
        Schedule.from_json({"moves": [{"number": 1}]})


def test_other_suffix_is_refused(tmp_path):
    with pytest.raises(ScheduleError, match=r"\.json MovementSeries or a \.toml"):
        read_schedule(_write(tmp_path, "x", "s.csv"))
