"""The physical diagnosis: payload, one leg, the IMU's alignment, fitted on the full model.

The fast tests check the pieces against values computed here by hand; the slow ones run the
whole loop on full-physics runs with hidden physics (a heavier cabin, a sticky leg, a weak leg
with and without leg logs, a clean run) and the calibrated configuration back through
``--save-config`` and ``twin simulate``. Acceptance rates over many draws are measured by
``bench/physical_acceptance.py``.
"""

from __future__ import annotations

import pickle
from pathlib import Path

import numpy as np
import pytest
from cli_contract import fails_in_one_line, run_cli

from twin.chain.config import motion_system
from twin.chain.extensions import Extension
from twin.chain.simulate import default_imu, simulate
from twin.chain.trajectory import Trajectory
from twin.cli.main import main
from twin.core.errors import SignalError
from twin.diagnose.hidden_physics import HiddenPhysics, draw, judged, record
from twin.diagnose.physical import rotated
from twin.diagnose.physical_evidence import _projector
from twin.diagnose.physical_vocabulary import PhysicalCause, configured, merged_config
from twin.diagnose.select import Finding
from twin.platform.facts import load_model


def test_a_payload_cause_makes_the_cabin_that_much_heavier_at_its_centre_of_gravity():
    mpi = motion_system("mpi")
    cabin = load_model("mpi").body("cabin")
    cfg = configured(mpi, PhysicalCause("payload", {"factor": 1.4}))
    assert cfg.physics.payload.mass_kg == pytest.approx(0.4 * float(cabin.mass[0]))
    assert np.allclose(cfg.physics.payload.position_m, cabin.ipos)
    assert np.allclose(cfg.physics.payload.inertia, 0.4 * np.asarray(cabin.inertia))
    assert configured(mpi, PhysicalCause("payload", {"factor": 1.0})).physics.payload is None


def test_a_leg_cause_changes_that_leg_only_and_causes_add_up():
    mpi = motion_system("mpi")
    both = merged_config(
        mpi,
        [
            PhysicalCause("leg", {"leg": 3, "coulomb_n": 250.0}),
            PhysicalCause("leg", {"leg": 5, "gain": 0.6}),
        ],
    )
    legs = both.physics.legs
    assert legs.coulomb_n.tolist() == [0, 0, 250.0, 0, 0, 0]
    assert legs.gain.tolist() == [1, 1, 1, 1, 0.6, 1]
    assert legs.play_m.tolist() == [0] * 6 and legs.lag_s.tolist() == [0] * 6


def test_an_alignment_cause_is_the_chains_imu_alignment_and_causes_describe_themselves():
    cause = PhysicalCause(
        "imu_alignment", {"roll_rad": 0.0, "pitch_rad": 0.01, "yaw_rad": 0.0}, ("pitch",)
    )
    cfg = configured(motion_system("srs"), cause)
    assert [e.effect for e in cfg.extensions][-1] == "imu_alignment"
    assert "pitch 0.57 deg" in cause.describe() and cause.describe().endswith("(pitch)")
    leg = PhysicalCause("leg", {"leg": 2, "play_m": 0.001}, ("roll",))
    assert leg.describe() == "leg 2: play_m 0.001 (roll)" and leg.kind == "play_m"
    assert leg.to_json() == {"effect": "leg", "parameters": {"leg": 2, "play_m": 0.001},
                             "dofs": ["roll"]}  # fmt: skip


def test_the_line_projector_gives_a_sines_amplitude_and_phase():
    t = np.arange(0, 20, 0.01)
    f = np.array([0.5, 1.25])
    y = 0.3 * np.sin(2 * np.pi * 0.5 * t + 0.4) + 2.0 + 0.1 * np.cos(2 * np.pi * 1.25 * t)
    proj, sel = _projector(t, f, (0.0, 20.0))
    c = proj @ y[sel]
    amp = c[:2] + 1j * c[2:4]
    # A sin(wt + phi) = A cos(phi) sin(wt) + A sin(phi) cos(wt): A e^{j phi}; a cosine is j
    assert amp[0] == pytest.approx(0.3 * np.exp(0.4j), abs=1e-9)
    assert amp[1] == pytest.approx(0.1j, abs=1e-9)


def test_rotating_an_ideal_imus_record_is_what_a_rotated_imu_reads():
    t = np.arange(0, 3.0, 0.01)
    v = np.zeros((t.size, 6))
    v[:, 4] = 0.02 * np.sin(2 * np.pi * 1.0 * t) * np.clip(t / 0.5, 0, 1)
    cmd = Trajectory(100.0, v)
    srs = motion_system("srs")
    angles = {"roll_rad": 0.01, "pitch_rad": -0.02, "yaw_rad": 0.03}
    imu = default_imu("srs").ideal()
    plain = simulate(srs, cmd, "reduced", 1, imu).imu
    tilted = simulate(srs.replace(extensions=(Extension("imu_alignment", angles),)), cmd,
                      "reduced", 1, imu).imu  # fmt: skip
    mine = rotated(plain, list(angles.values()))
    assert np.allclose(mine.accel, tilted.accel, atol=1e-12)
    assert np.allclose(mine.gyro, tilted.gyro, atol=1e-12)


def test_the_generator_is_seeded_and_draws_within_its_ranges():
    a, b = draw(3, "leg"), draw(3, "leg")
    assert a == b
    kinds = {draw(s).cause.effect if draw(s).cause else "clean" for s in range(30)}
    assert kinds == {"payload", "leg", "clean"}
    for s in range(20):
        h = draw(s, "payload")
        assert 1.3 <= h.cause.value("factor") <= 2.0 and 0.3 <= h.imu_noise <= 3.0
    with pytest.raises(SignalError, match="unknown kind 'legs'; expected one of payload"):
        draw(0, "legs")


def _hidden(seed, platform, dof, cause, logs=False, noise=1.0, signal=1, scale=1.0):
    """A draw of the hidden-physics generator, chosen by hand."""
    return HiddenPhysics(seed, motion_system(platform), dof, cause, noise, signal, scale, logs)


def _finding(effect: str, parameters: dict, dofs=("pitch",)) -> Finding:
    if effect in ("payload", "leg", "imu_alignment"):
        return Finding(PhysicalCause(effect, parameters, dofs), {"delta_bic": 50.0})
    return Finding(Extension(effect, parameters, dofs), {"delta_bic": 50.0})


def test_the_acceptance_judgement():
    payload = _hidden(0, "mpi", "pitch", PhysicalCause("payload", {"factor": 1.5}))
    assert judged(payload, [_finding("payload", {"factor": 1.4})]) == "right"
    assert judged(payload, [_finding("platform_lag", {"lag_s": 0.02})]) == "right"
    assert judged(payload, [_finding("platform_lag", {"lag_s": 0.02}, ("roll",))]) == "wrong"
    assert (
        judged(payload, [_finding("sensor_filter", {"cutoff_hz": 9.0, "channels": ["q"]})])
        == "wrong"
    )
    assert judged(payload, [_finding("noise", {"scale": 2.0})]) == "none"
    leg = _hidden(0, "mpi", "roll", PhysicalCause("leg", {"leg": 4, "gain": 0.5}))
    assert judged(leg, [_finding("leg", {"leg": 4, "coulomb_n": 300.0})]) == "right"
    assert judged(leg, [_finding("leg", {"leg": 3, "gain": 0.5})]) == "wrong"
    clean = _hidden(0, "mpi", "roll", None)
    assert judged(clean, []) == "right"
    assert judged(clean, [_finding("noise", {"scale": 2.0})]) == "right"
    assert judged(clean, [_finding("delay", {"extra_delay_s": 0.01})]) == "wrong"


def test_diagnose_physics_is_offered_and_refuses_a_missing_run_in_one_line(tmp_path, capsys):
    with pytest.raises(SystemExit):
        main(["diagnose", "--help"])
    assert "implies --model full" in " ".join(capsys.readouterr().out.split())
    fails_in_one_line(capsys, ["diagnose", str(tmp_path / "nope"), "--physics"], "nope")


# --- the whole loop on full-physics runs (slow: each about a minute on two cores) ----------


def _diagnosed(hidden: HiddenPhysics, tmp_path: Path):
    from twin.diagnose.diagnosis import diagnose

    return diagnose([record(hidden, tmp_path)], physics=True)


@pytest.mark.slow  # about 60 s: 25 + 20 simulations of a 60 s run on the full model
def test_a_heavier_cabin_is_named_a_payload_with_its_factor_from_the_imu_alone(tmp_path):
    hidden = _hidden(7, "mpi", "pitch", PhysicalCause("payload", {"factor": 1.6}))
    d = _diagnosed(hidden, tmp_path)
    first = d.findings[0]
    assert first.extension.effect == "payload"
    assert first.extension.value("factor") == pytest.approx(1.6, rel=0.2)  # the 20 %
    assert "sensor_filter" not in [f.extension.effect for f in d.findings]
    assert d.physical.sources == ["driven", "undriven"]  # no leg logs in this run
    cfg = d.extended_config
    assert cfg.physics.payload.mass_kg > 0 and cfg.name.endswith("+payload")
    again = pickle.loads(pickle.dumps(d))  # a task's result travels (twin diagnose --each)
    assert again.findings[0].extension.describe() == first.extension.describe()


@pytest.mark.slow  # about 60 s
def test_a_sticky_leg_is_named_by_its_number_from_the_parasitic_motion(tmp_path):
    hidden = _hidden(8, "mpi", "roll", PhysicalCause("leg", {"leg": 2, "coulomb_n": 400.0}))
    d = _diagnosed(hidden, tmp_path)
    assert judged(hidden, d.findings) == "right"
    sources = d.findings[0].evidence["sources"]
    assert sources["undriven"]["fall"] > sources["driven"]["fall"]  # the parasitic motion
    assert any("Coulomb friction below" in s for s in d.statements())


@pytest.mark.slow  # about 2 minutes: the same run with and without its leg logs
def test_leg_logs_show_a_weak_leg_the_imu_alone_hardly_sees(tmp_path):
    with_logs = _hidden(9, "mpi", "heave", PhysicalCause("leg", {"leg": 3, "gain": 0.6}), logs=True)
    d = _diagnosed(with_logs, tmp_path / "logs")
    assert judged(with_logs, d.findings) == "right"
    assert {"legs", "forces"} <= set(d.physical.sources)
    imu_only = _hidden(9, "mpi", "heave", with_logs.cause)
    e = _diagnosed(imu_only, tmp_path / "imu")
    best = {x["describe"].split(":")[0]: x["delta_bic"] for x in e.physical.table}
    assert d.findings[0].delta_bic > 2 * best.get("leg 3", 0.0)


@pytest.mark.slow  # about 90 s: diagnose, save the calibrated configuration, diagnose again
def test_the_calibrated_configuration_reproduces_the_run(tmp_path):
    from twin.diagnose.diagnosis import diagnose

    hidden = _hidden(10, "srs", "roll", PhysicalCause("payload", {"factor": 1.5}), signal=2)
    run = record(hidden, tmp_path)
    d = diagnose([run], physics=True)
    assert d.findings[0].extension.effect == "payload"
    saved = tmp_path / "calibrated.json"
    d.extended_config.save(saved)
    again = diagnose([run], config=motion_system(str(saved)), model="full")
    assert not again.findings  # the calibrated full model explains the run within its noise
    code, err = run_cli(
        [
            "simulate",
            str(saved),
            "--signal",
            "rest-2",
            "--model",
            "full",
            "--quiet",
            "--out",
            str(tmp_path / "sim"),
        ]
    )
    assert code == 0, err


@pytest.mark.slow  # about 60 s
def test_a_clean_full_physics_run_names_nothing(tmp_path):
    hidden = _hidden(11, "srs", "yaw", None, logs=True, noise=2.5, signal=2, scale=0.7)
    d = _diagnosed(hidden, tmp_path)
    assert judged(hidden, d.findings) == "right"
    assert d.physical.finding is None


def test_the_refinements_parabola_is_exact_and_quiet_for_close_values():
    from twin.diagnose.physical import _parabola_min

    x = np.array([-1.0, 0.5, 2.0, 3.0])
    y = 2.0 * (x - 0.7) ** 2 + 5.0  # vertex at 0.7, computed by hand
    assert _parabola_min(x, y) == pytest.approx(0.7, abs=1e-9)
    near = np.array([1.0, 1.0 + 1e-15, 1.0 + 2e-15])  # no warning (the suite's are errors)
    assert _parabola_min(near, np.array([3.0, 2.0, 3.0])) is None


def test_a_fit_whose_statistics_come_later_pickles_with_them():
    from twin.diagnose.candidates import SetFit

    asked = []

    def statistics():
        asked.append(1)
        return {"gain": {"gain": 0.02}}, {"labels": ["gain.gain"], "matrix": [[1.0]]}

    fit = SetFit((Extension("gain", {"gain": 0.9}, ("heave",)),), 3.0, statistics)
    again = pickle.loads(pickle.dumps(fit))  # a task's result travels (twin diagnose --each)
    assert again.std == {"gain": {"gain": 0.02}} and asked == [1]
    assert pickle.loads(pickle.dumps(again)).correlation["labels"] == ["gain.gain"]


def test_an_ambiguous_first_finding_with_the_truth_among_its_alternatives_is_not_wrong():
    leg = _hidden(0, "srs", "surge", PhysicalCause("leg", {"leg": 5, "gain": 0.47}))
    first = _finding("payload", {"factor": 1.39}, ("surge",))
    first.evidence.update(
        ambiguous=True,
        alternatives=[
            {"effects": ["leg 5: gain 0.5717"], "delta_bic": 15.2, "delta_bic_below_named": 0.8}
        ],
    )
    assert judged(leg, [first]) == "ambiguous"
    first.evidence["alternatives"] = [{"effects": ["leg 3: gain 0.6"]}]
    assert judged(leg, [first]) == "wrong"
