"""Expected evidence between explanations where one has a backlash: simulated, then refitted.

A backlash's describing function depends on the amplitude, so the evidence a run would give
between it and another explanation has no closed form (the linear pairs':
:mod:`twin.diagnose.design`). Here it is computed as the diagnosis would find it: the old runs
and a candidate run are simulated noise-free with explanation ``i`` (the chain's order: the
effects that shape the motion before the backlash, the backlash, the others' responses), the
other explanation ``j`` is fitted to them by the diagnosis's own fit
(:func:`twin.diagnose.candidates.fit_set`, its play searched by simulation where ``j`` has a
backlash), each line weighted by its noise (measured in the old runs; the design's estimate
for the new one), and twice the chi-square ``j`` leaves is the expected BIC difference: the
same quantity, with the same refit, as the linear pairs'.

Simulations are cached (one cache for every pair and candidate, keyed by run, window, play and
the effects simulated with it), and the truth of each explanation on each run is simulated
once. An explanation the chain cannot run in its order (a pole beyond a run's Nyquist
frequency) is simulated in the fast form, as the diagnosis fitted it then.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from twin.chain.extensions import Extension
from twin.chain.signals import DescribingSignal
from twin.core.errors import SignalError
from twin.core.frames import dof_index
from twin.diagnose.candidates import BEFORE_BACKLASH, Model, at_bounds, fit_set
from twin.diagnose.data import Case, Channel
from twin.diagnose.evidence import Lines, line_amplitudes, measured_line_sd
from twin.measurement.measure import ANALYSIS_RATE_HZ, simulate_measurement

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]


def has_backlash(extensions: Sequence[Extension]) -> bool:
    """Return whether a set of extensions holds a backlash (a response that needs simulating)."""
    return any(x.effect == "backlash" for x in extensions)


class SimulatedEvidence:
    """Expected evidence of the old runs plus a candidate run, each explanation simulated.

    Parameters
    ----------
    case : Case
        The diagnosed runs (their commands, measured noise and nominal predictions).
    dof : str
        The DOF the design is for.
    max_hz : float
        Lines above it are left out (the diagnosis's band).

    """

    def __init__(self, case: Case, dof: str, max_hz: float = np.inf) -> None:
        self.case, self.dof, self.max_hz = case, dof, max_hz
        self.cache: dict = {}
        self.old = [self._lines(ch, measured_line_sd(ch)) for ch in case.of(dof)]
        self._truths: dict[tuple, ComplexArray] = {}

    def _lines(self, ch: Channel, sd: FloatArray) -> Lines:
        keep = ch.lines_hz <= self.max_hz
        f = ch.lines_hz[keep]
        p = line_amplitudes(ch.t, ch.nominal, f, ch.window)
        return Lines(ch, ch.window, f, p, p, np.asarray(sd, dtype=float)[keep])

    def model(self, extensions: Sequence[Extension] = ()) -> Model:
        """Return a model of the DOF with ``extensions``, in the chain's order, sharing the cache.

        Effects that shape the motion before a backlash are simulated with it (the chain's
        order: :meth:`twin.diagnose.candidates.Model.anchored`); the others act as responses.
        """
        exts = list(extensions)
        m = Model(self.case, self.dof, exts, (), self.cache)
        if has_backlash(exts):
            shaping = [e for e in exts if e.effect in BEFORE_BACKLASH]
            if shaping:
                m = m.anchored(shaping)
        return m

    def candidate(
        self, sig: DescribingSignal, sd: FloatArray, name: str, filter_scale: float = 1.0
    ) -> Lines:
        """Return the lines of a candidate run: the nominal twin simulated on its commands.

        ``sd``: the noise expected of each line's amplitude over the run's window;
        ``filter_scale``: the run's platform-filter setting over the nominal's.
        """
        cmd = sig.commands
        t = np.arange(round(cmd.duration * ANALYSIS_RATE_HZ)) / ANALYSIS_RATE_HZ
        pred = simulate_measurement(
            self.case.clean.filter_scaled(filter_scale), cmd, t, self.case.model,
            self.case.seed, self.case.imu.ideal(),
        )  # fmt: skip
        k = dof_index(self.dof)
        lines_hz = np.asarray(sig.frequencies_hz, dtype=float)
        ch = Channel(name, self.dof, t, pred[:, k], pred[:, k], np.zeros((2, 1, t.size)),
                     lines_hz, tuple(sig.window), cmd, filter_scale)  # fmt: skip
        return self._lines(ch, sd)

    def truth(self, extensions: Sequence[Extension], lines: Lines) -> ComplexArray:
        """Return the line amplitudes of one run if ``extensions`` were true (noise-free)."""
        key = (lines.channel.run, lines.channel.filter_scale, lines.window, tuple(lines.f),
               tuple((e.effect, repr(e.parameters), e.dofs) for e in extensions))  # fmt: skip
        if key not in self._truths:
            try:
                self._truths[key] = self.model(extensions).line_prediction(lines)
            except SignalError:  # not in the chain's order: the fast form, as the fit did
                fast = Model(self.case, self.dof, list(extensions), (), self.cache)
                self._truths[key] = fast.line_prediction(lines)
        return self._truths[key]

    def evidence(
        self, truth: Sequence[Extension], other: Sequence[Extension], new: Lines | None
    ) -> float | None:
        """Return the expected evidence against ``other`` (refitted) if ``truth`` holds.

        Over the old runs and ``new`` (None: the old runs only). None where the refit lies at
        an end of a parameter's search: then it is no explanation (the diagnosis never names
        such a fit).
        """
        runs = [*self.old, *([new] if new is not None else [])]
        evidence = [
            Lines(x.channel, x.window, x.f, self.truth(truth, x), x.nominal, x.sd) for x in runs
        ]
        base = Model(self.case, self.dof, [], (), self.cache)
        if not other:  # nothing to refit: the nominal twin
            return 2.0 * base.chi2(evidence)
        fit = fit_set([e.effect for e in other], base, evidence)
        if at_bounds(fit, base, evidence):
            return None
        return 2.0 * fit.chi2
