"""Strict inputs: files, numbers, recorded runs and the locale.

- every file the twin reads refuses a key it does not know, naming the file, the allowed keys
  and the nearest one (a ``dof`` for ``dofs``, a ``dealy_s``), instead of ignoring it;
- a 5000-digit integer or a document nested too deeply is one line naming the file, not a bug;
- every numeric option is a finite number in a range its help gives;
- options that only shape a simulation are refused on a recorded run, not ignored, and the
  dynamic threshold refuses a run without acceleration steps instead of reporting steps;
- the locale does not matter: files are UTF-8, and a terminal that cannot encode ``°`` gets
  ASCII.

(:mod:`tests.test_fuzz_inputs` misspells every key of every format and splices huge integers.)
"""

from __future__ import annotations

import argparse
import ast
import io
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from cli_contract import fails_in_one_line as _one_line

from twin.cli.main import build_parser, main

ROOT = Path(__file__).resolve().parents[1]
REST = ["simulate", "srs", "--model", "reduced", "--signal", "rest-1", "--quiet"]


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """Recorded runs: a multi-sine without a design (twin simulate), a sine and steps with one."""
    from twin.agard.session import Session
    from twin.chain.signals import single_sine, square_steps
    from twin.measurement.measure import Bench, configure

    root = tmp_path_factory.mktemp("runs")
    argv = ["simulate", "srs", "--model", "reduced", "--signal", "multisine1-pitch", "--quiet"]
    assert main([*argv, "--out", str(root / "multisine")]) == 0
    with Session(Bench(configure("srs"), "reduced"), root / "agard") as s:
        s.measure(single_sine("pitch", 1.0, 0.5, window_s=4.0), "sine")
        s.measure(square_steps("pitch", 0.1, 0.5), "steps")
    return {"multisine": root / "multisine", "sine": root / "agard" / "runs" / "00-sine",
            "steps": root / "agard" / "runs" / "01-steps"}  # fmt: skip


# --- unknown keys: refused with the allowed ones and a did-you-mean ------------------------------


def _config(tmp_path: Path, edit) -> Path:
    """A twin-config/1 file of the SRS with one heave gain extension, edited by ``edit``."""
    from twin.chain.config import motion_system
    from twin.chain.extensions import Extension

    ms = motion_system("srs").replace(extensions=(Extension("gain", {"gain": 2.0}, ("heave",)),))
    path = ms.save(tmp_path / "c.json")
    doc = json.loads(path.read_text(encoding="utf-8"))
    edit(doc)
    path.write_text(json.dumps(doc), encoding="utf-8")
    return path


def _rename(node: dict, old: str, new: str) -> None:
    node[new] = node.pop(old)


@pytest.mark.parametrize(
    ("edit", "fragments"),
    [
        (lambda d: _rename(d["platform_config"]["extensions"][0], "dofs", "dof"),
         ("extensions[0]", "unknown key 'dof' (did you mean 'dofs'?)",
          "allowed: effect, parameters, dofs")),
        (lambda d: _rename(d["platform_config"], "delay_s", "dealy_s"),
         ("platform_config: unknown key 'dealy_s' (did you mean 'delay_s'?)",)),
        (lambda d: d["platform_config"].update(dealy_s=0.1),
         ("unknown key 'dealy_s' (did you mean 'delay_s'?)",)),
        (lambda d: _rename(d, "description", "descripton"),
         ("unknown key 'descripton' (did you mean 'description'?)",)),
        (lambda d: _rename(d["platform_config"]["extensions"][0]["parameters"], "gain", "gian"),
         ("effect 'gain': unknown parameter 'gian' (did you mean 'gain'?)",)),
        (lambda d: d["platform_config"]["extensions"][0].update(effect="gian"),
         ("unknown effect 'gian' (did you mean 'gain'?)",)),
    ],
)  # fmt: skip
def test_a_config_file_refuses_unknown_keys(tmp_path, capsys, edit, fragments):
    """A misspelt key of a twin-config/1 file: today's code applies the gain to every DOF
    (``dof`` ignored) or the default delay (``dealy_s`` ignored) and says nothing."""
    cfg = _config(tmp_path, edit)
    out = tmp_path / "o"
    _one_line(capsys, ["simulate", str(cfg), *REST[2:], "--out", str(out)], f"{cfg}: ", *fragments)
    assert not out.exists()


def test_a_misspelt_configuration_name_gets_a_did_you_mean(tmp_path, capsys):
    argv = ["simulate", "conditon-3", *REST[2:], "--out", str(tmp_path / "o")]
    _one_line(capsys, argv, "unknown configuration 'conditon-3' (did you mean 'condition-3'?)")


def test_a_sweep_file_refuses_unknown_keys_with_a_did_you_mean(tmp_path, capsys):
    grid = tmp_path / "grid.toml"
    cases = [
        ('task = "df"\ndealy_ms = 35\n', "unknown key 'dealy_ms' (did you mean 'delay_ms'?)"),
        ('task = "df"\n[grid]\nbreak = [1.0]\n', "unknown axis 'break' (did you mean 'break_hz'?)"),
        ('tsk = "df"\n', "unknown key 'tsk' (did you mean 'task'?)"),
    ]
    for text, message in cases:
        grid.write_text(text, encoding="utf-8")
        _one_line(capsys, ["sweep", str(grid), "--out", str(tmp_path / "o"), "--quiet"],
                  str(grid), message)  # fmt: skip


def test_omct_bounds_refuse_unknown_keys(tmp_path, capsys, runs):
    from twin.agard.omct import EXAMPLE_BOUNDS

    text = Path(EXAMPLE_BOUNDS).read_text(encoding="utf-8")
    bad = tmp_path / "b.toml"
    for old, new, message in [
        ("title =", "titel =", "unknown key 'titel' (did you mean 'title'?)"),
        ("gain_min =", "gain_mn =", "[default]: unknown key 'gain_mn' (did you mean 'gain_min'?)"),
        ("[default]", "[defualt]", "unknown table 'defualt' (did you mean 'default'?)"),
    ]:
        bad.write_text(text.replace(old, new, 1), encoding="utf-8")
        argv = ["agard", "omct", str(runs["sine"]), "--bounds", str(bad), "--quiet"]
        _one_line(capsys, argv, str(bad), message)


def test_platform_toml_and_build_toml_refuse_unknown_keys(tmp_path, monkeypatch):
    """The model folder's files: a misspelt platform.toml key would be ignored today."""
    from twin.core.errors import ModelFileError
    from twin.platform.build import read_build_parameters
    from twin.platform.facts import load_facts, model_dir

    folder = tmp_path / "models" / "simona_srs"
    folder.mkdir(parents=True)
    text = (model_dir("srs") / "platform.toml").read_text(encoding="utf-8")
    (folder / "platform.toml").write_text(text.replace("\nnoise =", "\nnoice ="), encoding="utf-8")
    build = (model_dir("srs") / "build.toml").read_text(encoding="utf-8")
    (folder / "build.toml").write_text(build.replace("\nstroke =", "\nstrok ="), encoding="utf-8")
    monkeypatch.setenv("TWIN_MODELS_DIR", str(tmp_path / "models"))
    load_facts.cache_clear()
    try:
        with pytest.raises(ModelFileError, match=r"\[motion_system\]: unknown key 'noice' "
                           r"\(did you mean 'noise'\?\)"):  # fmt: skip
            load_facts("srs")
    finally:
        load_facts.cache_clear()
    with pytest.raises(ModelFileError, match=r"unknown key 'strok' \(did you mean 'stroke'\?\)"):
        read_build_parameters(folder / "build.toml")


# --- huge integers, deep nesting ---------------------------------------------------------------


def test_a_5000_digit_integer_or_deep_nesting_is_one_line_naming_the_file(tmp_path, capsys, runs):
    """Python refuses to read an integer of more than 4300 digits (a ValueError) and nesting
    deeper than its stack (a RecursionError): today both are internal errors (exit 70)."""
    huge = "9" * 5000
    cfg = _config(tmp_path, lambda d: None)
    text = cfg.read_text(encoding="utf-8")
    out = tmp_path / "o"
    for bad in (text.replace('"delay_s": 0.025', f'"delay_s": {huge}'),
                "[" * 100_000 + "]" * 100_000):  # fmt: skip
        cfg.write_text(bad, encoding="utf-8")
        _one_line(capsys, ["simulate", str(cfg), *REST[2:], "--out", str(out)], f"{cfg}: ",
                  "not valid JSON")  # fmt: skip
    grid = tmp_path / "grid.toml"
    for bad in (f'task = "df"\nseed = {huge}\n', "task = " + "[" * 100_000 + "]" * 100_000):
        grid.write_text(bad, encoding="utf-8")
        _one_line(capsys, ["sweep", str(grid), "--out", str(out), "--quiet"], f"{grid}: ",
                  "not valid TOML")  # fmt: skip
    bounds = tmp_path / "b.toml"
    bounds.write_text(f'format = "twin-omct-bounds/1"\ntitle = {huge}\n', encoding="utf-8")
    argv = ["agard", "omct", str(runs["sine"]), "--bounds", str(bounds), "--quiet"]
    _one_line(capsys, argv, f"{bounds}: ", "integer with too many digits")
    assert not out.exists()


# --- numbers on the command line ------------------------------------------------------------------


def _actions(parser: argparse.ArgumentParser):
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for sub in action.choices.values():
                yield from _actions(sub)
        else:
            yield parser.prog, action


def test_every_numeric_option_has_a_range_given_in_its_help():
    """No option is a bare ``float`` or ``int`` (which take nan, inf, -1 and 1e9); each takes
    a :class:`twin.cli.common.Number`, whose range its help shows."""
    from twin.cli.common import Number

    numeric = [(prog, a) for prog, a in _actions(build_parser())
               if a.type in (float, int) or isinstance(a.type, Number)]  # fmt: skip
    assert len(numeric) > 40
    bare = [f"{prog} {a.option_strings}" for prog, a in numeric if not isinstance(a.type, Number)]
    assert bare == []
    unsaid = [f"{prog} {a.option_strings}" for prog, a in numeric if a.type.span not in a.help]
    assert unsaid == []


@pytest.mark.parametrize("value", ["nan", "-1", "1e9", "inf", "1001"])
def test_fix_delay_ms_takes_only_a_delay_the_fit_can_have(capsys, runs, value):
    """``agard threshold --fix-delay-ms nan`` was an internal error; -1, 1e9 and inf were fitted."""
    argv = ["agard", "threshold", str(runs["steps"]), "--fix-delay-ms", value, "--quiet"]
    _one_line(capsys, argv, "argument --fix-delay-ms: must be a number in [0, 1000]; got ")


def test_the_command_line_ranges_are_the_librarys():
    """The parser keeps copies of some bounds (it does not import the heavy modules)."""
    from twin.agard.threshold import MAX_FIT_DELAY_S
    from twin.cli import agard as cli_agard
    from twin.cli import diagnose as cli_diagnose
    from twin.cli import pilot as cli_pilot
    from twin.core.errors import SignalError
    from twin.diagnose.diagnosis import check_options
    from twin.pilot.studies.identified import MAX_FEEDTHROUGH

    assert cli_agard.FIX_DELAY_MS.hi == MAX_FIT_DELAY_S * 1e3
    assert cli_pilot.MAX_FEEDTHROUGH == MAX_FEEDTHROUGH
    rng = cli_diagnose.MAX_HZ
    check_options(rng.hi)
    for outside in (rng.lo, rng.hi * 1.001):
        with pytest.raises(SignalError):
            check_options(outside)
    noise = cli_diagnose.IMU_NOISE
    for inside in (noise.lo, noise.hi):
        check_options(15.0, inside)
    for outside in (noise.lo * 0.999, noise.hi * 1.001):
        with pytest.raises(SignalError):
            check_options(15.0, outside)


# --- a recorded run: simulation options refused, steps required ---------------------------------


@pytest.mark.parametrize(
    "options",
    [["--delay-ms", "50"], ["--break-hz", "2"], ["--model", "full"], ["--model", "reduced"],
     ["--seed", "3"], ["--seed", "0"], ["--no-noise"], ["--resonance"], ["--ideal-imu"],
     ["--delay-ms", "0", "--no-noise"]],
    ids=" ".join,
)  # fmt: skip
def test_simulation_options_are_refused_on_a_recorded_run(capsys, runs, options):
    """``agard df RUN --delay-ms 50`` printed the run's own describing function as if delayed."""
    run = str(runs["multisine"])
    err = _one_line(capsys, ["agard", "df", run, *options, "--quiet"],
                    "only for a test simulated on a configuration", run)  # fmt: skip
    named = err.removeprefix("twin: error: ").split(": only")[0]
    assert all(o in named for o in options if o.startswith("--"))


def test_other_tests_on_a_recorded_run_refuse_them_too(capsys, runs, tmp_path):
    for test in ("noise", "snr", "threshold", "omct"):
        argv = ["agard", test, str(runs["sine"]), "--seed", "1", "--quiet"]
        _one_line(capsys, argv, "--seed: only for a test simulated")
    rrd = tmp_path / "r.rrd"
    _one_line(capsys, ["agard", "df", str(runs["sine"]), "--rrd", str(rrd), "--quiet"], "--rrd: ")
    assert not rrd.exists()


def test_the_threshold_needs_steps(capsys, runs):
    """A multi-sine run gave "steps of 1.59 rad/s^2 lasting 0.01 s" and a fit."""
    _one_line(capsys, ["agard", "threshold", str(runs["sine"]), "--quiet"],
              "a periodic signal (meta.json signal.kind)", "needs acceleration steps")  # fmt: skip
    _one_line(capsys, ["agard", "threshold", str(runs["multisine"]), "--quiet"],
              "the pitch commands hold no acceleration steps")  # fmt: skip
    assert main(["agard", "threshold", str(runs["steps"]), "--json", "--quiet"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["amplitude"] == 0.1 and doc["step_s"] == 0.5


# --- the locale -----------------------------------------------------------------------------------

#: A locale whose text encoding is ASCII, with Python's UTF-8 mode and locale coercion off.
C_LOCALE = {"LC_ALL": "C", "LANG": "C", "PYTHONUTF8": "0", "PYTHONCOERCECLOCALE": "0"}


def _twin_in_c_locale(*argv: str) -> subprocess.CompletedProcess[bytes]:
    env = {k: v for k, v in os.environ.items()
           if not k.startswith(("LC_", "PYTHONIOENCODING", "PYTHONUTF8"))}  # fmt: skip
    env.update(C_LOCALE, PYTHONPATH=str(ROOT))
    return subprocess.run([sys.executable, "-m", "twin.cli", *argv], env=env, cwd=ROOT,
                          capture_output=True, timeout=120)  # fmt: skip


@pytest.mark.slow  # 3 s of subprocesses; the fast suite keeps the UTF-8 files test
def test_a_terminal_that_cannot_encode_degrees_gets_ascii():
    """``twin workspace`` prints degrees and ``agard df --help`` a §: today exit 70 there."""
    done = _twin_in_c_locale("workspace", "srs")
    assert done.returncode == 0, done.stderr
    assert done.stdout.isascii() and b"-25.92deg" in done.stdout and done.stderr == b""
    done = _twin_in_c_locale("agard", "df", "--help")
    assert done.returncode == 0, done.stderr
    assert done.stdout.isascii() and b"(S3.3.3, Table 5.2" in done.stdout


def test_files_are_utf8_whatever_the_locale(tmp_path):
    """The project's own platform.toml (which holds a §) was refused as "not UTF-8"."""
    done = _twin_in_c_locale(*REST, "--out", str(tmp_path / "run"))
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "run" / "meta.json").is_file()


def test_fit_streams_spells_in_ascii_only_where_needed():
    from twin.cli.terminal import fit_streams

    ascii_bytes, utf8_bytes = io.BytesIO(), io.BytesIO()
    ascii_out = io.TextIOWrapper(ascii_bytes, encoding="ascii")
    utf8_out = io.TextIOWrapper(utf8_bytes, encoding="utf-8")
    plain = io.StringIO()
    fit_streams(ascii_out, utf8_out, plain)
    text = "25.9° ± 0.1 (§3.3.4)"
    for stream in (ascii_out, utf8_out, plain):
        stream.write(text)
        stream.flush()
    ascii_out.write(" \udcff")  # a byte of a file name the locale could not decode: as it was
    ascii_out.flush()
    assert ascii_bytes.getvalue() == b"25.9deg +/- 0.1 (S3.3.4) \xff"
    assert utf8_bytes.getvalue() == text.encode() and utf8_out.errors == "strict"
    assert plain.getvalue() == text


def _calls_without_encoding(path: Path) -> list[str]:
    """``open``, ``.open``, ``.read_text`` and ``.write_text`` calls that name no encoding."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    found = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.Call):
            continue
        f = node.func
        text_io = (isinstance(f, ast.Attribute) and f.attr in ("open", "read_text", "write_text")
                   and not (isinstance(f.value, ast.Name) and f.value.id == "os")) or (
                   isinstance(f, ast.Name) and f.id == "open")  # fmt: skip
        modes = [a.value for a in node.args if isinstance(a, ast.Constant)]
        binary = any(isinstance(m, str) and "b" in m for m in modes)
        written = ast.unparse(node.args[0]) if node.args else ""
        ascii_json = written.startswith("json.dumps(") and "ensure_ascii" not in written
        if text_io and not binary and not ascii_json and all(k.arg != "encoding"
                                                             for k in node.keywords):  # fmt: skip
            found.append(f"{path.relative_to(ROOT)}:{node.lineno}")
    return found


def test_every_text_file_is_read_and_written_as_utf8():
    """Without ``encoding=`` Python uses the locale's (ASCII under ``LC_ALL=C``): ``agard report``
    could not write its summary.md, ``twin diagnose`` its own."""
    found = [c for p in sorted((ROOT / "twin").rglob("*.py")) for c in _calls_without_encoding(p)]
    assert found == []  # (json.dumps writes ASCII: allowed without)
