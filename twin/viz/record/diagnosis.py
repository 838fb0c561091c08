"""The Rerun recording of a diagnosis (``twin diagnose``: ``OUT/diagnosis.rrd``).

Per DOF (tab), run 1: the measured response overlaid with the nominal twin's and the
extended model's (``<dof>/response/measured|nominal|extended`` against ``sim_time``, in the
measurement's unit), the residuals of both models (``<dof>/residual/nominal|extended``).
Every run: the describing-function ratios measured / nominal and measured / extended at the
excited lines with their 95 % bounds (``<dof>/ratio/gain|phase/measured_over_nominal`` ...,
suffixed ``_run<k>`` when there are several runs), and the extended model's own ratio to the
nominal as a line, against ``frequency_mHz``; the report's two figures as images
(``<dof>/ratio/figure``, ``<dof>/residual_figure``). The findings as the terminal shows them,
ambiguous ones with every alternative, as a text document (``findings``).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import rerun as rr
import rerun.blueprint as rrb

from twin.diagnose.residual_figure import plot_residual, unit_of
from twin.diagnose.residuals import line_ratios
from twin.viz.record.spectra import Curve, bode_curve, log_curves, log_figure, response_views
from twin.viz.record.stream import TIMELINE, Recording, send_series, series_style

#: Colours of the measured, nominal and extended responses.
COLOURS = {"measured": (30, 30, 30), "nominal": (31, 119, 180), "extended": (255, 127, 14)}


def diagnosis_blueprint(dofs: tuple[str, ...]) -> rrb.Blueprint:
    """Return the layout: per DOF, the overlaid responses and residuals, the ratios, figures."""
    tabs = []
    for dof in dofs:
        time = rrb.Vertical(
            rrb.TimeSeriesView(origin=f"/{dof}/response",
                               name=f"{dof}: measured vs nominal vs extended"),
            rrb.TimeSeriesView(origin=f"/{dof}/residual", name=f"{dof}: residuals"),
            rrb.Spatial2DView(origin=f"/{dof}/residual_figure", name=f"{dof}: residual spectra"),
            name=f"{dof}: time",
        )  # fmt: skip
        tabs += [time, response_views(f"/{dof}/ratio", f"{dof}: measured / model")]
    tabs.insert(0, rrb.TextDocumentView(origin="/findings", name="findings"))
    return rrb.Blueprint(rrb.Tabs(*tabs), collapse_panels=True)


def record_diagnosis(d, path: str | Path) -> Path:
    """Save a :class:`~twin.diagnose.diagnosis.Diagnosis` to ``path`` (see module docstring)."""
    dofs = tuple(d.dofs)
    with Recording("twin diagnose", diagnosis_blueprint(dofs), rrd=path) as recording:
        rec = recording.rec
        text = "\n".join(d.summary_lines()) or "no finding"
        rec.log("findings", rr.TextDocument(text), static=True)
        for dof, r in d.dofs.items():
            ch = d.case.of(dof)[0]
            unit = unit_of(dof)
            times = rr.TimeColumn(TIMELINE, duration=np.asarray(ch.t, dtype=float))
            signals = {"measured": ch.measured, "nominal": ch.nominal,
                       "extended": r.model.predict(ch)}  # fmt: skip
            for name, values in signals.items():
                entity = f"{dof}/response/{name}"
                series_style(rec, entity, f"{name} [{unit}]", COLOURS[name],
                             2.0 if name == "measured" else 1.25)  # fmt: skip
                send_series(rec, entity, times, values)
                if name != "measured":
                    entity = f"{dof}/residual/{name}"
                    series_style(rec, entity, f"measured - {name} [{unit}]", COLOURS[name])
                    send_series(rec, entity, times, ch.measured - values)
            curves = []
            channels = d.case.of(dof)
            predictions = [r.model.predict(c) for c in channels]
            for i, ch_i in enumerate(channels):  # one curve per run: runs may share lines
                run = f"_run{i + 1}" if len(channels) > 1 else ""
                for name, pred in (("nominal", None), ("extended", [predictions[i]])):
                    lines = line_ratios([ch_i], pred)
                    lo, hi = lines.ci_db()
                    bounds = (lines.db - lo, hi - lines.db, lines.ci_deg())
                    curves.append(Curve(f"measured_over_{name}{run}", lines.f, lines.db,
                                        lines.deg, COLOURS[name], bounds))  # fmt: skip
            f = np.geomspace(r.lines.f.min() / 2, d.max_hz, 300)
            h = r.model.linear_response(f)
            curves.append(bode_curve("extended_over_nominal", f, h, (0, 0, 0)))
            log_curves(rec, f"{dof}/ratio", curves)
            log_figure(rec, f"{dof}/ratio/figure", lambda r=r: r.plot(max_hz=d.max_hz))
            log_figure(rec, f"{dof}/residual_figure", lambda dof=dof: plot_residual(d, dof))
    return Path(path)
