"""``twin agard ...``: the AGARD-AR-144 and OMCT tests from the command line.

Each test takes a configuration (``mpi``, ``srs``, ``condition-N``, ...; simulated) or a
recorded ``twin-run/1`` folder (analysed as measured). ``report`` runs the whole suite and
writes a report folder; ``demo`` is what ``make demo`` runs.
"""

from __future__ import annotations

import argparse
import contextlib
import json
from pathlib import Path

from twin.cli import common
from twin.frames import DOF_NAMES, dof_index
from twin.lifecycle import check_output_dir, replacing_dir, replacing_file
from twin.signals import MAX_STEP

TESTS = ("df", "noise", "snr", "threshold", "omct")
HELP = {
    "df": "describing function (§3.3.3, Table 5.2 multi-sines): gain, phase, fitted delay",
    "noise": "half-Hertz noise level (§3.3.1): harmonic and stochastic noise ratios (Fig 3.5)",
    "snr": "signal-to-noise grid (§3.3.2): noise-ratio contours vs system limits (Fig 3.6)",
    "threshold": "dynamic threshold (§3.3.4): Eq 3.7 fitted to acceleration steps",
    "omct": "Objective Motion Cueing Test (§5.3.2): DF at the twelve OMCT frequencies",
}


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
    from twin.chain.config import config_help

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
        p.add_argument(
            "target",
            metavar="PLATFORM_OR_CONFIG",
            help=f"{config_help()}, or a twin-run/1 folder",
        )
        p.add_argument(
            "--dof",
            choices=DOF_NAMES,
            help="driven DOF (needed for a configuration; a run says its own)",
        )
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
                "report folder: report.json, summary.md, a figure per test and DOF and the runs "
                "(twin-run/1) under runs/ (default out/agard-CONFIG-MODEL)"
            ),
            common.scheduler_parent(),
        ],
        help="run the whole suite and write a report folder",
        description="Run df, noise, threshold, omct and snr for each DOF and "
        "write report.json, summary.md and figures into a folder. Each DOF's suite is a task "
        "(--scheduler); with --rrd (one recording) the DOFs run one after another here.",
    )
    rep.add_argument("target", metavar="CONFIG", help=config_help())
    rep.add_argument(
        "--dof",
        nargs="+",
        choices=DOF_NAMES,
        default=["pitch", "heave"],
        help="DOFs (default pitch heave)",
    )
    rep.set_defaults(func=_cmd_report)
    demo = tests.add_parser(
        "demo",
        parents=[common.out_parent("folder for figures and .rrd (default out/demo)"),
                 common.quiet_parent()],
        help="the make-demo sweep: Table 5.2 DFs of MPI and SRS twins",
    )  # fmt: skip
    demo.set_defaults(func=_cmd_demo)


def _bench(args: argparse.Namespace, target: str):
    from twin.measurement.measure import Bench

    config = common.configured(target, args)
    model = common.DEFAULT_MODEL if args.model is None else args.model
    seed = 0 if args.seed is None else args.seed
    return Bench(config, model, seed, common.imu_of(config, args))


def _simulate(args: argparse.Namespace, out: Path | None):
    """Run a test on a configuration (runs into ``out``); return (result, config)."""
    from twin.agard import df, noise_level, omct, snr, threshold
    from twin.agard.session import Session
    from twin.errors import SignalError

    if args.dof is None:
        raise SignalError(f"give --dof for a configuration ({', '.join(DOF_NAMES)})")
    bench = _bench(args, args.target)
    with Session(bench, out, args.rrd, common.progress(args)) as s:
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
        return omct.run_omct(s, args.dof, _given(args.fraction, 0.1)), bench.config


#: Options of a simulated test only (their ``dest``): a recorded run has its own configuration,
#: model, seed, IMU and signals, and nothing is simulated to record.
SIMULATION_OPTIONS = ("model", "break_hz", "delay_ms", "no_noise", "resonance", "ideal_imu",
                      "seed", "rrd", "amplitude", "step_s", "repeats", "fraction")  # fmt: skip


def _given(value, default):
    return default if value is None else value


def _analyse(args: argparse.Namespace):
    """Run a test's analysis on a recorded run folder; return (result, config)."""
    import numpy as np

    from twin.agard import df, noise_level, omct, snr, threshold
    from twin.measurement.measure import from_run

    values = {o: getattr(args, o, None) for o in SIMULATION_OPTIONS}
    given = [o for o, v in values.items() if v is not None and v is not False]  # 0 is given
    if given:
        from twin.errors import UsageError

        names = ", ".join("--" + o.replace("_", "-") for o in given)
        raise UsageError(f"{names}: only for a test simulated on a configuration; the recorded "
                         f"run {args.target} has its own configuration, model, seed and "
                         "signals (leave them out)")  # fmt: skip
    m = from_run(args.target)
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
    analytic = m.config.frequency_response([w / (2 * np.pi)])[:, dof_index(dof)]
    return omct.OmctResult(
        dof, np.array([w]), np.array([h]), analytic, m.source, m.source
    ), m.config


def _cmd_test(args: argparse.Namespace) -> int:
    from twin.measurement.measure import check_target, is_run_folder

    check_target(args.target)
    bounds = None
    if args.test == "omct":  # checked before anything runs
        from twin.agard.omct import EXAMPLE_BOUNDS, read_bounds

        bounds = read_bounds(args.bounds or EXAMPLE_BOUNDS)
    if args.out:  # an earlier result folder is replaced; nothing else is (checked now)
        check_output_dir(args.out, "result.json")
    staged = replacing_dir(args.out, "result.json") if args.out else contextlib.nullcontext()
    with staged as work:  # renamed into place when complete, removed on failure
        if is_run_folder(args.target):
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
        fig = result.plot(png, config=config)
    elif test == "omct":
        fig = result.plot(png, bounds=bounds)
    else:
        fig = result.plot(png)
    plt.close(fig)


def _cmd_report(args: argparse.Namespace) -> int:
    from twin.agard.report import write_report
    from twin.errors import SignalError
    from twin.measurement.measure import check_target, is_run_folder

    check_target(args.target)
    if is_run_folder(args.target):
        raise SignalError(
            "report runs the whole suite on a configuration; for a recorded run "
            "use the single tests (twin agard df RUN_DIR, ...)"
        )
    bench = _bench(args, args.target)
    out = Path(args.out or f"out/agard-{bench.config.name}-{bench.model}")
    from twin.lifecycle import check_output_dir

    check_output_dir(out, "report.json")
    with common.engine(args) as engine:
        report = write_report(bench, args.dof, out, args.rrd, common.progress(args),
                              scheduler=engine)  # fmt: skip
    print(
        json.dumps(report, indent=2)
        if args.json
        else (out / "summary.md").read_text(encoding="utf-8")
    )
    return 0


def _cmd_demo(args: argparse.Namespace) -> int:
    from twin.agard.demo import run_demo

    final = Path(args.out or "out/demo")
    with replacing_dir(final, "df.json") as tmp:  # complete, or not there
        text = run_demo(tmp, common.progress(args), shown_as=final)
    print(text)
    return 0
