"""``twin diagnose RUN_DIR ...``: what the twin gets wrong about recorded runs, and why."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from twin.cli import common
from twin.core.lifecycle import check_output_dir

#: ``--max-hz``: the band :func:`twin.diagnose.diagnosis.check_options` allows (below the
#: 50 Hz Nyquist frequency of the 100 Hz grid; not imported: the parser stays light).
MAX_HZ = common.number(0.5, 45, lo_open=True)
#: ``--imu-noise``: the factors :func:`twin.diagnose.diagnosis.check_options` allows.
IMU_NOISE = common.number(1e-3, 1e3)


def add_parser(sub: argparse._SubParsersAction) -> None:
    """Add ``twin diagnose`` to the ``twin`` parser."""
    p = sub.add_parser(
        "diagnose",
        parents=[
            common.model_parent(
                "reduced",
                "the nominal twin is simulated once per run and candidate; give --model full "
                "for runs recorded on a platform whose own dynamics matter",
            ),
            common.overrides_parent(imu=False),
            common.seed_parent("seed of the simulated noise"),
            common.out_parent(
                common.default_out_help(
                    "report folder (with --each: the batch's folder, default "
                    "out/diagnose-each-<first run's name>)",
                    "diagnose",
                    "<first run's name>",
                )
            ),
            common.json_parent(),
            common.quiet_parent(),
            common.scheduler_parent(),
        ],
        help="compare recorded runs with the nominal twin, name the cause, extend the model",
        description="Simulate the nominal twin with the runs' own commands, compare the measured "
        "IMU signals (describing-function ratios with the measurement's own noise, harmonics, "
        "residual noise), fit every extension and pair of extensions (delay, gain, "
        "platform_filter, resonance, lead, sensor_filter, backlash) jointly, judge the noise "
        "(motion noise a cause, the IMU's a nuisance), name what the data support (BIC, "
        "held-out line error), and state what the runs could have shown.",
    )
    p.add_argument("runs", nargs="+", metavar="RUN_DIR", help="twin-run/1 folders (same platform)")
    p.add_argument("--config", metavar=common.CONFIG,
                   help="nominal configuration (name or twin-config/1 file), for every run "
                   "at its one filter setting; default: the runs' meta.json, each run at its "
                   "own filter setting; the overrides below apply to it")  # fmt: skip
    p.add_argument("--validate", nargs="+", default=[], metavar="RUN_DIR",
                   help="runs only for measuring the gain (default: held-out halves)")  # fmt: skip
    p.add_argument(
        "--save-config",
        metavar="FILE",
        type=common.output_file,
        help="write the extended configuration (JSON)",
    )
    p.add_argument("--max-hz", type=MAX_HZ, default=15.0,
                   help=f"top of the band, Hz ({MAX_HZ.span}; default 15)")  # fmt: skip
    common.add_dof(p, "a DOF to analyse (default: the driven ones)")
    p.add_argument("--imu-noise", type=IMU_NOISE, metavar="FACTOR",
                   help="the IMU's noise over its data sheet's, when known (e.g. from a "
                   f"recording at rest; {IMU_NOISE.span}); default: fitted as a "
                   "nuisance")  # fmt: skip
    p.add_argument(
        "--physics",
        action="store_true",
        help="also weigh physical causes (a heavier cabin, one leg's gain, lag, "
        "friction or play, a rotated IMU) by simulating the full model on every "
        "channel the runs have, leg lengths and forces included (about 45 "
        "simulations per run, about a minute; implies --model full; --save-config "
        "then carries the calibrated physics)",
    )
    p.add_argument("--no-figures", action="store_true", help="skip figures and the .rrd")
    p.add_argument("--each", action="store_true",
                   help="a batch: each RUN_DIR (a run folder, or a folder of run folders "
                   "diagnosed together) is its own measurement, diagnosed as a task "
                   "(--scheduler); writes one report per measurement and batch.csv")  # fmt: skip
    p.set_defaults(func=_cmd_diagnose)


def _nominal(args: argparse.Namespace):
    """Return the nominal configuration with the overrides (None: the runs' own, unchanged)."""
    if args.config is None and not common.overrides_given(args):
        return None
    if args.config is not None:
        return common.configured(args.config, args)
    from twin.measurement.measure import run_config

    return common.configured(run_config(args.runs[0]), args)


def _cmd_each(args: argparse.Namespace) -> int:
    from twin.cli.sweep import EXIT_PARTIAL
    from twin.core.errors import UsageError
    from twin.diagnose.batch import diagnose_each, write_batch
    from twin.viz.record.diagnosis import record_diagnosis

    if args.validate or args.save_config:
        raise UsageError("--each diagnoses every measurement on its own: --validate and "
                         "--save-config are for one measurement (each report folder holds "
                         "its extended.json)")  # fmt: skip
    if args.config is None and common.overrides_given(args):
        raise UsageError("with --each, configuration overrides need --config (the nominal of "
                         "every measurement); without it each uses its own meta.json")  # fmt: skip
    options = {"model": args.model, "max_hz": args.max_hz, "seed": args.seed, "dofs": args.dof,
               "imu_noise": args.imu_noise, "physics": args.physics}  # fmt: skip
    config = _nominal(args)
    out = Path(args.out or common.default_out("diagnose-each", Path(args.runs[0]).name))
    check_output_dir(out, "batch.json")
    with common.engine(args) as engine:
        b = diagnose_each(args.runs, config, engine, common.progress(args), **options)
    table = write_batch(b, out, not args.no_figures, None if args.no_figures else record_diagnosis)
    if args.json:
        print((out / "batch.json").read_text(encoding="utf-8"), end="")
    else:
        for row in b.rows():
            print(f"{row['measurement']}: {row['describe'] or 'no finding'}")
        print(f"{len(b.names) - len(b.failures)} of {len(b.names)} measurements diagnosed "
              f"({b.scheduler}); table: {table}")  # fmt: skip
    for f in b.failures:
        print(f"twin: measurement failed: {f.describe()}", file=sys.stderr)
    return EXIT_PARTIAL if b.failures else 0


def _cmd_diagnose(args: argparse.Namespace) -> int:
    from twin.diagnose.diagnosis import check_options, diagnose
    from twin.diagnose.report import write_report
    from twin.viz.record.diagnosis import record_diagnosis

    with common.options_named({"max_hz": "--max-hz", "imu_noise": "--imu-noise"}):
        check_options(args.max_hz, args.imu_noise)  # before any work, also of a batch
    if args.each:
        return _cmd_each(args)
    out = Path(args.out or common.default_out("diagnose", Path(args.runs[0]).name))
    check_output_dir(out, "diagnosis.json")

    d = diagnose(
        args.runs, _nominal(args), args.model, args.validate, args.max_hz, args.seed, args.dof,
        progress=common.progress(args), imu_noise=args.imu_noise, physics=args.physics,
    )  # fmt: skip
    write_report(d, out, not args.no_figures, None if args.no_figures else record_diagnosis)
    if args.save_config:
        d.extended_config.save(args.save_config)
    if args.json:
        print(json.dumps(d.to_dict(), indent=2))
        return 0
    for line in d.summary_lines():
        print(line)
    if d.physical is not None and args.model != "full":
        print("note: --physics diagnoses on the full model (the chain's effects too)")
    for dof, r in d.dofs.items():
        print(f"{dof}: IMU noise x{r.noise.fit.to_json()['imu_noise_scale']:.2f} of the data "
              "sheet (a nuisance, not a cause)")  # fmt: skip
    print(f"report: {out}/summary.md")
    if args.save_config:
        print(f"extended configuration: {args.save_config}")
    return 0
