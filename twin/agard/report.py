"""``twin agard report``: the whole AGARD-AR-144 / OMCT suite on one bench, as a folder.

For each DOF: describing function (Table 5.2 signals), half-Hertz noise levels, dynamic
threshold (§3.3.4 steps), OMCT (with the illustrative bounds unless others are given) and the
signal-to-noise grid. The folder holds ``report.json``, ``summary.md``, one PNG per test and
DOF, and every run as a ``twin-run/1`` folder under ``runs/``; it is written under a temporary
name and renamed when complete, so a failed report leaves nothing behind.
"""

from __future__ import annotations

import json
import shutil
from collections.abc import Sequence
from pathlib import Path

import matplotlib.pyplot as plt

from twin.agard import df, noise_level, omct, snr, threshold
from twin.agard.session import Session
from twin.frames import dof_index
from twin.measurement.measure import Bench
from twin.progress import ProgressFn


def threshold_defaults(dof: str) -> tuple[float, float]:
    """Step amplitude and length of §3.3.4: 0.1 m/s^2 or 0.075 rad/s^2, 1 s."""
    return (0.075 if dof_index(dof) >= 3 else 0.1), 1.0


def write_report(
    bench: Bench,
    dofs: Sequence[str],
    out: Path,
    rrd: str | None = None,
    progress: ProgressFn | None = None,
    bounds_path: str | Path | None = None,
) -> dict[str, object]:
    """Run the suite and write the report folder ``out``; return the report as a dict."""
    bounds = omct.read_bounds(bounds_path or omct.EXAMPLE_BOUNDS)
    tmp = out.with_name(out.name + ".partial")
    shutil.rmtree(tmp, ignore_errors=True)
    tmp.mkdir(parents=True)
    try:
        report, md = _run(bench, dofs, tmp, rrd, progress, bounds)
        (tmp / "report.json").write_text(json.dumps(report, indent=2) + "\n")
        (tmp / "summary.md").write_text(md)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    if out.exists():
        shutil.rmtree(out)
    tmp.rename(out)
    return report


def _figure(fig, path: Path) -> str:
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path.name


def _run(bench, dofs, tmp, rrd, progress, bounds):
    cfg = bench.config
    report: dict[str, object] = {"bench": bench.name, "config": cfg.to_meta(), "dofs": {}}
    md = [
        f"# AGARD-AR-144 / OMCT report: {bench.name}",
        "",
        f"Configuration `{cfg.name}`: {cfg.description or 'custom'}; platform {cfg.platform}, "
        f"filter {f'{cfg.filter_break_hz:g} Hz' if cfg.filter_break_hz else 'none'}, "
        f"total delay {cfg.delay_s * 1e3:.1f} ms, "
        f"noise {'on' if cfg.noise else 'off'}; model {bench.model}, seed {bench.seed}."
        + "".join(f" Extension {e.describe()}." for e in cfg.extensions),
        "",
    ]
    tests = 5 * len(dofs)

    def tested(k: int) -> None:
        if progress:
            progress(f"AGARD tests on {bench.name}", k, tests)

    def beside(message: str, done: float | None = None, total: float | None = None) -> None:
        if progress:  # a test's own runs, shown beside the report's bar
            progress(message if done is None else f"{message} {done:g}/{total:g}")

    with Session(bench, tmp, rrd, beside) as s:
        tested(0)
        for i, dof in enumerate(dofs):
            entry: dict[str, object] = {}
            d = df.run_df(s, dof)
            entry["df"] = d.to_dict()
            fig_df = _figure(d.plot(config=cfg), tmp / f"df-{dof}.png")
            tested(5 * i + 1)
            n = noise_level.run_noise(s, dof)
            entry["noise"] = n.to_dict()
            fig_n = _figure(n.plot(), tmp / f"noise-{dof}.png")
            tested(5 * i + 2)
            amp, step = threshold_defaults(dof)
            th = threshold.run_threshold(s, dof, amp, step)
            entry["threshold"] = th.to_dict()
            fig_t = _figure(th.plot(), tmp / f"threshold-{dof}.png")
            tested(5 * i + 3)
            o = omct.run_omct(s, dof)
            entry["omct"] = o.to_dict(bounds)
            fig_o = _figure(omct.plot_omct([o], bounds), tmp / f"omct-{dof}.png")
            tested(5 * i + 4)
            g = snr.run_snr(s, dof)
            entry["snr"] = g.to_dict()
            fig_s = _figure(g.plot(), tmp / f"snr-{dof}.png")
            tested(5 * i + 5)
            report["dofs"][dof] = entry  # type: ignore[index]
            md += [
                f"## {dof}",
                "",
                "```",
                d.format_table(),
                "```",
                f"![]({fig_df})",
                "",
                "```",
                n.format_table(),
                "```",
                f"![]({fig_n})",
                "",
                "```",
                th.format_table(),
                "```",
                f"![]({fig_t})",
                "",
                "```",
                o.format_table(bounds),
                "```",
                f"![]({fig_o})",
                "",
                "```",
                g.format_table(),
                "```",
                f"![]({fig_s})",
                "",
            ]
    md += [
        f"{s.count} runs, each a twin-run/1 folder under `runs/` (analyse one again with "
        "`twin agard df runs/NN-...`)."
    ]
    return report, "\n".join(md) + "\n"
