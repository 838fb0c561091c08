"""Runs with hidden physics: the generator the physical diagnosis is tested and measured on.

:func:`draw` picks, from a seed only, what a real platform's run differs in from its model,
*and* what is nominal varies too (a generator that varies only the hidden effect flatters the
diagnosis):

- the platform (MPI or SRS, nominal configuration with its noise) and the driven DOF (any);
- the hidden physics: a cabin 1.3-2 times heavier (mass and inertia: a new cockpit), one leg
  with one fault (gain 0.3-0.7, a servo lag of 10-60 ms, Coulomb friction of 150-1500 N, or
  play of 0.3-3 mm; any leg), or nothing (a clean run);
- the IMU's noise, 0.3-3 times the data sheet's (log-uniform);
- the run: Table 5.2 signal 1 or 2, its amplitudes times 0.5-1.2;
- the logs: with the leg lengths and forces (``actuators.csv``, ``forces.csv``) or with the
  IMU alone (half of the draws each).

:func:`record` simulates it on the full MuJoCo model and writes a ``twin-run/1`` folder whose
``meta.json`` names the nominal configuration only, as a real platform's recording would.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from twin.chain.config import MotionSystem, motion_system
from twin.chain.signals import describing_signal
from twin.chain.simulate import default_imu, prepare
from twin.core.errors import SignalError
from twin.core.frames import DOF_NAMES
from twin.diagnose.physical_vocabulary import PhysicalCause, configured
from twin.formats.run_folder import execute, run_meta

#: What :func:`draw` hides.
KINDS = ("payload", "leg", "clean")
#: A leg's faults and their ranges (drawn uniformly).
LEG_FAULTS = {"gain": (0.3, 0.7), "lag_s": (0.01, 0.06), "coulomb_n": (150.0, 1500.0),
              "play_m": (3e-4, 3e-3)}  # fmt: skip
PAYLOAD = (1.3, 2.0)
IMU_NOISE = (0.3, 3.0)
AMPLITUDE = (0.5, 1.2)
PLATFORMS = ("mpi", "srs")


@dataclass(frozen=True)
class HiddenPhysics:
    """One drawn run: the truth behind it and what it was recorded with.

    Attributes
    ----------
    seed : int
        The seed it was drawn from.
    config : MotionSystem
        The nominal configuration (what the run's ``meta.json`` names).
    dof : str
        The driven DOF.
    cause : PhysicalCause or None
        The hidden physics (None: a clean run).
    imu_noise : float
        The IMU's noise over the data sheet's.
    signal : int
        Table 5.2 signal.
    scale : float
        Factor on its amplitudes.
    logs : bool
        Whether the run has leg lengths and forces.

    """

    seed: int
    config: MotionSystem
    dof: str
    cause: PhysicalCause | None
    imu_noise: float
    signal: int
    scale: float
    logs: bool

    @property
    def truth(self) -> MotionSystem:
        """The configuration the run is simulated with."""
        return self.config if self.cause is None else configured(self.config, self.cause)

    def describe(self) -> str:
        """One line: the draw."""
        what = self.cause.describe() if self.cause is not None else "clean"
        logs = "IMU, legs, forces" if self.logs else "IMU only"
        return (
            f"seed {self.seed}: {self.config.platform} {self.dof}, {what}; IMU noise "
            f"x{self.imu_noise:.2f}, signal {self.signal} x{self.scale:.2f}, {logs}"
        )


def draw(seed: int, kind: str | None = None) -> HiddenPhysics:
    """Draw a run's hidden physics and nuisances from ``seed`` (see the module).

    Raises
    ------
    SignalError
        For an unknown ``kind``.

    """
    if kind is not None and kind not in KINDS:
        raise SignalError(f"unknown kind {kind!r}; expected one of {', '.join(KINDS)}")
    rng = np.random.default_rng(np.random.SeedSequence([seed, 45]))
    platform = str(rng.choice(PLATFORMS))
    dof = str(rng.choice(DOF_NAMES))
    kind = kind or str(rng.choice(KINDS))
    config = motion_system(platform)
    cause = None
    if kind == "payload":
        cause = PhysicalCause("payload", {"factor": float(rng.uniform(*PAYLOAD))})
    elif kind == "leg":
        fault = str(rng.choice(list(LEG_FAULTS)))
        leg = int(rng.integers(1, 7))
        cause = PhysicalCause("leg", {"leg": leg, fault: float(rng.uniform(*LEG_FAULTS[fault]))})
    noise = float(np.exp(rng.uniform(*np.log(IMU_NOISE))))
    signal = int(rng.integers(1, 3))
    scale = float(rng.uniform(*AMPLITUDE))
    logs = bool(rng.random() < 0.5)
    return HiddenPhysics(seed, config, dof, cause, noise, signal, scale, logs)


def record(hidden: HiddenPhysics, out: str | Path) -> Path:
    """Simulate a drawn run on the full model and write it (``meta.json`` names the nominal).

    Returns
    -------
    Path
        The run folder ``OUT/seed<seed>-<dof>``.

    """
    sig = describing_signal(hidden.signal, hidden.dof, settle_s=None, scale=hidden.scale)
    imu = default_imu(hidden.config.platform).with_noise(hidden.imu_noise)
    run = prepare(hidden.truth, sig.commands, "full", 7919 * hidden.seed + 1, imu)
    meta = run_meta(run, f"hidden-physics run, seed {hidden.seed}", hidden.config, sig)
    folder = Path(out) / f"seed{hidden.seed}-{hidden.dof}"
    execute(run, meta, folder, overwrite=True)
    if not hidden.logs:
        for name in ("actuators.csv", "forces.csv"):
            (folder / name).unlink(missing_ok=True)
    return folder


def judged(hidden: HiddenPhysics, findings: list) -> str:
    """Judge a diagnosis' findings against the truth of a draw.

    Parameters
    ----------
    hidden : HiddenPhysics
        The draw.
    findings : list of Finding
        The diagnosis' findings, the first the one a user acts on.

    Returns
    -------
    str
        ``right`` (the true cause named, or nothing for a clean run: for a payload, a
        ``payload`` or a ``platform_lag`` in the driven DOF counts), ``wrong`` (a cause named
        that is not the truth, e.g. a sensor effect for a heavier cabin), ``ambiguous`` (the
        first finding is flagged ambiguous and the truth is among its alternatives within the
        margin: the runs could not tell them apart, and the report says so) or ``none``
        (nothing named where something was hidden).

    """
    real = [f.extension for f in findings if f.extension.effect != "noise"]
    if hidden.cause is None:
        return "wrong" if real else "right"
    if not real:
        return "none"
    first = real[0]
    if hidden.cause.effect == "payload":
        ok = first.effect == "payload" or (
            first.effect == "platform_lag" and hidden.dof in first.dofs
        )
        truth = "payload"
    else:
        ok = first.effect == "leg" and int(first.value("leg")) == int(hidden.cause.value("leg"))
        truth = f"leg {int(hidden.cause.value('leg'))}:"
    if ok:
        return "right"
    top = next(f for f in findings if f.extension.effect != "noise")
    alternatives = top.evidence.get("alternatives") or []
    named = [" ".join(a.get("effects", [])) for a in alternatives]
    if top.evidence.get("ambiguous") and any(truth in n for n in named):
        return "ambiguous"
    return "wrong"
