"""How often the diagnosis names a wrong cause when what is nominal varies too.

Draws (:mod:`twin.diagnose.hidden`, ``nuisance=True``, seeds not tuned): single hidden effects
(``DRAWS`` of each type the generator hides), pairs (``--pairs``, any pair the drawing rule
admits) and clean runs (``--clean``); each with an IMU 0.3-3 times as noisy as its data sheet
and the nominal's nuisances drawn (motion-noise level, the platform filter's break frequency,
the signals' amplitudes, the measurement window); both Table 5.2 runs recorded through the
truth, ``meta.json`` naming the nominal only, diagnosed as a user would
(:func:`twin.diagnose.diagnosis.diagnose`). Each diagnosis is judged
(:func:`twin.diagnose.hidden.judged`): right / ambiguous / wrong / none.

Printed: one line per draw; per effect type and per pair the counts; the rate of wrong
*single* names (a wrong cause presented as the finding, over the single-effect draws; target
<= 2 %); how many wrong draws had the truth within the naming margin all the same (the true
set's BIC improvement in the DOF's selection table within ``BIC_MARGIN`` of the named set's:
the runs could not tell them apart, but the report did not say so); and, of the wrong draws,
those whose first finding is a platform filter where only the nuisance moved the break (the
nuisance itself named: see the module docstring of :mod:`twin.diagnose.hidden` on how
detectable a few per cent of break frequency is).

With ``--design`` every draw whose first finding is ambiguous goes one step further, as a lab
would: ``twin design`` on its diagnosis (:func:`twin.diagnose.design.design_from`, the
default budget of 120 s), the designed run played through the same truth
(:func:`twin.diagnose.hidden.play`; its own seed, the draw's IMU) and the old runs and the new
one diagnosed together and judged again. Printed: how many of those draws are then named right
(the true cause, unambiguously; target >= 90 %), still ambiguous, wrong or none, and whether
the design expected to decide them.

Usage: ``python bench/ambiguity_rates.py [DRAWS] [FIRST_SEED] [--pairs N] [--clean N]
[--workers N] [--filter-spread X] [--design] [--only EARLIER_JSON] [--json PATH]`` (defaults
3, 0; pairs and clean 2 x DRAWS; 2 workers; the generator's +-10 % break spread; ``--only``:
of those draws, only the ones an earlier run's ``--json`` found ambiguous).
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # one BLAS thread per worker process (twin.core.threads)

import argparse  # noqa: E402
import json  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
import traceback  # noqa: E402
from collections import Counter, defaultdict  # noqa: E402
from concurrent.futures import ProcessPoolExecutor, as_completed  # noqa: E402
from dataclasses import replace  # noqa: E402
from pathlib import Path  # noqa: E402

from twin.chain.extensions import EFFECTS  # noqa: E402
from twin.diagnose.design import design_from  # noqa: E402
from twin.diagnose.diagnosis import Diagnosis, diagnose  # noqa: E402
from twin.diagnose.hidden import (  # noqa: E402
    DOFS,
    DRAWN,
    NUISANCE_RANGES,
    RELATIVE_TOLERANCE,
    TOLERANCE,
    VERDICTS,
    Hidden,
    NuisanceRanges,
    clean,
    draw,
    judged,
    play,
    record,
    truth_delta_bic,
    values_within_tolerance,
)
from twin.diagnose.report import write_report  # noqa: E402
from twin.diagnose.select import BIC_MARGIN  # noqa: E402

try:
    from tqdm import tqdm
except ImportError:  # pragma: no cover - progress is optional
    tqdm = None

#: Draws tried per seed (motion noise is detectable only with a quiet IMU or a large scale).
MAX_REDRAWS = 400
#: Seed offsets of the pair and clean draws (single effects: 1000 x the effect's index).
PAIR_SEEDS = 50_000
CLEAN_SEEDS = 90_000


def _designed(h: Hidden, old: list[Path], d: Diagnosis, work: Path) -> dict[str, object]:
    """Design the next run of an ambiguous diagnosis, play it through the truth, judge again."""
    write_report(d, work / "diagnosis", figures=False)
    plan = design_from(work / "diagnosis")
    # at the filter setting the design asks for, as a lab would record it: the truth's filter
    # (and any off-setting of it) scaled with the setting, the run's meta naming the setting
    new = play(plan.at_setting(h.truth), plan.setting or h.config, plan.signal,
               work / "designed", 7919 * h.seed + 3, imu=h.imu)  # fmt: skip
    again = diagnose([*old, new], seed=h.seed)
    top = [f for f in again.findings if f.extension.effect != "noise" or "noise" in h.effects]
    return {
        "verdict": judged(h, again),
        "values_within_tolerance": values_within_tolerance(h, again),
        "decides": plan.decides,
        "weakest": plan.best.weakest,
        "lines_hz": [float(f) for f in plan.signal.frequencies_hz],
        "filter_hz": plan.setting.filter_break_hz if plan.filter_changed else None,  # type: ignore[union-attr]
        "duration_s": plan.signal.commands.duration,
        "first": top[0].extension.describe() if top else None,
        "alternatives": [a.get("effects") for a in (top[0].evidence.get("alternatives") or [])]
        if top and top[0].ambiguous
        else [],
    }


def _job(
    kind: str, seed: int, ranges: NuisanceRanges, tmp: str, design: bool = False
) -> dict[str, object]:
    """Draw, record, diagnose and judge one case; return its row (an ``error`` on failure)."""
    row: dict[str, object] = {"kind": kind, "seed": seed}
    t0 = time.perf_counter()
    try:
        if kind == "clean":
            h = clean(seed, (0.3, 3.0), DOFS, nuisance=True, nuisance_ranges=ranges)
        elif kind == "pair":
            h = draw(seed, count=2, nuisance=True, nuisance_ranges=ranges)
        else:
            h = draw(seed, kind, max_redraws=MAX_REDRAWS, nuisance=True, nuisance_ranges=ranges)
        row["draw"] = h.describe()
        row["effects"] = sorted(h.effects)
        row["nuisance_break"] = h.nuisance.filter_break if h.nuisance else 1.0
        old = record(h, Path(tmp) / f"{kind}-{seed}")
        d = diagnose(old, seed=h.seed)
        verdict = judged(h, d)
        chain = [f for f in d.findings if f.extension.effect != "noise" or "noise" in h.effects]
        top = chain[0] if chain else None
        true_dbic, named_dbic = truth_delta_bic(h, d)
        row |= {
            "verdict": verdict,
            "values_within_tolerance": values_within_tolerance(h, d),
            "first": top.extension.describe() if top else None,
            "first_effect": top.extension.effect if top else None,
            "first_ambiguous": bool(top.ambiguous) if top else False,
            "alternatives": [a.get("effects") for a in (top.evidence.get("alternatives") or [])]
            if top
            else [],
            "findings": [f.extension.describe() for f in d.findings],
            "truth_delta_bic": true_dbic,
            "named_delta_bic": named_dbic,
            "truth_within_margin": (
                true_dbic is not None and h.effects != () and named_dbic - true_dbic < BIC_MARGIN
            ),
        }
        if design and top is not None and top.ambiguous:
            row["designed"] = _designed(h, old, d, Path(tmp) / f"{kind}-{seed}-design")
    except Exception as e:  # a failed draw is reported, the bench goes on
        row["error"] = f"{type(e).__name__}: {e}"
        row["traceback"] = traceback.format_exc(limit=3)
    row["seconds"] = time.perf_counter() - t0
    return row


def _jobs(draws: int, first: int, pairs: int, cleans: int) -> list[tuple[str, int]]:
    jobs = [(e, 1000 * list(EFFECTS).index(e) + first + i) for e in DRAWN for i in range(draws)]
    jobs += [("pair", PAIR_SEEDS + first + i) for i in range(pairs)]
    jobs += [("clean", CLEAN_SEEDS + first + i) for i in range(cleans)]
    return jobs


def _group(row: dict[str, object]) -> str:
    if row["kind"] == "pair" and "effects" in row:
        return " + ".join(row["effects"])  # type: ignore[arg-type]
    return str(row["kind"])


def _line(row: dict[str, object]) -> str:
    if "error" in row:
        return f"{row['kind']} seed {row['seed']}: ERROR {row['error']}"
    amb = " (ambiguous: " + "; ".join("+".join(a) for a in row["alternatives"]) + ")"  # type: ignore[union-attr]
    text = f"{row['verdict']:9s} {row['draw']} -> {row['first'] or 'nothing'}"
    text += amb if row["first_ambiguous"] else ""
    if row["verdict"] == "wrong" and row["truth_delta_bic"] is not None:
        text += (f" [truth dBIC {row['truth_delta_bic']:.1f} vs named "
                 f"{row['named_delta_bic']:.1f}]")  # fmt: skip
    des = row.get("designed")
    if des:
        at = f", filter at {des['filter_hz']:g} Hz" if des.get("filter_hz") else ""  # type: ignore[union-attr]
        text += f"\n          designed run {des['lines_hz']} Hz{at}: "  # type: ignore[index]
        text += f"{des['verdict']} -> {des['first']}"  # type: ignore[index]
        if des["alternatives"]:  # type: ignore[index]
            text += " (ambiguous: " + "; ".join("+".join(a) for a in des["alternatives"]) + ")"  # type: ignore[index]
    return text + f" ({row['seconds']:.0f} s)"


def report(rows: list[dict[str, object]]) -> dict[str, object]:
    """Print the counts per group and the rates; return them."""
    counts: dict[str, Counter] = defaultdict(Counter)
    for r in rows:
        counts[_group(r)][r.get("verdict", "error")] += 1
    print("\ncounts (right / ambiguous / wrong / none / error):")
    order = [*DRAWN, *sorted(k for k in counts if "+" in k), "clean"]
    for k in order:
        if k in counts:
            c = counts[k]
            print(f"  {k:32s} " + " / ".join(str(c[v]) for v in (*VERDICTS, "error")))
    done = [r for r in rows if "verdict" in r]
    singles = [r for r in done if r["kind"] in DRAWN]
    wrong_single = [r for r in singles if r["verdict"] == "wrong"]
    wrong = [r for r in done if r["verdict"] == "wrong" and r["kind"] != "clean"]
    within = [r for r in wrong if r["truth_within_margin"]]
    nuisance_filter = [
        r for r in done
        if r["verdict"] == "wrong" and r["first_effect"] == "platform_filter"
        and "platform_filter" not in r["effects"] and r["nuisance_break"] != 1.0  # type: ignore[operator]
    ]  # fmt: skip
    rate = len(wrong_single) / len(singles) if singles else float("nan")
    summary = {
        "counts": {k: dict(v) for k, v in counts.items()},
        "single_draws": len(singles),
        "wrong_single": len(wrong_single),
        "wrong_single_rate": rate,
        "wrong_with_truth_within_margin": len(within),
        "wrong_with_effects": len(wrong),
        "wrong_naming_the_nuisance_filter": len(nuisance_filter),
        "errors": sum(1 for r in rows if "error" in r),
    }
    print(f"\nwrong single names: {len(wrong_single)} of {len(singles)} single-effect draws "
          f"({100 * rate:.1f} %; target <= 2 %)")  # fmt: skip
    print(f"wrong with the truth within the margin (not reported): {len(within)} of "
          f"{len(wrong)} wrong draws with hidden effects")  # fmt: skip
    print(f"wrong draws whose first finding is the nuisance's platform filter: "
          f"{len(nuisance_filter)}")  # fmt: skip
    right = [r for r in done if r["verdict"] == "right" and r["effects"]]
    close = sum(1 for r in right if r.get("values_within_tolerance"))
    summary["right_values_within_tolerance"] = [close, len(right)]
    print(f"named right with every value within the tolerance ({TOLERANCE}, else "
          f"{100 * RELATIVE_TOLERANCE:g} %): {close} of {len(right)}")  # fmt: skip
    ambiguous = sum(1 for r in done if r["verdict"] == "ambiguous")
    print(f"ambiguous: {ambiguous} of {len(done)}; errors: {summary['errors']}")
    designed = [r["designed"] for r in done if "designed" in r]
    if designed:
        after = Counter(d["verdict"] for d in designed)  # type: ignore[index]
        expected = sum(1 for d in designed if d["decides"])  # type: ignore[index]
        rate = after["right"] / len(designed)
        close = sum(1 for d in designed
                    if d["verdict"] == "right" and d.get("values_within_tolerance"))  # type: ignore[index]  # fmt: skip
        summary |= {
            "designed": len(designed),
            "designed_counts": dict(after),
            "designed_right_rate": rate,
            "designed_expected_to_decide": expected,
            "designed_right_values_within_tolerance": close,
        }
        print(f"\nafter one designed run, of {len(designed)} draws whose first finding was "
              "ambiguous: " + " / ".join(f"{after[v]} {v}" for v in VERDICTS)
              + f"; named right {100 * rate:.0f} % (target >= 90 %); the design expected "
              f"to decide {expected}; named right with every value within the tolerance "
              f"{close}")  # fmt: skip
    return summary


def main() -> None:
    """Run the bench (see the module docstring)."""
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("draws", nargs="?", type=int, default=3, help="draws per single effect type")
    p.add_argument("first", nargs="?", type=int, default=0, help="first seed offset")
    p.add_argument("--pairs", type=int, default=None, help="pair draws (2 x DRAWS)")
    p.add_argument("--clean", type=int, default=None, help="clean draws (2 x DRAWS)")
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--filter-spread", type=float, default=NUISANCE_RANGES.filter_break)
    p.add_argument("--design", action="store_true", help="design and play the next run of "
                   "every ambiguous draw, and judge again")  # fmt: skip
    p.add_argument("--only", type=Path, default=None, help="an earlier run's --json: draw "
                   "again only its draws whose first finding was ambiguous")  # fmt: skip
    p.add_argument("--json", type=Path, default=None, help="write every row and the summary")
    a = p.parse_args()
    pairs = 2 * a.draws if a.pairs is None else a.pairs
    cleans = 2 * a.draws if a.clean is None else a.clean
    ranges = replace(NUISANCE_RANGES, filter_break=a.filter_spread)
    jobs = _jobs(a.draws, a.first, pairs, cleans)
    if a.only is not None:
        earlier = json.loads(a.only.read_text(encoding="utf-8"))["rows"]
        keep = {(r["kind"], r["seed"]) for r in earlier if r.get("first_ambiguous")}
        jobs = [j for j in jobs if j in keep]
    print(f"{len(jobs)} draws ({a.draws} per effect type, {pairs} pairs, {cleans} clean), "
          f"nuisances {ranges}, {a.workers} workers")  # fmt: skip
    work = tempfile.TemporaryDirectory(prefix="ambiguity-rates-")  # removed when this returns
    tmp = work.name
    rows = []
    t0 = time.perf_counter()
    with ProcessPoolExecutor(a.workers) as pool:
        futures = [pool.submit(_job, kind, seed, ranges, tmp, a.design) for kind, seed in jobs]
        done = as_completed(futures)
        bar = tqdm(done, total=len(futures), mininterval=5) if tqdm else done
        for fut in bar:
            row = fut.result()
            rows.append(row)
            (bar.write if tqdm else print)(_line(row))  # type: ignore[union-attr]
    rows.sort(key=lambda r: (str(r["kind"]), int(r["seed"])))  # type: ignore[call-overload]
    summary = report(rows)
    print(f"wall time {time.perf_counter() - t0:.0f} s")
    if a.json:
        a.json.write_text(json.dumps({"summary": summary, "rows": rows}, indent=1, default=str))


if __name__ == "__main__":
    main()
