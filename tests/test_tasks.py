"""The task layer (twin.core.tasks) on a real Dask LocalCluster: two worker processes.

Every batch command's tasks are pure functions of their inputs, so a cluster must give the
very bits one process gives (compared with ==, not a tolerance), a worker killed mid-sweep
must cost nothing but time (the scheduler reruns its tasks), and a failing task must be
reported with its inputs while the others' results are kept.
"""

from __future__ import annotations

import json
import operator
import os
import signal
import time

import numpy as np
import pytest
from fake_servers import closed_port

from twin.chain.config import motion_system
from twin.chain.extensions import Extension
from twin.cli.main import main
from twin.core.errors import RunFormatError, UsageError
from twin.core.tasks.engine import Engine, parse_scheduler
from twin.core.tasks.outcome import TaskError
from twin.core.tasks.scheduler_probe import what_answers
from twin.diagnose.batch import diagnose_each, measurement_runs
from twin.diagnose.diagnosis import diagnose
from twin.diagnose.hidden import record_runs
from twin.pilot.models.pitch import PitchPilot
from twin.pilot.studies.experiment import fly_condition
from twin.pilot.studies.montecarlo import monte_carlo
from twin.studies.sweep import SweepError, parse_grid, run_sweep

DF_GRID = {
    "task": "df",
    "config": "mpi",
    "model": "reduced",
    "grid": {"break_hz": [0.5, 2.0], "delay_ms": [35.0, 100.0], "dof": ["pitch"]},
}


@pytest.fixture(scope="module")
def cluster():
    """A local Dask cluster of two worker processes, shared by this module's tests."""
    with Engine("local:2") as engine:
        assert sum(engine.client().nthreads().values()) == 2
        yield engine


@pytest.mark.parametrize(
    ("text", "kind", "workers", "address"),
    [
        ("inline", "inline", None, None),
        ("local", "local", None, None),
        ("local:3", "local", 3, None),
        ("tcp://10.1.2.3:8786", "remote", None, "tcp://10.1.2.3:8786"),
        ("sched.lab:8786", "remote", None, "tcp://sched.lab:8786"),
    ],
)
def test_scheduler_values(text, kind, workers, address):
    s = parse_scheduler(text)
    assert (s.kind, s.workers, s.address) == (kind, workers, address)


@pytest.mark.parametrize("text", ["local:0", "local:x", "cluster", "tcp://host", ""])
def test_bad_scheduler_is_refused_naming_what_is_allowed(text):
    with pytest.raises(UsageError, match=r"'local', 'local:N', 'inline'|local:N needs"):
        parse_scheduler(text)


def test_scheduler_default_comes_from_the_environment(monkeypatch):
    monkeypatch.setenv("TWIN_SCHEDULER", "local:5")
    assert parse_scheduler(None).workers == 5
    monkeypatch.delenv("TWIN_SCHEDULER")
    assert parse_scheduler(None).kind == "local"


def test_unreachable_scheduler_is_one_line_on_the_cli_at_once(capsys):
    """Before: Dask's client retried the refused connection for 20 s."""
    address = closed_port()
    start = time.monotonic()
    code = main(["pilot", "montecarlo", "--runs", "4", "--scheduler", address])
    took = time.monotonic() - start
    err = capsys.readouterr().err.strip()
    assert code == 2 and f"no Dask scheduler at {address}: nothing listens there" in err
    assert len(err.splitlines()) == 1
    assert took < 5


def test_a_running_scheduler_passes_the_probe(cluster):
    assert what_answers(cluster.client().scheduler.address) is None


def _ignores_ctrl_c() -> bool:
    return signal.getsignal(signal.SIGINT) is signal.SIG_IGN


@pytest.mark.slow  # 4 s: a worker killed and restarted
def test_local_workers_ignore_ctrl_c_also_when_started_again(cluster):
    """Ctrl-C reaches a local cluster's workers too (one process group): they leave it to the
    ``twin`` process, which shuts them down, instead of dying with a traceback each."""
    client = cluster.client()
    assert set(client.run(_ignores_ctrl_c).values()) == {True}
    killed = min(client.run(os.getpid).values())
    os.kill(killed, signal.SIGKILL)  # the nanny starts another (the preload sets it up)
    deadline = time.monotonic() + 120
    while killed in (pids := set(client.run(os.getpid, on_error="ignore").values())) or (
        len(pids) < 2
    ):
        assert time.monotonic() < deadline, "the killed worker was not started again"
        time.sleep(0.1)
    assert set(client.run(_ignores_ctrl_c).values()) == {True}


@pytest.mark.parametrize("where", ["inline", "cluster"])
def test_a_failing_task_is_named_and_the_others_kept(where, cluster):
    engine = cluster if where == "cluster" else Engine("inline")
    args = [(1.0, 2.0), (1.0, 0.0), (3.0, 4.0)]
    inputs = [{"n": 1}, {"n": "zero"}, {"n": 3}]
    seen = []
    out = engine.map(operator.truediv, args, inputs, "divisions", lambda m, d, t: seen.append(d))
    assert out.results == [0.5, None, 0.75]
    assert [f.index for f in out.failures] == [1]
    assert out.failures[0].inputs == {"n": "zero"}
    assert out.failures[0].error.startswith("ZeroDivisionError")
    assert seen == [0, 1, 2, 3]  # progress from 0 to all, whatever failed
    with pytest.raises(TaskError, match=r"1 of the divisions failed: task 1 \(n=zero\)"):
        out.values()


def test_monte_carlo_on_the_cluster_equals_one_process(cluster):
    a = monte_carlo(8, seed=4, batch=4, fit_runs=1)  # two tasks
    b = monte_carlo(8, seed=4, batch=4, fit_runs=1, scheduler=cluster)
    for method in ("fc", "arx"):
        for resp in ("pe", "px"):
            assert np.array_equal(getattr(a, method)[resp], getattr(b, method)[resp])
    assert np.array_equal(a.arx_sampled_std_mag["px"], b.arx_sampled_std_mag["px"])
    assert a.pilots == b.pilots
    assert json.dumps(a.to_dict()) == json.dumps(b.to_dict())


def test_experiment_conditions_on_the_cluster_equal_one_process(cluster):
    # run_experiment's tasks, with a given remnant scale (its own costs 32 runs in-process)
    args = [(PitchPilot(), n, 1, 2 + n, 0.4, False) for n in (1, 8)]
    inputs = [{"condition": n} for n in (1, 8)]
    a = Engine("inline").map(fly_condition, args, inputs, "conditions").values()
    b = cluster.map(fly_condition, args, inputs, "conditions").values()
    assert json.dumps(a) == json.dumps(b)
    assert a[1]["phase_margin_d"] < a[0]["phase_margin_d"]  # condition 8 has the 1 Hz filter


def test_sweep_survives_a_killed_worker_with_the_same_bits(cluster):
    grid = parse_grid(DF_GRID)
    alone = run_sweep(grid)
    pids = list(cluster.client().run(os.getpid).values())
    killed = []

    def kill_after_first(message, done=None, total=None):
        if done == 1 and not killed:
            os.kill(pids[0], signal.SIGKILL)  # mid-sweep: one point back, three to go
            killed.append(pids[0])

    spread = run_sweep(grid, cluster, kill_after_first)
    assert killed and not spread.failures
    assert alone.table().equals(spread.table())
    assert len(alone.table()) == 4 * 11  # 4 points x the 11 lines of Table 5.2 (signals 1, 2)
    assert sorted(set(alone.table()["break_hz"])) == [0.5, 2.0]
    # the cluster came back to two workers (the nanny restarted the killed one)
    cluster.client().wait_for_workers(2, timeout=60)


@pytest.mark.slow
def test_batch_diagnosis_on_the_cluster_equals_one_process(cluster, tmp_path):
    nominal = motion_system("srs")
    truth = nominal.replace(extensions=(Extension("delay", {"extra_delay_s": 0.06}, ("pitch",)),))
    a = record_runs(truth, nominal, "pitch", tmp_path / "day" / "slow", seed=3)
    b = record_runs(nominal, nominal, "pitch", tmp_path / "day" / "fine", seed=4, signals=(1,))
    assert measurement_runs(a[0].parent) == a
    alone = diagnose_each([a[0].parent, b[0]])
    spread = diagnose_each([a[0].parent, b[0]], scheduler=cluster)
    assert alone.rows() == spread.rows()
    assert [d.to_dict() for d in alone.diagnoses] == [d.to_dict() for d in spread.diagnoses]
    effects = {r["measurement"]: r["effect"] for r in alone.rows()}
    assert effects["slow"] == "delay"  # the 60 ms hidden in the two-run session is named


def test_diagnose_each_on_the_cluster_equals_diagnose_in_process(cluster, tmp_path, capsys):
    srs = motion_system("srs")
    gained = srs.replace(extensions=(Extension("gain", {"gain": 1.3}, ("pitch",)),))
    run = record_runs(gained, srs, "pitch", tmp_path / "day" / "one", seed=5, signals=(1,))[0]
    alone = diagnose([run])
    out = tmp_path / "batch"
    spec = "local:2"  # a cluster of its own, as the CLI starts one
    assert main(["diagnose", "--each", str(run.parent), "--out", str(out), "--no-figures",
                 "--quiet", "--scheduler", spec]) == 0  # fmt: skip
    doc = json.loads((out / "one" / "diagnosis.json").read_text())
    assert doc == json.loads(json.dumps(alone.to_dict()))
    rows = (out / "batch.csv").read_text().splitlines()
    assert rows[0].startswith("measurement,runs,finding,effect") and ",gain," in rows[1]
    assert (out / "one" / "extended.json").is_file()
    assert "1 of 1 measurements diagnosed" in capsys.readouterr().out


def test_batch_diagnosis_refuses_a_folder_without_runs(tmp_path):
    with pytest.raises(RunFormatError, match="not a measurement"):
        diagnose_each([tmp_path])


@pytest.mark.parametrize(
    ("change", "match"),
    [
        ({"task": "agard"}, "task must be one of"),
        ({"grid": {"break_hz": []}}, "non-empty list"),
        ({"grid": {"break_hz": ["fast"]}}, "must be a float"),
        ({"grid": {"delay_ms": [-5.0]}}, r"number in \[0, 10000\]"),
        ({"grid": {"break_hz": [1e300]}}, r"number in \[0, 1000\]"),
        ({"grid": {"dof": ["up"]}}, "must be one of surge"),
        ({"grid": {"colour": [1]}}, "unknown axis"),
        ({"gain": 2}, "unknown key 'gain'"),
        ({"model": "exact"}, "model must be"),
        ({"grid": {"break_hz": [1.0, 1.0]}}, "repeats a value"),
    ],
)
def test_bad_sweep_files_are_refused_naming_the_key(change, match):
    with pytest.raises(SweepError, match=match):
        parse_grid({**DF_GRID, **change}, "grid.toml")


def test_a_bad_point_is_refused_before_any_run():
    grid = parse_grid({**DF_GRID, "config": "nowhere"}, "grid.toml")
    with pytest.raises(SweepError, match=r"grid.toml: point config=nowhere.*unknown"):
        run_sweep(grid)


def test_sweep_cli_writes_table_points_manifest_and_figure(tmp_path, capsys):
    grid = tmp_path / "pilot.toml"
    grid.write_text('task = "pilot"\nruns = 1\n[grid]\nbreak_hz = [0, 1.0]\n')
    out = tmp_path / "sweep"
    assert main(["sweep", str(grid), "--out", str(out), "--scheduler", "inline", "--quiet",
                 "--format", "parquet"]) == 0  # fmt: skip
    import pandas as pd

    table = pd.read_parquet(out / "sweep.parquet")
    assert list(table["break_hz"]) == [0.0, 1.0] and list(table["point"]) == [0, 1]
    # the fixed pilot's disturbance-loop phase margin falls behind the 1 Hz filter (Ch 6)
    assert table["phase_margin_d_deg"][1] < table["phase_margin_d_deg"][0]
    manifest = json.loads((out / "sweep.json").read_text())
    assert manifest["points"] == 2 and manifest["failed"] == 0
    assert sorted(p.name for p in (out / "points").iterdir()) == ["0000.json", "0001.json"]
    assert (out / "sweep.png").stat().st_size > 10_000
    assert "2 of 2 points (this process)" in capsys.readouterr().out


@pytest.mark.slow
def test_agard_report_dofs_as_tasks_equal_one_session(cluster, tmp_path):
    from twin.agard.report import write_report
    from twin.measurement.measure import Bench, configure
    from twin.viz.record import bench_recorder

    bench = Bench(configure("srs"), "reduced", 0)
    alone = write_report(
        bench, ["heave", "pitch"], tmp_path / "a", bench_recorder(bench, tmp_path / "a.rrd")
    )
    spread = write_report(bench, ["heave", "pitch"], tmp_path / "b", scheduler=cluster)
    assert json.dumps(alone) == json.dumps(spread)
    assert (tmp_path / "a" / "summary.md").read_text() == (
        tmp_path / "b" / "summary.md"
    ).read_text()
    runs = sorted(p.name for p in (tmp_path / "b" / "runs").iterdir())
    assert runs == sorted(p.name for p in (tmp_path / "a" / "runs").iterdir())
    assert runs[0].startswith("00-") and any(r.startswith("1000-") for r in runs)


def test_a_result_that_cannot_come_back_is_a_failure_not_a_lost_batch(cluster):
    # a generator cannot be pickled back from the worker; the other task's result is kept
    out = cluster.map(eval, [("(x for x in [1])",), ("1 + 1",)], [{"k": 0}, {"k": 1}], "evals")
    assert out.results[1] == 2 and [f.index for f in out.failures] == [0]
    assert "pickle" in out.failures[0].error.lower() or "serializ" in out.failures[0].error


def test_sweep_refuses_an_out_folder_it_did_not_write(tmp_path, capsys, monkeypatch):
    grid = tmp_path / "g.toml"
    grid.write_text('task = "df"\nmodel = "reduced"\n')
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "keep.txt").write_text("the user's")
    assert main(["sweep", str(grid), "--out", str(mine), "--scheduler", "inline"]) == 2
    assert "is not an earlier output of this kind" in capsys.readouterr().err
    monkeypatch.chdir(mine)
    assert main(["sweep", str(grid), "--out", ".", "--scheduler", "inline"]) == 2
    assert "current folder" in capsys.readouterr().err
    assert (mine / "keep.txt").read_text() == "the user's" and grid.is_file()


def test_two_local_clusters_at_once_do_not_clash(cluster):
    """A second command on the same machine gets its own dashboard port (no warning: the suite
    turns warnings into errors, and two clusters used to fight over port 8787)."""
    with Engine("local:1") as other:
        got = other.map(abs, [(-3.0,), (-4.0,)], [{"n": 0}, {"n": 1}], "abs").values()
    assert got == [3.0, 4.0]
    assert cluster.map(abs, [(-5.0,), (6.0,)], [{"n": 0}, {"n": 1}], "abs").values() == [5.0, 6.0]


def test_each_worker_of_a_local_cluster_uses_one_blas_thread(cluster):
    """The workers run one BLAS thread each (two workers on two cores, no pools beside them)."""
    settings = cluster.client().run(os.environ.get, "OPENBLAS_NUM_THREADS")
    assert len(settings) == 2 and set(settings.values()) == {"1"}
