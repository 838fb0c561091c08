"""``twin pilot ...``: pilots in the loop from the command line (thesis Ch 2, 6, 7)."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from twin.cli import common
from twin.pilot.studies import spread as spreads

DEG2 = (180 / np.pi) ** 2
#: Most runs of ``pilot run`` and per condition of ``pilot experiment fixed``
#: (:data:`twin.pilot.models.pitch.MAX_RUNS`, not imported so that the parser stays light).
MAX_RUNS = 1000
#: Most simulated subjects of ``pilot experiment subjects``.
MAX_SUBJECTS = 1000
#: Subjects of ``pilot experiment subjects`` by default: the thesis' participants.
DEFAULT_SUBJECTS = 9
#: The library's names in ``pilot experiment subjects``' errors -> the options typed.
OPTIONS = {
    "feedthrough": "--feedthrough",
    "the motion perception's spread": "--motion-spread (the motion perception's spread)",
    "the visual delay's spread": "--visual-delay-spread (the visual delay's spread)",
}
#: Most populations of ``pilot experiment subjects --populations``.
MAX_POPULATIONS = 1000
#: Runs per task of ``pilot montecarlo``
#: (:func:`twin.pilot.studies.montecarlo.monte_carlo`'s batch).
MC_BATCH = 500
#: Most runs of ``pilot montecarlo`` (:data:`twin.pilot.studies.montecarlo.MAX_RUNS`, not imported
#: so that the parser stays light).
MAX_MC_RUNS = 100_000_000
#: Largest ``--feedthrough`` (:data:`twin.pilot.studies.identified.MAX_FEEDTHROUGH`, not imported).
MAX_FEEDTHROUGH = 1.0
#: Largest ``--weight``: the control weight r of :func:`twin.pilot.models.adapt.adapt` (its default
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
#: ``--margin-deg``: as :func:`twin.pilot.models.lead.analyse_lead` allows.
MARGIN_DEG = common.number(0, 90)


def add_parser(sub: argparse._SubParsersAction, parser_class: type) -> None:
    """Add ``twin pilot`` and its subcommands to the ``twin`` parser."""
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
    common.add_config(run)
    run.add_argument("--runs", type=RUNS, default=1,
                     help=f"runs with fresh remnant ({RUNS.span}; default 1)")  # fmt: skip
    run.add_argument(
        "--remnant",
        type=REMNANT,
        default=0.15,
        help=f"remnant power over control power ({REMNANT.span}; default 0.15; 0: none)",
    )
    run.set_defaults(func=_cmd_run)
    _add_experiment(cmds, parser_class)
    ada = cmds.add_parser(
        "adapt",
        parents=[common.json_parent()],
        help="the pitch-task pilot's equalisation and neuromuscular tuning adapted to a motion "
        "configuration (minimises var(e) + r var(u))",
        description="Adapt the pitch-task pilot to a motion configuration: the equalisation "
        "(K_v, t_lead, t_lag, K_m) and neuromuscular tuning (omega_nm, zeta_nm) that minimise "
        "var(e) + r var(u) through it, as a subject of `pilot experiment subjects` "
        "adapts to each condition.",
    )
    common.add_config(ada)
    ada.add_argument(
        "--weight",
        type=WEIGHT,
        help=f"r of the cost ({WEIGHT.span}; default: twin.pilot.models.adapt's)",
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
        metavar=common.CONFIG,
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
    common.add_config(lead)
    lead.add_argument(
        "--margin-deg",
        type=MARGIN_DEG,
        default=45.0,
        help=f"allowed lag behind an integrator over 0.06-2.8 Hz, deg ({MARGIN_DEG.span}; "
        "default 45)",
    )
    lead.set_defaults(func=_cmd_lead)


def _add_experiment(cmds: argparse._SubParsersAction, parser_class: type) -> None:
    """Add ``twin pilot experiment fixed`` and ``twin pilot experiment subjects``."""
    exp = cmds.add_parser(
        "experiment",
        help="the eight Table 6.3 conditions, flown by a fixed pilot model (fixed) or by "
        "simulated subjects with the thesis' ANOVA (subjects)",
        description="Fly the eight conditions of Table 6.3 (their filter, delay and noise are the "
        "experiment's factors: no configuration overrides): `fixed` flies one fixed pilot model "
        "in every condition; `subjects` flies simulated subjects who adapt their equalisation "
        "and neuromuscular tuning to each motion system, analysed with the thesis' "
        "repeated-measures ANOVA.",
    )
    kinds = exp.add_subparsers(dest="experiment", required=True, parser_class=parser_class)
    fixed = kinds.add_parser(
        "fixed",
        parents=[
            common.seed_parent("seed of the runs"),
            common.json_parent(),
            common.quiet_parent(),
            common.scheduler_parent(),
        ],
        help="one fixed pilot model in every condition (Fig 6.5-6.9)",
        description="Fly the eight conditions of Table 6.3 with one fixed pilot model (Eq "
        "6.5-6.7) in every condition and print the measures per condition (Fig 6.5-6.9).",
    )
    fixed.add_argument("--runs", type=RUNS, default=5,
                       help=f"runs per condition ({RUNS.span}; default 5)")  # fmt: skip
    fixed.add_argument("--plot", metavar="PNG", type=common.figure_file,
                       help="save the measures per condition as Fig 6.5-6.9")  # fmt: skip
    fixed.set_defaults(func=_cmd_fixed)
    subj = kinds.add_parser(
        "subjects",
        parents=[
            common.seed_parent("seed of the subjects (the first population's)"),
            common.json_parent(),
            common.quiet_parent(),
            common.scheduler_parent(),
        ],
        help="simulated subjects who adapt to each motion system, with the thesis' ANOVA",
        description="Fly the eight conditions of Table 6.3 with simulated subjects (each "
        "flies the thesis' five repetitions per condition) who adapt their equalisation and "
        "neuromuscular tuning to each motion system, and analyse their measures with the "
        "thesis' repeated-measures ANOVA; with --populations, over seeded populations.",
    )
    subj.add_argument(
        "--subjects",
        type=SUBJECTS,
        default=DEFAULT_SUBJECTS,
        help=f"simulated subjects ({SUBJECTS.span}; default {DEFAULT_SUBJECTS}, the thesis' "
        "participants)",
    )
    _adaptation_options(subj)
    subj.add_argument(
        "--identify",
        action="store_true",
        help="measure the pilot model as the thesis did, each subject's five repetitions "
        "flown in the time domain and Eq 6.5-6.7 fitted by the MLE to their average "
        "(twin.pilot.studies.identified; tau_m and tau_v in the ANOVA, each fit's goodness of "
        "fit in --json's rows; about 12 s a subject on two cores; with --populations, over "
        "populations)",
    )
    subj.add_argument(
        "--feedthrough",
        type=FEEDTHROUGH,
        default=0.0,
        metavar="R",
        help="with --identify: each subject also has a passive path from the motion to the "
        f"stick, R ({FEEDTHROUGH.span}) of its condition-1 motion response at 3 rad/s "
        "(twin.pilot.models.pitch.Feedthrough; an assumption: only the simulated subjects have "
        "it, no fit models it; default 0: none; about 5x slower)",
    )
    subj.add_argument(
        "--motion-spread",
        type=MOTION_SPREAD,
        metavar="SD",
        help="how much the subjects differ in perceiving motion, the log-normal sd of the felt "
        "rate's observation noise relative to the visual one "
        f"({MOTION_SPREAD.span}; default {spreads.MOTION_NOISE_SD:g}, from profiles "
        "against Tables 6.4-6.7, docs; 0: every subject perceives motion as well as vision; "
        "with --visual-delay-spread 0.03 the subjects of earlier versions)",
    )
    subj.add_argument(
        "--visual-delay-spread",
        type=VISUAL_DELAY_SPREAD,
        metavar="S",
        help="how much the subjects differ in visual delay, its sd in s around 0.30 s "
        f"({VISUAL_DELAY_SPREAD.span}; default {spreads.VISUAL_DELAY_SD:g}, from profiles "
        "against Tables 6.4-6.7, docs; 0: every subject has the mean delay)",
    )
    subj.add_argument(
        "--populations",
        type=POPULATIONS,
        default=1,
        help=f"seeded populations ({POPULATIONS.span}; seeds SEED, SEED + 1, ...); from 2 on, "
        "each effect's standardised size over populations (median, 5-95 %%) beside the "
        "thesis', and whether the thesis is a plausible draw of them; with 40 subjects or "
        "more in all, how many subjects an experiment needs to find each effect, for "
        "experiments of up to half the subjects flown, at most 60 (twin.pilot.studies.design) "
        "(default 1; 20 for a distribution: about 13 min on two cores)",
    )
    subj.add_argument(
        "--plot",
        metavar="PNG",
        type=common.figure_file,
        help="save the ANOVA's effects beside the thesis' here, and the measures per condition "
        "over subjects in PNG's name + '-conditions.png'; with --populations 2 or more, the "
        "standardised effects over populations beside the thesis', and in PNG's name + "
        "'-subjects.png' how often an experiment of 2 to 60 subjects finds each filter effect",
    )
    subj.set_defaults(func=_cmd_subjects)


def _cmd_run(args: argparse.Namespace) -> int:
    from twin.core.lifecycle import check_output_file
    from twin.core.ownership import check_replace, kind_of
    from twin.pilot.models.forcing import pitch_task
    from twin.pilot.models.pitch import (
        PitchPilot,
        open_loops,
        simulate_pitch,
        variance_decomposition,
    )
    from twin.pilot.models.records import repetition_paths, stale_repetitions, write_pilot_runs
    from twin.pilot.studies.experiment import pitch_remnant_scale

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
        from twin.viz.record.pilot import record_pilot

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
    """Add the options of what a pilot adapts (``pilot adapt``, ``pilot experiment subjects``).

    ``when`` ends their help (what they apply to).
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
        "speed-accuracy trade-off, twin.pilot.models.adapt.visual_noise_ratio; an assumption, not "
        "the thesis')" + when,
    )


def _adapted(args: argparse.Namespace) -> tuple[str, ...]:
    from twin.pilot.models.adapt import ADAPTED, EQUALISATION, SPEED_ACCURACY

    base = EQUALISATION if args.fixed_neuromuscular else ADAPTED
    return (*base, *SPEED_ACCURACY) if args.adapt_visual_delay else base


def _cmd_adapt(args: argparse.Namespace) -> int:
    from twin.chain.config import motion_system
    from twin.pilot.models.adapt import CONTROL_WEIGHT, adapt

    with common.options_named({"control weight r": "--weight (the control weight r)"}):
        a = adapt(motion_system(args.config),
                  weight=CONTROL_WEIGHT if args.weight is None else args.weight,
                  adapted=_adapted(args))  # fmt: skip
    print(json.dumps(a.to_dict(), indent=2) if args.json else a.format())
    return 0


def _cmd_fixed(args: argparse.Namespace) -> int:
    from twin.pilot.studies.experiment import run_experiment

    with common.engine(args) as engine:
        r = run_experiment(runs=args.runs, seed=args.seed, progress=common.progress(args),
                           fit=True, scheduler=engine)  # fmt: skip
    if args.plot:
        r.plot(path=args.plot)
    print(json.dumps(r.to_dict(), indent=2) if args.json else r.format_table())
    return 0


def _cmd_subjects(args: argparse.Namespace) -> int:
    from twin.core.errors import UsageError
    from twin.pilot.studies.identified import check_feedthrough
    from twin.pilot.studies.population import checked_settings
    from twin.pilot.studies.spread import Spread

    if args.feedthrough and not args.identify:
        raise UsageError("--feedthrough gives the subjects a path the MLE is to meet: give it "
                         "with --identify")  # fmt: skip
    given = {"motion": args.motion_spread, "visual_delay": args.visual_delay_spread}
    with common.options_named(OPTIONS):  # before any worker starts
        check_feedthrough(args.feedthrough)
        args.spread = Spread(**{k: v for k, v in given.items() if v is not None})
        checked_settings(_adapted(args), 0.0, args.spread)
    if args.populations > 1:
        return _replication(args)
    from twin.pilot.studies.identified import identified_population
    from twin.pilot.studies.population import run_population

    with common.engine(args) as engine, common.options_named(OPTIONS):
        if args.identify:
            p = identified_population(args.subjects, args.seed, common.progress(args), engine,
                                      _adapted(args), feedthrough=args.feedthrough,
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


def _replication(args: argparse.Namespace) -> int:
    from twin.pilot.studies.design import MIN_POOL, design
    from twin.pilot.studies.replication import run_populations

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


def _cmd_identify(args: argparse.Namespace) -> int:
    from twin.core.errors import UsageError
    from twin.pilot.identification.identify_runs import identify

    overridden = common.overrides_given(args)
    if overridden and args.config is None:
        raise UsageError(f"{', '.join(overridden)} {'change' if overridden[1:] else 'changes'} "
                         "a configuration: give it with --config")  # fmt: skip
    given = None if args.config is None else common.configured(args.config, args)
    result = identify(args.csv, given, continuous_loop=args.continuous_loop,
                      intervals=args.intervals, progress=common.progress(args))  # fmt: skip
    print(json.dumps(result.to_dict(), indent=2) if args.json else result.format_text())
    return 0


def _cmd_montecarlo(args: argparse.Namespace) -> int:
    from twin.pilot.studies.montecarlo import monte_carlo

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
    from twin.pilot.models.lead import SENSORS, analyse_lead

    cfg = common.configured(args.config, args)
    with common.options_named({"margin_deg": "--margin-deg"}):
        res = [analyse_lead(cfg, s, args.margin_deg) for s in SENSORS]
    if args.json:
        from twin.core.jsonable import plain

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
