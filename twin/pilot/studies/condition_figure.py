"""Measures per Table 6.3 condition drawn as the thesis draws them (Fig 6.5-6.9).

The eight conditions are grouped as in the thesis' figures: four groups of platform noise
(- or +) and time delay, each with the platform filter off (open marker) and on (1 Hz,
filled marker) side by side; a marker is the mean over subjects (or runs) and its bar the
95 % confidence interval of that mean (Student t, n - 1 degrees of freedom). A variance can
also be drawn as the thesis' stacked decomposition (target, disturbance, remnant).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray
from scipy import stats

from twin.core.plotting import AxesArg, save, subplots
from twin.core.thesis import TABLE_6_3

if TYPE_CHECKING:
    from matplotlib.figure import Figure

FloatArray = NDArray[np.float64]
#: Grey levels of the stacked variance parts (the thesis: t light, d dark, r white).
PART_COLOURS = {"target": "0.8", "disturbance": "0.35", "remnant": "white"}
#: Half the distance between filter off and on in a group.
OFFSET = 0.18
#: A panel's y axis spans at least this fraction of its values' size.
MIN_RELATIVE_SPAN = 0.1


@dataclass(frozen=True)
class Panel:
    """One measure's panel.

    Attributes
    ----------
    title : str
        Panel title (name the thesis figure).
    ylabel : str
        Axis label with unit.
    samples : mapping of int to sequence of float
        Per condition, the values over subjects or runs (one value: no bar).
    parts : mapping of int to mapping of str to float, optional
        Per condition, the variance split into ``target``, ``disturbance``, ``remnant``
        (stacked bars under the markers).

    """

    title: str
    ylabel: str
    samples: Mapping[int, Sequence[float]]
    parts: Mapping[int, Mapping[str, float]] | None = None


def position(condition: int) -> float:
    """Return the x position of a condition: its noise-delay group, filter off left, on right."""
    fb, delay, noise = TABLE_6_3[condition]
    delays = sorted({d for _, d, _ in TABLE_6_3.values()})
    group = 2 * delays.index(delay) + int(bool(noise))
    return group + (OFFSET if fb is not None else -OFFSET)


def group_labels() -> list[str]:
    """Return the four groups' tick labels (noise, delay)."""
    delays = sorted({d for _, d, _ in TABLE_6_3.values()})
    return [f"noise {'+' if noise else '-'}\n{d * 1e3:.0f} ms" for d in delays
            for noise in (False, True)]  # fmt: skip


def mean_ci(values: Sequence[float]) -> tuple[float, float]:
    """Return the mean and the half-width of its 95 % confidence interval (0 for one value).

    Examples
    --------
    >>> m, h = mean_ci([1.0, 2.0, 3.0])
    >>> round(m, 3), round(h, 3)   # t(0.975, 2) = 4.303, sd/sqrt(3) = 0.577
    (2.0, 2.484)

    """
    x = np.asarray(values, dtype=float)
    x = x[np.isfinite(x)]
    if x.size < 2:
        return (float(x.mean()) if x.size else float("nan")), 0.0
    return float(x.mean()), float(stats.t.ppf(0.975, x.size - 1) * x.std(ddof=1) / np.sqrt(x.size))


def draw_panel(ax, panel: Panel) -> None:
    """Draw one measure on ``ax`` (see the module docstring)."""
    for n, values in panel.samples.items():
        x = position(n)
        filt = TABLE_6_3[n][0] is not None
        if panel.parts is not None and n in panel.parts:
            bottom = 0.0
            for part, colour in PART_COLOURS.items():
                v = float(panel.parts[n][part])
                ax.bar(x, v, 0.3, bottom=bottom, color=colour, edgecolor="k", lw=0.5,
                       label=part if n == min(panel.parts) else None)  # fmt: skip
                bottom += v
        m, h = mean_ci(values)
        ax.errorbar(x, m, yerr=h if h > 0 else None, fmt="o", color="k",
                    mfc="k" if filt else "white", capsize=3, ms=5, zorder=3,
                    label=None)  # fmt: skip
    lo, hi = ax.get_ylim()  # a measure that barely changes is not stretched into an effect
    mid, span = 0.5 * (lo + hi), MIN_RELATIVE_SPAN * max(abs(0.5 * (lo + hi)), 1e-12)
    if hi - lo < span:
        ax.set_ylim(mid - span / 2, mid + span / 2)
    ax.set_xticks(range(4), group_labels(), fontsize=7)
    ax.set_xlim(-0.6, 3.6)
    ax.set_xlabel("platform noise, total delay", fontsize=7)
    ax.set_title(panel.title, fontsize=8)
    ax.set_ylabel(panel.ylabel, fontsize=8)
    ax.tick_params(labelsize=7)
    ax.grid(True, axis="y", alpha=0.4)
    if panel.parts is not None:
        ax.legend(fontsize=6, loc="upper right")


def plot_conditions(
    panels: Sequence[Panel],
    title: str,
    path: str | None = None,
    columns: int = 4,
    ax: AxesArg = None,
) -> Figure:
    """Draw ``panels`` in a grid (Fig 6.5-6.9 style) and return the figure.

    Parameters
    ----------
    panels : sequence of Panel
        The measures.
    title : str
        Figure title (say what the bars are over).
    path : str, optional
        Save the figure here.
    columns : int
        Panels per row.
    ax : sequence of Axes, optional
        Axes to draw on, ``columns`` per row, in row order (the last row filled with unused
        ones); a new figure by default.

    """
    rows = -(-len(panels) // columns)
    own = ax is None
    fig, axes = subplots(ax, rows, columns, figsize=(3.4 * columns, 3.0 * rows + 0.6),
                         squeeze=False, panels=f"{columns} per row")  # fmt: skip
    for a, panel in zip(axes.flat, panels, strict=False):
        draw_panel(a, panel)
    for a in list(axes.flat)[len(panels) :]:
        a.set_visible(False)
    handles = [
        axes.flat[0].errorbar([], [], yerr=[], fmt="o", color="k", mfc=face, capsize=3)
        for face in ("white", "k")
    ]
    fig.legend(handles, ["filter - (SRS dynamics)", "1 Hz filter (MPI)"], loc="upper right",
               fontsize=8, ncol=1)  # fmt: skip
    if own:  # the caller's figure is theirs to title and lay out
        fig.suptitle(title, fontsize=9, x=0.02, ha="left")
        fig.tight_layout(rect=(0, 0, 1, 1 - 0.5 / fig.get_figheight()))
    if path:
        save(fig, path, dpi=110)
    return fig


def samples_by_condition(
    rows: Sequence[Mapping[str, float]], measure: str
) -> dict[int, list[float]]:
    """Return {condition: the measure over subjects} from per-subject rows."""
    out: dict[int, list[float]] = {}
    for r in rows:
        out.setdefault(int(r["condition"]), []).append(float(r[measure]))
    return dict(sorted(out.items()))
