"""The command line's contract for bad input, shared by the fuzz tests: exit 0, or one line."""

from __future__ import annotations

import contextlib
import io

from twin.cli.main import main


def run_cli(argv: list[str]) -> tuple[int, str]:
    """Run ``twin argv`` in this process; return the exit code and stderr."""
    err = io.StringIO()
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
        code = main(argv)
    return code, err.getvalue()


def assert_answered(argv: list[str], code: int, err: str) -> None:
    """Exit 0, or 2 with exactly one line ``twin: error: ...``; never a traceback or 70."""
    shown = " ".join(argv)
    assert code in (0, 2), f"twin {shown}: exit {code}: {err}"
    assert "Traceback" not in err, f"twin {shown}: {err}"
    if code == 2:
        lines = [ln for ln in err.splitlines() if ln.strip()]
        assert len(lines) == 1 and lines[0].startswith("twin: error: "), f"twin {shown}: {err}"


def fails_in_one_line(capsys, argv: list[str], *fragments: str) -> str:
    """Run ``twin argv`` with pytest's ``capsys``: exit 2, one line, each fragment in it."""
    assert main(argv) == 2, argv
    err = capsys.readouterr().err
    assert err.startswith("twin: error: ") and err.count("\n") == 1, err
    for f in fragments:
        assert f in err, (f, err)
    return err.strip()
