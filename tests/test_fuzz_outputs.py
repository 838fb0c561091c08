"""Fuzzed output paths: no command ever deletes or replaces its input or a user's file.

Every command that reads a recorded run (or a file) and writes an output is pointed, with and
without ``--overwrite``, at every place an output can collide with what it must keep: the input
itself, the folder holding it, a file in it, a new folder inside it, a user's file beside it,
the whole work folder. Each case must exit 0 or 2 (one line, no traceback), leave the input
and the user's files byte for byte as they were (a user's file beside the input may be
replaced only where it was named with ``--overwrite``), and leave no staging file behind.

The fast suite tries every eighth case; ``make fuzz`` tries them all.
"""

from __future__ import annotations

import hashlib
import itertools
import shutil
from pathlib import Path

import numpy as np
import pytest
from cli_contract import assert_answered, run_cli

from twin.core.ownership import MANIFEST


def _hashes(folder: Path) -> dict[str, str]:
    return {p.relative_to(folder).as_posix(): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file()}  # fmt: skip


@pytest.fixture(scope="module")
def source(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A 6 s recorded run (heave sine) copied as a lab would hand it over (no manifest)."""
    root = tmp_path_factory.mktemp("outputs")
    t = np.arange(601) / 100.0
    cmd = np.zeros((t.size, 7))
    cmd[:, 0], cmd[:, 3] = t, 0.01 * np.sin(2 * np.pi * t)
    np.savetxt(root / "commands.csv", cmd, delimiter=",", fmt="%.10g", comments="",
               header="t,x,y,z,roll,pitch,yaw")  # fmt: skip
    argv = ["simulate", "srs", "--model", "reduced", "--signal", str(root / "commands.csv"),
            "--out", str(root / "sim"), "--quiet"]  # fmt: skip
    assert run_cli(argv)[0] == 0
    run = root / "run"
    run.mkdir()
    for p in (root / "sim").iterdir():
        if p.name != MANIFEST:
            shutil.copy(p, run / p.name)
    (run / "lab-notes.md").write_text("the lab's notes on this run")
    return run


#: Commands that read the input (RUN) and write an output (OUT: its place).
COMMANDS = {
    "agard noise --out": ["agard", "noise", "RUN", "--out", "OUT"],
    "agard df --rrd": ["agard", "df", "RUN", "--rrd", "OUT"],
    "simulate --signal RUN --out": ["simulate", "srs", "--model", "reduced", "--signal", "RUN",
                                    "--out", "OUT"],
    "import RUN --out": ["import", "RUN/commands.csv", "RUN/imu.csv", "--platform", "srs",
                         "--out", "OUT"],
    "simulate --signal RUN --rrd": ["simulate", "srs", "--model", "reduced", "--signal", "RUN",
                                    "--out", "NEW", "--rrd", "OUT"],
    "pilot run --out": ["pilot", "run", "condition-1", "--out", "OUT"],
}  # fmt: skip
#: Where the output goes, relative to the work folder holding ``data/run`` and ``data/notes.md``.
TARGETS = {
    "the input": "data/run",
    "the input's folder": "data",
    "a file of the input": "data/run/imu.csv",
    "the input's meta.json": "data/run/meta.json",
    "a new place in the input": "data/run/new.rrd",
    "a user's file beside it": "data/notes.md",
    "a user's recording": "data/old.rrd",
    "the work folder": ".",
}
CASES = list(itertools.product(COMMANDS, TARGETS, (False, True)))


def _case(source: Path, work: Path, command: str, target: str, overwrite: bool) -> None:
    data = work / "data"
    shutil.copytree(source, data / "run")
    (data / "notes.md").write_text("the user's notes")
    (data / "old.rrd").write_text("a recording the twin did not write")
    before = _hashes(data)
    out = str(work / TARGETS[target])
    argv = [out if a == "OUT" else a for a in COMMANDS[command]]
    argv = [a.replace("RUN", str(data / "run")) if "RUN" in a else a for a in argv]
    argv = [str(work / "new") if a == "NEW" else a for a in argv]
    argv += ["--quiet"] + (["--overwrite"] if overwrite else [])
    code, err = run_cli(argv)
    shown = " ".join(argv)
    assert_answered(argv, code, err)
    after = _hashes(data)
    named = Path(out).resolve().relative_to(data.resolve()).as_posix() if (
        Path(out).resolve().is_relative_to(data.resolve())) else None  # fmt: skip
    reads_run = any("RUN" in a for a in COMMANDS[command])
    for rel, h in before.items():
        if overwrite and rel == named and not (reads_run and rel.startswith("run/")):
            continue  # a file named with --overwrite that is no input may be replaced
        assert after.get(rel) == h, f"twin {shown} changed {rel} (exit {code}: {err.strip()})"
    if "RUN" in COMMANDS[command]:  # nothing added to an input folder, not even a manifest
        added = sorted(set(after) - set(before))
        assert not [a for a in added if a.startswith("run/")], f"twin {shown} added {added}"
    staging = [p for p in work.rglob(".*") if p.name != MANIFEST]
    assert not staging, f"twin {shown} left {staging}"


def _id(case: tuple[str, str, bool]) -> str:
    return f"{case[0]} -> {case[1]}{' --overwrite' if case[2] else ''}"


@pytest.mark.parametrize("case", CASES[::8], ids=_id)
def test_outputs_onto_inputs_and_users_files(case, source, tmp_path) -> None:
    _case(source, tmp_path, *case)


@pytest.mark.slow
@pytest.mark.parametrize("case", [c for c in CASES if c not in CASES[::8]], ids=_id)
def test_every_output_collision(case, source, tmp_path) -> None:
    _case(source, tmp_path, *case)
