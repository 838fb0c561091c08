"""Runs with a hidden effect: the seeded generator the diagnosis is tested (and shown) on.

:func:`draw` picks, from a seed only, a platform (MPI or SRS with their nominal
configurations and noise), a DOF (heave or pitch) and one effect with random parameters;
:func:`record` simulates both Table 5.2 multi-sines through the nominal configuration *plus*
the effect and writes ``twin-run/1`` folders whose ``meta.json`` names only the nominal
configuration, as a real platform's recording would.

Drawing rule (parameters only where the runs could reveal them): a draw is kept when, on the
nominal twin's prediction of the two runs and its noise, (1) the effect's expected BIC
improvement (:func:`twin.diagnose.detect.expected_delta_bic`) is at least
``DETECTABLE_FACTOR`` times the naming threshold and (2) the Cramér-Rao standard deviation of
every parameter is at most a third of the test's tolerance (delay 5 ms, others 20 %), so that
a fit within tolerance is likely; otherwise it is drawn again (the count is returned).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from twin.chain.config import MotionSystem, motion_system
from twin.chain.extensions import DOF_CHANNEL, EFFECTS, Extension
from twin.chain.imu import ImuSpec
from twin.chain.simulate import prepare
from twin.diagnose.candidates import Model
from twin.diagnose.data import Case, Channel, clean_config, measurement_channels, nominal_imu
from twin.diagnose.detect import expected_delta_bic, fisher_std
from twin.diagnose.residuals import segment
from twin.diagnose.select import BIC_MARGIN
from twin.errors import SignalError
from twin.measurement.measure import from_imu
from twin.run_folder import execute, run_meta, signal_meta
from twin.signals import describing_signal

#: Expected evidence of a drawn effect, in multiples of the naming threshold.
DETECTABLE_FACTOR = 3.0
#: Tolerances of the hidden-effect tests: absolute for delay [s], relative otherwise.
TOLERANCE = {"extra_delay_s": 0.005}
RELATIVE_TOLERANCE = 0.2
PLATFORMS = ("mpi", "srs")
DOFS = ("heave", "pitch")


@dataclass(frozen=True)
class Hidden:
    """A drawn case.

    Attributes
    ----------
    seed : int
        The seed it was drawn from.
    config : MotionSystem
        Nominal configuration (what ``meta.json`` says).
    dof : str
        Driven DOF.
    extension : Extension or None
        The hidden effect (None: a clean run).
    redraws : int
        Draws rejected by the detectability rule.

    """

    seed: int
    config: MotionSystem
    dof: str
    extension: Extension | None
    redraws: int = 0

    @property
    def truth(self) -> MotionSystem:
        """The configuration the runs are simulated with (nominal + effect)."""
        if self.extension is None:
            return self.config
        return self.config.replace(extensions=(*self.config.extensions, self.extension))


def _parameters(effect: str, rng: np.random.Generator, config: MotionSystem, dof: str) -> dict:
    u = rng.uniform
    sign = rng.choice([-1.0, 1.0])
    if effect == "delay":
        return {
            "extra_delay_s": float(u(0.01, 0.08) if sign > 0 else -u(0.005, 0.9 * config.delay_s))
        }
    if effect == "gain":
        return {"gain": float(np.exp(sign * u(np.log(1.08), np.log(1.5))))}
    if effect == "platform_filter":
        if config.filter_break_hz is None:
            return {"break_hz": float(np.exp(u(np.log(1.0), np.log(8.0))))}
        f = config.filter_break_hz * np.exp(sign * u(np.log(1.25), np.log(2.5)))
        return {"break_hz": float(f)}
    if effect == "resonance":
        return {
            "frequency_hz": float(np.exp(u(np.log(2.0), np.log(9.0)))),
            "damping": float(u(0.1, 0.6)),
        }
    if effect == "lead":
        return {"time_constant_s": float(u(0.008, 0.05))}
    if effect == "sensor_filter":
        return {
            "cutoff_hz": float(np.exp(u(np.log(1.5), np.log(10.0)))),
            "channels": (DOF_CHANNEL[dof],),
        }
    if effect == "backlash":
        play = u(0.001, 0.006) if dof in ("surge", "sway", "heave") else np.radians(u(0.05, 0.4))
        return {"play": float(play)}
    if effect == "noise":
        return {"scale": float(np.exp(sign * u(np.log(1.3), np.log(3.0))))}
    raise SignalError(f"unknown effect {effect!r}")


def clean(seed: int) -> Hidden:
    """Draw a platform and DOF from ``seed`` with no effect (a run the nominal model explains)."""
    rng = np.random.default_rng(seed)
    return Hidden(seed, motion_system(str(rng.choice(PLATFORMS))), str(rng.choice(DOFS)), None)


def draw(seed: int, effect: str | None = None, max_redraws: int = 50) -> Hidden:
    """Draw a detectable hidden effect from ``seed`` (``effect`` fixes its type)."""
    rng = np.random.default_rng(seed)
    for attempt in range(max_redraws + 1):
        platform = str(rng.choice(PLATFORMS))
        dof = str(rng.choice(DOFS))
        kind = effect or str(rng.choice(list(EFFECTS)))
        config = motion_system(platform)
        ext = Extension(kind, _parameters(kind, rng, config, dof), (dof,))
        # nominal prediction and noise of the two runs, from the twin itself
        imu = nominal_imu({}, platform)
        channels = [_channel(config, dof, number, imu, seed) for number in (1, 2)]
        case = Case(config, "reduced", imu, channels, seed)
        base = Model(case, dof)
        segs = [segment(c) for c in channels]
        ok = expected_delta_bic(base, ext, segs) >= DETECTABLE_FACTOR * BIC_MARGIN
        if ok:
            for name, sd in fisher_std(base, ext, segs).items():
                tol = TOLERANCE.get(name, RELATIVE_TOLERANCE * abs(ext.value(name)))
                ok &= sd <= tol / 3
        if ok:
            return Hidden(seed, config, dof, ext, attempt)
    raise SignalError(f"seed {seed}: no detectable {effect or 'effect'} in {max_redraws} draws")


def _channel(config: MotionSystem, dof: str, number: int, imu: ImuSpec, seed: int) -> Channel:
    """Return the nominal prediction and noise of one Table 5.2 run (no file written)."""
    sig = describing_signal(number, dof, settle_s=None)
    sim = prepare(clean_config(config), sig.commands, "reduced", seed, imu.ideal()).collect()
    meta = {"signal": signal_meta(sig)}
    m = from_imu(sig.commands, sim.imu, f"nominal-{number}", config, meta)
    return measurement_channels(m, config, "reduced", imu, seed, 0, [dof], realisations=4)[0]


def record(
    hidden: Hidden,
    out: str | Path,
    model: str = "reduced",
    signals: tuple[int, ...] = (1, 2),
    with_signal_meta: bool = True,
) -> list[Path]:
    """Simulate the runs of a hidden case and write them (meta names the nominal only)."""
    return record_runs(
        hidden.truth, hidden.config, hidden.dof, out, hidden.seed, model, signals,
        with_signal_meta,
    )  # fmt: skip


def record_runs(
    truth: MotionSystem,
    nominal: MotionSystem,
    dof: str,
    out: str | Path,
    seed: int = 0,
    model: str = "reduced",
    signals: tuple[int, ...] = (1, 2),
    with_signal_meta: bool = True,
) -> list[Path]:
    """Simulate Table 5.2 multi-sines through ``truth``; write run folders that name ``nominal``.

    Parameters
    ----------
    truth, nominal : MotionSystem
        What the runs are simulated with, and what their ``meta.json`` says.
    dof : str
        Driven DOF.
    out : path
        Parent folder; runs are ``seed<seed>-<dof>-multisine<n>``.
    seed : int
        Seed (noise and IMU of run n use ``7919 seed + n``).
    model : str
        Platform model of the truth.
    signals : tuple of int
        Table 5.2 signals to run.
    with_signal_meta : bool
        Write the signal design into ``meta.json`` (without it the diagnosis infers it).

    """
    out = Path(out)
    folders = []
    for number in signals:
        sig = describing_signal(number, dof, settle_s=None)
        run = prepare(truth, sig.commands, model, 7919 * seed + number)
        meta = run_meta(
            run, f"hidden-effect run, seed {seed}", nominal, sig if with_signal_meta else None
        )
        folder = out / f"seed{seed}-{dof}-multisine{number}"
        execute(run, meta, folder, overwrite=True)
        folders.append(folder)
    return folders
