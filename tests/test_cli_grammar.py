"""One grammar for every ``twin`` command: CONFIG, --dof, --quiet, --overwrite, --json, --out.

The parser is walked from :func:`twin.cli.main.build_parser`, so a command added later is
held to the same rules.
"""

from __future__ import annotations

import argparse
import json
import re
from collections.abc import Iterator

import pytest

from twin.cli import common
from twin.cli.main import build_parser, main

#: Commands that take a motion system as their first positional.
MOTION_SYSTEM_COMMANDS = {
    "workspace", "simulate", "compare", "dynamics", "pilot run", "pilot adapt", "pilot lead",
    "agard report", *(f"agard {t}" for t in ("df", "noise", "snr", "threshold", "omct",
                                             "parasitic", "linearity", "hysteresis", "bump",
                                             "limits")),
}  # fmt: skip
#: Commands whose ``--dof`` takes one DOF.
ONE_DOF_COMMANDS = {
    "design", *(f"agard {t}" for t in ("df", "noise", "snr", "threshold", "omct", "parasitic",
                                       "linearity", "hysteresis", "bump", "limits")),
}  # fmt: skip
#: The output path types of :mod:`twin.cli.common`.
OUTPUT_TYPES = (common.output_dir, common.output_file, common.rrd_file, common.csv_file,
                common.figure_file)  # fmt: skip


def _leaves(
    parser: argparse.ArgumentParser, path: tuple[str, ...] = ()
) -> Iterator[tuple[str, argparse.ArgumentParser]]:
    """Yield each command that runs (``pilot experiment fixed``) and its parser."""
    subs = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    if not subs:
        yield " ".join(path), parser
        return
    for name, sub in subs[0].choices.items():
        yield from _leaves(sub, (*path, name))


LEAVES = dict(_leaves(build_parser()))


def _options(parser: argparse.ArgumentParser) -> set[str]:
    return {s for a in parser._actions for s in a.option_strings}


def _positionals(parser: argparse.ArgumentParser) -> list[argparse.Action]:
    return [a for a in parser._actions if not a.option_strings]


def test_the_walk_finds_every_command():
    assert MOTION_SYSTEM_COMMANDS | ONE_DOF_COMMANDS <= set(LEAVES)
    assert {"pilot experiment fixed", "pilot experiment subjects", "pilot identify", "diagnose",
            "import", "sweep", "agard demo"} <= set(LEAVES)  # fmt: skip
    assert "pilot experiment" not in LEAVES  # only its two subcommands run


@pytest.mark.parametrize("command", sorted(MOTION_SYSTEM_COMMANDS))
def test_a_motion_system_is_the_first_positional_config(command):
    first = _positionals(LEAVES[command])[0]
    assert (first.metavar, first.dest) == ("CONFIG", "config"), command
    assert first.help.startswith(common.config_phrase()), command


def test_positionals_and_config_options_have_one_style_of_metavar():
    for command, parser in LEAVES.items():
        for a in _positionals(parser):
            assert re.fullmatch(r"[A-Z][A-Z_]*", a.metavar or ""), (command, a.metavar)
            assert a.metavar not in ("PLATFORM", "PLATFORM_OR_CONFIG", "CONFIG_OR_RUN"), command
            if a.dest == "config":
                assert a.metavar == "CONFIG"
        for a in parser._actions:
            if "--config" in a.option_strings:
                assert a.metavar == "CONFIG", command


def test_workspace_and_dynamics_take_a_configuration_and_use_its_platform(capsys):
    assert main(["workspace", "condition-3", "--json"]) == 0
    by_config = capsys.readouterr().out
    assert main(["workspace", "srs", "--json"]) == 0
    assert capsys.readouterr().out == by_config
    for command in ("workspace", "dynamics"):
        assert "only its platform matters" in LEAVES[command].format_help()


def test_dynamics_refuses_a_configuration_whose_physics_it_would_ignore(tmp_path, capsys):
    from twin.chain.config import motion_system
    from twin.platform.payload import Payload
    from twin.platform.platform_physics import PlatformPhysics

    heavy = motion_system("srs").replace(physics=PlatformPhysics(payload=Payload.of(200.0)))
    path = tmp_path / "heavy.json"
    heavy.save(path)
    assert main(["dynamics", str(path), "--dof", "heave"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "calibrated physics" in err and "give the platform, srs" in err
    assert main(["workspace", str(path)]) == 0  # the workspace is the geometry's
    assert "Workspace of 'srs'" in capsys.readouterr().out


def test_no_command_has_dofs_and_every_dof_is_one_option_repeated():
    for command, parser in LEAVES.items():
        assert "--dofs" not in _options(parser), command
        for a in parser._actions:
            if "--dof" in a.option_strings:
                assert a.metavar == "DOF" and a.nargs is None, command
                one = type(a).__name__ == "_OneDof"
                assert one == (command in ONE_DOF_COMMANDS), command
                assert one or isinstance(a, argparse._AppendAction), command


def test_repeated_dof_gives_several(monkeypatch, capsys):
    from twin.agard import compare as compare_module

    seen = {}

    def fake_dynamics(platform, dofs, progress=None):
        seen.update(platform=platform, dofs=list(dofs))
        raise KeyboardInterrupt  # stop before any work

    monkeypatch.setattr(compare_module, "platform_dynamics", fake_dynamics)
    assert main(["dynamics", "mpi-2008", "--dof", "pitch", "--dof", "roll"]) == 130
    assert seen == {"platform": "mpi", "dofs": ["pitch", "roll"]}
    capsys.readouterr()


@pytest.mark.parametrize("command", sorted(ONE_DOF_COMMANDS))
def test_a_second_dof_to_a_one_dof_command_is_one_line_exit_2(command, capsys, tmp_path):
    first = ["srs"] if command.startswith("agard") else [str(tmp_path)]
    argv = [*command.split(), *first, "--dof", "pitch", "--dof", "roll"]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("twin: error: argument --dof:")
    assert f"twin {command} takes one DOF; got --dof pitch --dof roll" in err


def test_every_command_that_writes_has_overwrite_with_one_help():
    writers = 0
    for command, parser in LEAVES.items():
        writes = any(a.type in OUTPUT_TYPES for a in parser._actions)
        overwrite = [a for a in parser._actions if "--overwrite" in a.option_strings]
        assert bool(overwrite) == writes, command
        if overwrite:
            writers += 1
            assert overwrite[0].help == common.OVERWRITE_HELP, command
    assert writers >= 20


def test_json_and_quiet_have_one_help_everywhere():
    for command, parser in LEAVES.items():
        for a in parser._actions:
            if "--json" in a.option_strings:
                assert a.help == common.JSON_HELP, command
            if "--quiet" in a.option_strings:
                assert a.help == "no progress on stderr", command


def test_default_output_folders_follow_one_rule():
    """A command that writes a folder by default writes out/<command>-<name>."""
    defaults = {}
    for command, parser in LEAVES.items():
        for a in parser._actions:
            if "--out" in a.option_strings and "(default out/" in (a.help or ""):
                defaults[command] = a.help.split("(default out/", 1)[1]
    assert set(defaults) == {"simulate", "agard report", "agard demo", "design", "diagnose",
                             "import", "sweep"}  # fmt: skip
    for command, shown in defaults.items():
        assert shown.startswith(command.replace(" ", "-")), (command, shown)
    assert str(common.default_out("agard-report", "srs-full")) == "out/agard-report-srs-full"


def _masked(text: str) -> str:
    """The text with the wall-clock figures of ``simulate``'s first line masked."""
    return re.sub(r"simulated in [0-9.]+ s, [0-9]+x real time", "simulated in T", text)


def test_quiet_never_changes_stdout(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    argv = ["pilot", "montecarlo", "--runs", "40", "--scheduler", "inline"]
    assert main(argv) == 0
    loud = capsys.readouterr().out
    assert main([*argv, "--quiet"]) == 0
    assert capsys.readouterr().out == loud != ""
    sim = ["simulate", "srs", "--model", "reduced", "--signal", "rest-1"]
    assert main([*sim, "--out", "a"]) == 0
    loud = capsys.readouterr().out
    assert main([*sim, "--out", "b", "--quiet"]) == 0
    quiet = capsys.readouterr().out
    assert "wrote b (" in quiet and "limit" in quiet.lower()
    assert _masked(quiet).replace("wrote b", "wrote a") == _masked(loud)


def test_simulate_writes_its_default_folder_under_the_rule(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["simulate", "srs", "--model", "reduced", "--signal", "rest-1", "--quiet"]) == 0
    assert (tmp_path / "out" / "simulate-srs-reduced-rest-1-seed0" / "meta.json").is_file()
    assert "wrote out/simulate-srs-reduced-rest-1-seed0 (" in capsys.readouterr().out


FIXED_OPTIONS = {"-h", "--help", "--seed", "--json", "--quiet", "--scheduler", "--runs", "--plot",
                 "--overwrite"}  # fmt: skip
SUBJECTS_OPTIONS = {"-h", "--help", "--seed", "--json", "--quiet", "--scheduler", "--subjects",
                    "--fixed-neuromuscular", "--adapt-visual-delay", "--identify",
                    "--feedthrough", "--motion-spread", "--visual-delay-spread", "--populations",
                    "--plot", "--overwrite"}  # fmt: skip


@pytest.mark.parametrize(("kind", "options"), [("fixed", FIXED_OPTIONS),
                                                ("subjects", SUBJECTS_OPTIONS)])  # fmt: skip
def test_each_experiment_shows_only_its_options(kind, options, capsys):
    with pytest.raises(SystemExit) as done:
        main(["pilot", "experiment", kind, "--help"])
    assert done.value.code == 0
    text = capsys.readouterr().out
    shown = set(re.findall(r"(?<![\w-])(-h|--[a-z][a-z-]*)", text))
    assert shown == options
    assert "--pilot" not in text and "adaptive subjects fly" not in text


def test_an_option_of_the_other_experiment_names_the_command(capsys):
    assert main(["pilot", "experiment", "fixed", "--identify"]) == 2
    err = capsys.readouterr().err
    assert err == ("twin: error: unrecognized arguments: --identify (see `twin pilot experiment "
                   "fixed --help`)\n")  # fmt: skip


def test_experiment_fixed_is_the_former_default_experiment(monkeypatch, capsys):
    """``pilot experiment fixed`` calls the library as ``pilot experiment`` did (5 runs)."""
    from twin.pilot.studies import experiment

    seen = {}

    def fake(**kwargs):
        seen.update(kwargs)
        raise KeyboardInterrupt

    monkeypatch.setattr(experiment, "run_experiment", fake)
    assert main(["pilot", "experiment", "fixed", "--seed", "3", "--scheduler", "inline"]) == 130
    assert (seen["runs"], seen["seed"], seen["fit"]) == (5, 3, True)
    capsys.readouterr()


def test_json_output_is_json(capsys):
    assert main(["pilot", "lead", "srs", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)[0]["sensor"] == "canals"
