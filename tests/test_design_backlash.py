"""A backlash among a diagnosis' explanations: the design weighs it by simulation.

A play shows in a motion of a few plays and hides in a large one, while a linear effect's
evidence grows with the amplitude. The design simulates each explanation on the old runs and
on candidate runs at several amplitudes, refits the others to it as the diagnosis would, and
keeps the run likeliest to separate every pair (of runs as likely, the smallest motion).
Checked here: a refit of the truth itself
leaves nothing (the search finds the play), no amplitude is best for every pair (a play
against a filter shows more in a small motion, a gain against a play in a large one), the
amplitudes tried are a few plays of motion, a set fitted in the chain's order is modelled
in it, and
(slow) a play the standard signals hid behind a moved platform filter is named after the
designed run.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from twin.chain.config import motion_system
from twin.chain.extensions import Extension
from twin.cli.main import main
from twin.diagnose.candidates import Model, SetFit
from twin.diagnose.data import load_case
from twin.diagnose.design import (
    Explanation,
    _multisine,
    amplitude_levels,
    design_from,
    design_run,
    measured_noise,
    peak_position,
    scaled,
)
from twin.diagnose.diagnosis import diagnose
from twin.diagnose.evidence import line_amplitudes, lines
from twin.diagnose.hidden import NUISANCE_RANGES, draw, judged, play, record, record_runs
from twin.diagnose.report import write_report
from twin.diagnose.select import BIC_MARGIN
from twin.diagnose.simulated_evidence import SimulatedEvidence
from twin.measurement.measure import simulate_measurement

MPI = motion_system("mpi")
PLAY = 0.004  # rad: 4 mrad in roll, a few per cent of Table 5.2 signal 2's excursion
BACKLASH = Extension("backlash", {"play": PLAY}, ("roll",))
GAIN = Extension("gain", {"gain": 0.95}, ("roll",))
FILTER = Extension("platform_filter", {"break_hz": 0.8}, ("roll",))


@pytest.fixture(scope="module")
def weighed(tmp_path_factory):
    runs = record_runs(MPI.replace(extensions=(BACKLASH,)), MPI, "roll",
                       tmp_path_factory.mktemp("bl") / "runs", 5, signals=(2,))  # fmt: skip
    case = load_case(runs, MPI, dofs=["roll"], realisations=2)
    return case, SimulatedEvidence(case, "roll")


def _run(case, factor=1.0):
    sig = _multisine("mpi", "roll", [(0.5, 0.5), (0.7, 1.0), (1.0, 1.5)], 120.0)
    assert sig is not None
    f = np.asarray(sig.frequencies_hz)
    noise, t_old = measured_noise(case, "roll", f, case.of("roll"))
    w = sig.window[1] - sig.window[0]
    return sig if factor == 1.0 else scaled(sig, "roll", factor), noise * np.sqrt(t_old / w)


def test_a_refit_of_the_truth_leaves_nothing_and_the_nominal_a_lot(weighed):
    _, sim = weighed
    assert sim.evidence([BACKLASH], [BACKLASH], None) < 1.0  # the play search finds 4 mrad
    assert sim.evidence([BACKLASH], [], None) > BIC_MARGIN  # the runs show the play


def test_no_amplitude_is_best_for_every_pair(weighed):
    """A play against a filter shows more in a motion of four plays than in the largest; a gain
    against a play less: the trade-off each amplitude's simulation weighs."""
    case, sim = weighed
    large, sd = _run(case)
    small, _ = _run(case, 4 * PLAY / peak_position(large, "roll"))
    runs = {name: sim.candidate(sig, sd, name)
            for name, sig in (("large", large), ("small", small))}  # fmt: skip

    def at(truth, other):
        out = {name: sim.evidence([truth], [other], lines) for name, lines in runs.items()}
        old = sim.evidence([truth], [other], None)
        assert old is not None and None not in out.values()
        assert min(out.values()) > old  # any new run adds evidence
        return out

    against_filter = at(BACKLASH, FILTER)
    assert against_filter["small"] > 1.2 * against_filter["large"]
    gain_against_play = at(GAIN, BACKLASH)
    assert gain_against_play["large"] > 2 * gain_against_play["small"]


def test_the_amplitudes_tried_are_a_few_plays_of_motion(weighed):
    case, _ = weighed
    large, _ = _run(case)
    peak = peak_position(large, "roll")
    assert peak == pytest.approx(0.0898, abs=5e-4)  # the largest the MPI's limits allow
    levels = amplitude_levels(large, "roll", PLAY)
    # 16, 8 and 4 plays of 4 mrad: all below the largest motion
    peaks = [peak_position(scaled(large, "roll", k), "roll") for k in levels]
    assert peaks == pytest.approx([peak, 0.064, 0.032, 0.016], rel=1e-9)
    for k in levels[1:]:
        small = scaled(large, "roll", k)
        assert small.window == large.window and small.commands.duration == large.commands.duration
    assert amplitude_levels(large, "roll", 0.0) == [1.0]  # no play: the largest only
    assert amplitude_levels(large, "roll", 0.01) == pytest.approx([1.0, 0.08 / peak, 0.04 / peak])


def test_a_set_fitted_in_the_chain_order_is_modelled_in_it(weighed):
    """A gain before a play (the chain's order) is not the fast form's gain after it."""
    case, _ = weighed
    ch = case.of("roll")[0]
    x = lines(ch)
    chain = case.clean.replace(extensions=(GAIN, BACKLASH))
    sim = simulate_measurement(chain, ch.commands, ch.t, case.model, case.seed, case.imu.ideal())
    expected = line_amplitudes(ch.t, sim[:, ch.index], x.f, x.window)
    base = Model(case, "roll")
    anchored = SetFit.of((BACKLASH, GAIN), 1.0, {}, {}, (GAIN,)).model(base)
    assert anchored.line_prediction(x) == pytest.approx(expected, rel=1e-9)
    fast = SetFit.of((BACKLASH, GAIN), 1.0, {}, {}).model(base).line_prediction(x)
    assert np.max(np.abs(fast / expected - 1)) > 1e-3  # the fast form: another play


@pytest.mark.slow
def test_a_play_the_standard_signals_hid_is_named_after_the_designed_run(tmp_path):
    """A 4.7 mrad play in the MPI's roll behind a filter the nuisances moved (seed 6008).

    The standard signals leave the moved filter and the play within the margin; the design
    tries smaller motions by simulation and the play is named from the old runs and the new.
    """
    h = draw(6008, "backlash", max_redraws=400, nuisance=True, nuisance_ranges=NUISANCE_RANGES)
    old = record(h, tmp_path / "old")
    first = diagnose(old, seed=h.seed)
    assert judged(h, first) == "ambiguous"
    write_report(first, tmp_path / "diagnosis", figures=False)
    plan = design_from(tmp_path / "diagnosis")
    assert plan.decides
    peaks = [p for p, *_ in plan.levels]
    assert len(peaks) >= 2 and peak_position(plan.signal, "roll") < max(peaks)
    new = play(h.truth, h.config, plan.signal, tmp_path / "designed", 7919 * h.seed + 3,
               imu=h.imu)  # fmt: skip
    again = diagnose([*old, new], seed=h.seed)
    assert judged(h, again) == "right"
    assert "backlash" in {f.extension.effect for f in again.findings}


@pytest.mark.slow
def test_a_run_is_designed_to_show_a_play_the_runs_could_not(tmp_path, capsys):
    """After "no finding": `twin design --effect backlash` weighs the play by simulation."""
    runs = record_runs(MPI, MPI, "roll", tmp_path / "runs", 5, signals=(2,))
    write_report(diagnose(runs, seed=5), tmp_path / "diag", figures=False)
    code = main(["design", str(tmp_path / "diag"), "--effect", "backlash", "--dof", "roll",
                 "--out", str(tmp_path / "design"), "--json", "--quiet"])  # fmt: skip
    assert code == 0
    doc = json.loads((tmp_path / "design" / "design.json").read_text(encoding="utf-8"))
    assert doc["explanations"][0]["label"] == "no effect"
    assert doc["explanations"][1]["extensions"][0]["effect"] == "backlash"
    assert len(doc["amplitudes_tried"]) >= 2  # the largest motion and a few plays
    assert doc["expected_evidence"] and all(e["delta_bic"] > 0 for e in doc["expected_evidence"])
    assert (tmp_path / "design" / "commands.csv").is_file()
    capsys.readouterr()
    assert main(["design", str(tmp_path / "diag"), "--effect", "noise", "--dof", "roll",
                 "--out", str(tmp_path / "no")]) == 2  # fmt: skip
    err = capsys.readouterr().err
    assert "backlash" in err and "'noise'" in err and err.count("\n") == 1


@pytest.mark.slow
def test_only_frequencies_a_sine_moves_beyond_the_play_through_are_chosen(weighed):
    """A play with an advance against the same play with a lead differ most at high frequency,
    where no sine the limits allow moves a few plays: those frequencies are not tried (small
    fast lines riding on a large slow one were: the diagnosis then named a wrong cause)."""
    case, _ = weighed
    advance = Extension("delay", {"extra_delay_s": -0.008}, ("roll",))
    lead = Extension("lead", {"time_constant_s": 0.008}, ("roll",))
    expls = [Explanation("play + advance", (BACKLASH, advance)),
             Explanation("play + lead", (BACKLASH, lead))]  # fmt: skip
    plan = design_run(case, expls, "roll")
    # 3 rad/s^2, the most the MPI's roll takes, moves 3 plays of 4 mrad up to 2.5 Hz
    assert max(plan.signal.frequencies_hz) <= 2.0
