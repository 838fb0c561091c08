"""Which motion system a pilot run was flown through, read from its theta_felt."""

import numpy as np
import pytest

from twin.chain.config import motion_system
from twin.core.errors import SignalError
from twin.pilot.identification.felt_motion import MATCH_MAX, felt_mismatch, match_motion, settle_s
from twin.pilot.models.pitch import PitchPilot, simulate_pitch
from twin.pilot.studies.experiment import pitch_remnant_scale

#: Configurations with condition-7's pitch response (1 Hz filter, 35 ms; noise is in heave).
LIKE_7 = {"condition-7", "condition-8", "mpi"}


@pytest.fixture(scope="module")
def runs() -> dict[str, dict[str, np.ndarray]]:
    """One run each through condition-7 and condition-1, 15 % remnant, flown in the time
    domain by the twin's loop (the check uses the frequency response)."""
    pilot = PitchPilot()
    scale = pitch_remnant_scale(pilot, 0.15, 3)
    out = {}
    for name in ("condition-7", "condition-1"):
        r = simulate_pitch(pilot, name, 1, 3, scale)
        out[name] = {"theta": r.theta[0], "theta_felt": r.theta_felt[0], "rate_hz": 100.0}
    return out


def test_the_configuration_is_read_from_theta_felt(runs):
    m = match_motion(runs["condition-7"])
    assert m.source == "theta_felt" and m.config.name in LIKE_7
    assert set(m.same_response) == LIKE_7
    assert m.mismatch < 0.005
    # 10 ms less delay is told apart (condition-5: 1 Hz filter, 25 ms)
    others = [n for n in m.candidates if n not in LIKE_7]
    assert others[0] in {"condition-5", "condition-6"} and m.candidates[others[0]] > 0.01
    assert "the built-in one theta_felt follows best" in m.format()
    m1 = match_motion(runs["condition-1"])
    assert m1.config.name in {"condition-1", "condition-2", "srs"} and m1.mismatch < 0.005


@pytest.mark.parametrize(("given", "questioned"), [("condition-1", True), ("condition-5", True),
                                                   ("condition-8", False)])  # fmt: skip
def test_a_given_configuration_is_checked(runs, given, questioned):
    m = match_motion(runs["condition-7"], motion_system(given))
    assert m.source == "given" and m.config.name == given
    assert (m.better in LIKE_7) if questioned else m.better is None
    assert ("WARNING" in m.format()) == questioned


def test_nuisance_in_the_felt_attitude(runs):
    """Sensor noise (2 % of the felt rms, white) and a record 10 ms late (a timing offset
    between the logged channels) still pick the filter and the nearest delay."""
    run = runs["condition-7"]
    felt = run["theta_felt"]
    rng = np.random.default_rng(5)
    noisy = dict(run, theta_felt=felt + 0.02 * np.sqrt(np.mean(felt**2)) * rng.standard_normal(
        felt.size))  # fmt: skip
    m = match_motion(noisy)
    assert m.config.name in LIKE_7 and 0.015 < m.mismatch < 0.03
    assert match_motion(noisy, motion_system("condition-8")).better is None
    late = dict(run, theta_felt=np.concatenate([felt[:1], felt[:-1]]))
    m = match_motion(late)
    assert m.config.name in LIKE_7 and m.mismatch < MATCH_MAX
    # a constant offset of the felt attitude (a sensor's zero) of 10 % of its rms is left out
    offset = dict(run, theta_felt=felt + 0.1 * np.sqrt(np.mean(felt**2)))
    assert match_motion(offset).mismatch == pytest.approx(match_motion(run).mismatch, abs=1e-9)


def test_no_built_in_match_asks_for_the_configuration(runs):
    """A felt attitude 20 % short in gain (a miscalibrated channel) follows no built-in
    configuration: the fit is not run through a guess."""
    run = runs["condition-1"]
    with pytest.raises(SignalError, match="follows none of the built-in motion systems"):
        match_motion(dict(run, theta_felt=0.8 * run["theta_felt"]))
    # given, it is fitted through, reported with its mismatch and questioned
    m = match_motion(dict(run, theta_felt=0.8 * run["theta_felt"]), motion_system("condition-1"))
    assert m.mismatch == pytest.approx(0.25, rel=0.05)  # |0.8 - 1| / 0.8
    assert m.better is None and "more than the 5 %" in m.warning
    assert m.to_dict()["warning"] == m.warning


def test_a_file_named_like_a_built_in_is_told_apart(runs, tmp_path):
    """A twin-config/1 file called "condition-1" with condition-7's response is checked as the
    file it is, and its label says it is not the built-in."""
    path = tmp_path / "c7.json"
    motion_system("condition-7").replace(name="condition-1").save(path)
    m = match_motion(runs["condition-7"], motion_system(str(path)))
    assert m.mismatch < 0.005 and m.warning is None
    assert m.label == "condition-1 (from a file: not the built-in condition-1)"
    assert match_motion(runs["condition-1"], motion_system("condition-1")).label == "condition-1"


def test_a_slow_filter_settles_before_it_is_compared():
    """The start of a record holds the response to the attitude before it: left out for the
    1 Hz filter's 2 s, for a 0.2 Hz filter its 10 s."""
    assert settle_s(motion_system("condition-1")) == settle_s(motion_system("mpi")) == 2.0
    assert settle_s(motion_system("mpi").override(0.2, None, None, None)) == pytest.approx(10.0)


def test_without_theta_felt(runs):
    bare = {k: v for k, v in runs["condition-1"].items() if k != "theta_felt"}
    m = match_motion(bare)
    assert (m.config.name, m.source, m.mismatch) == ("condition-1", "default", None)
    assert "assumed" in m.format()
    m = match_motion(bare, motion_system("condition-5"))
    assert (m.config.name, m.source) == ("condition-5", "given")


def test_bad_felt_attitude(runs):
    theta = runs["condition-1"]["theta"]
    with pytest.raises(SignalError, match="no felt motion"):
        felt_mismatch(theta, np.full_like(theta, 0.01), 100.0, motion_system("srs"))
    with pytest.raises(SignalError, match="too short"):
        felt_mismatch(theta[:150], theta[:150], 100.0, motion_system("srs"))
