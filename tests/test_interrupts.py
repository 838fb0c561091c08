"""Ctrl-C: one line, exit 130, no worker traceback, nothing left, and never a crash.

The commands run as programs in a process group of their own and get SIGINT as a terminal
sends it, to the whole group (:mod:`group_signals`), once they are at work (a run's physics
written). stderr must then be exactly ``twin: interrupted``: the command prints no progress
where stderr is no terminal, and nothing else. Nothing may be left in ``TMPDIR`` or beside
the output but Dask's shared scratch folder (lock files every run reuses). ``make fuzz``
interrupts more commands at random moments (tests/test_fuzz_inputs.py).
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time

import pytest
from group_signals import ctrl_c, finish, left_behind, start, wait_until, writing_a_run

from twin.cli.main import main
from twin.core.interrupts import handling_ctrl_c

INTERRUPTED = "twin: interrupted\n"


@pytest.mark.slow  # 8 s: a cluster started and stopped; the fast suite keeps the double Ctrl-C
def test_ctrl_c_with_a_local_cluster_is_one_line_and_leaves_no_temporary_folder(tmp_path):
    """Before: the DOF suites' ``twin-agard-*`` folders (26-49 MB) stayed in TMPDIR every
    time, as the workers were killed mid-task, and Ctrl-C at other moments printed 34-67
    lines of worker tracebacks. Now the workers ignore SIGINT and are stopped by the ``twin``
    process before it removes the report's staging folder, where their scratch folders are."""
    proc = start(["agard", "report", "srs", "--model", "reduced", "--dof", "pitch", "--dof",
                  "heave", "--scheduler", "local:2", "--out", "report"], tmp_path)  # fmt: skip
    wait_until(lambda: writing_a_run(tmp_path), proc, tmp_path)
    ctrl_c(proc)
    assert finish(proc, tmp_path) == (130, INTERRUPTED)
    assert left_behind(tmp_path) == []


def test_a_second_ctrl_c_during_a_full_model_run_does_not_crash(tmp_path):
    """Before: the second Ctrl-C came while Python waited at exit for MuJoCo's rollout thread,
    and the interpreter was torn down under it: exit -11 (139 in a shell), a traceback of
    ``threading._shutdown``. Now Ctrl-C is ignored once the command is ending."""
    proc = start(["simulate", "mpi", "--signal", "rest-600", "--out", "run", "--quiet"], tmp_path)
    wait_until(lambda: writing_a_run(tmp_path), proc, tmp_path)
    ctrl_c(proc, times=2, gap_s=0.2)
    assert finish(proc, tmp_path) == (130, INTERRUPTED)
    assert left_behind(tmp_path) == []


@pytest.fixture
def ctrl_c_as_in_a_terminal():
    """SIGINT with Python's default handler, also where the tests run with it ignored."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, previous)


def test_a_ctrl_c_that_an_import_turns_into_another_error_still_ends_as_interrupted(
    monkeypatch, capsys, ctrl_c_as_in_a_terminal
):
    """A Ctrl-C inside a compiled module's import can surface as ``ImportError:
    initialization failed`` without the interrupt attached; it was reported as a bug (exit
    70). The command knows a Ctrl-C came, and says so."""

    def cut_short(*args: object) -> str:
        try:
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(5)  # the Ctrl-C arrives in here
        except KeyboardInterrupt:
            raise ImportError("initialization failed") from None
        return "not interrupted"

    monkeypatch.setattr("twin.platform.workspace.format_table", cut_short)
    assert main(["workspace", "mpi"]) == 130
    assert capsys.readouterr().err == INTERRUPTED
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler  # a caller's, restored


def _python(code: str) -> str:
    """Run ``code`` in a fresh interpreter, SIGINT as in a terminal; return its stdout."""
    code = "import signal; signal.signal(signal.SIGINT, signal.default_int_handler)\n" + (
        textwrap.dedent(code)
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120, check=True)  # fmt: skip
    return done.stdout


def test_ctrl_c_is_handled_once_then_ignored_while_the_command_ends():
    out = _python("""
        import os, signal, time
        from twin.core.interrupts import GRACE_S, handling_ctrl_c

        def ctrl_c():
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(0.5)  # delivered in here

        with handling_ctrl_c(process=True) as handler:
            try:
                ctrl_c()
            except KeyboardInterrupt:
                print("first raised")
            ctrl_c()  # the clean-up of the first is under way: ignored
            print("second ignored", handler.interrupted)
            handler.first -= GRACE_S  # the first was long ago (swallowed by a library, say)
            try:
                ctrl_c()
            except KeyboardInterrupt:
                print("a later one raised")
        print("ignored for good", signal.getsignal(signal.SIGINT) is signal.SIG_IGN)
        with handling_ctrl_c(process=False):  # started ignoring it (a script's background job)
            print("kept ignored", signal.getsignal(signal.SIGINT) is signal.SIG_IGN)
    """)
    assert out.split("\n") == ["first raised", "second ignored True", "a later one raised",
                               "ignored for good True", "kept ignored True", ""]  # fmt: skip


def test_a_ctrl_c_while_deferred_comes_after_and_processes_started_meanwhile_ignore_it():
    out = _python("""
        import os, signal, subprocess, sys
        from twin.core.interrupts import deferred

        child = "import signal; print(signal.getsignal(signal.SIGINT) is signal.SIG_IGN)"
        try:
            with deferred():
                os.kill(os.getpid(), signal.SIGINT)
                started = subprocess.run([sys.executable, "-c", child], capture_output=True,
                                         text=True).stdout.strip()
                print("inside", started)
        except KeyboardInterrupt:
            print("after")
        print("restored", signal.getsignal(signal.SIGINT) is signal.default_int_handler)
    """)
    assert out.split("\n") == ["inside True", "after", "restored True", ""]


def test_the_worker_setup_ignores_ctrl_c_and_simulates_one_run_at_a_time():
    out = _python("""
        import signal
        import twin.core.threads
        from twin.core.tasks.worker_setup import dask_setup
        dask_setup(None)
        ignored = signal.getsignal(signal.SIGINT) is signal.SIG_IGN
        print(ignored, twin.core.threads.SIMULATION_THREADS)
    """)
    assert out == "True 1\n"


def test_a_command_that_finished_ignores_ctrl_c_while_the_process_exits():
    """Python waits for MuJoCo's rollout threads after the command's last line: a Ctrl-C
    then killed the process by the signal (exit -2, no line) where the command had finished
    without one; now SIGINT is ignored from the end of the command, interrupted or not."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        with handling_ctrl_c(process=True) as ctrl_c:
            pass
        assert not ctrl_c.interrupted
        assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN
        with handling_ctrl_c(process=False):  # a caller's own process: the default comes back
            pass
        assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN  # not installed over SIG_IGN
    finally:
        signal.signal(signal.SIGINT, previous)
