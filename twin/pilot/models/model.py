"""The multi-channel pilot model of Chapter 2 (Fig 2.5, Eq 2.19-2.21, Table 2.1).

    H_pe(jw) = K_v (1 + tau_lead jw) e^{-jw tau_v} H_nm(jw)            (visual: error, rate)
    H_px(jw) = K_m (jw)^2 H_v(jw) e^{-jw tau_m} H_nm(jw)               (motion: roll accel.)
    H_v      = (1 + tau_v1 jw) / (1 + tau_v2 jw)                          (canals, Eq 2.19)
    H_nm     = w_nm^2 / (w_nm^2 + 2 zeta_nm w_nm jw + (jw)^2)             (Eq 2.20)
    n        = 0.2 (3 s + 1) / ((1.5 s + 1)(0.4 s + 1)) n_w               (remnant, Eq 2.21)

The pilot's control signal is u = H_pe e - H_px x + n (Eq 2.2's sign convention).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]

#: The seven parameters estimated in §2.5.2.4 (the canal dynamics are kept constant), in the
#: order of Table 2.3.
ESTIMATED = ("k_v", "tau_lead", "tau_v", "k_m", "tau_m", "zeta_nm", "omega_nm")

#: Eq 2.21: remnant shaping filter (numerator, denominator in s, highest power first).
REMNANT_FILTER = (np.array([0.6, 0.2]), np.polymul([1.5, 1.0], [0.4, 1.0]))


def neuromuscular(w: ArrayLike, omega_nm: float, zeta_nm: float) -> ComplexArray:
    """Return the neuromuscular dynamics of Eq 2.20 / Eq 6.6 at ``w`` [rad/s]."""
    s = 1j * np.asarray(w, dtype=float)
    return omega_nm**2 / (omega_nm**2 + 2 * zeta_nm * omega_nm * s + s**2)


@dataclass(frozen=True)
class RollPilot:
    """Table 2.1's pilot model parameters (defaults: the thesis' values).

    Attributes
    ----------
    k_v : float
        Visual perception gain K_v [-].
    tau_lead : float
        Visual lead time constant tau_vl [s].
    tau_v : float
        Visual perception time delay [s].
    k_m : float
        Motion perception gain K_m [-].
    tau_m : float
        Motion perception time delay [s].
    zeta_nm, omega_nm : float
        Neuromuscular damping [-] and frequency [rad/s].
    tau_v1, tau_v2 : float
        Vestibular (canal) lead and lag time constants [s] (Eq 2.19).

    """

    k_v: float = 0.17
    tau_lead: float = 2.93
    tau_v: float = 0.32
    k_m: float = 1.59
    tau_m: float = 0.29
    zeta_nm: float = 0.30
    omega_nm: float = 12.0
    tau_v1: float = 0.10
    tau_v2: float = 6.00

    def vector(self) -> FloatArray:
        """Return the estimated parameters (:data:`ESTIMATED`) as an array."""
        return np.array([getattr(self, n) for n in ESTIMATED])

    def with_vector(self, v: ArrayLike) -> RollPilot:
        """Return a copy with the estimated parameters replaced."""
        return dataclasses.replace(self, **dict(zip(ESTIMATED, map(float, v), strict=True)))

    def nm(self, w: ArrayLike) -> ComplexArray:
        """H_nm of Eq 2.20 at ``w`` [rad/s]."""
        return neuromuscular(w, self.omega_nm, self.zeta_nm)

    def h_pe(self, w: ArrayLike) -> ComplexArray:
        """Visual response to the error at ``w`` [rad/s]."""
        s = 1j * np.asarray(w, dtype=float)
        return self.k_v * (1 + self.tau_lead * s) * np.exp(-s * self.tau_v) * self.nm(w)

    def h_px(self, w: ArrayLike) -> ComplexArray:
        """Motion response to the roll angle (felt as roll acceleration) at ``w`` [rad/s]."""
        s = 1j * np.asarray(w, dtype=float)
        canals = (1 + self.tau_v1 * s) / (1 + self.tau_v2 * s)
        return self.k_m * s**2 * canals * np.exp(-s * self.tau_m) * self.nm(w)

    def rational_parts(self) -> dict[str, tuple[FloatArray, FloatArray, float]]:
        """(numerator, denominator, delay [s]) of each channel, for simulation."""
        nm_den = np.array([1.0, 2 * self.zeta_nm * self.omega_nm, self.omega_nm**2])
        w2 = self.omega_nm**2
        pe_num = self.k_v * w2 * np.array([self.tau_lead, 1.0])
        px_num = self.k_m * w2 * np.polymul([1.0, 0.0, 0.0], [self.tau_v1, 1.0])
        px_den = np.polymul(nm_den, [self.tau_v2, 1.0])
        return {"pe": (pe_num, nm_den, self.tau_v), "px": (px_num, px_den, self.tau_m)}


def roll_dynamics(w: ArrayLike) -> ComplexArray:
    """Return the controlled roll dynamics of Chapter 2, H_c = 4 / s^2, at ``w`` [rad/s]."""
    s = 1j * np.asarray(w, dtype=float)
    return 4.0 / s**2
