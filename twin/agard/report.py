"""``twin agard report``: the whole AGARD-AR-144 / OMCT suite on one bench, as a folder.

For each DOF: describing function (Table 5.2 signals), half-Hertz noise levels, dynamic
threshold (§3.3.4 steps), OMCT (with the illustrative bounds unless others are given), the
signal-to-noise grid, linearity, hysteresis, parasitic motion, turn-around bump and the
system limits measured. The folder holds ``report.json``, ``summary.md``, one PNG per test and
DOF, and every run as a ``twin-run/1`` folder under ``runs/``; it is written under a temporary
name and renamed when complete, so a failed report leaves nothing behind.
"""

from __future__ import annotations

import dataclasses
import json
import tempfile
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

from twin.agard import (
    bump,
    df,
    hysteresis,
    limits,
    linearity,
    noise_level,
    omct,
    parasitic,
    snr,
    threshold,
)
from twin.agard.session import Session, SessionRecorder
from twin.core.frames import dof_index
from twin.core.lifecycle import replacing_dir, writing
from twin.core.progress import ProgressFn
from twin.core.tasks.engine import Engine, using
from twin.measurement.measure import Bench


def threshold_defaults(dof: str) -> tuple[float, float]:
    """Step amplitude and length of §3.3.4: 0.1 m/s^2 or 0.075 rad/s^2, 1 s."""
    return (0.075 if dof_index(dof) >= 3 else 0.1), 1.0


#: Run numbers (and seeds: ``bench.seed + k``) of the i-th DOF's runs start at ``i`` times this,
#: so a DOF's runs are the same whether the DOFs run one after another or as parallel tasks.
RUNS_PER_DOF = 1000


def write_report(
    bench: Bench,
    dofs: Sequence[str],
    out: Path,
    recorder: SessionRecorder | None = None,
    progress: ProgressFn | None = None,
    bounds_path: str | Path | None = None,
    scheduler: Engine | str | None = None,
) -> dict[str, object]:
    """Run the suite and write the report folder ``out``; return the report as a dict.

    Each DOF's suite is a task (:mod:`twin.core.tasks`) run in a folder of its own and sent back
    as files, so DOFs run side by side on a ``scheduler`` (default this process) with the
    same results. A recording (``recorder``, e.g. :func:`twin.viz.record.bench_recorder`; closed
    here) is one stream of runs: with it, the DOFs run one after another in this process
    whatever the scheduler.
    """
    bounds = omct.read_bounds(bounds_path or omct.EXAMPLE_BOUNDS)
    with replacing_dir(out, "report.json") as tmp:
        if recorder is not None or len(dofs) < 2:
            parts = _in_session(bench, dofs, tmp, recorder, progress, bounds)
        else:
            with using(scheduler) as engine:
                scratch = tmp if engine.spec.on_this_machine else None
                parts = engine.map(
                    dof_suite,
                    [(bench, dof, i, bounds, scratch) for i, dof in enumerate(dofs)],
                    [{"dof": dof, "first_run": i * RUNS_PER_DOF} for i, dof in enumerate(dofs)],
                    f"AGARD suites on {bench.name} [DOFs]",
                    progress,
                ).values()
            for part in parts:
                for name, data in part.files.items():
                    with writing(tmp / name) as path:
                        path.parent.mkdir(parents=True, exist_ok=True)
                        path.write_bytes(data)
        report, md = _assemble(bench, parts)
        with writing(tmp / "report.json") as path:
            path.write_text(json.dumps(report, indent=2) + "\n", encoding="utf-8")
        with writing(tmp / "summary.md") as path:
            path.write_text(md, encoding="utf-8")
    return report


@dataclass(frozen=True)
class DofPart:
    """One DOF's share of a report: its entry, its summary lines, its files and run count."""

    dof: str
    entry: dict[str, object]
    md: list[str]
    runs: int
    files: dict[str, bytes] = field(default_factory=dict)


def dof_suite(
    bench: Bench, dof: str, i: int, bounds: omct.OmctBounds, scratch: Path | None = None
) -> DofPart:
    """Run the five tests in ``dof`` (the ``i``-th DOF of the report) in a folder of its own.

    A task: returns the run folders and figures as files (relative path -> bytes). The
    folder is a hidden one in ``scratch`` (the report's own staging folder, when the task
    runs on this machine: whatever ends the report, even a Ctrl-C that stops the worker
    mid-task, removes it with the report), else in the worker's temporary folder.
    """
    prefix = f".{dof}." if scratch is not None else "twin-agard-"
    with tempfile.TemporaryDirectory(prefix=prefix, dir=scratch) as folder:
        root = Path(folder)
        with Session(bench, root) as s:
            s.count = i * RUNS_PER_DOF
            part = _suite(s, dof, root, bounds)
        files = {
            str(p.relative_to(root)): p.read_bytes() for p in sorted(root.rglob("*")) if p.is_file()
        }
    return dataclasses.replace(part, files=files)


def _in_session(bench, dofs, tmp, recorder, progress, bounds) -> list[DofPart]:
    """Run every DOF's suite in one session (one recording), one after another."""
    tests = TESTS_PER_DOF * len(dofs)

    def beside(message: str, done: float | None = None, total: float | None = None) -> None:
        if progress:  # a test's own runs, shown beside the report's bar
            progress(message if done is None else f"{message} {done:g}/{total:g}")

    parts = []
    with Session(bench, tmp, recorder, beside) as s:
        for i, dof in enumerate(dofs):
            s.count = i * RUNS_PER_DOF
            parts.append(_suite(s, dof, tmp, bounds, lambda k, i=i: progress and progress(
                f"AGARD tests on {bench.name}", TESTS_PER_DOF * i + k, tests)))  # fmt: skip
    return parts


def _figure(fig, path: Path) -> str:
    with writing(path):
        fig.savefig(path, dpi=120)
    return path.name


def _tests(dof: str, bounds, cfg):
    """Return the tests of a DOF: (name, run, JSON of the result, figure, table)."""
    amp, step = threshold_defaults(dof)
    plain = (lambda r: r.to_dict(), lambda r: r.plot(), lambda r: r.format_table())
    return (
        ("df", lambda s: df.run_df(s, dof), lambda r: r.to_dict(),
         lambda r: r.plot(config=cfg), lambda r: r.format_table()),
        ("noise", lambda s: noise_level.run_noise(s, dof), *plain),
        ("threshold", lambda s: threshold.run_threshold(s, dof, amp, step), *plain),
        ("omct", lambda s: omct.run_omct(s, dof), lambda r: r.to_dict(bounds),
         lambda r: omct.plot_omct([r], bounds), lambda r: r.format_table(bounds)),
        ("snr", lambda s: snr.run_snr(s, dof), *plain),
        ("linearity", lambda s: linearity.run_linearity(s, dof), *plain),
        ("hysteresis", lambda s: hysteresis.run_hysteresis(s, dof), *plain),
        ("parasitic", lambda s: parasitic.run_parasitic(s, (dof,)), *plain),
        ("bump", lambda s: bump.run_bump(s, dof), *plain),
        ("limits", lambda s: limits.run_limits(s, dof), *plain),
    )  # fmt: skip


#: Tests each DOF of a report runs (:func:`_tests`).
TESTS_PER_DOF = len(_tests("surge", None, None))


def _suite(s: Session, dof: str, tmp: Path, bounds, tested=None) -> DofPart:
    """Run every test of :func:`_tests` in ``dof``; figures into ``tmp``."""
    first = s.count
    entry: dict[str, object] = {}
    md = [f"## {dof}", ""]
    for k, (name, run, as_json, figure, table) in enumerate(_tests(dof, bounds, s.bench.config)):
        if tested:
            tested(k)
        result = run(s)
        entry[name] = as_json(result)
        md += [
            "```",
            table(result),
            "```",
            f"![]({_figure(figure(result), tmp / f'{name}-{dof}.png')})",
            "",
        ]
    if tested:
        tested(TESTS_PER_DOF)
    if s.count - first > RUNS_PER_DOF:
        raise RuntimeError(f"{dof}: {s.count - first} runs, more than RUNS_PER_DOF allows")
    return DofPart(dof, entry, md, s.count - first)


def _assemble(bench: Bench, parts: list[DofPart]) -> tuple[dict[str, object], str]:
    cfg = bench.config
    report: dict[str, object] = {
        "bench": bench.name,
        "config": cfg.to_meta(),
        "dofs": {p.dof: p.entry for p in parts},
    }
    md = [
        f"# AGARD-AR-144 / OMCT report: {bench.name}",
        "",
        f"Configuration `{cfg.name}`: {cfg.description or 'custom'}; platform {cfg.platform}, "
        f"filter {f'{cfg.filter_break_hz:g} Hz' if cfg.filter_break_hz else 'none'}, "
        f"total delay {cfg.delay_s * 1e3:.1f} ms, "
        f"noise {'on' if cfg.noise else 'off'}; model {bench.model}, seed {bench.seed}."
        + "".join(f" Extension {e.describe()}." for e in cfg.extensions),
        "",
    ]
    for p in parts:
        md += p.md
    md += [
        f"{sum(p.runs for p in parts)} runs, each a twin-run/1 folder under `runs/` (DOF i's "
        f"numbered from {RUNS_PER_DOF} i; analyse one again with `twin agard df runs/NN-...`)."
    ]
    return report, "\n".join(md) + "\n"
