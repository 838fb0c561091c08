"""Rerun recordings of pilot-in-the-loop runs (``twin pilot run --rrd``).

Entity paths (angles in deg, against ``sim_time`` from the measurement window's start):
``tracking/ft|theta|e`` (target, pitch attitude, error), ``control/u|fd`` (stick and the
disturbance added to it), ``motion/theta|theta_felt`` (the aircraft's attitude again, beside
what the pilot feels through the motion system), ``remnant/n``; the two open loops (in Hz on
``frequency_mHz``; their figure in rad/s, as pilot models are plotted) under
``open_loop/gain|phase/disturbance|target``, the figure at ``open_loop/figure`` (crossovers
and phase margins marked).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import rerun as rr
import rerun.blueprint as rrb

from twin.core.plotting import subplots
from twin.measurement.describing_function import phase_deg
from twin.pilot.models.pitch import open_loop_responses, open_loops
from twin.viz.record.spectra import bode_curve, log_curves, log_figure, response_views
from twin.viz.record.stream import TIMELINE, Recording, send_series, series_style

#: (entity, legend, colour) of each signal.
SIGNALS = (
    ("tracking/ft", "target f_t", (120, 120, 120)),
    ("tracking/theta", "pitch attitude theta", (31, 119, 180)),
    ("tracking/e", "error e", (214, 39, 40)),
    ("control/u", "stick u", (44, 160, 44)),
    ("control/fd", "disturbance f_d", (140, 86, 75)),
    ("motion/theta", "attitude theta", (31, 119, 180)),
    ("motion/theta_felt", "felt attitude (through the motion system)", (148, 103, 189)),
    ("remnant/n", "remnant n", (127, 127, 127)),
)


def pilot_blueprint() -> rrb.Blueprint:
    """Return the layout of a pilot run: tracking, control, motion; the open loops."""
    series = rrb.Vertical(
        rrb.TimeSeriesView(origin="/tracking", name="tracking: f_t, theta, e [deg]"),
        rrb.TimeSeriesView(origin="/control", name="control: u, f_d [deg]"),
        rrb.TimeSeriesView(origin="/motion", name="motion: theta vs felt [deg]"),
        rrb.TimeSeriesView(origin="/remnant", name="remnant [deg]"),
        name="pilot in the loop",
    )
    loops = response_views("/open_loop", "open loops")
    return rrb.Blueprint(rrb.Tabs(series, loops), collapse_panels=True)


def record_pilot(path: str | Path, runs, pilot, run: int = 0) -> Path:
    """Save run ``run`` of :class:`~twin.pilot.models.pitch.PitchRuns`, open loops, to ``path``."""
    cfg = runs.config
    with Recording(f"pilot {cfg.name}", pilot_blueprint(), rrd=path) as recording:
        rec = recording.rec
        times = rr.TimeColumn(TIMELINE, duration=np.asarray(runs.t, dtype=float))
        values = {"tracking/ft": runs.ft, "tracking/theta": runs.theta[run],
                  "tracking/e": runs.e[run], "control/u": runs.u[run], "control/fd": runs.fd,
                  "motion/theta": runs.theta[run], "motion/theta_felt": runs.theta_felt[run],
                  "remnant/n": runs.n[run]}  # fmt: skip
        for entity, legend, colour in SIGNALS:
            series_style(rec, entity, f"{legend} [deg]", colour)
            send_series(rec, entity, times, np.degrees(np.asarray(values[entity], dtype=float)))
        w = np.geomspace(0.1, 50.0, 400)
        loops = open_loop_responses(pilot, cfg, w)
        names = {"d": ("disturbance", (214, 39, 40)), "t": ("target", (31, 119, 180))}
        log_curves(rec, "open_loop", [bode_curve(names[k][0], w / (2 * np.pi), h, names[k][1])
                                      for k, h in loops.items()])  # fmt: skip
        log_figure(rec, "open_loop/figure", lambda: _open_loop_figure(pilot, cfg, w, loops))
    return Path(path)


def _open_loop_figure(pilot, cfg, w, loops):
    """Bode plot of the open loops [rad/s] with crossovers and phase margins marked."""
    names = {"d": "disturbance", "t": "target"}
    ol = open_loops(pilot, cfg)
    fig, (ax_g, ax_p) = subplots(None, 2, 1, figsize=(6.5, 6), sharex=True)
    for k, h in loops.items():
        wc, pm = (ol.crossover_d, ol.phase_margin_d) if k == "d" else (
            ol.crossover_t, ol.phase_margin_t)  # fmt: skip
        label = f"{names[k]}: crossover {wc:.2f} rad/s, phase margin {pm:.1f} deg"
        ax_g.semilogx(w, 20 * np.log10(np.abs(h)), label=label)
        ax_p.semilogx(w, phase_deg(h))
        ax_p.plot([wc], [pm - 180.0], "o", color=ax_g.lines[-1].get_color())
    ax_g.axhline(0.0, color="k", lw=0.6)
    ax_p.axhline(-180.0, color="k", lw=0.6)
    # the delays' phase runs away at high frequency: keep the crossover region readable
    ax_p.set_ylim(max(ax_p.get_ylim()[0], -540.0), ax_p.get_ylim()[1])
    ax_g.set_ylabel("gain [dB]")
    ax_p.set_ylabel("phase [deg]")
    ax_p.set_xlabel("frequency [rad/s]")
    ax_g.set_title(f"pitch-task open loops through {cfg.name}", fontsize=9)
    ax_g.legend(fontsize=8)
    for ax in (ax_g, ax_p):
        ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    return fig
