"""The one protocol every analysis result of the twin follows.

Runs and simulations are data (arrays), not results. A result
(:class:`~twin.agard.df.DfResult`, :class:`~twin.diagnose.diagnosis.Diagnosis`,
:class:`~twin.pilot.studies.population.PopulationResult`, ...) has

- ``to_dict()``: the result as JSON-ready Python values (``json.dumps`` takes it as it is);
- ``to_frame()``: its main table as a :class:`pandas.DataFrame` (each class says what a row
  is);
- ``plot(ax=None, *, path=None)``: draws it and returns the
  :class:`~matplotlib.figure.Figure`; ``ax`` is one :class:`~matplotlib.axes.Axes` or, for a
  plot of several panels, a sequence of them (each ``plot`` says how many and in which
  order); without ``ax`` a new figure is made; ``path`` saves the figure (format from the
  suffix).

A result that is a frequency response (describing functions, the full-versus-reduced
comparison, OMCT, a diagnosis' measured-over-nominal ratios) also has ``to_frd()``: a
:class:`control.FrequencyResponseData` at its frequencies in rad/s, as python-control takes
them (see :doc:`/conventions`).

Examples
--------
>>> from twin.core.results import FrequencyResult, Result
>>> from twin.agard.df import DfResult
>>> issubclass(DfResult, FrequencyResult)
True

"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

from twin.core.errors import UsageError

if TYPE_CHECKING:
    import control
    import pandas as pd
    from matplotlib.figure import Figure
    from numpy.typing import ArrayLike

    from twin.core.plotting import AxesArg


@runtime_checkable
class Result(Protocol):
    """What every result object has: ``to_dict``, ``to_frame`` and ``plot``."""

    def to_dict(self) -> dict[str, Any]:
        """Return the result as JSON-ready values."""

    def to_frame(self) -> pd.DataFrame:
        """Return the result's main table."""

    def plot(self, ax: AxesArg = None, *, path: str | None = None) -> Figure:
        """Draw the result on ``ax`` (or a new figure), save it to ``path``, return it."""


@runtime_checkable
class FrequencyResult(Result, Protocol):
    """A result that is a frequency response: a :class:`Result` with ``to_frd``."""

    def to_frd(self) -> control.FrequencyResponseData:
        """Return the response as python-control frequency response data (rad/s)."""


def frame(rows: Iterable[Mapping[str, Any]] | Mapping[str, Any]) -> pd.DataFrame:
    """Return a DataFrame of ``rows`` (dicts, nested ones flattened to ``outer.inner``).

    A mapping of columns (equal lengths) is taken as it is.
    """
    import numpy as np
    import pandas as pd

    if isinstance(rows, Mapping):
        return pd.DataFrame({k: np.asarray(v) if not isinstance(v, list) else v
                             for k, v in rows.items()})  # fmt: skip
    rows = list(rows)
    if not rows:
        return pd.DataFrame()
    return pd.json_normalize(rows)


def frd(
    response: ArrayLike, frequencies_hz: ArrayLike, name: str = "", *, rad_s: bool = False
) -> control.FrequencyResponseData:
    """Return python-control frequency response data of a SISO response.

    Parameters
    ----------
    response : array_like of complex
        The response at each frequency.
    frequencies_hz : array_like of float
        The frequencies, in Hz (or in rad/s with ``rad_s=True``); the data are at rad/s.
    name : str
        The system's name.
    rad_s : bool
        Whether ``frequencies_hz`` are already in rad/s.

    """
    import control
    import numpy as np

    f = np.asarray(frequencies_hz, dtype=float)
    w = f if rad_s else 2 * np.pi * f
    h = np.asarray(response, dtype=complex)
    return control.FrequencyResponseData(h, w, name=name or None)


def pick(dof: str | None, names: Iterable[str], what: str) -> str:
    """Return ``dof``, or the only one of ``names`` when it is None.

    Raises
    ------
    UsageError
        For a DOF not among ``names``, or None where there are several.

    """
    names = list(names)
    if dof is None:
        if len(names) == 1:
            return names[0]
        raise UsageError(f"{what} holds several DOFs ({', '.join(names)}); name one with dof=")
    if dof not in names:
        raise UsageError(f"{what} has no {dof!r}; it holds {', '.join(names)}")
    return dof
