"""``twin pilot ...``: pilots in the loop from the command line (thesis Ch 2, 6, 7)."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from twin.cli import common
from twin.pilot import spread as spreads

DEG2 = (180 / np.pi) ** 2
#: Most runs of ``pilot run`` and per condition of ``pilot experiment``
#: (:data:`twin.pilot.pitch.MAX_RUNS`, not imported so that the parser stays light).
MAX_RUNS = 1000
#: Most simulated subjects of ``pilot experiment --pilot adaptive``.
MAX_SUBJECTS = 1000
#: Subjects of ``pilot experiment --pilot adaptive`` by default: the thesis' participants.
DEFAULT_SUBJECTS = 9
#: The library's names in ``pilot experiment``'s errors -> the options typed.
OPTIONS = {
    "feedthrough": "--feedthrough",
    "the motion perception's spread": "--motion-spread (the motion perception's spread)",
    "the visual delay's spread": "--visual-delay-spread (the visual delay's spread)",
}
#: Most populations of ``pilot experiment --pilot adaptive --populations``.
MAX_POPULATIONS = 1000
#: Runs per task of ``pilot montecarlo`` (:func:`twin.pilot.montecarlo.monte_carlo`'s batch).
MC_BATCH = 500
#: Most runs of ``pilot montecarlo`` (:data:`twin.pilot.montecarlo.MAX_RUNS`, not imported
#: so that the parser stays light).
MAX_MC_RUNS = 100_000_000
#: Largest ``--feedthrough`` (:data:`twin.pilot.identified.MAX_FEEDTHROUGH`, not imported).
MAX_FEEDTHROUGH = 1.0
#: Largest ``--weight``: the control weight r of :func:`twin.pilot.adapt.adapt` (its default
#: is 0.03); beyond it the pilot hardly acts.
MAX_WEIGHT = 1000.0
#: Ranges of the numeric options (argparse ``type``; their help gives the range).
RUNS = common.count(1, MAX_RUNS)
SUBJECTS = common.count(2, MAX_SUBJECTS)
POPULATIONS = common.count(1, MAX_POPULATIONS)
MC_RUNS = common.count(2, MAX_MC_RUNS)
FIT_RUNS = common.count(0, MC_BATCH)
REMNANT = common.number(0, 1, hi_open=True)
FEEDTHROUGH = common.number(0, MAX_FEEDTHROUGH)
MOTION_SPREAD = common.number(0, spreads.MAX_MOTION_SPREAD)
VISUAL_DELAY_SPREAD = common.number(0, spreads.MAX_VISUAL_DELAY_SD)
WEIGHT = common.number(0, MAX_WEIGHT, lo_open=True)
#: ``--margin-deg``: as :func:`twin.pilot.lead.analyse_lead` allows.
MARGIN_DEG = common.number(0, 90)


def add_parser(sub: argparse._SubParsersAction, parser_class: type) -> None:
    """Add ``twin pilot`` and its subcommands to the ``twin`` parser."""
    from twin.chain.config import config_help

    pilot = sub.add_parser(
        "pilot",
        help="pilot-in-the-loop tasks and identification",
        description="Pilots in the loop (thesis Ch 2, 6, 7): fly the pitch task through a "
        "motion configuration, run the Table 6.3 experiment, adapt the pilot to a configuration, "
        "identify a pilot from recorded runs, Chapter 2's Monte-Carlo, the vestibular lead.",
    )
    cmds = pilot.add_subparsers(dest="pilot_command", required=True, parser_class=parser_class)
    run = cmds.add_parser(
        "run",
        parents=[
            common.model_parent(
                "reduced", "the pilot closes the loop at every sample; MuJoCo in the loop is slow"
            ),
            common.overrides_parent(imu=False),
            common.seed_parent("seed of the remnant and the noise"),
            common.out_parent(
                "write the run as a twin-pilot/1 CSV here; with --runs N, N files beside it "
                "named STEM-1 ... STEM-N (repetitions for `twin pilot identify`)",
                "CSV",
            ),
            common.rrd_parent("save e, u, theta, forcing functions and felt motion (.rrd)"),
            common.json_parent(),
            common.quiet_parent(),
        ],
        help="fly the pitch task (§6.3) through a motion configuration",
        description="Fly the pitch tracking task of §6.3 (the Table 6.2 forcing functions, the "
        "pilot model of Eq 6.5-6.7 with remnant) through a motion configuration; print the "
        "variances of e, u and theta and the pilot model's crossovers and phase margins, and "
        "write the runs as twin-pilot/1 CSVs for `twin pilot identify` (--out).",
    )
    run.add_argument("config", metavar="CONFIG", help=config_help())
    run.add_argument("--runs", type=RUNS, default=1,
                     help=f"runs with fresh remnant ({RUNS.span}; default 1)")  # fmt: skip
    run.add_argument(
        "--remnant",
        type=REMNANT,
        default=0.15,
        help=f"remnant power over control power ({REMNANT.span}; default 0.15; 0: none)",
    )
    run.set_defaults(func=_cmd_run)
    exp = cmds.add_parser(
        "experiment",
        parents=[
            common.seed_parent(
                "seed of the runs; with --pilot adaptive, of the subjects (the first population's)"
            ),
            common.json_parent(),
            common.quiet_parent(),
            common.scheduler_parent(),
        ],
        help="the eight Table 6.3 conditions, flown by a fixed pilot model or (--pilot adaptive) "
        "simulated subjects",
        description="Fly the eight conditions of Table 6.3 (their filter, delay and noise are the "
        "experiment's factors: no configuration overrides) with one fixed pilot model in every "
        "condition (--pilot fixed, the default), or with simulated subjects who adapt their "
        "equalisation and neuromuscular tuning to each motion system, analysed with the "
        "thesis' repeated-measures ANOVA (--pilot adaptive).",
    )
    exp.add_argument("--runs", type=RUNS,
                     help=f"runs per condition of the fixed pilot ({RUNS.span}; default 5; "
                     "adaptive subjects fly the thesis' five repetitions)")  # fmt: skip
    exp.add_argument(
        "--plot",
        metavar="PNG",
        type=common.figure_file,
        help="save the measures per condition as Fig 6.5-6.9 (fixed pilot); with --pilot "
        "adaptive, the ANOVA's effects beside the thesis' here and the measures per condition "
        "over subjects in PNG's name + '-conditions.png'; with --populations, the standardised "
        "effects over populations beside the thesis', and in PNG's name + '-subjects.png' how "
        "often an experiment of 2 to 60 subjects finds each filter effect",
    )
    exp.add_argument(
        "--pilot",
        choices=("fixed", "adaptive"),
        default="fixed",
        help="fixed: one pilot model in every condition; adaptive: simulated subjects who adapt "
        "their equalisation and neuromuscular tuning to each motion system, with the thesis' "
        "repeated-measures ANOVA",
    )
    _adaptation_options(exp, " (with --pilot adaptive)")
    exp.add_argument(
        "--subjects",
        type=SUBJECTS,
        help=f"simulated subjects with --pilot adaptive ({SUBJECTS.span}; default 9, the thesis' "
        "participants)",
    )
    exp.add_argument(
        "--identify",
        action="store_true",
        help="with --pilot adaptive: measure the pilot model as the thesis did, each subject's "
        "five repetitions flown in the time domain and Eq 6.5-6.7 fitted by the MLE to their "
        "average (twin.pilot.identified; tau_m and tau_v in the ANOVA, each fit's goodness of "
        "fit in --json's rows; about 12 s a subject on two cores; with --populations, "
        "over populations)",
    )
    exp.add_argument(
        "--feedthrough",
        type=FEEDTHROUGH,
        default=0.0,
        metavar="R",
        help="with --identify: each subject also has a passive path from the motion to the "
        f"stick, R ({FEEDTHROUGH.span}) of its condition-1 motion response at 3 rad/s "
        "(twin.pilot.pitch.Feedthrough; an assumption: only the simulated subjects have it, no "
        "fit models it; default 0: none; about 5x slower)",
    )
    exp.add_argument(
        "--motion-spread",
        type=MOTION_SPREAD,
        metavar="SD",
        help="with --pilot adaptive: how much the subjects differ in perceiving motion, the "
        "log-normal sd of the felt rate's observation noise relative to the visual one "
        f"({MOTION_SPREAD.span}; default {spreads.MOTION_NOISE_SD:g}, from profiles "
        "against Tables 6.4-6.7, docs; 0: every subject perceives motion as well as vision; "
        "with --visual-delay-spread 0.03 the subjects of earlier versions)",
    )
    exp.add_argument(
        "--visual-delay-spread",
        type=VISUAL_DELAY_SPREAD,
        metavar="S",
        help="with --pilot adaptive: how much the subjects differ in visual delay, its sd in s "
        f"around 0.30 s ({VISUAL_DELAY_SPREAD.span}; default "
        f"{spreads.VISUAL_DELAY_SD:g}, from profiles against Tables 6.4-6.7, docs; 0: every "
        "subject has the mean delay)",
    )
    exp.add_argument(
        "--populations",
        type=POPULATIONS,
        help=f"with --pilot adaptive: seeded populations ({POPULATIONS.span}; seeds SEED, "
        "SEED + 1, ...); from 2 on, "
        "each effect's standardised size over populations (median, 5-95 %%) beside the "
        "thesis', and whether the thesis is a plausible draw of them; with 40 subjects or "
        "more in all, how many subjects an experiment needs to find each effect, for "
        "experiments of up to half the subjects flown, at most 60 (twin.pilot.design) "
        "(default 1; 20 for a distribution: about 13 min on two cores)",
    )
    exp.set_defaults(func=_cmd_experiment)
    ada = cmds.add_parser(
        "adapt",
        parents=[common.json_parent()],
        help="the pitch-task pilot's equalisation and neuromuscular tuning adapted to a motion "
        "configuration (minimises var(e) + r var(u))",
        description="Adapt the pitch-task pilot to a motion configuration: the equalisation "
        "(K_v, t_lead, t_lag, K_m) and neuromuscular tuning (omega_nm, zeta_nm) that minimise "
        "var(e) + r var(u) through it, as a subject of `pilot experiment --pilot adaptive` "
        "adapts to each condition.",
    )
    ada.add_argument("config", metavar="CONFIG", help=config_help())
    ada.add_argument(
        "--weight", type=WEIGHT, help=f"r of the cost ({WEIGHT.span}; default: twin.pilot.adapt's)"
    )
    _adaptation_options(ada)
    ada.set_defaults(func=_cmd_adapt)
    ide = cmds.add_parser(
        "identify",
        parents=[common.overrides_parent(imu=False), common.json_parent(), common.quiet_parent()],
        help="FC, ARX and MLE on a twin-pilot/1 CSV",
        description="Identify the pilot from twin-pilot/1 runs (§6.3.4): the Fourier-coefficient "
        "(FC) and ARX estimates of the pilot's responses at the forcing functions' lines, and "
        "the maximum-likelihood fit of the pilot model (Eq 6.5-6.7) in the closed loop through "
        "the motion configuration the runs were flown with.",
    )
    ide.add_argument(
        "csv",
        metavar="RUN_CSV",
        nargs="+",
        help="t,ft,fd,e,u,theta[,theta_felt] (rad); several: repetitions of one condition "
        "(the same t, ft and fd, as `pilot run --runs N --out` writes them), averaged at the "
        "forcing functions' lines as the thesis averaged its five (§6.3.4)",
    )
    ide.add_argument(
        "--config",
        default=None,
        help="motion configuration the run was flown with (name or twin-config/1 file; the "
        "configuration overrides change it): the fit models the loop through it; checked "
        "against the run's theta_felt. Default: the built-in one theta_felt follows (refused "
        "if none is within 5 %%), or condition-1 if the run has no theta_felt",
    )
    ide.add_argument(
        "--continuous-loop",
        action="store_true",
        help="the recorded loop did not hold u over each sample (default: it did, as the "
        "twin's and a digital simulator's do; the MLE models that zero-order hold)",
    )
    ide.add_argument(
        "--intervals",
        action="store_true",
        help="also each parameter's likelihood-ratio interval (2 sd) from the profile "
        "likelihood: honest where the Cramer-Rao bound is not (typically 5-35 s more)",
    )
    ide.set_defaults(func=_cmd_identify)
    mc = cmds.add_parser(
        "montecarlo",
        parents=[
            common.seed_parent("seed of the runs"),
            common.json_parent(),
            common.quiet_parent(),
            common.scheduler_parent(),
        ],
        help="Chapter 2 Monte-Carlo: FC versus ARX (§2.5)",
        description="Chapter 2's Monte-Carlo study (§2.5): closed-loop runs identified with FC "
        "and ARX, the spread of each at the forcing functions' lines, and ARX's analytic "
        "standard deviation (Eq 2.16) against the spread; with --fit-runs, pilot-model fits "
        "too.",
    )
    mc.add_argument("--runs", type=MC_RUNS, default=1000,
                    help=f"closed-loop runs ({MC_RUNS.span}; default 1000)")  # fmt: skip
    mc.add_argument("--fit-runs", type=FIT_RUNS, default=0,
                    help=f"pilot-model fits per batch of {MC_BATCH} runs ({FIT_RUNS.span}; "
                    "default 0)")  # fmt: skip
    mc.set_defaults(func=_cmd_montecarlo)
    lead = cmds.add_parser(
        "lead",
        parents=[common.overrides_parent(imu=False), common.json_parent()],
        help="vestibular lead through a configuration (§7.4)",
        description="The vestibular lead through a configuration (§7.4): for the semicircular "
        "canals and the otoliths, the lowest platform-filter break frequency (no delay) and the "
        "largest delay (no filter) at which the lead channel lags an integrator by at most "
        "--margin-deg over 0.06-2.8 Hz, and whether this configuration meets the criterion.",
    )
    lead.add_argument("config", metavar="CONFIG", help=config_help())
    lead.add_argument(
        "--margin-deg",
        type=MARGIN_DEG,
        default=45.0,
        help=f"allowed lag behind an integrator over 0.06-2.8 Hz, deg ({MARGIN_DEG.span}; "
        "default 45)",
    )
    lead.set_defaults(func=_cmd_lead)


def _cmd_run(args: argparse.Namespace) -> int:
    from twin.lifecycle import check_output_file
    from twin.ownership import check_replace, kind_of
    from twin.pilot.experiment import pitch_remnant_scale
    from twin.pilot.forcing import pitch_task
    from twin.pilot.pitch import PitchPilot, open_loops, simulate_pitch, variance_decomposition
    from twin.pilot.records import repetition_paths, stale_repetitions, write_pilot_runs

    if args.out:  # every file the runs will go to, before the work
        for path in repetition_paths(args.out, args.runs):
            check_replace(check_output_file(path), kind_of(path))
    cfg = common.configured(args.config, args)
    pilot = PitchPilot()
    progress = common.progress(args)
    if args.remnant:
        progress(f"scaling the remnant to {args.remnant:g} of the control power")
    scale = pitch_remnant_scale(pilot, args.remnant, args.seed) if args.remnant else 0.0
    r = simulate_pitch(pilot, cfg, args.runs, args.seed, scale, model=args.model,
                       progress=progress)  # fmt: skip
    fd, ft = pitch_task()
    ol = open_loops(pilot, cfg)
    out = {
        "config": cfg.to_meta(),
        "runs": args.runs,
        "variance_deg2": {
            n: {k: v * DEG2 for k, v in variance_decomposition(getattr(r, n), fd, ft).items()}
            for n in ("e", "u", "theta")
        },
        "open_loops": ol.__dict__,
    }
    if args.out:
        written = write_pilot_runs(args.out, {"t": r.t, "ft": r.ft, "fd": r.fd, "e": r.e,
                                              "u": r.u, "theta": r.theta,
                                              "theta_felt": r.theta_felt})  # fmt: skip
        if len(written) > 1:
            progress(f"{len(written)} runs written: {written[0]} ... {written[-1]}")
        older = stale_repetitions(args.out, written)
        if older:
            verb = "are" if older[1:] else "is"
            print(f"note: {', '.join(map(str, older))} beside them {verb} from an earlier run, "
                  "not this one", file=sys.stderr)  # fmt: skip
    if args.rrd:
        from twin.record.pilot import record_pilot

        progress(f"recording {args.rrd}")
        record_pilot(args.rrd, r, pilot)
    if args.json:
        print(json.dumps(out, indent=2))
    else:
        print(f"pitch task through {cfg.name} ({args.runs} run(s), {args.model} platform)")
        for n, parts in out["variance_deg2"].items():
            print(f"  var({n}) " + ", ".join(f"{k} {v:.3f}" for k, v in parts.items()) + " deg^2")
        print(
            f"  the pilot model's loops through {cfg.name} (predicted, not measured from the "
            f"runs): disturbance crossover {ol.crossover_d:.2f} rad/s, phase margin "
            f"{ol.phase_margin_d:.1f} deg; target {ol.crossover_t:.2f} rad/s, "
            f"{ol.phase_margin_t:.1f} deg; felt motion's phase against the attitude at the "
            f"disturbance crossover {ol.motion_lead_phase_deg:+.1f} deg (negative: behind)"
        )
    return 0


def _adaptation_options(parser: argparse.ArgumentParser, when: str = "") -> None:
    """Add the options of what a pilot adapts (``pilot adapt``, ``pilot experiment``).

    ``when`` ends their help where they need another option (``pilot experiment``'s
    ``--pilot adaptive``).
    """
    parser.add_argument(
        "--fixed-neuromuscular",
        action="store_true",
        help="adapt only the equalisation (K_v, t_lead, t_lag, K_m) and keep the pilot's "
        "neuromuscular system (omega_nm, zeta_nm), as a pilot model with fixed limitations" + when,
    )
    parser.add_argument(
        "--adapt-visual-delay",
        action="store_true",
        help="also adapt the visual delay tau_v, traded against the visual remnant (a "
        "speed-accuracy trade-off, twin.pilot.adapt.visual_noise_ratio; an assumption, not "
        "the thesis')" + when,
    )


def _adapted(args: argparse.Namespace) -> tuple[str, ...]:
    from twin.pilot.adapt import ADAPTED, EQUALISATION, SPEED_ACCURACY

    base = EQUALISATION if args.fixed_neuromuscular else ADAPTED
    return (*base, *SPEED_ACCURACY) if args.adapt_visual_delay else base


def _cmd_adapt(args: argparse.Namespace) -> int:
    from twin.chain.config import motion_system
    from twin.pilot.adapt import CONTROL_WEIGHT, adapt

    with common.options_named({"control weight r": "--weight (the control weight r)"}):
        a = adapt(motion_system(args.config),
                  weight=CONTROL_WEIGHT if args.weight is None else args.weight,
                  adapted=_adapted(args))  # fmt: skip
    print(json.dumps(a.to_dict(), indent=2) if args.json else a.format())
    return 0


def _cmd_experiment(args: argparse.Namespace) -> int:
    from twin.errors import UsageError
    from twin.pilot.experiment import run_experiment

    for flag, given in (("--fixed-neuromuscular", args.fixed_neuromuscular),
                        ("--adapt-visual-delay", args.adapt_visual_delay)):  # fmt: skip
        if given and args.pilot != "adaptive":
            raise UsageError(f"{flag} chooses what adaptive subjects adapt: give it with "
                             "--pilot adaptive")  # fmt: skip
    if args.subjects is not None and args.pilot != "adaptive":
        raise UsageError("--subjects counts adaptive subjects; the fixed pilot is one model "
                         "(--runs sets its runs per condition): give it with --pilot "
                         "adaptive")  # fmt: skip
    if args.subjects is None:
        args.subjects = DEFAULT_SUBJECTS
    if args.runs is not None and args.pilot == "adaptive":
        raise UsageError("--runs sets the fixed pilot's runs per condition; adaptive subjects "
                         "fly five repetitions per condition, as the thesis' participants "
                         "did")  # fmt: skip
    if args.feedthrough and not args.identify:
        raise UsageError("--feedthrough gives the subjects a path the MLE is to meet: give it "
                         "with --identify")  # fmt: skip
    if args.identify and args.pilot != "adaptive":
        raise UsageError("--identify measures the pilot model of adaptive subjects: give it "
                         "with --pilot adaptive")  # fmt: skip
    for flag, value in (("--motion-spread", args.motion_spread),
                        ("--visual-delay-spread", args.visual_delay_spread)):  # fmt: skip
        if value is not None and args.pilot != "adaptive":
            raise UsageError(f"{flag} sets how adaptive subjects differ: give it with "
                             "--pilot adaptive")  # fmt: skip
    if args.pilot == "adaptive":  # before any worker starts
        from twin.pilot.identified import check_feedthrough
        from twin.pilot.population import checked_settings
        from twin.pilot.spread import Spread

        given = {"motion": args.motion_spread, "visual_delay": args.visual_delay_spread}
        with common.options_named(OPTIONS):
            check_feedthrough(args.feedthrough)
            args.spread = Spread(**{k: v for k, v in given.items() if v is not None})
            checked_settings(_adapted(args), 0.0, args.spread)
    if args.populations is not None:
        if args.pilot != "adaptive":
            raise UsageError("--populations counts populations of adaptive subjects: give it "
                             "with --pilot adaptive")  # fmt: skip
        if args.populations > 1:
            return _replication(args)
    if args.pilot == "adaptive":
        from twin.pilot.identified import identified_population
        from twin.pilot.population import run_population

        with common.engine(args) as engine, common.options_named(OPTIONS):
            if args.identify:
                p = identified_population(args.subjects, args.seed, common.progress(args),
                                          engine, _adapted(args), feedthrough=args.feedthrough,
                                          spread=args.spread)  # fmt: skip
            else:
                p = run_population(args.subjects, args.seed, common.progress(args), engine,
                                   _adapted(args), spread=args.spread)  # fmt: skip
        if args.plot:
            p.plot(path=args.plot)
            plot = Path(args.plot)
            p.plot_conditions(str(plot.with_name(f"{plot.stem}-conditions.png")))
        print(json.dumps(p.to_dict(), indent=2) if args.json else p.format_table())
        return 0
    with common.engine(args) as engine:
        runs = 5 if args.runs is None else args.runs
        r = run_experiment(runs=runs, seed=args.seed, progress=common.progress(args), fit=True,
                           scheduler=engine)  # fmt: skip
    if args.plot:
        r.plot(path=args.plot)
    if args.json:
        print(json.dumps(r.to_dict(), indent=2))
    else:
        print(r.format_table())
    return 0


def _replication(args: argparse.Namespace) -> int:
    from twin.pilot.design import MIN_POOL, design
    from twin.pilot.replication import run_populations

    identified = args.feedthrough if args.identify else None
    with common.engine(args) as engine, common.options_named(OPTIONS):
        rep, results = run_populations(args.populations, args.subjects, args.seed,
                                       common.progress(args), engine, _adapted(args),
                                       identified=identified, spread=args.spread)  # fmt: skip
    pooled = args.populations * args.subjects
    plan = design(results) if pooled >= MIN_POOL else None
    if args.plot:
        rep.plot(path=args.plot)
        if plan is not None:
            plot = Path(args.plot)
            plan.plot(path=str(plot.with_name(f"{plot.stem}-subjects.png")))
    if args.json:  # the summary, and each population's ANOVA as a single one prints it
        per = [{"seed": r.seed, "anova": r.anova, "agreement": r.agreement()} for r in results]
        for entry, r in zip(per, results, strict=True):
            if r.identified is not None:  # each fit's goodness of fit: 5, 50, 95 %
                chi = [row["chi2_per_dof"] for row in r.rows]
                entry["chi2_per_dof_5_50_95"] = [float(q) for q in np.percentile(chi, [5, 50, 95])]
        out = {**rep.to_dict(), "per_population": per,
               "design": None if plan is None else plan.to_dict()}  # fmt: skip
        print(json.dumps(out, indent=2))
    else:
        print(rep.format_table())
        print()
        print(plan.format_table() if plan is not None else
              f"(no design of experiments: it pools at least {MIN_POOL} subjects; these "
              f"populations have {pooled})")  # fmt: skip
    return 0


def _pilot_window(path: str) -> tuple[str, dict, dict, float]:
    """Read a twin-pilot/1 run; return its name, columns, last 81.92 s and rate [Hz].

    Raises
    ------
    SignalError
        Naming the file: shorter than the window, or without excitation in it.

    """
    from twin.errors import SignalError
    from twin.pilot.forcing import MEASUREMENT_S
    from twin.pilot.records import read_pilot_csv

    d = read_pilot_csv(path)
    rate = float(d["rate_hz"])
    n = round(MEASUREMENT_S * rate)
    if d["t"].size < n:
        raise SignalError(
            f"{path}: needs at least {MEASUREMENT_S} s of data ({n} samples at {rate:g} Hz); "
            f"has {d['t'].size} samples"
        )
    w = {k: v[-n:] for k, v in d.items() if k != "rate_hz"}
    felt = "theta_felt" if "theta_felt" in w else "theta"
    flat = [k for k in ("ft", "fd", "e", "u", felt) if np.ptp(w[k]) == 0]
    if flat:
        raise SignalError(
            f"{path}: the run carries no excitation: {', '.join(flat)} constant over the "
            f"last {MEASUREMENT_S} s (a tracking run has the Table 6.2 forcing functions in ft "
            "and fd, the pilot's e and u, and the motion the pilot felt)"
        )
    return path, d, w, rate


def _cmd_identify(args: argparse.Namespace) -> int:
    from twin.errors import SignalError, UsageError
    from twin.pilot.arx import ARX_RATE_HZ, decimate, select_orders
    from twin.pilot.fc import fc_estimate
    from twin.pilot.felt_motion import felt_mismatch, match_motion
    from twin.pilot.forcing import pitch_task
    from twin.pilot.mle import LOWER, PARAMETERS, UPPER, fit_pitch_pilot, fit_text

    overridden = common.overrides_given(args)
    if overridden and args.config is None:
        raise UsageError(f"{', '.join(overridden)} {'change' if overridden[1:] else 'changes'} "
                         "a configuration: give it with --config")  # fmt: skip
    given = None if args.config is None else common.configured(args.config, args)
    seen: dict[Path, str] = {}
    for path in args.csv:
        resolved = Path(path).resolve()
        if resolved in seen:
            again = "given twice" if seen[resolved] == path else f"{seen[resolved]} again"
            raise UsageError(f"{path} is {again}: give each repetition once")
        seen[resolved] = path
    runs = [_pilot_window(path) for path in args.csv]
    name, d, w, rate = runs[0]
    for other, od, ow, orate in runs[1:]:
        if set(od) != set(d):
            cols = [",".join(k for k in x if k != "rate_hz") for x in (od, d)]
            raise SignalError(f"{other}: columns {cols[0]}; {name} has {cols[1]}: repetitions "
                              "must have the same columns")  # fmt: skip
        if not np.isclose(orate, rate, rtol=1e-9) or ow["t"].size != w["t"].size:
            raise SignalError(f"{other}: {orate:g} Hz, {ow['t'].size} samples in the window; "
                              f"{name} has {rate:g} Hz, {w['t'].size}: repetitions must share "
                              "the time grid")  # fmt: skip
        differ = [k for k in ("ft", "fd") if not np.allclose(ow[k], w[k], rtol=1e-6, atol=1e-9)]
        if differ:
            verb = "differ" if differ[1:] else "differs"
            raise SignalError(f"{other}: {' and '.join(differ)} {verb} from {name}'s: "
                              "repetitions must share the forcing functions (the thesis' five "
                              "runs per condition did)")  # fmt: skip
        if np.array_equal(ow["u"], w["u"]):
            raise SignalError(f"{other}: u is {name}'s, sample for sample: the same run twice "
                              "is not a repetition")  # fmt: skip
    label = name if len(runs) == 1 else f"{name} and {len(runs) - 1} more"
    try:
        motion = match_motion(d, given)
    except SignalError as e:
        raise SignalError(f"{name}: {e}") from None
    cfg = motion.config
    if motion.mismatch is not None:  # every repetition felt the motion system the first did
        for other, od, _, _ in runs[1:]:
            off = felt_mismatch(od["theta"], od["theta_felt"], rate, cfg)
            if off > max(2 * motion.mismatch, motion.mismatch + 0.01):
                raise SignalError(
                    f"{other}: theta_felt differs from {cfg.name}'s response to theta by "
                    f"{off:.1%} rms, {name}'s by {motion.mismatch:.1%}: repetitions must be "
                    "flown through one motion system"
                )
    felt_key = "theta_felt" if "theta_felt" in w else "theta"
    # the repetitions' mean: FC and ARX of the averaged run (linear: the lines' average)
    mean = {k: np.mean([r[2][k] for r in runs], axis=0) for k in ("e", "u", felt_key)}
    u_runs = np.array([r[2]["u"] for r in runs]) if len(runs) > 1 else w["u"]
    fd, ft = pitch_task()
    try:  # the analyses' refusals name the file they refuse
        fc = fc_estimate(mean["e"][None], mean["u"][None], mean[felt_key][None], fd, ft,
                         w["fd"], w["ft"])  # fmt: skip
        arx = select_orders(*(decimate(mean[k], rate, ARX_RATE_HZ) for k in ("u", "e", felt_key)),
                            rate_hz=ARX_RATE_HZ)  # fmt: skip
        h_pe, h_px = arx.responses(fc.omega_rad_s)
        mle = fit_pitch_pilot(
            w["ft"],
            w["fd"],
            u_runs,
            cfg,
            rate,
            hold=not args.continuous_loop,
            progress=common.progress(args),
            intervals=args.intervals,
        )
    except SignalError as e:
        raise SignalError(f"{label}: {e}") from None
    out = {
        "runs": [str(r[0]) for r in runs],
        "omega_rad_s": fc.omega_rad_s.tolist(),
        "fc": {
            "h_pe_gain": np.abs(fc.h_pe[0]).tolist(),
            "h_pe_phase_deg": np.degrees(np.angle(fc.h_pe[0])).tolist(),
            "h_ptheta_gain": np.abs(fc.h_px[0]).tolist(),
            "h_ptheta_phase_deg": np.degrees(np.angle(fc.h_px[0])).tolist(),
        },
        "arx": {
            "orders": arx.orders.__dict__,
            "h_pe_gain": np.abs(h_pe).tolist(),
            "h_ptheta_gain": np.abs(h_px).tolist(),
        },
        "mle": mle.to_dict(),
        "motion": motion.to_dict(),
    }
    if args.json:
        print(json.dumps(out, indent=2))
    else:
        p = mle.pilot
        loop = "continuous" if args.continuous_loop else f"held over each {1e3 / rate:g} ms"
        reps = "" if len(runs) == 1 else f", {len(runs)} repetitions averaged"
        print(
            f"{label}: MLE fit (Eq 6.5-6.7, closed loop through {cfg.name}'s pitch "
            f"response, u {loop}{reps}), VAF {mle.vaf_percent:.1f} %"
        )
        print("  " + motion.format())
        print("  " + fit_text(mle.evidence["fit"]))
        own_sd = mle.crlb_at_estimate or mle.crlb
        for name, sd in mle.crlb.items():
            value = getattr(p, name)
            span = ""
            if mle.intervals is not None:
                span = "  2-sd interval " + _interval_text(name, *mle.intervals[name])
            if name in mle.on_range_bound:
                sd_text = "at the end of its range: no sd"
            elif not np.isfinite(sd):  # JSON: null
                sd_text = "no finite sd: the data do not pin it down here"
            elif own_sd[name] == sd:
                sd_text = f"CRLB sd {sd:.4f}"
            else:
                sd_text = (f"sd {sd:.4f}: the CRLB here, {own_sd[name]:.4f}, widened for the "
                           "fits below")  # fmt: skip
            flag = ""
            if name in mle.unidentifiable:
                why = ("at the end of its range" if name in mle.on_range_bound else
                       "sd above a third of its value" if not sd < abs(value) / 3 else
                       "its likelihood-ratio interval reaches far beyond 2 sd")  # fmt: skip
                flag = f"  not identifiable ({why})"
            print(f"  {name:9s} {value:8.4f}  ({sd_text}){span}{flag}")

        def moved(other, skip: str = "") -> str:
            far = [f"{n} {getattr(other, n):.4f}" for n in own_sd
                   if n != skip and abs(getattr(other, n) - getattr(p, n)) > own_sd[n]]  # fmt: skip
            return ", ".join(far) or "every parameter within one CRLB of the estimate"

        def end_of(name: str, at: float) -> str:
            side = "lower" if at == LOWER[PARAMETERS.index(name)] else "upper"
            return f"the {side} end of its range, {at:g}"

        why = mle.evidence.get("competing_minima", [])
        for other, ev in zip(mle.competing, why, strict=True):
            print(f"  another minimum the data do not rule out (chi-square +{ev['delta_chi2']:.2f} "
                  f"over the best, Vuong's z {ev['vuong_z']:.2f}; it competes within 3.84 or "
                  f"below z 1.96): {moved(other)}")  # fmt: skip
        ruled = mle.evidence.get("ruled_out_minima", [])
        if ruled:
            rises = ", ".join(f"+{ev['delta_chi2']:.1f}" for ev in ruled[:4])
            print(f"  {len(ruled)} other minim{'um' if len(ruled) == 1 else 'a'} the data rule "
                  f"out (chi-square {rises}{', ...' if len(ruled) > 4 else ''}): a bound is "
                  "widened for the selection where its estimate is near the limit at which "
                  "one would compete again (twin.pilot.selection)")  # fmt: skip
        for name, other in mle.on_range_bound.items():
            at, k = getattr(other, name), PARAMETERS.index(name)
            end, way = (LOWER[k], "up") if at > getattr(p, name) else (UPPER[k], "down")
            print(f"  {name} estimated at {end_of(name, end)}: the data allow it {way} to "
                  f"{at:.4f} (chi-square +3.84, the rest refitted); the fit there: "
                  f"{moved(other, name)}")  # fmt: skip
        for name, other in mle.range_end.items():
            rise = mle.evidence["range_end"][name]
            print(f"  {name} may be at {end_of(name, getattr(other, name))}: held there, the "
                  f"rest refitted, the chi-square rises by {rise:.2f} (< 3.84); the fit there: "
                  f"{moved(other, name)}")  # fmt: skip
        if mle.competing or mle.on_range_bound or mle.range_end:
            print("  (the fits above list the parameters more than one CRLB from the estimate)")
        print(
            f"  ARX structure {arx.orders}; FC and ARX responses at "
            f"{fc.omega_rad_s.size} lines in --json"
        )
    return 0


def _interval_text(name: str, low: float, high: float) -> str:
    """``[low, high]``, saying so where an end is the fit's range, not the data's bound."""
    from twin.pilot.mle import LOWER, PARAMETERS, UPPER

    k = PARAMETERS.index(name)
    open_ends = [side for side, hit in (("below", low <= LOWER[k] and LOWER[k] > 0),
                                        ("above", high >= UPPER[k])) if hit]  # fmt: skip
    return f"[{low:.4f}, {high:.4f}]" + (f" (open {' and '.join(open_ends)})" if open_ends else "")


def _cmd_montecarlo(args: argparse.Namespace) -> int:
    from twin.pilot.montecarlo import monte_carlo

    with common.engine(args) as engine:
        r = monte_carlo(args.runs, args.seed, fit_runs=args.fit_runs,
                        progress=common.progress(args), scheduler=engine)  # fmt: skip
    out = r.to_dict()
    if args.json:
        print(json.dumps(out, indent=2))
    else:
        print(f"Chapter 2 Monte-Carlo: {r.runs} runs, ARX {r.orders}")
        for resp in ("pe", "px"):
            ratio = r.sample_std_mag("fc", resp) / r.sample_std_mag("arx", resp)
            print(
                f"  H_{resp}: FC std / ARX std at the 24 lines: {ratio.min():.1f}-{ratio.max():.1f}"
            )
            for label, std in (
                ("Eq 2.16", r.arx_std_mag),
                ("P through exact H", r.arx_sampled_std_mag),
            ):
                q = std[resp] / r.sample_std_mag("arx", resp)
                span = f"{q.min():.2f}-{q.max():.2f}"
                print(f"  H_{resp}: ARX analytic ({label}) / Monte-Carlo std: {span}")
        if args.fit_runs:
            for m, errs in out["parameter_errors"].items():
                print(
                    f"  {m:3s} mean |error|: " + ", ".join(f"{k} {v:.3g}" for k, v in errs.items())
                )
    return 0


def _cmd_lead(args: argparse.Namespace) -> int:
    from twin.pilot.lead import SENSORS, analyse_lead

    cfg = common.configured(args.config, args)
    with common.options_named({"margin_deg": "--margin-deg"}):
        res = [analyse_lead(cfg, s, args.margin_deg) for s in SENSORS]
    if args.json:
        from twin.jsonable import plain

        # no threshold: null (strict JSON has no NaN)
        print(json.dumps(plain([r.__dict__ for r in res]), indent=2))
    else:
        print(
            f"lead channel through {cfg.name} (criterion: at most {args.margin_deg:g} deg "
            "behind an integrator over 0.06-2.8 Hz)"
        )
        for r in res:
            if np.isfinite(r.break_hz_threshold) and np.isfinite(r.delay_threshold_s):
                limits = (f"thresholds {r.break_hz_threshold:.2f} Hz, "
                          f"{r.delay_threshold_s * 1e3:.0f} ms")  # fmt: skip
            else:
                limits = "no threshold: the sensor alone lags more than the criterion allows"
            print(
                f"  {r.sensor:8s}: {limits}; this configuration: worst phase "
                f"{r.config_worst_phase_deg:.1f} deg -> {'meets' if r.config_meets else 'fails'}"
            )
    return 0
