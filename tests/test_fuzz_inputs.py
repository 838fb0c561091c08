"""Fuzzed bad input: every command answers with exit 0, or one clear line and exit 2.

Each example runs the ``twin`` command line in this process on a damaged copy of a valid
file of one format: random bytes, a truncation, a splice of odd text (``nan``, ``1e300``, a
NUL, a quote, a byte-order mark, a non-UTF-8 byte, ...), a CSV cell or a JSON/TOML value
replaced by an odd value of another type, a JSON key removed. Odd numbers go to every numeric
option. Well-formed runs that no motion system can have made (:data:`IMPLAUSIBLE`: a valid
run's IMU in other units, axes or order, off its clock, dead, reversed or resampled) go to
``twin agard noise``. Each example must:

- exit with 0 or 2 (70 is a bug: an exception the twin did not expect; warnings are errors
  here, so a silent overflow fails too);
- on 2, print exactly one line, ``twin: error: ...``, and no traceback;
- leave nothing half-written: no hidden staging file or folder, and no output on failure.

The fast suite tries :data:`FAST` examples per format (derandomised: the same examples every
run); ``make test-all`` tries :data:`SLOW` per format and a full-length pilot run, and prints
the counts (docs, reliability).

``make fuzz`` also sends Ctrl-C to the process group of commands at work, at moments drawn
from a generator seeded by the command's name (exit 130 and one line, nothing left), and
points ``--scheduler`` at servers that are not Dask schedulers (exit 2 and one line within
seconds); tests/test_interrupts.py and tests/test_scheduler_probe.py hold one of each.
"""

from __future__ import annotations

import contextlib
import json
import os
import random
import re
import shutil
import struct
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np
import pytest
from cli_contract import assert_answered, run_cli
from fake_servers import closed_port, echoes, http_server, says, silent_listener, tcp_server
from group_signals import (
    ctrl_c,
    finish,
    left_behind,
    start,
    starting_processes,
    wait_until,
    writing_a_run,
)
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from twin.core.ownership import MANIFEST

FAST = 20
SLOW = 300
#: Odd text spliced into files and given to numeric options.
TOKENS = ["", "nan", "NaN", "inf", "-inf", "1e300", "-1e300", "1e-300", "-1", "0", "-0", "1e9",
          "99999999999999999999999", "0x10", "abc", "1e", "\uff11\uff12", "1,5", " 7", "\"",
          "'", ",", ",,", "[", "{", "}", "]", "null", "true", "\n", "\r\n", "\ufeff", "\x00",
          "\u00e9", "9" * 400]  # fmt: skip
#: Odd values of other types put in JSON (and TOML) documents.
_SCALARS = (
    st.none() | st.booleans() | st.integers(-(2**70), 2**70) | st.floats()
    | st.sampled_from(TOKENS) | st.text(max_size=8)
)  # fmt: skip
JSON_VALUES = st.recursive(
    _SCALARS,
    lambda inner: (
        st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=6), inner, max_size=3)
    ),
    max_leaves=6,
)
TOML_VALUES = ['"a"', "[1]", "[[1], 2]", "{a = 1}", "true", "nan", "inf", "-inf", "1e300",
               "[]", '["x", 2]', "-1", "0", "[1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13]",
               "[0.0, 0.0]", '"""', "1979-05-27"]  # fmt: skip


# --- the valid files the examples damage ------------------------------------------------------


@pytest.fixture(scope="module")
def valid(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """Valid files of every format, and a small recorded run (6 s, 1 Hz heave sine)."""
    root = tmp_path_factory.mktemp("valid")
    t = np.arange(601) / 100.0
    cmd = np.zeros((t.size, 7))
    cmd[:, 0], cmd[:, 3] = t, 0.01 * np.sin(2 * np.pi * t)
    (root / "cmd").mkdir()
    np.savetxt(root / "cmd" / "commands.csv", cmd, delimiter=",", fmt="%.10g", comments="",
               header="t,x,y,z,roll,pitch,yaw")  # fmt: skip
    run = root / "run"
    argv = ["simulate", "srs", "--model", "reduced", "--signal", str(root / "cmd" / "commands.csv"),
            "--out", str(run), "--quiet"]  # fmt: skip
    assert run_cli(argv)[0] == 0
    from twin.chain.config import motion_system

    motion_system("mpi").save(root / "config.json")
    pilot = root / "pilot.csv"  # 6 s: read in full, then refused as too short for the analysis
    cols = {k: np.sin(t * (i + 1)) * 0.01 for i, k in enumerate(("ft", "fd", "e", "u", "theta"))}
    from twin.pilot.models.records import write_pilot_csv

    write_pilot_csv(pilot, {"t": t, **cols, "theta_felt": cols["theta"]})
    from twin.agard.omct import EXAMPLE_BOUNDS

    shutil.copy(EXAMPLE_BOUNDS, root / "bounds.toml")
    (root / "grid.toml").write_text(
        'task = "df"\nmodel = "reduced"\nconfig = "srs"\ndof = "heave"\n[grid]\ndelay_ms = [25]\n'
    )
    lab = root / "lab.csv"  # a lab log: commands and IMU in one file, its own names and units
    imu = np.loadtxt(run / "imu.csv", delimiter=",", skiprows=1)[::8]
    heave_mm = np.interp(imu[:, 0], t, cmd[:, 3]) * 1e3
    rows = np.column_stack([imu[:, 0], heave_mm, imu[:, 3] / 9.81])
    np.savetxt(lab, rows, delimiter=",", fmt="%.8g", comments="", header="time_s,heave_mm,AccZ (g)")
    files = {"commands.csv": root / "cmd" / "commands.csv", "twin-config/1": root / "config.json",
             "twin-pilot/1": pilot, "omct-bounds": root / "bounds.toml",
             "sweep": root / "grid.toml", "lab-csv": lab}  # fmt: skip
    return {"root": root, "run": run, **files}


# --- damage ----------------------------------------------------------------------------------


def _splices(data: bytes) -> st.SearchStrategy[bytes]:
    """Random bytes, a truncation, or odd text (or bytes) spliced in anywhere."""
    n = len(data)
    odd = (
        st.sampled_from(TOKENS).map(lambda s: s.encode())
        | st.binary(max_size=12)
        | st.just(b"\xff\xfe")
    )
    splice = st.tuples(st.integers(0, n), st.integers(0, 40), odd).map(
        lambda a: data[: a[0]] + a[2] + data[a[0] + a[1] :]
    )
    return st.binary(max_size=600) | st.integers(0, n).map(lambda k: data[:k]) | splice


def _csv_cells(data: bytes) -> st.SearchStrategy[bytes]:
    """One cell of a CSV (header included) replaced by an odd value."""
    lines = data.decode().split("\n")

    def put(a: tuple[int, int, str]) -> bytes:
        row, col, token = a
        cells = lines[row % len(lines)].split(",")
        cells[col % len(cells)] = token
        out = list(lines)
        out[row % len(lines)] = ",".join(cells)
        return "\n".join(out).encode("utf-8", "surrogatepass")

    rows = st.integers(0, 3) | st.integers(0, len(lines) - 1)  # the header and first rows often
    return st.tuples(rows, st.integers(0, 9), st.sampled_from(TOKENS)).map(put)


def _json_values(data: bytes) -> st.SearchStrategy[bytes]:
    """A value anywhere in a JSON document replaced by one of another type, or a key removed."""
    doc = json.loads(data)
    paths: list[tuple] = []

    def walk(node: object, path: tuple) -> None:
        paths.append(path)
        items = (
            node.items()
            if isinstance(node, dict)
            else enumerate(node)
            if isinstance(node, list)
            else ()
        )
        for k, v in items:
            walk(v, (*path, k))

    walk(doc, ())

    def put(a: tuple[int, object, bool]) -> bytes:
        path, value, remove = paths[a[0] % len(paths)], a[1], a[2]
        new = json.loads(data)
        if not path:
            new = value
        else:
            node = new
            for k in path[:-1]:
                node = node[k]
            if remove and isinstance(node, dict):
                del node[path[-1]]
            else:
                node[path[-1]] = value
        return json.dumps(new).encode()

    return st.tuples(st.integers(0, 10_000), JSON_VALUES, st.booleans()).map(put)


def _toml_values(data: bytes) -> st.SearchStrategy[bytes]:
    """A value of a TOML document (``key = value``) replaced by one of another type."""
    text = data.decode()
    spots = [m.span(1) for m in re.finditer(r"=\s*(.+)$", text, flags=re.M)]

    def put(a: tuple[int, str]) -> bytes:
        lo, hi = spots[a[0] % len(spots)]
        return (text[:lo] + a[1] + text[hi:]).encode()

    return st.tuples(st.integers(0, 10_000), st.sampled_from(TOML_VALUES)).map(put)


class Damaged(bytes):
    """A damaged file: bytes whose repr in a failure report is short (a run's imu.csv is 0.5 MB)."""

    def __repr__(self) -> str:
        head = bytes(self[:160])
        return f"Damaged({head!r}{'...' if len(self) > 160 else ''}, {len(self)} bytes)"


# --- one example ----------------------------------------------------------------------------


def _leftovers(where: Path) -> list[str]:
    """Hidden files or folders (staging names) anywhere under ``where`` (not manifests)."""
    return [str(p) for p in where.rglob(".*") if p.name != MANIFEST]


def check_clean(argv: list[str], work: Path, out: Path | None = None) -> int:
    """Run one command and assert the contract of this module; return its exit code."""
    code, err = run_cli(argv)
    shown = " ".join(argv)
    assert_answered(argv, code, err)
    if code == 2:
        assert out is None or not out.exists(), f"twin {shown} failed but wrote {out}"
    assert not _leftovers(work), f"twin {shown} left {_leftovers(work)}"
    return code


# --- the formats, each with a command that reads it ---------------------------------------------

RUN_FILES = ("meta.json", "imu.csv", "actuators.csv", "commands.csv")


def _format_case(
    fmt: str, valid: dict[str, Path], work: Path, data: bytes
) -> tuple[list[str], Path | None]:
    """Write ``data`` as a file of ``fmt`` under ``work``; return the command and its output."""
    out = work / "out"
    if fmt.startswith("run/"):
        run = work / "run"
        shutil.copytree(valid["run"], run)
        (run / fmt[4:]).write_bytes(data)
        return ["agard", "noise", str(run), "--quiet", "--json"], None
    if fmt == "commands.csv":
        (work / "cmd").mkdir()
        f = work / "cmd" / "commands.csv"
        f.write_bytes(data)
        return ["simulate", "srs", "--model", "reduced", "--signal", str(f), "--out", str(out),
                "--quiet"], out  # fmt: skip
    f = work / valid[fmt].name
    f.write_bytes(data)
    if fmt == "twin-config/1":
        return ["simulate", str(f), "--model", "reduced", "--signal", "rest-1", "--out", str(out),
                "--quiet"], out  # fmt: skip
    if fmt == "twin-pilot/1":
        return ["pilot", "identify", str(f), "--quiet", "--json"], None
    if fmt == "omct-bounds":
        return ["agard", "omct", str(valid["run"]), "--bounds", str(f), "--quiet", "--json"], None
    if fmt == "sweep":
        return ["sweep", str(f), "--scheduler", "inline", "--out", str(out), "--quiet"], out
    return ["import", str(f), "--platform", "srs", "--out", str(out), "--quiet"], out


def _original(fmt: str, valid: dict[str, Path]) -> bytes:
    return (valid["run"] / fmt[4:] if fmt.startswith("run/") else valid[fmt]).read_bytes()


MUTATORS: dict[str, Callable[[bytes], st.SearchStrategy[bytes]]] = {
    "run/meta.json": lambda d: _splices(d) | _json_values(d),
    "run/imu.csv": lambda d: _splices(d) | _csv_cells(d),
    "run/actuators.csv": lambda d: _splices(d) | _csv_cells(d),
    "run/commands.csv": lambda d: _splices(d) | _csv_cells(d),
    "commands.csv": lambda d: _splices(d) | _csv_cells(d),
    "twin-config/1": lambda d: _splices(d) | _json_values(d),
    "twin-pilot/1": lambda d: _splices(d) | _csv_cells(d),
    "omct-bounds": lambda d: _splices(d) | _toml_values(d),
    "sweep": lambda d: _splices(d) | _toml_values(d),
    "lab-csv": lambda d: _splices(d) | _csv_cells(d),
}


def _run_fuzz(
    damage: st.SearchStrategy[bytes],
    case: Callable[[Path, bytes], tuple[list[str], Path | None]],
    root: Path,
    examples: int,
) -> tuple[int, int]:
    """Try ``examples`` damaged files (``case`` writes one and gives its command and output)."""
    counts = [0, 0]

    @settings(max_examples=examples, derandomize=True, deadline=None, database=None,
              suppress_health_check=list(HealthCheck))  # fmt: skip
    @given(damage.map(Damaged))
    def one(data: bytes) -> None:
        with tempfile.TemporaryDirectory(dir=root) as tmp:
            argv, out = case(Path(tmp), data)
            code = check_clean(argv, Path(tmp), out)
        counts[0] += 1
        counts[1] += code == 0

    one()
    return counts[0], counts[1]


def _fuzz(fmt: str, valid: dict[str, Path], examples: int) -> tuple[int, int]:
    """Try ``examples`` damaged files of ``fmt``; return (tried, accepted with exit 0)."""
    damage = MUTATORS[fmt](_original(fmt, valid))
    return _run_fuzz(damage, lambda work, data: _format_case(fmt, valid, work, data),
                     valid["root"], examples)  # fmt: skip


@pytest.mark.parametrize("fmt", list(MUTATORS))
def test_damaged_files_get_one_line_or_run(fmt: str, valid: dict[str, Path]) -> None:
    tried, _ = _fuzz(fmt, valid, FAST)
    assert tried >= FAST // 2  # hypothesis may stop early when it has seen every small case


@pytest.mark.slow
@pytest.mark.parametrize("fmt", list(MUTATORS))
def test_many_damaged_files_get_one_line_or_run(fmt: str, valid: dict[str, Path]) -> None:
    tried, ok = _fuzz(fmt, valid, SLOW)
    print(f"\nfuzz {fmt}: {tried} tried, {tried} clean ({ok} accepted, {tried - ok} refused)")


@pytest.mark.slow
def test_damaged_full_pilot_runs_get_one_line_or_are_identified(valid: dict[str, Path]) -> None:
    """A full-length ``twin-pilot/1`` run (the analysis runs: FC, ARX, MLE) with one cell odd."""
    full = valid["root"] / "full" / "pilot.csv"
    argv = ["pilot", "run", "condition-1", "--out", str(full), "--quiet"]
    assert run_cli(argv)[0] == 0

    def case(work: Path, data: bytes) -> tuple[list[str], Path | None]:
        (work / "pilot.csv").write_bytes(data)
        return ["pilot", "identify", str(work / "pilot.csv"), "--quiet"], None

    tried, ok = _run_fuzz(_csv_cells(full.read_bytes()), case, valid["root"], SLOW // 10)
    print(f"\nfuzz twin-pilot/1 (full length): {tried} tried, {tried} clean "
          f"({ok} accepted, {tried - ok} refused)")  # fmt: skip


def test_the_valid_files_and_a_byte_order_mark_are_accepted(valid: dict[str, Path]) -> None:
    """The damage is what fails: the originals run, and so do they with a BOM in front."""
    for fmt in MUTATORS:
        if fmt in ("twin-pilot/1",):  # valid but 6 s long: refused as too short, by design
            continue
        for prefix in (b"", b"\xef\xbb\xbf"):
            with tempfile.TemporaryDirectory(dir=valid["root"]) as tmp:
                argv, out = _format_case(fmt, valid, Path(tmp), prefix + _original(fmt, valid))
                assert check_clean(argv, Path(tmp), out) == 0, (fmt, prefix)


# --- physically implausible but well-formed runs ---------------------------------------------

#: Transformations of a valid run's IMU that keep the format: a unit factor on a
#: channel, channels in another order, the IMU's clock shifted, a channel held constant or
#: offset, the IMU time-reversed (another run's), resampled (its rate in meta.json follows).
IMPLAUSIBLE = st.lists(
    st.tuples(st.just("scale"), st.integers(0, 5),
              st.sampled_from([0.0, -1.0, 1 / 9.81, 9.81, float(np.degrees(1.0)), 1e-3, 50.0]))
    | st.tuples(st.just("permute"), st.permutations(range(6)))
    | st.tuples(st.just("shift"), st.sampled_from([-2.0, -0.5, -0.05, 0.05, 0.3, 0.5, 2.0, 1e3]))
    | st.tuples(st.just("constant"), st.integers(0, 5), st.sampled_from([0.0, -9.81, 1.0]))
    | st.tuples(st.just("offset"), st.integers(0, 5), st.sampled_from([-9.81, 9.81, 0.5]))
    | st.tuples(st.just("reverse"))
    | st.tuples(st.just("rate"), st.sampled_from([1 / 16, 1 / 8, 1 / 2, 2, 5, 25])),
    min_size=1,
    max_size=3,
).map(lambda ops: json.dumps(ops).encode())  # fmt: skip


def _implausible(run: Path, ops: list[list]) -> None:
    """Apply transformations of :data:`IMPLAUSIBLE` to the IMU of the run folder ``run``."""
    data = np.loadtxt(run / "imu.csv", delimiter=",", skiprows=1)
    t, v = data[:, 0], data[:, 1:].copy()
    meta = json.loads((run / "meta.json").read_text())
    rate = meta["imu"]["rate_hz"]
    for op, *a in ops:
        if op in ("scale", "constant", "offset"):
            k, x = a
            v[:, k] = v[:, k] * x if op == "scale" else (x if op == "constant" else v[:, k] + x)
        elif op == "permute":
            v = v[:, a[0]]
        elif op == "shift":
            t = t + a[0]
        elif op == "reverse":
            v = v[::-1].copy()
        elif a[0] < 1:  # rate: every k-th sample
            k = round(1 / a[0])
            t, v, rate = t[::k], v[::k], rate / k
        else:  # rate: linear interpolation a[0] times as fast
            tn = t[0] + np.arange(int((len(t) - 1) * a[0]) + 1) / (rate * a[0])
            v = np.column_stack([np.interp(tn, t, v[:, j]) for j in range(6)])
            t, rate = tn, rate * a[0]
    np.savetxt(run / "imu.csv", np.column_stack([t, v]), delimiter=",", fmt="%.10g",
               header="t,ax,ay,az,p,q,r", comments="")  # fmt: skip
    meta["imu"]["rate_hz"] = rate
    (run / "meta.json").write_text(json.dumps(meta))


def _implausible_case(valid: dict[str, Path], work: Path, data: bytes) -> tuple[list[str], None]:
    run = work / "run"
    shutil.copytree(valid["run"], run)
    _implausible(run, json.loads(data))
    return ["agard", "noise", str(run), "--quiet", "--json"], None


def _fuzz_implausible(valid: dict[str, Path], examples: int) -> tuple[int, int]:
    return _run_fuzz(IMPLAUSIBLE, lambda work, data: _implausible_case(valid, work, data),
                     valid["root"], examples)  # fmt: skip


def test_implausible_runs_get_one_line_or_run(valid: dict[str, Path]) -> None:
    """Well-formed runs a motion system cannot have made: read (exit 0) or one clear line,
    and most are refused: at most a third read (some transformations touch only channels
    nothing drives; before the plausibility checks, 15 of these 20 were read)."""
    tried, ok = _fuzz_implausible(valid, FAST)
    assert tried >= FAST // 2 and ok <= tried // 3


@pytest.mark.slow
def test_many_implausible_runs_get_one_line_or_run(valid: dict[str, Path]) -> None:
    tried, ok = _fuzz_implausible(valid, SLOW)
    assert ok <= tried // 3
    print(f"\nfuzz implausible runs: {tried} tried, {tried} clean ({ok} accepted, "
          f"{tried - ok} refused)")  # fmt: skip


# --- odd numbers on the command line ----------------------------------------------------------

#: Numeric options, each in a command that is quick when the value is allowed (X: the value).
SLOTS = [
    ["simulate", "srs", "--model", "reduced", "--signal", "rest-1", "--delay-ms", "X"],
    ["simulate", "srs", "--model", "reduced", "--signal", "rest-1", "--break-hz", "X"],
    ["simulate", "srs", "--model", "reduced", "--signal", "rest-1", "--seed", "X"],
    ["simulate", "srs", "--model", "reduced", "--signal", "rest-X"],
    ["pilot", "lead", "srs", "--margin-deg", "X"],
    ["pilot", "lead", "srs", "--delay-ms", "X"],
    ["agard", "omct", "srs", "--dof", "pitch", "--model", "reduced", "--fraction", "X"],
    ["agard", "threshold", "RUN", "--amplitude", "X"],
    ["agard", "threshold", "RUN", "--fix-delay-ms", "X"],
    ["agard", "df", "RUN", "--delay-ms", "X"],
    ["import", "RUN/commands.csv", "RUN/imu.csv", "--platform", "srs", "--clock-offset", "X"],
    ["import", "RUN/commands.csv", "RUN/imu.csv", "--platform", "srs", "--imu-position", "X", "0",
     "0"],
]  # fmt: skip
#: Numeric options whose allowed values start longer work (``make test-all`` only).
SLOW_SLOTS = [
    ["pilot", "montecarlo", "--runs", "2", "--fit-runs", "X", "--scheduler", "inline"],
    ["pilot", "montecarlo", "--runs", "X", "--scheduler", "inline"],
    ["pilot", "run", "srs", "--runs", "X"],
    ["pilot", "run", "srs", "--remnant", "X"],
    ["pilot", "adapt", "srs", "--weight", "X"],
    ["agard", "threshold", "srs", "--dof", "pitch", "--model", "reduced", "--amplitude", "X"],
    ["agard", "threshold", "srs", "--dof", "pitch", "--model", "reduced", "--step-s", "X"],
    ["agard", "threshold", "srs", "--dof", "pitch", "--model", "reduced", "--repeats", "X"],
    ["agard", "threshold", "srs", "--dof", "pitch", "--model", "reduced", "--fix-delay-ms", "X"],
    ["diagnose", "RUN", "--max-hz", "X", "--no-figures", "--scheduler", "inline"],
    ["diagnose", "RUN", "--imu-noise", "X", "--no-figures", "--scheduler", "inline"],
]  # fmt: skip
#: Odd values tried in every slot.
NUMBERS = ["nan", "inf", "-inf", "1e300", "-1e300", "1e-300", "-1", "-0", "1e9",
           "99999999999999999999999", "9" * 5000, "0x10", "", "abc", "1e", "\uff11\uff12",
           "1,5"]  # fmt: skip


def _slot_argv(slot: list[str], value: str, run: Path, out: Path) -> list[str]:
    argv = [a.replace("RUN", str(run)).replace("X", value) if "X" in a or "RUN" in a else a
            for a in slot]  # fmt: skip
    if argv[0] in ("simulate", "import", "diagnose"):
        argv += ["--out", str(out)]
    return argv + (["--quiet"] if argv[:2] not in (["pilot", "lead"], ["pilot", "adapt"]) else [])


def _odd_numbers(slot: list[str], valid: dict[str, Path]) -> None:
    for value in NUMBERS:
        with tempfile.TemporaryDirectory(dir=valid["root"]) as tmp:
            out = Path(tmp) / "out"
            check_clean(_slot_argv(slot, value, valid["run"], out), Path(tmp), out)


def _slot_id(slot: list[str]) -> str:
    return " ".join(a for a in slot if a.startswith("--") or a in ("X", "rest-X") or a == slot[0])


@pytest.mark.parametrize("slot", SLOTS, ids=_slot_id)
def test_odd_numbers_get_one_line_or_run(slot: list[str], valid: dict[str, Path]) -> None:
    _odd_numbers(slot, valid)


@pytest.mark.slow
@pytest.mark.parametrize("slot", SLOW_SLOTS, ids=_slot_id)
def test_odd_numbers_in_long_commands_get_one_line_or_run(
    slot: list[str], valid: dict[str, Path]
) -> None:
    _odd_numbers(slot, valid)


# --- misspelt keys and huge integers -------------------------------------------------------------

#: An integer beyond Python's int-from-string limit (4300 digits): json and tomllib refuse it.
HUGE = "9" * 5000


def _huge_integers(data: bytes) -> st.SearchStrategy[bytes]:
    """A number of a JSON or TOML document replaced by :data:`HUGE` (or nested arrays)."""
    text = data.decode()
    spots = [m.span() for m in re.finditer(r"(?<![\w.\"])-?\d+(\.\d+)?(?![\w\"])", text)]

    def put(a: tuple[int, str]) -> bytes:
        lo, hi = spots[a[0] % len(spots)]
        return (text[:lo] + a[1] + text[hi:]).encode()

    odd = st.sampled_from([HUGE, "-" + HUGE, HUGE + ".5", "[" * 5000 + "1" + "]" * 5000])
    return st.tuples(st.integers(0, 10_000), odd).map(put)


#: The formats a user writes by hand, damaged with huge integers too.
HUGE_FORMATS = ("twin-config/1", "omct-bounds", "sweep", "run/meta.json")


@pytest.mark.parametrize("fmt", HUGE_FORMATS)
def test_huge_integers_in_files_get_one_line(fmt: str, valid: dict[str, Path]) -> None:
    """A 5000-digit integer was an internal error (exit 70) in a config, sweep or run file."""
    damage = _huge_integers(_original(fmt, valid))
    tried, ok = _run_fuzz(damage, lambda work, data: _format_case(fmt, valid, work, data),
                          valid["root"], FAST)  # fmt: skip
    assert tried >= FAST // 2 and ok < tried  # (some numbers, like a title's, are not read)


def _typo(key: str, taken: set[str]) -> str:
    """``key`` misspelt: its last two letters swapped (or an x added), no other key's name."""
    typo = key[:-2] + key[-1] + key[-2] if len(key) > 2 and key[-1] != key[-2] else key + "x"
    return typo if typo not in taken else typo + "x"


def _json_keys(node: object, path: tuple = ()) -> list[tuple]:
    """Every key path of a JSON document."""
    if isinstance(node, dict):
        return [p for k, v in node.items() for p in [(*path, k), *_json_keys(v, (*path, k))]]
    if isinstance(node, list):
        return [p for i, v in enumerate(node) for p in _json_keys(v, (*path, i))]
    return []


def _misspelt_json(data: bytes) -> list[tuple[str, bytes]]:
    """Each key of a JSON document misspelt in turn: (the misspelt key, the document)."""
    doc = json.loads(data)
    taken = {p[-1] for p in _json_keys(doc) if isinstance(p[-1], str)}
    out = []
    for path in _json_keys(doc):
        if not isinstance(path[-1], str):
            continue
        new = json.loads(data)
        node = new
        for k in path[:-1]:
            node = node[k]
        typo = _typo(path[-1], taken)
        node[typo] = node.pop(path[-1])
        out.append((typo, json.dumps(new).encode()))
    return out


def _misspelt_toml(data: bytes) -> list[tuple[str, bytes]]:
    """Each key (``key = ...``) and table (``[name]``) of a TOML document misspelt in turn."""
    text = data.decode()
    spans = [m.span(1) for m in re.finditer(r"^\[?([A-Za-z_]+)\]?\s*(?:=|$)", text, flags=re.M)]
    taken = {text[lo:hi] for lo, hi in spans}
    out = []
    for lo, hi in spans:
        typo = _typo(text[lo:hi], taken)
        out.append((typo, (text[:lo] + typo + text[hi:]).encode()))
    return out


@pytest.fixture(scope="module")
def config_with_extension(valid: dict[str, Path]) -> Path:
    """A twin-config/1 file whose every kind of key is present (an extension on one DOF)."""
    from twin.chain.config import motion_system
    from twin.chain.extensions import Extension

    ms = motion_system("srs").replace(extensions=(Extension("gain", {"gain": 2.0}, ("heave",)),))
    return ms.save(valid["root"] / "extended.json")


@pytest.mark.parametrize("fmt", ["twin-config/1", "omct-bounds", "sweep"])
def test_every_misspelt_key_is_refused_naming_it(
    fmt: str, valid: dict[str, Path], config_with_extension: Path
) -> None:
    """A misspelt key was ignored (``dof`` for ``dofs``, ``dealy_s``): each key of each file a
    user writes, misspelt, is refused with the nearest allowed key."""
    if fmt == "twin-config/1":
        cases = _misspelt_json(config_with_extension.read_bytes())
    else:
        cases = _misspelt_toml(_original(fmt, valid))
    assert len(cases) >= 6
    for typo, data in cases:
        with tempfile.TemporaryDirectory(dir=valid["root"]) as tmp:
            argv, out = _format_case(fmt, valid, Path(tmp), data)
            assert check_clean(argv, Path(tmp), out) == 2, (fmt, typo)
            err = run_cli(argv)[1]
        assert f"'{typo}' (did you mean '" in err, err


@pytest.mark.parametrize("name", ["platform.toml", "build.toml"])
def test_every_misspelt_key_of_a_model_file_is_refused_naming_it(
    name: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The model folder's files (``TWIN_MODELS_DIR``): a misspelt key was ignored."""
    from twin.core.errors import ModelFileError
    from twin.platform.build import read_build_parameters
    from twin.platform.facts import load_facts, model_dir

    original = (model_dir("srs") / name).read_bytes()
    folder = tmp_path / "models" / "simona_srs"
    folder.mkdir(parents=True)
    monkeypatch.setenv("TWIN_MODELS_DIR", str(tmp_path / "models"))
    cases = _misspelt_toml(original)
    assert len(cases) >= 15
    read = (lambda: load_facts("srs")) if name == "platform.toml" else \
        (lambda: read_build_parameters(folder / name))  # fmt: skip
    try:
        for typo, data in cases:
            (folder / name).write_bytes(data)
            load_facts.cache_clear()
            with pytest.raises(ModelFileError, match=rf"'{typo}' \(did you mean '"):
                read()
    finally:
        load_facts.cache_clear()


# --- Ctrl-C to the process group, and servers that are not Dask schedulers -------------------

#: Rounds of Ctrl-C per command, at moments drawn from a generator seeded by its name.
CTRL_C_ROUNDS = 6
_SWEEP_GRID = (
    'task = "df"\nconfig = "mpi"\nmodel = "full"\n'
    '[grid]\nbreak_hz = [0.5, 2.0]\ndelay_ms = [35.0, 100.0]\ndof = ["pitch"]\n'
)


def _run_written(proc: subprocess.Popen, root: Path) -> bool:
    return writing_a_run(root)


def _processes_started(proc: subprocess.Popen, root: Path) -> bool:
    return starting_processes(proc)


#: Commands interrupted: the command line, when it is at work, and the longest wait after that
#: for the Ctrl-C (s): from the cluster's start to the end of the tasks or outputs written.
INTERRUPTIBLE = {
    "agard report, local cluster starting": (
        ["agard", "report", "srs", "--model", "reduced", "--dof", "pitch", "--dof", "heave",
         "--scheduler", "local:2", "--out", "out"], _processes_started, 4.0),
    "agard report, local cluster at work": (
        ["agard", "report", "srs", "--dof", "pitch", "--dof", "heave", "--scheduler", "local:2",
         "--out", "out"], _run_written, 6.0),
    "agard df, threads": (
        ["agard", "df", "srs", "--dof", "pitch", "--out", "out", "--quiet"], _run_written, 3.0),
    "simulate, full model": (
        ["simulate", "mpi", "--signal", "rest-60", "--out", "out", "--quiet"], _run_written, 3.0),
    "sweep, local cluster": (
        ["sweep", "GRID", "--scheduler", "local:2", "--out", "out"], _processes_started, 8.0),
    "pilot montecarlo, local cluster": (
        ["pilot", "montecarlo", "--runs", "2000", "--scheduler", "local:2"], _processes_started,
        8.0),
}  # fmt: skip


@pytest.mark.slow
@pytest.mark.parametrize("name", list(INTERRUPTIBLE))
def test_ctrl_c_to_the_process_group_at_random_moments(name: str, tmp_path: Path) -> None:
    """One or two Ctrl-C (SIGINT to the whole process group, workers included): exit 130 and
    the one line ``twin: interrupted``, nothing left in TMPDIR or beside the output; or, when
    the command finished first, exit 0 and nothing on stderr. Never a traceback, a crash
    (exit -11), a bug (70), a hang."""
    argv, at_work, longest_s = INTERRUPTIBLE[name]
    grid = tmp_path / "grid.toml"
    grid.write_text(_SWEEP_GRID)
    argv = [str(grid) if a == "GRID" else a for a in argv]
    rng = random.Random(name)
    outcomes = []
    for k in range(CTRL_C_ROUNDS):
        root = tmp_path / f"round-{k}"
        root.mkdir()
        proc = start(argv, root)
        wait_until(lambda p=proc, r=root: at_work(p, r), proc, root)
        time.sleep(rng.uniform(0, longest_s))
        times, gap_s = rng.choice((1, 2)), rng.uniform(0.05, 1.0)
        ctrl_c(proc, times, gap_s)
        code, err = finish(proc, root)
        if code == 0:  # done before the Ctrl-C came
            assert err == "", (name, k)
        else:
            assert (code, err) == (130, "twin: interrupted\n"), (name, k, times, gap_s)
            assert left_behind(root) == [], (name, k, times, gap_s)
        outcomes.append(code)
    print(f"\nCtrl-C {name}: {outcomes.count(130)} interrupted cleanly, "
          f"{outcomes.count(0)} finished first")  # fmt: skip


@contextlib.contextmanager
def _nothing_listens() -> Iterator[str]:
    yield closed_port()


@contextlib.contextmanager
def _unknown_host() -> Iterator[str]:
    yield "tcp://no-such-host.invalid:8786"


def _drips(conn) -> None:
    """Say a few bytes at a time, slowly (never a full greeting)."""
    for _ in range(40):
        conn.sendall(b"\x00")
        time.sleep(0.25)


#: Servers that are not Dask schedulers, and what the error line must say of each.
NOT_SCHEDULERS = {
    "http": (http_server, "it speaks HTTP"),
    "silent": (silent_listener, "said nothing within 5 s"),
    "nothing": (_nothing_listens, "nothing listens there"),
    "unknown host": (_unknown_host, "unknown host 'no-such-host.invalid'"),
    "ssh banner": (lambda: tcp_server(says(b"SSH-2.0-OpenSSH_9.2\r\n")), "'SSH-2.0-OpenSSH_9.2'"),
    "smtp banner": (lambda: tcp_server(says(b"220 mail ESMTP\r\n")), "'220 mail ESMTP'"),
    "closes": (lambda: tcp_server(says(b"", then_wait=False)), "without Dask's greeting"),
    "echo": (lambda: tcp_server(echoes), "'HEAD / HTTP/1.0'"),
    "random bytes": (lambda: tcp_server(says(random.Random(3).randbytes(300))),
                     "is not a Dask scheduler"),
    "huge frame": (lambda: tcp_server(says(struct.pack("<QQQ", 2**62, 1, 2**62 - 16))),
                   "is not a Dask scheduler"),
    "drips": (lambda: tcp_server(_drips), "is not a Dask scheduler"),
}  # fmt: skip


@pytest.mark.slow
@pytest.mark.parametrize("kind", list(NOT_SCHEDULERS))
@pytest.mark.parametrize("via", ["option", "environment"])
def test_a_scheduler_address_that_is_no_scheduler_gets_one_line_within_seconds(
    kind: str, via: str, tmp_path: Path
) -> None:
    server, said = NOT_SCHEDULERS[kind]
    with server() as address:
        where = ["--scheduler", address] if via == "option" else []
        env = {**os.environ, "TWIN_SCHEDULER": address}
        start_s = time.monotonic()
        done = subprocess.run(
            [sys.executable, "-m", "twin.cli", "pilot", "montecarlo", "--runs", "4", *where],
            cwd=tmp_path, env=env, capture_output=True, text=True, timeout=120,
        )  # fmt: skip
        took = time.monotonic() - start_s
    assert done.returncode == 2, done.stderr
    assert done.stderr.startswith(f"twin: error: no Dask scheduler at {address}: ")
    assert said in done.stderr and done.stderr.count("\n") == 1
    print(f"\n{kind} ({via}): {took:.1f} s")
