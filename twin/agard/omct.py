"""The Objective Motion Cueing Test (§5.3.2, §5.6.3, Fig 5.12).

The OMCT (ICAO 9625; Advani et al. 2007) plots the gain and phase of the whole cueing system
at twelve frequencies, 10^(k/5) rad/s for k = -5 ... 6 (0.1 to 15.85 rad/s), against
performance boundaries. Here each frequency is a single sine (Eq 3.4 with the phases of
§3.2.3) in one DOF, and the describing function at that frequency is the OMCT point.

The boundaries are not in the thesis and the regulatory ones are not reproduced here: they are
read from a user-supplied TOML file (:func:`read_bounds`)::

    format = "twin-omct-bounds/1"
    title = "what these bounds are and where they come from"
    [default]                     # for every DOF without its own table
    frequency_rad_s = [0.1, 1.0, 15.85]
    gain_min = [0.6, 0.6, 0.3]    # ratio (not dB), linearly interpolated in log frequency
    gain_max = [1.4, 1.4, 1.4]
    phase_min_deg = [-30.0, -40.0, -120.0]
    phase_max_deg = [30.0, 30.0, 30.0]
    [pitch]                       # optional, same keys

``twin/agard/omct_bounds_illustrative.toml`` is an example, clearly labelled illustrative.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from twin.agard.session import Session
from twin.agard.snr import system_limit
from twin.core.checks import check_keys, number, numbers, read_toml
from twin.core.errors import SignalError, TwinError
from twin.core.frames import DOF_NAMES, dof_index
from twin.core.plotting import AxesArg, finish, subplots
from twin.core.results import frame, frd
from twin.measurement.describing_function import ResponseMixin, describing_function, phase_deg
from twin.measurement.measure import Measurement, driven_dof
from twin.measurement.periodic import periodic_design

if TYPE_CHECKING:
    import control
    import pandas as pd
    from matplotlib.figure import Figure

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]

#: The OMCT frequencies: 10^(k/5) rad/s, k = -5 ... 6.
OMCT_RAD_S = 10.0 ** (np.arange(-5, 7) / 5.0)
#: Illustrative boundaries shipped with the twin (not ICAO 9625's).
EXAMPLE_BOUNDS = Path(__file__).with_name("omct_bounds_illustrative.toml")
BOUNDS_FORMAT = "twin-omct-bounds/1"
#: The keys of each table of a bounds file, and the keys outside them.
_KEYS = ("frequency_rad_s", "gain_min", "gain_max", "phase_min_deg", "phase_max_deg")
_TOP_KEYS = ("format", "title")


class BoundsFileError(TwinError, ValueError):
    """An OMCT boundaries file that does not follow ``twin-omct-bounds/1``."""


@dataclass(frozen=True)
class OmctBounds:
    """Gain and phase boundaries per DOF (see the module docstring for the file format).

    Attributes
    ----------
    title : str
        What the bounds are.
    tables : dict of str to dict of str to ndarray
        DOF name (or ``default``) -> the five arrays of the file.
    path : str
        Where they were read from.

    """

    title: str
    tables: dict[str, dict[str, FloatArray]]
    path: str = ""

    def at(self, dof: str, w_rad_s: FloatArray) -> dict[str, FloatArray]:
        """Return the boundaries of ``dof`` at ``w_rad_s`` (log-frequency interpolation)."""
        table = self.tables.get(dof, self.tables.get("default"))
        if table is None:
            raise BoundsFileError(f"{self.path}: no bounds for {dof} and no [default] table")
        lw = np.log10(table["frequency_rad_s"])
        return {k: np.interp(np.log10(w_rad_s), lw, table[k]) for k in _KEYS[1:]}


def read_bounds(path: str | Path = EXAMPLE_BOUNDS) -> OmctBounds:
    """Read and check an OMCT boundaries file.

    Raises
    ------
    BoundsFileError
        Naming the file and what is wrong (missing file, bad TOML, wrong format, a missing or
        unknown key or table, arrays of different lengths, non-increasing frequencies, min
        above max).

    """
    p = Path(path)
    if not p.is_file():
        raise BoundsFileError(f"{p}: no such OMCT bounds file")
    data = read_toml(p, f"a {BOUNDS_FORMAT} TOML file", BoundsFileError)
    given = {k: v for k, v in data.items() if isinstance(v, dict)}
    keys = {k: v for k, v in data.items() if k not in given}
    if "format" not in data:  # a misspelt "format" is named as such
        check_keys(keys, _TOP_KEYS, str(p), BoundsFileError)
    if data.get("format") != BOUNDS_FORMAT:
        raise BoundsFileError(f"{p}: format must be {BOUNDS_FORMAT!r}; got {data.get('format')!r}")
    check_keys(keys, _TOP_KEYS, str(p), BoundsFileError)
    check_keys(given, ("default", *DOF_NAMES), str(p), BoundsFileError, "table")
    if not isinstance(data.get("title", ""), str):
        raise BoundsFileError(f"{p}: title must be text; got {data['title']!r}")
    tables = {}
    for name, table in given.items():
        check_keys(table, _KEYS, f"{p}: [{name}]", BoundsFileError)
        missing = [k for k in _KEYS if k not in table]
        if missing:
            raise BoundsFileError(f"{p}: [{name}] misses {', '.join(missing)}")
        arrays = {k: numbers(table[k], f"{p}: [{name}] {k}", min_size=2, error=BoundsFileError)
                  for k in _KEYS}  # fmt: skip
        sizes = {a.size for a in arrays.values()}
        if len(sizes) != 1 or sizes.pop() < 2:
            raise BoundsFileError(f"{p}: [{name}] arrays must have one equal length >= 2")
        if np.any(np.diff(arrays["frequency_rad_s"]) <= 0) or arrays["frequency_rad_s"][0] <= 0:
            raise BoundsFileError(f"{p}: [{name}] frequency_rad_s must be positive, increasing")
        if np.any(arrays["gain_min"] > arrays["gain_max"]) or np.any(
            arrays["phase_min_deg"] > arrays["phase_max_deg"]
        ):
            raise BoundsFileError(f"{p}: [{name}] a minimum lies above its maximum")
        tables[name] = arrays
    if not tables:
        raise BoundsFileError(f"{p}: no bounds tables ([default] or per DOF)")
    return OmctBounds(str(data.get("title", "")), tables, str(p))


@dataclass(frozen=True, eq=False)
class OmctResult(ResponseMixin):
    """OMCT points of one DOF.

    Attributes
    ----------
    dof : str
        Driven DOF.
    w_rad_s : ndarray
        OMCT frequencies measured [rad/s].
    response : ndarray of complex
        Describing function at each.
    analytic : ndarray of complex
        The configuration's Eq 5.11 at each.
    source : str
        What was measured.
    label : str
        Legend label.
    skipped : dict of float to str
        Frequencies not run (a platform limit) with the reason.

    """

    dof: str
    w_rad_s: FloatArray
    response: ComplexArray
    analytic: ComplexArray
    source: str
    label: str
    skipped: dict[float, str] = field(default_factory=dict)

    def check(self, bounds: OmctBounds) -> list[bool]:
        """Whether each point lies inside the boundaries."""
        b = bounds.at(self.dof, self.w_rad_s)
        return [
            bool(x)
            for x in (self.gain >= b["gain_min"])
            & (self.gain <= b["gain_max"])
            & (self.phase_deg >= b["phase_min_deg"])
            & (self.phase_deg <= b["phase_max_deg"])
        ]

    def to_dict(self, bounds: OmctBounds | None = None) -> dict[str, object]:
        """JSON-ready (with ``inside`` per point when bounds are given)."""
        out = {
            "test": "OMCT",
            "dof": self.dof,
            "label": self.label,
            "source": self.source,
            "frequencies_rad_s": self.w_rad_s.tolist(),
            "gain": self.gain.tolist(),
            "phase_deg": self.phase_deg.tolist(),
            "analytic_gain": np.abs(self.analytic).tolist(),
            "analytic_phase_deg": phase_deg(self.analytic).tolist(),
            "skipped": {str(w): why for w, why in self.skipped.items()},
        }
        if bounds is not None:
            out["inside"] = self.check(bounds)
            out["bounds"] = {"title": bounds.title, "path": bounds.path}
        return out

    def to_frame(self) -> pd.DataFrame:
        """One row per OMCT frequency: measured and Eq 5.11 gain and phase."""
        return frame({
            "frequency_rad_s": self.w_rad_s, "gain": self.gain, "phase_deg": self.phase_deg,
            "analytic_gain": np.abs(self.analytic), "analytic_phase_deg": phase_deg(self.analytic),
        })  # fmt: skip

    def to_frd(self) -> control.FrequencyResponseData:
        """Return the measured response at the OMCT frequencies, as python-control data (rad/s)."""
        return frd(self.response, self.w_rad_s, self.label or self.dof, rad_s=True)

    def plot(
        self, ax: AxesArg = None, *, path: str | None = None, bounds: OmctBounds | None = None
    ) -> Figure:
        """Gain and phase at the OMCT frequencies, with boundaries if given (Fig 5.12).

        Parameters
        ----------
        ax : sequence of two Axes, optional
            Gain and phase panels to draw on; a new figure by default.
        path : str, optional
            Save the figure here.
        bounds : OmctBounds, optional
            Boundaries to shade.

        Returns
        -------
        matplotlib.figure.Figure

        """
        return plot_omct([self], bounds, ax=ax, path=path)

    def format_table(self, bounds: OmctBounds | None = None) -> str:
        """Plain-text table."""
        inside = self.check(bounds) if bounds is not None else [None] * self.w_rad_s.size
        lines = [
            f"OMCT, {self.dof} ({self.source})",
            f"{'w [rad/s]':>10} {'gain':>7} {'phase':>7} {'Eq 5.11':>8} {'phase':>7}"
            + ("  inside" if bounds is not None else ""),
        ]
        pa = phase_deg(self.analytic)
        for w, g, p, ga, pha, ok in zip(
            self.w_rad_s, self.gain, self.phase_deg, np.abs(self.analytic), pa, inside, strict=True
        ):
            flag = "" if ok is None else ("  yes" if ok else "  NO")
            lines.append(f"{w:10.3f} {g:7.3f} {p:7.1f} {ga:8.3f} {pha:7.1f}{flag}")
        for w, why in self.skipped.items():
            lines.append(f"{w:10.3f} skipped: {why}")
        if bounds is not None:
            lines.append(f"bounds: {bounds.title} ({bounds.path})")
        return "\n".join(lines)


def plot_omct(
    results: Sequence[OmctResult],
    bounds: OmctBounds | None = None,
    *,
    ax: AxesArg = None,
    path: str | None = None,
) -> Figure:
    """Gain and phase of several OMCT results on one figure, with boundaries (Fig 5.12).

    ``ax``: gain and phase Axes to draw on (a new figure by default); ``path``: save here.
    """
    fig, (ax_g, ax_p) = subplots(ax, 2, 1, figsize=(6.5, 6), sharex=True, panels="gain, phase")
    if bounds is not None and results:
        w = np.geomspace(OMCT_RAD_S[0], OMCT_RAD_S[-1], 200)
        b = bounds.at(results[0].dof, w)
        ax_g.fill_between(w, b["gain_min"], b["gain_max"], color="0.9", label="bounds")
        ax_p.fill_between(w, b["phase_min_deg"], b["phase_max_deg"], color="0.9")
    for i, r in enumerate(results):
        ax_g.semilogx(r.w_rad_s, r.gain, "o-", ms=4, color=f"C{i}", label=r.label)
        ax_p.semilogx(r.w_rad_s, r.phase_deg, "o-", ms=4, color=f"C{i}")
    ax_g.set_ylabel("gain [-]")
    ax_p.set_ylabel("phase [deg]")
    ax_p.set_xlabel("frequency [rad/s]")
    title = f"OMCT, {results[0].dof}" if results else "OMCT"
    if bounds is not None:
        title += f"\nbounds: {bounds.title}"
    ax_g.set_title(title, fontsize=8)
    ax_g.legend(fontsize=7)
    return finish(fig, path)


def default_amplitude(dof: str, w_rad_s: float, platform: str, fraction: float = 0.1) -> float:
    """Acceleration amplitude of an OMCT sine: ``fraction`` of the DOF's system limit at w.

    As the Table 5.2 amplitudes (10 % of the system limits, §3.3.3), capped like them at
    0.2 m/s^2 and 1 rad/s^2; the system limit is that of :func:`twin.agard.snr.system_limit`.
    """
    cap = 1.0 if dof_index(dof) >= 3 else 0.2
    return min(cap, fraction * float(system_limit(platform, dof, w_rad_s / (2 * np.pi))))


def analyse_omct_point(m: Measurement, dof: str | None = None) -> tuple[float, complex]:
    """Return the describing function of a single-sine run: (w [rad/s], H)."""
    k = driven_dof(m, dof)
    f, window = periodic_design(m, k)
    if f.size != 1:
        raise SignalError(f"{m.source}: an OMCT point needs a single sine; got {f.size} lines")
    h = describing_function(m.t, m.commanded[:, k], m.measured[:, k], f, window)
    return float(2 * np.pi * f[0]), complex(h[0])


def run_omct(
    session: Session,
    dof: str,
    fraction: float = 0.1,
    w_rad_s: Sequence[float] = tuple(OMCT_RAD_S),
    window_s: float = 10.0,
    label: str | None = None,
) -> OmctResult:
    """Run one single sine per OMCT frequency in ``dof`` and collect the describing function.

    ``fraction`` (of the DOF's system limit, Fig 3.6) must lie in (0, 1].
    """
    number(fraction, "OMCT amplitude fraction of the system limit", lo=0, lo_open=True, hi=1,
           error=SignalError)  # fmt: skip
    cfg = session.bench.config
    ws, hs, skipped = [], [], {}
    session.expect(len(w_rad_s), f"OMCT {dof}")
    for w in w_rad_s:
        amp = default_amplitude(dof, w, cfg.platform, fraction)
        m = session.measure_sine(dof, w / (2 * np.pi), amp, window_s, f"omct-{dof}-{w:.3g}rad_s")
        if isinstance(m, str):
            skipped[float(w)] = m
            continue
        wi, h = analyse_omct_point(m, dof)
        ws.append(wi)
        hs.append(h)
    w_arr = np.asarray(ws)
    analytic = cfg.response_at_hz(w_arr / (2 * np.pi))[:, dof_index(dof)]
    return OmctResult(
        dof,
        w_arr,
        np.asarray(hs),
        analytic,
        session.bench.name,
        label or session.bench.name,
        skipped,
    )
