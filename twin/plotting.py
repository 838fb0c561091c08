"""What every result's ``plot(path=None)`` shares: a non-interactive figure, saved on request.

Every result object of the twin (:class:`~twin.agard.df.DfResult`, ...,
:class:`~twin.diagnose.diagnosis.Diagnosis`) has ``to_dict()`` (JSON-ready) and
``plot(path=None)`` returning a :class:`matplotlib.figure.Figure`; plots never open a window
(the Agg backend is selected here, in plotting code only).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from matplotlib.figure import Figure


def pyplot() -> Any:
    """Return :mod:`matplotlib.pyplot` on the non-interactive Agg backend."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def save(fig: Figure, path: str | Path, dpi: int = 120) -> None:
    """Save ``fig`` to ``path`` (format from its suffix); the file appears only when complete."""
    from twin.lifecycle import replacing_file

    with replacing_file(path) as tmp:
        fig.savefig(tmp, dpi=dpi)


def finish(fig: Figure, path: str | Path | None = None, dpi: int = 120) -> Figure:
    """Lay out ``fig``, save it to ``path`` if given (:func:`save`), and return it."""
    fig.tight_layout()
    if path:
        save(fig, path, dpi)
    return fig
