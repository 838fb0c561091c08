"""``twin design DIAGNOSIS_DIR``: the next run, the one that tells the explanations apart."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from twin.cli import common
from twin.core.lifecycle import check_output_dir, replacing_dir

#: ``--budget-s``: from a few periods to an hour.
BUDGET_S = common.number(10, 3600)
#: ``--finding``: which finding of the diagnosis (from 1).
FINDING = common.count(1, 1000)


def add_parser(sub: argparse._SubParsersAction) -> None:
    """Add ``twin design`` to the ``twin`` parser."""
    p = sub.add_parser(
        "design",
        parents=[
            common.out_parent(
                common.default_out_help(
                    "folder for design.json, commands.csv, schedule.toml and config.json",
                    "design",
                    "<diagnosis folder's name>",
                )
            ),
            common.json_parent(),
            common.quiet_parent(),
        ],
        help="design the run that tells a diagnosis' explanations apart",
        description="Read a diagnosis folder (twin diagnose --out) whose finding is ambiguous "
        "and choose the multisine in its DOF, within the platform's limits and a time budget, "
        "that the alternatives explain most differently (each refitted to the others); or, "
        "with --effect, the run that best shows an effect the runs could not. Writes the run "
        "as a twin-run/1 commands.csv and a twin-schedule/1 TOML schedule, and the expected "
        "evidence. Run it on the platform, import it, and give it to twin diagnose with the "
        "old runs.",
    )
    p.add_argument("diagnosis", metavar="DIAGNOSIS_DIR", help="a folder twin diagnose wrote")
    p.add_argument(
        "--finding",
        type=FINDING,
        default=1,
        help=f"the ambiguous finding to resolve ({FINDING.span}; default 1)",
    )
    p.add_argument(
        "--effect",
        help="instead: the effect to see below its smallest detectable "
        "size (after 'no finding'; e.g. delay, backlash)",
    )
    common.add_dof(p, "with --effect: the DOF (default the first the diagnosis analysed)",
                   one=True)  # fmt: skip
    p.add_argument(
        "--budget-s",
        type=BUDGET_S,
        default=120.0,
        help=f"longest run, s ({BUDGET_S.span}; default 120)",
    )
    p.add_argument(
        "--shortest",
        action="store_true",
        help="shorten the run to the fewest whole base periods (at least 20 s) expected to "
        "decide with chance 0.95 (off: the whole budget, evidence to spare)",
    )
    p.add_argument(
        "--keep-filter",
        action="store_true",
        help="keep the platform filter at the nominal's setting (a platform whose filter "
        "cannot be changed; by default the design may ask for it opened to 5 or 10 Hz, the "
        "settings the thesis measured the MPI at)",
    )
    p.set_defaults(func=_cmd_design)


def _cmd_design(args: argparse.Namespace) -> int:
    from twin.diagnose.design import design_from, write_design

    out = Path(args.out or common.default_out("design", Path(args.diagnosis).resolve().name))
    check_output_dir(out, "design.json")
    result = design_from(
        args.diagnosis,
        args.finding - 1,
        args.effect,
        args.dof,
        args.budget_s,
        common.progress(args),
        args.shortest,
        args.keep_filter,
    )
    with replacing_dir(out, "design.json") as tmp:
        write_design(result, tmp)
    if args.json:
        print(json.dumps(result.to_dict(), indent=2))
        return 0
    for line in result.summary_lines():
        print(line)
    print(
        f"wrote {out}/commands.csv (twin-run/1 commands), {out}/schedule.toml "
        f"(twin-schedule/1) and {out}/design.json"
    )
    fb = result.setting.filter_break_hz if result.setting is not None else None
    print(
        f"wrote {out}/config.json: the configuration to record the run at ("
        + ("no platform filter" if fb is None else f"platform filter at {fb:g} Hz")
        + ")"
    )
    if result.filter_changed:
        print(
            "next: run it on the platform with the filter at that setting, import it (twin "
            f"import --config {out}/config.json), then twin diagnose the old runs and the new "
            "one together, without --config (each is compared at its own filter setting)"
        )
        return 0
    print(
        f"next: run it on the platform, import it (twin import --config {out}/config.json), "
        "then twin diagnose the old runs and the new one together"
    )
    return 0
