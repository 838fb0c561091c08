"""No output deletes or replaces an input of its command, nor a file the twin did not write.

Each case is one a user met: an output folder that held the very run being diagnosed, a grid
file or a configuration inside the output folder, a user's notes beside a report, a file
output pointed at a recorded run's ``meta.json``, ``--overwrite`` pointed at a measured run.
"""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path

import pytest
from cli_contract import fails_in_one_line as _fails

from twin.cli.main import main
from twin.core.errors import UsageError
from twin.core.lifecycle import replacing_dir, replacing_file
from twin.core.ownership import MANIFEST, output_policy, owned

SIM = ["simulate", "srs", "--model", "reduced", "--quiet"]


def _tree(folder: Path) -> dict[str, str]:
    """Every file below ``folder`` (but the manifests) -> its SHA-256."""
    return {
        p.relative_to(folder).as_posix(): hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted(folder.rglob("*"))
        if p.is_file() and p.name != MANIFEST
    }


def _report(tmp: Path, files: dict[str, str]) -> None:
    for name, text in files.items():
        (tmp / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp / name).write_text(text)


# --- the rule, on the library's folder and file outputs -----------------------------------------


def test_a_rerun_replaces_only_the_files_the_earlier_output_wrote(tmp_path):
    out = tmp_path / "rep"
    with replacing_dir(out, "report.json") as tmp:
        _report(tmp, {"report.json": "1", "old.png": "a", "runs/00/imu.csv": "x"})
    (out / "notes.md").write_text("the user's")
    (out / "runs" / "mine.txt").write_text("the user's too")
    with replacing_dir(out, "report.json") as tmp:
        _report(tmp, {"report.json": "2"})
    assert sorted(_tree(out)) == ["notes.md", "report.json", "runs/mine.txt"]
    assert (out / "report.json").read_text() == "2"
    assert json.loads((out / MANIFEST).read_text())["files"].keys() == {"report.json"}


def test_a_file_changed_since_the_twin_wrote_it_is_the_users(tmp_path):
    out = tmp_path / "rep"
    with replacing_dir(out, "report.json") as tmp:
        _report(tmp, {"report.json": "1", "summary.md": "twin's"})
    (out / "summary.md").write_text("twin's, annotated by the user")
    before = _tree(out)
    with pytest.raises(UsageError, match=r"summary.md \(not written by twin, or changed since\)"):
        with replacing_dir(out, "report.json") as tmp:
            _report(tmp, {"report.json": "2", "summary.md": "new"})
    assert _tree(out) == before and not list(tmp_path.glob(".rep.*"))
    # a file the new output no longer writes is not removed either once changed
    with replacing_dir(out, "report.json") as tmp:
        _report(tmp, {"report.json": "3"})
    assert (out / "summary.md").read_text() == "twin's, annotated by the user"


def test_a_users_file_where_a_new_output_file_goes_is_refused(tmp_path):
    out = tmp_path / "rep"
    with replacing_dir(out, "report.json") as tmp:
        _report(tmp, {"report.json": "1"})
    (out / "df.png").write_text("the user's figure")
    with pytest.raises(UsageError, match=r"df\.png"):
        with replacing_dir(out, "report.json") as tmp:
            _report(tmp, {"report.json": "2", "df.png": "new"})
    assert (out / "df.png").read_text() == "the user's figure"
    assert (out / "report.json").read_text() == "1"  # nothing moved before the refusal


def test_an_output_of_another_kind_or_without_a_manifest_is_not_written_into(tmp_path):
    old = tmp_path / "old"  # an output of a twin before manifests: its files are not known
    old.mkdir()
    (old / "report.json").write_text("{}")
    with pytest.raises(UsageError, match="no twin manifest"):
        with replacing_dir(old, "report.json"):
            pass
    other = tmp_path / "other"
    with replacing_dir(other, "diagnosis.json") as tmp:
        _report(tmp, {"diagnosis.json": "{}"})
    with pytest.raises(UsageError, match="not an earlier output of this kind"):
        with replacing_dir(other, "report.json"):
            pass
    assert (old / "report.json").is_file() and (other / "diagnosis.json").is_file()


def test_an_input_inside_an_earlier_output_stays(tmp_path):
    out = tmp_path / "rep"
    with replacing_dir(out, "result.json") as tmp:
        _report(tmp, {"result.json": "1", "runs/00/imu.csv": "x", "runs/00/meta.json": "{}"})
    with output_policy(inputs=[out / "runs" / "00"]):
        with replacing_dir(out, "result.json") as tmp:
            _report(tmp, {"result.json": "2"})
        with pytest.raises(UsageError, match="is an input of this command"):
            with replacing_dir(out / "runs" / "00", "result.json"):
                pass
    assert sorted(_tree(out)) == ["result.json", "runs/00/imu.csv", "runs/00/meta.json"]


def test_single_file_outputs_replace_only_their_own_kind_or_with_overwrite(tmp_path):
    fig = tmp_path / "fig.png"
    for text in ("one", "two"):  # an earlier figure of the twin is replaced
        with replacing_file(fig) as tmp:
            tmp.write_text(text)
    assert fig.read_text() == "two" and owned(fig, "figure")
    mine = tmp_path / "mine.png"
    mine.write_text("the user's")
    with pytest.raises(UsageError, match="is not an earlier figure output of twin"):
        with replacing_file(mine):
            pass
    with pytest.raises(UsageError, match="not an earlier recording"):
        with replacing_file(fig, "recording"):
            pass  # a figure is no recording
    with output_policy(overwrite=True):
        with replacing_file(mine) as tmp:
            tmp.write_text("replaced on request")
    assert mine.read_text() == "replaced on request"
    with output_policy(overwrite=True, inputs=[fig]), pytest.raises(UsageError, match="an input"):
        with replacing_file(fig):
            pass
    assert fig.read_text() == "two"


def test_a_symbolic_link_loop_is_one_line(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    os.symlink("loop", "loop")
    _fails(capsys, [*SIM, "--signal", "rest-1", "--out", "loop/run"], "loop")
    _fails(capsys, [*SIM, "--signal", "rest-1", "--out", "r", "--rrd", "loop/x.rrd"], "loop")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["loop"]


# --- the cases users met, through the command line ----------------------------------------------


@pytest.fixture
def measured(tmp_path):
    """A recorded run the twin did not write (copied in: no manifest) and its contents."""
    run = tmp_path / "imp" / "measured"
    assert main([*SIM, "--signal", "multisine1-pitch", "--out", str(tmp_path / "sim")]) == 0
    run.mkdir(parents=True)
    for p in (tmp_path / "sim").iterdir():
        if p.name != MANIFEST:
            (run / p.name).write_bytes(p.read_bytes())
    (run / "report").mkdir()
    (run / "report" / "notes.md").write_text("the lab's notes")
    return run, _tree(run)


def test_overwrite_never_replaces_an_input_or_a_run_the_twin_did_not_write(measured, capsys):
    run, before = measured
    _fails(capsys, [*SIM, "--signal", str(run), "--out", str(run), "--overwrite"], "an input")
    other = run.parent / "other"
    other.mkdir()
    for name in ("meta.json", "commands.csv"):
        (other / name).write_bytes((run / name).read_bytes())
    _fails(capsys, [*SIM, "--signal", "rest-1", "--out", str(other), "--overwrite"],
           "not an earlier output")  # fmt: skip
    assert _tree(run) == before and sorted(_tree(other)) == ["commands.csv", "meta.json"]


def test_file_outputs_onto_a_recorded_run_are_refused(measured, capsys, tmp_path):
    run, before = measured
    _fails(capsys, ["pilot", "run", "condition-1", "--quiet", "--out", str(run / "commands.csv")],
           "is not an earlier table output")  # fmt: skip
    _fails(capsys, ["agard", "df", str(run), "--quiet", "--rrd", str(run / "commands.csv")])
    (tmp_path / "old.rrd").write_text("not a recording of the twin")
    _fails(capsys, ["agard", "df", str(run), "--quiet", "--rrd", str(tmp_path / "old.rrd")],
           "--overwrite")  # fmt: skip
    _fails(capsys, ["diagnose", str(run), "--quiet", "--save-config", str(run / "meta.json"),
                    "--overwrite"], "an input")  # fmt: skip
    assert _tree(run) == before
    assert (tmp_path / "old.rrd").read_text() == "not a recording of the twin"


def test_import_with_overwrite_keeps_what_else_the_folder_held(measured, tmp_path, capsys):
    run, _ = measured
    csv = tmp_path / "log.csv"
    imu = (run / "imu.csv").read_text().splitlines()
    cmd = (run / "commands.csv").read_text().splitlines()
    # one log: commands and IMU on one clock at the IMU's rate is not needed; two files are
    (tmp_path / "cmd.csv").write_text("\n".join(cmd) + "\n")
    csv.write_text("\n".join(imu) + "\n")
    args = ["import", str(tmp_path / "cmd.csv"), str(csv), "--platform", "srs", "--quiet"]
    out = tmp_path / "imported"
    assert main([*args, "--out", str(out)]) == 0
    (out / "actuators.csv").write_text("t,l1,l2,l3,l4,l5,l6\n")  # the lab adds its legs
    (out / "report").mkdir()
    (out / "report" / "notes.md").write_text("the lab's")
    before = _tree(out)
    _fails(capsys, [*args, "--out", str(out), "--overwrite"], "actuators.csv")
    assert _tree(out) == before
    (out / "actuators.csv").unlink()
    assert main([*args, "--out", str(out), "--overwrite"]) == 0
    assert (out / "report" / "notes.md").read_text() == "the lab's"
    _fails(capsys, [*args, "--out", str(run), "--overwrite"], "not an earlier output")


def test_a_diagnosis_into_the_folder_holding_its_run_keeps_the_run(tmp_path, capsys):
    from twin.diagnose.hidden import clean, record

    runs_dir = tmp_path / "RUNS"
    first = record(clean(102), tmp_path / "first")[0]
    diag = ["--no-figures", "--quiet", "--out", str(runs_dir)]
    saved = tmp_path / "nominal.json"
    assert main(["diagnose", str(first), *diag, "--save-config", str(saved)]) == 0
    cfg = runs_dir / "nominal.json"  # the user keeps the configuration beside the report
    cfg.write_bytes(saved.read_bytes())
    measured = runs_dir / "measured"
    measured.mkdir()
    for p in first.iterdir():
        if p.name != MANIFEST:
            (measured / p.name).write_bytes(p.read_bytes())
    (runs_dir / "notes.md").write_text("the user's")
    listed = json.loads((runs_dir / MANIFEST).read_text())["files"]
    ours = {k for k, e in listed.items() if e["kind"] == "diagnosis.json"}  # the diagnosis'
    keep = {k: v for k, v in _tree(runs_dir).items() if k not in ours}
    assert {"notes.md", "nominal.json", "measured/imu.csv"} <= keep.keys()
    capsys.readouterr()
    assert main(["diagnose", str(measured), "--config", str(cfg), *diag]) == 0
    after = _tree(runs_dir)
    assert {k: after.get(k) for k in keep} == keep  # the run, the notes, the --config
    assert str(measured) in (runs_dir / "summary.md").read_text()  # the new diagnosis
    for name, words in (("meta.json", "lies in an input"), ("new.json", "lies in an input")):
        # not the run's files, not even a new file inside the run
        _fails(capsys, ["diagnose", str(measured), "--no-figures", "--quiet", "--save-config",
                        str(measured / name)], words)  # fmt: skip
    _fails(capsys, ["diagnose", str(first), "--no-figures", "--quiet", "--out",
                    str(tmp_path / "d4"), "--save-config", str(measured / "meta.json")],
           "is not an earlier json output")  # fmt: skip
    assert _tree(measured) == {k[len("measured/"):]: v for k, v in keep.items()
                               if k.startswith("measured/")}  # fmt: skip


def test_a_sweep_keeps_its_grid_file_in_the_output_folder(tmp_path):
    out = tmp_path / "d"
    grid = tmp_path / "grid.toml"
    grid.write_text('task = "df"\nmodel = "reduced"\n')
    assert main(["sweep", str(grid), "--out", str(out), "--scheduler", "inline", "--quiet"]) == 0
    inside = out / "grid.toml"
    inside.write_bytes(grid.read_bytes())
    assert main(["sweep", str(inside), "--out", str(out), "--scheduler", "inline",
                 "--quiet"]) == 0  # fmt: skip
    assert inside.read_bytes() == grid.read_bytes()


def test_agard_df_of_a_run_in_its_own_result_folder_keeps_the_run(tmp_path, capsys):
    out = tmp_path / "OUT"
    df = ["agard", "df", "--model", "reduced", "--quiet"]
    assert main([*df, "srs", "--dof", "pitch", "--out", str(out)]) == 0
    run = next((out / "runs").iterdir())
    before = _tree(run)
    assert main([*df[:2], str(run), "--quiet", "--out", str(out)]) == 0
    assert _tree(run) == before and (out / "result.json").is_file()
    capsys.readouterr()


def test_a_file_output_inside_the_output_folder_is_refused_before_the_work(tmp_path, capsys):
    out = tmp_path / "OUT"
    _fails(capsys, ["agard", "df", "srs", "--dof", "pitch", "--model", "reduced", "--quiet",
                    "--out", str(out), "--rrd", str(out / "df.rrd")],
           "must not lie inside the output folder")  # fmt: skip
    assert not out.exists()


def test_pilot_repetitions_refuse_a_users_file_before_flying(tmp_path, capsys):
    (tmp_path / "run-2.csv").write_text("the user's")
    _fails(capsys, ["pilot", "run", "condition-1", "--runs", "2", "--quiet", "--out",
                    str(tmp_path / "run.csv")], "run-2.csv", "--overwrite")  # fmt: skip
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run-2.csv"]
