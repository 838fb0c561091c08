"""The shared command line: overrides everywhere, one progress helper, one error path, layers."""

from __future__ import annotations

import argparse
import ast
import io
import json
from pathlib import Path

import pytest

from twin.cli import common
from twin.cli.main import main

TWIN = Path(__file__).resolve().parents[1] / "twin"


def test_simulate_takes_the_configuration_overrides(tmp_path):
    out = tmp_path / "run"
    argv = ["simulate", "srs", "--signal", "rest-2", "--model", "reduced", "--delay-ms", "50",
            "--break-hz", "2", "--no-noise", "--out", str(out), "--quiet"]  # fmt: skip
    assert main(argv) == 0
    meta = json.loads((out / "meta.json").read_text())
    cfg = meta["platform_config"]
    assert cfg["delay_s"] == pytest.approx(0.05)
    assert cfg["filter_break_hz"] == pytest.approx(2.0)
    assert cfg["noise"] is False
    assert meta["model"] == "reduced" and meta["seed"] == 0


def test_no_library_module_imports_the_cli():
    offenders = []
    for path in TWIN.rglob("*.py"):
        if path.parent.name == "cli" and path.parent.parent == TWIN:
            continue
        if path == TWIN / "__main__.py":  # ``python -m twin``: the command itself
            continue
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            names = []
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                names = [node.module]
            if any(n == "twin.cli" or n.startswith("twin.cli.") for n in names):
                offenders.append(str(path.relative_to(TWIN.parent)))
    assert offenders == []


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["simulate", "srs", "--signal", "rest-1", "--seed", "-1"], "seed must be an integer >= 0"),
        (["simulate", "srs", "--signal", "rest-1", "--seed", "x"], "seed must be an integer >= 0"),
        (["simulate", "srs", "--signal", "rest-1", "--delay-ms", "-5"], "delay"),
        (["simulate", "srs"], "the following arguments are required: --signal"),
        (["simulate", "srs", "--signal", "rest-1", "--model", "half"], "invalid choice: 'half'"),
        (["pilot", "lead", "srs", "--break-hz", "-1"], "--break-hz: must be a number in [0, 1000]"),
        (["diagnose", "/no/such/run", "--delay-ms", "10"], "/no/such/run"),
    ],
)
def test_usage_errors_are_one_line_and_exit_2(capsys, tmp_path, argv, message):
    out = [] if argv[0] == "pilot" else ["--out", str(tmp_path / "o")]  # lead writes nothing
    assert main([*argv, *out]) == 2
    err = capsys.readouterr().err
    assert err.startswith("twin: error: ") and message in err and err.count("\n") == 1
    assert not (tmp_path / "o").exists()


def test_seed_type_rejects_negative_seeds():
    with pytest.raises(argparse.ArgumentTypeError, match=r"seed must be an integer >= 0; got -2"):
        common.seed_type("-2")


def test_a_reduced_default_must_say_why():
    with pytest.raises(ValueError, match="--model defaults to full; say why reduced here"):
        common.model_parent("reduced")
    help_text = common.model_parent("reduced", "many runs").format_help()
    assert "default reduced: many runs" in help_text


class _Tty(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_progress_prints_only_on_a_terminal_and_not_when_quiet():
    tty, pipe = _Tty(), io.StringIO()
    common.Progress(stream=tty)("run 1")
    common.Progress(stream=pipe)("run 1")
    common.Progress(quiet=True, stream=tty)("run 1")
    assert tty.getvalue() == "  run 1\n" and pipe.getvalue() == ""
    assert common.progress(argparse.Namespace(quiet=True)).quiet


def test_counted_progress_draws_one_bar_with_an_eta_and_steps_beside_it():
    tty, pipe = _Tty(), io.StringIO()
    for stream in (tty, pipe):
        p = common.Progress(stream=stream)
        p("runs", 0, 4)
        for k in range(1, 5):
            p(f"run {k}")  # a step of the counted job: beside the bar, not a new line
            p("runs", k, 4)
        p("done")
    text = tty.getvalue()
    frames = text.replace("\r", "\n").splitlines()
    assert any("runs:" in f and "4/4" in f and "<" in f for f in frames)  # elapsed<remaining
    assert any("run 3" in f and "runs:" in f for f in frames)
    assert text.rstrip().endswith("done") and text.count("\n  done") == 1
    assert pipe.getvalue() == ""  # not a terminal: nothing
    # late reports from worker threads, also after the bar finished, draw no second bar
    late = _Tty()
    p = common.Progress(stream=late)
    for done in (1, 2, 2, 1):
        p("batches", done, 2)
    frames = late.getvalue().replace("\r", "\n").splitlines()
    assert sum("batches:" in f and "2/2" in f for f in frames) >= 1
    assert not any("batches:" in f and "1/2" in f for f in frames[-2:])
    assert late.getvalue().count("\n") == 1  # one finished bar, one line


def test_execute_reports_progress_at_most_ten_times(tmp_path):
    from twin.chain.signals import builtin_signal
    from twin.chain.simulate import prepare
    from twin.formats.run_folder import execute, run_meta

    run = prepare("srs", builtin_signal("rest-2", 100.0), "reduced", 0)
    steps: list[tuple] = []
    sim = execute(run, run_meta(run, "test"), tmp_path / "r",
                  progress=lambda *a: steps.append(a))  # fmt: skip
    assert 1 <= len(steps) <= 10 and steps[-1] == ("simulated [s]", 2.0, 2.0)
    assert sim.imu.t.size > 0
    meta = json.loads((tmp_path / "r" / "meta.json").read_text())
    assert meta["notes"] == "test" and "limits" in meta


def test_an_agard_test_counts_its_runs_including_skipped_ones():
    """A session announces a test's runs, so progress counts them (a run refused by the
    platform limits still counts) and ends at total/total."""
    from twin.agard.noise_level import run_noise
    from twin.agard.omct import run_omct
    from twin.agard.session import Session
    from twin.measurement.measure import Bench, configure

    counted: list[tuple] = []

    def progress(message, done=None, total=None):
        if done is not None:
            counted.append((done, total))

    with Session(Bench(configure("srs"), "reduced"), progress=progress) as s:
        r = run_omct(s, "heave", fraction=0.1, w_rad_s=(1.0, 3.0), window_s=4.0)
        # a 100 m/s^2 sine breaks the heave limits: refused, but counted
        n = run_noise(s, "heave", amplitudes=(0.05, 100.0), window_s=4.0)
    assert len(r.w_rad_s) == 2 and list(n.skipped) == [100.0]
    assert counted == [(0, 2), (1, 2), (2, 2), (0, 2), (1, 2), (2, 2)]
