"""Acceptance rates of the physical diagnosis on runs with hidden physics (full MuJoCo truth).

Each draw (:mod:`twin.diagnose.hidden_physics`, seeds 0, 1, ... per kind, not tuned): a
platform, a DOF, a heavier cabin, one faulty leg or nothing, an IMU 0.3-3 times as noisy as
its data sheet, Table 5.2 signal 1 or 2 at 0.5-1.2 times its amplitudes, with or without the
leg logs; one run, simulated on the full model, diagnosed with ``physics=True``. Printed per
draw and per kind: right / wrong / nothing named, the fitted value against the truth, the wall
time; hidden physics that is not named and that the diagnosis' own detectability statement
puts below what the run could show is counted apart ("below detectability": the run could not
have shown it, and the report says so), as the issue of the physical vocabulary asks.

Goals: payload named (payload or platform_lag in the driven DOF), never a sensor effect, in
>= 90 % of draws, factor within 20 %; a detectable faulty leg named with its number in
>= 90 %; clean runs: nothing named in >= 95 %.

Usage: ``python bench/physical_acceptance.py [DRAWS_PER_KIND] [FIRST_SEED]`` (default 10, 0).
"""

import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from twin.diagnose.diagnosis import diagnose
from twin.diagnose.hidden_physics import KINDS, draw, judged, record


def _detectable(d, hidden) -> bool:
    """Whether the diagnosis' detectability puts the hidden physics within reach."""
    cause = hidden.cause
    if cause.effect == "payload":
        return cause.value("factor") - 1.0 >= d.physical.detectable["payload"]["smallest"][0]
    kind = cause.kind
    entry = d.physical.detectable[f"leg {kind}"]
    smallest = entry["smallest"][int(cause.value("leg")) - 1]
    nominal = 1.0 if kind == "gain" else 0.0
    return abs(cause.value(kind) - nominal) >= smallest


def main() -> None:
    draws = int(sys.argv[1]) if len(sys.argv) > 1 else 10
    first = int(sys.argv[2]) if len(sys.argv) > 2 else 0
    work = tempfile.TemporaryDirectory()  # removed when this returns
    tmp = Path(work.name)
    summary = {}
    for kind in KINDS:
        counts = {"right": 0, "wrong": 0, "ambiguous": 0, "none": 0, "below detectability": 0}
        errors, times, kinds = [], [], 0
        for seed in range(first, first + draws):
            hidden = draw(seed, kind)
            run = record(hidden, tmp / kind)
            t0 = time.perf_counter()
            d = diagnose([run], physics=True, seed=seed)
            times.append(time.perf_counter() - t0)
            verdict = judged(hidden, d.findings)
            if kind != "clean" and verdict == "none" and not _detectable(d, hidden):
                verdict = "below detectability"
            counts[verdict] += 1
            if kind == "leg" and verdict == "right":  # the leg right: its fault's kind too?
                kinds += d.findings[0].extension.kind == hidden.cause.kind
            named = "; ".join(f.extension.describe() for f in d.findings) or "nothing"
            if kind == "payload" and d.findings and d.findings[0].extension.effect == "payload":
                errors.append(d.findings[0].extension.value("factor") /
                              hidden.cause.value("factor") - 1)  # fmt: skip
            print(f"{hidden.describe()} -> {named}  [{verdict}, {times[-1]:.0f} s]", flush=True)
        summary[kind] = (counts, errors, times, kinds)
    print()
    for kind, (counts, errors, times, kinds) in summary.items():
        judged_n = sum(v for k, v in counts.items() if k != "below detectability")
        rate = counts["right"] / judged_n if judged_n else float("nan")
        extra = ""
        if kind == "leg":
            extra = f"; the fault's kind right too in {kinds} of {counts['right']}"
        if errors:
            e = np.abs(errors)
            extra = f"; factor error median {np.median(e):.1%}, max {e.max():.1%}"
        print(f"{kind:8s}: right {counts['right']}/{judged_n} ({rate:.0%}), wrong "
              f"{counts['wrong']}, ambiguous (truth listed as likely) {counts['ambiguous']}, "
              f"nothing {counts['none']}, below detectability "
              f"{counts['below detectability']}; time median {np.median(times):.0f} s, max "
              f"{max(times):.0f} s{extra}")  # fmt: skip


if __name__ == "__main__":
    main()
