"""The task layer on a core install (no Dask): ``local`` is a pool of the standard library.

``pip install twin`` has no Dask (the ``cluster`` extra brings it). There, every batch
command's default ``--scheduler local`` must still use the cores and give the very bits one
process gives; a failing task is named with its inputs, the others kept; a remote scheduler
and a Parquet table say what to install.
"""

from __future__ import annotations

import json
import operator
import os
import signal

import pytest

from twin.cli.main import main
from twin.core.tasks import engine as engine_module
from twin.core.tasks.engine import Engine, SchedulerError
from twin.pilot.studies.montecarlo import monte_carlo
from twin.studies.sweep import SweepError
from twin.studies.sweep_report import check_table_format


@pytest.fixture
def no_dask(monkeypatch):
    """As if ``distributed`` (and pyarrow) were not installed."""
    monkeypatch.setattr(engine_module, "dask_installed", lambda: False)
    real = engine_module.importlib.util.find_spec
    monkeypatch.setattr(
        "importlib.util.find_spec",
        lambda name, *a: None if name in ("distributed", "pyarrow") else real(name, *a),
    )


def test_local_without_dask_is_a_process_pool_with_failures_named(no_dask):
    engine = Engine("local:2")
    assert engine.spec.describe() == "local process pool (2 worker processes)"
    args = [(1.0, 2.0), (1.0, 0.0), (3.0, 4.0)]
    seen = []
    out = engine.map(operator.truediv, args, [{"n": 1}, {"n": "zero"}, {"n": 3}], "divisions",
                     lambda m, d, t: seen.append(d))  # fmt: skip
    assert engine._client is None  # no Dask client was made
    assert out.results == [0.5, None, 0.75]
    assert [f.index for f in out.failures] == [1]
    assert out.failures[0].inputs == {"n": "zero"}
    assert out.failures[0].error.startswith("ZeroDivisionError")
    assert "ZeroDivisionError" in out.failures[0].traceback  # the worker's, chained
    assert seen == [0, 1, 2, 3]


def test_monte_carlo_on_the_process_pool_equals_one_process(no_dask):
    a = monte_carlo(8, seed=4, batch=4, fit_runs=1)  # two tasks
    b = monte_carlo(8, seed=4, batch=4, fit_runs=1, scheduler="local:2")
    assert json.dumps(a.to_dict()) == json.dumps(b.to_dict())


def test_a_remote_scheduler_without_dask_says_what_to_install(no_dask):
    with pytest.raises(SchedulerError, match=r"needs Dask.*twin\[cluster\]"):
        Engine("tcp://127.0.0.1:8786").client()


def test_a_parquet_table_without_pyarrow_says_what_to_install(no_dask, tmp_path, capsys):
    with pytest.raises(SweepError, match=r"pyarrow.*twin\[cluster\]"):
        check_table_format("parquet")
    check_table_format("csv")  # needs nothing more
    grid = tmp_path / "grid.toml"
    grid.write_text('task = "df"\nconfig = "mpi"\n[grid]\ndof = ["pitch"]\n', encoding="utf-8")
    assert main(["sweep", str(grid), "--format", "parquet", "--out", str(tmp_path / "s")]) == 2
    assert "pyarrow" in capsys.readouterr().err
    assert not (tmp_path / "s").exists()  # refused before any run


def _worker_state(_: int) -> tuple[bool, str | None]:
    """Whether this process ignores Ctrl-C, and its OpenBLAS thread setting."""
    return signal.getsignal(signal.SIGINT) is signal.SIG_IGN, os.environ.get("OPENBLAS_NUM_THREADS")


def test_pool_workers_ignore_ctrl_c_and_use_one_blas_thread(no_dask, monkeypatch):
    """Set up as a Dask worker is: the twin process stops them; BLAS does not oversubscribe."""
    for name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        monkeypatch.delenv(name, raising=False)  # restored after: the pool sets them here
    before = signal.getsignal(signal.SIGINT)
    out = Engine("local:2").map(_worker_state, [(0,), (1,)], [{}, {}], "probes")
    assert out.values() == [(True, "1"), (True, "1")]
    assert signal.getsignal(signal.SIGINT) is before  # this process: as it was
