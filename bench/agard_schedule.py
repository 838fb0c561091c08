"""Wall time of a whole AGARD-AR-144 A schedule on the full SRS twin (goal <= 60 s, 2 cores).

The schedule is written here in the SIMONA Research Simulator's ``MovementSeries`` format, as
an AR-144 A set is: the six DOFs in turn (rotations scaled 0.7 rad per unit), five
frequencies (0.195, 0.488, 0.977, 1.95 and 4.88 Hz), three amplitudes a decade apart (the
largest 0.6-3 m/s^2 at the moves' frequencies), each a 23 s faded sine (6 s fades), a second
at rest between the sets: 2086 s of motion. Timed: ``twin agard report srs --model full
--schedule FILE`` (simulate it as one run, write the run folder, analyse every test it holds:
describing functions at the schedule's frequencies, linearity from its three amplitudes,
parasitic motion) and, apart, the simulation alone.

Usage: ``python bench/agard_schedule.py``
"""

import contextlib
import io
import json
import math
import tempfile
import time
from pathlib import Path

from twin.chain.config import motion_system
from twin.chain.simulate import prepare
from twin.cli.main import main as twin
from twin.formats.schedule import read_schedule

GOAL_S = 60.0
#: Angular frequencies [rad/s] and largest acceleration amplitude of each set [m/s^2].
SETS = ((1.2272, 0.6136), (3.0680, 1.534), (6.1359, 3.0), (12.272, 3.0), (30.680, 3.0))
AXES = [
    [1, 0, 0, 0, 0, 0],
    [0, 1, 0, 0, 0, 0],
    [0, 0, 1, 0, 0, 0],
    [0, 0, 0, 0.7, 0, 0],
    [0, 0, 0, 0, 0.7, 0],
    [0, 0, 0, 0, 0, 0.7],
]


def ar144a() -> dict:
    """Return an AR-144 A style MovementSeries (see the module docstring)."""
    zero = {
        "type": "Pose",
        "uvw": [0.0] * 3,
        "pqr": [0.0] * 3,
        "xyz": [0.0] * 3,
        "phithetapsi": [0.0] * 3,
    }
    moves, t = [], 0.0
    for scale in (1.0, 0.1, 0.01):
        for omega, acc in SETS:
            moves.append(
                {"time": t, "move": {"type": "Still", "xyz": [0.0] * 3, "phithetapsi": [0.0] * 3}}
            )
            t += 1.0
            for axis in AXES:
                profile = {
                    "type": "FadedSineProfile",
                    "Tfade": 6.0,
                    "Ttotal": 23.0,
                    "omg": [omega],
                    "gain": [scale * acc / omega**2],
                    "phi0": [0.0],
                }
                moves.append(
                    {
                        "time": t,
                        "move": {
                            "type": "ProfileMotion",
                            "from": zero,
                            "move": zero,
                            "axis": axis,
                            "profile": profile,
                            "dt": 23.0,
                        },
                    }
                )
                t += 23.0
    moves.append({"time": t, "move": {"type": "Still", "xyz": [0.0] * 3, "phithetapsi": [0.0] * 3}})
    return {"type": "MovementSeries", "moves": moves}


def main() -> None:
    work = tempfile.TemporaryDirectory()  # removed when this returns
    tmp = Path(work.name)
    path = tmp / "ar144a.json"
    path.write_text(json.dumps(ar144a()), encoding="utf-8")
    schedule = read_schedule(path)
    print(f"schedule: {len(schedule.moves)} moves, {schedule.duration_s:.0f} s of motion")
    t0 = time.perf_counter()
    with contextlib.redirect_stdout(io.StringIO()):  # the report's own summary
        code = twin(
            [
                "agard",
                "report",
                "srs",
                "--model",
                "full",
                "--schedule",
                str(path),
                "--out",
                str(tmp / "report"),
                "--quiet",
            ]
        )
    wall = time.perf_counter() - t0
    report = json.loads((tmp / "report" / "report.json").read_text())
    t0 = time.perf_counter()
    prepare(motion_system("srs"), schedule.commands(), "full", 0).collect()
    sim = time.perf_counter() - t0
    print(
        f"exit {code}; tests {', '.join(report['tests'])}; missing {', '.join(report['missing'])}"
    )
    for dof, df in report["tests"]["df"].items():
        gains = ", ".join(f"{20 * math.log10(g):+.2f}" for g in df["gain"])
        print(f"  df {dof:5s}: {len(df['frequencies_hz'])} lines, gain dB {gains}")
    print(
        f"report: {wall:.1f} s (goal {GOAL_S:g} s: ratio {wall / GOAL_S:.2f}); "
        f"the full-model simulation alone {sim:.1f} s ({schedule.duration_s / sim:.0f}x "
        "real time)"
    )


if __name__ == "__main__":
    main()
