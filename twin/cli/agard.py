"""The AGARD-AR-144 and OMCT tests from the command line (twin agard TEST CONFIG).

Each test takes a configuration (mpi, srs, condition-N, ...; simulated) or a recorded
twin-run/1 folder (analysed as measured). 'report' runs the whole suite and writes a report
folder; 'demo' is what 'make demo' runs.
"""

from __future__ import annotations

import argparse
import contextlib
import json
from pathlib import Path

from twin.chain.signals import MAX_STEP
from twin.cli import common
from twin.core.frames import DOF_NAMES, dof_index
from twin.core.lifecycle import check_output_dir, replacing_dir, replacing_file

TESTS = ("df", "noise", "snr", "threshold", "omct", "parasitic", "linearity", "hysteresis",
         "bump", "limits")  # fmt: skip
HELP = {
    "df": "describing function (§3.3.3, Table 5.2 multi-sines): gain, phase, fitted delay",
    "noise": "half-Hertz noise level (§3.3.1): harmonic and stochastic noise ratios (Fig 3.5)",
    "snr": "signal-to-noise grid (§3.3.2): noise-ratio contours vs system limits (Fig 3.6)",
    "threshold": "dynamic threshold (§3.3.4): Eq 3.7 fitted to acceleration steps",
    "omct": "Objective Motion Cueing Test (§5.3.2): DF at the twelve OMCT frequencies",
    "parasitic": "parasitic motion (§3.3.1): each driven DOF's motion in the five others, 6x6",
    "linearity": "linearity: the describing function at amplitudes a decade apart, with "
    "confidence intervals",
    "hysteresis": "hysteresis: output against input position of a very-low-frequency sine; "
    "the loop's width",
    "bump": "turn-around bump: the acceleration peak at velocity reversals, against speed",
    "limits": "system limits measured: excursion, velocity, acceleration and jerk reached by "
    "jerk-limited moves, and the limit that stopped each",
}
#: Tests a schedule's moves can serve (``--schedule``); the others need the twin's signals.
SCHEDULED = ("df", "parasitic", "linearity", "hysteresis", "bump", "limits")
#: Tests a recorded run serves only through its schedule (they take several sines).
SCHEDULE_ONLY = ("linearity", "hysteresis")


#: ``agard threshold --amplitude``: up to the largest step the signals build.
AMPLITUDE = common.number(0, MAX_STEP, lo_open=True)
#: ``agard threshold --step-s``: up to 10 minutes a level.
STEP_S = common.number(0, 600, lo_open=True)
#: ``agard threshold --fix-delay-ms``: as far as the free fit searches
#: (:data:`twin.agard.threshold.MAX_FIT_DELAY_S`; not imported: the parser stays light).
FIX_DELAY_MS = common.number(0, 1000)
#: ``agard threshold --repeats``.
REPEATS = common.count(1, 1000)
#: ``agard omct --fraction`` of the system limit.
FRACTION = common.number(0, 1, lo_open=True)


def _common(out: str) -> list[argparse.ArgumentParser]:
    """Return the parent parsers every test (and the report) shares; ``out``: --out's help."""
    return [
        common.model_parent(),
        common.overrides_parent(),
        common.seed_parent("seed of the first run; run k uses seed + k"),
        common.json_parent(),
        common.out_parent(out),
        common.rrd_parent("save every run to this Rerun recording"),
        common.quiet_parent(),
    ]


def add_parser(sub: argparse._SubParsersAction, parser_class: type) -> None:
    """Add ``twin agard`` and its subcommands to the ``twin`` parser."""
    agard = sub.add_parser(
        "agard", help="AGARD-AR-144 and OMCT tests on a twin or a recorded run", description=__doc__
    )
    tests = agard.add_subparsers(dest="test", required=True, parser_class=parser_class)
    for name in TESTS:
        p = tests.add_parser(
            name,
            parents=_common("folder for the runs (twin-run/1), result.json and the figure"),
            help=HELP[name],
            description=HELP[name],
        )
        common.add_config(p, run=True, note=" (analysed as measured)")
        common.add_dof(
            p,
            "the driven DOF (needed for a configuration; a run says its own"
            + ("; default all six)" if name == "parasitic" else ")"),
            one=True,
        )
        if name in SCHEDULED:
            _schedule_option(p)
        if name == "threshold":
            p.add_argument(
                "--amplitude",
                type=AMPLITUDE,
                help=f"step amplitude, m/s^2 or rad/s^2 ({AMPLITUDE.span}; default 0.1, §3.3.4)",
            )
            p.add_argument("--step-s", type=STEP_S,
                           help=f"step length, s ({STEP_S.span}; default 1)")  # fmt: skip
            p.add_argument(
                "--fix-delay-ms",
                type=FIX_DELAY_MS,
                help="keep tau_d at this value, ms (the thesis fixed it to the DF's; "
                f"{FIX_DELAY_MS.span}, as far as the free fit searches)",
            )
            p.add_argument(
                "--repeats",
                type=REPEATS,
                help=f"run the 8-step pattern this many times ({REPEATS.span}; default 1)",
            )
        if name == "omct":
            p.add_argument(
                "--bounds",
                default=None,
                help="OMCT boundaries file (twin-omct-bounds/1 TOML); default: the "
                "illustrative example shipped with the twin",
            )
            p.add_argument(
                "--fraction",
                type=FRACTION,
                help=f"sine amplitude as a fraction of the system limit ({FRACTION.span}; "
                "default 0.1)",
            )
        # None: not given (a recorded run refuses them); a configuration: full, seed 0
        p.set_defaults(func=_cmd_test, model=None, seed=None)
    rep = tests.add_parser(
        "report",
        parents=[
            *_common(
                common.default_out_help(
                    "report folder: report.json, summary.md, a figure per test and DOF and the "
                    "runs (twin-run/1) under runs/",
                    "agard-report",
                    "CONFIG-MODEL",
                )
            ),
            common.scheduler_parent(),
        ],
        help="run the whole suite and write a report folder",
        description="Run df, noise, threshold, omct and snr for each DOF and "
        "write report.json, summary.md and figures into a folder. Each DOF's suite is a task "
        "(--scheduler); with --rrd (one recording) the DOFs run one after another here.",
    )
    common.add_config(
        rep, run=True, note=" (the tests a run holds are reported, and the ones it lacks named)"
    )
    common.add_dof(
        rep, "a DOF of the twin's own suite (default pitch and heave; a schedule names its own)"
    )
    _schedule_option(rep)
    rep.set_defaults(func=_cmd_report, model=None, seed=None)
    demo = tests.add_parser(
        "demo",
        parents=[
            common.out_parent(common.default_out_help("folder for figures and .rrd", "agard-demo")),
            common.quiet_parent(),
        ],
        help="the make-demo sweep: Table 5.2 DFs of MPI and SRS twins",
    )  # fmt: skip
    demo.set_defaults(func=_cmd_demo)


def _schedule_option(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--schedule",
        metavar="FILE",
        help="a lab's test schedule (.json MovementSeries, .toml twin-schedule/1): on a "
        "configuration it is simulated as one run; with a recorded run it says what the run "
        "did (its t = 0 the commands' first sample; a run the twin simulated from a schedule "
        "carries it). Writes a report folder of the tests the schedule holds (default "
        "out/agard-<test or report>-<name>: the run folder's name, or "
        "CONFIG-MODEL-<schedule's name>).",
    )


def _has_schedule(target: str) -> bool:
    """Return whether ``target`` is a run folder made from a schedule (meta.json says)."""
    from twin.core.checks import read_json
    from twin.core.errors import RunFormatError
    from twin.measurement.measure import is_run_folder

    if not is_run_folder(target):
        return False
    meta = read_json(Path(target) / "meta.json", "a twin-run/1 meta.json", RunFormatError)
    return isinstance(meta, dict) and "schedule" in meta


def _bench(args: argparse.Namespace, target: str):
    from twin.measurement.measure import Bench

    config = common.configured(target, args)
    model = common.DEFAULT_MODEL if args.model is None else args.model
    seed = 0 if args.seed is None else args.seed
    return Bench(config, model, seed, common.imu_of(config, args))


def _recorder(bench, rrd: str | None):
    """Return the Rerun recording of a session on ``bench`` saved to ``rrd`` (None: none)."""
    if rrd is None:
        return None
    from twin.viz.record import bench_recorder

    return bench_recorder(bench, rrd)


def _simulate(args: argparse.Namespace, out: Path | None):
    """Run a test on a configuration (runs into ``out``); return (result, config)."""
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
    from twin.agard.session import Session
    from twin.core.errors import SignalError

    if args.dof is None and args.test != "parasitic":
        raise SignalError(f"give --dof for a configuration ({', '.join(DOF_NAMES)})")
    bench = _bench(args, args.config)
    with Session(bench, out, _recorder(bench, args.rrd), common.progress(args)) as s:
        if args.test == "df":
            return df.run_df(s, args.dof), bench.config
        if args.test == "noise":
            return noise_level.run_noise(s, args.dof), bench.config
        if args.test == "snr":
            return snr.run_snr(s, args.dof), bench.config
        if args.test == "threshold":
            fix = None if args.fix_delay_ms is None else args.fix_delay_ms / 1e3
            return threshold.run_threshold(
                s, args.dof, _given(args.amplitude, 0.1), _given(args.step_s, 1.0), fix,
                _given(args.repeats, 1),
            ), bench.config  # fmt: skip
        if args.test == "parasitic":
            dofs = DOF_NAMES if args.dof is None else (args.dof,)
            return parasitic.run_parasitic(s, dofs), bench.config
        if args.test == "linearity":
            return linearity.run_linearity(s, args.dof), bench.config
        if args.test == "hysteresis":
            return hysteresis.run_hysteresis(s, args.dof), bench.config
        if args.test == "bump":
            return bump.run_bump(s, args.dof), bench.config
        if args.test == "limits":
            return limits.run_limits(s, args.dof), bench.config
        return omct.run_omct(s, args.dof, _given(args.fraction, 0.1)), bench.config


#: Options of a simulated test only (their ``dest``): a recorded run has its own configuration,
#: model, seed, IMU and signals, and nothing is simulated to record.
SIMULATION_OPTIONS = ("model", "break_hz", "delay_ms", "no_noise", "resonance", "ideal_imu",
                      "seed", "rrd", "amplitude", "step_s", "repeats", "fraction")  # fmt: skip


def _refuse_simulation_options(args: argparse.Namespace) -> None:
    """Refuse options that only a simulated test takes, for a recorded run."""
    values = {o: getattr(args, o, None) for o in SIMULATION_OPTIONS}
    given = [o for o, v in values.items() if v is not None and v is not False]  # 0 is given
    if given:
        from twin.core.errors import UsageError

        names = ", ".join("--" + o.replace("_", "-") for o in given)
        raise UsageError(f"{names}: only for a test simulated on a configuration; the recorded "
                         f"run {args.config} has its own configuration, model, seed and "
                         "signals (leave them out)")  # fmt: skip


def _given(value, default):
    return default if value is None else value


def _analyse(args: argparse.Namespace):
    """Run a test's analysis on a recorded run folder; return (result, config)."""
    import numpy as np

    from twin.agard import bump, df, limits, noise_level, omct, parasitic, snr, threshold
    from twin.agard.positions import PositionRecord
    from twin.formats.run_checks import read_plausible_run
    from twin.measurement.measure import driven_dof, from_run

    _refuse_simulation_options(args)
    if args.test in SCHEDULE_ONLY:
        from twin.core.errors import UsageError

        raise UsageError(f"{args.config}: a {args.test} test takes several sines; give the "
                         "schedule the run was made with (--schedule FILE)")  # fmt: skip
    m = from_run(args.config)
    kind = m.meta.get("signal", {}).get("kind")
    if args.test in ("bump", "limits") and kind != args.test:
        from twin.core.errors import UsageError

        raise UsageError(f"{args.config}: a {args.test} test analyses a {args.test} run (twin "
                         f"agard {args.test} CONFIG --out DIR writes them) or a schedule's "
                         f"moves (--schedule FILE); this run's signal is "
                         f"{kind or 'not stated in its meta.json'}")  # fmt: skip
    if args.test == "parasitic":
        return parasitic.analyse_parasitic(m, args.dof), m.config
    if args.test == "bump":
        return bump.analyse_bump(m, args.dof), m.config
    if args.test == "limits":
        rec = read_plausible_run(args.config)
        pose = PositionRecord.from_run(rec).on(m.t)
        level = limits.analyse_limits(m, pose, args.dof, limits.recorded_counts(rec))
        dof = DOF_NAMES[driven_dof(m, args.dof)]
        computed = limits.dof_limits(m.config.platform, dof)
        return limits.LimitsResult(dof, (level,), computed, m.source), m.config
    if args.test == "df":
        return df.analyse_df(m, args.dof), m.config
    if args.test == "noise":
        return noise_level.NoiseLevelResult([noise_level.analyse_noise(m, args.dof)]), m.config
    if args.test == "snr":
        p = noise_level.analyse_noise(m, args.dof)
        return snr.SnrResult(p.dof, m.config.platform, [p], source=m.source), m.config
    if args.test == "threshold":
        fix = None if args.fix_delay_ms is None else args.fix_delay_ms / 1e3
        return threshold.analyse_threshold(m, args.dof, fix), m.config
    w, h = omct.analyse_omct_point(m, args.dof)
    dof = DOF_NAMES[np.argmax(np.ptp(m.commands.values, axis=0))] if args.dof is None else args.dof
    analytic = m.config.response_at_hz([w / (2 * np.pi)])[:, dof_index(dof)]
    return omct.OmctResult(
        dof, np.array([w]), np.array([h]), analytic, m.source, m.source
    ), m.config


def _cmd_test(args: argparse.Namespace) -> int:
    from twin.measurement.measure import check_target, is_run_folder

    check_target(args.config)
    if args.test in SCHEDULED and (args.schedule is not None or _has_schedule(args.config)):
        return _scheduled(args, (args.test,))
    bounds = None
    if args.test == "omct":  # checked before anything runs
        from twin.agard.omct import EXAMPLE_BOUNDS, read_bounds

        bounds = read_bounds(args.bounds or EXAMPLE_BOUNDS)
    if args.out:  # an earlier result folder is replaced; nothing else is (checked now)
        check_output_dir(args.out, "result.json")
    staged = replacing_dir(args.out, "result.json") if args.out else contextlib.nullcontext()
    with staged as work:  # renamed into place when complete, removed on failure
        if is_run_folder(args.config):
            result, config = _analyse(args)
        else:
            result, config = _simulate(args, work)
        payload = result.to_dict(bounds) if bounds is not None else result.to_dict()
        if work is not None:
            _save(work, args.test, result, payload, config, bounds)
    if args.json:
        print(json.dumps(payload, indent=2))
    else:
        print(result.format_table(bounds) if bounds is not None else result.format_table())
        if args.out:
            print(f"wrote {args.out}/result.json and {args.out}/{args.test}.png")
    return 0


def _save(out: Path, test: str, result, payload: dict, config, bounds) -> None:
    """Write result.json and the test's figure into ``out``."""
    import matplotlib.pyplot as plt

    with replacing_file(out / "result.json") as tmp:
        tmp.write_text(json.dumps(payload, indent=2) + "\n", encoding="utf-8")
    png = str(out / f"{test}.png")
    if test == "df":
        fig = result.plot(path=png, config=config)
    elif test == "omct":
        fig = result.plot(path=png, bounds=bounds)
    else:
        fig = result.plot(path=png)
    plt.close(fig)


def _cmd_report(args: argparse.Namespace) -> int:
    from twin.agard.report import write_report
    from twin.measurement.measure import check_target, is_run_folder

    check_target(args.config)
    if args.schedule is not None or is_run_folder(args.config):
        return _scheduled(args, None)
    bench = _bench(args, args.config)
    out = Path(args.out or common.default_out("agard-report", f"{bench.config.name}-{bench.model}"))
    check_output_dir(out, "report.json")
    with common.engine(args) as engine:
        recorder = _recorder(bench, args.rrd)
        try:
            report = write_report(bench, args.dof or ["pitch", "heave"], out, recorder,
                                  common.progress(args), scheduler=engine)  # fmt: skip
        except BaseException:
            if recorder is not None:
                recorder.abort()
            raise
    print(
        json.dumps(report, indent=2)
        if args.json
        else (out / "summary.md").read_text(encoding="utf-8")
    )
    return 0


def _scheduled(args: argparse.Namespace, tests: tuple[str, ...] | None) -> int:
    """Report the tests a recorded run or a simulated schedule holds (``tests``: only these)."""
    from twin.agard.positions import PositionRecord
    from twin.agard.scheduled import analyse_designed, analyse_schedule
    from twin.agard.session import Session
    from twin.core.errors import DataError, UsageError
    from twin.formats.schedule import Schedule, read_schedule
    from twin.measurement.measure import from_run, is_run_folder

    if args.dof is not None and args.schedule is not None:
        raise UsageError("--dof: a schedule names the DOFs it drives (leave --dof out)")
    schedule = read_schedule(args.schedule) if args.schedule is not None else None
    run = is_run_folder(args.config)
    if run:
        _refuse_simulation_options(args)
        name = Path(args.config).resolve().name
    else:
        bench = _bench(args, args.config)
        name = f"{bench.config.name}-{bench.model}-{schedule.slug}"  # type: ignore[union-attr]
    command = "agard-report" if tests is None else f"agard-{args.test}"
    out = Path(args.out or common.default_out(command, name))
    check_output_dir(out, "report.json")
    with replacing_dir(out, "report.json") as tmp:
        if run:
            m = from_run(args.config)
            if schedule is None and "schedule" in m.meta:
                schedule = Schedule.from_json(m.meta["schedule"])
            positions = None
            with contextlib.suppress(DataError):  # no actuators.csv: no position record
                positions = PositionRecord.from_run(args.config)
        else:
            with Session(bench, tmp, _recorder(bench, args.rrd), common.progress(args)) as s:
                m = s.measure_schedule(schedule)  # type: ignore[arg-type]
                positions = PositionRecord.from_simulation(s.simulation)  # type: ignore[arg-type]
        if schedule is None:
            report = analyse_designed(m)
        else:
            report = analyse_schedule(m, schedule, tests, positions=positions)
        report.write(tmp, m)
    if args.json:
        print(json.dumps(report.to_dict(), indent=2))
    else:
        print(report.format_table())
        print(f"wrote {out}/report.json, {out}/summary.md and the figures")
    return 0


def _cmd_demo(args: argparse.Namespace) -> int:
    from twin.agard.demo import run_demo
    from twin.viz.record import bench_recorder

    final = Path(args.out or common.default_out("agard-demo"))
    with replacing_dir(final, "df.json") as tmp:  # complete, or not there
        text = run_demo(tmp, common.progress(args), shown_as=final, recorder=bench_recorder)
    print(text)
    return 0
