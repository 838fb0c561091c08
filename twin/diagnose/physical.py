"""Physical causes fitted by simulating the full MuJoCo model: payload, one leg, the IMU.

The chain's effects are fitted on their line responses (:mod:`twin.diagnose.candidates`);
a physical cause (:mod:`twin.diagnose.physical_vocabulary`) has none: a heavier cabin, a weak
or sticky leg shape the motion through the platform's rigid-body dynamics, its PD and its
closed kinematic loop, in every DOF at once. So each is fitted by simulating the full model,
on every channel the runs have (:mod:`twin.diagnose.physical_evidence`):

1. *Screening.* The nominal model and each candidate at a probe value (the payload factor,
   each leg's gain, lag, friction and play: 25 simulations per run, run concurrently; the
   MuJoCo physics of each releases the GIL) give each candidate's standardised change of the
   evidence, d. Linearised, the residual r is fitted by a d: the value a = <r, d> / <d, d>
   and the fall of chi2 <r, d>^2 / <d, d>. The IMU's alignment needs no simulation: the
   nominal IMU samples are rotated (three small rotations, fitted jointly, a linear model).
2. *Refinement.* The :data:`REFINE` candidates that screening ranks best are fitted by a
   one-dimensional search of simulations (a bracket around the linearised value in the log of
   the parameter's change, a parabola through it, the value at its vertex simulated).
3. *Selection.* With chi2 = -log L as for the chain's effects, BIC = 2 chi2 + p ln n; the best
   candidate is named when it beats the nominal model by ``BIC_MARGIN`` (10) and its fit on
   each half of the measurement window improves the other half (the held-out gate). The
   candidates within the margin of it are reported as its alternatives: the runs cannot tell
   them apart. A value at its search range's end is reported "at the bound", not named.
4. *Detectability.* The screening also says what the runs could have shown: the smallest
   change of each parameter whose expected BIC improvement reaches the margin (linearised
   at the probe), per leg and per kind ("a leg's friction below 900 N could not have been
   seen in these runs").

What each source contributed (the driven DOF's channel, the undriven DOFs, the leg lengths,
the leg forces) is the fall of chi2 in each, reported with the finding.

Why not ``mujoco.sysid``: its optimiser is SciPy's least squares on time-domain residuals
with parameters edited on an ``MjSpec`` per evaluation. The twin's evidence is the excited
lines standardised by the measurement's own noise, its physics edits (a payload by
``MjSpec``, a leg's gain, friction, lag and play) are :mod:`twin.platform`'s and its
candidates are one-parameter each (a search of a few simulations, run concurrently), and the
toolbox's extra dependencies (plotly, imageio with ffmpeg, jinja2) are not the twin's.
"""

from __future__ import annotations

import threading
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import partial

import numpy as np
from numpy.typing import NDArray

from twin.chain.config import MotionSystem
from twin.chain.extensions import Extension, imu_rotation
from twin.chain.imu import ImuRecord, ImuSpec, rotate_readings
from twin.core.errors import SignalError
from twin.core.progress import ProgressFn
from twin.core.threads import concurrently
from twin.diagnose.candidates import numeric_names
from twin.diagnose.physical_evidence import Block, Simulated, blocks, reread, simulate_run
from twin.diagnose.physical_vocabulary import (
    ALIGNMENT,
    LEG_KINDS,
    SEARCH,
    PhysicalCause,
    configured,
    nominal_value,
)
from twin.diagnose.select import BIC_MARGIN, Finding
from twin.formats.runs import RecordedRun
from twin.measurement.measure import Measurement

FloatArray = NDArray[np.float64]
#: Candidates refined by simulation after the screening.
REFINE = 3
#: Factor between the points of the refinement's bracket (on the parameter's change).
BRACKET = 1.6
#: The stated preference that names a physical cause slightly behind an undecided sensor filter.
UNDECIDED_SENSOR = (
    "named before the chain's sensor filter although its BIC is slightly lower: the two are "
    "within the margin, and the noise could not tell whether the filter is in the sensor "
    "(a stated preference for the platform side, which predicts every channel)"
)
#: What each source of evidence is, in a report (:meth:`Block.source_of`'s labels).
SOURCE_TEXT = {"driven": "the driven DOF's IMU channel", "undriven": "the undriven DOFs' IMU "
               "channels (parasitic motion)", "legs": "the leg lengths (actuators.csv)",
               "forces": "the leg forces (forces.csv)"}  # fmt: skip


def rotated(record: ImuRecord, angles: Sequence[float]) -> ImuRecord:
    """Return an (ideal) IMU's record as axes rotated by (roll, pitch, yaw) [rad] read it.

    The ``imu_alignment`` extension's rotation (:func:`twin.chain.extensions.imu_rotation`)
    applied to the readings, which for an ideal IMU is what the rotated IMU reads.
    """
    angles = {n: float(a) for n, a in zip(ALIGNMENT, angles, strict=True)}
    r = imu_rotation([Extension("imu_alignment", angles)])
    values = rotate_readings(np.hstack([record.accel, record.gyro]), r)
    return ImuRecord(record.t, values[:, :3], values[:, 3:], record.saturated)


@dataclass
class Candidate:
    """One physical candidate: the cause at any value of its one parameter.

    Attributes
    ----------
    effect : str
        ``payload`` or ``leg``.
    name : str
        The parameter (``factor``, ``gain``, ``lag_s``, ``coulomb_n``, ``play_m``).
    leg : int or None
        The leg (1-6).
    nominal : float
        The parameter's nominal value.

    """

    effect: str
    name: str
    leg: int | None
    nominal: float
    points: dict[float, dict[str, float]] = field(default_factory=dict)  # value -> chi2s
    sims: dict[float, list[Simulated]] = field(default_factory=dict, repr=False)
    direction: FloatArray | None = field(default=None, repr=False)
    linearised: float | None = None
    halves: dict[str, float] = field(default_factory=dict)  # the value fitted on each half

    def cause(self, value: float, dofs: tuple[str, ...] = ()) -> PhysicalCause:
        """Return the cause at ``value``."""
        params = (
            {"factor": value} if self.effect == "payload" else {"leg": self.leg, self.name: value}
        )
        return PhysicalCause(self.effect, params, dofs)

    @property
    def label(self) -> str:
        """E.g. ``leg 3 coulomb_n`` or ``payload factor``."""
        return f"leg {self.leg} {self.name}" if self.effect == "leg" else "payload factor"

    @property
    def probe(self) -> float:
        """The screening value."""
        return SEARCH[self.name][0]

    @property
    def bounds(self) -> tuple[float, float]:
        """The search range."""
        return SEARCH[self.name][1], SEARCH[self.name][2]


def candidates(config: MotionSystem) -> list[Candidate]:
    """Return the payload and every leg's faults of a configuration (its values as nominal)."""
    out = []
    if config.physics is None or config.physics.payload is None:  # one payload at a time
        out.append(Candidate("payload", "factor", None, 1.0))
    for leg in range(1, 7):
        for kind in LEG_KINDS:
            out.append(Candidate("leg", kind, leg, nominal_value(config, kind, leg)))
    return out


@dataclass
class Calibration:
    """The runs, their evidence and the simulations of candidate physics.

    Parameters
    ----------
    config : MotionSystem
        The nominal configuration.
    runs : sequence of (RecordedRun, Measurement)
        The runs as read and as post-processed.
    imu : ImuSpec
        The nominal IMU.
    seed : int
        Seed of the simulations' bookkeeping (they are noise-free).
    max_hz : float
        Top of the band.
    progress : callable, optional
        Called with a count of the simulations done.
    filter_scales : sequence of float
        Each run's platform-filter setting over the nominal's (empty: all at the nominal's;
        :meth:`twin.diagnose.data.Case.config_of`).

    """

    config: MotionSystem
    runs: Sequence[tuple[RecordedRun, Measurement]]
    imu: ImuSpec
    seed: int
    max_hz: float
    progress: ProgressFn | None = None
    filter_scales: Sequence[float] = ()
    done: int = 0
    total: int = 0

    def __post_init__(self) -> None:
        if self.filter_scales and len(self.filter_scales) != len(self.runs):
            raise SignalError(
                f"filter_scales: one per run ({len(self.runs)}); got {len(self.filter_scales)}"
            )
        self.nominal = self.simulate([self.config])[0]
        self.evidence: dict[str, list[Block]] = {"full": [], "half1": [], "half2": []}
        for i, (rec, m) in enumerate(self.runs):
            for kind, bl in blocks(i, rec, m, self.nominal[i], self.max_hz).items():
                self.evidence[kind] += bl
        self.observations = int(sum(2 * b.measured.size for b in self.evidence["full"]))
        self.labels = np.concatenate([b.source_of() for b in self.evidence["full"]])

    @property
    def driven(self) -> tuple[str, ...]:
        """The driven DOFs of the runs."""
        return tuple(dict.fromkeys(b.driven for b in self.evidence["full"]))

    def simulate(self, configs: Sequence[MotionSystem]) -> list[list[Simulated]]:
        """Simulate every run through each configuration, concurrently."""
        jobs = [(c, r) for c in configs for r in range(len(self.runs))]
        self.total += len(jobs)
        lock = threading.Lock()  # local: a result that holds this calibration pickles

        def one(cfg: MotionSystem, r: int) -> Simulated:
            scale = self.filter_scales[r] if self.filter_scales else 1.0
            sim = simulate_run(cfg.filter_scaled(scale), self.runs[r][1], self.imu, self.seed)
            with lock:
                self.done += 1
                if self.progress:
                    self.progress("physical calibration [simulations]", self.done, self.total)
            return sim

        flat = concurrently([partial(one, cfg, r) for cfg, r in jobs])
        n = len(self.runs)
        return [flat[i * n : (i + 1) * n] for i in range(len(configs))]

    def residuals(self, sims: Sequence[Simulated], kind: str = "full") -> FloatArray:
        """Standardised residuals of a simulation of the runs over the windows of ``kind``."""
        return np.concatenate([b.residuals(sims[b.run].series) for b in self.evidence[kind]])

    def chi2(self, sims: Sequence[Simulated]) -> dict[str, float]:
        """chi2 (= -log L) over the full windows and each half."""
        return {k: float(np.sum(self.residuals(sims, k) ** 2)) for k in self.evidence}

    def by_source(self, sims: Sequence[Simulated]) -> dict[str, float]:
        """chi2 over the full windows, per source of evidence (:meth:`Block.source_of`)."""
        r = self.residuals(sims)
        return {s: float(np.sum(r[self.labels == s] ** 2)) for s in np.unique(self.labels)}

    def rotated(self, angles: Sequence[float]) -> list[Simulated]:
        """Return the nominal simulations read by an IMU rotated by ``angles``."""
        return [reread(sim, rotated(sim.imu, angles), self.config, m)
                for sim, (_, m) in zip(self.nominal, self.runs, strict=True)]  # fmt: skip


def _alternative(describe: str, delta_bic: float, named: float) -> dict[str, object]:
    """Return an explanation within the margin of the named one (the chain's alternatives' form)."""
    return {"effects": [describe], "delta_bic": delta_bic,
            "delta_bic_below_named": named - delta_bic}  # fmt: skip


def _bic(chi2_0: float, chi2_1: float, p: int, n: int) -> float:
    return 2.0 * (chi2_0 - chi2_1) - p * np.log(n)


def _distinct(x: FloatArray) -> int:
    """Return how many values of ``x`` differ by more than 1e-9 of their largest magnitude."""
    xs = np.sort(np.asarray(x, dtype=float))
    return 1 + int(np.sum(np.diff(xs) > 1e-9 * max(float(np.abs(xs).max()), 1e-300)))


def _fitted(x: FloatArray, y: FloatArray, deg: int) -> tuple[FloatArray, float, float]:
    """Return a least-squares polynomial in (x - centre) / spread, its centre and spread."""
    centre, spread = float(np.mean(x)), max(float(np.ptp(x)), 1e-300)
    return np.polyfit((x - centre) / spread, y, deg), centre, spread


def _parabola_min(x: FloatArray, y: FloatArray) -> float | None:
    """Return the least-squares parabola's vertex through (x, y) if a minimum, else None."""
    if _distinct(x) < 3:
        return None
    (a, b, _), centre, spread = _fitted(x, y, 2)
    return float(centre - spread * b / (2 * a)) if a > 0 else None


@dataclass
class PhysicalResult:
    """What the physical calibration found.

    Attributes
    ----------
    finding : Finding or None
        The named physical cause (None: none beat the nominal model by the margin).
    table : list of dict
        Every candidate refined: cause, dBIC, held-out chi2 per line, at bound.
    screening : list of dict
        Every candidate's linearised value and fall of chi2.
    detectable : dict
        Per kind of physical effect: the smallest change the runs could have shown.
    observations : int
        Real observations (2 x lines x channels).
    sources : list of str
        The sources of evidence the runs had.
    chi2_nominal : float
        chi2 of the nominal model.
    simulations : int
        Full-model simulations run.

    """

    finding: Finding | None
    table: list[dict[str, object]]
    screening: list[dict[str, object]]
    detectable: dict[str, dict[str, object]]
    observations: int
    sources: list[str]
    chi2_nominal: float
    simulations: int
    calibration: Calibration = field(repr=False)
    chain: dict[str, object] | None = None
    preferred: bool = False

    def delta_bic(self, sims: Sequence[Simulated], parameters: int) -> float:
        """BIC improvement over the nominal model of another simulation of the runs."""
        chi2 = self.calibration.chi2(sims)["full"]
        return _bic(self.chi2_nominal, chi2, parameters, self.observations)

    def weigh(
        self,
        chain: MotionSystem | None,
        findings: Sequence[Finding],
        annotate: Sequence[Finding] = (),
    ) -> None:
        """Weigh the physical finding against the chain's findings on the same evidence.

        The chain's extended configuration is simulated on the full model like a physical
        candidate (its legs and undriven DOFs move too) and scored on every channel. The
        physical finding is preferred when its BIC is at least as good. Within
        ``BIC_MARGIN`` of each other the runs cannot tell the two apart: each is listed as the
        other's alternative (``ambiguous``), and the physical cause is named first also when
        it is slightly behind if the chain's findings are sensor filters whose side the noise
        left undecided (:mod:`twin.diagnose.sensor_side`): the one evidence that could put
        the cause in the sensor was inconclusive, and the platform side has a mechanism that
        predicts every channel (a stated preference, reported with the finding). Sets
        :attr:`preferred` and :attr:`chain`.

        Parameters
        ----------
        chain : MotionSystem or None
            The nominal configuration with the chain's findings (None: it found nothing).
        findings : sequence of Finding
            The chain's findings (the motion noise's left out).
        annotate : sequence of Finding
            The findings to list the physical cause beside when the two are within the
            margin (the per-DOF ones: :attr:`Diagnosis.findings` merges them anew).

        """
        describe = "; ".join(f.extension.describe() for f in findings)
        if chain is not None:
            parameters = sum(len(numeric_names(f.extension.effect)) for f in findings)
            sims = self.calibration.simulate([chain])[0]
            self.simulations = self.calibration.total
            self.chain = {"describe": describe, "parameters": parameters,
                          "delta_bic": self.delta_bic(sims, parameters)}  # fmt: skip
        if self.finding is None:
            return
        rival = float(self.chain["delta_bic"]) if self.chain else 0.0  # type: ignore[arg-type]
        close = self.chain is not None and abs(self.finding.delta_bic - rival) < BIC_MARGIN
        undecided = bool(findings) and all(
            f.extension.effect == "sensor_filter"
            and (f.evidence.get("side") or {}).get("verdict") == "undecided"  # type: ignore[union-attr]
            for f in findings
        )
        self.preferred = self.finding.delta_bic >= rival or (close and undecided)
        if not close:
            return
        alternatives: list = self.finding.evidence["alternatives"]  # type: ignore[assignment]
        alternatives.append(_alternative(f"the chain's findings: {describe}", rival,
                                         self.finding.delta_bic))  # fmt: skip
        self.finding.evidence["ambiguous"] = True
        if self.preferred and self.finding.delta_bic < rival:
            self.finding.evidence["preference"] = UNDECIDED_SENSOR
        for f in annotate:  # the chain's, named or not, list the physical cause beside them
            f.evidence.setdefault("alternatives", []).append(  # type: ignore[union-attr]
                _alternative(self.finding.extension.describe(), self.finding.delta_bic, rival)
            )
            f.evidence["ambiguous"] = True

    @property
    def chain_supported(self) -> bool:
        """Whether the chain's findings beat the nominal by the margin on every channel too.

        With the physics weighed, every cause named must beat the full nominal model by
        ``BIC_MARGIN`` on the same evidence; chain findings that do not are not named.
        """
        return self.chain is None or float(self.chain["delta_bic"]) > BIC_MARGIN  # type: ignore[arg-type]

    def weak(self) -> list[tuple[str, float]]:
        """Return the explanations with some support below the margin (description, dBIC)."""
        out = [(str(e["describe"]), float(e["delta_bic"])) for e in self.table]  # type: ignore[arg-type]
        if self.chain is not None:
            out.append((f"the chain's findings: {self.chain['describe']}",
                        float(self.chain["delta_bic"])))  # type: ignore[arg-type]  # fmt: skip
        named = self.finding.delta_bic if self.finding is not None else np.inf
        return sorted(((d, b) for d, b in out if 0 < b <= BIC_MARGIN and b < named),
                      key=lambda x: -x[1])  # fmt: skip

    def statements(self) -> list[str]:
        """Return what the runs could have shown of the physical effects."""
        return [str(d["statement"]) for d in self.detectable.values()]

    def to_json(self) -> dict[str, object]:
        """JSON-ready summary (the finding is in the diagnosis' ``findings``)."""
        return {
            "criterion": "one physical cause at a time, fitted by simulating the full MuJoCo "
            f"model on every channel the runs have; named when its BIC improves by > "
            f"{BIC_MARGIN:g} and its fit on each half of the window improves the other",
            "sources": self.sources,
            "observations": self.observations,
            "simulations": self.simulations,
            "candidates": self.table,
            "chain_findings_on_all_channels": self.chain,
            "named": self.finding.extension.describe() if self.finding else None,
            "preferred_to_chain": self.preferred,
            "chain_findings_supported": self.chain_supported,
            "below_the_margin": [{"describe": d, "delta_bic": b} for d, b in self.weak()],
            "screening": self.screening,
            "detectable": self.detectable,
        }


def calibrate(
    config: MotionSystem,
    runs: Sequence[tuple[RecordedRun, Measurement]],
    imu: ImuSpec,
    seed: int = 0,
    max_hz: float = 15.0,
    progress: ProgressFn | None = None,
    filter_scales: Sequence[float] = (),
) -> PhysicalResult:
    """Fit the physical vocabulary to recorded runs on the full model (see the module).

    Parameters
    ----------
    config : MotionSystem
        The nominal configuration.
    runs : sequence of (RecordedRun, Measurement)
        The runs as read (:func:`twin.formats.run_checks.read_plausible_run`) and post-processed.
    imu : ImuSpec
        The nominal IMU.
    seed : int
        Seed (the simulations are noise-free).
    max_hz : float
        Top of the analysis band [Hz].
    progress : callable, optional
        Called with the count of simulations.
    filter_scales : sequence of float
        Each run's platform-filter setting over the nominal's (empty: the nominal's).

    """
    cal = Calibration(config, runs, imu, seed, max_hz, progress, filter_scales)
    r0 = cal.residuals(cal.nominal)
    chi2_0 = cal.chi2(cal.nominal)
    cands = candidates(config)
    probes = cal.simulate([configured(config, c.cause(c.probe)) for c in cands])
    screening = []
    for c, sims in zip(cands, probes, strict=True):
        c.sims[c.probe] = sims
        c.points[c.probe] = cal.chi2(sims)
        c.direction = r0 - cal.residuals(sims)  # standardised change of the prediction
        screening.append(_screen(c, r0))
    align = _alignment(cal, r0)
    screening.append(align["screen"])
    detectable = _detectability(cands, align, cal, config)
    ranked = sorted((s for s in screening[:-1] if s["linearised_value"] is not None),
                    key=lambda s: -float(s["chi2_fall"]))  # fmt: skip
    chosen = [c for c in cands if any(s["candidate"] == c.label for s in ranked[:REFINE])]
    _refine(cal, chosen, config)
    for c in chosen:
        c.halves = _half_fits(c)
    halves = [[v for v in dict.fromkeys(c.halves.values()) if v not in c.points] for c in chosen]
    _score(cal, chosen, halves, config)  # each half's fit, scored on the other: held out
    table = [_entry(c, cal, chi2_0) for c in chosen] + [align["entry"]]
    table.sort(key=lambda e: -float(e["delta_bic"]))  # type: ignore[arg-type]
    finding = _name(table, cal)
    sources = sorted(set(cal.labels.tolist()))
    cal.progress = None  # a result travels (a task's, pickled): no callback of the caller's
    return PhysicalResult(finding, [_public(e) for e in table], screening, detectable,
                          cal.observations, sources, chi2_0["full"], cal.total, cal)  # fmt: skip


def _screen(c: Candidate, r0: FloatArray) -> dict[str, object]:
    """Return the linearised fit of one candidate from its probe's change ``d``."""
    d = c.direction
    dd = float(d @ d)
    a = float(r0 @ d) / dd if dd > 0 else 0.0
    value = c.nominal + a * (c.probe - c.nominal)
    lo, hi = c.bounds
    clipped = float(np.clip(value, lo, hi)) if dd > 0 else c.nominal
    # refined wherever the linearised fit moves it off nominal, either way and clipped to the
    # range (a value beyond it is then fitted at the bound and reported so, not dropped)
    c.linearised = clipped if abs(clipped - c.nominal) > 1e-12 else None
    return {"candidate": c.label, "linearised_value": c.linearised,
            "chi2_fall": float(r0 @ d) ** 2 / dd if dd > 0 else 0.0,
            "probe": c.probe, "probe_visibility": dd}  # fmt: skip


def _alignment(cal: Calibration, r0: FloatArray) -> dict[str, object]:
    """Fit the IMU's three small rotations jointly (linear in the angles)."""
    step = SEARCH["angle_rad"][0]
    cols = []
    for axis in range(3):
        angles = np.zeros(3)
        angles[axis] = step
        cols.append((r0 - cal.residuals(cal.rotated(angles))) / step)
    d = np.column_stack(cols)
    angles, *_ = np.linalg.lstsq(d, r0, rcond=None)
    lo, hi = SEARCH["angle_rad"][1:3]
    angles = np.clip(angles, lo, hi)
    sims = cal.rotated(angles)
    chi2 = cal.chi2(sims)
    held = {}
    for fit_on, score_on in (("half1", "half2"), ("half2", "half1")):
        rf = cal.residuals(cal.nominal, fit_on)
        df = np.column_stack([(rf - cal.residuals(cal.rotated(np.eye(3)[k] * step), fit_on))
                              / step for k in range(3)])  # fmt: skip
        a_half, *_ = np.linalg.lstsq(df, rf, rcond=None)
        after = float(np.sum(cal.residuals(cal.rotated(np.clip(a_half, lo, hi)), score_on) ** 2))
        before = float(np.sum(cal.residuals(cal.nominal, score_on) ** 2))
        held[f"fit_{fit_on}"] = (before, after)
    cause = PhysicalCause("imu_alignment", dict(zip(ALIGNMENT, angles.tolist(), strict=True)))
    chi2_0 = cal.chi2(cal.nominal)
    entry = {
        "cause": cause, "sims": sims, "parameters": 3,
        "delta_bic": _bic(chi2_0["full"], chi2["full"], 3, cal.observations),
        "held_out": held, "at_bound": bool(np.any(np.abs(angles) >= hi - 1e-12)),
        "std": _alignment_std(d),
    }  # fmt: skip
    screen = {"candidate": "imu_alignment", "linearised_value": angles.tolist(),
              "chi2_fall": float(chi2_0["full"] - chi2["full"]), "probe": step,
              "probe_visibility": float(np.sum((d * step) ** 2))}  # fmt: skip
    return {"entry": entry, "screen": screen, "visibility": np.sum(d**2, axis=0)}


def _alignment_std(d: FloatArray) -> dict[str, float]:
    """Return the standard deviations of the angles from the linear model's Fisher information."""
    cov = np.linalg.pinv(2 * d.T @ d)  # -log L = sum r^2 (each r of variance 1/2): F = 2 D^T D
    return {n: float(np.sqrt(max(cov[i, i], 0.0))) for i, n in enumerate(ALIGNMENT)}


def _refine(cal: Calibration, chosen: Sequence[Candidate], config: MotionSystem) -> None:
    """Fit each chosen candidate by a bracket of simulations around its linearised value.

    A bracket of three values (the linearised one, and it times and over :data:`BRACKET` in
    its change from nominal), a parabola through chi2 in the log of the change; where its
    vertex lies outside the values scored (or it has none), a second bracket around it; the
    vertex simulated last. All candidates' simulations of a round run side by side.
    """
    lo_hi = [c.bounds for c in chosen]
    centres = [c.probe if c.linearised is None else c.linearised for c in chosen]
    settled = [False] * len(chosen)
    for _ in range(2):
        values = []
        for c, centre, (lo, hi), done in zip(chosen, centres, lo_hi, settled, strict=True):
            ds = _change(c, centre) * np.array([1 / BRACKET, 1.0, BRACKET])
            vs = [float(np.clip(c.nominal + x, lo, hi)) for x in ds]
            values.append([] if done else [v for v in dict.fromkeys(vs) if v not in c.points])
        _score(cal, chosen, values, config)
        for i, c in enumerate(chosen):
            centres[i], settled[i] = _vertex(c, *lo_hi[i])
    _score(
        cal,
        chosen,
        [[v] if v not in c.points else [] for c, v in zip(chosen, centres, strict=True)],
        config,
    )


def _vertex(c: Candidate, lo: float, hi: float) -> tuple[float, bool]:
    """Return the value at the chi2 parabola's vertex, and whether it lies among the scored."""
    best = _best_value(c)
    x, y = _log_points(c)
    vertex = _parabola_min(x, y)
    if vertex is None:
        return best, False
    lo_x, hi_x = x.min() - np.log(BRACKET), x.max() + np.log(BRACKET)
    change = np.sign(_change(c, best)) * np.exp(np.clip(vertex, lo_x, hi_x))
    return float(np.clip(c.nominal + change, lo, hi)), bool(x.min() <= vertex <= x.max())


def _change(c: Candidate, value: float) -> float:
    """Return the change from nominal, never zero (a tenth of the probe's at least)."""
    ch = value - c.nominal
    least = 0.1 * abs(c.probe - c.nominal)
    return ch if abs(ch) >= least else np.sign(c.probe - c.nominal) * least


def _log_points(c: Candidate) -> tuple[FloatArray, FloatArray]:
    """Return the scored values as log |change| and their chi2, on the side of the best value."""
    sign = np.sign(_change(c, _best_value(c)))
    pts = [(np.log(abs(v - c.nominal)), p["full"]) for v, p in c.points.items()
           if np.sign(v - c.nominal) == sign and abs(v - c.nominal) > 0]  # fmt: skip
    x, y = (np.array(a) for a in zip(*pts, strict=True))
    return x, y


def _best_value(c: Candidate) -> float:
    return min(c.points, key=lambda v: c.points[v]["full"])


def _score(cal: Calibration, chosen: Sequence[Candidate], values: Sequence[Sequence[float]],
           config: MotionSystem) -> None:  # fmt: skip
    """Simulate each candidate at its values (all at once) and keep their chi2."""
    jobs = [(c, v) for c, vs in zip(chosen, values, strict=True) for v in vs]
    if not jobs:
        return
    sims = cal.simulate([configured(config, c.cause(v)) for c, v in jobs])
    for (c, v), s in zip(jobs, sims, strict=True):
        c.points[v], c.sims[v] = cal.chi2(s), s


def _half_fits(c: Candidate) -> dict[str, float]:
    """Return the value fitted on each half of the window (the scored values' parabola).

    The vertex is kept within the values scored (no extrapolation); the held-out score is then
    the simulated chi2 at it on the other half (:func:`_entry`).
    """
    best = _best_value(c)
    sign = np.sign(_change(c, best))
    x, _ = _log_points(c)
    out = {}
    for half in ("half1", "half2"):
        ys = np.array([c.points[v][half] for v in _side(c, sign)])
        vertex = _parabola_min(x, ys)
        at = x[np.argmin(ys)] if vertex is None else float(np.clip(vertex, x.min(), x.max()))
        out[half] = float(np.clip(c.nominal + sign * np.exp(at), *c.bounds))
    return out


def _entry(c: Candidate, cal: Calibration, chi2_0: dict[str, float]) -> dict[str, object]:
    """Return the refined fit of one candidate: value, dBIC, held-out halves, its std.

    The half fits (:attr:`Candidate.halves`) must have been simulated (:func:`_score`).
    """
    best = _best_value(c)
    lo, hi = c.bounds
    halves = c.halves
    held = {f"fit_{fit_on}": (chi2_0[score_on], c.points[halves[fit_on]][score_on])
            for fit_on, score_on in (("half1", "half2"), ("half2", "half1"))}  # fmt: skip
    return {
        "cause": c.cause(best), "sims": c.sims[best], "parameters": 1,
        "delta_bic": _bic(chi2_0["full"], c.points[best]["full"], 1, cal.observations),
        "held_out": held,
        "at_bound": bool(abs(best - lo) < 1e-12 and lo != c.nominal) or abs(best - hi) < 1e-12,
        "std": {c.name: _std(c, best)},
    }  # fmt: skip


def _side(c: Candidate, sign: float) -> list[float]:
    return [v for v in c.points if np.sign(v - c.nominal) == sign and abs(v - c.nominal) > 0]


def _std(c: Candidate, best: float) -> float:
    """Return the value's standard deviation from the chi2 parabola's curvature."""
    x = np.sort(np.array(sorted(c.points, key=lambda v: abs(v - best))[:3]))
    if x.size < 3 or _distinct(x) < 3:
        return float("nan")
    y = np.array([c.points[v]["full"] for v in x])
    # the parabola through three points: its second coefficient is the second divided difference
    a = ((y[2] - y[1]) / (x[2] - x[1]) - (y[1] - y[0]) / (x[1] - x[0])) / (x[2] - x[0])
    return float(np.sqrt(1.0 / (2 * a))) if a > 0 else float("nan")


def _public(entry: dict[str, object]) -> dict[str, object]:
    """Return the JSON form of a table entry."""
    cause: PhysicalCause = entry["cause"]  # type: ignore[assignment]
    return {"describe": cause.describe(), **cause.to_json(), "delta_bic": entry["delta_bic"],
            "held_out_chi2": {k: list(v) for k, v in entry["held_out"].items()},  # type: ignore[union-attr]
            "at_bound": entry["at_bound"], "parameter_std": entry["std"]}  # fmt: skip


def _name(table: list[dict[str, object]], cal: Calibration) -> Finding | None:
    """Name the best candidate if it beats the nominal model and passes the held-out gate."""
    if not table:
        return None
    best = table[0]
    held = best["held_out"]
    improves = all(after < before for before, after in held.values())  # type: ignore[union-attr]
    if float(best["delta_bic"]) <= BIC_MARGIN or best["at_bound"] or not improves:
        return None
    cause: PhysicalCause = best["cause"]  # type: ignore[assignment]
    cause = PhysicalCause(cause.effect, cause.parameters, cal.driven)
    nominal_by = cal.by_source(cal.nominal)
    after_by = cal.by_source(best["sims"])  # type: ignore[arg-type]
    rivals = [e for e in table[1:] if float(best["delta_bic"]) - float(e["delta_bic"]) < BIC_MARGIN]
    evidence = {
        "criterion": f"BIC improvement > {BIC_MARGIN:g} over the nominal full model on every "
        "channel the runs have (simulated); the fit on each half improves the other half",
        "delta_bic": float(best["delta_bic"]),
        "observations": cal.observations,
        "parameter_std": best["std"],
        "sources": {s: {"chi2_nominal": nominal_by[s], "chi2_fitted": after_by.get(s, 0.0),
                        "fall": nominal_by[s] - after_by.get(s, 0.0)} for s in nominal_by},
        "alternatives": [_alternative(e["cause"].describe(),  # type: ignore[union-attr]
                                      float(e["delta_bic"]), float(best["delta_bic"]))
                         for e in rivals],
        "ambiguous": bool(rivals),
    }  # fmt: skip
    lines = sum(b.measured.size for b in cal.evidence["half1"])
    folds = list(held.values())  # type: ignore[union-attr]
    gain = {
        "held_out": "other half of the measurement window (two-fold), every channel",
        "chi2_per_line_before": float(np.mean([b for b, _ in folds])) / lines,
        "chi2_per_line_after": float(np.mean([a for _, a in folds])) / lines,
    }
    return Finding(cause, evidence, gain)  # type: ignore[arg-type]


def _detectability(
    cands: Sequence[Candidate], align: dict[str, object], cal: Calibration, config: MotionSystem
) -> dict[str, dict[str, object]]:
    """Return the smallest change of each physical parameter the runs could have shown.

    The expected BIC improvement of a change x of a parameter whose probe change x_p moved the
    standardised evidence by d (chi2 = -log L = the sum of the squared residuals) is
    2 (x / x_p)^2 <d, d> - ln n; it reaches the margin at x = x_p sqrt((margin + ln n) /
    (2 <d, d>)).
    """
    need = BIC_MARGIN + np.log(cal.observations)
    out: dict[str, dict[str, object]] = {}
    groups: dict[str, list[tuple[Candidate, float]]] = {}
    for c in cands:
        dd = float(c.direction @ c.direction)  # type: ignore[union-attr]
        x = abs(c.probe - c.nominal) * np.sqrt(need / (2 * dd)) if dd > 0 else np.inf
        key = "payload" if c.effect == "payload" else f"leg {c.name}"
        groups.setdefault(key, []).append((c, x))
    for key, items in groups.items():
        c0 = items[0][0]
        lo, hi = c0.bounds
        reach = abs((hi if c0.probe > c0.nominal else lo) - c0.nominal)  # the search's reach
        xs = np.array([x if x <= reach else np.inf for _, x in items])
        unit = SEARCH[c0.name][3]
        if key == "payload":
            text = ("no heavier cabin within the search (x3) could have been seen in these runs"
                    if not np.isfinite(xs[0]) else
                    f"a cabin heavier by less than {100 * xs[0]:.0f} % (mass and inertia) could "
                    "not have been seen in these runs")  # fmt: skip
        else:
            what = {
                "gain": "gain off by less than",
                "lag_s": "servo lag below",
                "coulomb_n": "Coulomb friction below",
                "play_m": "play below",
            }[c0.name]
            per = ", ".join(
                f"{c.leg}: {_fmt(x, unit)}" for (c, _), x in zip(items, xs, strict=True)
            )
            text = (f"a leg's {what} {_fmt(xs.min(), unit)} could not have been seen in "
                    f"these runs (per leg {per}; linearised at {_fmt(c0.probe, unit)}; 'any': "
                    "not within the search)")  # fmt: skip
            if not np.isfinite(xs).any():
                text = (f"no leg's {what.split(' below')[0].split(' off')[0]} within the search "
                        "could have been seen in these runs")  # fmt: skip
        out[key] = {"statement": text, "smallest": xs.tolist(), "unit": unit}
    vis = np.asarray(align["visibility"])
    angles = np.sqrt(need / np.maximum(2 * vis, 1e-300))
    angles = np.where(angles <= SEARCH["angle_rad"][2], angles, np.inf)
    out["imu_alignment"] = {
        "statement": "an IMU rotated by less than "
        + ", ".join(
            f"{n.removesuffix('_rad')} {np.degrees(a):.2f} deg"
            if np.isfinite(a)
            else f"{n.removesuffix('_rad')} any (none within the search)"
            for n, a in zip(ALIGNMENT, angles, strict=True)
        )
        + " could not have been seen in these runs",
        "smallest": angles.tolist(),
        "unit": "rad",
    }
    return out


def _fmt(x: float, unit: str) -> str:
    """Return a detectability threshold with its unit (an infinite one: 'any')."""
    if not np.isfinite(x):
        return "any"  # nothing within the search could have been seen
    if unit == "m":
        return f"{x * 1e3:.2g} mm"
    if unit == "s":
        return f"{x * 1e3:.2g} ms"
    if unit == "x":
        return f"{x:.2g}"
    return f"{x:.3g} {unit}"
