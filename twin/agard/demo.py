"""``make demo``: the Table 5.2 describing-function sweep of the MPI and SRS twins.

Pitch and heave, signals 1 and 2, on the MPI twin (full MuJoCo model and reduced Eq 5.11) and
the SRS twin (full). Prints a short table (fitted delay against the configured one, worst gain
and phase difference from Eq 5.11 at the lines whose signal-to-noise ratio is at least 20 dB),
and writes Bode figures, the results as JSON and one Rerun recording per bench into the
output folder (given a way to record: :func:`twin.viz.record.bench_recorder`).
"""

from __future__ import annotations

import json
import threading
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

from twin.agard.df import DfResult, draw_bode, run_df
from twin.agard.session import Session, SessionRecorder
from twin.core.progress import ProgressFn
from twin.measurement.measure import Bench, configure

BENCHES = (("mpi", "full"), ("mpi", "reduced"), ("srs", "full"))
DOFS = ("pitch", "heave")
#: Lines compared with Eq 5.11 in the table: signal-to-noise at least this [dB].
GOOD_SNR_DB = 20.0


#: Builds a bench's recording saved to a path (:func:`twin.viz.record.bench_recorder`).
RecorderFactory = Callable[[Bench, Path], SessionRecorder]


def _sweep(
    config: str, model: str, out: Path, done, recorder: RecorderFactory | None
) -> list[DfResult]:
    bench = Bench(configure(config), model)
    rec = None if recorder is None else recorder(bench, out / f"{config}-{model}.rrd")
    with Session(bench, recorder=rec) as s:
        results = []
        for dof in DOFS:
            results.append(run_df(s, dof))
            done()
        return results


def run_demo(
    out: Path,
    progress: ProgressFn | None = None,
    shown_as: Path | None = None,
    recorder: RecorderFactory | None = None,
) -> str:
    """Run the sweep into ``out``; return the printed table (naming ``shown_as`` or ``out``).

    ``recorder`` builds each bench's recording, ``OUT/<config>-<model>.rrd`` (none without).
    """
    from twin.core.plotting import subplots

    out.mkdir(parents=True, exist_ok=True)
    lock, count = threading.Lock(), [0]

    def done() -> None:  # one DOF's sweep finished (called from the workers)
        with lock:
            count[0] += 1
            if progress:
                progress("describing-function sweeps", count[0], len(BENCHES) * len(DOFS))

    with ThreadPoolExecutor(2) as pool:  # MuJoCo releases the GIL: both cores
        jobs = {(c, m): pool.submit(_sweep, c, m, out, done, recorder) for c, m in BENCHES}
        results = {key: job.result() for key, job in jobs.items()}
    lines = [
        "Table 5.2 describing-function sweep (signals 1 + 2, IMU post-processed as App. C)",
        f"{'twin':14} {'dof':6} {'delay fit':>9} {'config':>7} {'|dgain| dB':>10} "
        f"{'|dphase| deg':>12} {'lines':>6}  (vs Eq 5.11, at lines with SNR >= 20 dB)",
    ]
    payload = {}
    for (config, model), rs in results.items():
        for r in rs:
            good = r.snr_db >= GOOD_SNR_DB
            err = r.response[good] / r.analytic()[good]
            db = np.abs(20 * np.log10(np.abs(err))).max()
            deg = np.abs(np.angle(err, deg=True)).max()
            lines.append(
                f"{config + ' ' + model:14} {r.dof:6} {r.delay_s * 1e3:7.1f}ms "
                f"{r.configured_delay_s * 1e3:5.1f}ms {db:10.2f} {deg:12.1f} {good.sum():3d}/"
                f"{good.size}"
            )
            payload[f"{config}-{model}-{r.dof}"] = r.to_dict()
    for i, dof in enumerate(DOFS):
        fig, (ax_g, ax_p) = subplots(None, 2, 1, figsize=(6.5, 6), sharex=True)
        for j, ((config, model), rs) in enumerate(results.items()):
            draw_bode(ax_g, ax_p, rs[i], f"C{j}", f"{config} {model}", configure(config))
        ax_g.set_title(f"describing functions, {dof} (points: twin, 95 %; lines: Eq 5.11)",
                       fontsize=9)  # fmt: skip
        ax_g.legend(fontsize=8)
        fig.tight_layout()
        fig.savefig(out / f"df-{dof}.png", dpi=120)
    (out / "df.json").write_text(json.dumps(payload, indent=2) + "\n", encoding="utf-8")
    if recorder is None:
        lines.append(f"figures and results in {shown_as or out}/: df-pitch.png, df-heave.png, "
                     "df.json")  # fmt: skip
    else:
        lines.append(
            f"figures, results and recordings in {shown_as or out}/: df-pitch.png, df-heave.png, "
            "df.json, " + ", ".join(f"{c}-{m}.rrd" for c, m in BENCHES)
        )
    return "\n".join(lines)
