"""A day's measurements diagnosed one by one, as tasks: ``twin diagnose --each``.

Each target is one measurement: a ``twin-run/1`` folder (diagnosed alone), or a folder whose
sub-folders are run folders (diagnosed together, e.g. Table 5.2's two multi-sines of one
session). The runs are read and checked here, before any task starts (a malformed folder is
refused in one line), and handed to the tasks as data, so workers on other machines need no
shared disk. Each diagnosis is a task of :mod:`twin.core.tasks.engine`, a pure function of the
runs, the nominal configuration and the seed; one that fails is listed with its runs and the
others are written.

The batch folder holds one diagnosis report per measurement (``NAME/``, as ``twin diagnose``
writes it, plus ``NAME/extended.json``, the extended configuration), ``batch.csv`` (one row
per finding: measurement, rank, effect, DOFs, parameters, BIC evidence, held-out VAF before
and after; a measurement without a finding gets one row with effect ``none``) and
``batch.json`` (the same, and the failures).
"""

from __future__ import annotations

import csv
import json
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from twin.chain.config import MotionSystem
from twin.core.errors import RunFormatError
from twin.core.lifecycle import replacing_dir
from twin.core.progress import ProgressFn
from twin.core.tasks.engine import Engine, using
from twin.core.tasks.outcome import Failure
from twin.diagnose.diagnosis import Diagnosis, diagnose
from twin.diagnose.report import Recording, write_report
from twin.formats.run_checks import read_plausible_run
from twin.formats.runs import RecordedRun

#: Columns of ``batch.csv``.
COLUMNS = ("measurement", "runs", "finding", "effect", "dofs", "describe", "delta_bic",
           "vaf_before", "vaf_after")  # fmt: skip


def measurement_runs(target: str | Path) -> list[Path]:
    """Return the run folders of one measurement (see the module docstring).

    Raises
    ------
    RunFormatError
        For a target that is neither a run folder nor a folder of run folders.

    """
    path = Path(target)
    if (path / "meta.json").is_file():
        return [path]
    if path.is_dir():
        runs = sorted(p for p in path.iterdir() if (p / "meta.json").is_file())
        if runs:
            return runs
    raise RunFormatError(
        f"{path}: not a measurement (expected a twin-run/1 folder, or a folder of them)"
    )


def diagnose_measurement(
    runs: list[RecordedRun], config: MotionSystem | None, options: dict[str, Any]
) -> Diagnosis:
    """Diagnose one measurement (a task): :func:`twin.diagnose.diagnosis.diagnose` on its runs."""
    return diagnose(runs, config, **options)


@dataclass
class BatchResult:
    """Diagnoses of several measurements.

    Attributes
    ----------
    names : list of str
        Each measurement's name (its folder's, made unique).
    runs : list of list of str
        Each measurement's run folders.
    diagnoses : list of Diagnosis or None
        Each measurement's diagnosis (None: failed).
    failures : list of Failure
        The failed measurements, with their runs.
    scheduler : str
        Where the tasks ran.

    """

    names: list[str]
    runs: list[list[str]]
    diagnoses: list[Diagnosis | None]
    failures: list[Failure]
    scheduler: str

    def rows(self) -> list[dict[str, Any]]:
        """Return ``batch.csv``'s rows (see the module docstring)."""
        out = []
        for name, runs, d in zip(self.names, self.runs, self.diagnoses, strict=True):
            if d is None:
                continue
            base = {"measurement": name, "runs": " ".join(runs)}
            if not d.findings:
                out.append({**base, "finding": 0, "effect": "none", "dofs": "", "describe": "",
                            "delta_bic": "", "vaf_before": "", "vaf_after": ""})  # fmt: skip
            for i, f in enumerate(d.findings, 1):
                j = f.to_json()
                out.append({
                    **base, "finding": i, "effect": j["effect"], "dofs": " ".join(j["dofs"]),
                    "describe": f.extension.describe(), "delta_bic": f.delta_bic,
                    "vaf_before": f.gain.get("vaf_before", ""),
                    "vaf_after": f.gain.get("vaf_after", ""),
                })  # fmt: skip
        return out


def diagnose_each(
    targets: Sequence[str | Path],
    config: MotionSystem | None = None,
    scheduler: Engine | str | None = None,
    progress: ProgressFn | None = None,
    **options: Any,
) -> BatchResult:
    """Diagnose each target as its own measurement; one task per measurement.

    Parameters
    ----------
    targets : sequence of path
        Run folders, or folders of run folders (see the module docstring).
    config : MotionSystem, optional
        Nominal configuration of every measurement (default: each one's ``meta.json``).
    scheduler : Engine or str, optional
        Where the diagnoses run (:func:`twin.core.tasks.engine.using`; default this process).
    progress : callable, optional
        Called as measurements finish.
    **options
        ``model``, ``max_hz``, ``seed``, ``dofs``, ``imu_noise``, ``physics`` of
        :func:`twin.diagnose.diagnosis.diagnose`.

    Raises
    ------
    RunFormatError
        Before any diagnosis, for a target or run folder that is malformed.

    """
    groups = [measurement_runs(t) for t in targets]
    names = _unique([Path(t).resolve().name or "measurement" for t in targets])
    data = [[read_plausible_run(p) for p in g] for g in groups]
    with using(scheduler) as engine:
        outcome = engine.map(
            diagnose_measurement,
            [(d, config, options) for d in data],
            [
                {"measurement": n, "runs": " ".join(map(str, g))}
                for n, g in zip(names, groups, strict=True)
            ],
            "measurements",
            progress,
        )
        where = engine.spec.describe()
    runs = [[str(p) for p in g] for g in groups]
    return BatchResult(names, runs, outcome.results, outcome.failures, where)


def _unique(names: list[str]) -> list[str]:
    """Return the names made unique: a repeated name gets ``-2``, ``-3``, ... (never one taken).

    >>> _unique(["a", "a", "a-2", "b"])
    ['a', 'a-3', 'a-2', 'b']

    """
    taken = set(names)
    out: list[str] = []
    for n in names:
        if n not in out:
            out.append(n)
            continue
        k = 2
        while f"{n}-{k}" in taken or f"{n}-{k}" in out:
            k += 1
        out.append(f"{n}-{k}")
    return out


def write_batch(
    result: BatchResult, out: str | Path, figures: bool = True, recording: Recording | None = None
) -> Path:
    """Write the batch folder (see the module docstring); return ``batch.csv``'s path.

    ``figures`` and ``recording`` as :func:`twin.diagnose.report.write_report`'s, for each
    measurement's report.
    """
    out = Path(out)
    with replacing_dir(out, "batch.json") as tmp:
        for name, d in zip(result.names, result.diagnoses, strict=True):
            if d is not None:
                write_report(d, tmp / name, figures=figures, recording=recording)
                d.extended_config.save(tmp / name / "extended.json")
        rows = result.rows()
        with open(tmp / "batch.csv", "w", newline="", encoding="utf-8") as fh:
            w = csv.DictWriter(fh, COLUMNS)
            w.writeheader()
            w.writerows(rows)
        doc = {
            "measurements": len(result.names),
            "failed": len(result.failures),
            "scheduler": result.scheduler,
            "findings": rows,
            "failures": [f.to_dict() for f in result.failures],
        }
        (tmp / "batch.json").write_text(json.dumps(doc, indent=2) + "\n", encoding="utf-8")
    return out / "batch.csv"
