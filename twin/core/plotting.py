"""What every result's ``plot(ax=None, *, path=None)`` shares: figures, axes given or made.

Every result object of the twin (:class:`~twin.agard.df.DfResult`, ...,
:class:`~twin.diagnose.diagnosis.Diagnosis`) follows :class:`twin.core.results.Result`: its
``plot`` draws on the axes it is given (``ax``: one :class:`~matplotlib.axes.Axes`, or a
sequence of them for a plot of several panels, as each ``plot`` documents) or, without
``ax``, on a new :class:`matplotlib.figure.Figure`; it saves the figure to ``path`` on
request and returns it. Figures are made as :class:`~matplotlib.figure.Figure` objects, not
through :mod:`matplotlib.pyplot`: no window opens, no backend is selected and pyplot's list of
open figures is left alone (a notebook shows a returned figure as the value of its cell).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any
from weakref import WeakSet

import numpy as np

from twin.core.errors import UsageError

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

#: What a result's ``plot`` takes as ``ax``: one Axes, a sequence of them, or None.
AxesArg = "Axes | Sequence[Axes] | None"

#: Figures :func:`subplots` made (laid out by :func:`finish`; a caller's figure is theirs).
_MADE: WeakSet[Figure] = WeakSet()


def subplots(
    ax: Axes | Sequence[Axes] | None = None,
    nrows: int = 1,
    ncols: int = 1,
    *,
    figsize: tuple[float, float] | None = None,
    squeeze: bool = True,
    panels: str = "",
    **kwargs: Any,
) -> tuple[Figure, Any]:
    """Return ``(figure, axes)``: a new figure's grid of axes, or the axes the caller gave.

    Parameters
    ----------
    ax : Axes or sequence of Axes, optional
        The caller's axes: one for a single panel, ``nrows * ncols`` of them (in row order)
        for several. None makes a new :class:`~matplotlib.figure.Figure` of ``figsize``.
    nrows, ncols : int
        The grid of panels.
    figsize : tuple of float, optional
        Size of a new figure [inch].
    squeeze : bool
        As :meth:`matplotlib.figure.Figure.subplots`: a single panel as one Axes, one row or
        column as a 1-D array.
    panels : str
        What the panels show, named in the error for axes of the wrong count.
    **kwargs
        Passed to :meth:`matplotlib.figure.Figure.subplots` for a new figure (``sharex``, ...).

    Returns
    -------
    figure : Figure
        The new figure, or the figure of the given axes.
    axes : Axes or numpy.ndarray of Axes
        Shaped as :meth:`matplotlib.figure.Figure.subplots` shapes them.

    Raises
    ------
    UsageError
        For ``ax`` that is no Axes, or a count of axes other than ``nrows * ncols``.

    """
    if ax is None:
        from matplotlib.figure import Figure

        fig = Figure(figsize=figsize)
        _MADE.add(fig)
        return fig, fig.subplots(nrows, ncols, squeeze=squeeze, **kwargs)
    from matplotlib.axes import Axes

    n = nrows * ncols
    given: list[Any] | None = None
    if isinstance(ax, Axes):
        given = [ax]
    elif isinstance(ax, np.ndarray):
        given = list(ax.ravel())
    elif isinstance(ax, Sequence) and not isinstance(ax, str):
        given = list(ax)
    what = f"{n} Axes ({panels})" if panels else ("one Axes" if n == 1 else f"{n} Axes")
    if given is None or len(given) != n or not all(isinstance(a, Axes) for a in given):
        got = type(ax).__name__ if given is None else f"{len(given)} item(s)"
        raise UsageError(f"ax: expected {what}; got {got}")
    grid = np.empty(n, dtype=object)
    grid[:] = given
    grid = grid.reshape(nrows, ncols)
    out: Any = grid
    if squeeze:
        out = grid[0, 0] if n == 1 else grid.ravel() if 1 in (nrows, ncols) else grid
    return given[0].figure, out


def save(fig: Figure, path: str | Path, dpi: int = 120) -> None:
    """Save ``fig`` to ``path`` (format from its suffix); the file appears only when complete."""
    from twin.core.lifecycle import replacing_file

    with replacing_file(path) as tmp:
        fig.savefig(tmp, dpi=dpi)


def finish(fig: Figure, path: str | Path | None = None, dpi: int = 120) -> Figure:
    """Lay out ``fig`` if :func:`subplots` made it, save it to ``path`` if given, return it.

    A plot drawn on the caller's axes leaves the caller's figure to the caller to lay out.
    """
    if fig in _MADE:
        fig.tight_layout()
    if path:
        save(fig, path, dpi)
    return fig
