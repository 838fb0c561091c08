"""`twin pilot ...`: runs, recorded runs, identification, Monte-Carlo, lead; errors."""

import json

import pytest

from twin.cli.main import main
from twin.core.ownership import MANIFEST


def test_run_writes_a_csv_that_identify_reads(capsys, tmp_path):
    """A pilot recording holds the loop's signals [deg] and the open loops against frequency
    with their figure; the CSV is read back by identify."""
    from twin.viz.record import read_archetypes, read_entities, read_timelines

    csv, rrd = tmp_path / "run.csv", tmp_path / "run.rrd"
    assert main(["pilot", "run", "condition-1", "--out", str(csv), "--rrd", str(rrd),
                 "--json"]) == 0  # fmt: skip
    run = json.loads(capsys.readouterr().out)
    assert run["open_loops"]["crossover_d"] > run["open_loops"]["crossover_t"]
    assert csv.read_text().splitlines()[0] == "t,ft,fd,e,u,theta,theta_felt"
    counts = read_entities(rrd)
    assert counts["/tracking/e"] == counts["/motion/theta_felt"] == 8192 + 1  # + style row
    kinds, timelines = read_archetypes(rrd), read_timelines(rrd)
    assert kinds["/control/u"] == {"Scalars", "SeriesLines"}
    assert kinds["/open_loop/figure"] == {"EncodedImage"}
    assert timelines["/open_loop/gain/disturbance"] == {"frequency_mHz"}
    assert timelines["/tracking/ft"] == {"sim_time"}
    assert main(["pilot", "identify", str(csv), "--json"]) == 0
    out = json.loads(capsys.readouterr().out, parse_constant=_no_constant)  # strict JSON
    assert len(out["omega_rad_s"]) == 20  # Table 6.2: 10 + 10 lines
    assert 60 < out["mle"]["vaf_percent"] < 99
    assert out["mle"]["parameters"]["k_v"] == pytest.approx(1.5, rel=0.2)
    keys = set(out["mle"]["parameters"])
    assert all(set(other) == keys for other in out["mle"]["competing_minima"])
    assert isinstance(out["mle"]["on_range_bound"], dict)  # parameter -> its profile's point
    assert set(out["mle"]["on_range_bound"]) <= set(out["mle"]["not_identifiable"])
    assert isinstance(out["mle"]["range_end"], dict)  # parameter -> the fit on its range's end
    assert not set(out["mle"]["range_end"]) & set(out["mle"]["on_range_bound"])
    assert len(out["mle"]["evidence"]["competing_minima"]) == len(out["mle"]["competing_minima"])
    assert set(out["mle"]["evidence"]["range_end"]) == set(out["mle"]["range_end"])
    fit = out["mle"]["evidence"]["fit"]  # the twin's own pilot: the model holds
    assert 0.3 < fit["ratio"] < 3.0 and fit["p"] > 1e-3
    # no --config: the motion system is the one the run's theta_felt follows (condition-1's
    # pitch response, which condition-2 and srs share)
    assert out["motion"]["source"] == "theta_felt" and out["motion"]["mismatch"] < 0.01
    assert out["motion"]["config"] in {"condition-1", "condition-2", "srs"}


def _no_constant(name):
    raise ValueError(f"not JSON: {name}")


def test_montecarlo_and_lead_json(capsys):
    assert main(["pilot", "montecarlo", "--runs", "40", "--json"]) == 0
    mc = json.loads(capsys.readouterr().out)
    assert mc["runs"] == 40 and len(mc["pe"]["fc_std_gain"]) == 24
    assert main(["pilot", "lead", "srs", "--json"]) == 0
    lead = json.loads(capsys.readouterr().out)
    assert [r["sensor"] for r in lead] == ["canals", "otoliths"]


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["pilot", "run", "nosuch"], "unknown configuration"),
        (["pilot", "run", "srs", "--runs", "0"], "--runs: must be an integer in [1, 1,000]"),
        (["pilot", "run", "srs", "--remnant", "1.5"], "--remnant: must be a number in [0, 1)"),
        (["pilot", "identify", "/no/such.csv"], "no such pilot-run file"),
        (["pilot", "identify", "/no/such.csv", "--break-hz", "2"], "give it with --config"),
        (["pilot", "identify", "/no/such.csv", "--break-hz", "0"], "--break-hz changes a config"),
    ],
)
def test_bad_input_is_one_line_and_exit_2(capsys, argv, message):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1


@pytest.mark.slow  # 7 s: three repetitions identified together (make test within 2 minutes)
def test_repetitions_are_written_one_file_each_and_identified_together(capsys, tmp_path):
    """`pilot run --runs 3 --out` writes three files; `identify` on all three fits them as
    repetitions: the same estimate as the library's fit of the three runs' u."""
    import numpy as np

    from twin.chain.config import motion_system
    from twin.pilot.identification.mle import fit_pitch_pilot
    from twin.pilot.models.pitch import PitchPilot, simulate_pitch
    from twin.pilot.models.records import read_pilot_csv, write_pilot_csv
    from twin.pilot.studies.experiment import pitch_remnant_scale

    out = tmp_path / "rep.csv"
    assert main(["pilot", "run", "condition-8", "--runs", "3", "--out", str(out), "--quiet"]) == 0
    files = [tmp_path / f"rep-{k}.csv" for k in (1, 2, 3)]
    assert sorted(tmp_path.iterdir()) == [tmp_path / MANIFEST, *files]  # no partial files
    capsys.readouterr()
    assert main(["pilot", "identify", *map(str, files), "--config", "condition-8", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out, parse_constant=_no_constant)
    assert doc["runs"] == list(map(str, files))
    cfg, pilot = motion_system("condition-8"), PitchPilot()
    r = simulate_pitch(pilot, cfg, 3, 0, pitch_remnant_scale(pilot, 0.15, 0))
    n = 8192
    fit = fit_pitch_pilot(r.ft[-n:], r.fd[-n:], r.u[:, -n:], cfg)
    for name, value in doc["mle"]["parameters"].items():  # the CSVs keep 10 significant figures
        assert value == pytest.approx(getattr(fit.pilot, name), rel=1e-4, abs=1e-6), name
    # a repetition must share the forcing functions and the time grid
    d = read_pilot_csv(files[1])
    write_pilot_csv(files[1], {**{k: v for k, v in d.items() if k != "rate_hz"},
                               "ft": 1.1 * d["ft"]})  # fmt: skip
    assert main(["pilot", "identify", *map(str, files)]) == 2
    assert f"{files[1]}: ft differs from {files[0]}'s" in capsys.readouterr().err
    write_pilot_csv(files[1], {**{k: v for k, v in d.items() if k != "rate_hz"},
                               "t": 2 * d["t"]})  # fmt: skip
    assert main(["pilot", "identify", str(files[0]), str(files[1])]) == 2
    assert "repetitions must share the time grid" in capsys.readouterr().err
    # the same file twice, the same run under two names, a column missing in one, a run
    # whose felt motion is another motion system's: refused, naming the file
    cols = {k: v for k, v in d.items() if k != "rate_hz"}
    copy, bare, fixed = (tmp_path / f"{n}.csv" for n in ("copy", "bare", "fixed"))
    first = read_pilot_csv(files[0])
    write_pilot_csv(copy, {k: v for k, v in first.items() if k != "rate_hz"})
    write_pilot_csv(bare, {k: v for k, v in cols.items() if k != "theta_felt"})
    write_pilot_csv(fixed, {**cols, "theta_felt": cols["theta"]})
    for given, message in (
        ([files[0], f"{tmp_path}/./{files[0].name}"], "again: give each repetition once"),
        ([files[0], copy], "the same run twice is not a repetition"),
        ([files[0], bare], "repetitions must have the same columns"),
        ([files[0], fixed], "repetitions must be flown through one motion system"),
    ):
        assert main(["pilot", "identify", *map(str, given)]) == 2
        err = capsys.readouterr().err
        assert message in err and err.count("\n") == 1
    # a later run with fewer repetitions says which older files beside them are not its own
    assert main(["pilot", "run", "condition-8", "--runs", "2", "--out", str(out), "--quiet"]) == 0
    assert f"{files[2]} beside them is from an earlier run" in capsys.readouterr().err
    # every output file is checked before the runs are flown
    (tmp_path / "sx-2.csv").mkdir()
    assert main(["pilot", "run", "condition-8", "--runs", "2", "--out",
                 str(tmp_path / "sx.csv")]) == 2  # fmt: skip
    assert "sx-2.csv: is a folder" in capsys.readouterr().err
    assert not (tmp_path / "sx-1.csv").exists()
    assert doc["mle"]["crlb_sd"]["k_v"] == pytest.approx(fit.crlb["k_v"], rel=1e-3)
    assert np.isfinite(fit.crlb["k_v"])


def test_a_malformed_pilot_csv_names_the_problem(capsys, tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("t,ft,fd,e,u\n0,0,0,0,0\n")
    assert main(["pilot", "identify", str(bad)]) == 2
    assert "header must be" in capsys.readouterr().err
    bad.write_text("t,ft,fd,e,u,theta\n0,0,0,0,0,0\n0.01,0,0,nan,0,0\n")
    assert main(["pilot", "identify", str(bad)]) == 2
    assert "row 2 (line 3): e is nan; all values must be finite" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("rows", "message"),
    [
        # every message counts rows alike: row 1 is the first after the header, on line 2
        ("0,0,0,0,0,0\n0.01,0,0,,0,0\n", "row 2 (line 3): e is empty, not a number"),
        ("0,0,0,0,0,0\n0.01,0,0,x,0,0\n", "row 2 (line 3): e is 'x', not a number"),
        ("0,0,0,0,0,0\n0.01,0,0\n", "row 2 (line 3) has 3 values, the header 6"),
        ("0,0,0,0,0,0\n0,0,0,0,0,0\n", "row 2 (0 s) is not after row 1 (0 s)"),
        # blank and comment lines are no rows (as numpy reads the file); lines still count
        ("0,0,0,0,0,0\n\n0.01,0,0,nan,0,0\n", "row 2 (line 4): e is nan"),
        ("# a note\n0,0,0,0,0,0\n0.01,0,0,x,0,0\n", "row 2 (line 4): e is 'x', not a number"),
        ("0,0,0,0,0,0\n0.01,0,0,1_0,0,0\n", "row 2 (line 3): e is '1_0', not a number"),
        ("0,0,0,0,0,0\n0.01,0,0,0,0,0\n0.025,0,0,0,0,0\n0.03,0,0,0,0,0\n", "row 3 is at 0.025 s"),
    ],
)
def test_a_bad_pilot_csv_row_is_named_as_its_row_and_line(capsys, tmp_path, rows, message):
    bad = tmp_path / "bad.csv"
    bad.write_text("t,ft,fd,e,u,theta\n" + rows)
    assert main(["pilot", "identify", str(bad)]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1


@pytest.mark.slow
def test_identify_intervals_are_printed_and_in_the_json(capsys, tmp_path):
    """--intervals: every parameter's likelihood-ratio interval holds its estimate."""
    csv = tmp_path / "run.csv"
    assert main(["pilot", "run", "condition-8", "--out", str(csv), "--quiet"]) == 0
    capsys.readouterr()
    assert main(["pilot", "identify", str(csv), "--config", "condition-8", "--intervals",
                 "--quiet"]) == 0  # fmt: skip
    text = capsys.readouterr().out
    assert text.count("2-sd interval [") == 8
    assert "condition-8 (or " in text and ", given; theta_felt differs" in text
    assert "WARNING" not in text
    # the wrong configuration given: fitted through it, and questioned
    assert main(["pilot", "identify", str(csv), "--config", "condition-1", "--quiet"]) == 0
    text = capsys.readouterr().out
    assert "closed loop through condition-1" in text
    assert "WARNING: theta_felt differs from condition-7's response by only" in text
    assert main(["pilot", "identify", str(csv), "--config", "condition-8", "--intervals",
                 "--json", "--quiet"]) == 0  # fmt: skip
    mle = json.loads(capsys.readouterr().out)["mle"]
    for name, (lo, hi) in mle["likelihood_interval_2sd"].items():
        assert lo <= mle["parameters"][name] <= hi, name


def test_an_interval_end_at_the_fit_range_is_called_open():
    from twin.pilot.identification.identify_runs import interval_text

    assert interval_text("omega_nm", 9.5, 12.0) == "[9.5000, 12.0000]"
    assert interval_text("omega_nm", 3.0, 12.0) == "[3.0000, 12.0000] (open below)"
    assert interval_text("t_lag", 0.0, 5.0) == "[0.0000, 5.0000] (open above)"  # 0: physical
