"""The residual figure of a diagnosis: what the models leave unexplained, in physical units.

Two panels for one run of one DOF. Top, *at the excited lines*: the amplitude of the residual
sinusoid, measured - model, for the nominal and the extended model, against the level that
noise alone exceeds in 5 % of lines. Bottom, *between the lines*: the residual's power
spectral density with the excited lines (and ``LEAKAGE_BINS`` bins either side) left out,
against the nominal noise model and the noise model scaled to the measurement. Kept apart,
a large line residual (a filter the nominal model lacks) no longer hides the noise floor as
a 9-bin smear over the lines did.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from twin.core.frames import dof_index
from twin.core.plotting import finish, subplots
from twin.diagnose.residuals import segment

FloatArray = NDArray[np.float64]
#: Bins either side of a line left out of the between-lines spectrum: the Hann taper's own
#: leakage is one bin, but a run's fades and transients put skirts of a few bins around
#: large lines (about 1 % of the line at 2-5 bins).
LEAKAGE_BINS = 6
#: Non-line bins averaged in the PSD (each side of a bin).
SMOOTH_BINS = 4


def unit_of(dof: str) -> str:
    """Return the unit of a DOF's measured acceleration."""
    return "m/s^2" if dof_index(dof) < 3 else "rad/s^2"


def plot_residual(d, dof: str, path: str | None = None):
    """Plot the residuals of ``dof`` in run 1 of a :class:`~twin.diagnose.diagnosis.Diagnosis`.

    Returns
    -------
    matplotlib.figure.Figure

    """
    r = d.dofs[dof]
    ch = d.case.of(dof)[0]
    seg = segment(ch, max_hz=d.max_hz)
    sum_w = float(seg.taper.sum())
    fs = ch.rate_hz
    to_psd = 2.0 / (fs * float(np.sum(seg.taper**2)))  # |rfft|^2 -> one-sided PSD [unit^2/Hz]
    df = seg.f[1] - seg.f[0]
    line_bins = np.unique(np.round((ch.lines_hz - seg.f[0]) / df).astype(int))
    line_bins = line_bins[(line_bins >= 0) & (line_bins < seg.f.size)]
    near = np.zeros(seg.f.size, dtype=bool)
    for k in range(-LEAKAGE_BINS, LEAKAGE_BINS + 1):
        near[np.clip(line_bins + k, 0, seg.f.size - 1)] = True
    between = np.flatnonzero(~near)
    unit = unit_of(dof)
    fig, (top, bottom) = subplots(None, 2, 1, figsize=(7, 6.5), sharex=True)
    models = (("nominal", ch.nominal, "C0", "o"), ("extended", r.model.predict(ch), "C1", "s"))
    for label, pred, colour, marker in models:
        resid = seg.measured - seg.spectrum(pred)
        # a sinusoid of amplitude A gives |X| = A sum(w) / 2 under the taper
        top.semilogy(seg.f[line_bins], 2 * np.abs(resid[line_bins]) / sum_w, marker,
                     color=colour, mfc="none" if label == "extended" else colour,
                     label=f"measured - {label}")  # fmt: skip
        psd = np.abs(resid[between]) ** 2 * to_psd
        kernel = np.ones(2 * SMOOTH_BINS + 1)
        # a mean over the bins that exist (no zero padding drooping the ends)
        smooth = np.convolve(psd, kernel, "same") / np.convolve(np.ones(psd.size), kernel, "same")
        bottom.loglog(seg.f[between], smooth, "-", color=colour, lw=1,
                      label=f"measured - {label}")  # fmt: skip
    # noise alone: |X|^2 is exponential with mean S, exceeded by ln(20) S in 5 % of lines
    # (the scaled noise model: where a sensor filter was found, the level is an upper one)
    noise = seg.scaled(r.noise.fit.scales).noise_psd
    top.semilogy(seg.f[line_bins], 2 * np.sqrt(np.log(20.0) * noise[line_bins]) / sum_w, "k_",
                 ms=10, label="noise exceeds this in 5 % of lines")  # fmt: skip
    bottom.loglog(seg.f[between], seg.noise_psd[between] * to_psd, "k--", lw=1,
                  label="nominal noise model")  # fmt: skip
    bottom.loglog(seg.f[between], noise[between] * to_psd, "k:", lw=1,
                  label="noise model scaled to the measurement (nominal shape: a sensor filter "
                        "found is not applied to it)")  # fmt: skip
    top.set_ylabel(f"residual amplitude [{unit}]")
    top.set_title(f"{dof}: residuals of run 1 - at the excited lines", fontsize=9)
    bottom.set_title(f"between the lines ({2 * SMOOTH_BINS + 1}-bin mean)", fontsize=9)
    bottom.set_ylabel(f"residual PSD [({unit})^2/Hz]")
    bottom.set_xlabel("frequency [Hz]")
    for ax in (top, bottom):
        ax.grid(True, which="major", alpha=0.5)
        ax.grid(True, which="minor", alpha=0.2)
        ax.legend(fontsize=7)
    return finish(fig, path, dpi=110)
