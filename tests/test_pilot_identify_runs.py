"""twin.pilot.identification.identify_runs: the pilot identified from recorded runs."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from twin.cli.main import main
from twin.core.errors import SignalError, UsageError
from twin.pilot.identification.identify_runs import PilotIdentification, identify


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """Two repetitions of condition 8 flown by the twin's pilot (``pilot run --runs 2``)."""
    folder = tmp_path_factory.mktemp("pilot")
    assert main(["pilot", "run", "condition-8", "--runs", "2", "--seed", "3", "--quiet",
                 "--out", str(folder / "run.csv")]) == 0  # fmt: skip
    return [str(folder / "run-1.csv"), str(folder / "run-2.csv")]


def test_identify_returns_what_the_command_prints(runs, capsys):
    result = identify(runs, "condition-8")
    assert isinstance(result, PilotIdentification)
    assert result.runs == tuple(runs) and result.motion.config.name == "condition-8"
    doc = result.to_dict()
    assert sorted(doc) == ["arx", "fc", "mle", "motion", "omega_rad_s", "runs"]
    assert len(doc["omega_rad_s"]) == 20  # Table 6.2: 10 + 10 lines
    assert doc["mle"]["parameters"]["k_v"] == pytest.approx(1.5, rel=0.3)
    capsys.readouterr()
    assert main(["pilot", "identify", *runs, "--config", "condition-8", "--json"]) == 0
    assert json.loads(capsys.readouterr().out) == json.loads(json.dumps(doc))
    text = result.format_text()
    assert text.startswith(f"{runs[0]} and 1 more: MLE fit (Eq 6.5-6.7, closed loop through "
                           "condition-8's pitch response, u held over each 10 ms, 2 repetitions "
                           "averaged), VAF ")  # fmt: skip
    assert main(["pilot", "identify", *runs, "--config", "condition-8"]) == 0
    assert capsys.readouterr().out == text + "\n"
    table = result.to_frame()
    assert len(table) == 20 and table["fc_h_pe_gain"].tolist() == doc["fc"]["h_pe_gain"]
    fig = result.plot()
    assert [a.get_title() for a in fig.axes] == [f"H_pe from {result.label}",
                                                 f"H_ptheta from {result.label}"]  # fmt: skip
    assert len(fig.axes[0].lines) == 2  # FC points and the ARX line


def test_identify_without_a_configuration_finds_the_one_the_runs_felt(runs):
    result = identify(runs[:1], continuous_loop=True)
    assert result.motion.to_dict()["source"] == "theta_felt"
    assert result.continuous_loop and result.label == runs[0]
    assert "u continuous" in result.format_text().splitlines()[0]


def test_identify_refuses_what_is_no_set_of_repetitions(runs, tmp_path):
    with pytest.raises(UsageError, match="no runs"):
        identify([])
    with pytest.raises(UsageError, match="given twice: give each repetition once"):
        identify([runs[0], runs[0]])
    short = tmp_path / "short.csv"
    lines = Path(runs[0]).read_text(encoding="utf-8").splitlines()
    short.write_text("\n".join(lines[:100]) + "\n", encoding="utf-8")
    with pytest.raises(SignalError, match=rf"{short}: needs at least 81.92 s of data"):
        identify([str(short)])
